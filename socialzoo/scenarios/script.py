"""A scenario's script: what its people do besides walking their routes, the goal kind of its robots, and doors that
open and close on a schedule (the guidelines' scenarios, socialzoo.scenarios.suite); run by socialzoo.env.script."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

NO_GESTURE, WAIT, PROCEED = 0, 1, 2
GESTURES = {"none": NO_GESTURE, "wait": WAIT, "proceed": PROCEED}
REACH, FOLLOW, LEAD, ACCOMPANY = 0, 1, 2, 3
ESCORT_KINDS = {"reach": REACH, "follow": FOLLOW, "lead": LEAD, "accompany": ACCOMPANY}

_PERSON = ("stop", "release", "wait", "gate", "gesture", "follow", "gap", "stay")

# How a waiting (or following) person comes to a stop, m (see Script's docstring).
SLOW_DISTANCE = 1.0
STOP_RADIUS = 0.15
ARRIVE_RADIUS = 0.5
# An escort (Script's docstring): the longest the person may be out of its place at a stretch, s, and
# the least share of the escort's time it must be in its place.
ESCORT_GRACE = 2.0
ESCORT_SHARE = 0.8
_ROBOT = ("escort", "escort_kind", "band")
_FIELDS = (*_PERSON, *_ROBOT, "doors")


def _array(value: Any, dtype: type, shape: tuple[int, ...], what: str) -> np.ndarray:
    arr: np.ndarray = np.array(value, dtype=dtype)
    if arr.size == 0 and len(shape) > 1:
        arr = arr.reshape((0, *shape[1:]))
    if arr.shape != shape:
        raise ValueError(f"Script.{what} must have shape {shape}, got {arr.shape}")
    arr.flags.writeable = False
    return arr


@dataclass(frozen=True, kw_only=True, eq=False)
class Script:
    """A scenario's script (below); every array is read-only.

    Per person:
    - stop, release, wait, gate: the person walks its route to route point `stop` and waits there until
      released: at world time `release` (s), `wait` seconds after it came to stand there, or once any
      robot is past the gate line, whichever comes first (a person released before it reaches its stop
      does not wait). It slows down within SLOW_DISTANCE of its stop point (its preferred speed scaled
      by the distance left) and stands within STOP_RADIUS of it; it has reached its stop within
      ARRIVE_RADIUS.
    - stay: the person stays at the end of its route once there (instead of walking it back), as it
      stands at a stop (after a stop too: someone who waits in a lobby, then enters a car and stays).
    - gesture: what the person signals from reaching its stop until, released, it is 3 m past it
      (0 none, 1 WAIT: the robot should wait, 2 PROCEED: the robot may go first); the robot observes it.
    - follow, gap: the person walks after robot `follow` (its route is the robot's position) and stops
      within `gap` of it: a person the robot leads, or a crowd pressing on the robot.

    Per robot:
    - escort, escort_kind, band: the person the robot follows, leads or accompanies, all the way. The
      person is in its place while it is within the distance band of the robot and, in the frame of
      the robot's way (the line from its start to its goal, the suite's escorts being straight walks),
      ahead of it when the robot follows (within 45 degrees of straight ahead), behind it when the
      robot leads (within 45 degrees of straight behind), beside it when the robot accompanies (within
      45 degrees of abreast, either side). The robot's goal counts as reached only while the person is
      in its place (they arrive together), and only if, from the episode's start, the person was never
      out of its place for more than ESCORT_GRACE seconds at a stretch and was in it for at least
      ESCORT_SHARE of the time: a robot that overtakes the person it follows, leaves behind the
      person it leads or accompanies, or waits while that person walks on, has lost its escort and
      cannot succeed (its episode runs to the time limit).

    Doors: (D, 6) x1, y1, x2, y2, t_open, t_close: a door segment, open from t_open to t_close (s) and
    closed before and after; a robot touching a closed door collides with it as with a wall.

    Attributes:
        stop: (n,) int route point where each person waits, -1 none.
        release: (n,) world time at which a waiting person walks on, s; inf: not by time.
        wait: (n,) how long a person stands at its stop before walking on, s; inf: not by its own clock.
        gate: (n, 4) x, y, nx, ny: the person walks on once a robot is past this line
            (dot(robot - (x, y), (nx, ny)) > 0); NaN: no gate.
        gesture: (n,) int signal while waiting (NO_GESTURE, WAIT, PROCEED).
        follow: (n,) int robot the person walks after, -1 none.
        gap: (n,) distance a following person keeps to its robot, m.
        stay: (n,) bool, the person stays at its route's end once there.
        escort: (R,) int person each robot escorts, -1 none.
        escort_kind: (R,) int REACH (no escort), FOLLOW, LEAD or ACCOMPANY.
        band: (R, 2) the escorted person's distance band (min, max), m.
        doors: (D, 6) door segments and their open interval, m and s.
    """

    stop: np.ndarray
    release: np.ndarray
    wait: np.ndarray
    gate: np.ndarray
    gesture: np.ndarray
    follow: np.ndarray
    gap: np.ndarray
    stay: np.ndarray
    escort: np.ndarray
    escort_kind: np.ndarray
    band: np.ndarray
    doors: np.ndarray

    def __post_init__(self) -> None:
        n, r = len(np.atleast_1d(self.stop)), len(np.atleast_1d(self.escort))
        for name, dtype, shape in (
            ("stop", np.int64, (n,)),
            ("release", np.float64, (n,)),
            ("wait", np.float64, (n,)),
            ("gate", np.float64, (n, 4)),
            ("gesture", np.int64, (n,)),
            ("follow", np.int64, (n,)),
            ("gap", np.float64, (n,)),
            ("stay", np.bool_, (n,)),
            ("escort", np.int64, (r,)),
            ("escort_kind", np.int64, (r,)),
            ("band", np.float64, (r, 2)),
            ("doors", np.float64, (len(np.reshape(self.doors, (-1, 6))), 6)),
        ):
            object.__setattr__(self, name, _array(getattr(self, name), dtype, shape, name))
        if np.any(np.isnan(self.release)) or np.any(np.isnan(self.gap)) or np.any(self.gap < 0):
            raise ValueError("Script.release must not be NaN and Script.gap must be >= 0")
        if np.any(np.isnan(self.wait)) or np.any(self.wait < 0):
            raise ValueError("Script.wait must be >= 0 (inf: no waiting time of its own)")
        if not np.all(np.isin(self.gesture, list(GESTURES.values()))):
            raise ValueError(
                f"Script.gesture must hold {sorted(GESTURES.values())}, got {self.gesture.tolist()}"
            )
        if (
            np.any(self.stop < -1)
            or np.any(self.follow < -1)
            or np.any((self.escort < -1) | (self.escort >= n))
        ):
            raise ValueError("Script.stop, follow and escort must be -1 or an index (escort: of a person)")
        if np.any(self.follow >= r):
            raise ValueError(f"Script.follow names robot {int(self.follow.max())}, the script has {r} robots")
        if not np.all(np.isin(self.escort_kind, list(ESCORT_KINDS.values()))):
            raise ValueError(f"Script.escort_kind must hold {sorted(ESCORT_KINDS.values())}")
        if np.any((self.escort >= 0) != (self.escort_kind != REACH)):
            raise ValueError("Script: a robot escorts a person exactly when its escort_kind is not REACH")
        if np.any(~np.isfinite(self.band)) or np.any(self.band[:, 0] > self.band[:, 1]):
            raise ValueError("Script.band must be finite (min, max) pairs with min <= max")
        if np.any(~np.isfinite(self.doors[:, :4])) or np.any(np.isnan(self.doors[:, 4:])):
            raise ValueError("Script.doors must have finite segments and times that are not NaN")

    @classmethod
    def plain(cls, num_humans: int, num_robots: int = 1, **fields: Any) -> Script:
        """A script in which nobody waits, follows or escorts and there are no doors, with `fields`
        (arrays of the full shapes) replacing those defaults."""
        n, r = num_humans, num_robots
        base: dict[str, Any] = {
            "stop": np.full(n, -1),
            "release": np.full(n, np.inf),
            "wait": np.full(n, np.inf),
            "gate": np.full((n, 4), np.nan),
            "gesture": np.zeros(n, dtype=np.int64),
            "follow": np.full(n, -1),
            "gap": np.zeros(n),
            "stay": np.zeros(n, dtype=bool),
            "escort": np.full(r, -1),
            "escort_kind": np.zeros(r, dtype=np.int64),
            "band": np.zeros((r, 2)),
            "doors": np.zeros((0, 6)),
        }
        unknown = set(fields) - set(base)
        if unknown:
            raise ValueError(f"Script.plain: unknown fields {sorted(unknown)}")
        return cls(**{**base, **fields})

    @property
    def num_humans(self) -> int:
        """n, the people the script is for."""
        return len(self.stop)

    @property
    def num_robots(self) -> int:
        """R, the robots the script is for."""
        return len(self.escort)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Script):
            return NotImplemented
        return all(np.array_equal(getattr(self, k), getattr(other, k), equal_nan=True) for k in _FIELDS)

    __hash__ = None  # type: ignore[assignment]

    def to_json(self) -> dict[str, Any]:
        """JSON-ready lists; JSON has no inf or NaN, so they are the strings "inf" and "nan"."""
        arrays = {k: getattr(self, k) for k in _FIELDS}
        return {k: a.tolist() if a.dtype.kind in "ib" else _floats(a) for k, a in arrays.items()}

    @classmethod
    def from_json(cls, data: Any) -> Script:
        """Inverse of `to_json`.

        Raises:
            ValueError: not an object, a missing or unknown key, or a value of the wrong shape.
        """
        if not isinstance(data, dict) or set(data) != set(_FIELDS):
            got = sorted(data) if isinstance(data, dict) else type(data).__name__
            raise ValueError(f"script must be an object with keys {sorted(_FIELDS)}, got {got}")
        return cls(**{k: _unfloats(data[k]) for k in _FIELDS})


def _floats(a: np.ndarray) -> Any:
    """Nested lists with inf, -inf and NaN as the strings "inf", "-inf", "nan"."""
    if a.ndim == 0:
        x = float(a)
        return x if np.isfinite(x) else str(x)
    return [_floats(x) for x in a]


def _unfloats(value: Any) -> Any:
    if isinstance(value, list):
        return [_unfloats(x) for x in value]
    if isinstance(value, str) and value in ("inf", "-inf", "nan"):
        return float(value)
    return value
