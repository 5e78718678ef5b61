"""The `socialzoo` command: one entry point, one module per group of subcommands, each imported only when its
subcommand runs, so no command pays for torch, ray or matplotlib unless it runs them."""

from __future__ import annotations

import argparse
import contextlib
import importlib
import logging
import os
import signal
import sys
import threading
from collections.abc import Iterator, Sequence
from concurrent.futures.process import BrokenProcessPool

from socialzoo import __version__

# Subcommand -> (the module that registers it, the line `socialzoo --help` shows for it), in the
# order `socialzoo --help` lists them. A module's register() takes its help lines from here.
COMMANDS: dict[str, tuple[str, str]] = {
    "benchmark": (
        "socialzoo.cli.benchmark_cmd",
        "evaluate policies on the benchmark test sets (results store, tables, figures)",
    ),
    "demos": ("socialzoo.cli.benchmark_cmd", "record Ref demonstrations for the imitation baselines"),
    "demo": ("socialzoo.cli.demo_cmd", "animate one episode of a policy (GIF or MP4)"),
    "crowdnav": (
        "socialzoo.cli.crowdnav_cmd",
        "the CrowdNav task: evaluate velocity policies on its fixed cases, replay an episode",
    ),
    "data": ("socialzoo.cli.data_cmd", "fetch the recorded ETH/UCY pedestrian trajectories, list the cache"),
    "humans": (
        "socialzoo.cli.humans_cmd",
        "the people: compare learned with social-force humans, select a learned checkpoint, "
        "report how each crowd model walks",
    ),
    "map": ("socialzoo.cli.map_cmd", "list, show, validate, check, import and drive maps"),
    "metrics": (
        "socialzoo.cli.metrics_cmd",
        "score episode logs (JSON, any simulator) with the evaluation guidelines' Table I metrics",
    ),
    "replay": (
        "socialzoo.cli.replay_cmd",
        "write an episode (several policies side by side) as an HTML viewer",
    ),
    "reproduce": (
        "socialzoo.cli.reproduce_cmd",
        "regenerate every table and figure of the paper (resumable), with REPRODUCTION.md",
    ),
    "steps-to-ref": (
        "socialzoo.cli.steps_cmd",
        "train PPO on past the paper's 84,000 steps until it matches Ref (validation scenarios)",
    ),
    "study": ("socialzoo.cli.study_cmd", "single experiments with no other command (ref-tradeoff)"),
    "suite": (
        "socialzoo.cli.suite_cmd",
        "policies x the scenario suite's 25 scenarios x seeds: tables, heatmaps, a results page",
    ),
    "train": (
        "socialzoo.cli.train_cmd",
        "train a learned baseline (writes the policy, its run record, checkpoints and logs)",
    ),
}

# The modules that only an extra of pyproject.toml brings (pillow comes with matplotlib and imageio) -> that
# extra: a command that needs one says what to install instead of ending in a traceback.
EXTRA_MODULES: dict[str, str] = {
    **dict.fromkeys(("matplotlib", "imageio", "imageio_ffmpeg", "PIL"), "plot"),
    **dict.fromkeys(
        ("torch", "stable_baselines3", "supersuit", "torchrl", "tensordict", "tensorboard", "z3", "cma"),
        "train",
    ),
    "ray": "ray",
}

# Former subcommands -> the command that took their place; naming one is a usage error (exit 2).
MOVED: dict[str, str] = {"compare-humans": "humans compare", "select-humans": "humans select"}


def command_help(name: str) -> str:
    """The one-line help of subcommand `name` (COMMANDS)."""
    return COMMANDS[name][1]


def fail(command: str, err: object) -> int:
    """Say "socialzoo COMMAND: error: ERR" on stderr; returns 2, the exit status of a usage or input error."""
    print(f"socialzoo {command}: error: {err}", file=sys.stderr)
    return 2


def _chosen_command(argv: Sequence[str]) -> str | None:
    """The subcommand named on the command line: its first word that is not an option."""
    return next((word for word in argv if not word.startswith("-")), None)


def _refuse_moved(parser: argparse.ArgumentParser, argv: Sequence[str]) -> None:
    """Stop with a usage error (exit status 2) naming the new command when argv names a moved one."""
    chosen = _chosen_command(argv)
    if chosen in MOVED:
        new = MOVED[chosen]
        group = new.split()[0]
        parser.error(
            f"'{chosen}' is now 'socialzoo {new}' (`socialzoo {group} --help` lists its subcommands)"
        )


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The argument parser: every subcommand listed, and the one `argv` names (all of them when
    argv is None) registered with its options."""
    parser = argparse.ArgumentParser(
        prog="socialzoo",
        description="socialzoo: social-navigation simulator, benchmark and baselines.",
    )
    parser.add_argument("--version", action="version", version=f"socialzoo {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="debug logging")
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    chosen = _chosen_command(argv) if argv is not None else None
    wanted = {module for module, _ in COMMANDS.values()} if argv is None else set()
    if chosen in COMMANDS:
        wanted.add(COMMANDS[chosen][0])
    for name, (module, help_line) in COMMANDS.items():
        if name in subparsers.choices:
            continue
        if module in wanted:
            importlib.import_module(module).register(subparsers)
        else:
            # Listed only: its options are registered when it is the command asked for.
            subparsers.add_parser(name, help=help_line, add_help=False)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status (2 for a usage or input error or a missing file,
    130 when interrupted by Ctrl-C and 143 by SIGTERM, 1 when a worker process was killed: a line on
    stderr instead of a traceback, which --verbose keeps)."""
    words = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser(words)
    _refuse_moved(parser, words)
    args = parser.parse_args(words)
    logging.basicConfig(
        level=logging.DEBUG if args.verbose else logging.INFO, format="%(levelname)s %(name)s: %(message)s"
    )
    try:
        with _terminate_as_interrupt():
            return int(args.func(args))
    except ModuleNotFoundError as err:
        extra = EXTRA_MODULES.get((err.name or "").partition(".")[0])
        if extra is None:
            raise
        return fail(
            args.command, f"this needs {err.name}, of the {extra} extra: pip install 'socialzoo[{extra}]'"
        )
    except FileNotFoundError as err:
        # A file the command needs and does not find wherever it is looked for (a recorded scene not
        # fetched yet, read when a task is built): the message names it and says what to do.
        if args.verbose:
            raise
        return fail(args.command, err)
    except BrokenPipeError:
        # The reader of stdout left (`socialzoo data list | head -1`): not an error of the command.
        # Nothing more can go there, and Python's flush at exit would raise again.
        try:
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        except (OSError, ValueError, AttributeError):  # stdout is no file descriptor (captured)
            pass
        return BROKEN_PIPE
    except (KeyboardInterrupt, BrokenProcessPool) as err:
        if args.verbose:
            raise
        # A run stopped from outside, by Ctrl-C or by a worker process killed (a kill -9, the
        # out-of-memory killer), is not a bug: a line saying so and, for a command that stores as it
        # goes, how to continue, not the traceback of wherever the run happened to be.
        hint = getattr(args, "resume_hint", None)
        interrupted = isinstance(err, KeyboardInterrupt)
        what = (
            "interrupted" if interrupted else "error: a worker process was killed (the out-of-memory killer?)"
        )
        print(f"socialzoo {args.command}: {what}" + (f"; {hint}" if hint else ""), file=sys.stderr)
        if isinstance(err, Terminated):
            return 128 + err.signum  # as a shell reports a command ended by that signal
        return INTERRUPTED if interrupted else 1


class Terminated(KeyboardInterrupt):
    """SIGTERM (a `kill`, a job scheduler's stop) raised where the command was, so that the run ends
    as Ctrl-C ends it: its worker processes stopped, what it stored kept, a line saying how to go on."""

    def __init__(self, signum: int) -> None:
        super().__init__(f"signal {signum}")
        self.signum = signum


def _raise_terminated(signum: int, frame: object) -> None:
    raise Terminated(signum)


@contextlib.contextmanager
def _terminate_as_interrupt() -> Iterator[None]:
    """SIGTERM ends the command as Ctrl-C does (Terminated) while it runs; the handler before is put
    back after (a caller of main(), such as a test, keeps its own). Only the main thread can set it."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    before = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, before)


# The exit status of a command stopped by Ctrl-C (SIGINT), as a shell reports it: 128 + 2.
INTERRUPTED = 130
# The exit status of a command whose output's reader left, as a shell reports SIGPIPE: 128 + 13.
BROKEN_PIPE = 141
