"""Our ORCA (socialzoo.humans.orca) against the reference library RVO2, built here from its source.

    python tools/compare_rvo2.py --rvo2 PATH [--precision double] [--steps 400] [--cases 4000] [--seed 0]

PATH is a checkout of snape/RVO2 (never part of this repository). g++ compiles its sources with a small C
shim of ours into a temporary folder and ctypes drives it. RVO2 computes in float32; `--precision double`
(the default) compiles a copy with float replaced by double, which separates a difference of ours from
float32 rounding. Runs, with the same agents, parameters and preferred velocities in both:

- scenarios (head-on pairs, four crossing agents, circles of 5, 10 and 20 swapping places, two groups of
  25 crossing, a corridor, a door, a box) for `--steps` steps under two parameter sets (socialzoo's,
  CrowdNav's), printing the largest position difference over the steps;
- `--cases` random one-step cases (1-13 agents of random radii, speeds and velocities, random parameters,
  0-4 random walls), printing the largest velocity difference and the cases above 1e-8 m/s.

Walls are two-vertex obstacles. RVO2 splits an obstacle that another obstacle's line crosses when it builds
its obstacle tree; the random walls are drawn so that none does, as the scenarios' walls are.
"""

from __future__ import annotations

import argparse
import ctypes
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from socialzoo.core.config import OrcaConfig
from socialzoo.core.walls import WallIndex
from socialzoo.humans.orca import orca_velocities

_SHIM = r"""
#include "RVO.h"
#include <vector>
extern "C" {
void* sim_new(double dt, double nd, int mn, double th, double tho, double r, double ms) {
  RVO::RVOSimulator* s = new RVO::RVOSimulator();
  s->setTimeStep((REAL)dt);
  s->setAgentDefaults((REAL)nd, (std::size_t)mn, (REAL)th, (REAL)tho, (REAL)r, (REAL)ms);
  return s;
}
void sim_free(void* s) { delete (RVO::RVOSimulator*)s; }
void sim_add_agent(void* s, double x, double y, double r, double ms, double vx, double vy) {
  RVO::RVOSimulator* S = (RVO::RVOSimulator*)s;
  std::size_t i = S->addAgent(RVO::Vector2((REAL)x, (REAL)y));
  S->setAgentRadius(i, (REAL)r);
  S->setAgentMaxSpeed(i, (REAL)ms);
  S->setAgentVelocity(i, RVO::Vector2((REAL)vx, (REAL)vy));
}
void sim_add_wall(void* s, double x1, double y1, double x2, double y2) {
  std::vector<RVO::Vector2> v;
  v.push_back(RVO::Vector2((REAL)x1, (REAL)y1));
  v.push_back(RVO::Vector2((REAL)x2, (REAL)y2));
  ((RVO::RVOSimulator*)s)->addObstacle(v);
}
void sim_process(void* s) { ((RVO::RVOSimulator*)s)->processObstacles(); }
void sim_set_pref(void* s, int i, double x, double y) {
  ((RVO::RVOSimulator*)s)->setAgentPrefVelocity(i, RVO::Vector2((REAL)x, (REAL)y));
}
void sim_step(void* s) { ((RVO::RVOSimulator*)s)->doStep(); }
void sim_get(void* s, int i, double* out) {
  RVO::RVOSimulator* S = (RVO::RVOSimulator*)s;
  RVO::Vector2 p = S->getAgentPosition(i), v = S->getAgentVelocity(i);
  out[0] = p.x(); out[1] = p.y(); out[2] = v.x(); out[3] = v.y();
}
}
"""
# Parameter sets: neighbor_dist, max_neighbors, time_horizon, time_horizon_obst, radius, max_speed, dt.
_PARAMS = {
    "socialzoo": (4.0, 10, 2.0, 0.45, 0.35, 1.3, 0.1),
    "crowdnav": (10.0, 10, 5.0, 5.0, 0.3, 1.0, 0.25),
}
# Far from everything: the scenarios without walls still need a wall index.
_FAR_WALL = np.array([[1000.0, 1000.0, 1001.0, 1000.0]])


class Rvo2:
    """RVO2 compiled from `source` (a checkout of snape/RVO2) in `precision` ("float" or "double")."""

    def __init__(self, source: Path, precision: str, build: Path) -> None:
        sources = [f for f in sorted((source / "src").glob("*")) if f.suffix in (".cc", ".cpp", ".h")]
        if not sources:
            raise SystemExit(f"{source}: no src/ folder with RVO2's sources")
        folder = build / precision
        folder.mkdir()
        for path in sources:
            text = path.read_text()
            if precision == "double":
                text = re.sub(r"\bfloat\b", "double", text)
                text = re.sub(r"(\d)[fF]\b", r"\1", text)
            (folder / path.name).write_text(text)
        (folder / "shim.cc").write_text(_SHIM)
        library = folder / "librvo.so"
        compile_units = [str(f) for f in sorted(folder.glob("*")) if f.suffix in (".cc", ".cpp")]
        command = ["g++", "-O2", "-fPIC", "-shared", f"-DREAL={precision}", f"-I{folder}", *compile_units]
        subprocess.run([*command, "-o", str(library)], check=True)
        self.lib = ctypes.CDLL(str(library))
        d, p = ctypes.c_double, ctypes.c_void_p
        self.lib.sim_new.restype = p
        self.lib.sim_new.argtypes = [d, d, ctypes.c_int, d, d, d, d]
        self.lib.sim_add_agent.argtypes = [p, d, d, d, d, d, d]
        self.lib.sim_add_wall.argtypes = [p, d, d, d, d]
        self.lib.sim_set_pref.argtypes = [p, ctypes.c_int, d, d]
        self.lib.sim_get.argtypes = [p, ctypes.c_int, ctypes.POINTER(d)]
        for name in ("sim_free", "sim_process", "sim_step"):
            getattr(self.lib, name).argtypes = [p]

    def simulator(self, params, pos, vel, radius, speed, walls):  # type: ignore[no-untyped-def]
        """A new simulator with these agents and walls (params as in _PARAMS)."""
        sim = self.lib.sim_new(params[6], params[0], params[1], params[2], params[3], params[4], params[5])
        for i in range(len(pos)):
            self.lib.sim_add_agent(sim, *pos[i], radius[i], speed[i], *vel[i])
        for wall in walls:
            self.lib.sim_add_wall(sim, *wall)
        self.lib.sim_process(sim)
        return sim

    def state(self, sim, num: int) -> tuple[np.ndarray, np.ndarray]:  # type: ignore[no-untyped-def]
        """(positions, velocities) (num, 2) of the simulator's agents."""
        out = (ctypes.c_double * 4)()
        rows = np.empty((num, 4))
        for i in range(num):
            self.lib.sim_get(sim, i, out)
            rows[i] = out[:]
        return rows[:, :2], rows[:, 2:]


def _ours(params, pos, vel, pref, radius, speed, index):  # type: ignore[no-untyped-def]
    """Our new velocities (N, 2) of one row."""
    cfg = OrcaConfig(
        neighbor_dist=params[0], max_neighbors=params[1], time_horizon=params[2], time_horizon_obst=params[3]
    )
    ones = np.ones((1, len(pos)), dtype=bool)
    return orca_velocities(
        pos[None], vel[None], pref[None], radius[None], speed[None], ones, ones, ones, index, cfg, params[6]
    )[0]


def _pref(pos: np.ndarray, goal: np.ndarray, speed: np.ndarray) -> np.ndarray:
    """Towards the goal at full speed, slower within 1 m (RVO2's examples)."""
    offset = goal - pos
    dist = np.linalg.norm(offset, axis=-1, keepdims=True)
    return np.where(dist > 1.0, offset / np.maximum(dist, 1e-12), offset) * speed[:, None]


def _scenarios(rng: np.random.Generator):  # type: ignore[no-untyped-def]
    """(name, starts, goals, walls) of the multi-step scenarios."""
    yield "head-on, in line", [[-4.0, 0.0], [4.0, 0.0]], [[4.0, 0.0], [-4.0, 0.0]], []
    yield "head-on, offset", [[-4.0, 0.05], [4.0, 0.0]], [[4.0, 0.05], [-4.0, 0.0]], []
    cross = [[-4.0, 0.3], [4.0, -0.2], [0.1, -4.0], [-0.3, 4.0]]
    yield "crossing 4", cross, [[4.0, 0.3], [-4.0, -0.2], [0.1, 4.0], [-0.3, -4.0]], []
    for num in (5, 10, 20):
        angle = np.arange(num) * 2 * np.pi / num
        ring = (4.0 if num < 20 else 6.0) * np.stack([np.cos(angle), np.sin(angle)], -1)
        yield f"circle {num}", ring, -ring, []
        yield f"circle {num}, noisy", ring + rng.normal(0.0, 0.02, ring.shape), -ring, []
    # Two groups of 25 on a 0.8 m lattice crossing at right angles: a dense crowd, more agents than
    # max_neighbors, many at equal distances.
    lattice = 0.8 * np.stack(np.meshgrid(np.arange(5), np.arange(5)), -1).reshape(-1, 2) - 1.6
    west, south = lattice + [-8.0, 0.0], lattice[:, ::-1] + [0.0, -8.0]
    yield "crossing 50", np.concatenate([west, south]), np.concatenate([west + [16, 0], south + [0, 16]]), []
    corridor = [[-6.0, 1.0, 6.0, 1.0], [6.0, -1.0, -6.0, -1.0]]
    yield "corridor pair", [[-4.0, 0.1], [4.0, -0.1]], [[4.0, 0.1], [-4.0, -0.1]], corridor
    door = [[-5.0, 0.0, -0.5, 0.0], [0.5, 0.0, 5.0, 0.0]]
    starts = [[-1.0, -3.0], [1.0, -3.2], [0.8, 3.0], [-1.2, 3.1]]
    yield "door 4", starts, [[1.0, 3.0], [-1.0, 3.2], [-0.8, -3.0], [1.2, -3.1]], door
    box = [[-5.0, -5.0, 5.0, -5.0], [5.0, -5.0, 5.0, 5.0], [5.0, 5.0, -5.0, 5.0], [-5.0, 5.0, -5.0, -5.0]]
    angle = np.arange(8) * 2 * np.pi / 8
    ring = 4.0 * np.stack([np.cos(angle), np.sin(angle)], -1)
    yield "box, circle 8", ring + rng.normal(0.0, 0.02, ring.shape), -ring, box


def compare_scenarios(rvo2: Rvo2, steps: int, seed: int) -> None:
    """Print the largest position difference of every scenario under every parameter set."""
    for set_name, params in _PARAMS.items():
        for name, starts, goals, walls in _scenarios(np.random.default_rng(seed)):
            pos, goal = np.array(starts, float), np.array(goals, float)
            num = len(pos)
            radius, speed = np.full(num, params[4]), np.full(num, params[5])
            index = WallIndex(np.array(walls, float) if walls else _FAR_WALL)
            sim = rvo2.simulator(params, pos, np.zeros_like(pos), radius, speed, walls)
            ref, vel, worst = pos.copy(), np.zeros_like(pos), 0.0
            for _ in range(steps):
                for i, (x, y) in enumerate(_pref(ref, goal, speed)):
                    rvo2.lib.sim_set_pref(sim, i, x, y)
                rvo2.lib.sim_step(sim)
                ref, _ = rvo2.state(sim, num)
                vel = _ours(params, pos, vel, _pref(pos, goal, speed), radius, speed, index)
                pos = pos + params[6] * vel
                worst = max(worst, float(np.linalg.norm(pos - ref, axis=-1).max()))
            rvo2.lib.sim_free(sim)
            print(f"{set_name:10s} {name:20s} largest position difference over {steps} steps: {worst:.2e} m")


def _walls(rng: np.random.Generator, count: int) -> list[list[float]]:
    """`count` random walls, none of which another's line crosses (RVO2 would split it)."""

    def splits(a: list[float], b: list[float]) -> bool:
        side = [(a[2] - a[0]) * (y - a[1]) - (a[3] - a[1]) * (x - a[0]) for x, y in (b[:2], b[2:])]
        return min(side) < -1e-5 and max(side) > 1e-5

    for _ in range(1000):
        walls = []
        for _ in range(count):
            centre, angle, length = rng.uniform(-5, 5, 2), rng.uniform(0, np.pi), rng.uniform(0.5, 4.0)
            half = 0.5 * length * np.array([np.cos(angle), np.sin(angle)])
            walls.append([*(centre - half), *(centre + half)])
        if not any(splits(a, b) for a in walls for b in walls if a is not b):
            return walls
    return []


def compare_cases(rvo2: Rvo2, cases: int, seed: int) -> None:
    """Print the largest new-velocity difference over random one-step cases."""
    rng = np.random.default_rng(seed)
    errors, above = [], []
    for case in range(cases):
        num = int(rng.integers(1, 14))
        walls = _walls(rng, int(rng.integers(0, 5)))
        params = (
            float(rng.uniform(0.5, 10.0)), int(rng.integers(0, 12)), float(rng.uniform(0.2, 6.0)),
            float(rng.uniform(0.1, 6.0)), 0.3, 1.0, float(rng.choice([0.025, 0.1, 0.25, 0.4])),
        )  # fmt: skip
        pos = rng.uniform(-5, 5, (num, 2))
        if num > 1 and rng.random() < 0.3:
            pos[1] = pos[0] + rng.normal(0.0, 0.2, 2)  # overlapping agents
        vel, pref = rng.normal(0.0, 1.0, (num, 2)), rng.normal(0.0, 1.2, (num, 2))
        radius, speed = rng.uniform(0.1, 0.6, num), rng.uniform(0.3, 2.0, num)
        index = WallIndex(np.array(walls, float) if walls else _FAR_WALL)
        ours = _ours(params, pos, vel, pref, radius, speed, index)
        sim = rvo2.simulator(params, pos, vel, radius, speed, walls)
        for i in range(num):
            rvo2.lib.sim_set_pref(sim, i, *pref[i])
        rvo2.lib.sim_step(sim)
        _, ref = rvo2.state(sim, num)
        rvo2.lib.sim_free(sim)
        error = float(np.abs(ours - ref).max())
        errors.append(error)
        if not error <= 1e-8:
            above.append((error, case, num, len(walls)))
    largest, median = max(errors), float(np.median(errors))
    print(
        f"{cases} random one-step cases: largest velocity difference {largest:.2e} m/s, median {median:.1e}"
    )
    print(f"{len(above)} above 1e-8 m/s; the largest:")
    for error, case, num, num_walls in sorted(above, reverse=True)[:10]:
        print(f"  case {case}: {error:.2e} m/s ({num} agents, {num_walls} walls)")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--rvo2", type=Path, required=True, help="a checkout of snape/RVO2")
    p.add_argument("--precision", choices=("double", "float"), default="double", help="RVO2's number type")
    p.add_argument("--steps", type=int, default=400, help="steps of each scenario")
    p.add_argument("--cases", type=int, default=4000, help="random one-step cases")
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args()
    if shutil.which("g++") is None:
        raise SystemExit("g++ is needed to build RVO2")
    with tempfile.TemporaryDirectory() as build:
        rvo2 = Rvo2(args.rvo2, args.precision, Path(build))
        compare_scenarios(rvo2, args.steps, args.seed)
        compare_cases(rvo2, args.cases, args.seed)


if __name__ == "__main__":
    main()
