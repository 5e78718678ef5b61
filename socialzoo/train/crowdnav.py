"""`socialzoo train crowdnav`: PPO (Stable-Baselines3) with attention over people on the CrowdNav task."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from socialzoo.env.crowd_variants import crowd_env_id
from socialzoo.env.registration import CROWD_SUITE_ID
from socialzoo.train.checks import (
    MAX_SB3_SEED,
    check_block,
    check_choice,
    check_int,
    check_minibatch,
    check_number,
    check_seed,
    check_sizes,
    coerce,
)
from socialzoo.train.skeleton import Trainer, TrainingRun, run_training

TRAINER = Trainer("crowdnav", policy_file="crowdnav.safetensors")
# The id whose task --families trains on (socialzoo.env.registration.SUITE_IDS).
SUITE_ID = CROWD_SUITE_ID
# The CrowdNavConfig fields --families decides (each family on its own map).
FAMILY_FIELDS = ("family", "map")
# The CrowdNavArgs fields passed to stable_baselines3.PPO by name.
PPO_FIELDS: tuple[str, ...] = ("n_steps", "batch_size", "n_epochs", "learning_rate", "gamma", "gae_lambda")
PPO_FIELDS += ("clip_range", "ent_coef", "vf_coef", "max_grad_norm", "seed")


@dataclass(frozen=True, kw_only=True)
class CrowdNavArgs:
    """Train PPO with attention over people on the CrowdNav task.

    Attributes:
        out: the run folder: run.json, checkpoints/, tensorboard/, crowdnav.safetensors.
        seed: seeds the network, SB3's sampling and the training cases.
        variant: the task's variant ("" CrowdNav's own; "20", "Unicycle", "Square", "Visible",
            "SocialForce", "Walls": socialzoo.env.crowd_variants); "" with families.
        families: "" (the variant's own cases), "suite" (the guidelines' 25 scenarios) or a comma
            list of suite names or Fig. 7 letters (socialzoo.scenarios.suite; any other registered
            family by name): train on the suite id's task (socialzoo/CrowdNavSuite-v2: among walls,
            signals on, 60 s, 20 person slots), one part of num_envs' rows per family, each on its
            family's training seeds; checkpoints evaluated on eval_trials of the families'
            validation cases, spread over them.
        env_overrides: other CrowdNavConfig fields, as a JSON object (with families: on top of the
            suite id's, except family and map).
        action: "discrete" (CrowdNav's 81 actions) or "continuous" (a velocity).
        total_steps: env steps (decisions) of training (CrowdNav's 5-person task: the default; the
            20-person arena, --variant 20: 8,192,000 passed 0.90 test success over three seeds,
            docs/crowdnav.md).
        checkpoint_every: a policy file every this many env steps; a multiple of the rollout.
        num_envs: rows of the batched training env.
        n_steps: env steps per row per rollout.
        batch_size: minibatch size of the PPO update, 2 to the rollout (num_envs * n_steps).
        n_epochs: passes over each rollout.
        learning_rate: Adam learning rate, > 0.
        gamma: discount per decision step (0.25 s).
        gae_lambda: GAE lambda.
        clip_range: PPO clipping.
        ent_coef: entropy bonus weight.
        vf_coef: value loss weight.
        max_grad_norm: gradient clipping.
        net_arch: hidden sizes of the policy and value MLPs on the attention features.
        embed: hidden sizes of the per-person embedding (ReLU).
        value: hidden sizes of the per-person feature MLP.
        attention: hidden sizes of the attention-score MLP.
        progress_reward: weight of the goal-distance shaping term per metre (0: none).
        collision_penalty: the training reward of a collision (the task's own, CrowdNav's, is -0.25;
            -1 here learned to collide about half as often in the same steps).
        eval_trials: evaluate every checkpoint on this many of the task's validation cases
            (evaluations.csv, TensorBoard eval/*) and keep the best one as the policy; 0: none
            (the policy is the last checkpoint). With families: cases 0, 1, ... of each family's
            validation split, eval_trials in all (at most 100 per family), spread as evenly as
            possible (the first families take one more).
        threads: torch CPU threads.
        progress: show progress.
    """

    out: Path = Path("runs/crowdnav")
    seed: int = 0
    variant: str = ""
    families: str = ""
    env_overrides: dict[str, Any] = field(default_factory=dict)
    action: Literal["discrete", "continuous"] = "discrete"
    total_steps: int = 2_048_000
    checkpoint_every: int = 204_800
    num_envs: int = 64
    n_steps: int = 64
    batch_size: int = 1024
    n_epochs: int = 4
    learning_rate: float = 5e-4
    gamma: float = 0.97
    gae_lambda: float = 0.95
    clip_range: float = 0.2
    ent_coef: float = 0.005
    vf_coef: float = 0.5
    max_grad_norm: float = 0.5
    net_arch: tuple[int, ...] = (128, 128)
    embed: tuple[int, ...] = (64, 64)
    value: tuple[int, ...] = (64, 32)
    attention: tuple[int, ...] = (64,)
    progress_reward: float = 0.1
    collision_penalty: float = -1.0
    eval_trials: int = 100
    threads: int = 1
    progress: bool = True

    def __post_init__(self) -> None:
        coerce(self, out=Path, net_arch=tuple, embed=tuple, value=tuple, attention=tuple)
        check_sizes(self, "net_arch", "embed", "value", "attention")
        check_int(self, "total_steps", "checkpoint_every", "num_envs", "n_steps", "batch_size", low=1)
        check_int(self, "n_epochs", "threads", low=1)
        check_seed(self, MAX_SB3_SEED)
        families = self.family_names()
        check_int(self, "eval_trials", low=0, high=100 * max(1, len(families)))
        if families and self.num_envs < len(families):
            raise ValueError(
                f"CrowdNavArgs.num_envs ({self.num_envs}) must be at least the number of families "
                f"({len(families)}): each family's part needs a row"
            )
        check_number(self, "learning_rate", low=0.0, high=1.0, low_open=True)  # 0: nothing learned
        check_number(self, "gamma", "gae_lambda", low=0.0, high=1.0)
        check_number(self, "clip_range", "ent_coef", "vf_coef", low=0.0, high=10.0)
        check_number(self, "max_grad_norm", low=0.0, high=1e6)
        check_number(self, "progress_reward", low=0.0, high=100.0)
        check_number(self, "collision_penalty", low=-100.0, high=0.0)
        check_choice(self, "action", ("discrete", "continuous"))
        # SB3's PPO normalises each minibatch's advantages, which takes two samples at least.
        check_int(self, "batch_size", low=2)
        rollout = (self.num_envs * self.n_steps, "the rollout, num_envs * n_steps")
        check_block(self, *rollout)
        check_minibatch(self, "batch_size", *rollout)
        try:
            self.tasks()
        except (TypeError, ValueError) as err:
            raise ValueError(f"CrowdNavArgs: bad task ({err})") from None

    def family_names(self) -> tuple[str, ...]:
        """The families of --families, registry names in the order given (() without).

        Raises:
            ValueError: an unknown or repeated name, or families with a variant.
        """
        if not isinstance(self.families, str):
            raise ValueError(f"CrowdNavArgs.families must be a string, got {self.families!r}")
        spec = self.families.strip()
        if not spec:
            return ()
        from socialzoo.scenarios.catalogue import FAMILIES
        from socialzoo.scenarios.suite import SUITE_NAMES, suite_entry

        if self.variant:
            raise ValueError(
                f"CrowdNavArgs.families: the families play the suite id's task ({SUITE_ID}); "
                f"leave variant empty (got {self.variant!r}) and change its fields with env_overrides"
            )
        if spec == "suite":
            return SUITE_NAMES
        names: list[str] = []
        for word in (w.strip() for w in spec.split(",")):
            try:
                name = suite_entry(word).family
            except KeyError:
                if word not in FAMILIES:
                    raise ValueError(
                        f"CrowdNavArgs.families: unknown family {word!r}; give 'suite' or suite names or "
                        f"letters ({', '.join(SUITE_NAMES)}) or registered families"
                    ) from None
                name = word
            if name in names:
                raise ValueError(f"CrowdNavArgs.families names {name!r} twice")
            names.append(name)
        return tuple(names)

    @property
    def env_id(self) -> str:
        """The id of the task trained on: the variant's, or with families the suite id."""
        return SUITE_ID if self.family_names() else crowd_env_id(self.variant)

    def task(self, family: str | None = None) -> Any:
        """The task's CrowdNavConfig: the variant, the overrides, the action kind, a flat observation;
        with families the suite id's task playing `family` (default the first).

        Raises:
            ValueError: a family without families, or one not among them.
        """
        from socialzoo.env.crowd_config import CrowdNavConfig

        overrides = {**dict(self.env_overrides), "action": self.action, "observation": "flat"}
        families = self.family_names()
        if not families:
            if family is not None:
                raise ValueError(f"CrowdNavArgs.task: family {family!r} asked of a run without families")
            return CrowdNavConfig.variant(self.variant, **overrides)
        if family is None:
            family = families[0]
        if family not in families:
            raise ValueError(f"CrowdNavArgs.task: {family!r} is not one of the run's families {families}")
        taken = sorted(set(FAMILY_FIELDS) & set(self.env_overrides))
        if taken:
            raise ValueError(
                f"CrowdNavArgs.env_overrides: {taken} are decided by the families (each plays on its own map)"
            )
        kwargs = suite_kwargs()
        variant = kwargs.pop("variant", "")
        return CrowdNavConfig.variant(variant, **{**kwargs, **overrides, "family": family, "map": None})

    def tasks(self) -> list[Any]:
        """The config of each family (the one task without families)."""
        return [self.task(f) for f in self.family_names()] or [self.task()]

    def rows(self) -> list[int]:
        """The training env's rows of each family: num_envs split as evenly as possible, the first
        families taking one more ([num_envs] without families)."""
        k = max(1, len(self.family_names()))
        return [self.num_envs // k + (i < self.num_envs % k) for i in range(k)]


def suite_kwargs() -> dict[str, Any]:
    """The CrowdNavConfig fields of the suite id (SUITE_ID) as Gymnasium's registry holds them
    (`variant` among them; without `task`)."""
    import gymnasium as gym

    import socialzoo  # noqa: F401  (registers the ids)

    kwargs = dict(gym.spec(SUITE_ID).kwargs)
    kwargs.pop("task", None)
    return kwargs


def training_reward(venv: Any, progress: float, collision_extra: float) -> Any:
    """An SB3 VecEnvWrapper adding the training-only terms to each row's task reward:
    progress * (goal distance before - after) (the goal distance is the observation's first entry,
    socialzoo.env.crowd_observation) and collision_extra on a step that ends in a collision.

    The training reward is the task's (CrowdNav's) with two training-only changes: a potential-based shaping
    term progress_reward * (d_before - d_after) on the robot's goal distance d (Ng et al. 1999: shaping by a
    potential's difference keeps the optimal policies; CrowdNav++ shapes the same way), and a collision
    costing `collision_penalty` instead of the task's -0.25 (CrowdNav++ charges -20 against +10 for the goal).
    """
    from stable_baselines3.common.vec_env import VecEnvWrapper

    class TrainingReward(VecEnvWrapper):
        def reset(self) -> np.ndarray:
            obs = np.asarray(self.venv.reset())
            self.distance = obs[:, 0].astype(np.float64)
            return obs

        def step_wait(self) -> Any:
            obs, reward, done, infos = self.venv.step_wait()
            obs = np.asarray(obs)
            after = obs[:, 0].astype(np.float64)
            extra = np.zeros(len(reward))
            for row in np.flatnonzero(done):
                after[row] = infos[row]["terminal_observation"][0]
                extra[row] = collision_extra * float(infos[row]["metrics"]["collision"])
            reward = reward + progress * (self.distance - after) + extra
            self.distance = obs[:, 0].astype(np.float64)
            return obs, reward.astype(np.float32), done, infos

    return TrainingReward(venv)


def train(args: CrowdNavArgs) -> Path:
    """Train on the trainer skeleton; returns crowdnav.safetensors (or a finished run's).

    The policy reads the robot-centred joint state (socialzoo.env.crowd_observation) through an
    attention-pooling features extractor in the spirit of SARL (socialzoo.train.crowd_attention), and picks
    one of CrowdNav's 81 actions (or a velocity, with --action continuous). It trains on the task's training
    cases only (CrowdNav's training split; the 100 validation cases choose nothing unless --eval-trials asks
    for checkpoint evaluations, and the 500 test cases are never seen), on the batched CrowdNavVectorEnv
    behind SB3's VecEnv. Episodes are judged, and every reported metric computed, on the task's reward and
    outcomes alone.

    With --families (the guidelines' suite, socialzoo.scenarios.suite, or some of its scenarios) one learner
    trains on several scenario families at once: the task is the suite id's (socialzoo/CrowdNavSuite-v2, its
    kwargs read from Gymnasium's registry, so the learner trains on what the suite evaluates: among walls,
    signals on), one CrowdNavVectorEnv per family on the family's own map, side by side as one env
    (socialzoo.env.concat_vector.ConcatVectorEnv); each draws only its family's training seeds, and
    checkpoints are chosen on the families' validation splits.
    """
    evaluator = _validation(args) if args.eval_trials else None
    return run_training(TRAINER, args, lambda run: _fit(run, args), evaluator=evaluator)


def validation_cases(args: CrowdNavArgs) -> list[tuple[Any, int]]:
    """(task config, cases) of each checkpoint evaluation: the first eval_trials validation cases,
    or with families eval_trials cases spread over the families' validation splits (cases 0, 1, ...
    of each; the first families take one more; a family left with none is skipped)."""
    tasks = args.tasks()
    k, n = len(tasks), args.eval_trials
    counts = [n // k + (i < n % k) for i in range(k)]
    return [(task, count) for task, count in zip(tasks, counts, strict=True) if count]


def _validation(args: CrowdNavArgs) -> Any:
    """A checkpoint evaluator on the validation cases of `validation_cases` (success first), the
    metrics over all of them."""
    plan = validation_cases(args)

    def evaluate(path: Path) -> dict[str, float]:
        from socialzoo.agents.crowd_policy import CrowdAttentionPolicy
        from socialzoo.bench.crowd_eval import evaluate_crowd
        from socialzoo.bench.task_benchmark import summarize

        policy = CrowdAttentionPolicy.load(path)
        episodes = []
        for task, cases in plan:
            episodes += evaluate_crowd(lambda obs, core: policy.act(obs), task, "val", cases).episodes
        s = summarize(episodes)
        keys = ("success_rate", "collision_rate", "timeout_rate", "navigation_time", "discounted_return")
        return {k.removesuffix("_rate"): float(s[k]) for k in keys}

    return evaluate


def _fit(run: TrainingRun, args: CrowdNavArgs) -> Mapping[str, Any]:
    import torch
    from stable_baselines3.common.vec_env import VecMonitor

    from socialzoo.env.concat_vector import ConcatVectorEnv
    from socialzoo.env.sb3_vec import SB3VecEnv
    from socialzoo.env.vector import CrowdNavVectorEnv
    from socialzoo.train.crowd_attention import CrowdAttentionExtractor
    from socialzoo.train.sb3_common import learn_with_checkpoints, sb3_model

    task = args.task()
    families = args.family_names()
    if families:
        # One part per family, each its own world on its own map; the rows end to end.
        parts = [CrowdNavVectorEnv(n, config) for n, config in zip(args.rows(), args.tasks(), strict=True)]
        vector_env: Any = ConcatVectorEnv(parts)
    else:
        vector_env = CrowdNavVectorEnv(args.num_envs, task)
    venv: Any = VecMonitor(SB3VecEnv(args.num_envs, vector_env=vector_env))
    venv = training_reward(venv, args.progress_reward, args.collision_penalty - task.reward.collision_penalty)
    kwargs = {name: getattr(args, name) for name in PPO_FIELDS}
    policy_kwargs = {
        "net_arch": list(args.net_arch),
        "activation_fn": torch.nn.Tanh,
        "features_extractor_class": CrowdAttentionExtractor,
        "features_extractor_kwargs": {
            "slots": task.observed_slots,
            "embed": args.embed,
            "value": args.value,
            "attention": args.attention,
            "signals": task.signals,
        },
    }
    model = sb3_model(run, "PPO", venv, {**kwargs, "policy_kwargs": policy_kwargs})

    def save(path: Path, step: int) -> None:
        export_crowd_policy(model, task, run, step).save(path, crowd_tensors(model))

    steps, last = learn_with_checkpoints(run, model, args.total_steps, args.checkpoint_every, save)
    # Checkpoint choice by validation: with evaluated checkpoints the kept policy is the one of the
    # best validation success (the earliest among equals), never a test-set choice.
    best = run.best_evaluation()
    kept = run.path / best["file"] if best is not None else last
    run.policy.write_bytes(kept.read_bytes())
    venv.close()
    return {
        "env_steps": steps,
        "env_steps_per_second": round(steps / run.seconds, 1),
        "kept_checkpoint": str(kept.relative_to(run.path)),
        "env_id": args.env_id,
        "task": task.to_dict(),
        **_family_record(args),
    }


def _family_record(args: CrowdNavArgs) -> dict[str, Any]:
    """What the run record and the policy header say of --families (nothing without)."""
    families = args.family_names()
    if not families:
        return {}
    return {"families": list(families), "family_rows": dict(zip(families, args.rows(), strict=True))}


def crowd_tensors(model: Any) -> dict[str, Any]:
    """The acting network of an SB3 PPO model with the attention extractor, named as
    socialzoo.agents.crowd_policy reads them."""
    policy = model.policy
    tensors = {f"attention.{k}": v for k, v in policy.features_extractor.net.state_dict().items()}
    tensors.update({f"policy.{k}": v for k, v in policy.mlp_extractor.policy_net.state_dict().items()})
    tensors.update({f"action.{k}": v for k, v in policy.action_net.state_dict().items()})
    return tensors


def export_crowd_policy(model: Any, task: Any, run: TrainingRun, step: int) -> Any:
    """The numpy policy (header and all) of an SB3 PPO model trained on `task`."""
    from socialzoo.agents.crowd_policy import POLICY_NAME, CrowdAttentionPolicy
    from socialzoo.train.sb3_common import sb3_training_record

    tensors = {k: v.detach().cpu().numpy() for k, v in crowd_tensors(model).items()}
    args = run.args
    header = {
        "policy": POLICY_NAME,
        "env_id": args.env_id,
        "observation": {"kind": "flat", "slots": task.observed_slots, "signals": task.signals},
        "network": {
            "action": task.action,
            "activation": "tanh",
            "embed": list(args.embed),
            "value": list(args.value),
            "attention": list(args.attention),
            "net_arch": list(args.net_arch),
        },
        "training": sb3_training_record(run, "ppo", step, task=task.to_dict(), **_family_record(args)),
    }
    return CrowdAttentionPolicy(tensors, header)
