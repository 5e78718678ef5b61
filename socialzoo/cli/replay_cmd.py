"""`socialzoo replay`: one or several policies on one scenario, written as a self-contained HTML
viewer (socialzoo.render.replay_html), from a seed or from a trial of a benchmark results store."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from socialzoo.cli import command_help, fail
from socialzoo.cli.arg_types import (
    add_case_arguments,
    add_scenario_arguments,
    at_least,
    comma_list,
    count,
    given,
    given_flags,
    out_file,
    task_config,
)


def register(subparsers: Any) -> None:
    """Add `replay`."""
    parser = subparsers.add_parser(
        "replay",
        help=command_help("replay"),
        description=(
            "Run policies on one scenario and write one self-contained HTML file that plays the "
            "episodes side by side on a shared timeline: walls, humans and their velocities, the robot's "
            "footprint, laser, global plan and carrot, the sub-policy at each step, and charts of reward, "
            "force and blame. The scenario comes from --map/--seed (as in socialzoo demo), or from a trial "
            "stored by socialzoo benchmark (--results DIR --trial N), which is re-run and checked against "
            "the stored metrics."
        ),
    )
    parser.add_argument(
        "--policy",
        action="append",
        type=comma_list("policies"),
        default=None,
        metavar="NAME[=PATH][,...]",
        help="policies, comma-separated or repeated; NAME=PATH loads a learned policy's file "
        "(default ref; with --results: every policy stored for the trial)",
    )
    parser.add_argument(
        "--policy-path", type=Path, default=None, help="saved file of the (single) learned policy"
    )
    add_scenario_arguments(parser)
    parser.add_argument("--seed", type=count, default=None, help="scenario seed (default 0)")
    parser.add_argument(
        "--max-steps", type=at_least(1), default=None, help="episode time limit override, steps"
    )
    add_case_arguments(parser)
    parser.add_argument(
        "--results", type=Path, default=None, help="a socialzoo benchmark --out directory (with --trial)"
    )
    parser.add_argument(
        "--trial", type=count, default=None, help="scenario index of the stored trial (with --results)"
    )
    parser.add_argument(
        "--test-set", default=None, help="test set (or map) of the stored trial, if the store holds several"
    )
    parser.add_argument(
        "--view", choices=("follow", "map"), default="follow", help="camera the page opens with"
    )
    parser.add_argument(
        "--stride",
        type=at_least(1),
        default=None,
        help="steps per stored frame (default: those of 50 ms, 2 of the action-selection task's "
        "25 ms steps, every step of the CrowdNav task's 0.25 s)",
    )
    parser.add_argument(
        "--laser-rays", type=count, default=60, help="laser rays drawn (default 60; 0: no laser)"
    )
    parser.add_argument("--out", type=out_file, default=Path("episode.html"), help="the .html file to write")
    parser.set_defaults(func=run_replay)


def _specs(args: argparse.Namespace) -> list[Any]:
    """The requested policies as PolicySpecs (none: an empty list)."""
    from socialzoo.bench.replay import PolicySpec

    texts = [t for group in (args.policy or []) for t in group]
    specs = [PolicySpec.parse(t) for t in texts]
    if args.policy_path is not None:
        if len(specs) > 1 or (specs and specs[0].kwargs):
            raise ValueError("--policy-path goes with a single --policy; for several use --policy NAME=PATH")
        name = specs[0].name if specs else "ref"
        specs = [PolicySpec.parse(f"{name}={args.policy_path}")]
    names = [s.label for s in specs]
    if len(set(names)) != len(names):
        raise ValueError(f"--policy names a policy twice: {names}")
    return specs


def _size(path: Path) -> str:
    size = path.stat().st_size
    return f"{size / 1e6:.1f} MB" if size >= 1e6 else f"{size / 1e3:.0f} kB"


def _describe(trace: Any) -> str:
    return f"{trace.outcome} at {trace.num_steps * trace.dt:.2f} s ({trace.num_steps} steps)"


def run_replay(args: argparse.Namespace) -> int:
    """Run `socialzoo replay`; returns the exit status (1 when a stored trial is not reproduced)."""
    from socialzoo.bench.store import StoreError
    from socialzoo.maps.map_file import MapError

    try:
        if args.out.suffix.lower() not in (".html", ".htm"):
            raise ValueError(f"--out {args.out} must end in .html")
        if args.env is not None:
            if clash := given_flags(args, "map", "family", "seed", "results", "trial"):
                raise ValueError(f"{clash} cannot be combined with --env: a task id plays its own cases")
            return _replay_case(args)
        if clash := given_flags(args, "case", "split", "task_config"):
            raise ValueError(f"{clash} cannot be used without --env")
        if (args.results is None) != (args.trial is None):
            raise ValueError("--results and --trial go together")
        if args.results is not None:
            if clash := given_flags(args, "map", "family", "seed", "max_steps"):
                raise ValueError(
                    f"{clash} cannot be combined with --results: "
                    "a stored trial runs with its own map, scenario and env config"
                )
            return _replay_stored(args)
        if args.test_set is not None:
            raise ValueError("--test-set goes with --results")
        return _replay_seed(args)
    except (MapError, StoreError, FileNotFoundError, ValueError, KeyError) as err:
        return fail("replay", err)


def _write_page(args: argparse.Namespace, scene: Any, traces: list[Any], what: str, lines: list[str]) -> None:
    """Write the page of `traces` to --out (states every --stride steps, else those of 50 ms of each
    episode's own step) and say so: its path, `what` it shows and its size, then `lines`."""
    from socialzoo.render.replay_data import Encoding
    from socialzoo.render.replay_html import write_replay_html

    encoding = Encoding(stride=args.stride, laser_rays=args.laser_rays)
    path = write_replay_html(args.out, scene, traces, encoding=encoding, view=args.view)
    print(f"{path}: {what}; {_size(path)}")
    print("\n".join(lines))


def _described(traces: list[Any]) -> list[str]:
    """A line per episode: its label and how it ended."""
    return [f"  {trace.label}: {_describe(trace)}" for trace in traces]


def _recording(args: argparse.Namespace, dt: float, world_map: Any) -> dict[str, Any]:
    """What the recorders (of fresh episodes, of stored trials replayed) keep of an episode on
    `world_map`: --laser-rays rays, scanned in the states the page keeps (every --stride steps, else
    those of 50 ms of the step dt)."""
    from socialzoo.render.replay_data import default_stride

    return {
        "laser_rays": args.laser_rays,
        "laser_stride": int(args.stride or default_stride(dt)),
        "world_map": world_map,
    }


def _replay_case(args: argparse.Namespace) -> int:
    """`socialzoo replay --env ID --case K`: every policy on one fixed case of any task id."""
    from socialzoo.agents import make_policy
    from socialzoo.bench.replay import record_case
    from socialzoo.bench.task_benchmark import TaskId, acting_overrides

    task_id = TaskId.of(args.env)
    overrides = given(args, "max_steps") | task_config(args.task_config)
    probe = task_id.make(1, **overrides)
    specs = _specs(args)
    if not specs:
        raise ValueError(f"name the policies to play on {args.env} (--policy)")
    case, split = args.case or 0, args.split or "test"
    # Every policy is built before any episode runs.
    policies = [make_policy(s.name, task=probe, **s.kwargs) for s in specs]
    traces, task = [], probe
    for spec, policy in zip(specs, policies, strict=True):
        acting = acting_overrides(policy, overrides)
        trace, task = record_case(args.env, policy, split, case, label=spec.label, **acting)
        traces.append(trace)
    title = f"{' vs '.join(t.label for t in traces)} on {args.env}, {split} case {case}"
    title += "".join(f", {k}={v}" for k, v in task_config(args.task_config).items())
    scene = task.viewer_scene(title, f"the {probe.name} task", traces)
    what = f"{len(traces)} episode(s) on {args.env}, {split} case {case}"
    _write_page(args, scene, traces, what, _described(traces))
    return 0


def _replay_seed(args: argparse.Namespace) -> int:
    from socialzoo.bench.replay import PolicySpec, benchmark_scenario, record_policies, replay_scene
    from socialzoo.env.config import EnvConfig
    from socialzoo.maps.map_file import load_map
    from socialzoo.scenarios.catalogue import family_name

    specs = _specs(args) or [PolicySpec.parse("ref")]
    seed = 0 if args.seed is None else args.seed
    family = args.family and family_name(args.family)
    config = EnvConfig(map=args.map, family=family)  # no --map: the family's, else gdc1
    if args.max_steps is not None:
        config = config.replace(max_steps=args.max_steps)
    m = load_map(config.map_name)
    scenario = benchmark_scenario(config, seed, m)
    traces = record_policies(config, scenario, specs, **_recording(args, config.dt, m))
    kind = f"{family} scenario" if family else "scenario"
    title = f"{' vs '.join(t.label for t in traces)} on {m.name}, {kind} seed {seed}"
    subtitle = (
        f"{len(scenario.human_spawn)} humans; time limit {config.max_steps * config.dt:.0f} s "
        f"({config.max_steps} steps of {config.dt * 1000:.0f} ms)"
    )
    scene = replay_scene(config, m, title, subtitle)
    _write_page(args, scene, traces, f"{len(traces)} episode(s) on {m.name}, seed {seed}", _described(traces))
    return 0


def _replay_stored(args: argparse.Namespace) -> int:
    from socialzoo.bench.replay import record_episode, replay_scene
    from socialzoo.bench.replay_trials import find_trials, map_change, replay_trial
    from socialzoo.maps.map_file import load_map

    specs = _specs(args)
    stored = find_trials(args.results, args.trial, test_set=args.test_set)
    first = stored[0]
    m = load_map(first.env_config.map_name)
    scenario = first.scenario(m)
    recording = _recording(args, first.env_config.dt, m)
    by_name = {t.policy: t for t in stored}
    # The stored trials asked for (all of them by default); a policy the store lacks, or one
    # loaded from a file given here, runs fresh on the trial's scenario and env config.
    wanted = [(s, by_name.get(s.name) if not s.kwargs else None) for s in specs] or [
        (None, t) for t in stored
    ]
    # Fail on a policy that cannot be built before any episode runs.
    fresh = [spec.build() if trial is None and spec is not None else None for spec, trial in wanted]
    traces, lines, failed = [], [], False
    for (spec, trial), policy in zip(wanted, fresh, strict=True):
        if trial is None:
            assert spec is not None and policy is not None
            trace = record_episode(
                first.env_config, scenario, policy, label=f"{spec.label} (not stored)", **recording
            )
            traces.append(trace)
            lines.append(f"  {trace.label}: {_describe(trace)}; not in the store, run fresh")
            continue
        done = replay_trial(trial, **recording)
        traces.append(done.trace)
        changed = map_change(args.results, trial, m) or (
            "the code or config changed since it was stored" if done.code_changed else ""
        )
        note = f" ({changed})" if changed else ""
        if done.mismatches:
            failed = True
            lines.append(
                f"  {done.trace.label}: {_describe(done.trace)}; DOES NOT reproduce the stored trial{note}: "
                + "; ".join(done.mismatches)
            )
        else:
            lines.append(
                f"  {done.trace.label}: {_describe(done.trace)}; "
                f"all {len(trial.metrics)} metrics match the stored trial{note}"
            )
    title = f"{first.test_set} scenario #{first.index}: {' vs '.join(t.label for t in traces)}"
    config = first.env_config
    subtitle = (
        f"{m.name}, seed {first.seed}, {len(scenario.human_spawn)} humans; results {args.results}; "
        f"time limit {config.max_steps * config.dt:.0f} s"
    )
    what = f"{first.test_set} scenario #{first.index} (seed {first.seed}), {len(traces)} episode(s)"
    _write_page(args, replay_scene(config, m, title, subtitle), traces, what, lines)
    if failed:
        print("socialzoo replay: the replay differs from the stored trial (see above)", file=sys.stderr)
        return 1
    return 0
