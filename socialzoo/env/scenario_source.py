"""Where an environment's episodes come from: seeded scenario streams, one per batch row."""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any

import numpy as np

from socialzoo.maps.map_file import POSE_CLEARANCE, Map
from socialzoo.maps.segments import segments_free
from socialzoo.nav.graph import graph_of
from socialzoo.scenarios.catalogue import get_family
from socialzoo.scenarios.generator import ScenarioConfig, generate_scenario
from socialzoo.scenarios.scenario import Scenario
from socialzoo.scenarios.scenario_sets import TestSet

if TYPE_CHECKING:
    from socialzoo.env.config import EnvConfig


# An extra robot starts at least START_CLEARANCE (m) from every person's spawn and every other
# robot's start: the largest robot-person collision distance of the registered tasks, 0.5 m
# (CrowdNavWalls: robot radius 0.3 + person radius 0.2; the benchmark's
# WorldConfig.human_collision_distance is 0.4), plus a margin of START_MARGIN, so no robot starts
# inside a person and one walking straight at it at 1 m/s takes half a second to reach it.
START_MARGIN = 0.5
START_CLEARANCE = 0.5 + START_MARGIN
# Where too few legal poses are clear (a small room crowded by its people: open_room's 9 poses
# leave none clear in about 30% of the benchmark's scenarios), a robot starts at a spot drawn
# within START_REACH of a legal pose (per axis), at least POSE_CLEARANCE from every wall and in
# straight sight of that pose; the first clear one of START_TRIES draws.
START_REACH = 1.5
START_TRIES = 256


class RobotPlacementError(ValueError):
    """No start for an extra robot keeps START_CLEARANCE from the people and the other robots."""


def with_robots(scenario: Scenario, m: Map, num_robots: int) -> Scenario:
    """The scenario with `num_robots` robots: extra robots start clear of the people and each other.

    Robot 0 keeps the scenario's own start and goal. Each extra robot starts on a legal pose at
    least START_CLEARANCE from every person's spawn and every robot placed before it, drawn
    uniformly among such poses; when none is left, on a spot near a legal pose (START_REACH,
    START_TRIES) as clear, in sight of that pose and of the navigation graph. Its goal is a legal
    pose other than the one it starts on or near. Every draw comes from a generator seeded by the
    scenario seed and the robot count, so the result is as reproducible as the scenario itself.

    Raises:
        RobotPlacementError: no clear start for an extra robot (names the map, the scenario seed
            and the robot count).
    """
    have = scenario.num_robots
    if num_robots <= have:
        return scenario
    poses = np.asarray(m.legal_poses, dtype=np.float64).reshape(-1, 3)
    rng = np.random.default_rng([int(scenario.seed), num_robots])
    taken = np.vstack((scenario.human_spawn.reshape(-1, 2), scenario.robot_starts[:, :2]))
    starts, anchors = [scenario.robot_starts], []
    for robot in range(have, num_robots):
        clear = np.flatnonzero(_clearance(poses[:, :2], taken) >= START_CLEARANCE)
        if len(clear):
            anchor = int(rng.choice(clear))
            start = poses[anchor]
        else:
            anchor, start = _spot_near_poses(rng, m, poses, taken, scenario, robot, num_robots)
        starts.append(start[None, :])
        anchors.append(anchor)
        taken = np.vstack((taken, start[None, :2]))
    goals = [scenario.robot_goals]
    for anchor in anchors:
        choices = [j for j in range(len(poses)) if j != anchor]
        goals.append(poses[[rng.choice(choices)]])
    script = scenario.script
    if script is not None:  # the extra robots reach their goals alone
        extra = num_robots - have
        script = dataclasses.replace(
            script,
            escort=np.concatenate((script.escort, np.full(extra, -1))),
            escort_kind=np.concatenate((script.escort_kind, np.zeros(extra, dtype=np.int64))),
            band=np.concatenate((script.band, np.zeros((extra, 2)))),
        )
    return dataclasses.replace(
        scenario, robot_starts=np.vstack(starts), robot_goals=np.vstack(goals), script=script
    )


def _clearance(points: np.ndarray, taken: np.ndarray) -> np.ndarray:
    """(n,) distance from each of `points` (n, 2) to the nearest of `taken` (k, 2), m (inf if k = 0)."""
    if len(taken) == 0:
        return np.full(len(points), np.inf)
    return np.sqrt(((points[:, None, :] - taken[None, :, :]) ** 2).sum(-1)).min(axis=1)


def _spot_near_poses(
    rng: np.random.Generator,
    m: Map,
    poses: np.ndarray,
    taken: np.ndarray,
    scenario: Scenario,
    robot: int,
    num_robots: int,
) -> tuple[int, np.ndarray]:
    """(legal-pose index, (3,) start) of a clear spot near a legal pose, with that pose's heading."""
    anchor = rng.integers(len(poses), size=START_TRIES)
    spot = poses[anchor, :2] + rng.uniform(-START_REACH, START_REACH, size=(START_TRIES, 2))
    _, wall_dist = m.wall_index.nearest(spot)
    good = (
        (_clearance(spot, taken) >= START_CLEARANCE)
        & (wall_dist >= POSE_CLEARANCE)
        & segments_free(m.wall_index, spot, poses[anchor, :2])
    )
    # A spot in sight of its legal pose but of no edge or node of the navigation graph would end the
    # reset in the navigator's AttachError: the robot has no plan from it.
    good[good] = graph_of(m).attach(spot[good], strict=False).found
    if not good.any():
        raise RobotPlacementError(
            f"{m.where}: scenario seed {scenario.seed} with {num_robots} robots: no start for robot {robot} "
            f"keeps {START_CLEARANCE:g} m from the scenario's {scenario.num_humans} people and the other robots "
            f"(no clear legal pose, none of {START_TRIES} spots near one that joins the navigation graph)"
        )
    k = int(np.argmax(good))
    return int(anchor[k]), np.array([spot[k, 0], spot[k, 1], poses[anchor[k], 2]])


def reseed_rows(rngs: list[np.random.Generator], seed: int | None, rows: Any = None) -> list[int]:
    """Reseed the per-row generators `rngs` of `rows` (default all) from `seed`: row i gets
    SeedSequence(seed).spawn(len(rngs))[i], row 0 the seed itself (so a single env seeded with s
    matches row 0 of any batch); the other rows keep theirs. Returns the rows."""
    children = np.random.SeedSequence(seed).spawn(len(rngs))
    rows = list(range(len(rngs))) if rows is None else np.asarray(rows).tolist()
    for row in rows:
        rngs[row] = np.random.default_rng(seed if row == 0 else children[row])
    return rows


class ScenarioStream:
    """Seeded scenarios for every row of a batch.

    Each row draws scenario seeds from its own numpy Generator (seeded at reset) and runs each
    scenario `repeats` times (SPEC section 5, N_r) before drawing the next, so a row's episodes are
    the same whatever the batch size.

    Args:
        m: the map.
        batch_size: B.
        num_robots: robots per scenario.
        cfg: scenario generation parameters (cfg.repeats = N_r).
        family: None for benchmark scenarios, else a registered scenario family's name
            (socialzoo.scenarios.catalogue).
    """

    def __init__(
        self, m: Map, batch_size: int, num_robots: int, cfg: ScenarioConfig, family: str | None = None
    ) -> None:
        self.map = m
        self.num_robots = num_robots
        self.cfg = cfg
        self.family = family
        # The family itself, not only its name: a copy of the stream (a pickled env in a worker
        # process) draws and looks up its scenarios without the registry of the process that
        # registered the family (register_family: a recording of one's own, docs/recorded.md).
        self.scenario_family = None if family is None else get_family(family)
        self._rngs: list[np.random.Generator] = [np.random.default_rng() for _ in range(batch_size)]
        self._current: list[Scenario | None] = [None] * batch_size
        self._uses = np.zeros(batch_size, dtype=np.intp)
        splits = {} if self.scenario_family is None else self.scenario_family.splits
        self._first_training_seed = splits["train"].first if "train" in splits else 0

    @classmethod
    def for_config(cls, m: Map, batch_size: int, config: EnvConfig) -> ScenarioStream:
        """The stream of an environment of `config` on map `m` with B = batch_size rows.

        Every adapter builds its stream here: config.num_robots robots per scenario, the
        benchmark's generation with config.scenario, or config.family's scenarios.
        """
        return cls(m, batch_size, config.num_robots, config.scenario, config.family)

    def seed(self, seed: int | None, rows: np.ndarray | None = None) -> None:
        """Reseed rows (default all): row i of a batch seeded with s uses SeedSequence(s).spawn."""
        for row in reseed_rows(self._rngs, seed, rows):
            self._current[row] = None
            self._uses[row] = 0

    def next(self, rows: np.ndarray) -> list[Scenario]:
        """The next scenario of each row in `rows` (a loop over rows being reset, not a step)."""
        out = []
        for row in np.asarray(rows, dtype=np.intp):
            current = self._current[row]
            if current is None or self._uses[row] >= self.cfg.repeats:
                seed = int(self._rngs[row].integers(0, 2**63 - 1))
                while seed < self._first_training_seed:  # never a family's validation or test case
                    seed = int(self._rngs[row].integers(0, 2**63 - 1))
                current = self.make(seed)
                self._current[row] = current
                self._uses[row] = 0
            self._uses[row] += 1
            out.append(current)
        return out

    def make(self, seed: int) -> Scenario:
        """The scenario of `seed` (benchmark generation or the configured family)."""
        if self.scenario_family is None:
            scenario = generate_scenario(self.map, seed, self.cfg)
        else:
            scenario = self.scenario_family.make(seed, self.num_robots, m=self.map)
        return with_robots(scenario, self.map, self.num_robots)

    def case_sets(self) -> dict[str, TestSet | str]:
        """The fixed case sets by split name: for a family with fixed splits of its own, each split's
        name (its "val" and "test"; "train" is the training stream's); else the map's TestSets
        (socialzoo.scenarios.scenario_sets.map_case_sets: the map's validation scenarios, never a
        test set, as "val"; its registered test sets as "test" for "<map>-test" and by their own
        names; a map without a registered test set has the generated one)."""
        from socialzoo.scenarios.scenario_sets import map_case_sets

        splits = {} if self.scenario_family is None else self.scenario_family.splits
        if splits:
            return {k: k for k, v in splits.items() if k != "train" and v.size is not None}
        return dict(map_case_sets(self.map))

    def case_sizes(self) -> dict[str, int]:
        """The number of cases of each of `case_sets`."""
        splits = {} if self.scenario_family is None else self.scenario_family.splits
        return {
            name: int(splits[cases].size or 0) if isinstance(cases, str) else len(cases)
            for name, cases in self.case_sets().items()
        }

    def cases(self, split: str, indices: Any) -> list[Scenario]:
        """Cases `indices` of split `split` of `case_sets`: a family's own split, a registered test
        set's seeds as the family's scenarios, or without a family the test set's own scenarios."""
        case_set = self.case_sets()[split]
        if self.scenario_family is None:
            assert isinstance(case_set, TestSet)
            return [
                with_robots(case_set.scenario(int(k), self.map), self.map, self.num_robots) for k in indices
            ]
        if isinstance(case_set, str):
            family = self.scenario_family
            return [self.make(family.case_seed(case_set, int(k))) for k in indices]
        return [self.make(case_set.seed(int(k))) for k in indices]
