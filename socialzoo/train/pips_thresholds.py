"""Threshold holes of PIPS predicate sketches: the thresholds that classify the most (weighted) examples correctly,
by an exact search (one comparison, or a pair joined by and/or) and by z3's MaxSMT optimiser (any sketch)."""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import numpy as np

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class SingleFit:
    """Best single comparisons of many features at once.

    Attributes:
        score: (F,) weighted correct count of the best comparison of each feature.
        cmp: (F,) "<=" or ">=".
        threshold: (F,) the threshold, midway between the two example values it separates.
    """

    score: np.ndarray
    cmp: np.ndarray
    threshold: np.ndarray


def fit_single(values: np.ndarray, label: np.ndarray, weight: np.ndarray) -> SingleFit:
    """The best comparison `f <= t` or `f >= t` for each feature row, exactly.

    Only thresholds that split the examples are considered (a constant guard is no comparison);
    a feature with a single value gets score -inf.

    Args:
        values: (F, N) feature values on the examples.
        label: (N,) bool, where the guard should hold.
        weight: (N,) positive example weights.
    """
    num_features, n = values.shape
    order = np.argsort(values, axis=1, kind="stable")
    v = np.take_along_axis(values, order, axis=1)
    g = (weight * np.where(label, 1.0, -1.0))[order]
    s = np.cumsum(g, axis=1)[:, :-1]  # s[:, k-1]: examples 0..k-1 predicted true (k = 1..n-1)
    w_pos, w_neg = float(weight[label].sum()), float(weight[~label].sum())
    split = v[:, 1:] > v[:, :-1]  # a threshold between sorted k-1 and k separates them
    le = np.where(split, w_neg + s, -np.inf)
    ge = np.where(split, w_pos - s, -np.inf)
    k_le, k_ge = np.argmax(le, axis=1), np.argmax(ge, axis=1)
    rows = np.arange(num_features)
    best_le, best_ge = le[rows, k_le], ge[rows, k_ge]
    use_le = best_le >= best_ge
    k = np.where(use_le, k_le, k_ge)
    lo, hi = v[rows, k], v[rows, k + 1] if n > 1 else v[rows, k]
    return SingleFit(
        score=np.where(use_le, best_le, best_ge),
        cmp=np.where(use_le, "<=", ">="),
        threshold=0.5 * (lo + hi),
    )


def _midpoint(values: np.ndarray, t: float) -> float:
    """A threshold classifying `values` as `<= t` does, midway to the next value above t."""
    above = values[values > t]
    below = values[values <= t]
    lo = float(below.max()) if len(below) else t
    hi = float(above.min()) if len(above) else lo + 1.0
    return 0.5 * (lo + hi)


@dataclass(frozen=True)
class PairFit:
    """The best `a cmp_a t_a  <junction>  b cmp_b t_b` for a fixed `a` and each candidate `b`.

    Thresholds are kept as the example values they sit on (signed: a ">=" comparison is
    `-f <= -t`); `PairSearch.thresholds` turns one into midpoints.

    Attributes:
        score: (F,) weighted correct count for each `b`.
        junction: (F,) "and" or "or".
        sign_a, sign_b: (F,) +1 for "<=", -1 for ">=".
        raw_a, raw_b: (F,) the signed example values the thresholds sit on.
    """

    score: np.ndarray
    junction: np.ndarray
    sign_a: np.ndarray
    sign_b: np.ndarray
    raw_a: np.ndarray
    raw_b: np.ndarray


def boundary_candidates(values: np.ndarray, positive: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per row, the thresholds of `f <= t` worth trying: the values of positive examples after
    which (in increasing order) comes a negative one, or nothing. Moving a threshold up past a
    stretch of positives only adds positives, and moving it down to a positive's value only
    drops negatives, so for "and" and "or" alike an optimum sits at one of these.

    Args:
        values: (F, N) feature values.
        positive: (N,) bool labels.

    Returns:
        (cand, count): cand (F, M) each row's candidates in increasing order, padded by
        repeating its last one; count (F,) how many are real.
    """
    num_rows, n = values.shape
    order = np.argsort(values, axis=1, kind="stable")
    v = np.take_along_axis(values, order, axis=1)
    p = positive[order]
    starts = np.ones((num_rows, n), dtype=bool)
    starts[:, 1:] = v[:, 1:] > v[:, :-1]
    group = np.cumsum(starts, axis=1) - 1
    flat = (np.arange(num_rows)[:, None] * n + group).ravel()
    has_pos = np.bincount(flat, weights=p.ravel(), minlength=num_rows * n).reshape(num_rows, n) > 0
    has_neg = np.bincount(flat, weights=(~p).ravel(), minlength=num_rows * n).reshape(num_rows, n) > 0
    is_last = np.arange(n)[None, :] == group[:, -1:]
    next_neg = np.zeros((num_rows, n), dtype=bool)
    next_neg[:, :-1] = has_neg[:, 1:]
    chosen = has_pos & (next_neg | is_last)
    group_value = np.zeros((num_rows, n))
    rows, cols = np.nonzero(starts)
    group_value[rows, group[rows, cols]] = v[rows, cols]
    count = chosen.sum(axis=1)
    width = max(int(count.max()), 1)
    pick = np.argsort(~chosen, axis=1, kind="stable")[:, :width]
    cand = np.take_along_axis(group_value, pick, axis=1)
    last = cand[np.arange(num_rows), np.maximum(count - 1, 0)]
    cand = np.where(np.arange(width)[None, :] >= count[:, None], last[:, None], cand)
    return cand, count


class PairSearch:
    """Exact search of the best pair of comparisons joined by "and" or "or", for features `b`
    given once and a feature `a` given per call.

    Each threshold is tried at the `boundary_candidates` of its feature only: with Ca and Cb of
    them, a (junction, directions) combination is a (Ca+1) x (Cb+1) table of 2-D prefix sums,
    built for many `b` at once (rows with similar Cb together).

    Args:
        others: (F, N) values of the features `b`.
        label: (N,) bool, where the guard should hold.
        weight: (N,) positive example weights.
    """

    def __init__(
        self, others: np.ndarray, label: np.ndarray, weight: np.ndarray, *, block: int = 512
    ) -> None:
        self.others = others
        self.pos = np.asarray(label, dtype=bool)
        self.g = weight * np.where(self.pos, 1.0, -1.0)
        self.w_neg = float(weight[~self.pos].sum())
        self.exact32 = bool(np.all(weight == np.round(weight))) and float(weight.sum()) < 2**24
        # Per direction: each row's candidates, their count, and every example's rank r among
        # them (f <= cand[i] exactly when i >= r; r >= count: at no candidate).
        self.ranks: dict[float, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        num_features = len(others)
        for sign in (1.0, -1.0):
            parts = [
                boundary_candidates(sign * others[lo : lo + block], self.pos)
                for lo in range(0, num_features, block)
            ]
            width = max((c.shape[1] for c, _ in parts), default=1)
            cand = (
                np.concatenate([np.pad(c, ((0, 0), (0, width - c.shape[1])), mode="edge") for c, _ in parts])
                if parts
                else np.zeros((0, 1))
            )
            count = np.concatenate([k for _, k in parts]) if parts else np.zeros(0, dtype=np.int64)
            rank = np.empty(others.shape, dtype=np.int32)
            for f in range(num_features):  # searchsorted has no row-wise form
                rank[f] = np.minimum(np.searchsorted(cand[f], sign * others[f], side="left"), count[f])
            self.ranks[sign] = (cand, count, rank)

    def fit(self, a: np.ndarray, *, chunk: int = 256) -> PairFit:
        """The best pair (a, b) for every `b`: every direction, junction and threshold."""
        num_features, n = self.others.shape
        pos, g = self.pos, self.g
        best = np.full(num_features, -np.inf)
        junction = np.full(num_features, "and", dtype=object)
        sign_a_out, sign_b_out = np.ones(num_features), np.ones(num_features)
        raw_a, raw_b = np.zeros(num_features), np.zeros(num_features)
        if not pos.any() or n == 0:
            return PairFit(best, junction, sign_a_out, sign_b_out, raw_a, raw_b)
        for sign_a in (1.0, -1.0):
            cand_a, count_a = boundary_candidates((sign_a * a)[None, :], pos)
            ma = int(count_a[0])
            cand_a = cand_a[0, :ma]
            ra = np.minimum(np.searchsorted(cand_a, sign_a * a, side="left"), ma)
            for sign_b in (1.0, -1.0):
                cand_b, count_b, rank_b = self.ranks[sign_b]
                by_count = np.argsort(count_b, kind="stable")
                for lo in range(0, num_features, chunk):
                    rows = by_count[lo : lo + chunk]
                    k_rows = len(rows)
                    mb = int(count_b[rows].max())
                    size = (ma + 1) * (mb + 1)
                    idx = np.arange(k_rows)[:, None] * size + ra[None, :] * (mb + 1) + rank_b[rows]
                    hist = np.bincount(
                        idx.ravel(), weights=np.broadcast_to(g, (k_rows, n)).ravel(), minlength=k_rows * size
                    ).reshape(k_rows, ma + 1, mb + 1)
                    # float32 sums of example weights are exact while they stay below 2^24.
                    hist = hist.astype(np.float32) if self.exact32 else hist
                    both = hist.cumsum(axis=1).cumsum(axis=2)[:, :ma, :mb]  # a and b hold
                    only_a = hist.sum(axis=2).cumsum(axis=1)[:, :ma]  # a holds
                    only_b = hist.sum(axis=1).cumsum(axis=1)[:, :mb]  # b holds
                    for name_j, covered in (
                        ("and", both),
                        ("or", only_a[:, :, None] + only_b[:, None, :] - both),
                    ):
                        flat = covered.reshape(k_rows, -1)
                        k = np.argmax(flat, axis=1)
                        score = self.w_neg + flat[np.arange(k_rows), k]
                        better = score > best[rows]
                        if not better.any():
                            continue
                        i, j = np.divmod(k[better], mb)
                        sel = rows[better]
                        best[sel] = score[better]
                        junction[sel] = name_j
                        sign_a_out[sel] = sign_a
                        sign_b_out[sel] = sign_b
                        raw_a[sel] = cand_a[i]
                        raw_b[sel] = cand_b[sel, j]
        return PairFit(best, junction, sign_a_out, sign_b_out, raw_a, raw_b)

    def thresholds(self, a: np.ndarray, fit: PairFit, f: int) -> tuple[str, float, str, float]:
        """(cmp_a, t_a, cmp_b, t_b) of the pair (a, b = row f), thresholds at midpoints."""
        sa, sb = float(fit.sign_a[f]), float(fit.sign_b[f])
        t_a = sa * _midpoint(sa * a, float(fit.raw_a[f]))
        t_b = sb * _midpoint(sb * self.others[f], float(fit.raw_b[f]))
        return ("<=" if sa > 0 else ">="), t_a, ("<=" if sb > 0 else ">="), t_b


# ---------------------------------------------------------------------------------- z3 (MaxSMT)
# A sketch for the solvers: ("leaf", index, cmp) or (junction, [sketch, ...]).
Sketch = tuple[Any, ...]


def sketch_eval(sketch: Sketch, columns: list[np.ndarray], thresholds: list[float]) -> np.ndarray:
    """Where a sketch holds, with its thresholds filled in ((N,) bool)."""
    if sketch[0] == "leaf":
        _, i, cmp = sketch
        return columns[i] <= thresholds[i] if cmp == "<=" else columns[i] >= thresholds[i]
    vals = [sketch_eval(s, columns, thresholds) for s in sketch[1]]
    return (np.logical_and if sketch[0] == "and" else np.logical_or).reduce(vals)


def centre_thresholds(sketch: Sketch, columns: list[np.ndarray], thresholds: list[float]) -> list[float]:
    """Move each threshold to the middle of the gap between example values it falls in (the
    same examples on each side, so the same classification); a ">=" comparison is `-f <= -t`."""
    out = list(thresholds)
    for i, col in enumerate(columns):
        sign = 1.0 if _leaf_cmp(sketch, i) == "<=" else -1.0
        out[i] = sign * _midpoint(sign * col, sign * thresholds[i])
    return out


def _leaf_cmp(sketch: Sketch, index: int) -> str | None:
    if sketch[0] == "leaf":
        return sketch[2] if sketch[1] == index else None
    for s in sketch[1]:
        found = _leaf_cmp(s, index)
        if found is not None:
            return found
    return None


def score_of(sketch: Sketch, columns: list[np.ndarray], thresholds: list[float], label, weight) -> float:
    """Weighted number of examples the filled sketch classifies as labelled."""
    return float(weight[sketch_eval(sketch, columns, thresholds) == label].sum())


def solve_z3(
    sketch: Sketch,
    columns: list[np.ndarray],
    label: np.ndarray,
    weight: np.ndarray,
    *,
    timeout_s: float = 30.0,
    seed: int = 0,
) -> tuple[float, list[float]] | None:
    """The thresholds that maximise the weighted correctly classified examples, by z3's Optimize
    (MaxSMT: one weighted soft constraint "guard(e) == label(e)" per distinct example).

    A sketch is a predicate (socialzoo.agents.pips) whose thresholds are holes; here its comparisons are given
    by their value columns (the compared expression on every example) and directions. Both solvers (this and
    the exact search) maximise the weighted number of examples the guard classifies as labelled, and both
    place each threshold midway between the nearest example values on either side.

    Args:
        sketch: the predicate sketch; its leaves index `columns`.
        columns: (N,) values of each compared expression.
        label: as in `fit_single`.
        weight: as in `fit_single`.
        timeout_s: z3's time limit.
        seed: z3's random seed.

    Returns:
        (score, centred thresholds), or None when z3 gives up within the time limit.
    """
    import z3

    table = np.column_stack([*columns, label.astype(np.float64)])
    rows, inverse = np.unique(table, axis=0, return_inverse=True)
    row_weight = np.bincount(inverse.ravel(), weights=weight, minlength=len(rows))
    # Integer weights when they are (the usual case); z3 adds them exactly.
    scale = 1.0 if np.allclose(row_weight, np.round(row_weight)) else 1000.0
    opt = z3.Optimize()
    opt.set(timeout=max(1, int(timeout_s * 1000)))
    opt.set("maxsat_engine", "maxres")
    z3.set_param("smt.random_seed", seed)
    t = [z3.Real(f"t{i}") for i in range(len(columns))]

    def formula(node: Sketch, row: np.ndarray) -> Any:
        if node[0] == "leaf":
            _, i, cmp = node
            value = z3.RealVal(repr(float(row[i])))
            return value <= t[i] if cmp == "<=" else value >= t[i]
        parts = [formula(s, row) for s in node[1]]
        return z3.And(*parts) if node[0] == "and" else z3.Or(*parts)

    for row, w in zip(rows, row_weight, strict=True):
        holds = formula(sketch, row)
        opt.add_soft(holds if row[-1] > 0.5 else z3.Not(holds), round(w * scale))
    if opt.check() != z3.sat:
        logger.warning("z3 gave up on a sketch (%s)", opt.reason_unknown())
        return None
    model = opt.model()
    thresholds = []
    for i, var in enumerate(t):
        value = model.eval(var, model_completion=True)
        num = value.as_fraction() if z3.is_rational_value(value) else None
        thresholds.append(float(num) if num is not None else float(np.median(columns[i])))
    thresholds = centre_thresholds(sketch, columns, thresholds)
    return score_of(sketch, columns, thresholds, label, weight), thresholds
