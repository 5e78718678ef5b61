"""Where the CrowdNav task's episodes come from: a seeded training stream per batch row, or the fixed validation and
test cases (docs/crowdnav.md)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from socialzoo.core.state import WorldState
from socialzoo.env.crowd_config import CrowdNavConfig
from socialzoo.env.scenario_source import ScenarioStream, reseed_rows
from socialzoo.scenarios.catalogue import get_family
from socialzoo.scenarios.crowd_cases import SPLIT_SIZE, CrowdCase, Split, crowd_family
from socialzoo.scenarios.scenario import Scenario

# CrowdNav seeds numpy's legacy generator, whose seeds are below 2**32.
_SEED_LIMIT = 2**32


class CrowdCaseSource:
    """Cases for the rows of a batch.

    Arena cases come from the task's CrowdNav scenario family (socialzoo.scenarios.crowd_cases.crowd_family:
    crowdnav_circle_crossing or crowdnav_square_crossing, for the task's CrowdCaseConfig), training cases
    from its training split (case seeds from 2000 up): row i of a batch reset with seed s draws its case
    seeds from its own Generator (row 0 from s itself, so a single env seeded with s plays row 0's
    episodes), never a validation or test case. On a building map the cases are the benchmark's
    scenarios of that map, drawn by the benchmark's training stream (socialzoo.env.scenario_source);
    with a scenario family (CrowdNavConfig.family) that family's scenarios, drawn by the same stream
    (which skips the family's validation and test seeds), and its fixed cases from the family's own
    splits. A family in the open (a recorded scene) draws its training seeds like the arena's cases,
    from its training split's first seed up.

    Args:
        config: the task (its case settings and map).
        batch_size: B.
    """

    def __init__(self, config: CrowdNavConfig, batch_size: int) -> None:
        self.config = config
        self.batch_size = batch_size
        self.family = crowd_family(config.cases)
        self._rngs = [np.random.default_rng() for _ in range(batch_size)]
        # One case generator reseeded per case (CrowdNav's seeding; a fresh one costs ~0.6 ms).
        self._case_rs = np.random.RandomState()
        self._scenarios = None
        # A family in the open (a recorded scene's): its scenarios, no map.
        self.open_family = (
            get_family(config.family) if config.family is not None and config.map is None else None
        )
        if config.map is not None:
            from socialzoo.maps.map_file import load_map
            from socialzoo.scenarios.generator import ScenarioConfig

            scenario = ScenarioConfig(max_humans=config.slots, min_humans=min(5, config.slots))
            self._scenarios = ScenarioStream(
                load_map(config.map), batch_size, config.num_robots, scenario, config.family
            )

    def seed(self, seed: int | None, rows: np.ndarray | None = None) -> None:
        """Reseed the training streams of `rows` (default all; row 0 with the seed itself); the
        other rows keep theirs."""
        reseed_rows(self._rngs, seed, rows)
        if self._scenarios is not None:
            self._scenarios.seed(seed, rows)

    def next(self, rows: np.ndarray) -> list[Scenario] | list[CrowdCase]:
        """The next training case of each row in `rows` (arena cases as CrowdCase arrays)."""
        rows = np.asarray(rows, dtype=np.intp)
        if self._scenarios is not None:
            return self._scenarios.next(rows)
        low = (self.open_family or self.family).splits["train"].first
        seeds = [int(self._rngs[row].integers(low, _SEED_LIMIT)) for row in rows]
        r = self.config.num_robots
        if self.open_family is not None:
            return [self.open_family.make(seed, r) for seed in seeds]
        # The family's fast path: plain arrays, which the core's reset reads without a Scenario.
        return [self.family.arrays(seed, r, self._case_rs) for seed in seeds]

    def fixed(self, split: Split, indices: list[int] | np.ndarray) -> list[Scenario]:
        """Cases `indices` of the validation or test split (CrowdNav's fixed cases; on a building
        map, the map's registered test set or validation scenarios; with a scenario family, the
        family's scenarios of its split's seeds, or of the map's sets' seeds for a family without
        splits of its own)."""
        r = self.config.num_robots
        if self.config.map is None:
            family = self.open_family or self.family
            return [family.make(family.case_seed(split, int(k)), r) for k in indices]
        assert self._scenarios is not None
        return self._scenarios.cases(split, indices)

    def case_splits(self) -> dict[str, int]:
        """The fixed case sets and their sizes: CrowdNav's (100 and 500) in the arena, a family in
        the open's own splits, else those of the scenario stream
        (socialzoo.env.scenario_source.ScenarioStream.case_sets)."""
        if self.open_family is not None:
            splits = self.open_family.splits
            return {k: int(splits[k].size or 0) for k in ("val", "test") if k in splits}
        if self._scenarios is None:
            return dict(SPLIT_SIZE)
        return self._scenarios.case_sizes()


def write_cases(
    s: WorldState, rows: np.ndarray, cases: Sequence[CrowdCase], human_speed: float, models: np.ndarray
) -> None:
    """Write arena cases into rows of the state: robots on their starts, people on theirs with a
    one-point route to their goals at `human_speed`, everyone still, each person driven by its
    model (len(rows), H), as scenarios_to_state writes their Scenarios (the noise key is the case's
    seed: the task has no laser to draw noise for)."""
    n = cases[0].human_starts.shape[0]
    s.robot_pose[rows] = np.stack([c.robot_starts for c in cases])
    s.robot_goal[rows] = np.stack([c.robot_goals for c in cases])
    s.robot_vel[rows] = 0.0
    s.human_pos[rows] = 0.0
    s.human_pos[rows, :n] = np.stack([c.human_starts for c in cases])
    s.human_vel[rows] = 0.0
    s.human_route[rows] = 0.0
    s.human_route[rows, :n] = np.stack([c.human_goals for c in cases])[:, :, None, :]
    s.human_mask[rows] = False
    s.human_mask[rows, :n] = True
    s.human_pref_speed[rows] = 0.0
    s.human_pref_speed[rows, :n] = human_speed
    s.human_route_len[rows] = 1
    s.human_waypoint[rows] = 0
    s.human_direction[rows] = 1
    s.step_count[rows] = 0
    s.noise_key[rows] = [c.seed for c in cases]
    s.human_model[rows] = models
    s.human_group[rows] = -1
