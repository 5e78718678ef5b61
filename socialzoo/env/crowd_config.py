"""Configuration of the CrowdNav task: a velocity-controlled robot crossing a crowd (Chen et al.
2019, vita-epfl/CrowdNav), with CrowdNav's settings as the defaults and its usual variants."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any, Literal, get_args

from socialzoo.core.config import HumanConfig, OrcaConfig, RobotConfig, WorldConfig
from socialzoo.core.validation import check_choice, check_int, check_number
from socialzoo.env.config import check_family_robots, check_known, family_map
from socialzoo.env.crowd_observation import OBSERVATION_KINDS, ObservationKind
from socialzoo.env.crowd_outcome import CrowdRewardConfig
from socialzoo.env.crowd_variants import VARIANTS
from socialzoo.humans.models import PeopleConfig, PeopleSpecError
from socialzoo.scenarios.catalogue import get_family
from socialzoo.scenarios.crowd_cases import CrowdCaseConfig

CrowdAction = Literal["continuous", "discrete"]
CROWD_ACTIONS: tuple[str, ...] = get_args(CrowdAction)
# The models of a people spec (socialzoo.humans.models) the task drives through the one world step
# (socialzoo.env.core): its cases have no routes for walking groups, and it runs no learned
# policy of its own.
# Recorded people (a recorded scene's) may also replay their tracks or react by one of these
# ("replay", "hybrid:sf", "hybrid:orca").
CROWD_MODELS: tuple[str, ...] = ("sf", "orca", "replay")
ActionFrame = Literal["goal", "world"]
ACTION_FRAMES: tuple[str, ...] = get_args(ActionFrame)
# The map_name of the families of CrowdNav's open arena (socialzoo.scenarios.catalogue).
ARENA = "arena"
# CrowdNav's own arena families, chosen by cases.layout (not CrowdNavConfig.family).
ARENA_LAYOUTS = ("crowdnav_circle_crossing", "crowdnav_square_crossing")
# The case fields that follow the robot and the reward (CrowdNavConfig.replace).
_CASE_SPACING = ("robot_radius", "discomfort_dist")


@dataclass(frozen=True, kw_only=True)
class CrowdNavConfig:
    """Everything the CrowdNav task needs; the defaults are CrowdNav's.

    Attributes:
        cases: how cases are drawn (layout, people, radii, speeds).
        time_step: the decision step, s (CrowdNav: 0.25).
        physics_substeps: world steps per decision (1: the people move at the decision step, as
            CrowdNav's ORCA people do; social-force people take 10 steps of 0.025 s, the
            benchmark's physics).
        time_limit: s; a step that starts at time_limit - 1 s or later ends the episode (CrowdNav).
        robot: the robot (kinematics, radius, max_speed = its preferred speed; CrowdNav's:
            holonomic, radius 0.3 m, preferred (and largest) speed 1 m/s).
        robot_visible: whether the people see and avoid the robot (CrowdNav: invisible).
        humans: who walks, as a people spec (socialzoo.humans.models, the one way every env and
            the benchmark say it): "orca" (CrowdNav's), "sf" (also "social_force"), or a mix such
            as "sf@0.5+orca@0.5", assigned from each case's seed. A PeopleConfig, or a dict of its
            fields, also sets a hybrid crowd's reaction rule (react_radius, react_time; models
            defaults to "orca"), e.g. {"models": "hybrid:orca", "react_radius": 3.0}.
        reward: the task's reward.
        action: "continuous" (Box [-1, 1]^2 scaled to the robot's speed: (vx, vy) for a holonomic
            robot, (speed, turn) for a unicycle) or "discrete" (CrowdNav's 81 actions).
        observation: "flat" or "dict" (socialzoo.env.crowd_observation).
        max_humans: person slots of the observation and the state (default: cases.num_humans, or a
            family's largest scenario where that holds more people; given, at least that many).
        observed_people: None (CrowdNav's): the observation holds every person slot, in slot order.
            A count K: it holds the K present people nearest the robot, nearest first (empty slots
            after them when fewer are present), whatever the world's slots: a policy trained with K
            people (the attention network reads a set) plays a scene of more or fewer slots, as a
            recorded scene's (socialzoo.scenarios.recorded).
        num_robots: robots per world (1: CrowdNav's task; more for the PettingZoo env, each seeing
            the others as people: socialzoo.scenarios.crowd_cases.robot_poses).
        map: None for CrowdNav's open arena; a building map ("gdc1", a path) for crowd navigation
            among walls, with the benchmark's scenarios and social-force people. Among walls the
            robot is guided as the benchmark's robot is: the goal it sees is its route's local
            target on the map's navigation graph (the carrot, SPEC section 6) and its goal distance
            is the length of route left. None with a family: the family's map (`map` is then its
            name; a config that changes its family with `replace` keeps its map unless map=None
            is given too).
        family: None, or a registered scenario family on a map (socialzoo.scenarios.catalogue,
            e.g. the guidelines' suite, socialzoo.scenarios.suite): the task plays that family's
            scenarios, training cases from its training seeds and fixed cases from its own "val"
            and "test" splits (a family without splits: its map's validation and test sets' seeds).
            CrowdNav's arena families are cases.layout, not a family here. A family in the open
            (map "arena", a recorded scene's: socialzoo.scenarios.recorded) plays without walls,
            its person slots (max_humans None) sized to its largest scenario.
        signals: each person slot also carries the gesture its person shows (0 none, 1 wait,
            2 proceed; socialzoo.scenarios.script) and the robot part the nearest door (its point
            nearest the robot in the observation frame, and closed 0/1)
            (socialzoo.env.crowd_observation). Off: the observation is CrowdNav's joint state.
        wall_rays: rays of a scan around the robot whose wall hits within wall_range it sees as
            still obstacles of radius 0, one slot per ray after the people (masked when the ray
            hits nothing): an end-to-end robot among walls must see them. 0: none (the arena).
        wall_range: the scan's range, m.
        action_frame: the frame of a holonomic robot's velocity (continuous or discrete): "goal"
            (x towards the goal the robot sees: the observation's own frame, so a policy acts in
            the frame it observes; the default) or "world" (CrowdNav's ActionXY). The goal frame
            turns with the robot's bearing to the goal: in CrowdNav's arena the two differ by a
            quarter turn only on the start-goal line, and by that bearing elsewhere; with random
            layouts (CrowdNav++'s arena) or among walls only "goal" can be learned from the
            observation.
    """

    cases: CrowdCaseConfig = field(default_factory=CrowdCaseConfig)
    time_step: float = 0.25
    physics_substeps: int = 1
    time_limit: float = 25.0
    robot: RobotConfig = field(
        default_factory=lambda: RobotConfig(kinematics="holonomic", radius=0.3, max_speed=1.0)
    )
    robot_visible: bool = False
    humans: str | PeopleConfig = "orca"
    reward: CrowdRewardConfig = field(default_factory=CrowdRewardConfig)
    action: CrowdAction = "continuous"
    observation: ObservationKind = "flat"
    max_humans: int | None = None
    observed_people: int | None = None
    num_robots: int = 1
    map: str | None = None
    wall_rays: int = 0
    wall_range: float = 4.0
    action_frame: ActionFrame = "goal"
    family: str | None = None
    signals: bool = False

    def __post_init__(self) -> None:
        for name, cls in (("cases", CrowdCaseConfig), ("robot", RobotConfig), ("reward", CrowdRewardConfig)):
            value = getattr(self, name)
            if not isinstance(value, cls):
                raise ValueError(
                    f"CrowdNavConfig.{name} must be a {cls.__name__} or a dict of its fields, got {value!r}"
                )
        if not isinstance(self.robot_visible, bool):
            raise ValueError(f"CrowdNavConfig.robot_visible must be a bool, got {self.robot_visible!r}")
        check_int(
            "CrowdNavConfig", "max_humans", self.max_humans, low=0, allow_none=True
        )  # the family reads it
        self._resolve_family()
        check_number("CrowdNavConfig", "time_step", self.time_step, low=0, low_open=True)
        check_int("CrowdNavConfig", "physics_substeps", self.physics_substeps, low=1)
        check_number("CrowdNavConfig", "time_limit", self.time_limit, low=1, low_open=True)
        if self.robot.kinematics == "differential":
            raise ValueError(
                "CrowdNavConfig.robot.kinematics must be 'holonomic' or 'unicycle', got 'differential'"
            )
        if self.robot.radius is None:
            raise ValueError("CrowdNavConfig.robot.radius must be set (the task's robot is a disc)")
        if isinstance(self.humans, dict):
            object.__setattr__(self, "humans", people_config(self.humans))
        people = self.people
        models = {part.walks_as for part in people.parts}
        if not models <= set(CROWD_MODELS):
            raise ValueError(
                f"CrowdNavConfig.humans: the CrowdNav task's people walk by {CROWD_MODELS} (or a mix of them), "
                "recorded people also as hybrid:sf or hybrid:orca; learned people, hybrid or not, and groups "
                f"are the action-selection task's, got {people.models!r}"
            )
        if people.counterfactual:
            raise ValueError("CrowdNavConfig.humans: counterfactual runs are the action-selection task's")
        check_choice("CrowdNavConfig", "action", self.action, CROWD_ACTIONS)
        check_choice("CrowdNavConfig", "observation", self.observation, OBSERVATION_KINDS)
        check_int("CrowdNavConfig", "observed_people", self.observed_people, low=1, allow_none=True)
        check_int("CrowdNavConfig", "num_robots", self.num_robots, low=1)
        check_family_robots(self.family, self.num_robots, "CrowdNavConfig")
        if self.max_humans is not None and self.max_humans < self.cases.num_humans:
            raise ValueError(
                f"CrowdNavConfig.max_humans ({self.max_humans}) is below cases.num_humans ({self.cases.num_humans})"
            )
        if self.map is not None and (not isinstance(self.map, str) or not self.map):
            raise ValueError(f"CrowdNavConfig.map must be None or a map name or path, got {self.map!r}")
        check_int("CrowdNavConfig", "wall_rays", self.wall_rays, low=0)
        check_number("CrowdNavConfig", "wall_range", self.wall_range, low=0, low_open=True)
        check_choice("CrowdNavConfig", "action_frame", self.action_frame, ACTION_FRAMES)
        # CrowdNav spaces its people from its robot by the robot's radius and the reward's
        # discomfort distance: cases drawn for another robot could start it inside a person.
        for spacing, value, owner in (
            ("robot_radius", self.robot.radius, "robot.radius"),
            ("discomfort_dist", self.reward.discomfort_dist, "reward.discomfort_dist"),
        ):
            if getattr(self.cases, spacing) != value:
                raise ValueError(
                    f"CrowdNavConfig.cases.{spacing} ({getattr(self.cases, spacing)}) must equal {owner} "
                    f"({value}): the cases are drawn for the task's robot and reward (replace() carries "
                    f"{owner} into the cases)"
                )
        if not isinstance(self.signals, bool):
            raise ValueError(f"CrowdNavConfig.signals must be a bool, got {self.signals!r}")

    def _resolve_family(self) -> None:
        """Refuse a family that is unknown, cannot load or is CrowdNav's arena; map None: its map."""
        if self.family is None:
            return
        home = family_map(self.family, "CrowdNavConfig.family")
        if self.family in ARENA_LAYOUTS:
            raise ValueError(
                f"CrowdNavConfig.family: {self.family!r} is a family of CrowdNav's open arena; choose the "
                "arena's cases with cases.layout (and map=None, no family)"
            )
        if self.map is None and home != ARENA:
            object.__setattr__(self, "map", home)
        # A family whose scenarios hold more people than the cases' count (a recorded scene's) sizes
        # the person slots; slots given that are too few for it would fail at the first reset of
        # such a scenario, after a run has begun.
        most = getattr(get_family(self.family), "max_people", None)
        if most is None:
            return
        if self.max_humans is None:
            if most > self.cases.num_humans:
                object.__setattr__(self, "max_humans", int(most))
        elif self.max_humans < most:
            raise ValueError(
                f"CrowdNavConfig.max_humans ({self.max_humans}) is below the {most} people of the largest "
                f"scenario of family {self.family!r}: give max_humans >= {most}, or None to size the person "
                "slots to the family"
            )

    @property
    def people(self) -> PeopleConfig:
        """Who walks and how hybrid people react (`humans` as a PeopleConfig)."""
        if isinstance(self.humans, PeopleConfig):
            return self.humans
        if isinstance(self.humans, str):
            try:
                return PeopleConfig(models=self.humans)
            except PeopleSpecError as err:
                raise ValueError(f"CrowdNavConfig.humans: {err}") from None
        raise ValueError(
            f"CrowdNavConfig.humans must be a people spec, a PeopleConfig or a dict of its fields, got {self.humans!r}"
        )

    @property
    def slots(self) -> int:
        """Person slots H."""
        return self.cases.num_humans if self.max_humans is None else self.max_humans

    @property
    def observed_slots(self) -> int:
        """Slots of a robot's observation: the people, the other robots, then the wall rays."""
        return (self.observed_people or self.slots) + self.num_robots - 1 + self.wall_rays

    @property
    def physics_dt(self) -> float:
        """The world step, s."""
        return self.time_step / self.physics_substeps

    @property
    def preferred_speed(self) -> float:
        """The robot's preferred speed v_pref, m/s (its largest)."""
        return self.robot.max_speed

    @property
    def world(self) -> WorldConfig:
        """The world's parameters: the physics step, the robot, and CrowdNav's people (ORCA with its
        parameters, at the people's own radius and speed)."""
        cases = self.cases
        return WorldConfig(
            dt=self.physics_dt,
            robot=self.robot,
            human=HumanConfig(radius=cases.human_radius),
            human_collision_distance=float(self.robot.radius) + cases.human_radius,  # type: ignore[arg-type]
            orca=dataclasses.replace(
                OrcaConfig.preset("crowdnav"),
                radius=cases.human_radius,
                max_speed=cases.human_speed,
                robot_visible=self.robot_visible,
            ),
        )

    def replace(self, **changes: Any) -> CrowdNavConfig:
        """A copy with `changes`; nested configs may be given as dicts of their fields.

        The cases follow the robot and the reward (CrowdNav reads one value for each): a new
        robot radius or discomfort distance is carried into cases.robot_radius and
        cases.discomfort_dist unless `changes` sets those itself (a CrowdCaseConfig, or a dict
        naming them)."""
        cases = changes.get("cases")
        named = cases.keys() if isinstance(cases, dict) else _CASE_SPACING if cases is not None else ()
        for name in ("cases", "robot", "reward"):
            if isinstance(changes.get(name), dict):
                changes[name] = _replace_nested(getattr(self, name), changes[name], f"CrowdNavConfig.{name}")
        robot, reward = changes.get("robot", self.robot), changes.get("reward", self.reward)
        follow: dict[str, Any] = {
            "robot_radius": getattr(robot, "radius", None),
            "discomfort_dist": getattr(reward, "discomfort_dist", None),
        }
        follow = {k: v for k, v in follow.items() if k not in named and v is not None}
        cases = changes.get("cases", self.cases)
        if isinstance(cases, CrowdCaseConfig) and any(getattr(cases, k) != v for k, v in follow.items()):
            changes["cases"] = dataclasses.replace(cases, **follow)
        check_known(self, changes, "CrowdNavConfig")
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON values (what the registry and run records store)."""
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> CrowdNavConfig:
        """The config of `to_dict`'s form (missing fields keep their defaults)."""
        return cls().replace(**dict(data))

    @classmethod
    def variant(cls, name: str, **overrides: Any) -> CrowdNavConfig:
        """The config of a registered variant ("" for CrowdNav's own; VARIANTS), then `overrides`.

        Raises:
            ValueError: an unknown variant (the message lists them).
        """
        if name not in VARIANTS:
            known = ", ".join(repr(v) for v in VARIANTS)
            raise ValueError(f"unknown CrowdNav variant {name!r}; known variants: {known}")
        # replace() reads the nested dicts, never writes them: the registry's stay as they are.
        return cls().replace(**VARIANTS[name][1]).replace(**overrides)


def resolve_config(config: CrowdNavConfig | None, overrides: dict[str, Any]) -> CrowdNavConfig:
    """The config of `config` (default CrowdNav's) with plain overrides; `variant=NAME` starts from
    a registered variant (socialzoo.env.crowd_variants)."""
    overrides = dict(overrides)
    variant = overrides.pop("variant", None)
    if config is not None and not isinstance(config, CrowdNavConfig):
        raise TypeError(f"config must be a CrowdNavConfig or None, got {type(config).__name__}")
    base = config or (CrowdNavConfig.variant(variant) if variant is not None else CrowdNavConfig())
    return base.replace(**overrides) if overrides else base


def _replace_nested(config: Any, fields: dict[str, Any], where: str) -> Any:
    """`config` with `fields`; an unknown field raises naming `where` and the known ones."""
    check_known(config, fields, where)
    return dataclasses.replace(config, **fields)


def people_config(fields: dict[str, Any]) -> PeopleConfig:
    """CrowdNavConfig.humans given as a dict of PeopleConfig's fields (models defaults to "orca")."""
    try:
        return PeopleConfig(**{"models": "orca", **fields})
    except TypeError as err:
        known = sorted(f.name for f in dataclasses.fields(PeopleConfig))
        raise ValueError(f"CrowdNavConfig.humans: {err}; known fields: {known}") from None
    except ValueError as err:
        raise ValueError(f"CrowdNavConfig.humans: {err}") from None
