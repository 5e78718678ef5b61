"""The core's side of its people (a PeopleConfig): which model drives each person of a scenario, the learned people
the env drives itself, the counterfactual rows without the robot, and the metrics of what the robot costs people."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from socialzoo.core.config import WorldConfig
from socialzoo.core.metrics import names as metric_names
from socialzoo.core.metrics import registered
from socialzoo.core.state import WorldState, pad_to
from socialzoo.core.walls import WallIndex
from socialzoo.env.human_agents import action_velocities, human_observations
from socialzoo.env.world import step_world
from socialzoo.humans.group_formation import with_groups
from socialzoo.humans.models import LEARNED, MODEL_IDS, PeopleConfig, assign_models
from socialzoo.humans.presets import with_presets
from socialzoo.maps.map_file import Map
from socialzoo.scenarios.scenario import Scenario

if TYPE_CHECKING:
    from socialzoo.env.human_policy import LearnedHumanPolicy

# Summary keys this module adds to a robot's episode metrics (only those its config asks for):
# the registry's people metrics (socialzoo.core.metrics), the group intrusions and the costs.
PEOPLE_KEYS = metric_names("people")
GROUP_KEYS = registered("group_intrusions")
COST_KEYS = tuple(key for key in PEOPLE_KEYS if key not in GROUP_KEYS)
# Why counterfactual rows refuse recorded people (the end of the message naming where they are): the twin
# steps the world without the robot, not the recording.
COUNTERFACTUAL_RECORDED = (
    "recorded people, who have no twin without the robot (it would not replay the recording, nor let anyone "
    "enter): the recording is that world; a recorded scene's measures compare with it (people_reacting, "
    "reacting_time_lost, reacting_extra_distance: docs/recorded.md)"
)
# Two members farther apart than this are not walking together: passing between them is no intrusion.
GROUP_SPAN = 3.0


class People:
    """The people of a batched core (socialzoo.env.core.BatchedCore) of B rows and R robots per row.

    - Models: each scenario's people are assigned to the models of the people spec from the
      scenario's seed (socialzoo.humans.models.assign_models); people of the "groups" model walk in
      groups (socialzoo.humans.group_formation.with_groups); the world reads WorldState.human_model and
      human_group.
    - Learned people: the policy file of a "learned:PATH" model acts on each learned person's
      observation (socialzoo.env.human_agents) every step; its desired velocity drives that person
      through the social force, as for the learned humans of the multi-agent envs.
    - Counterfactual rows (PeopleConfig.counterfactual): every row has a twin that starts from the
      same scenario without the robot (same people, same seed) and steps beside it through the same
      world step, people only. Per person, with T the robot's episode time, A the time the person
      reaches the goal end of its route (turns back there) or, if it has not by T, T + the route left
      / its preferred speed, and D the distance it walked until then (plus the route left):
      time lost = A(with robot) - A(without), extra distance = D(with) - D(without).
    - Group intrusion: the robot's centre crosses the line between two members of a walking group
      (within 3 m of each other) between their positions, counted per episode.

    Everything is per row and in a fixed order, so a row's metrics do not depend on its batch; with
    the default config (social force only, no counterfactual) nothing here runs.

    Args:
        config: the people's models, walking groups and counterfactual rows.
        world: the world's parameters; `self.world` is the world its people walk in, with the spec's
            fitted presets (socialzoo.humans.presets) and a learned policy file's dynamics in place.
        batch_size: B.
        num_robots: R.
        max_humans: H.
        walls: the map's wall index (learned people observe its walls; counterfactual rows walk among them).
        m: the map (None without one: no walking groups then).
        robot_visible: whether the people see the robots (learned people observe them only then).

    Raises:
        PolicyFileError: the learned model's file is not a learned human policy file.
    """

    def __init__(
        self,
        config: PeopleConfig,
        world: WorldConfig,
        batch_size: int,
        num_robots: int,
        max_humans: int,
        walls: WallIndex,
        m: Map | None = None,
        robot_visible: bool = True,
    ) -> None:
        self.config = config
        self.robot_visible = robot_visible
        # A fitted preset of the spec replaces its model's parameters (socialzoo.humans.presets).
        self.world = world = with_presets(world, config.presets)
        self.walls = walls
        self.map = m
        self.batch_size = batch_size
        self.num_robots = num_robots
        self.max_humans = max_humans
        self.parts = self.config.parts
        self.ids = np.array([MODEL_IDS[p.model] for p in self.parts], dtype=np.int8)
        # Each kind's model and, last (kind -1, an empty slot), social force.
        self._slot_ids = np.append(self.ids, np.int8(MODEL_IDS["sf"]))
        self.policy: LearnedHumanPolicy | None = None
        path = self.config.learned_path
        if path is not None:
            from socialzoo.env.human_policy import LearnedHumanPolicy

            self.policy = LearnedHumanPolicy.load(path)
            # Its people walk as in the world it was trained in.
            dynamics: dict[str, Any] = {"learned_forces": self.policy.learned_forces}
            if self.policy.relaxation_time is not None:
                dynamics["learned_relaxation_time"] = self.policy.relaxation_time
            if any(getattr(world.human, name) != value for name, value in dynamics.items()):
                human = dataclasses.replace(world.human, **dynamics)
                self.world = world = dataclasses.replace(world, human=human)
        self.groups = self.config.has_groups
        self.counterfactual = self.config.counterfactual
        b, h, br = batch_size, self.max_humans, batch_size * self.num_robots
        self.ghost: WorldState | None = None
        self.intrusions = np.zeros(br, dtype=np.int64)
        # Per row: time of the episode so far, and whether it ended (the metrics freeze then).
        self.elapsed = np.zeros(b)
        self.frozen = np.zeros(b, dtype=bool)
        # Per run (0 with the robot, 1 without) and person: walked distance, arrival time, route left.
        self.walked = np.zeros((2, b, h))
        self.arrived = np.full((2, b, h), np.nan)
        self.left = np.zeros((2, b, h))
        self.suffix = np.zeros((b, h, 1))
        self.counted = np.zeros((b, h), dtype=bool)
        # The latest states with and without the robot, and the rows whose `left` they outdate.
        self.latest: tuple[WorldState, WorldState] | None = None
        self.stale = np.zeros(b, dtype=bool)

    @property
    def keys(self) -> tuple[str, ...]:
        """The summary keys this config adds."""
        return (GROUP_KEYS if self.groups else ()) + (COST_KEYS if self.counterfactual else ())

    # ------------------------------------------------------------------ reset
    def kinds(self, seeds: Sequence[int], counts: Sequence[int]) -> np.ndarray:
        """(len(seeds), H) each person slot's index into the spec's parts for rows with these seeds
        and head counts (socialzoo.humans.models.assign_models); -1 in empty slots."""
        if len(seeds) != len(counts):
            raise ValueError(f"People.kinds: {len(seeds)} seeds but {len(counts)} head counts")
        if len(self.parts) == 1:  # one model needs no draw (assign_models): slot i < n is part 0
            present = np.arange(self.max_humans) < np.asarray(counts, dtype=np.int64).reshape(-1, 1)
            return np.where(present, 0, -1)
        kinds = np.full((len(seeds), self.max_humans), -1, dtype=np.int64)
        for row, (seed, n) in enumerate(zip(seeds, counts, strict=True)):
            kinds[row, :n] = assign_models(self.parts, n, seed)
        return kinds

    def models(self, seeds: Sequence[int], counts: Sequence[int]) -> np.ndarray:
        """(len(seeds), H) int8 model of every person slot of rows with these seeds and head counts
        (socialzoo.humans.models.assign_models); social force in empty slots."""
        if len(self.parts) == 1 and self.parts[0].model == "sf":  # every slot social force: no draw
            return np.zeros((len(seeds), self.max_humans), dtype=np.int8)
        return self.models_of(self.kinds(seeds, counts))

    def models_of(self, kinds: np.ndarray) -> np.ndarray:
        """(n, H) int8 model of every person slot of `kinds` (n, H) (`kinds`); social force in empty slots."""
        return self._slot_ids[kinds]

    def prepare(self, scenarios: list[Scenario]) -> tuple[list[Scenario], np.ndarray]:
        """The scenarios as the config's people walk them, and (len, H) each slot's index into the
        spec's parts (`kinds`, drawn once per reset: `models_of` gives their models)."""
        recorded = next((s for s in scenarios if s.recorded is not None), None)
        if self.counterfactual and recorded is not None:
            raise ValueError(
                f"PeopleConfig.counterfactual: scenario {recorded.family} seed {recorded.seed} "
                f"has {COUNTERFACTUAL_RECORDED}"
            )
        kinds = self.kinds([s.seed for s in scenarios], [s.num_humans for s in scenarios])
        if not self.groups:
            return scenarios, kinds
        grouped = np.array([p.model == "groups" for p in self.parts])
        out = []
        for row, scenario in enumerate(scenarios):
            members = grouped[kinds[row, : scenario.num_humans]]
            if scenario.recorded is not None:
                # Recorded people walk with their recorded companions, each from its entry along its own
                # route (with_groups would group strangers and give them their leader's route).
                group = scenario.recorded.companion_groups(members)
                out.append(dataclasses.replace(scenario, human_group=group))
                continue
            assert self.map is not None, "walking groups form on a map"
            out.append(with_groups(scenario, self.map, members, self.config.group_sizes))
        return out, kinds

    def reset(self, rows: np.ndarray, state: WorldState) -> None:
        """Start the episodes of `rows`, whose rows of `state` were just written."""
        if not (self.groups or self.counterfactual):
            return
        fresh = state.rows(rows)
        self.intrusions[(rows[:, None] * self.num_robots + np.arange(self.num_robots)).reshape(-1)] = 0
        if not self.counterfactual:
            return
        alone = without_robots(fresh)
        if self.ghost is None:
            self.ghost = WorldState.concatenate([alone.rows(0)] * self.batch_size)
        self.ghost.set_rows(rows, alone)
        route = self.ghost.human_route
        seg = np.sqrt(((np.diff(route[rows], axis=2)) ** 2).sum(-1))  # padded repeats add 0
        suffix = np.concatenate(
            (np.cumsum(seg[..., ::-1], axis=-1)[..., ::-1], np.zeros(seg.shape[:2] + (1,))), -1
        )
        if suffix.shape[2] != self.suffix.shape[2]:
            self.suffix = pad_to(self.suffix, (self.max_humans, suffix.shape[2]), "suffix")
        self.suffix[rows] = suffix
        self.elapsed[rows] = 0.0
        self.frozen[rows] = False
        self.walked[:, rows] = 0.0
        self.arrived[:, rows] = np.nan
        self.counted[rows] = fresh.human_mask & (fresh.human_route_len > 1)
        self.left[0, rows] = self._route_left(fresh, np.arange(len(rows)), self.suffix[rows])
        self.left[1, rows] = self.left[0, rows]
        self.stale[rows] = False

    # ------------------------------------------------------------------ step
    def drive(
        self, state: WorldState, desired: np.ndarray | None, learned: np.ndarray | None
    ) -> tuple[np.ndarray | None, np.ndarray | None]:
        """Add the learned people's desired velocities to those of the env's learners (slots the
        env's learners drive, EnvConfig.num_learned_humans, stay theirs)."""
        if self.policy is None:
            return desired, learned
        mine = state.human_mask & (state.human_model == LEARNED)
        if not mine.any():
            return desired, learned
        policy = self.policy
        slots = np.arange(state.max_humans)
        # People who do not see the robots do not observe them either.
        seen = state if self.robot_visible else without_robots(state)
        obs = human_observations(seen, self.walls, slots, policy.num_neighbours)
        action = np.zeros(state.human_pos.shape)
        action[mine] = policy.act(obs[mine])
        velocity = action_velocities(state, slots, action, policy.action_frame, policy.action_scale)
        if desired is None or learned is None:
            desired = np.zeros(state.human_pos.shape)
            learned = np.zeros(state.human_mask.shape, dtype=bool)
        free = mine & ~learned
        return np.where(free[..., None], velocity, desired), learned | free

    def step(self, before: WorldState, after: WorldState, was_done: np.ndarray, done: np.ndarray) -> None:
        """Account for one step: the robots' group intrusions, the counterfactual rows' step and
        the people's progress with and without the robot.

        Args:
            before: the world before the step.
            after: the world after it.
            was_done: (B, R) robots whose episode had ended before the step.
            done: (B, R) robots whose episode has ended after it.
        """
        if self.groups:
            self.intrusions += _group_crossings(before, after).reshape(-1) * ~was_done.reshape(-1)
        if not self.counterfactual:
            return
        assert self.ghost is not None
        ghost_before = self.ghost
        desired, learned = self.drive(ghost_before, None, None)
        b = self.batch_size
        ghost_after, _ = step_world(
            ghost_before, self.walls, self.world, np.zeros((b, 0, 2)), np.zeros((b, 0), bool),
            desired, learned,
        )  # fmt: skip
        self.ghost = ghost_after
        self.latest = (after, ghost_after)
        live = ~self.frozen
        if not live.any():
            return
        # Slices keep the common case (every row live) free of fancy-index copies.
        rows: slice | np.ndarray = slice(None) if live.all() else np.flatnonzero(live)
        self.elapsed[rows] += self.world.dt
        counted = self.counted[rows]
        for run, (old, new) in enumerate(((before, after), (ghost_before, ghost_after))):
            arrived = self.arrived[run, rows]
            going = np.isnan(arrived)
            step = new.human_pos[rows] - old.human_pos[rows]
            moved = np.sqrt(step[..., 0] ** 2 + step[..., 1] ** 2)
            self.walked[run, rows] += np.where(going & counted, moved, 0.0)
            turned = going & (old.human_direction[rows] > 0) & (new.human_direction[rows] < 0)
            if turned.any():
                self.arrived[run, rows] = np.where(turned, self.elapsed[rows, None], arrived)
        self.stale[rows] = True
        ending = np.flatnonzero(done.all(axis=1) & live)
        if len(ending):
            # The route left is read at the episode's end; the rows step on after it.
            for run, state in enumerate((after, ghost_after)):
                self.left[run, ending] = self._route_left(state, ending, self.suffix[ending])
            self.stale[ending] = False
            self.frozen[ending] = True

    def _route_left(self, state: WorldState, rows: np.ndarray, suffix: np.ndarray) -> np.ndarray:
        """(len(rows), H) route length left to the goal end, less the waypoint radius, m (0 after
        the person turned back there); suffix: (len(rows), H, L) route length from each waypoint on."""
        waypoint = state.human_waypoint[rows]
        target = state.human_target[rows]
        along = np.take_along_axis(suffix, np.minimum(waypoint, suffix.shape[2] - 1)[..., None], axis=2)[
            ..., 0
        ]
        left = np.sqrt(((target - state.human_pos[rows]) ** 2).sum(-1)) + along
        left = np.maximum(left - self.world.human.waypoint_radius, 0.0)
        return np.where(state.human_direction[rows] > 0, left, 0.0)

    # ------------------------------------------------------------------ results
    def summaries(self, rows: np.ndarray, robot: int = 0) -> list[dict[str, Any]]:
        """The people's metrics of `rows` for robot `robot` (keys `keys`)."""
        out: list[dict[str, Any]] = []
        for row in np.asarray(rows, dtype=np.intp).tolist():
            entry: dict[str, Any] = {}
            if self.groups:
                entry["group_intrusions"] = int(self.intrusions[row * self.num_robots + robot])
            if self.counterfactual:
                entry.update(self._cost(row))
            out.append(entry)
        return out

    def _cost(self, row: int) -> dict[str, float]:
        people = self.counted[row]
        if not people.any():
            return {key: float("nan") for key in COST_KEYS}
        assert self.ghost is not None
        speed = np.maximum(self.ghost.human_pref_speed[row], 1e-9)
        if self.stale[row] and self.latest is not None:
            # A running episode: the route left now.
            for run, state in enumerate(self.latest):
                self.left[run, row] = self._route_left(state, np.array([row]), self.suffix[[row]])[0]
            self.stale[row] = False
        reach, dist = [], []
        for run in (0, 1):
            arrived = self.arrived[run, row]
            done = ~np.isnan(arrived)
            reach.append(np.where(done, arrived, self.elapsed[row] + self.left[run, row] / speed))
            dist.append(self.walked[run, row] + np.where(done, 0.0, self.left[run, row]))
        lost = (reach[0] - reach[1])[people]
        extra = (dist[0] - dist[1])[people]
        return {
            "people_time_lost": float(lost.mean()),
            "people_time_lost_max": float(lost.max()),
            "people_extra_distance": float(extra.mean()),
        }

    def rows(self, index: np.ndarray) -> People:
        """The people of rows `index` (copies), for a core compacted to those rows."""
        index = np.asarray(index, dtype=np.intp)
        new = object.__new__(People)
        new.__dict__.update(self.__dict__)
        new.batch_size = len(index)
        robot_rows = (index[:, None] * self.num_robots + np.arange(self.num_robots)).reshape(-1)
        new.intrusions = self.intrusions[robot_rows].copy()
        for name in ("elapsed", "frozen", "suffix", "counted", "stale"):
            setattr(new, name, getattr(self, name)[index].copy())
        for name in ("walked", "arrived", "left"):
            setattr(new, name, getattr(self, name)[:, index].copy())
        new.ghost = None if self.ghost is None else self.ghost.rows(index)
        new.latest = None if self.latest is None else (self.latest[0].rows(index), self.latest[1].rows(index))
        return new


def without_robots(state: WorldState) -> WorldState:
    """The state with no robot (robot arrays of R = 0), every array copied."""
    fields = {name: np.array(value) for name, value in vars(state).items()}
    for name in ("robot_pose", "robot_vel", "robot_goal"):
        fields[name] = fields[name][:, :0].copy()
    return WorldState(**fields)


def _group_crossings(before: WorldState, after: WorldState) -> np.ndarray:
    """(B, R) int: pairs of members of a walking group (within GROUP_SPAN of each other) that each
    robot's centre passed between during the step."""
    group = after.human_group
    b, h = group.shape
    i, j = np.triu_indices(h, 1)
    pair = (group[:, i] >= 0) & (group[:, i] == group[:, j]) & after.human_mask[:, i] & after.human_mask[:, j]
    r = after.robot_pose.shape[1]
    if not pair.any():
        return np.zeros((b, r), dtype=np.int64)
    a0, b0 = before.human_pos[:, i], before.human_pos[:, j]  # (B, P, 2)
    a1, b1 = after.human_pos[:, i], after.human_pos[:, j]
    r0 = before.robot_pose[:, :, None, :2]  # (B, R, 1, 2)
    r1 = after.robot_pose[:, :, None, :2]

    def side(a: np.ndarray, c: np.ndarray, p: np.ndarray) -> np.ndarray:
        return (c[..., 0] - a[..., 0]) * (p[..., 1] - a[..., 1]) - (c[..., 1] - a[..., 1]) * (
            p[..., 0] - a[..., 0]
        )

    s0 = side(a0[:, None], b0[:, None], r0)
    s1 = side(a1[:, None], b1[:, None], r1)
    span = b1 - a1
    length2 = (span**2).sum(-1)[:, None]
    t = (((r1 - a1[:, None]) * span[:, None]).sum(-1)) / np.maximum(length2, 1e-12)
    close = length2 <= GROUP_SPAN**2
    crossed = (s0 * s1 < 0.0) & (t >= 0.0) & (t <= 1.0) & close & pair[:, None]
    return crossed.sum(-1).astype(np.int64)
