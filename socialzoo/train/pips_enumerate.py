"""Enumeration of PIPS feature expressions for the synthesiser: unit-consistent expressions by depth, their values
on the examples without order-duplicates, and lane half-widths refined to the centimetre."""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping, Sequence

import numpy as np

from socialzoo.agents.pips import Atom, Expr, Op, expr_atoms, expr_depth, expr_eval, expr_str, expr_unit
from socialzoo.agents.pips_features import (
    COMPARABLE_UNITS,
    LANE_CM_RANGE,
    PaperParts,
    atom_values,
    lane_cm,
    with_lane_cm,
)
from socialzoo.train.pips_thresholds import fit_single


def combine(left: Expr, right: Expr) -> list[Expr]:
    """Every unit-consistent binary expression of `left` and `right` whose unit is comparable
    (socialzoo.agents.pips_features.COMPARABLE_UNITS); commutative operators once per pair."""
    out: list[Expr] = []
    lu, ru = expr_unit(left), expr_unit(right)
    if left == right:
        return out
    if lu == ru:
        # One orientation of a difference: b - a <= t is a - b >= -t. Human features first
        # ("lane62.dist - target_dist"), then alphabetical.
        first, second = sorted((left, right), key=lambda e: (not _about_humans(e), expr_str(e)))
        out.append(Op("-", (first, second)))
        out.append(Op("+", (left, right)))
        out.append(Op("norm", (left, right)))
    for op, unit in (("*", lu * ru), ("/", lu / ru)):
        if unit in COMPARABLE_UNITS:
            out.append(Op(op, (left, right)))
    if (ru / lu) in COMPARABLE_UNITS:
        out.append(Op("/", (right, left)))
    return out


def _about_humans(expr: Expr) -> bool:
    return any("." in name for name in expr_atoms(expr))


def enumerate_depth(depth: int, beam: Sequence[Expr], atoms: Sequence[Expr]) -> list[Expr]:
    """Expressions of exactly `depth`: the atoms (depth 0), or each beam expression of depth
    depth - 1 under abs and combined with each atom (atom pairs once each at depth 1).

    Every expression returned has a comparable unit; none adds, subtracts or compares
    quantities of different units (such a combination is never built).

    Depth d combines a beam of depth d-1 expressions with an atom by +, -, norm (same unit only), *, / (when
    the result is a comparable unit) or abs.
    """
    if depth == 0:
        return list(atoms)
    out: list[Expr] = []
    seen: set[Expr] = set()
    for left in beam:
        candidates: list[Expr] = [Op("abs", (left,))]
        for right in atoms:
            candidates += combine(left, right)
        for expr in candidates:
            if expr not in seen and expr_depth(expr) == depth:
                seen.add(expr)
                out.append(expr)
    return out


def _rank_signatures(values: np.ndarray) -> tuple[list[bytes], list[bytes]]:
    """Per row, the dense ranks of its values, and of its negation (rows that order the examples
    alike, or in reverse, compare alike: f <= t is -f >= -t)."""
    order = np.argsort(values, axis=1, kind="stable")
    v = np.take_along_axis(values, order, axis=1)
    dense = np.concatenate(
        [np.zeros((len(v), 1), dtype=np.int32), np.cumsum(np.diff(v, axis=1) > 0, axis=1, dtype=np.int32)],
        axis=1,
    )
    ranks = np.empty_like(dense)
    np.put_along_axis(ranks, order, dense, axis=1)
    flipped = ranks.max(axis=1, keepdims=True) - ranks
    return [r.tobytes() for r in ranks], [r.tobytes() for r in flipped]


class AtomCache(Mapping[str, np.ndarray]):
    """Atomic feature values on the examples, computed on first use (lane selectors of any
    half-width included)."""

    def __init__(self, parts: PaperParts) -> None:
        self.parts = parts
        self._values: dict[str, np.ndarray] = {}

    def __getitem__(self, name: str) -> np.ndarray:
        if name not in self._values:
            self._values.update(atom_values(self.parts, [name]))
        return self._values[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)


class FeatureBank:
    """Feature expressions and their values on the examples, without order-duplicates (an
    expression that orders the examples as a kept one does, or in reverse, is dropped).

    Why: a comparison sees only the order.
    """

    def __init__(self, atoms: Mapping[str, np.ndarray]) -> None:
        self.atoms = atoms
        self.exprs: list[Expr] = []
        self.rows: list[np.ndarray] = []
        self._signatures: set[bytes] = set()

    def add(self, exprs: Iterable[Expr]) -> list[int]:
        """Evaluate and keep the expressions that order the examples in a new way (and are
        finite and not constant); returns their indices."""
        exprs = list(exprs)
        if not exprs:
            return []
        with np.errstate(all="ignore"):
            values = np.stack([expr_eval(e, self.atoms) for e in exprs]).astype(np.float64)
        ok = np.isfinite(values).all(axis=1) & (values.max(axis=1) > values.min(axis=1))
        kept = []
        signatures, flipped = _rank_signatures(values)
        for e, v, sig, flip, good in zip(exprs, values, signatures, flipped, ok, strict=True):
            if good and sig not in self._signatures and flip not in self._signatures:
                self._signatures.add(sig)
                kept.append(len(self.exprs))
                self.exprs.append(e)
                self.rows.append(v)
        return kept

    @property
    def values(self) -> np.ndarray:
        """(F, N) values of every kept expression."""
        return np.stack(self.rows) if self.rows else np.zeros((0, 0))


def rename_atom(expr: Expr, old: str, new: str) -> Expr:
    """The expression with the atom `old` replaced by `new`."""
    if isinstance(expr, Atom):
        return Atom(new) if expr.name == old else expr
    return Op(expr.op, tuple(rename_atom(a, old, new) for a in expr.args))


def rename_lane(expr: Expr, cm: int, new_cm: int) -> Expr:
    """The expression with every lane feature of half-width `cm` (cm) moved to `new_cm`."""
    for name in expr_atoms(expr):
        if lane_cm(name) == cm:
            expr = rename_atom(expr, name, with_lane_cm(name, new_cm))
    return expr


def lane_family(expr: Expr) -> str | None:
    """The expression's text with every lane half-width blanked (None without lanes)."""
    widths = {c for n in expr_atoms(expr) if (c := lane_cm(n))}
    if not widths:
        return None
    for cm in widths:
        expr = rename_lane(expr, cm, LANE_CM_RANGE[0])
    return expr_str(expr)


def refine_lane_features(bank: FeatureBank, label: np.ndarray, weight: np.ndarray, count: int) -> list[int]:
    """For the `count` best families of lane expressions (the same expression at other lane
    half-widths), add the variant whose half-width, to the centimetre and within 9 cm of the
    family's best enumerated one, compares best (among ties, the middle one).

    The half-width is a threshold inside a selector: expressions that use it well often show
    only once combined (a gap to the local target, say), so it is refined at every depth."""
    fit = fit_single(bank.values, label, weight)
    best: dict[str, int] = {}
    for f in np.argsort(-fit.score, kind="stable").tolist():
        family = lane_family(bank.exprs[f])
        if family is not None and family not in best:
            best[family] = f
            if len(best) == count:
                break
    added: list[int] = []
    for f in best.values():
        expr = bank.exprs[f]
        for cm in sorted({c for n in expr_atoms(expr) if (c := lane_cm(n))}):
            variants = [
                rename_lane(expr, cm, new)
                for new in range(max(cm - 9, LANE_CM_RANGE[0]), min(cm + 9, LANE_CM_RANGE[1]) + 1)
            ]
            with np.errstate(all="ignore"):
                values = np.stack([expr_eval(e, bank.atoms) for e in variants])
            scores = fit_single(values, label, weight).score
            top = np.flatnonzero(scores == scores.max())
            expr = variants[int(top[len(top) // 2])]
        added += bank.add([expr])
    return added
