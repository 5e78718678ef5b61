"""`socialzoo train humans`: learned humans trained with MAPPO or IPPO while the robot runs a policy."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from socialzoo.train.marl_args import HUMANS_POLICY_FILE, MarlArgs
from socialzoo.train.skeleton import Trainer

TRAINER = Trainer("humans", policy_file=HUMANS_POLICY_FILE, inputs=("robot",))


@dataclass(frozen=True, kw_only=True)
class HumansArgs(MarlArgs):
    """Train learned humans with MAPPO or IPPO (shared parameters) while the robot runs a policy.

    The arguments every multi-agent trainer takes are socialzoo.train.marl_args.MarlArgs (their
    defaults are this trainer's); this is the robot's.

    Attributes:
        out: the run folder (run.json, tensorboard/, checkpoints/, history.csv, humans.safetensors).
        robot: the robot's policy spec (socialzoo.agents.make_policy), e.g. ref, goalone, ppo:PATH.
        num_robots: robots per world (all run the robot policy).
    """

    robot: str = "ref"

    def __post_init__(self) -> None:
        from socialzoo.agents import check_policy_spec

        try:
            check_policy_spec(self.robot)
        except ValueError as err:
            raise ValueError(f"HumansArgs.robot: {err}") from None
        super().__post_init__()
        if not self.env_config().num_learned_humans:
            raise ValueError(
                "HumansArgs.num_learned_humans must be >= 1: this trainer learns humans only (the robots "
                f"run {self.robot!r}), got 0"
            )


def train(args: HumansArgs) -> Path:
    """Train the learned humans; returns the path of humans.safetensors.

    Every learned human of a world shares one policy (TanhNormal over its desired velocity in its own frame,
    socialzoo.env.human_agents), trained with TorchRL's MAPPOLoss (centralised critic over the group's
    observations) or IPPOLoss (per-agent critic) on batches collected from the native env
    (socialzoo.env.torchrl_env) by a TorchRL collector: in this process, over local processes, or on a Ray
    cluster. The robot meanwhile acts with any policy spec ("ref", "goalone", "ppo:PATH", ...); scripted
    social-force humans fill the slots beyond num_learned_humans. The run folder (socialzoo.train.run_dir)
    holds run.json, TensorBoard logs, checkpoints/ and the final policy humans.safetensors, which `socialzoo
    benchmark --humans learned:PATH` loads.
    """
    from socialzoo.train.marl_run import run_marl

    return run_marl(TRAINER, args, robot_policy=args.robot)
