"""`socialzoo demo`: an animated GIF or MP4 of one episode with a chosen policy."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from socialzoo.cli import command_help, fail
from socialzoo.cli.arg_types import add_scenario_arguments, count, out_file, positive_int


def register(subparsers: Any) -> None:
    """Add `demo`."""
    parser = subparsers.add_parser(
        "demo",
        help=command_help("demo"),
        description="Run one benchmark episode with a policy and write it as an animation.",
    )
    parser.add_argument("--policy", default="ref", help="policy name (goalone, ref, ...; default ref)")
    parser.add_argument("--policy-path", type=Path, default=None, help="saved file of a learned policy")
    add_scenario_arguments(parser)
    parser.add_argument("--seed", type=count, default=0, help="scenario seed (default 0)")
    parser.add_argument("--view", choices=("follow", "map"), default="follow", help="camera")
    parser.add_argument("--stride", type=positive_int, default=4, help="steps per frame (default 4 = 0.1 s)")
    parser.add_argument("--fps", type=float, default=20.0, help="frames per second of the file")
    parser.add_argument("--max-frames", type=positive_int, default=800, help="longest animation, frames")
    parser.add_argument("--out", type=out_file, default=Path("episode.gif"), help=".gif or .mp4 file")
    parser.set_defaults(func=run_demo)


def run_demo(args: argparse.Namespace) -> int:
    """Run `socialzoo demo`; returns the exit status."""
    from socialzoo.agents import make_policy
    from socialzoo.bench.episode_video import animate_episode
    from socialzoo.env.config import EnvConfig
    from socialzoo.env.scenario_source import ScenarioStream
    from socialzoo.maps.map_file import MapError, load_map
    from socialzoo.scenarios.catalogue import family_name

    try:
        config = EnvConfig(map=args.map, family=args.family and family_name(args.family))
        m = load_map(config.map_name)
        scenario = ScenarioStream.for_config(m, 1, config).make(args.seed)
        policy = (
            make_policy(args.policy, path=args.policy_path) if args.policy_path else make_policy(args.policy)
        )
        video = animate_episode(
            args.out,
            config,
            scenario,
            policy,
            label=f"{args.policy} on {m.name}, seed {args.seed}",
            view=args.view,
            stride=args.stride,
            fps=args.fps,
            max_frames=args.max_frames,
        )
    except (MapError, FileNotFoundError, ValueError, KeyError) as err:
        return fail("demo", err)
    result = (
        "success"
        if video.metrics["success"]
        else ("goal reached" if video.metrics["reached"] else "no success")
    )
    print(f"{video.path}: {video.frames} frames; {result} in {video.metrics['duration']:.1f} s")
    return 0
