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


def test_numpy_float_scalars_are_numbers_and_their_nan_is_null():
    record = {"a": np.float32(0.5), "b": np.float32("nan"), "c": [np.float16("-inf"), np.int64(3)]}
    text = json_text(record, default=int)
    assert json.loads(text, parse_constant=pytest.fail) == {"a": 0.5, "b": None, "c": [None, 3]}


def test_a_nan_that_a_converter_returns_is_refused():
    class Reading:
        """A value json cannot write, which the converter turns into NaN."""

    with pytest.raises(ValueError, match="not JSON compliant"):
        json_text({"x": Reading()}, default=lambda v: math.nan)
