"""`socialzoo benchmark` (evaluate policies on the benchmark's test sets: store, tables, figures) and
`socialzoo demos` (record Ref demonstrations for the imitation baselines)."""

from __future__ import annotations

import argparse
import re
from pathlib import Path
from typing import Any

from socialzoo.cli import command_help, fail
from socialzoo.cli.arg_types import (
    add_backend_arguments,
    add_task_config_argument,
    comma_list,
    given,
    out_dir,
    out_file,
    positive_int,
    split_commas,
    task_config,
)
from socialzoo.cli.dataclass_args import dataclass_from_namespace
from socialzoo.cli.humans_cmd import people_spec


def _lower_name(spec: str) -> str:
    """A policy spec with its registry name lower-cased and a ':PATH' kept as written."""
    name, sep, path = spec.partition(":")
    return name.lower() + sep + path


_policy_specs = comma_list("policies", _lower_name)


def _map_name(name_or_path: str) -> str:
    """A shipped map's name lower-cased, a map file's path kept as written."""
    from socialzoo.maps.map_file import names_a_file  # the CLI starts without numpy

    return name_or_path if names_a_file(name_or_path) else name_or_path.lower()


_map_names = comma_list("map names or paths", _map_name)


def add_benchmark_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add `benchmark` to a subparsers object; returns its parser."""
    parser = subparsers.add_parser(
        "benchmark",
        help=command_help("benchmark"),
        description=(
            "Evaluate policies on the Social Action Selection benchmark: each policy on the first N "
            "scenarios of each map's test set (<map>-test: 2000 scenarios; <map>-quick: 100; any other "
            "map, e.g. an imported building's JSON, gets a seeded test set stored in DIR/test_sets/). Trials "
            "go to DIR/results.sqlite as they finish; a rerun reads stored trials and an interrupted "
            "run resumes. Writes DIR/summary.csv, summary.md, success.{png,pdf}, failures.{png,pdf}, "
            "metrics.{png,pdf} and config.json."
        ),
    )
    parser.add_argument(
        "--policies",
        type=_policy_specs,
        default=None,
        help="comma-separated policies: registry names (a learned policy's name alone is its shipped file) "
        "or NAME:PATH for a policy file (default goalone,ref)",
    )
    parser.add_argument(
        "--maps",
        type=_map_names,
        default=None,
        help=(
            "comma-separated maps: shipped names or map JSON files (default gdc1,ghc3); a map without a "
            "registered test set gets one generated on first use, stored in DIR/test_sets/ with the "
            "map's hash and reused by reruns; or registered task ids (socialzoo/CrowdNav-v1, "
            "socialzoo/CrowdNav20-v1, any task's NAMESPACE/Name-vN, or MODULE:NAMESPACE/Name-vN for an id that "
            "MODULE registers: their fixed test cases)"
        ),
    )
    parser.add_argument(
        "--trials", type=positive_int, default=None, help="scenarios per policy and map (default: all)"
    )
    add_backend_arguments(parser, "trials")
    parser.add_argument(
        "--max-steps", type=positive_int, default=None, help="episode time limit override, steps"
    )
    parser.add_argument(
        "--humans",
        default="social_force",
        help="the people, a people spec that the env drives: social_force (sf, the default), orca, groups, "
        "learned:PATH (a learned human policy file, socialzoo train humans), learned (the shipped learned "
        "humans), or a mix such as "
        "sf@0.5+orca@0.5 or learned:PATH@0.4+sf@0.6. Several, comma-separated "
        "(e.g. sf,orca,groups,learned:PATH), run every policy among every crowd model with counterfactual "
        "rows and write DIR/matrix.md, matrix.csv and matrix.png (success, collisions, force, blame, "
        "the people's time lost and extra distance), one folder per model",
    )
    parser.add_argument(
        "--counterfactual",
        action="store_true",
        help="also run every scenario without the robot and record the people's time lost and extra "
        "distance walked because of it (people_time_lost, people_extra_distance)",
    )
    parser.add_argument(
        "--human-metrics",
        action="store_true",
        help="also record the humans' metrics (goal reach, collisions, distances, speed, path ratio) "
        "in humans.csv and humans.md",
    )
    parser.add_argument("--out", type=out_dir, required=True, help="output directory")
    parser.add_argument(
        "--quick",
        action="store_true",
        help="GoAlone, Ref and the paper's learned policies (PPO, DQN, BC, GAIL, PIPS; shipped files) on "
        "gdc1-quick and ghc3-quick (100 trials each), plus one Ref episode GIF (ref_episode.gif, which a "
        "rerun without --quick removes)",
    )
    add_task_config_argument(parser)
    parser.add_argument(
        "--no-figures",
        action="store_true",
        help="skip the figures, removing those an earlier run drew into --out (no matplotlib needed)",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.set_defaults(
        func=run_benchmark_command,
        resume_hint="the finished trials are kept in the results store: the same command resumes",
    )
    return parser


def add_demos_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add `demos` to a subparsers object; returns its parser."""
    parser = subparsers.add_parser(
        "demos",
        help=command_help("demos"),
        description=(
            "Record demonstrations of the reference policy (obs, action, next_obs, reward, terminated, "
            "truncated, episode) on scenarios of their own seeds. Chunks are written to FILE.parts/ as "
            "they finish, so an interrupted recording resumes; then they are merged into FILE."
        ),
    )
    parser.add_argument("--episodes", type=positive_int, required=True, help="number of episodes")
    parser.add_argument("--out", type=out_file, required=True, help="output .npz file")
    parser.add_argument("--map", default="gdc1", help="map (default gdc1, the training map)")
    parser.add_argument("--policy", type=str.lower, default="ref", help="demonstrating policy (default ref)")
    parser.add_argument("--chunk-episodes", type=positive_int, default=25, help="episodes per chunk file")
    parser.add_argument("--batch-size", type=positive_int, default=64, help="env rows stepped together")
    parser.add_argument(
        "--max-steps", type=positive_int, default=None, help="episode time limit override, steps"
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.set_defaults(
        func=run_demos_command, resume_hint="the finished chunks are kept: the same command resumes"
    )
    return parser


def register(subparsers: Any) -> None:
    """Add both subcommands."""
    add_benchmark_parser(subparsers)
    add_demos_parser(subparsers)


def run_benchmark_command(args: argparse.Namespace) -> int:
    """Run `socialzoo benchmark`; returns the exit status."""
    from socialzoo.bench.experiment import BenchmarkConfig, quick_config, run_benchmark
    from socialzoo.bench.figures import pyplot
    from socialzoo.bench.store import StoreError
    from socialzoo.bench.tables import policy_label

    if not args.no_figures:
        try:  # before the trials, not after them
            pyplot()
        except ModuleNotFoundError as err:
            return fail("benchmark", f"{err}, or pass --no-figures")
    ids = [m for m in args.maps or () if ENV_ID.fullmatch(m)]
    if ids:
        return run_task_ids(args, ids)
    if args.task_config:
        return fail("benchmark", "--task-config sets a task id's config: name the id in --maps")
    specs = list(split_commas(args.humans))
    if len(specs) > 1:
        return run_matrix_command(args, specs)
    chosen = {
        **_runner_choices(args),
        "humans": people_spec(args.humans),
        "human_metrics": args.human_metrics,
        "counterfactual": args.counterfactual,
    }
    try:
        config = quick_config(**chosen) if args.quick else BenchmarkConfig(**chosen)
        result = run_benchmark(config, args.out, progress=not args.no_progress, figures=not args.no_figures)
    except (ValueError, KeyError, StoreError, FileNotFoundError) as err:
        return fail("benchmark", err)
    print(f"{result.computed} trials run, {result.reused} read from the store, in {result.seconds:.1f} s")
    for entry in result.summary:
        print(
            f"  {policy_label(entry['policy']):>8} on {entry['map']:<6} success "
            f"{100 * entry['success_rate']:5.1f}% [{100 * entry['success_ci_low']:.1f}, "
            f"{100 * entry['success_ci_high']:.1f}] over {entry['trials']} trials"
        )
    print(f"results in {args.out}: " + ", ".join(p.name for p in result.files))
    return 0


def run_task_ids(args: argparse.Namespace, ids: list[str]) -> int:
    """`socialzoo benchmark --maps ID[,ID...]` with registered task ids (socialzoo/CrowdNav-v1, any
    task's id): each id's policies on the first --trials cases of its test split, stored and reused
    by reruns, with tables and the success figure (socialzoo.bench.task_benchmark), one folder per id."""
    from socialzoo.bench.store import StoreError
    from socialzoo.bench.task_benchmark import TaskId, run_task_benchmark, task_policies

    if len(ids) != len(args.maps):
        others = sorted(set(args.maps) - set(ids))
        return fail("benchmark", f"task ids cannot be mixed with benchmark maps {others}")
    if args.humans != "social_force" or args.counterfactual or args.human_metrics or args.quick:
        return fail(
            "benchmark",
            "--humans, --counterfactual, --human-metrics and --quick are options of the benchmark maps, "
            "not of a task id (its config says who walks)",
        )
    if args.backend != "local" or args.address is not None or args.workers is not None:
        return fail(
            "benchmark",
            "--backend, --address and --workers are options of the benchmark maps: a task id's cases are "
            "played in this process, --batch-size rows at once",
        )
    try:
        # --max-steps is a field of the task's config (a task without max_steps refuses it).
        config = given(args, "max_steps") | task_config(args.task_config)
        folders = _id_folders(ids)
        chosen = {}
        for env_id in ids:
            task = TaskId.of(env_id)
            default = _DEFAULT_POLICIES.get(task.task, ())
            chosen[env_id] = list(args.policies) if args.policies else list(default)
            if not chosen[env_id]:
                raise ValueError(f"{env_id}: name the policies to run (--policies)")
            if len(ids) > 1:  # every id's policies are refused before the first id plays
                task_policies(task, chosen[env_id], config)
        for env_id, policies in chosen.items():
            out = Path(args.out) / folders[env_id] if len(ids) > 1 else Path(args.out)
            _, files = run_task_benchmark(
                env_id,
                policies,
                out,
                cases=args.trials,
                batch_size=args.batch_size or 100,
                figures=not args.no_figures,
                say=print,
                config=config,
            )
            print(f"results in {out}: " + ", ".join(p.name for p in files))
    except (ValueError, StoreError) as err:
        return fail("benchmark", err)
    return 0


# A Gymnasium id (namespace/Name-vN, or module:namespace/Name-vN: the module registers it), told
# apart from map names and map files.
ENV_ID = re.compile(r"(?:[A-Za-z_][\w.]*:)?[A-Za-z0-9_.-]+/[A-Za-z0-9_.]+-v\d+")
# The policies a task id's benchmark runs when --policies names none.
_DEFAULT_POLICIES: dict[str, tuple[str, ...]] = {"crowdnav": ("orca", "social_force", "crowdnav")}


def _runner_choices(args: argparse.Namespace) -> dict[str, Any]:
    """The options a benchmark run and the matrix's runs share, as their configs' fields: those not given
    keep the config's defaults, but no --workers with --backend ray is None (one chunk per CPU of
    the Ray cluster)."""
    chosen = {
        "backend": args.backend,
        "address": args.address,
        "batch_size": args.batch_size,
        "env_overrides": given(args, "max_steps"),
        **given(args, "policies", "maps", "trials", "workers"),
    }
    if args.workers is None and args.backend == "ray":
        chosen["workers"] = None
    return chosen


def run_matrix_command(args: argparse.Namespace, specs: list[str]) -> int:
    """`socialzoo benchmark --humans A,B,...`: every policy among every crowd model (the matrix)."""
    from socialzoo.bench.store import StoreError
    from socialzoo.studies.crowd_matrix import MatrixConfig, crowd_matrix

    if args.quick:
        return fail("benchmark", "several --humans make a matrix: without --quick")
    try:
        config = MatrixConfig(humans=tuple(map(people_spec, specs)), **_runner_choices(args))
        result = crowd_matrix(config, args.out, progress=not args.no_progress, figures=not args.no_figures)
    except (ValueError, KeyError, StoreError, FileNotFoundError) as err:
        return fail("benchmark", err)
    print((result.out_dir / "matrix.md").read_text())
    print(f"results in {args.out}: " + ", ".join(p.name for p in result.files))
    return 0


def run_demos_command(args: argparse.Namespace) -> int:
    """Run `socialzoo demos`; returns the exit status."""
    from socialzoo.agents.demonstrations import DemonstrationError, load_demonstrations
    from socialzoo.bench.demonstrations import DemoConfig, record_demonstrations

    try:
        config = dataclass_from_namespace(DemoConfig, args, env_overrides=given(args, "max_steps"))
        path = record_demonstrations(args.out, config, progress=not args.no_progress)
        arrays, _ = load_demonstrations(path)
    except (ValueError, KeyError, DemonstrationError) as err:
        return fail("demos", err)
    print(f"{path}: {len(arrays['episode_ids'])} episodes, {len(arrays['action'])} steps")
    return 0


def _id_folders(ids: list[str]) -> dict[str, str]:
    """Each task id's folder under --out: its name without the namespace ("Name-vN"), or, where two
    ids share that name (a/X-v0 and b/X-v0), the whole id with "_" for its "/" and ":"."""
    short = {env_id: env_id.split("/")[-1] for env_id in ids}  # an id given twice is one id
    taken = list(short.values())
    return {
        env_id: name if taken.count(name) == 1 else env_id.replace("/", "_").replace(":", "_")
        for env_id, name in short.items()
    }
