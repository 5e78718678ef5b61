"""The "finite number in range" checks shared by every config: what passes, and the messages."""

import math
from dataclasses import dataclass

import numpy as np
import pytest

from socialzoo.core.config import HumanConfig, LaserConfig, RobotConfig, WorldConfig
from socialzoo.core.validation import check_fields, check_int, check_number
from socialzoo.maps.map_file import MapError


@pytest.mark.parametrize(
    ("kwargs", "value"),
    [
        ({}, 0),
        ({}, -3.5),
        ({}, np.float64(2.0)),
        ({"low": 0}, 0.0),
        ({"low": 0, "low_open": True}, 1e-12),
        ({"low": 0, "high": 90}, 90),
        ({"high": 1, "high_open": True}, 0.999),
        ({"allow_none": True}, None),
    ],
)
def test_accepted_numbers_come_back_unchanged(kwargs, value):
    assert check_number("Cfg", "x", value, **kwargs) is value


@pytest.mark.parametrize(
    ("kwargs", "value", "message"),
    [
        ({}, math.nan, "Cfg.x must be a finite number, got nan"),
        ({}, math.inf, "Cfg.x must be a finite number, got inf"),
        ({}, True, "Cfg.x must be a finite number, got True"),
        ({}, "1.0", "Cfg.x must be a finite number, got '1.0'"),
        ({}, None, "Cfg.x must be a finite number, got None"),
        pytest.param({}, 10**400, f"Cfg.x must be a finite number, got {10**400}", id="int-beyond-float"),
        ({"allow_none": True}, "a", "Cfg.x must be a finite number or None, got 'a'"),
        ({"low": 0}, -0.5, "Cfg.x must be >= 0, got -0.5"),
        ({"low": 0.0, "low_open": True}, 0.0, "Cfg.x must be > 0.0, got 0.0"),
        ({"high": 360}, 361.0, "Cfg.x must be <= 360, got 361.0"),
        ({"high": 1, "high_open": True}, 1, "Cfg.x must be < 1, got 1"),
        ({"low": 0, "low_open": True, "high": 90}, 120.0, r"Cfg.x must be in (0, 90], got 120.0"),
        ({"low": 0, "high": 1, "high_open": True}, -1, r"Cfg.x must be in [0, 1), got -1"),
    ],
)
def test_refused_numbers_name_the_field_and_the_value(kwargs, value, message):
    with pytest.raises(ValueError) as err:
        check_number("Cfg", "x", value, **kwargs)
    assert str(err.value) == message


@pytest.mark.parametrize(
    ("kwargs", "value", "message"),
    [
        ({"low": 1}, 0, "Cfg.n must be an int >= 1, got 0"),
        ({"low": 1}, 2.0, "Cfg.n must be an int >= 1, got 2.0"),
        ({"low": 0}, True, "Cfg.n must be an int >= 0, got True"),
        ({"low": 0}, np.int64(3), f"Cfg.n must be an int >= 0, got {np.int64(3)!r}"),
        ({"low": 1, "high": 4}, 5, "Cfg.n must be an int in [1, 4], got 5"),
        ({"low": 0, "allow_none": True}, -1, "Cfg.n must be an int >= 0 or None, got -1"),
        ({}, "3", "Cfg.n must be an int, got '3'"),
    ],
)
def test_check_int(kwargs, value, message):
    with pytest.raises(ValueError) as err:
        check_int("Cfg", "n", value, **kwargs)
    assert str(err.value) == message
    assert check_int("Cfg", "n", 4, low=1, high=4) == 4
    assert check_int("Cfg", "n", None, allow_none=True) is None


def test_the_error_class_can_be_chosen():
    with pytest.raises(MapError, match=r"graph\.json: nodes\[2\]\.loc\.x must be a finite number, got None"):
        check_number("graph.json: nodes[2]", "loc.x", None, error=MapError)


@dataclass(frozen=True, kw_only=True)
class Sample:
    speed: float = 1.0
    margin: float = 0.0
    weight: float = -2.0
    count: int = 3
    name: str = "not a number"
    limit: float | None = None


def test_check_fields_positive_unless_listed():
    check_fields(Sample(), nonnegative=("margin",), signed=("weight",))
    with pytest.raises(ValueError, match=r"^Sample\.margin must be > 0, got 0\.0$"):
        check_fields(Sample(), signed=("weight",))
    with pytest.raises(ValueError, match=r"^Sample\.weight must be >= 0, got -2\.0$"):
        check_fields(Sample(), nonnegative=("margin", "weight"))
    with pytest.raises(ValueError, match=r"^Sample\.count must be an int >= 1, got 2\.5$"):
        check_fields(Sample(count=2.5), nonnegative=("margin",), signed=("weight",))
    with pytest.raises(ValueError, match=r"^Sample\.speed must be a finite number, got nan$"):
        check_fields(Sample(speed=math.nan), nonnegative=("margin",), signed=("weight",))
    with pytest.raises(TypeError, match="not number fields: \\['name', 'wieght'\\]"):
        check_fields(Sample(), signed=("wieght", "name"))


def test_check_fields_checks_an_optional_number_unless_none():
    lenient = {"nonnegative": ("margin",), "signed": ("weight",)}
    check_fields(Sample(limit=None), **lenient)
    check_fields(Sample(limit=0.5), **lenient)
    with pytest.raises(ValueError, match=r"^Sample\.limit must be > 0, got -1\.0$"):
        check_fields(Sample(limit=-1.0), **lenient)
    with pytest.raises(ValueError, match=r"^Sample\.limit must be a finite number or None, got 'x'$"):
        check_fields(Sample(limit="x"), **lenient)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: RobotConfig(length=0.0), r"RobotConfig\.length must be > 0, got 0\.0"),
        (lambda: HumanConfig(social_strength=-1.0), r"HumanConfig\.social_strength must be >= 0, got -1\.0"),
        (lambda: LaserConfig(num_rays=0), r"LaserConfig\.num_rays must be an int >= 1, got 0"),
        (lambda: LaserConfig(fov_deg=400.0), r"LaserConfig\.fov_deg must be <= 360, got 400\.0"),
        (lambda: WorldConfig(dt=math.inf), r"WorldConfig\.dt must be a finite number, got inf"),
    ],
)
def test_world_configs_use_it(build, message):
    with pytest.raises(ValueError, match=message):
        build()
    assert HumanConfig(social_strength=0.0).social_strength == 0.0
