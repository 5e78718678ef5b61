"""Layered, dimension-informed search for one PIPS guard: unit-consistent feature expressions by depth, sketches of one
or two comparisons filled by exact threshold search, the best extended, the final thresholds solved with z3."""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from socialzoo.agents.pips import (
    Atom,
    Compare,
    Expr,
    Junction,
    Predicate,
    expr_atoms,
    expr_depth,
    expr_eval,
    predicate_eval,
)
from socialzoo.agents.pips_features import ATOMS, LANE_CM_RANGE, PaperParts, UnitError, human_present, lane_cm
from socialzoo.train.pips_enumerate import (
    AtomCache,
    FeatureBank,
    enumerate_depth,
    refine_lane_features,
    rename_lane,
)
from socialzoo.train.pips_thresholds import PairSearch, Sketch, fit_single, score_of, solve_z3

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class Candidate:
    """A filled guard and how well it classifies the examples.

    Attributes:
        predicate: the guard.
        score: weighted correctly classified examples.
        complexity: comparisons beyond the first plus the deepest expression's depth.
        gap: its smallest threshold margin (normalised; larger is safer), a tie-breaker.
        solver: "z3" when z3 solved or confirmed its thresholds, else "exact".
    """

    predicate: Predicate
    score: float
    complexity: int
    gap: float
    solver: str = "exact"


def _leaves(pred: Predicate) -> list[Compare]:
    if isinstance(pred, Compare):
        return [pred]
    return [leaf for a in pred.args for leaf in _leaves(a)]


def _complexity(pred: Predicate) -> int:
    leaves = _leaves(pred)
    return len(leaves) - 1 + max(expr_depth(leaf.expr) for leaf in leaves)


def _sketch(pred: Predicate, counter: list[int]) -> Sketch:
    if isinstance(pred, Compare):
        counter[0] += 1
        return ("leaf", counter[0] - 1, pred.cmp)
    return (pred.op, [_sketch(a, counter) for a in pred.args])


def _fill(pred: Predicate, thresholds: list[float], counter: list[int]) -> Predicate:
    if isinstance(pred, Compare):
        counter[0] += 1
        return Compare(pred.expr, pred.cmp, float(thresholds[counter[0] - 1]))
    return Junction(pred.op, tuple(_fill(a, thresholds, counter) for a in pred.args))


def _gap(pred: Predicate, atoms: Mapping[str, np.ndarray]) -> float:
    """Smallest normalised distance from a threshold to the nearest example value."""
    gaps = []
    for leaf in _leaves(pred):
        v = expr_eval(leaf.expr, atoms)
        spread = max(float(v.max() - v.min()), 1e-12)
        gaps.append(float(np.min(np.abs(v - leaf.threshold))) / spread)
    return min(gaps)


def physical_thresholds(pred: Predicate, atoms: Mapping[str, np.ndarray]) -> bool:
    """True when every comparison of an expression over people compares it with a value it takes
    where those people are there.

    An absent person reads as FAR (1000 m) away, which an atomic feature compares with sensibly
    ("lane62.dist >= 2.5 m" holds when the lane is empty) but arithmetic does not: in
    "ahead.absy - lane37.x <= -999.4 m" the stand-in turns "nobody in the lane" into a guard that
    fires on a person 0.6 m to the side at any distance. Such a threshold lies outside the
    expression's values on the examples where its people are present; the search drops it.
    """
    for leaf in _leaves(pred):
        if isinstance(leaf.expr, Atom):
            continue
        masks = [m for name in expr_atoms(leaf.expr) if (m := human_present(atoms, name)) is not None]
        if not masks:
            continue
        present = np.logical_and.reduce(masks)
        if not present.any():
            return False
        values = expr_eval(leaf.expr, atoms)[present]
        if not values.min() <= leaf.threshold <= values.max():
            return False
    return True


def _candidate(
    pred: Predicate, score: float, atoms: Mapping[str, np.ndarray], solver: str = "exact"
) -> Candidate:
    """A scored guard; one with a threshold only the absent-person stand-in reaches scores -inf
    (`physical_thresholds`)."""
    if not physical_thresholds(pred, atoms):
        score = -np.inf
    return Candidate(pred, float(score), _complexity(pred), _gap(pred, atoms), solver)


@dataclass(frozen=True, kw_only=True)
class SearchOptions:
    """How hard one guard is searched: the options `socialzoo train pips` passes on (PipsArgs
    inherits them).

    Attributes:
        max_depth: deepest feature expression (0: atomic features only).
        max_pred_size: most comparisons in one guard (1 to 3).
        beam: expressions of each depth combined into the next.
        pool: best-comparing features tried as the first of two comparisons.
        partners: best-comparing expressions tried as the second (besides every atomic feature).
        complexity_cost: the price of complexity, in examples: a guard must classify this many
            more examples right than never firing, and as many more again for each comparison
            beyond the first and each level of expression depth.
        solver: "z3" (the best candidates' thresholds by z3's MaxSMT optimiser) or "exact"
            (the exact threshold search alone).
        z3_candidates: candidates per guard whose thresholds z3 solves.
        z3_timeout_s: z3's time limit per candidate, s.
    """

    max_depth: int = 2
    max_pred_size: int = 2
    beam: int = 24
    pool: int = 24
    partners: int = 1000
    complexity_cost: float = 1.0
    solver: Literal["z3", "exact"] = "z3"
    z3_candidates: int = 3
    z3_timeout_s: float = 30.0


@dataclass(frozen=True, kw_only=True)
class SearchSettings(SearchOptions):
    """The search of one guard: its options and what the synthesiser sets for a run.

    Attributes:
        refine: lane-expression families (and best candidates) whose lane widths are refined
            to the centimetre.
        seed: z3's random seed.
        deadline: time.monotonic() after which no deeper level is started.
    """

    refine: int = 16
    seed: int = 0
    deadline: float = float("inf")

    @classmethod
    def of(cls, options: SearchOptions, **settings: Any) -> SearchSettings:
        """The settings with `options`' search options (from PipsArgs, say) and `settings`."""
        shared = {f.name: getattr(options, f.name) for f in dataclasses.fields(SearchOptions)}
        return cls(**shared, **settings)


class _Ranker:
    """Orders candidates: score less the price of complexity, then simpler, then wider margin."""

    def __init__(self, cost: float) -> None:
        self.cost = cost

    def merit(self, c: Candidate) -> float:
        return c.score - self.cost * c.complexity

    def key(self, c: Candidate) -> tuple[float, int, float]:
        return (-self.merit(c), c.complexity, -c.gap)


def _level_candidates(
    bank: FeatureBank, label: np.ndarray, weight: np.ndarray, settings: SearchSettings
) -> list[Candidate]:
    """One- and two-comparison guards over the bank (and three, extended from the best pairs)."""
    values = bank.values
    fit = fit_single(values, label, weight)
    cands = [
        _candidate(Compare(bank.exprs[f], str(fit.cmp[f]), float(fit.threshold[f])), fit.score[f], bank.atoms)
        for f in range(len(bank.exprs))
        if np.isfinite(fit.score[f])
    ]
    if settings.max_pred_size < 2 or not label.any():
        return cands
    # Partners: every atomic feature (the usual second comparison: a speed, an angle) and the
    # best-comparing deeper expressions.
    ranked = np.argsort(-fit.score, kind="stable")
    atomic = [f for f in range(len(bank.exprs)) if isinstance(bank.exprs[f], Atom)]
    partners = np.array(sorted(set(atomic) | set(ranked[: settings.partners].tolist())))
    search = PairSearch(values[partners], label, weight)
    pairs: list[Candidate] = []
    for a in ranked[: settings.pool].tolist():
        pf = search.fit(values[a])
        for k in np.argsort(-pf.score, kind="stable")[:4].tolist():
            b = int(partners[k])
            if b == a or not np.isfinite(pf.score[k]):
                continue
            cmp_a, t_a, cmp_b, t_b = search.thresholds(values[a], pf, k)
            pred = Junction(
                str(pf.junction[k]), (Compare(bank.exprs[a], cmp_a, t_a), Compare(bank.exprs[b], cmp_b, t_b))
            )
            pairs.append(_candidate(pred, pf.score[k], bank.atoms))
    pairs.sort(key=lambda c: -c.score)
    cands += pairs
    if settings.max_pred_size >= 3:
        for c in pairs[:4]:
            ext = _extend(c, bank, values, label, weight)
            if ext is not None:
                cands.append(ext)
    return cands


def _extend(
    cand: Candidate, bank: FeatureBank, values: np.ndarray, label: np.ndarray, weight: np.ndarray
) -> Candidate | None:
    """The best third comparison joined to a two-comparison guard by its own junction, fitted
    exactly on the examples it can change (the other thresholds fixed)."""
    pred = cand.predicate
    assert isinstance(pred, Junction)
    holds = predicate_eval(pred, bank.atoms)
    # "and" can only turn true examples false; "or" only false ones true.
    region = holds if pred.op == "and" else ~holds
    if region.sum() < 2:
        return None
    fit = fit_single(values[:, region], label[region], weight[region])
    f = int(np.argmax(fit.score))
    if not np.isfinite(fit.score[f]):
        return None
    outside = float(weight[~region][(holds == label)[~region]].sum())
    new = Junction(pred.op, (*pred.args, Compare(bank.exprs[f], str(fit.cmp[f]), float(fit.threshold[f]))))
    return _candidate(new, outside + float(fit.score[f]), bank.atoms)


def _refit(
    pred: Predicate, atoms: Mapping[str, np.ndarray], label: np.ndarray, weight: np.ndarray
) -> Candidate:
    """The same expressions with the best exact thresholds (directions and junction refitted too)."""
    leaves = _leaves(pred)
    cols = [expr_eval(leaf.expr, atoms) for leaf in leaves]
    if len(leaves) == 1:
        fit = fit_single(cols[0][None, :], label, weight)
        if not np.isfinite(fit.score[0]):
            return _candidate(pred, -np.inf, atoms)
        new: Predicate = Compare(leaves[0].expr, str(fit.cmp[0]), float(fit.threshold[0]))
        return _candidate(new, fit.score[0], atoms)
    if len(leaves) == 2:
        search = PairSearch(cols[1][None, :], label, weight)
        pf = search.fit(cols[0])
        cmp_a, t_a, cmp_b, t_b = search.thresholds(cols[0], pf, 0)
        new = Junction(
            str(pf.junction[0]), (Compare(leaves[0].expr, cmp_a, t_a), Compare(leaves[1].expr, cmp_b, t_b))
        )
        return _candidate(new, pf.score[0], atoms)
    score = float(weight[predicate_eval(pred, atoms) == label].sum())
    return _candidate(pred, score, atoms)


def _rename_lane(pred: Predicate, cm: int, new_cm: int) -> Predicate:
    if isinstance(pred, Junction):
        return Junction(pred.op, tuple(_rename_lane(a, cm, new_cm) for a in pred.args))
    return Compare(rename_lane(pred.expr, cm, new_cm), pred.cmp, pred.threshold)


def _refine_lanes(
    cand: Candidate, atoms: Mapping[str, np.ndarray], label: np.ndarray, weight: np.ndarray
) -> Candidate:
    """The candidate with each lane half-width moved to the best whole centimetre within 5 cm
    (thresholds refitted exactly for each); among equally good widths, the middle one."""
    if len(_leaves(cand.predicate)) > 2:
        return cand
    best = cand
    widths = sorted(
        {cm for leaf in _leaves(cand.predicate) for n in expr_atoms(leaf.expr) if (cm := lane_cm(n))}
    )
    for cm in widths:
        trials = []
        for new_cm in range(max(cm - 5, LANE_CM_RANGE[0]), min(cm + 5, LANE_CM_RANGE[1]) + 1):
            pred = best.predicate if new_cm == cm else _rename_lane(best.predicate, cm, new_cm)
            trials.append((new_cm, _refit(pred, atoms, label, weight)))
        top = max(c.score for _, c in trials)
        tied = [c for _, c in trials if c.score == top]
        best = tied[len(tied) // 2]
    return best


def _solve_with_z3(
    cand: Candidate, atoms: Mapping[str, np.ndarray], label, weight, settings: SearchSettings
) -> Candidate:
    """The candidate's thresholds solved jointly by z3 (MaxSMT).

    z3 proves what the best score of the sketch is. When it finds more than the exact search
    (three comparisons, where the exact search extended a fixed pair), its thresholds are used;
    when it confirms the exact search's score, of the two equally good assignments the one with
    the wider margin is kept; when it gives up, the exact one stays (solver "exact")."""
    pred = cand.predicate
    leaves = _leaves(pred)
    columns = [expr_eval(leaf.expr, atoms) for leaf in leaves]
    sketch = _sketch(pred, [0])
    solved = solve_z3(sketch, columns, label, weight, timeout_s=settings.z3_timeout_s, seed=settings.seed)
    if solved is None:
        return cand
    score, thresholds = solved
    exact = score_of(sketch, columns, [leaf.threshold for leaf in leaves], label, weight)
    if score < exact:
        logger.warning(
            "z3 found %.0f correct where the exact search found %.0f; keeping the exact one", score, exact
        )
        return cand
    found = _candidate(_fill(pred, thresholds, [0]), score, atoms, "z3")
    if not np.isfinite(found.score):  # z3's thresholds lean on the absent-person stand-in
        return cand
    if score > exact:
        logger.info("z3 improved a guard from %.0f to %.0f correct", exact, score)
        return found
    return found if found.gap > cand.gap else dataclasses.replace(cand, solver="z3")


def search_guard(
    parts: PaperParts, label: np.ndarray, weight: np.ndarray, settings: SearchSettings
) -> Candidate | None:
    """The best guard for examples labelled where it should hold.

    Depth by depth: enumerate expressions, fit one- and two-comparison guards exactly (and
    extend the best pairs to three when allowed); a deeper level is searched only while it beats
    the previous one after the price of complexity (settings.complexity_cost). Then the best
    candidates' lane widths are refined to the centimetre, and z3 re-solves the thresholds of
    the best few.

    A threshold that only the absent-person stand-in (socialzoo.agents.pips_features.FAR) reaches is refused
    (`physical_thresholds`). The expressions come from socialzoo.train.pips_enumerate; the thresholds from
    socialzoo.train.pips_thresholds. The search widens (deeper expressions) only while that improves the guard
    by more than the price of complexity.

    Args:
        parts: the examples' observations (socialzoo.agents.pips_features.paper_parts).
        label: (N,) bool, where the guard should hold.
        weight: (N,) example weights.
        settings: the search's settings.

    Returns:
        The best candidate, or None when no guard beats never firing.
    """
    total = float(weight.sum())
    never = float(weight[~label].sum())
    rank = _Ranker(settings.complexity_cost)
    atoms = AtomCache(parts)
    names: list[Expr] = [Atom(name) for name in ATOMS]
    bank = FeatureBank(atoms)
    best: list[Candidate] = []
    beam: list[Expr] = []
    for depth in range(settings.max_depth + 1):
        if depth > 0 and time.monotonic() > settings.deadline:
            logger.info("time budget reached: no expressions of depth %d", depth)
            break
        try:
            added = bank.add(enumerate_depth(depth, beam, names))
        except UnitError as err:  # enumeration builds unit-consistent expressions only
            raise AssertionError(f"enumerated an expression with inconsistent units: {err}") from None
        added += refine_lane_features(bank, label, weight, settings.refine)
        cands = sorted(_level_candidates(bank, label, weight, settings), key=rank.key)
        logger.debug("depth %d: %d new expressions, %d in all", depth, len(added), len(bank.exprs))
        if not cands or (best and rank.merit(cands[0]) <= rank.merit(best[0])):
            break
        best = cands
        if best[0].score >= total or not added:
            break
        fit = fit_single(bank.values[added], label, weight)
        beam = [bank.exprs[added[i]] for i in np.argsort(-fit.score, kind="stable")[: settings.beam]]
    distinct = list({c.predicate: c for c in best}.values())
    refined = sorted(
        (_refine_lanes(c, atoms, label, weight) for c in distinct[: settings.refine]), key=rank.key
    )
    # A guard must pay for itself: beat never firing by the price of one comparison more than
    # the price of its complexity.
    if not refined or rank.merit(refined[0]) - rank.cost <= never:
        return None
    if settings.solver == "z3":
        refined = sorted(
            (_solve_with_z3(c, atoms, label, weight, settings) for c in refined[: settings.z3_candidates]),
            key=rank.key,
        )
    return refined[0]
