"""What the Stable-Baselines3 trainers (ppo, dqn) share: their common arguments, the training
env, and the SB3 callback that feeds the trainer skeleton's checkpoints, logs and progress."""

from __future__ import annotations

import dataclasses
import functools
import logging
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from socialzoo.core.metrics import registered
from socialzoo.env.config import EnvConfig
from socialzoo.train.checks import (
    MAX_SB3_SEED,
    check_block,
    check_eval_trials,
    check_int,
    check_number,
    check_seed,
    check_sizes,
    coerce,
)
from socialzoo.train.skeleton import CheckpointSchedule, Trainer, TrainingRun, run_training

logger = logging.getLogger(__name__)

POLICY_SUFFIX = ".safetensors"


@dataclass(frozen=True)
class SB3Trainer(Trainer):
    """An SB3 trainer: its model class and the activation of its network.

    Attributes:
        model: the stable_baselines3 class name ("PPO", "DQN").
        activation: the torch.nn activation of the MLP ("Tanh" for PPO, "ReLU" for DQN: SB3's defaults).
    """

    model: str = "PPO"
    activation: str = "Tanh"


@dataclass(frozen=True, kw_only=True)
class SB3Args:
    """The arguments every Stable-Baselines3 trainer takes; the defaults are PPO's set-up (SB3's
    PPO defaults and the paper's schedule), and each trainer states where it differs.

    Attributes:
        out: the run folder: run.json, checkpoints/, tensorboard/ and the final <algo>.safetensors.
        seed: seeds the network, SB3's sampling and the env's scenario stream.
        total_steps: env steps of training (the paper: 84,000).
        checkpoint_every: a policy file every this many env steps (the paper: 2,000); a multiple
            of the trainer's update block (PPO: the rollout, num_envs * n_steps; DQN: num_envs *
            train_freq).
        map: the training map; scenarios come from the env's own seeded stream, never a test set.
            "" (the default): the family's own map with a family, else gdc1 (the paper's).
        family: a scenario family instead of the benchmark's scenarios (None: the benchmark).
        max_steps: episode time limit in steps (the benchmark: 3,200 = 80 s).
        scenario_repeats: episodes run on each scenario before a new one is drawn (the original:
            1 for PPO, 20 for DQN).
        env_overrides: other EnvConfig fields, as a JSON object (e.g. {"reward": {"w_force": -0.02}});
            one that a field above decides (map, family, max_steps, scenario.repeats) is refused
            unless it is that field's value.
        num_envs: rows of the batched training env.
        learning_rate: Adam learning rate, > 0 (SB3: PPO 3e-4, DQN 1e-4).
        batch_size: minibatch size of an update (SB3: PPO 64, DQN 32); PPO: 2 to the rollout,
            DQN: at most buffer_size.
        gamma: discount factor (SB3: 0.99).
        max_grad_norm: gradient clipping (SB3: PPO 0.5, DQN 10).
        net_arch: hidden layer sizes of the network (SB3: 64 64; tanh for PPO, ReLU for DQN).
        normalize: normalise observations with VecNormalize (saved with the policy).
        normalize_reward: normalise rewards with VecNormalize during training (SB3's PPO default).
        eval_trials: evaluate every checkpoint on this many validation scenarios of the training
            map, or with a family of the family's validation split (never a test set;
            evaluations.csv, TensorBoard eval/*), in episodes of max_steps; 0: none.
        eval_every: evaluate only the checkpoints at multiples of this many env steps, and the
            last one (a multiple of checkpoint_every); 0: every checkpoint.
        threads: torch CPU threads.
        progress: show progress.
    """

    out: Path = Path("runs/sb3")
    seed: int = 0
    total_steps: int = 84_000
    checkpoint_every: int = 2_000
    map: str = ""
    family: str | None = None
    max_steps: int = 3200
    scenario_repeats: int = 1
    env_overrides: dict[str, Any] = field(default_factory=dict)
    num_envs: int = 50
    learning_rate: float = 3e-4
    batch_size: int = 64
    gamma: float = 0.99
    max_grad_norm: float = 0.5
    net_arch: tuple[int, ...] = (64, 64)
    normalize: bool = True
    normalize_reward: bool = True
    eval_trials: int = 0
    eval_every: int = 0
    threads: int = 1
    progress: bool = True

    def __post_init__(self) -> None:
        coerce(self, out=Path, net_arch=tuple)
        owner = type(self).__name__
        if not self.map:
            object.__setattr__(self, "map", default_map(self.family))
        check_int(self, "total_steps", "checkpoint_every", "max_steps", "scenario_repeats", "num_envs", low=1)
        check_int(self, "batch_size", "threads", low=1)
        check_int(self, "eval_trials", "eval_every", low=0)
        check_seed(self, MAX_SB3_SEED)
        if self.eval_every % self.checkpoint_every:
            raise ValueError(
                f"{owner}.eval_every ({self.eval_every}) must be a multiple of checkpoint_every "
                f"({self.checkpoint_every})"
            )
        check_number(self, "learning_rate", low=0.0, high=1.0, low_open=True)  # 0: nothing learned
        check_number(self, "gamma", low=0.0, high=1.0)
        check_number(self, "max_grad_norm", low=0.0, high=1e6)
        check_sizes(self, "net_arch")
        for name, given in self._overridden().items():
            if given != getattr(self, name):
                raise ValueError(
                    f"{owner}.env_overrides sets {name} ({given!r}), which its own field decides "
                    f"({getattr(self, name)!r}): give {name} instead"
                )
        try:
            self.env_config()
        except (TypeError, ValueError) as err:
            raise ValueError(f"{owner}: bad training env ({err})") from None
        if self.family is not None and self.map != default_map(self.family):
            check_family_fits(owner, self.family, self.map)
        check_eval_trials(self, f"map {self.map!r}", self.family)

    def _overridden(self) -> dict[str, Any]:
        """The env_overrides values of the EnvConfig fields that env_config sets from this
        dataclass's own fields (map, family, max_steps, scenario_repeats), by the field's name."""
        given = dict(self.env_overrides)
        found: dict[str, Any] = {
            name: given[name] for name in ("map", "family", "max_steps") if name in given
        }
        scenario = given.get("scenario")
        if isinstance(scenario, Mapping) and "repeats" in scenario:
            found["scenario_repeats"] = scenario["repeats"]
        return found

    def check_block(self, block: int, what: str) -> None:
        """Raise ValueError unless checkpoints and the end of training fall on `block` env steps
        (socialzoo.train.checks.check_block)."""
        check_block(self, block, what)

    def model_kwargs(self, activation: str) -> dict[str, Any]:
        """The SB3 model's keyword arguments: those every trainer sets from these fields, then the
        trainer's own fields (every field its Args adds to SB3Args, by the same name as SB3's)."""
        import torch

        common = {
            "learning_rate": self.learning_rate,
            "batch_size": self.batch_size,
            "gamma": self.gamma,
            "max_grad_norm": self.max_grad_norm,
            "policy_kwargs": {
                "net_arch": list(self.net_arch),
                "activation_fn": getattr(torch.nn, activation),
            },
            "seed": self.seed,
            "device": "cpu",
            "verbose": 0,
        }
        shared = {f.name for f in dataclasses.fields(SB3Args)}
        own = {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name not in shared}
        return {**common, **own}

    def env_config(self) -> EnvConfig:
        """The training env's config: the benchmark's, on `map` (or a scenario family), with each
        scenario run `scenario_repeats` times before the next is drawn, and `env_overrides`."""
        config = EnvConfig().replace(**dict(self.env_overrides))
        return config.replace(
            map=self.map,
            family=self.family,
            max_steps=self.max_steps,
            scenario={"repeats": self.scenario_repeats},
        )


def default_map(family: str | None) -> str:
    """The map a run trains on when none is named: a family's own (a family's scenarios are laid out
    for its map, and another map may lack the place they need), else the paper's gdc1."""
    if family is not None:
        from socialzoo.scenarios.catalogue import get_family

        try:
            own = get_family(family).map_name
        except KeyError:
            own = ""  # an unknown family: the env's own error names it
        if own and own != "arena":
            return own
    return "gdc1"


def check_family_fits(owner: str, family: str, map_name: str) -> None:
    """Refuse a scenario family that lays out no scenario on map `map_name` (a corridor, door or
    crossing ways it needs that the map lacks, or people where no route reaches): the training env
    would fail at its first reset, inside the run. Checked on another map than the family's own.

    Raises:
        ValueError: the family does not fit the map (naming both, and why).
    """
    from socialzoo.maps.map_file import load_map
    from socialzoo.scenarios.catalogue import get_family

    try:
        m = load_map(map_name)
    except (OSError, ValueError):
        return  # the run folder's map check names the map (run_dir.map_digest)
    try:
        get_family(family).make(0, m=m)
    except ValueError as err:
        raise ValueError(f"{owner}: family {family!r} does not fit map {map_name!r} ({err})") from None


def env_id_of(config: EnvConfig) -> str:
    """The registered Gymnasium id a policy trained on `config` records (its version is checked when
    the policy loads): the benchmark id of the map (its reference id with the reference code's
    quirks on), the family's id, else the benchmark's id."""
    from socialzoo.env.registration import BENCHMARK_IDS, FAMILY_IDS, REFERENCE_IDS

    if config.quirks.any and not config.family:
        for env_id, kwargs in REFERENCE_IDS.items():
            if kwargs["map"] == config.map:
                return env_id
    for env_id, kwargs in FAMILY_IDS.items() if config.family else BENCHMARK_IDS.items():
        if kwargs.get("family") == config.family and kwargs.get("map") == config.map:
            return env_id
    return next(iter(BENCHMARK_IDS))


def make_training_env(args: SB3Args, config: EnvConfig) -> tuple[Any, Any]:
    """(the VecEnv to train on, its VecNormalize or None): SB3VecEnv -> VecMonitor (episode returns
    and lengths for SB3's logs) -> VecNormalize (observations, and rewards if asked)."""
    from stable_baselines3.common.vec_env import VecMonitor, VecNormalize

    from socialzoo.env.sb3_vec import SB3VecEnv

    venv = VecMonitor(SB3VecEnv(args.num_envs, config))
    if not (args.normalize or args.normalize_reward):
        return venv, None
    norm = VecNormalize(venv, norm_obs=args.normalize, norm_reward=args.normalize_reward, gamma=args.gamma)
    return norm, norm


# Episode metrics every SB3 trainer logs to TensorBoard as episode/<key> (those its task reports).
EPISODE_METRICS = registered(
    "success", "reached", "collision", "timeout", "average_step_reward", "navigation_time"
)


def learn_with_checkpoints(
    run: TrainingRun, model: Any, total_steps: int, every: int, save: Callable[[Path, int], None]
) -> tuple[int, Path]:
    """Train an SB3 model for total_steps env steps with the run's checkpoints (save(path, steps)
    writes one; the last is written at the end if no rollout boundary fell on it); returns (the env
    steps trained, the last checkpoint)."""
    schedule = run.schedule(total_steps, every)
    model.learn(
        total_timesteps=total_steps, callback=checkpoint_callback(run, schedule, save), progress_bar=False
    )
    steps = int(model.num_timesteps)
    last = run.checkpoint_path(total_steps, POLICY_SUFFIX)
    if not last.is_file():
        run.checkpoint(total_steps, lambda path: save(path, steps), POLICY_SUFFIX)
    return steps, last


def _save_at(save: Callable[[Path, int], None], step: int, path: Path) -> None:
    """save(path, step): a checkpoint writer of one step (functools.partial binds save and step)."""
    save(path, step)


def checkpoint_callback(
    run: TrainingRun, schedule: CheckpointSchedule, save: Callable[[Path, int], None]
) -> Any:
    """An SB3 BaseCallback that checkpoints through the run once the model has trained on each
    checkpoint's env steps (at the start of the next rollout, or at the end of training), logs the
    success rate and metrics of finished episodes, and drives the run's progress display."""
    from stable_baselines3.common.callbacks import BaseCallback

    total = schedule.steps[-1]

    class PolicyCheckpoints(BaseCallback):
        def _on_training_start(self) -> None:
            self.bar = run.progress(total, desc=f"train {run.trainer.name}")

        def _save_due(self) -> None:
            for step in schedule.due(self.num_timesteps):
                if step != self.num_timesteps:
                    logger.warning("checkpoint %d written at step %d", step, self.num_timesteps)
                run.checkpoint(step, functools.partial(_save_at, save, step), POLICY_SUFFIX)

        def _on_rollout_start(self) -> None:
            self._save_due()

        def _on_step(self) -> bool:
            self.bar.update(self.training_env.num_envs)
            for info in self.locals.get("infos", ()):
                metrics = info.get("metrics")
                if metrics is not None:
                    for key in EPISODE_METRICS:
                        value = metrics.get(key)
                        if value is not None and value == value:  # NaN: not defined for this episode
                            self.logger.record_mean(f"episode/{key}", float(value))
            return True

        def _on_training_end(self) -> None:
            self._save_due()

    return PolicyCheckpoints()


def run_sb3(trainer: SB3Trainer, args: SB3Args) -> Path:
    """Train one SB3 model as `args` say on the trainer skeleton; returns the final policy file.

    The model is stable_baselines3.<trainer.model>("MlpPolicy", the training env,
    **args.model_kwargs(trainer.activation)), seeded with args.seed. A finished run of the same
    arguments in args.out is not repeated: its policy file is returned.

    A run trains on the batched SB3VecEnv (scenarios from the env's own seeded stream, never a test set),
    optionally behind VecNormalize, and writes into its run folder (socialzoo.train.skeleton): a policy file
    every `checkpoint_every` env steps (checkpoints/step_<steps>.safetensors: the policy after training on
    that many steps), TensorBoard logs of SB3's losses and of the episodes' success, and the final policy file
    <algo>.safetensors.
    """
    from socialzoo.train.validation import validation_evaluator

    evaluator = None
    if args.eval_trials:
        # Validation episodes end at the training's time limit, which args.max_steps sets over
        # env_overrides (env_config).
        overrides = {**dict(args.env_overrides), "max_steps": args.max_steps}
        evaluator = validation_evaluator(
            trainer.name, args.map, args.eval_trials, env_overrides=overrides, family=args.family
        )
    return run_training(trainer, args, lambda run: _fit(run, trainer, args), evaluator=evaluator)


def quiet_logger() -> Any:
    """An SB3 logger that writes nothing, anywhere: a model learns with it and leaves no folder behind.

    SB3 gives a model that has no logger one of its own on its first learn(), made by
    stable_baselines3.common.logger.configure: with no folder named, that makes an empty
    <temp folder>/SB3-<date and time> for every such model, even with no output at all."""
    from stable_baselines3.common.logger import Logger

    return Logger(folder=None, output_formats=[])


def sb3_model(run: TrainingRun, model: str, venv: Any, kwargs: Mapping[str, Any]) -> Any:
    """stable_baselines3.<model>("MlpPolicy", venv, **kwargs) on the CPU, silent, logging to the run's
    tensorboard/."""
    import stable_baselines3
    from stable_baselines3.common.logger import configure

    with warnings.catch_warnings():
        # PPO warns that 2,000 is no multiple of 64: the last minibatch holds 16 samples, and an
        # epoch has 32 minibatches, as with SB3's default rollout of 2,048.
        warnings.filterwarnings("ignore", message=".*mini-batch size.*")
        made = getattr(stable_baselines3, model)(
            "MlpPolicy", venv, **{"device": "cpu", "verbose": 0, **kwargs}
        )
    made.set_logger(configure(str(run.path / "tensorboard"), ["tensorboard"]))
    return made


def sb3_training_record(run: TrainingRun, algo: str, step: int, **extra: Any) -> dict[str, Any]:
    """The training record of an SB3 model's policy file after `step` env steps: algorithm, library,
    seed, steps, the run's command and arguments, and `extra` (its env or task), with its paths as
    run.json holds them (TrainingRun.recorded)."""
    record = {"algo": algo, "library": "stable-baselines3", "seed": run.args.seed, "steps": step}
    return run.recorded({**record, "command": run.record["command"], "args": run.record["args"], **extra})


def _fit(run: TrainingRun, trainer: SB3Trainer, args: SB3Args) -> Mapping[str, Any]:
    from socialzoo.train.run_dir import plain
    from socialzoo.train.sb3_export import export_policy

    config = args.env_config()
    observation = plain(config.observation)
    venv, norm = make_training_env(args, config)
    model = sb3_model(run, trainer.model, venv, args.model_kwargs(trainer.activation))
    algo = trainer.name

    def save(path: Path, step: int) -> None:
        policy, output = export_policy(model, algo, observation, norm)
        header = {
            "env_id": env_id_of(config),
            "network": {"output": output},
            "training": sb3_training_record(run, algo, step, env=config.to_dict()),
        }
        policy.save(path, header)

    steps, last = learn_with_checkpoints(run, model, args.total_steps, args.checkpoint_every, save)
    run.policy.write_bytes(last.read_bytes())
    model.get_env().close()
    return {"env_steps": steps, "env_steps_per_second": round(steps / run.seconds, 1)}
