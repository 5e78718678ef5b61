"""Records written as strict JSON (socialzoo.core.files)."""

import json
import math

import numpy as np
import pytest

from socialzoo.core.files import json_text, write_json


def test_numbers_json_has_no_word_for_are_written_as_null(tmp_path):
    record = {"a": math.nan, "b": [1.5, -math.inf, (np.float64("nan"), 2)], "c": {"d": math.inf, "e": "NaN"}}
    expected = {"a": None, "b": [1.5, None, [None, 2]], "c": {"d": None, "e": "NaN"}}
    assert json.loads(json_text(record), parse_constant=pytest.fail) == expected
    write_json(tmp_path / "r.json", record)
    assert json.loads((tmp_path / "r.json").read_text(), parse_constant=pytest.fail) == expected
    assert not list(tmp_path.glob("*.tmp"))


def test_a_nan_that_a_converter_returns_is_refused():
    with pytest.raises(ValueError, match="not JSON compliant"):
        json_text({"x": np.float32(1)}, default=lambda v: math.nan)
