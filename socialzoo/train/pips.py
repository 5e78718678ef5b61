"""PIPS: synthesise a readable action-selection program from demonstrations (SPEC section 10)."""

from __future__ import annotations

import itertools
import logging
import math
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from socialzoo.agents.demonstrations import DemonstrationError, load_demonstrations
from socialzoo.agents.pips import Program, Transition, predicate_atoms, predicate_eval, predicate_str
from socialzoo.agents.pips_features import PaperParts, atom_values, paper_parts
from socialzoo.data.fetch import sha256
from socialzoo.nav.subpolicies import ACTION_NAMES, GO_ALONE, NUM_ACTIONS
from socialzoo.train.checks import check_choice, check_int, check_number, check_seed
from socialzoo.train.demo_data import check_steps
from socialzoo.train.pips_search import SearchOptions, SearchSettings, search_guard
from socialzoo.train.run_dir import read_record
from socialzoo.train.skeleton import Trainer, TrainingRun, run_training

logger = logging.getLogger(__name__)

SIDECAR_SUFFIX = ".train.json"


@dataclass(frozen=True, kw_only=True)
class PipsArgs(SearchOptions):
    """Synthesise a PIPS program (a readable action-selection program) from Ref demonstrations.

    The defaults are the paper's set-up: the first 3,500 demonstration steps of Ref, windowed around
    changes of action. The search options (max_depth ... z3_timeout_s) are
    socialzoo.train.pips_search.SearchOptions.

    Attributes:
        demos: demonstration file (.npz, `socialzoo demos --out FILE`), recorded on training scenarios.
        out: where the program JSON goes; the run record is written beside it (NAME.train.json).
        steps: demonstration steps used (see `sampling`), in the file's episode order.
        window: examples are the steps at most this many steps before or after a change of
            action (in the same episode); 0 uses every step (no windowing).
        sampling: "prefix": the examples are the windowed steps among the first `steps` steps
            of the file; "windows": they are the first `steps` windowed steps of the file.
        min_positives: a transition is learned only if the examples show it at least this often.
        seed: the demonstration sample, as a seed is for BC and GAIL what their data is drawn in:
            seed 0 reads the file's episodes in their order (the paper's set-up: the first `steps`
            steps), seed k > 0 in the order of a permutation of the episodes drawn from k
            (`episode_order`), so that k seeds are k samples of `steps` steps; also z3's random
            seed (the search itself is deterministic).
        time_budget_s: no deeper expressions are started after this much synthesis time, s.
        heldout_steps: demonstration steps after the used ones on which the agreement with the
            demonstrator is measured (0: none).
    """

    demos: str
    out: str = "pips.json"
    steps: int = 3500
    window: int = 20
    sampling: Literal["prefix", "windows"] = "prefix"
    min_positives: int = 1
    seed: int = 0
    time_budget_s: float = 540.0
    heldout_steps: int = 20_000

    def __post_init__(self) -> None:
        if not isinstance(self.demos, str) or not self.demos:
            raise ValueError(f"PipsArgs.demos must be a file path, got {self.demos!r}")
        if not isinstance(self.out, str) or not self.out.endswith(".json"):
            raise ValueError(f"PipsArgs.out must be a .json path, got {self.out!r}")
        check_int(self, "steps", "max_pred_size", "beam", "pool", "partners", "min_positives", low=1)
        check_int(self, "z3_candidates", low=1)
        if self.max_pred_size > 3:
            raise ValueError(f"PipsArgs.max_pred_size must be at most 3, got {self.max_pred_size!r}")
        check_int(self, "window", "max_depth", "heldout_steps", low=0)
        check_seed(self)
        check_number(self, "complexity_cost", low=0)
        check_number(self, "z3_timeout_s", "time_budget_s", low=0, low_open=True)
        check_choice(self, "sampling", ("prefix", "windows"))
        check_choice(self, "solver", ("z3", "exact"))


@dataclass(frozen=True)
class ProgramTrainer(Trainer):
    """PIPS writes a program file (args.out) and its run record beside it (NAME.train.json)."""

    def folder(self, args: Any) -> Path:
        """The program's folder."""
        return Path(args.out).parent

    def record_name(self, args: Any) -> str:
        """NAME.train.json for program NAME.json."""
        return sidecar_path(args.out).name

    def policy_path(self, args: Any) -> Path:
        """The program file."""
        return Path(args.out)


# The run's identity is every argument but the program's file name (its record is named after it).
TRAINER = ProgramTrainer(
    "pips", policy_file="pips.json", uses_torch=False, volatile=("out",), inputs=("demos",)
)


def window_mask(action: np.ndarray, prev: np.ndarray, episode: np.ndarray, window: int) -> np.ndarray:
    """Steps within `window` steps of a change of action in the same episode ((N,) bool); a
    change is a step whose action differs from its previous action. window 0: every step."""
    n = len(action)
    if window == 0:
        return np.ones(n, dtype=bool)
    changes = np.flatnonzero(action != prev)
    mask = np.zeros(n, dtype=bool)
    if len(changes) == 0:
        return mask
    offsets = np.arange(-window, window + 1)
    idx = changes[:, None] + offsets[None, :]
    ok = (idx >= 0) & (idx < n)
    idx_c = np.clip(idx, 0, n - 1)
    ok &= episode[idx_c] == episode[changes][:, None]
    mask[idx_c[ok]] = True
    return mask


def episode_order(episode: np.ndarray, seed: int) -> np.ndarray:
    """The demonstration steps in the order the seed reads them ((N,) indices): seed 0 the file's
    order; seed k > 0 whole episodes in the order of a permutation drawn from k (each episode's
    steps stay in order, so windows and previous actions keep their meaning)."""
    if seed == 0:
        return np.arange(len(episode))
    ids, first, inverse = np.unique(episode, return_index=True, return_inverse=True)
    # The file's episodes (indices into the sorted ids, in file order), permuted by the seed.
    shuffled = np.argsort(first)[np.random.default_rng(seed).permutation(len(ids))]
    rank = np.empty(len(ids), dtype=np.int64)
    rank[shuffled] = np.arange(len(ids))
    return np.argsort(rank[inverse], kind="stable")


def select_examples(
    action: np.ndarray, prev: np.ndarray, episode: np.ndarray, steps: int, window: int, sampling: str
) -> tuple[int, np.ndarray]:
    """Which demonstration steps become examples.

    "prefix": the first `steps` steps, windowed (`window_mask`). "windows": windows around
    changes of action from the start of the file, in order, until they hold `steps` steps (the
    examples are `steps` demonstration steps, chosen from a longer stretch). With window 0 both
    are the first `steps` steps.

    Returns:
        (span, mask): the examples lie among the first `span` steps, at mask (span,) == True.
    """
    n = len(action)
    if sampling == "prefix" or window == 0:
        span = min(steps, n)
        return span, window_mask(action[:span], prev[:span], episode[:span], window)
    chosen = np.flatnonzero(window_mask(action, prev, episode, window))[:steps]
    span = int(chosen[-1]) + 1 if len(chosen) else 0
    mask = np.zeros(span, dtype=bool)
    mask[chosen] = True
    return span, mask


@dataclass(frozen=True)
class GuardReport:
    """How one learned guard fits its examples."""

    state: int
    target: int
    examples: int
    positives: int
    correct: float
    solver: str

    def to_json(self) -> dict[str, Any]:
        """The transition as plain JSON, action names spelled out, then the fit's fields."""
        fit = {k: v for k, v in asdict(self).items() if k not in ("state", "target")}
        return {"from": ACTION_NAMES[self.state], "to": ACTION_NAMES[self.target], **fit}


def _decision_list(
    parts: PaperParts, action: np.ndarray, state: int, order: tuple[int, ...], settings: SearchSettings
) -> tuple[list[Transition], list[GuardReport], float]:
    """Guards out of `state` for targets in `order`, each learned on the examples the earlier
    ones leave; returns them, their reports and their merit on all the examples (decisions
    right, less the price of their complexity)."""
    rows = np.arange(len(action))
    learned: list[Transition] = []
    reports: list[GuardReport] = []
    complexity = 0
    for b in order:
        label = action[rows] == b
        if not label.any():
            continue
        sub = PaperParts(*(p[rows] for p in parts))
        found = search_guard(sub, label, np.ones(len(rows)), settings)
        if found is None:
            continue
        learned.append(Transition(b, found.predicate))
        reports.append(GuardReport(state, b, len(rows), int(label.sum()), found.score, found.solver))
        complexity += 1 + found.complexity
        rows = rows[~predicate_eval(found.predicate, atom_values(sub, predicate_atoms(found.predicate)))]
        if len(rows) == 0:
            break
    decided = Program({state: tuple(learned)}).decide_parts(parts) if learned else np.full(len(action), state)
    merit = float((decided == action).sum()) - settings.complexity_cost * complexity
    return learned, reports, merit


def without_dead_ends(transitions: dict[int, tuple[Transition, ...]]) -> dict[int, tuple[Transition, ...]]:
    """The transitions less those into a state the program could never leave.

    Only GoAlone, the state that drives to the goal, may have no way out: a program that enters
    Halt or Follow with no guard out of it (too few examples of leaving it paid for one) halts
    or follows until the time limit. Removing the way in can leave another state without a way
    out, so this repeats until nothing changes.
    """
    kept = {s: tuple(ts) for s, ts in transitions.items()}
    while True:
        dead = {s for s in range(NUM_ACTIONS) if s != GO_ALONE and not kept.get(s)}
        pruned = {s: tuple(t for t in ts if t.target not in dead) for s, ts in kept.items()}
        pruned = {s: ts for s, ts in pruned.items() if ts}
        if pruned == kept:
            return kept
        kept = pruned


def oscillations(program: Program, parts: PaperParts) -> list[tuple[int, int]]:
    """(observation row, state) for every state of a flip: observations on which the program
    would go from a to b and from b back to a (a robot halting and going on alternate steps),
    each with both a and b. A demonstrator that decides from what it sees never does this."""
    n = len(parts.prev_action)
    decided = [program.decide_parts(parts._replace(prev_action=np.full(n, s))) for s in range(NUM_ACTIONS)]
    found: list[tuple[int, int]] = []
    for a, b in itertools.combinations(range(NUM_ACTIONS), 2):
        for row in np.flatnonzero((decided[a] == b) & (decided[b] == a)).tolist():
            found += [(row, a), (row, b)]
    return found


def _learn_states(
    parts: PaperParts, action: np.ndarray, settings: SearchSettings, min_positives: int
) -> tuple[dict[int, tuple[Transition, ...]], list[GuardReport]]:
    """Each state's decision list, learned on the examples in that state (see `synthesize`)."""
    state = parts.prev_action
    transitions: dict[int, tuple[Transition, ...]] = {}
    reports: list[GuardReport] = []
    for s in range(NUM_ACTIONS):
        rows = np.flatnonzero(state == s)
        if len(rows) == 0:
            continue
        counts = np.bincount(action[rows], minlength=NUM_ACTIONS)
        targets = [b for b in range(NUM_ACTIONS) if b != s and counts[b] >= min_positives]
        sub = PaperParts(*(p[rows] for p in parts))
        best: tuple[list[Transition], list[GuardReport], float] | None = None
        for order in itertools.permutations(targets):
            found = _decision_list(sub, action[rows], s, order, settings)
            logger.debug(
                "%s: order %s, merit %.1f", ACTION_NAMES[s], [ACTION_NAMES[b] for b in order], found[2]
            )
            if best is None or found[2] > best[2]:
                best = found
        if best is None or not best[0]:
            continue
        transitions[s] = tuple(best[0])
        reports += best[1]
    return transitions, reports


def synthesize(
    obs: np.ndarray,
    action: np.ndarray,
    settings: SearchSettings,
    *,
    min_positives: int = 1,
    sample: tuple[np.ndarray, np.ndarray] | None = None,
    repairs: int = 3,
) -> tuple[Program, list[GuardReport]]:
    """A program from examples: for each current action (the observations' previous action), an
    ordered list of guarded transitions. Each order of the targets is tried (sequential covering:
    a guard is learned on the examples the earlier guards leave, as first-guard-fires reads
    them), and the order whose list decides the most examples right, less the price of its
    complexity, is kept. Transitions into a state with no way out are dropped
    (`without_dead_ends`).

    With `sample` (every demonstration step the examples come from, windowed or not), the program
    is checked for `oscillations` on those steps; where it would flip between two states, the
    demonstrator's own action there becomes an example from each state of the flip (the action to
    settle on, whichever state the program is in), and the guards are learned again, at most
    `repairs` times.

    Args:
        obs: (N, D) paper-layout observations.
        action: (N,) the demonstrator's actions.
        settings: the guard search's settings.
        min_positives: fewest examples of a transition for it to be learned.
        sample: (observations, actions) of the demonstration steps the examples come from.
        repairs: most rounds of learning again where the program oscillates.
    """
    parts, labels = paper_parts(obs), action
    sample_parts = paper_parts(sample[0]) if sample is not None else None
    added: set[tuple[int, int]] = set()
    for round_ in range(repairs + 1):
        transitions, reports = _learn_states(parts, labels, settings, min_positives)
        live = without_dead_ends(transitions)
        program = Program(live)
        if sample is None or sample_parts is None or round_ == repairs:
            break
        flips = oscillations(program, sample_parts)
        new = [f for f in flips if f not in added]
        if not new:
            break
        logger.info(
            "PIPS: the program flips between two states on %d of %d sample steps; learning again with "
            "the demonstrator's action there as an example from each state of the flip",
            len({row for row, _ in flips}),
            len(sample_parts.prev_action),
        )
        added.update(new)
        rows = np.array([row for row, _ in new])
        extra = PaperParts(*(p[rows] for p in sample_parts))._replace(
            prev_action=np.array([state for _, state in new], dtype=np.int64)
        )
        parts = PaperParts(*(np.concatenate([a, b]) for a, b in zip(parts, extra, strict=True)))
        labels = np.concatenate([labels, sample[1][rows]])
    for s, ts in transitions.items():
        for t in ts:
            to = ACTION_NAMES[t.target]
            if t not in live.get(s, ()):
                logger.info("%s -> %s dropped: %s has no way out", ACTION_NAMES[s], to, to)
    for r, (s, t) in zip(reports, [(s, t) for s, ts in transitions.items() for t in ts], strict=True):
        logger.info(
            "%s -> %s if %s  (%d/%d examples right, %d positive)",
            ACTION_NAMES[s],
            ACTION_NAMES[t.target],
            predicate_str(t.guard),
            r.correct,
            r.examples,
            r.positives,
        )
    kept = {(s, t.target) for s, ts in live.items() for t in ts}
    return program, [r for r in reports if (r.state, r.target) in kept]


def agreement(program: Program, obs: np.ndarray, action: np.ndarray) -> dict[str, Any]:
    """How often the program picks the demonstrator's action, given the same previous action.

    Returns:
        {"steps", "agreement" (fraction), "majority" (fraction of the most common action, the
        agreement of always answering it), "confusion" (demonstrator action -> program action
        -> count)}.
    """
    chosen = program.decide(obs)
    confusion = {
        ACTION_NAMES[a]: {
            ACTION_NAMES[b]: int(((action == a) & (chosen == b)).sum())
            for b in range(NUM_ACTIONS)
            if ((action == a) & (chosen == b)).any()
        }
        for a in range(NUM_ACTIONS)
        if (action == a).any()
    }
    n = len(action)
    return {
        "steps": n,
        "agreement": float((chosen == action).mean()) if n else math.nan,
        "majority": float(np.bincount(action, minlength=NUM_ACTIONS).max() / n) if n else math.nan,
        "confusion": confusion,
    }


def sidecar_path(program_path: str | Path) -> Path:
    """The sidecar of a program file: NAME.json -> NAME.train.json."""
    path = Path(program_path)
    return path.with_name(path.stem + SIDECAR_SUFFIX)


def train(args: PipsArgs) -> Path:
    """Synthesise a program from demonstrations on the trainer skeleton.

    Writes args.out (the program, socialzoo.agents.pips JSON) and its run record NAME.train.json
    beside it: the resolved arguments, the seed, the command line, and in its results the
    synthesis time, the demonstrations used (file digest, steps, episodes, examples), each guard's
    fit, the readable rules, and the agreement with the demonstrator on the examples, on the steps
    used and on held-out steps (`read_program_record` reads it). A finished run of the same
    arguments is not repeated.

    The demonstrations' first `steps` steps (in the file's episode order for seed 0, in a seeded order of
    whole episodes for other seeds: a seed is a demonstration sample) are cut into examples (observation,
    previous action, action), windowed around the changes of action; for each current action the synthesiser
    learns the guards of its transitions one target at a time (each on the examples the earlier guards leave),
    with the layered search of socialzoo.train.pips_search, and drops the transitions into a state the program
    could never leave.

    Returns:
        The program's path.

    Raises:
        socialzoo.agents.demonstrations.DemonstrationError: an unreadable demonstration file, one
            that is not in the paper observation layout, or one with fewer steps than args.steps
            (with sampling "windows", fewer windowed steps).
    """
    return run_training(TRAINER, args, lambda run: _synthesize_run(run, args))


def _synthesize_run(run: TrainingRun, args: PipsArgs) -> dict[str, Any]:
    demos = Path(args.demos)
    arrays, meta = load_demonstrations(demos)
    layout = meta.get("env_config", {}).get("observation", {}).get("layout", "paper")
    if layout != "paper":
        raise DemonstrationError(f"{demos}: PIPS reads the paper observation layout, the file has {layout!r}")
    order = episode_order(arrays["episode"], args.seed)
    obs_all, act_all, ep_all = (
        arrays["obs"][order],
        arrays["action"].astype(np.int64)[order],
        arrays["episode"][order],
    )
    prev_all = paper_parts(obs_all).prev_action
    used, mask = select_examples(act_all, prev_all, ep_all, args.steps, args.window, args.sampling)
    # Fewer steps than asked are refused, as the other imitation trainers refuse them: a run
    # recorded as N steps learned from N.
    windowed = args.sampling == "windows" and args.window > 0
    what = f"steps within {args.window} steps of a change of action" if windowed else "demonstration steps"
    check_steps(demos, int(mask.sum()) if windowed else len(act_all), args.steps, what)
    obs, action, episode, prev = obs_all[:used], act_all[:used], ep_all[:used], prev_all[:used]
    logger.info(
        "PIPS: %d examples (window %d, %s) from the first %d demonstration steps in seed %d's episode order "
        "(%d episodes, %d changes of action)",
        int(mask.sum()),
        args.window,
        args.sampling,
        used,
        args.seed,
        len(np.unique(episode)),
        int((action != prev).sum()),
    )
    settings = SearchSettings.of(args, seed=args.seed, deadline=time.monotonic() + args.time_budget_s)
    search_started = time.perf_counter()
    program, reports = synthesize(
        obs[mask], action[mask], settings, min_positives=args.min_positives, sample=(obs, action)
    )
    synthesis_s = time.perf_counter() - search_started
    program.save(run.policy)
    rules = program.rules()
    for line in rules:
        logger.info("PIPS rule: %s", line)
    held = slice(used, min(used + args.heldout_steps, len(act_all)))
    fit = {
        "examples": agreement(program, obs[mask], action[mask]),
        "steps_spanned": agreement(program, obs, action),
        "held_out": agreement(program, obs_all[held], act_all[held]) if held.stop > held.start else None,
    }
    if fit["held_out"] is not None:
        logger.info(
            "PIPS: agreement with the demonstrator on %d held-out steps: %.1f%% (always %s: %.1f%%)",
            fit["held_out"]["steps"],
            100 * fit["held_out"]["agreement"],
            ACTION_NAMES[int(np.bincount(act_all[held]).argmax())],
            100 * fit["held_out"]["majority"],
        )
    import z3

    logger.info("PIPS: program in %s (synthesis %.1f s)", run.policy, synthesis_s)
    return {
        "synthesis_seconds": synthesis_s,
        "z3_version": z3.get_version_string(),
        "demonstrations": {
            "path": str(demos),
            "sha256": sha256(demos) if demos.exists() else None,
            "config_hash": meta.get("config_hash"),
            "test_set": meta.get("test_set"),
            "steps_in_file": len(act_all),
            "steps_spanned": used,
            "episodes_used": len(np.unique(episode)),
            "episode_ids": [int(e) for e in dict.fromkeys(episode.tolist())],
            "changes_of_action": int((action != prev).sum()),
            "examples": int(mask.sum()),
        },
        "guards": [r.to_json() for r in reports],
        "rules": rules,
        "agreement": fit,
    }


def read_program_record(program: str | Path) -> dict[str, Any]:
    """The run record beside a program file (NAME.train.json) as one flat dict: the record's
    fields with its results beside them (synthesis_seconds, agreement, demonstrations, rules,
    wall_seconds, ...); records written before the trainer skeleton are flat already. {} when
    there is none.

    Raises:
        socialzoo.train.run_dir.RunDirError: a record that is not a JSON object (naming it).
    """
    record = read_record(sidecar_path(program))
    if record is None:
        return {}
    return {**record, **(record.get("results") or {})}
