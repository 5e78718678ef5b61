"""`socialzoo demo`: an animated GIF or MP4 of one episode with a chosen policy."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from socialzoo.cli import command_help, fail
from socialzoo.cli.arg_types import (
    add_case_arguments,
    add_scenario_arguments,
    count,
    given_flags,
    out_file,
    positive_int,
    task_config,
)


def register(subparsers: Any) -> None:
    """Add `demo`."""
    parser = subparsers.add_parser(
        "demo",
        help=command_help("demo"),
        description=(
            "Run one episode with a policy and write it as an animation: a benchmark map's scenario "
            "(--map, --family, --seed), or a fixed case of any registered task id (--env, --case, --split)."
        ),
    )
    parser.add_argument(
        "--policy",
        default=None,
        help="policy name (goalone, ref, ...; default ref; with --env one of its task's: orca, crowdnav, ...)",
    )
    parser.add_argument("--policy-path", type=Path, default=None, help="saved file of a learned policy")
    add_scenario_arguments(parser)
    parser.add_argument("--seed", type=count, default=None, help="scenario seed (default 0)")
    add_case_arguments(parser)
    parser.add_argument("--view", choices=("follow", "map"), default="follow", help="camera")
    parser.add_argument(
        "--stride",
        type=positive_int,
        default=None,
        help="steps per frame (default: those of 0.1 s, 4 of the action-selection task's 25 ms steps, "
        "every step of the CrowdNav task's 0.25 s)",
    )
    parser.add_argument(
        "--fps", type=float, default=None, help="frames per second of the file (default: twice real time)"
    )
    parser.add_argument("--max-frames", type=positive_int, default=800, help="longest animation, frames")
    parser.add_argument("--out", type=out_file, default=Path("episode.gif"), help=".gif or .mp4 file")
    parser.set_defaults(func=run_demo)


def run_demo(args: argparse.Namespace) -> int:
    """Run `socialzoo demo`; returns the exit status."""
    from socialzoo.bench.episode_play import step_seconds
    from socialzoo.bench.episode_video import animate_episode
    from socialzoo.maps.map_file import MapError

    try:
        if args.env is not None:
            if clash := given_flags(args, "map", "family", "seed"):
                raise ValueError(f"{clash} cannot be combined with --env: a task id plays its own cases")
            task, policy, label = _case(args)
        else:
            if clash := given_flags(args, "case", "split", "task_config"):
                raise ValueError(f"{clash} cannot be used without --env")
            task, policy, label = _scenario(args)
        # Frames of 0.1 s unless asked otherwise, whatever the task's step.
        stride = args.stride or max(1, round(0.1 / step_seconds(task)))
        fps = args.fps or 2.0 / (stride * step_seconds(task))
        video = animate_episode(
            args.out, task, policy, label=label, view=args.view, stride=stride, fps=fps,
            max_frames=args.max_frames,
        )  # fmt: skip
    except (MapError, FileNotFoundError, ValueError, KeyError) as err:
        return fail("demo", err)
    print(
        f"{video.path}: {video.frames} frames; {video.outcome} at {video.seconds:.1f} s ({video.steps} steps)"
    )
    return 0


def _learned_file(args: argparse.Namespace) -> dict[str, Any]:
    """make_policy's keyword arguments for --policy-path."""
    return {} if args.policy_path is None else {"path": args.policy_path}


def _scenario(args: argparse.Namespace) -> tuple[Any, Any, str]:
    """(task, policy, label) of a benchmark map's scenario: --map, --family, --seed."""
    from socialzoo.agents import make_policy
    from socialzoo.bench.episode_play import scenario_task
    from socialzoo.bench.replay import benchmark_scenario
    from socialzoo.env.config import EnvConfig
    from socialzoo.maps.map_file import load_map
    from socialzoo.scenarios.catalogue import family_name

    config = EnvConfig(map=args.map, family=args.family and family_name(args.family))
    m = load_map(config.map_name)
    seed = args.seed or 0
    name = args.policy or "ref"
    policy = make_policy(name, **_learned_file(args))  # before the scenario is made
    task = scenario_task(config, benchmark_scenario(config, seed, m), m)
    return task, policy, f"{name} on {m.name}, seed {seed}"


def _case(args: argparse.Namespace) -> tuple[Any, Any, str]:
    """(task, policy, label) of a fixed case of a registered task id: --env, --case, --split, --task-config."""
    from socialzoo.agents import make_policy
    from socialzoo.bench.replay import case_task
    from socialzoo.bench.task_benchmark import TaskId, acting_overrides

    if args.policy is None:
        raise ValueError(f"name the policy to play on {args.env} (--policy)")
    overrides = task_config(args.task_config)
    probe = TaskId.of(args.env).make(1, **overrides)
    policy = make_policy(args.policy, task=probe, **_learned_file(args))
    case, split = args.case or 0, args.split or "test"
    task = case_task(args.env, split, case, **acting_overrides(policy, overrides))
    label = f"{args.policy} on {args.env}, {split} case {case}"
    return task, policy, label + "".join(f", {k}={v}" for k, v in overrides.items())
