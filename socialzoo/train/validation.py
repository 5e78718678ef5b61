"""The trainers' checkpoint evaluator: a robot policy file on the first scenarios of its training
map's validation set (socialzoo.scenarios.scenario_sets.validation_set, "<map>-val": never a test set),
or of its scenario family's own validation split."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from socialzoo.core.metrics import metric, registered
from socialzoo.core.validation import check_int
from socialzoo.train.skeleton import Evaluator

# The metrics an evaluation reports, averaged over its scenarios (the success-only ones, as the
# metric registry flags them, over the successful ones).
EVALUATION_METRICS = registered(
    "success", "reached", "time_to_goal", "average_step_reward", "mean_force", "mean_blame"
)


def validation_evaluator(
    policy: str,
    map_name: str,
    trials: int,
    *,
    env_overrides: Mapping[str, Any] | None = None,
    family: str | None = None,
    max_rows: int = 128,
) -> Evaluator:
    """An evaluator of policy files of registry name `policy` ("ppo", "bc", ...).

    Run in this process, one batched world of `trials` rows, so a checkpoint costs one episode's wall time;
    the skeleton (socialzoo.train.skeleton) calls it after each checkpoint when a trainer's `eval_trials` is
    above 0, and the run keeps the metrics in evaluations.csv and TensorBoard.

    Args:
        policy: the registry name the files load with (make_policy("<policy>:PATH")).
        map_name: the training map; its validation scenarios 0 .. trials-1 are run.
        trials: scenarios per checkpoint.
        env_overrides: EnvConfig fields the policy was trained with (observation, reward, ...).
        family: the scenario family the policy was trained on: cases 0 .. trials-1 of the action-selection
            task's "val" split of that family on `map_name` (the family's own validation seeds, or for a
            family without splits its scenarios of the map's validation seeds) in place of "<map>-val".
        max_rows: most env rows stepped together.

    A family's split holds socialzoo.bench.test_sets.family_validation_size(family) cases; more trials
    fail at the first evaluation.

    Returns:
        path -> {metric: mean over the scenarios} (EVALUATION_METRICS; time_to_goal over the
        successful ones, NaN when none).

    Raises:
        ValueError: trials below 1, or an unknown map or family.
    """
    from socialzoo.bench.runner import CaseSet, RunSpec, Trial, env_config_for, run_chunk
    from socialzoo.env.config import EnvConfig
    from socialzoo.scenarios.scenario_sets import TestSet, validation_set

    check_int("validation_evaluator", "trials", trials, low=1)
    test_set: TestSet | CaseSet
    if family is None:
        test_set = validation_set(map_name)
        config = env_config_for(test_set, **dict(env_overrides or {}))
    else:
        config = EnvConfig(map=map_name, family=family).replace(**dict(env_overrides or {}))
        test_set = CaseSet("action_selection", "val", trials, name=f"{family}-val", map_name=map_name)

    def evaluate(path: Path) -> dict[str, float]:
        import numpy as np

        spec_name = f"{policy}:{path}"
        spec = RunSpec(
            test_sets={test_set.name: test_set},
            env_configs={test_set.name: config},
            policies={spec_name: {}},
            batch_size=min(trials, max_rows),
        )
        results = run_chunk([Trial(spec_name, test_set.name, k) for k in range(trials)], spec)
        metrics = [r.metrics for r in results]
        out = {}
        for key in EVALUATION_METRICS:
            values = [
                float(m[key])
                for m in metrics
                if key in m and (not metric(key).success_only or m.get("success"))
            ]
            out[key] = float(np.mean(values)) if values else float("nan")
        return out

    return evaluate


def kept_policy(policy: str | Path) -> Path:
    """The policy a training run keeps: its best validation checkpoint when the run evaluated its
    checkpoints (run.json's results.best_checkpoint: the highest validation success, the earliest
    among equals; chosen on validation scenarios, never on a test set), else `policy`, the run's
    final policy file.

    Args:
        policy: the final policy file a trainer returned (its folder holds the run's run.json).

    Raises:
        socialzoo.train.run_dir.RunDirError: an unreadable run record.
    """
    from socialzoo.train.run_dir import RUN_FILE, read_record

    policy = Path(policy)
    record = read_record(policy.parent / RUN_FILE)
    best = (record or {}).get("results", {}).get("best_checkpoint") if record else None
    if not isinstance(best, dict) or not isinstance(best.get("file"), str):
        return policy
    chosen = policy.parent / best["file"]
    if not chosen.is_file():
        raise FileNotFoundError(f"{policy.parent / RUN_FILE}: its best checkpoint {chosen} is missing")
    return chosen
