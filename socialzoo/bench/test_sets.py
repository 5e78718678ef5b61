"""Test sets for maps without a registered one (any imported building): generated on first use, stored beside the
results with the map's hash, and reused so that reruns are comparable. A scenario family's validation cases too."""

from __future__ import annotations

import dataclasses
import json
import logging
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from socialzoo.core.files import read_json, write_text_atomic
from socialzoo.maps.map_file import Map, load_map, map_sha256
from socialzoo.scenarios.catalogue import get_family
from socialzoo.scenarios.generator import ScenarioConfig, generate_scenario
from socialzoo.scenarios.scenario import Scenario, ScenarioError
from socialzoo.scenarios.scenario_sets import (
    CUSTOM_QUICK_SEED,
    CUSTOM_QUICK_SIZE,
    CUSTOM_TEST_SEED,
    CUSTOM_TEST_SIZE,
    VALIDATION_BASE_SEED,
    VALIDATION_SIZE,
    TestSet,
)

logger = logging.getLogger(__name__)

TEST_SET_FORMAT = "socialzoo-testset/1"
TEST_SET_DIR = "test_sets"


class TestSetError(ValueError):
    """A stored test set file that cannot be used: unreadable, of another kind, or made on another
    version of the map; the message names the file."""

    __test__ = False  # not a pytest test class, despite its name


@dataclass(frozen=True)
class StoredTestSet(TestSet):
    """A TestSet whose scenarios were generated once and stored: `scenario(k)` reads them back.

    Attributes:
        stored: the first len(stored) scenarios of the set, as generated.
    """

    stored: tuple[Scenario, ...] = field(default=(), compare=False, repr=False)

    def scenario(self, k: int, m: Map | None = None) -> Scenario:
        """Scenario k as stored (generated from seed(k) when beyond the stored ones)."""
        if 0 <= k < len(self.stored):
            return self.stored[k]
        return generate_scenario(m if m is not None else load_map(self.map_name), self.seed(k), self.cfg)


@dataclass(frozen=True)
class FamilyCases(TestSet):
    """A scenario family's validation cases on a map as a TestSet, the cases the action-selection task
    plays as its "val" split with config.family (ActionSelectionTask.case_splits): case k is the family's
    scenario of its "val" split's seed k, or for a family without seed splits of the map's validation seed
    k (base_seed and count: validation_set's). Made by family_validation_set.

    Attributes:
        family: the scenario family's registered name.
    """

    family: str = ""

    def seed(self, k: int) -> int:
        """Seed of case k, 0 <= k < count."""
        splits = get_family(self.family).splits
        if not splits:
            return super().seed(k)
        if not 0 <= k < self.count:
            raise IndexError(f"test set {self.name!r}: case {k} is outside 0..{self.count - 1}")
        return get_family(self.family).case_seed("val", k)

    def scenario(self, k: int, m: Map | None = None) -> Scenario:
        """Case k: the family's scenario of seed(k), on `m` (default: the set's map)."""
        from socialzoo.env.scenario_source import ScenarioStream

        m = self._map(m)
        return ScenarioStream(m, 1, 1, self.cfg, self.family).make(self.seed(k))

    def scenarios(self, indices: Sequence[int] | None = None, m: Map | None = None) -> list[Scenario]:
        """Cases at `indices` (default: all), each as `scenario(k)` makes it."""
        m = self._map(m)
        return [self.scenario(k, m) for k in (range(self.count) if indices is None else indices)]


def family_validation_size(family: str) -> int:
    """The cases of the action-selection task's "val" split with scenario family `family`: its own
    "val" split's, or the map's validation set's for a family without seed splits (0: none)."""
    splits = get_family(family).splits
    if not splits:
        return VALIDATION_SIZE
    return int(splits["val"].size or 0) if "val" in splits else 0


def family_validation_set(family: str, map_name: str) -> FamilyCases:
    """Family `family`'s validation cases on map `map_name` ("<family>-val"; FamilyCases), which a run
    trained on the family is chosen on, as the checkpoint evaluator (socialzoo.train.validation) does.

    Raises:
        ValueError: an unknown family.
    """
    return FamilyCases(
        map_name, VALIDATION_BASE_SEED, family_validation_size(family), name=f"{family}-val", family=family
    )


def stored_set_name(map_ref: str, quick: bool = False) -> str:
    """The name of the test set stored_test_set keeps for a map: its name field, then -test or -quick
    (two map files of one name share it). Raises as load_map does."""
    return f"{load_map(map_ref).name}-{'quick' if quick else 'test'}"


def stored_test_set(
    map_ref: str, out_dir: str | Path, trials: int | None, quick: bool = False
) -> StoredTestSet:
    """The test set of a map without a registered one, read from (or written to) out_dir.

    The file is DIR/test_sets/<map name>-test.json (or -quick): the map's sha256, the set's base
    seed and scenario settings, and every scenario generated so far, exactly (socialzoo-scenario/1).
    A rerun reads the scenarios back instead of generating them, so later changes to the generator
    cannot change them; a run that needs more scenarios generates the next ones (scenario k always
    has seed TestSet.seed(k)) and appends them. A map whose contents changed since is refused.

    Args:
        map_ref: a shipped map name or a map JSON path, as the benchmark names it.
        out_dir: the benchmark's output directory; the set lives in out_dir/test_sets/.
        trials: scenarios needed (None: the whole set, 2000, or 100 with quick).
        quick: the quick set (its own base seed and size).

    Returns:
        The set with at least `trials` scenarios stored; its map_name is `map_ref`, so that
        workers load the same map.

    Raises:
        TestSetError: (a ValueError) the stored file belongs to another version of the map (its
            hash differs), or is not a test set file (random bytes, a truncated file, a file of
            another kind or a folder included); the message names the file.
        ValueError: trials exceeds the set's size.
        FileNotFoundError, MapError: the map cannot be loaded.
    """
    m = load_map(map_ref)
    size = CUSTOM_QUICK_SIZE if quick else CUSTOM_TEST_SIZE
    need = size if trials is None else trials
    if need > size:
        raise ValueError(f"{need} trials asked on map {map_ref!r}, but its generated test set holds {size}")
    name = stored_set_name(map_ref, quick)
    path = Path(out_dir) / TEST_SET_DIR / f"{name}.json"
    digest = map_sha256(m)
    cfg = ScenarioConfig()
    base = TestSet(map_ref, CUSTOM_QUICK_SEED if quick else CUSTOM_TEST_SEED, size, cfg=cfg, name=name)
    scenarios: list[Scenario] = []
    if path.exists():  # a folder there too: _read refuses it, where writing would end in a traceback
        scenarios = _read(path, digest, base)
    if len(scenarios) < need:
        logger.info("%s: generating scenarios %d..%d", name, len(scenarios), need - 1)
        scenarios += [generate_scenario(m, base.seed(k), cfg) for k in range(len(scenarios), need)]
        _write(path, base, m, digest, scenarios)
    return StoredTestSet(
        base.map_name, base.base_seed, base.count, base.cfg, base.name, stored=tuple(scenarios)
    )


def _read(path: Path, digest: str, base: TestSet) -> list[Scenario]:
    data = read_json(path, "test set file", TestSetError, kind=dict)
    if data.get("format") != TEST_SET_FORMAT:
        raise TestSetError(f"{path}: not a {TEST_SET_FORMAT} file")
    if data.get("map_sha256") != digest:
        raise TestSetError(
            f"{path}: this test set was generated on map {data.get('map')!r} with sha256 "
            f"{str(data.get('map_sha256'))[:12]}..., but the map now has sha256 {digest[:12]}...: results "
            "would not be comparable; use another --out directory (or delete the file to start afresh)"
        )
    if data.get("base_seed") != base.base_seed or data.get("scenario") != dataclasses.asdict(base.cfg):
        raise TestSetError(
            f"{path}: stored with base seed {data.get('base_seed')} and scenario settings "
            f"{data.get('scenario')}, which differ from this version's; use another --out directory"
        )
    stored = data.get("scenarios", [])
    if not isinstance(stored, list):
        raise TestSetError(f"{path}: 'scenarios' must be a list, got {type(stored).__name__}")
    try:
        return [Scenario.from_json(s, f"{path}: scenarios[{k}]") for k, s in enumerate(stored)]
    except ScenarioError as err:
        raise TestSetError(str(err)) from None


def _write(path: Path, base: TestSet, m: Map, digest: str, scenarios: list[Scenario]) -> None:
    data: dict[str, Any] = {
        "format": TEST_SET_FORMAT,
        "name": base.name,
        "map": base.map_name,
        "map_name": m.name,
        "map_sha256": digest,
        "base_seed": base.base_seed,
        "size": base.count,
        "scenario": dataclasses.asdict(base.cfg),
        "scenarios": [s.to_json() for s in scenarios],
    }
    write_text_atomic(path, json.dumps(data, separators=(",", ":")) + "\n")
