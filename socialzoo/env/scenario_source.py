"""Where an environment's episodes come from: seeded scenario streams, one per batch row.

Each row draws scenario seeds from its own numpy Generator (seeded at reset) and runs each scenario
`repeats` times (SPEC section 5, N_r) before drawing the next, so a row's episodes are the same
whatever the batch size.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from socialzoo.nav.maps import Map
from socialzoo.nav.scenario_families import make_family_scenario
from socialzoo.nav.scenarios import Scenario, ScenarioConfig, generate_scenario

if TYPE_CHECKING:
    from socialzoo.env.config import EnvConfig


def with_robots(scenario: Scenario, m: Map, num_robots: int) -> Scenario:
    """The scenario with `num_robots` robots: extra robots get distinct legal start and goal poses.

    Robot 0 keeps the scenario's own start and goal. Extra robots are drawn from a generator
    seeded by the scenario seed, so the result is as reproducible as the scenario itself.

    Raises:
        ValueError: the map has too few legal poses for distinct robot starts.
    """
    have = scenario.num_robots
    if num_robots <= have:
        return scenario
    poses = m.legal_poses
    if len(poses) < num_robots + 1:
        raise ValueError(
            f"{m.where}: {num_robots} robots need at least {num_robots + 1} legal poses, the map has {len(poses)}"
        )
    rng = np.random.default_rng([int(scenario.seed), num_robots])
    used = {tuple(np.round(p[:2], 6)) for p in scenario.robot_starts}
    free = [i for i, p in enumerate(poses) if tuple(np.round(p[:2], 6)) not in used]
    extra = rng.choice(free, size=num_robots - have, replace=False)
    starts = np.vstack((scenario.robot_starts, poses[extra]))
    goals = [scenario.robot_goals]
    for i in extra:
        choices = [j for j in range(len(poses)) if j != i]
        goals.append(poses[[rng.choice(choices)]])
    return dataclasses.replace(scenario, robot_starts=starts, robot_goals=np.vstack(goals))


class ScenarioStream:
    """Seeded scenarios for every row of a batch.

    Args:
        m: the map.
        batch_size: B.
        num_robots: robots per scenario.
        cfg: scenario generation parameters (cfg.repeats = N_r).
        family: None for benchmark scenarios, else a scenario family name.
    """

    def __init__(
        self, m: Map, batch_size: int, num_robots: int, cfg: ScenarioConfig, family: str | None = None
    ) -> None:
        self.map = m
        self.num_robots = num_robots
        self.cfg = cfg
        self.family = family
        self._rngs: list[np.random.Generator] = [np.random.default_rng() for _ in range(batch_size)]
        self._current: list[Scenario | None] = [None] * batch_size
        self._uses = np.zeros(batch_size, dtype=np.intp)

    @classmethod
    def for_config(cls, m: Map, batch_size: int, config: EnvConfig) -> ScenarioStream:
        """The stream of an environment of `config` on map `m` with B = batch_size rows.

        Every adapter builds its stream here: config.num_robots robots per scenario, the
        benchmark's generation with config.scenario, or config.family's scenarios.
        """
        return cls(m, batch_size, config.num_robots, config.scenario, config.family)

    def seed(self, seed: int | None, rows: np.ndarray | None = None) -> None:
        """Reseed rows (default all): row i of a batch seeded with s uses SeedSequence(s).spawn."""
        rows = np.arange(len(self._rngs)) if rows is None else np.asarray(rows)
        children = np.random.SeedSequence(seed).spawn(len(self._rngs))
        for row in rows:
            # Row 0 of any batch uses the seed itself, so a single env seeded with s matches it.
            self._rngs[row] = np.random.default_rng(seed if row == 0 else children[row])
            self._current[row] = None
            self._uses[row] = 0

    def next(self, rows: np.ndarray) -> list[Scenario]:
        """The next scenario of each row in `rows` (a loop over rows being reset, not a step)."""
        out = []
        for row in np.asarray(rows, dtype=np.intp):
            current = self._current[row]
            if current is None or self._uses[row] >= self.cfg.repeats:
                seed = int(self._rngs[row].integers(0, 2**63 - 1))
                current = self.make(seed)
                self._current[row] = current
                self._uses[row] = 0
            self._uses[row] += 1
            out.append(current)
        return out

    def make(self, seed: int) -> Scenario:
        """The scenario of `seed` (benchmark generation or the configured family)."""
        if self.family is None:
            scenario = generate_scenario(self.map, seed, self.cfg)
        else:
            scenario = make_family_scenario(self.family, self.map, seed)
        return with_robots(scenario, self.map, self.num_robots)
