"""Scenario families: the interface every family implements, and the one registry of families by name."""

from __future__ import annotations

import importlib
from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING, NamedTuple

if TYPE_CHECKING:
    from socialzoo.maps.map_file import Map
    from socialzoo.scenarios.scenario import Scenario


class SeedSplit(NamedTuple):
    """A split of a family's seeds: case k of the split has seed `first + k`, k < `size` (None: no end)."""

    first: int
    size: int | None = None


class ScenarioFamily:
    """A scenario family: one class that draws a Scenario from a seed.

    A subclass sets the class attributes and writes `make`; `register_family` makes its name
    known to `EnvConfig(family=...)`, the scenario streams and `get_family`.

    Attributes:
        name: the registry name (snake_case).
        map_name: the map it is designed for ("arena": CrowdNav's open arena, no map).
        description: one line saying what happens.
        splits: fixed seed splits of its own ("val", "test", "train"), if any; a family without
            them plays its map's validation and test seeds.
        max_robots: the most robots one of its scenarios can hold (None: any number); configs
            asking for more are refused when made.
    """

    name: str = ""
    map_name: str = ""
    description: str = ""
    splits: Mapping[str, SeedSplit] = {}
    max_robots: int | None = None

    def make(self, seed: int, num_robots: int = 1, m: Map | None = None) -> Scenario:
        """The scenario of `seed` with `num_robots` robots, on map m (default: the family's map)."""
        raise NotImplementedError(f"{type(self).__name__}.make")

    def case_seed(self, split: str, index: int) -> int:
        """The seed of case `index` of one of the family's splits.

        Raises:
            ValueError: an unknown split, or an index outside it.
        """
        if split not in self.splits:
            raise ValueError(f"unknown split {split!r}; known: {tuple(self.splits)}")
        if not isinstance(index, int) or isinstance(index, bool) or index < 0:
            raise ValueError(f"case index must be an int >= 0, got {index!r}")
        first, size = self.splits[split]
        if size is not None and index >= size:
            raise ValueError(f"the {split} split holds {size} cases; index {index} is outside it")
        return first + index


# Family name -> the family: an instance, or the "module:Class" path of one (loaded on first use).
FAMILIES: dict[str, ScenarioFamily | str] = {
    "hallway_head_on": "socialzoo.scenarios.families:HallwayHeadOn",
    "overtaking": "socialzoo.scenarios.families:Overtaking",
    "crossing": "socialzoo.scenarios.families:Crossing",
    "doorway": "socialzoo.scenarios.families:Doorway",
    "circle_crossing": "socialzoo.scenarios.families:CircleCrossing",
    "parallel_traffic": "socialzoo.scenarios.families:ParallelTraffic",
    "crowdnav_circle_crossing": "socialzoo.scenarios.crowd_cases:CrowdNavCircleCrossing",
    "crowdnav_square_crossing": "socialzoo.scenarios.crowd_cases:CrowdNavSquareCrossing",
    # The guidelines' suite, Fig. 7 a-y (socialzoo.scenarios.suite): traffic on ways, places, people.
    "frontal_approach": "socialzoo.scenarios.suite_ways:FrontalApproach",
    "pedestrian_obstruction": "socialzoo.scenarios.suite_ways:PedestrianObstruction",
    "pedestrian_overtaking": "socialzoo.scenarios.suite_ways:PedestrianOvertaking",
    "robot_overtaking": "socialzoo.scenarios.suite_ways:RobotOvertaking",
    "down_path": "socialzoo.scenarios.suite_ways:DownPath",
    "intersection_no_gesture": "socialzoo.scenarios.suite_ways:IntersectionNoGesture",
    "intersection_wait": "socialzoo.scenarios.suite_ways:IntersectionWait",
    "intersection_proceed": "socialzoo.scenarios.suite_ways:IntersectionProceed",
    "blind_corner": "socialzoo.scenarios.suite_places:BlindCorner",
    "narrow_hallway": "socialzoo.scenarios.suite_places:NarrowHallway",
    "narrow_doorway": "socialzoo.scenarios.suite_ways:NarrowDoorway",
    "entering_room": "socialzoo.scenarios.suite_places:EnteringRoom",
    "exiting_room": "socialzoo.scenarios.suite_places:ExitingRoom",
    "entering_elevator": "socialzoo.scenarios.suite_places:EnteringElevator",
    "exiting_elevator": "socialzoo.scenarios.suite_places:ExitingElevator",
    "joining_group": "socialzoo.scenarios.suite_social:JoiningGroup",
    "leaving_group": "socialzoo.scenarios.suite_social:LeavingGroup",
    "following_person": "socialzoo.scenarios.suite_social:FollowingPerson",
    "leading_person": "socialzoo.scenarios.suite_social:LeadingPerson",
    "accompanying_peer": "socialzoo.scenarios.suite_social:AccompanyingPeer",
    "crowd_navigation": "socialzoo.scenarios.suite_social:CrowdNavigation",
    "parallel_flow": "socialzoo.scenarios.suite_ways:ParallelFlow",
    "perpendicular_flow": "socialzoo.scenarios.suite_social:PerpendicularFlow",
    "circular_crossing": "socialzoo.scenarios.suite_ways:CircularCrossing",
    "robot_crowding": "socialzoo.scenarios.suite_social:RobotCrowding",
    # Recorded scenes (socialzoo.scenarios.recorded): the robot in a recorded person's place.
    **{
        f"recorded_{scene}": f"socialzoo.scenarios.recorded:Recorded{scene.capitalize()}"
        for scene in ("eth", "hotel", "univ", "zara1", "zara2")
    },
}


# The package's own families: every process knows them; register_family adds others in its own.
_PACKAGE_FAMILIES = frozenset(FAMILIES)


def added_families(names: Iterable[str | None]) -> tuple[ScenarioFamily, ...]:
    """The families among `names` that register_family added in this process (not the package's
    own, which a new process loads by name): what a worker process must be given to play them."""
    return tuple(
        get_family(name)
        for name in dict.fromkeys(names)
        if name in FAMILIES and name not in _PACKAGE_FAMILIES
    )


def register_family(family: ScenarioFamily | type[ScenarioFamily]) -> ScenarioFamily:
    """Register a family (an instance, or a class made with no arguments) under its name.

    Raises:
        ValueError: not a ScenarioFamily, no name, or the name is taken by another family.
    """
    if isinstance(family, type) and issubclass(family, ScenarioFamily):
        family = family()
    if not isinstance(family, ScenarioFamily):
        raise ValueError(f"register_family needs a ScenarioFamily, got {family!r}")
    if not family.name:
        raise ValueError(f"{type(family).__name__}.name must be set to register it")
    old = FAMILIES.get(family.name)
    if old is not None and type(_load(family.name, old)) is not type(family):
        raise ValueError(f"scenario family {family.name!r} is already registered ({old!r})")
    FAMILIES[family.name] = family
    return family


def family_name(text: str) -> str:
    """The family a command line names: NAME, or MODULE:NAME for a family that MODULE registers when
    imported (imported here, as Gymnasium's MODULE:ID names an id a module registers).

    Raises:
        ValueError: MODULE cannot be imported, or registers no family NAME.
    """
    module, sep, name = text.rpartition(":")
    if sep:
        try:
            importlib.import_module(module)
        except (ImportError, ValueError, TypeError) as err:  # also an empty or relative name (":x", ".m:x")
            raise ValueError(f"scenario family {text}: cannot import {module!r} ({err})") from None
        if name not in FAMILIES:
            raise ValueError(f"scenario family {text}: importing {module!r} registers no family {name!r}")
    return name


def get_family(name: str) -> ScenarioFamily:
    """The registered family `name` (a registry path is loaded and kept).

    Raises:
        KeyError: unknown family (the message lists the known ones).
    """
    if name not in FAMILIES:
        raise KeyError(f"unknown scenario family {name!r}; known: {sorted(FAMILIES)}")
    family = _load(name, FAMILIES[name])
    FAMILIES[name] = family
    return family


def _load(name: str, entry: ScenarioFamily | str) -> ScenarioFamily:
    if isinstance(entry, ScenarioFamily):
        return entry
    module, _, attr = entry.partition(":")
    family = getattr(importlib.import_module(module), attr)()
    if not isinstance(family, ScenarioFamily) or family.name != name:
        raise ValueError(f"scenario family {name!r}: {entry!r} is not a ScenarioFamily named {name!r}")
    return family
