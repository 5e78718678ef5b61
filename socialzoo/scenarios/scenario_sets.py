"""Fixed lists of seeded benchmark scenarios: the registered test sets ("gdc1-test", ...) and each map's validation
set, apart from every test set (generated sets for other maps: socialzoo.bench.test_sets)."""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from socialzoo.core.validation import check_int
from socialzoo.maps.map_file import Map
from socialzoo.scenarios.generator import ScenarioConfig, generate_scenario
from socialzoo.scenarios.scenario import Scenario


@dataclass(frozen=True)
class TestSet:
    """A fixed list of seeded benchmark scenarios on one map.

    Scenario k has seed `seed(k)`, a 64-bit value derived from (base_seed, k) by numpy's
    SeedSequence, so it is the same on every machine, whether generated alone or in a list, and
    independent of every other scenario.

    Attributes:
        map_name: the map, as `load_map` names it (a shipped name or a map file's path).
        base_seed: the set's seed.
        count: number of scenarios.
        cfg: generator settings.
        name: the set's registry name, if any.
    """

    __test__: ClassVar[bool] = False  # not a pytest test class

    map_name: str
    base_seed: int
    count: int
    cfg: ScenarioConfig = field(default_factory=ScenarioConfig)
    name: str = ""

    def __post_init__(self) -> None:
        check_int("TestSet", "count", self.count, low=0)
        check_int("TestSet", "base_seed", self.base_seed, low=0)

    def __len__(self) -> int:
        return self.count

    def seed(self, k: int) -> int:
        """Seed of scenario k, 0 <= k < count."""
        if not 0 <= k < self.count:
            raise IndexError(
                f"test set {self.name or self.map_name!r}: scenario {k} is outside 0..{self.count - 1}"
            )
        return int(np.random.SeedSequence([self.base_seed, k]).generate_state(1, dtype=np.uint64)[0])

    def _map(self, m: Map | None) -> Map:
        if m is None:
            from socialzoo.maps import map_file as maps

            return maps.load_map(self.map_name)
        if self.map_name not in (m.name, m.path):
            raise ValueError(
                f"test set {self.name or self.map_name!r} is on map {self.map_name!r}, got map {m.name!r}"
            )
        return m

    def scenario(self, k: int, m: Map | None = None) -> Scenario:
        """Scenario k; loads the map by name unless `m` is given."""
        return generate_scenario(self._map(m), self.seed(k), self.cfg)

    def scenarios(self, indices: Sequence[int] | None = None, m: Map | None = None) -> list[Scenario]:
        """Scenarios at `indices` (default: all), each exactly as `scenario(k)` makes it."""
        m = self._map(m)
        ks = range(self.count) if indices is None else indices
        return [generate_scenario(m, self.seed(k), self.cfg) for k in ks]


TEST_SETS: dict[str, TestSet] = {
    "gdc1-test": TestSet("gdc1", 20220001, 2000, name="gdc1-test"),
    "ghc3-test": TestSet("ghc3", 20220002, 2000, name="ghc3-test"),
    "gdc1-quick": TestSet("gdc1", 20220003, 100, name="gdc1-quick"),
    "ghc3-quick": TestSet("ghc3", 20220004, 100, name="ghc3-quick"),
}


# Base seed of every map's validation scenarios: apart from every test set's, for choices
# (training lengths, settings, checkpoints) that must not look at a test set.
VALIDATION_BASE_SEED = 20_229_001
VALIDATION_SIZE = 1000


def validation_set(map_name: str) -> TestSet:
    """Our own validation scenarios on a map ("<map>-val", 1000 scenarios): never a test set."""
    return TestSet(map_name, VALIDATION_BASE_SEED, VALIDATION_SIZE, name=f"{map_name}-val")


# Base seeds and sizes of the test sets of maps without a registered one (any imported building): the
# benchmark stores their scenarios beside its results (socialzoo.bench.test_sets); a task plays them
# as its "test" split on such a map.
CUSTOM_TEST_SEED = 20220100
CUSTOM_QUICK_SEED = 20220101
CUSTOM_TEST_SIZE = 2000
CUSTOM_QUICK_SIZE = 100


def shipped_map(map_ref: str | Map) -> str | None:
    """The shipped map whose registered sets `map_ref` plays: a shipped map's name, or a Map or map
    file whose contents are that shipped map's (the same map_sha256: name, walls, graph, poses and the
    rest, so every set's scenarios are the same), wherever the file lies; None for any other map (an
    imported building, an edited or renamed copy of a shipped one) and a file that does not load."""
    from socialzoo.maps.map_file import MapError, list_maps, load_map

    if isinstance(map_ref, str):
        if map_ref in list_maps():
            return map_ref
        try:
            map_ref = load_map(map_ref)
        except (OSError, MapError):
            return None
    return _shipped_map_of(map_ref)


@functools.lru_cache(maxsize=16)
def _shipped_map_of(m: Map) -> str | None:
    # Keyed on the Map object (immutable; a file read again with the same text is the same object),
    # so a task asking at every reset hashes a map once.
    from socialzoo.maps.map_file import list_maps, load_map, map_sha256

    if m.name not in list_maps():
        return None
    shipped = load_map(m.name)
    return m.name if m is shipped or map_sha256(m) == map_sha256(shipped) else None


def map_case_sets(map_ref: str | Map) -> dict[str, TestSet]:
    """A map's fixed case sets, as both robot tasks and the benchmark split them: "val" (validation_set,
    never a test set), each registered test set of the map by its own name (e.g. "gdc1-quick"), and
    "test": the registered "<map>-test", else the generated set of a map without one (CUSTOM_TEST_SEED,
    the benchmark's for that map). A map file with a shipped map's contents has the shipped map's sets
    (shipped_map). The sets of any other map are keyed by its contents: named "<name>-<first 8 hex
    digits of its map_sha256>-val" (and "-test"), on the map's file (its reference, else the Map's
    path), so two maps of one name (two "floor.json" files, an edited copy still named "gdc1") never
    share a set, and a set's scenarios without a map given are its own map's (a file that does not load:
    its reference)."""
    shipped = shipped_map(map_ref)
    where = key = shipped or (map_ref if isinstance(map_ref, str) else map_ref.path or map_ref.name)
    if shipped is None:
        from socialzoo.maps.map_file import MapError, load_map, map_sha256

        try:
            m = load_map(map_ref) if isinstance(map_ref, str) else map_ref
            key = f"{m.name}-{map_sha256(m)[:8]}"
        except (OSError, MapError):  # no contents to key by: the reference itself
            pass
    sets = {"val": dataclasses.replace(validation_set(where), name=f"{key}-val")}
    registered = {k: v for k, v in TEST_SETS.items() if v.map_name == shipped}
    sets.update(registered)
    sets["test"] = registered.get(f"{key}-test") or TestSet(
        where, CUSTOM_TEST_SEED, CUSTOM_TEST_SIZE, name=f"{key}-test"
    )
    return sets


def evaluation_seeds(map_ref: str | Map) -> frozenset[int]:
    """The base seeds of every fixed set the map `map_ref` is validated or tested on: its map_case_sets,
    and the generated quick set of a map without a registered test set (socialzoo.bench.test_sets). A
    set of training scenarios on the map (demonstrations, DAgger's rollouts) must use none of them."""
    sets = map_case_sets(map_ref)
    seeds = {ts.base_seed for ts in sets.values()}
    if sets["test"].base_seed == CUSTOM_TEST_SEED:
        seeds.add(CUSTOM_QUICK_SEED)
    return frozenset(seeds)


def get_test_set(name: str) -> TestSet:
    """A named test set: "gdc1-test", "ghc3-test" (2000 each), "gdc1-quick", "ghc3-quick" (100 each).

    The quick sets have their own base seeds: they are not the first 100 of the full sets, so
    choosing checkpoints on a quick set does not look at the final test scenarios.
    """
    try:
        return TEST_SETS[name]
    except KeyError:
        raise KeyError(f"unknown test set {name!r}; known: {sorted(TEST_SETS)}") from None
