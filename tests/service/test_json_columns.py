"""The JSON codec of PostgreSQL's columns (service.json_columns): non-finite floats survive, nothing else changes."""
from __future__ import annotations

import json
import math

from service import json_columns


def test_finite_json_is_plain_json():
    value = {"a": [1.0, 2, "NaN", None, True], "b": {"c": "Infinity"}}
    assert json_columns.dumps(value) == json.dumps(value)
    assert json_columns.loads(json_columns.dumps(value)) == value


def test_non_finite_floats_are_written_without_nan_tokens_and_read_back():
    value = {"curve": [1.0, math.nan, math.inf, -math.inf], "nested": {"fit": (math.nan,)}}
    text = json_columns.dumps(value)
    json.loads(text, parse_constant=lambda token: (_ for _ in ()).throw(ValueError(token)))  # no NaN token
    back = json_columns.loads(text.encode())  # the driver may hand bytes
    assert back["curve"][0] == 1.0 and math.isnan(back["curve"][1]) and back["curve"][2:] == [math.inf, -math.inf]
    assert math.isnan(back["nested"]["fit"][0])


def test_an_object_that_only_resembles_the_marker_is_kept():
    value = {"x": {json_columns.MARKER: "zero"}, "y": {json_columns.MARKER: "NaN", "other": 1}, "z": math.nan}
    back = json_columns.loads(json_columns.dumps(value))
    assert back["x"] == value["x"] and back["y"] == value["y"] and math.isnan(back["z"])
