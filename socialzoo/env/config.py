"""Configuration of the environments: one frozen EnvConfig holds every part."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, get_args

from socialzoo.core.config import GroupConfig, HumanConfig, LaserConfig, OrcaConfig, RobotConfig, WorldConfig
from socialzoo.core.files import no_file
from socialzoo.core.validation import check_choice, check_int, check_number, unknown_fields
from socialzoo.env.human_agents import HumanRewardConfig
from socialzoo.env.metrics import MetricsConfig
from socialzoo.env.observation import ObservationConfig, observation_size
from socialzoo.env.people import COUNTERFACTUAL_RECORDED
from socialzoo.env.quirks import ReferenceQuirks
from socialzoo.env.reward import RewardConfig
from socialzoo.humans.models import PeopleConfig
from socialzoo.nav.local_planner import LocalPlannerConfig
from socialzoo.nav.subpolicies import SubPolicyConfig
from socialzoo.scenarios.catalogue import get_family
from socialzoo.scenarios.families import FAMILIES
from socialzoo.scenarios.generator import ScenarioConfig

RobotAction = Literal["subpolicy", "velocity"]
HumanActionFrame = Literal["world", "human"]

# Nested configs, by field name, for building an EnvConfig from plain JSON.
_NESTED: dict[str, type] = {
    "world": WorldConfig,
    "scenario": ScenarioConfig,
    "observation": ObservationConfig,
    "reward": RewardConfig,
    "subpolicy": SubPolicyConfig,
    "planner": LocalPlannerConfig,
    "metrics": MetricsConfig,
    "human_reward": HumanRewardConfig,
    "people": PeopleConfig,
    "quirks": ReferenceQuirks,
}
_WORLD_NESTED: dict[str, type] = {
    "robot": RobotConfig,
    "human": HumanConfig,
    "laser": LaserConfig,
    "orca": OrcaConfig,
    "groups": GroupConfig,
}
# Fields that were renamed: old name -> new name. An old name is refused with a message that
# names its successor, rather than ignored or reported as merely unknown.
RENAMED_FIELDS: dict[str, str] = {
    "learned_humans": "num_learned_humans",
    "human_neighbours": "num_human_neighbours",
    "human_collision_penalty": "human_reward",  # its human_contact and robot_contact weights
}


@dataclass(frozen=True, kw_only=True)
class EnvConfig:
    """Everything an environment needs.

    Every field has the benchmark's value by default (SPEC sections 2 to 9); overrides go through
    `EnvConfig.replace`, `EnvConfig.resolve` (what every adapter does with its keyword arguments)
    or `EnvConfig.from_dict`, whose plain-JSON form is what the registry stores.

    Attributes:
        map: a shipped map name ("gdc1", "ghc3", "open_room", ...) or a path to a map JSON file;
            None (the default): the family's map with a family, else "gdc1" (`map` is then that
            name). A config that changes its family with `replace` keeps its map unless map=None
            is given too.
        num_robots: robots per world (R); the single-agent benchmark uses 1.
        max_steps: episode time limit in steps (SPEC: 3200 = 80 s); reaching it truncates.
        goal_radius: success distance between robot centre and goal, m (SPEC: 0.5).
        robot_action: "subpolicy" (Discrete(4): GoAlone, Halt, Follow, Pass) or "velocity"
            (Box [-1, 1]^2 scaled to robot.max_speed and robot.max_angular_speed).
        num_learned_humans: number of human slots (human_0 .. human_{k-1}) driven by a learner;
            the others follow their scripted social-force policy. (Called learned_humans before;
            the old name is refused.)
        num_human_neighbours: neighbours (humans and robots) in a learned human's observation.
            (Called human_neighbours before; the old name is refused.)
        human_action_frame: the frame of a learned human's action: "world" (a world-frame
            velocity) or "human" (its own frame, x towards its waypoint, as its observation).
        human_action_scale: a learned human's action [-1, 1]^2 times this times its preferred
            speed is its desired velocity (> 0). Above 1 a learner can ask for more than the
            preferred speed (relaxing back to it sooner after a slowdown); the motion model still
            caps every human's speed at its preferred speed.
        human_reward: the learned humans' reward weights (socialzoo.env.human_agents).
            (human_collision_penalty before; the old name is refused.)
        family: None for the benchmark's scenario generation (SPEC section 5), or a scenario
            family name (socialzoo.scenarios.families.FAMILIES).
        signals: the robot also observes the scenario script's signals: each human slot's
            gesture and the nearest door (socialzoo.env.observation's signal block). Off: the
            observation layout is exactly the benchmark's.
        world, scenario, observation, reward, subpolicy, planner, metrics: the parts' configs.
        people: which models drive the people of each scenario (social force, ORCA, walking
            groups, a learned policy file, or a mix), and whether each scenario also runs
            without the robot to measure what it costs them (socialzoo.humans.models.PeopleConfig,
            socialzoo.env.people). The default is the benchmark's social-force people.
        quirks: the reference code's behaviour where it departed from the paper (SPEC section
            11; socialzoo.env.quirks.ReferenceQuirks), each switch off by default;
            `ReferenceQuirks.reference()` (every one on) is the preset of the
            socialzoo/ActionSelectionReference-v2 ids.
    """

    map: str | None = None
    num_robots: int = 1
    max_steps: int = 3200
    goal_radius: float = 0.5
    robot_action: RobotAction = "subpolicy"
    num_learned_humans: int = 0
    num_human_neighbours: int = 6
    human_action_frame: HumanActionFrame = "world"
    human_action_scale: float = 1.0
    family: str | None = None
    signals: bool = False
    world: WorldConfig = field(default_factory=WorldConfig)
    scenario: ScenarioConfig = field(default_factory=ScenarioConfig)
    observation: ObservationConfig = field(default_factory=ObservationConfig)
    reward: RewardConfig = field(default_factory=RewardConfig)
    subpolicy: SubPolicyConfig = field(default_factory=SubPolicyConfig)
    planner: LocalPlannerConfig = field(default_factory=LocalPlannerConfig)
    metrics: MetricsConfig = field(default_factory=MetricsConfig)
    human_reward: HumanRewardConfig = field(default_factory=HumanRewardConfig)
    # Or a people spec string, taken as PeopleConfig(models=...).
    people: PeopleConfig = field(default_factory=PeopleConfig)
    quirks: ReferenceQuirks = field(default_factory=ReferenceQuirks)

    def __post_init__(self) -> None:
        if isinstance(self.people, str):  # a people spec, as the CrowdNav task and the CLI take it
            object.__setattr__(self, "people", PeopleConfig(models=self.people))
        home = "gdc1"  # the benchmark's map
        if self.family is not None:
            home = family_map(self.family, "EnvConfig.family")
        if self.map is None and home == OPEN:
            # The task plans on a map's graph: a family in the open gives its open area as one.
            opening = getattr(get_family(self.family), "open_map", None)  # type: ignore[arg-type]
            if opening is None:
                raise ValueError(
                    f"EnvConfig.family: {self.family!r} plays in the open arena, with no map of its own; give map=PATH"
                )
            home = opening()
        if self.map is None:
            object.__setattr__(self, "map", home)
        if not isinstance(self.map, str) or not self.map:
            raise ValueError(f"EnvConfig.map must be a map name or path, or None, got {self.map!r}")
        if not isinstance(self.signals, bool):
            raise ValueError(f"EnvConfig.signals must be a bool, got {self.signals!r}")
        for name, low in (
            ("num_robots", 1),
            ("max_steps", 1),
            ("num_learned_humans", 0),
            ("num_human_neighbours", 0),
        ):
            check_int("EnvConfig", name, getattr(self, name), low=low)
        check_family_robots(self.family, self.num_robots, "EnvConfig")
        if self.num_learned_humans > self.max_humans:
            raise ValueError(
                f"EnvConfig.num_learned_humans ({self.num_learned_humans}) exceeds the human slots "
                f"(scenario.max_humans = {self.max_humans})"
            )
        check_number("EnvConfig", "goal_radius", self.goal_radius, low=0, low_open=True)
        check_number("EnvConfig", "human_action_scale", self.human_action_scale, low=0, low_open=True)
        check_choice("EnvConfig", "robot_action", self.robot_action, get_args(RobotAction))
        check_choice("EnvConfig", "human_action_frame", self.human_action_frame, get_args(HumanActionFrame))
        self._check_people()
        for name, cls in _NESTED.items():
            if not isinstance(getattr(self, name), cls):
                raise ValueError(f"EnvConfig.{name} must be a {cls.__name__}, got {getattr(self, name)!r}")

    def _check_people(self) -> None:
        """Refuse people the env cannot drive, naming the field."""
        if not isinstance(self.people, PeopleConfig):
            return  # reported with the other nested configs
        path = self.people.learned_path
        if path is not None and not Path(path).is_file():
            raise ValueError(f"EnvConfig.people.models: {no_file(path, 'learned policy file')}")
        if self.people.counterfactual and (self.people.recorded or _recorded_family(self.family)):
            where = (
                f"people spec {self.people.models!r}" if self.people.recorded else f"family {self.family!r}"
            )
            raise ValueError(f"EnvConfig.people.counterfactual: the {where} has {COUNTERFACTUAL_RECORDED}")
        if self.people.counterfactual and self.num_learned_humans:
            raise ValueError(
                "EnvConfig.people.counterfactual needs people the env drives itself, but "
                f"num_learned_humans = {self.num_learned_humans} are driven from outside"
            )
        if self.people.recorded and self.num_learned_humans:
            # The recording places replayed and hybrid people after every step: a learner's actions
            # for their slots would be ignored.
            raise ValueError(
                f"EnvConfig.people.models {self.people.models!r} puts people on their recorded tracks, "
                f"where num_learned_humans = {self.num_learned_humans} learned slots cannot walk; "
                "give people a model that walks (e.g. 'sf') or num_learned_humans = 0"
            )

    @property
    def map_name(self) -> str:
        """The map, a shipped name or a file path: `map` once built (None stands for the family's
        map, else gdc1, and is replaced by it)."""
        assert self.map is not None  # __post_init__ set it
        return self.map

    @property
    def max_humans(self) -> int:
        """Human slots per world (H): the scenario generator's maximum head count, or a family's
        largest scenario where that is larger (a recorded scene's: socialzoo.scenarios.recorded)."""
        most = getattr(get_family(self.family), "max_people", None) if self.family is not None else None
        return self.scenario.max_humans if most is None else max(self.scenario.max_humans, int(most))

    @property
    def observation_size(self) -> int:
        """Length of one robot observation: the layout's, with the signal block if `signals`."""
        return observation_size(self.observation, self.signals)

    @property
    def dt(self) -> float:
        """The step, s (the world's dt)."""
        return self.world.dt

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready dict (nested configs as dicts)."""
        return dataclasses.asdict(self)

    @classmethod
    def resolve(
        cls, config: EnvConfig | None = None, overrides: Mapping[str, Any] | None = None
    ) -> EnvConfig:
        """The config an adapter runs: `config` (default: the benchmark's) with `overrides`.

        This is what every adapter (single-agent, vector, parallel) does with its `config`
        argument and keyword arguments.

        Args:
            config: a base EnvConfig, or None for the defaults.
            overrides: EnvConfig fields as plain values, nested configs as dicts of overrides
                (see `replace`).

        Raises:
            ValueError: an unknown or renamed field, or a bad value (naming it).
            TypeError: `config` is not an EnvConfig.
        """
        if config is not None and not isinstance(config, EnvConfig):
            raise TypeError(f"config must be an EnvConfig or None, got {type(config).__name__}")
        if config is None:  # the defaults: with a family and no map, the family's own map
            return cls().replace(**{"map": None, **overrides}) if overrides else cls()
        return config.replace(**overrides) if overrides else config

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> EnvConfig:
        """Build from a plain dict such as `to_dict()` gives; unknown keys raise naming the key."""
        return cls(**_nested_overrides(None, data))

    def replace(self, **changes: Any) -> EnvConfig:
        """A copy with `changes`; nested configs may be given as dicts of overrides.

        Raises:
            ValueError: an unknown or renamed field (naming it), or a bad value.
        """
        return dataclasses.replace(self, **_nested_overrides(self, changes))


# A family's map_name for the open (no walls): CrowdNav's arena, a recorded scene.
OPEN = "arena"


def family_map(name: str, where: str) -> str:
    """The map registered family `name` is designed for (its map_name).

    Raises:
        ValueError: an unknown family, or one that cannot be loaded (naming `where`, the family
            and why).
    """
    if not isinstance(name, str) or name not in FAMILIES:
        raise ValueError(f"{where} must be None or one of {sorted(FAMILIES)}, got {name!r}")
    try:
        return get_family(name).map_name
    except (ImportError, AttributeError, KeyError, ValueError) as err:
        raise ValueError(f"{where}: scenario family {name!r} cannot be loaded ({err})") from None


def check_family_robots(name: str | None, num_robots: int, owner: str) -> None:
    """Refuse more robots than family `name`'s scenarios hold (ScenarioFamily.max_robots), naming
    `owner`'s fields, when the config is made rather than at its first reset."""
    most = None if name is None else get_family(name).max_robots
    if most is not None and num_robots > most:
        raise ValueError(
            f"{owner}.num_robots = {num_robots}, but scenario family {name!r} holds {most} robot(s) per episode"
        )


def _recorded_family(name: str | None) -> bool:
    """Whether family `name`'s episodes have recorded people (a recorded scene, loaded only when played)."""
    from socialzoo.scenarios.recorded import RecordedScene

    return name is not None and isinstance(get_family(name), RecordedScene)


def _nested_overrides(base: EnvConfig | None, data: Mapping[str, Any]) -> dict[str, Any]:
    """EnvConfig fields of `data`, nested configs given as dicts applied to `base`'s (None: the
    defaults). Raises for a renamed field (naming its new name) or an unknown one."""
    for key in data:
        if key in RENAMED_FIELDS:
            raise ValueError(f"EnvConfig: {key} was renamed {RENAMED_FIELDS[key]}")
    check_known(EnvConfig, data, "EnvConfig")
    return {
        key: _override(_NESTED[key]() if base is None else getattr(base, key), value, f"EnvConfig.{key}")
        if key in _NESTED and isinstance(value, dict)
        # A people spec string changes the models only (a run's counterfactual switch is kept).
        else _override(PeopleConfig() if base is None else base.people, {"models": value}, "EnvConfig.people")
        if key == "people" and isinstance(value, str)
        else value
        for key, value in data.items()
    }


def check_known(cls: Any, data: Mapping[str, Any], where: str) -> None:
    """Refuse keys of `data` that are no field of dataclass `cls` (or of its instance), naming
    `where`, the unknown fields and the known ones (socialzoo.core.validation.UnknownFieldError)."""
    error = unknown_fields(where, data, [f.name for f in dataclasses.fields(cls)])
    if error is not None:
        raise error


def _override(base: Any, data: dict[str, Any], where: str) -> Any:
    check_known(base, data, where)
    resolved: dict[str, Any] = {}
    for key, value in data.items():
        nested = _WORLD_NESTED.get(key) if isinstance(base, WorldConfig) else None
        if nested is not None and isinstance(value, dict):
            current = getattr(base, key) or nested()
            resolved[key] = _override(current, value, f"{where}.{key}")
        elif isinstance(value, list):
            resolved[key] = tuple(value)
        else:
            resolved[key] = value
    return dataclasses.replace(base, **resolved)
