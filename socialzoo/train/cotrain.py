"""`socialzoo train cotrain`: robots and learned humans trained together with MAPPO or IPPO."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from socialzoo.train.checks import check_choice, check_int, check_number
from socialzoo.train.marl_args import HUMANS_POLICY_FILE, ROBOT_POLICY_FILE, MarlArgs
from socialzoo.train.skeleton import Trainer

Schedule = Literal["simultaneous", "alternating"]
SCHEDULES: tuple[str, ...] = ("simultaneous", "alternating")


@dataclass(frozen=True)
class CotrainTrainer(Trainer):
    """Co-training's final policy is the humans' file, or the robots' when no human is learned."""

    def policy_path(self, args: Any) -> Path:
        """humans.safetensors, or robot.safetensors without learned humans (in the run's env config:
        env_overrides may set them too)."""
        humans = args.env_config().num_learned_humans
        return self.folder(args) / (HUMANS_POLICY_FILE if humans else ROBOT_POLICY_FILE)


TRAINER = CotrainTrainer("cotrain", policy_file=HUMANS_POLICY_FILE)


@dataclass(frozen=True, kw_only=True)
class CotrainArgs(MarlArgs):
    """Train robots (one shared policy) and learned humans together with MAPPO or IPPO.

    The arguments every multi-agent trainer takes are socialzoo.train.marl_args.MarlArgs; these
    are co-training's own, and the defaults it changes.

    Attributes:
        out: the run folder (run.json, tensorboard/, checkpoints/, history.csv, humans.safetensors,
            robot.safetensors).
        algo: "mappo" (centralised critics) or "ippo" (per-agent critics), for both groups.
        num_robots: robots per world, all sharing one policy.
        schedule: "simultaneous" (both groups learn on every batch) or "alternating" (turns).
        alternate_every: batches per turn with schedule=alternating (robots first).
        robot_lr: Adam learning rate of the robots.
    """

    num_robots: int = 2
    schedule: Schedule = "simultaneous"
    alternate_every: int = 5
    robot_lr: float = 3e-4

    def __post_init__(self) -> None:
        check_choice(self, "schedule", SCHEDULES)
        check_int(self, "alternate_every", low=1)
        check_number(self, "robot_lr", low=0, low_open=True)
        super().__post_init__()

    def groups_at(self, index: int) -> Sequence[str]:
        """The groups updated on collected batch `index` (robots take the first turn)."""
        learned = ["robot", "human"] if self.env_config().num_learned_humans else ["robot"]
        if self.schedule == "simultaneous" or len(learned) == 1:
            return learned
        return [learned[(index // self.alternate_every) % 2]]


def train(args: CotrainArgs) -> Path:
    """Train robots and humans together; returns the path of humans.safetensors (robot.safetensors
    beside it), or of robot.safetensors when no human is learned.

    Both groups of the native env learn: the robots (several per world share one policy, a Categorical over
    the four sub-policies, with the benchmark's reward, SPEC section 9) and the learned humans (as in
    `socialzoo train humans`). Schedule "simultaneous" updates both groups on every collected batch;
    "alternating" updates one group for `alternate_every` batches, then the other, while both keep acting (the
    other group's policy is frozen meanwhile). Load humans.safetensors with `socialzoo benchmark --humans
    learned:PATH`, and robot.safetensors (a socialzoo policy file) with `socialzoo benchmark --policies
    mappo:PATH`.
    """
    from socialzoo.train.marl_run import run_marl

    return run_marl(TRAINER, args, robot_policy=None, schedule=args.groups_at)
