"""The features PIPS programs are written in: physical units, and the atomic features (with their
units) computed, batched, from paper-layout observations (SPEC section 8)."""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from socialzoo.core.geometry import wrap_angle


class UnitError(ValueError):
    """An expression or a comparison whose physical units do not agree (or an unreadable unit)."""


# Base dimensions of a unit, in order: length (m), time (s), plane angle (rad).
_SYMBOLS = ("m", "s", "rad")
_TOKEN = re.compile(r"^(m|s|rad)(?:\^(-?[1-9][0-9]*))?$")


@dataclass(frozen=True, order=True)
class Unit:
    """A physical unit as integer exponents of metres, seconds and radians (m/s is (1, -1, 0)).

    The plane angle is kept as its own dimension, so that an angle (rad) and a ratio of lengths
    (dimensionless) are not confused.
    """

    m: int = 0
    s: int = 0
    rad: int = 0

    def __mul__(self, other: Unit) -> Unit:
        return Unit(self.m + other.m, self.s + other.s, self.rad + other.rad)

    def __truediv__(self, other: Unit) -> Unit:
        return Unit(self.m - other.m, self.s - other.s, self.rad - other.rad)

    def __str__(self) -> str:
        def side(exps: list[tuple[str, int]]) -> str:
            return "*".join(sym if e == 1 else f"{sym}^{e}" for sym, e in exps)

        exps = list(zip(_SYMBOLS, (self.m, self.s, self.rad), strict=True))
        num = side([(sym, e) for sym, e in exps if e > 0])
        den = side([(sym, -e) for sym, e in exps if e < 0])
        if not den:
            return num or "1"
        return f"{num or '1'}/{den}"

    @classmethod
    def parse(cls, text: str) -> Unit:
        """The unit written as `str(unit)` writes it ("m", "m/s", "rad/s", "1", "m^2", "1/s").

        Raises:
            UnitError: text that is not such a unit.
        """
        if not isinstance(text, str) or not text:
            raise UnitError(f"a unit must be a string such as 'm' or 'm/s', got {text!r}")
        parts = text.split("/")
        if len(parts) > 2:
            raise UnitError(f"unreadable unit {text!r}: more than one '/'")
        exps = dict.fromkeys(_SYMBOLS, 0)
        for sign, part in zip((1, -1), parts, strict=False):
            if part == "1":
                continue
            for token in part.split("*"):
                match = _TOKEN.match(token)
                if match is None:
                    raise UnitError(f"unreadable unit {text!r}: unknown symbol {token!r} (use m, s, rad)")
                exps[match.group(1)] += sign * int(match.group(2) or 1)
        unit = cls(**exps)
        if str(unit) != text:
            raise UnitError(f"unit {text!r} is not written in canonical form; write {str(unit)!r}")
        return unit


DIMENSIONLESS = Unit()
METRE = Unit(m=1)
SECOND = Unit(s=1)
RADIAN = Unit(rad=1)
METRE_PER_SECOND = Unit(m=1, s=-1)
RADIAN_PER_SECOND = Unit(s=-1, rad=1)
# Units a compared expression may have: the quantities a navigation rule talks about. Products
# and quotients outside this set (m^2, 1/s, m*rad...) are never enumerated.
COMPARABLE_UNITS: frozenset[Unit] = frozenset(
    {DIMENSIONLESS, METRE, SECOND, RADIAN, METRE_PER_SECOND, RADIAN_PER_SECOND}
)

# A human that a selector does not find counts as standing this far away, m (farther than any
# human the robot can see on the benchmark maps), still, and straight behind.
FAR = 1000.0
# A human slower than this has no walking direction (its heading mismatch counts as pi), m/s; the
# sub-policies' target selection uses the same convention (SubPolicyConfig.still_speed).
STILL_SPEED = 0.1
# Half-widths of the lanes ahead of the robot that the enumerated "lane" selectors look in, m.
# Any half-width from 0.20 to 2.00 m in whole centimetres is a valid selector ("lane62": 0.62 m):
# the synthesiser refines the enumerated ones to the centimetre.
LANE_WIDTHS: tuple[float, ...] = (0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0)
LANE_CM_RANGE = (20, 200)
_LANE = re.compile(r"^lane([1-9][0-9]*)\.([a-z]+)$")


class PaperParts(NamedTuple):
    """The parts of a batch of paper-layout observations (SPEC section 8), robot frame.

    Attributes:
        goal: (N, 2) global goal (x, y), m.
        target: (N, 2) local target (x, y), m.
        robot_vel: (N, 2) robot (v m/s, omega rad/s).
        prev_action: (N,) int64 previous action index: the program's current state.
        slots: (N, K, 4) visible humans nearest first: (x, y) m and (vx, vy) m/s relative to the
            robot (the robot's own (v, 0) subtracted), all zero for an empty slot.
    """

    goal: np.ndarray
    target: np.ndarray
    robot_vel: np.ndarray
    prev_action: np.ndarray
    slots: np.ndarray


def paper_parts(obs: np.ndarray) -> PaperParts:
    """Split (N, 7 + 4K) paper-layout observations into their parts (the one place PIPS reads the
    layout).

    Raises:
        ValueError: the width is not 7 + 4K.
    """
    obs = np.asarray(obs, dtype=np.float64)
    width = obs.shape[-1]
    if obs.ndim != 2 or width < 7 or (width - 7) % 4:
        raise ValueError(f"PIPS reads paper-layout observations (N, 7 + 4K), got shape {obs.shape}")
    n = obs.shape[0]
    return PaperParts(
        goal=obs[:, 0:2],
        target=obs[:, 2:4],
        robot_vel=obs[:, 4:6],
        prev_action=np.rint(obs[:, 6]).astype(np.int64),
        slots=obs[:, 7:].reshape(n, -1, 4),
    )


@dataclass(frozen=True)
class AtomSpec:
    """An atomic feature: its name, unit and meaning.

    An atomic feature is one number per observation: the robot's speed, the distance to the local target, or
    an attribute of one chosen human (its distance, lateral offset, walking speed...). Humans are chosen by a
    selector: the nearest visible one, the nearest ahead (x > 0), or the nearest ahead inside a lane |y| <= w
    of a fixed half-width w. Feature expressions (sums, ratios...) are built over these in
    socialzoo.agents.pips; units keep those expressions meaningful.
    """

    name: str
    unit: Unit
    description: str


# Selectors: which human an attribute is read from.
_SELECTORS: dict[str, str] = {
    "near": "the nearest visible human",
    "ahead": "the nearest visible human ahead (x > 0)",
    **{
        f"lane{round(100 * w)}": f"the nearest visible human ahead in the lane |y| <= {w:.1f} m"
        for w in LANE_WIDTHS
    },
}
# Attributes of a selected human: (unit, meaning).
_ATTRIBUTES: dict[str, tuple[Unit, str]] = {
    "dist": (METRE, "distance"),
    "x": (METRE, "distance ahead along the heading"),
    "absy": (METRE, "lateral offset |y|"),
    "speed": (METRE_PER_SECOND, "walking speed"),
    "closing": (METRE_PER_SECOND, "closing speed (positive when the gap shrinks)"),
    "mismatch": (RADIAN, "angle between its walking direction and the direction to the local target"),
    "bearing": (RADIAN, "bearing |atan2(y, x)|"),
}
_HEADER: dict[str, tuple[Unit, str]] = {
    "goal_dist": (METRE, "distance to the goal"),
    "goal_bearing": (RADIAN, "bearing of the goal |atan2(y, x)|"),
    "target_dist": (METRE, "distance to the local target"),
    "target_bearing": (RADIAN, "bearing of the local target |atan2(y, x)|"),
    "robot_v": (METRE_PER_SECOND, "robot's speed"),
    "robot_omega": (RADIAN_PER_SECOND, "robot's turn rate (left positive)"),
    "num_visible": (DIMENSIONLESS, "number of visible humans"),
    "num_ahead": (DIMENSIONLESS, "number of visible humans ahead"),
}

ATOMS: dict[str, AtomSpec] = {
    **{name: AtomSpec(name, unit, text) for name, (unit, text) in _HEADER.items()},
    **{
        f"{sel}.{attr}": AtomSpec(f"{sel}.{attr}", unit, f"{text} of {who}")
        for sel, who in _SELECTORS.items()
        for attr, (unit, text) in _ATTRIBUTES.items()
    },
}


def atom_spec(name: str) -> AtomSpec:
    """The atomic feature called `name`: one of ATOMS, or a lane selector of any half-width in
    whole centimetres within LANE_CM_RANGE ("lane62.dist").

    Raises:
        KeyError: an unknown feature (the message names it).
    """
    if name in ATOMS:
        return ATOMS[name]
    match = _LANE.match(name) if isinstance(name, str) else None
    if match is not None and match.group(2) in _ATTRIBUTES:
        cm = int(match.group(1))
        if LANE_CM_RANGE[0] <= cm <= LANE_CM_RANGE[1]:
            unit, text = _ATTRIBUTES[match.group(2)]
            return AtomSpec(
                name, unit, f"{text} of the nearest visible human ahead in the lane |y| <= {cm / 100:.2f} m"
            )
    raise KeyError(
        f"unknown PIPS feature {name!r}; features are {', '.join(_HEADER)}, or SELECTOR.ATTRIBUTE with "
        f"SELECTOR near, ahead or laneCM ({LANE_CM_RANGE[0]} <= CM <= {LANE_CM_RANGE[1]}) and ATTRIBUTE "
        f"one of {', '.join(_ATTRIBUTES)}"
    )


def human_present(atoms: Mapping[str, np.ndarray], name: str) -> np.ndarray | None:
    """Where the human an atomic feature reads was found ((N,) bool), or None for a feature of
    the robot, its goal or target (always there). Absent humans read as FAR away (see FAR)."""
    if "." not in name:
        return None
    return atoms[f"{name.split('.', 1)[0]}.dist"] < FAR


def lane_cm(name: str) -> int | None:
    """The lane half-width (cm) of a lane feature's name, None for other features."""
    match = _LANE.match(name)
    return int(match.group(1)) if match is not None else None


def with_lane_cm(name: str, cm: int) -> str:
    """A lane feature's name with another half-width (cm)."""
    match = _LANE.match(name)
    if match is None:
        raise KeyError(f"{name!r} is not a lane feature")
    return f"lane{cm}.{match.group(2)}"


def _selector_mask(name: str, xy: np.ndarray, seen: np.ndarray) -> np.ndarray:
    if name == "near":
        return seen
    ahead = seen & (xy[..., 0] > 0.0)
    if name == "ahead":
        return ahead
    return ahead & (np.abs(xy[..., 1]) <= int(name[4:]) / 100.0)


def _human_attributes(sel: str, parts: PaperParts) -> dict[str, np.ndarray]:
    """Every attribute of the human `sel` picks, per row; FAR-away defaults where there is none."""
    slots = parts.slots
    if slots.shape[1] == 0:  # no slots: one empty slot, nobody seen
        slots = np.zeros((len(slots), 1, 4))
    xy, rel_vel = slots[..., 0:2], slots[..., 2:4]
    seen = (xy != 0.0).any(axis=-1)
    dist = np.sqrt((xy**2).sum(-1))
    mask = _selector_mask(sel, xy, seen)
    rows = np.arange(len(slots))
    pick = np.argmin(np.where(mask, dist, np.inf), axis=1)
    found = mask.any(axis=1)
    hx, hy, hd = xy[rows, pick, 0], xy[rows, pick, 1], dist[rows, pick]
    rvx, rvy = rel_vel[rows, pick, 0], rel_vel[rows, pick, 1]
    # The human's own walking velocity in robot axes: add back the robot's (v, 0).
    wvx, wvy = rvx + parts.robot_vel[:, 0], rvy
    speed = np.hypot(wvx, wvy)
    target_dir = np.arctan2(parts.target[:, 1], parts.target[:, 0])
    mismatch = np.abs(wrap_angle(np.arctan2(wvy, wvx) - target_dir))
    mismatch = np.where(speed < STILL_SPEED, math.pi, mismatch)
    closing = -(hx * rvx + hy * rvy) / np.maximum(hd, 1e-9)
    values = {
        "dist": hd,
        "x": hx,
        "absy": np.abs(hy),
        "speed": speed,
        "closing": closing,
        "mismatch": mismatch,
        "bearing": np.abs(np.arctan2(hy, hx)),
    }
    absent = {"dist": FAR, "x": FAR, "absy": FAR, "speed": 0.0, "closing": 0.0, "mismatch": math.pi}
    absent["bearing"] = math.pi
    return {k: np.where(found, v, absent[k]) for k, v in values.items()}


def _seen(parts: PaperParts) -> np.ndarray:
    """(N, K) bool: the slots that hold a visible human (an empty slot is all zero)."""
    return (parts.slots[..., 0:2] != 0.0).any(axis=-1)


# The robot's own features (_HEADER), each from the observations' parts.
_HEADER_VALUES: dict[str, Callable[[PaperParts], np.ndarray]] = {
    "goal_dist": lambda p: np.hypot(p.goal[:, 0], p.goal[:, 1]),
    "goal_bearing": lambda p: np.abs(np.arctan2(p.goal[:, 1], p.goal[:, 0])),
    "target_dist": lambda p: np.hypot(p.target[:, 0], p.target[:, 1]),
    "target_bearing": lambda p: np.abs(np.arctan2(p.target[:, 1], p.target[:, 0])),
    "robot_v": lambda p: p.robot_vel[:, 0].copy(),
    "robot_omega": lambda p: p.robot_vel[:, 1].copy(),
    "num_visible": lambda p: _seen(p).sum(axis=1).astype(np.float64),
    "num_ahead": lambda p: (_seen(p) & (p.slots[..., 0] > 0.0)).sum(axis=1).astype(np.float64),
}


def atom_values(obs_or_parts: np.ndarray | PaperParts, names: set[str] | list[str]) -> dict[str, np.ndarray]:
    """The atomic features `names` for a batch of paper-layout observations.

    Args:
        obs_or_parts: (N, 7 + 4K) observations, or their `paper_parts`.
        names: keys of ATOMS.

    Returns:
        name -> (N,) float64 values in the feature's unit.

    Raises:
        KeyError: an unknown feature name (the message names it).
    """
    parts = obs_or_parts if isinstance(obs_or_parts, PaperParts) else paper_parts(obs_or_parts)
    for name in names:
        atom_spec(name)
    out: dict[str, np.ndarray] = {}
    by_selector: dict[str, list[str]] = {}
    for name in names:
        if "." in name:
            sel, attr = name.split(".")
            by_selector.setdefault(sel, []).append(attr)
        else:
            out[name] = _HEADER_VALUES[name](parts)
    for sel, attrs in by_selector.items():
        values = _human_attributes(sel, parts)
        for attr in attrs:
            out[f"{sel}.{attr}"] = values[attr]
    return out
