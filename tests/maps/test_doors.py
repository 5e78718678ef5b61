"""The map format's optional doors: read, validated, written only when present, round-tripped."""

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from socialzoo.maps.map_file import MapError, load_map, map_from_json, validate_map

MAPS_DIR = Path(__file__).resolve().parents[2] / "maps"


def _room_with(doors):
    data = load_map("open_room").to_json()
    data["doors"] = doors
    return data


def test_a_map_without_doors_has_none_and_writes_none():
    m = load_map("hallway")
    assert m.doors.shape == (0, 4) and m.num_doors == 0
    assert "doors" not in m.to_json()


@pytest.mark.parametrize("name", ["hallway", "doorway"])
def test_shipped_files_round_trip_byte_for_byte(tmp_path, name):
    m = load_map(name)
    copy = m.save(tmp_path / f"{name}.json")
    assert copy.read_bytes() == (MAPS_DIR / f"{name}.json").read_bytes()


def test_doors_round_trip(tmp_path):
    path = tmp_path / "room.json"
    path.write_text(json.dumps(_room_with([[0, 4, 0, 5], [10, 2.5, 10, 3.75]])))
    m = load_map(path)
    np.testing.assert_array_equal(m.doors, [[0, 4, 0, 5], [10, 2.5, 10, 3.75]])
    assert not m.doors.flags.writeable
    again = load_map(m.save(tmp_path / "copy.json"))
    np.testing.assert_array_equal(again.doors, m.doors)
    assert again.to_json() == m.to_json()


@pytest.mark.parametrize(
    ("doors", "message"),
    [
        ("door", "doors must be a list"),
        ([[0, 4, 0, 5], [10, 2, 10]], r"doors\[1\]: expected 4 numbers"),
        ([[0, 4, 0, 5], [10, 2, "x", 3]], r"doors\[1\]: expected 4 numbers"),
        ([[0, 4, 0, 5], [10, 2, True, 3]], r"doors\[1\]: expected 4 numbers"),
        ([[0, 4, 0, 5], [10, 2, float("nan"), 3]], r"doors\[1\]: coordinate is NaN"),
        ([[0, 4, 0, 5], [10, 2, float("inf"), 3]], r"doors\[1\]: coordinate is inf"),
        ([[0, 4, 0, 5], [10, 2, 10, 2]], r"doors\[1\]: zero length"),
    ],
)
def test_a_malformed_door_is_named(tmp_path, doors, message):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(_room_with(doors)))
    with pytest.raises(MapError, match=message) as err:
        load_map(path)
    assert str(err.value).startswith(str(path))


def test_validate_map_checks_doors_made_in_code():
    m = map_from_json(load_map("open_room").to_json(), "room.json")
    validate_map(dataclasses.replace(m, doors=np.array([[0.0, 4.0, 0.0, 5.0]])))
    with pytest.raises(MapError, match=r"room.json: doors\[0\]: zero length"):
        validate_map(dataclasses.replace(m, doors=np.array([[1.0, 1.0, 1.0, 1.0]])))
    with pytest.raises(MapError, match=r"doors\[0\]: coordinate is NaN"):
        validate_map(dataclasses.replace(m, doors=np.array([[np.nan, 1.0, 1.0, 1.0]])))
    with pytest.raises(MapError, match=r"doors must be a numeric array of shape \(n, 4\)"):
        validate_map(dataclasses.replace(m, doors=np.array([[1.0, 1.0, 2.0]])))
