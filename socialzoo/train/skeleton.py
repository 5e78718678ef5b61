"""The skeleton every trainer runs on: run folder, seed, run record, checkpoints, resume,
evaluation callback, TensorBoard and progress; a trainer file holds only its algorithm."""

from __future__ import annotations

import contextlib
import logging
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from socialzoo.bench.progress import progress_bar
from socialzoo.bench.tables import write_csv
from socialzoo.train.machine import machine_facts
from socialzoo.train.run_dir import (
    RUN_FILE,
    RunDir,
    checkpoint_steps,
    differing_args,
    read_record,
)

logger = logging.getLogger(__name__)

EVALUATIONS_FILE = "evaluations.csv"
# Arguments of every trainer that never change what is trained: a progress display and the run folder
# itself (it may move). Not the number of CPU threads: two threads take another kernel path and train
# other weights (REPRODUCTION.md, "Where the runs part"), so a run of another --threads is another run.
VOLATILE: tuple[str, ...] = ("progress", "out")

# A checkpoint's evaluation: policy file -> metrics (success first; plain floats).
Evaluator = Callable[[Path], Mapping[str, float]]


@dataclass(frozen=True)
class Trainer:
    """What a trainer is, for the skeleton. A trainer whose files lie elsewhere than
    args.out/<policy_file> with args.out/run.json (PIPS: a program file and its sidecar record)
    overrides `folder`, `record_name` and `policy_path`.

    Attributes:
        name: the registry name (`socialzoo train <name>`), recorded as run.json's "algo".
        policy_file: the final policy's file name in the run folder.
        uses_torch: seed torch and set its threads around the run (False: a trainer without torch).
        volatile: argument names that do not change the result (not part of the run's identity).
        inputs: argument names that name input files (socialzoo.train.run_dir.RunDir: the same
            input when the run folder moved with it).
    """

    name: str
    policy_file: str
    uses_torch: bool = True
    volatile: tuple[str, ...] = VOLATILE
    inputs: tuple[str, ...] = ()

    def folder(self, args: Any) -> Path:
        """The run folder of `args`: args.out."""
        return Path(args.out)

    def record_name(self, args: Any) -> str:
        """The run record's file name in the folder: run.json."""
        return RUN_FILE

    def policy_path(self, args: Any) -> Path:
        """The final policy file of `args`: <folder>/<policy_file>."""
        return self.folder(args) / self.policy_file


def finished_run(trainer: Trainer, args: Any) -> bool:
    """True when the trainer's folder holds a finished run of these arguments and its policy file
    (what `run_training` would return at once); creates nothing.

    Raises:
        socialzoo.train.run_dir.RunDirError: an unreadable record.
    """
    record = read_record(trainer.folder(args) / trainer.record_name(args))
    return (
        record is not None
        and bool(record.get("finished"))
        and differing_args(record, trainer.name, args, trainer.volatile, trainer.inputs, trainer.folder(args))
        is None
        and trainer.policy_path(args).is_file()
    )


class CheckpointSchedule:
    """The steps at which a run saves its policy: every `every` steps up to `total`, and `total`
    (the run's length in the trainer's own unit: env steps, updates or frames)."""

    def __init__(self, total: int, every: int) -> None:
        self.steps = checkpoint_steps(total, every)
        self._pending = list(self.steps)

    def due(self, done: int) -> list[int]:
        """The checkpoint steps reached once `done` steps are done, each returned once."""
        reached = [s for s in self._pending if s <= done]
        self._pending = self._pending[len(reached) :]
        return reached


class TrainingRun:
    """One run of a trainer: its folder and record, checkpoints, evaluations, logs and progress.

    Built by `run_training`; a trainer's `fit` uses it. `args` is the trainer's argument dataclass
    (fields `out` and `seed`; `progress` when it shows progress); `evaluator` evaluates each
    checkpoint (None: checkpoints are only saved).
    """

    def __init__(self, trainer: Trainer, args: Any, *, evaluator: Evaluator | None = None) -> None:
        self.trainer = trainer
        self.args = args
        self.dir = RunDir(
            trainer.folder(args),
            trainer.name,
            args,
            volatile=trainer.volatile,
            record_name=trainer.record_name(args),
            inputs=trainer.inputs,
        )
        self.policy = trainer.policy_path(args)
        self.evaluator = evaluator
        self.evaluations: list[dict[str, Any]] = []
        self.checkpoint_files: list[Path] = []
        self._last_step: int | None = None
        self._started = time.perf_counter()
        self._writer: Any = None
        self._closing = contextlib.ExitStack()

    @property
    def path(self) -> Path:
        """The run folder."""
        return self.dir.path

    @property
    def record(self) -> dict[str, Any]:
        """The run record (algo, args, command, seed, package_version, started, finished, results)."""
        return self.dir.record

    @property
    def finished(self) -> bool:
        """True when the folder holds a finished run of these arguments and its policy file."""
        return self.dir.finished and self.policy.is_file()

    @property
    def seconds(self) -> float:
        """Wall time since the run started, s."""
        return time.perf_counter() - self._started

    @property
    def writer(self) -> Any:
        """The run's TensorBoard SummaryWriter (tensorboard/), opened on first use."""
        if self._writer is None:
            self._writer = self._closing.enter_context(self.dir.tensorboard())
        return self._writer

    def recorded(self, value: Any) -> Any:
        """`value` with its absolute paths relative to the run folder, as run.json holds them (never
        the machine's absolute ones): a policy file's training record (RunDir.recorded)."""
        return self.dir.recorded(value)

    def progress(self, total: int, unit: str = "step", desc: str | None = None) -> Any:
        """A progress display of `total` units, closed when the run ends (args.progress=False: silent)."""
        bar = progress_bar(total, desc or self.trainer.name, getattr(self.args, "progress", True), unit)
        self._closing.callback(bar.close)
        return bar

    def schedule(self, total: int, every: int) -> CheckpointSchedule:
        """The run's checkpoint steps (CheckpointSchedule)."""
        self._last_step = total
        return CheckpointSchedule(total, every)

    def evaluation_due(self, step: int) -> bool:
        """True when the checkpoint at `step` is to be evaluated: the run has an evaluator, and
        args.eval_every is 0 (every checkpoint), divides `step`, or `step` is the last one."""
        if self.evaluator is None:
            return False
        every = int(getattr(self.args, "eval_every", 0) or 0)
        return every <= 0 or step % every == 0 or step == self._last_step

    def checkpoint_path(self, step: int, suffix: str = ".safetensors") -> Path:
        """checkpoints/step_<step><suffix> (folder created)."""
        return self.dir.checkpoint_path(step, suffix)

    def checkpoint(self, step: int, save: Callable[[Path], Any], suffix: str = ".safetensors") -> Path:
        """Save the policy at `step` with save(path) into checkpoints/, then evaluate it when the run
        has an evaluator; returns the checkpoint's path."""
        path = self.checkpoint_path(step, suffix)
        save(path)
        self.checkpoint_files.append(path)
        if self.evaluation_due(step):
            self._evaluate(step, path)
        return path

    def _evaluate(self, step: int, path: Path) -> None:
        metrics = {k: float(v) for k, v in self.evaluator(path).items()} if self.evaluator else {}
        row = {"step": step, "file": str(path.relative_to(self.path)), **metrics}
        self.evaluations.append(row)
        for key, value in metrics.items():
            self.writer.add_scalar(f"eval/{key}", value, step)
        write_csv(self.evaluations, self.path / EVALUATIONS_FILE, blank_nan=False)
        logger.info("%s: checkpoint %d evaluated: %s", self.trainer.name, step, metrics)

    def best_evaluation(self, key: str = "success") -> dict[str, Any] | None:
        """The evaluated checkpoint with the highest `key` (the earliest among equals), or None."""
        rows = [r for r in self.evaluations if key in r]
        return max(rows, key=lambda r: (r[key], -r["step"])) if rows else None

    def close(self) -> None:
        """Close the progress displays and the TensorBoard writer."""
        self._closing.close()

    def finish(self, results: Mapping[str, Any]) -> None:
        """Record the run as finished with `results`, wall time, policy and checkpoints."""
        summary: dict[str, Any] = {"policy": self.policy.name, "wall_seconds": round(self.seconds, 1)}
        summary["checkpoints"] = [str(p.relative_to(self.path)) for p in self.checkpoint_files]
        best = self.best_evaluation()
        if best is not None:
            summary["best_checkpoint"] = best
        self.dir.finish(**{**summary, **dict(results)})


@contextlib.contextmanager
def seeded_torch(seed: int, threads: int | None) -> Iterator[None]:
    """Seed torch's global generator with `seed`, use `threads` CPU threads and torch's
    deterministic algorithms (warn only, where an operation has none) inside the block; the
    caller's generator state, thread count and determinism setting are given back after it.

    The deterministic switch costs nothing measurable on the CPU trainers (a 2,000-update BC run:
    the same time within the machine's noise, docs/reproduce.md) and keeps any operation with a
    nondeterministic kernel from entering a trainer unnoticed."""
    import torch

    before = torch.get_num_threads()
    deterministic = torch.are_deterministic_algorithms_enabled()
    warn_only = torch.is_deterministic_algorithms_warn_only_enabled()
    if threads is not None:
        torch.set_num_threads(threads)
    torch.use_deterministic_algorithms(True, warn_only=True)
    try:
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(seed)
            yield
    finally:
        torch.set_num_threads(before)
        torch.use_deterministic_algorithms(deterministic, warn_only=warn_only)


def masked_interrupt(err: BaseException) -> KeyboardInterrupt | None:
    """The Ctrl-C (KeyboardInterrupt, or the command line's SIGTERM, a subclass) that `err` replaced:
    one that `err` was raised while handling, when `err` is no interrupt itself; else None.

    A library's cleanup can fail on the way out of an interrupted block: TorchRL's BCLoss runs its
    actor inside tensordict's `to_module()`, whose exit tests a TensorDict as a bool and raises
    RuntimeError, so Ctrl-C during a BC update ended `socialzoo train bc` in that traceback (exit
    status 1) instead of "interrupted" (130)."""
    seen: set[int] = set()
    cause: BaseException | None = err
    while cause is not None and id(cause) not in seen:
        if isinstance(cause, KeyboardInterrupt):
            return None if cause is err else cause
        seen.add(id(cause))
        cause = cause.__context__
    return None


def run_training(
    trainer: Trainer,
    args: Any,
    fit: Callable[[TrainingRun], Mapping[str, Any]],
    *,
    evaluator: Evaluator | None = None,
) -> Path:
    """Run `fit` on the skeleton; returns the policy file. `fit` trains,
    saves the final policy at run.policy and returns results for the run record; `evaluator`
    evaluates each checkpoint (socialzoo.train.validation.validation_evaluator).

    It does the rest, the same way for every trainer:

    - the run folder and its record (socialzoo.train.run_dir.RunDir: arguments, command, seed,
      package version, start and end, results), refusing a folder that holds another run; a run
      that stops before writing anything but its record (a missing input file) removes the record;
    - resume: a finished run of the same arguments is not repeated (its policy is returned), so a
      rerun of an interrupted protocol (`socialzoo reproduce`) trains only what is missing. An
      interrupted run starts again from step 0 in its folder: the checkpoints hold the policy, not
      the optimiser, replay buffer or env state, and a run continued from one would not equal an
      uninterrupted run of the same seed;
    - the seed: torch's global generator seeded from args.seed for the run only (the caller's state is
      given back), torch CPU threads from args.threads and torch's deterministic algorithms (both
      restored after);
    - the machine facts that decide torch-trained numbers (socialzoo.train.machine: CPU model and
      flags, torch and BLAS builds, thread counts, numpy, Python) in run.json's "machine";
    - checkpoints on a fixed schedule (`schedule`), each one evaluated by the run's evaluator when it
      has one (`evaluations.csv`, TensorBoard `eval/*`, the best one named in run.json); with
      args.eval_every > 0 only the checkpoints at multiples of it and the last one are evaluated;
    - TensorBoard (`tensorboard/`, opened on first use) and a progress display that suits a terminal
      or a log (socialzoo.bench.progress);
    - wall time, the checkpoint list and the policy file in run.json when the run finishes.

    Raises:
        socialzoo.train.run_dir.RunDirError: the folder holds a run of other arguments.
    """
    run = TrainingRun(trainer, args, evaluator=evaluator)
    if run.finished:
        logger.info("%s: %s holds a finished run of these arguments; nothing to do", trainer.name, run.path)
        return run.policy
    threads = getattr(args, "threads", None)
    context = seeded_torch(args.seed, threads) if trainer.uses_torch else contextlib.nullcontext()
    try:
        with context:
            # Inside the run's torch settings, so the threads recorded are the run's.
            run.record["machine"] = machine_facts()
            results = fit(run)
    except BaseException as err:
        run.close()
        run.dir.discard()
        interrupt = masked_interrupt(err)
        if interrupt is not None:
            raise interrupt from None
        raise
    finally:
        run.close()
    if not run.policy.is_file():
        raise RuntimeError(f"{trainer.name}: fit returned without writing {run.policy}")
    run.finish(results)
    logger.info("%s: %s in %.1f s", trainer.name, run.policy, run.seconds)
    return run.policy
