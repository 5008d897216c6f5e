"""Tool schemas derived from a registry, and their jsonschema validation (incl. 1,000 hypothesis calls)."""

from __future__ import annotations

import json
import math

import jsonschema
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from legged_gente.generation.spec import TerrainSpec
from legged_gente.generation.tools import named_regions, tool_schemas
from legged_gente.generation.validation import ToolCall, ValidationError, validate_call
from legged_gente.terrain.registry import AtomicTerrain, Param


def _fn(shape, resolution, rng, **kw):
    return np.zeros(shape, np.float32)


REGISTRY = {
    "t_steps": AtomicTerrain(
        "t_steps", "geometric", "test steps",
        {
            "step_height": Param(0.1, "rise of one step", "m", 0.0, 0.3),
            "num_steps": Param(4, "number of steps", "1", 1, 20, integer=True),
            "direction": Param("up", "up or down", "", choices=("up", "down")),
        },
        _fn,
    ),
    "t_mud": AtomicTerrain("t_mud", "physical", "test mud", {"depth": Param(0.1, "mud depth", "m", 0.0, 0.5)}, _fn),
}


def test_schema_shape():
    tools = {t["function"]["name"]: t for t in tool_schemas(20.0, 10.0, REGISTRY)}
    assert sorted(tools) == ["t_mud", "t_steps"]
    p = tools["t_steps"]["function"]["parameters"]
    jsonschema.Draft202012Validator.check_schema(p)
    assert p["additionalProperties"] is False and p["required"] == ["region"]
    assert (p["properties"]["step_height"]["minimum"], p["properties"]["step_height"]["maximum"]) == (0.0, 0.3)
    assert "[m]" in p["properties"]["step_height"]["description"]
    assert p["properties"]["num_steps"]["type"] == "integer"
    assert p["properties"]["direction"]["enum"] == ["up", "down"]
    assert p["properties"]["mode"]["enum"] == ["set", "add"]
    assert "mode" not in tools["t_mud"]["function"]["parameters"]["properties"]
    rect = p["properties"]["region"]["oneOf"][1]["properties"]
    assert rect["x1"]["maximum"] == 20.0 and rect["y1"]["maximum"] == 10.0
    assert tools["t_mud"]["function"]["description"].startswith("Physical")


def test_named_regions():
    r = named_regions(20.0, 10.0)
    assert r["full"] == (0.0, 0.0, 20.0, 10.0)
    assert r["front"] == (10.0, 0.0, 20.0, 10.0) and r["left"] == (0.0, 5.0, 20.0, 10.0)
    assert r["front_left"] == (10.0, 5.0, 20.0, 10.0)


def test_valid_call_fills_defaults():
    c = validate_call("t_steps", json.dumps({"step_height": 0.2, "region": "back", "mode": "add"}), registry=REGISTRY)
    assert c == ToolCall("t_steps", {"step_height": 0.2, "num_steps": 4, "direction": "up"}, "back", "add")
    assert validate_call(c.tool, c.arguments(), registry=REGISTRY) == c


@pytest.mark.parametrize(
    "tool, args, expected",
    [
        ("t_nope", {"region": "full"}, r"unknown tool \"t_nope\"; available tools are \['t_mud', 't_steps'\]"),
        ("t_steps", {"step_height": 0.5, "region": "full"}, r"t_steps: argument 'step_height'=0.5 is outside the allowed range \[0.0, 0.3\]"),
        ("t_steps", {"step_height": "high", "region": "full"}, r"t_steps: argument 'step_height'=\"high\" has the wrong type; expected a number"),
        ("t_steps", {"num_steps": 2.5, "region": "full"}, r"argument 'num_steps'=2.5 has the wrong type; expected a whole number"),
        ("t_steps", {"direction": "sideways", "region": "full"}, r"argument 'direction'=\"sideways\" is not one of \['up', 'down'\]"),
        ("t_steps", {"step_height": 0.1}, r"t_steps: missing required argument 'region'"),
        ("t_steps", {"region": "full", "colour": "red"}, r"t_steps: unexpected argument\(s\) \['colour'\]; allowed arguments are"),
        ("t_mud", {"region": "full", "mode": "add"}, r"t_mud: unexpected argument\(s\) \['mode'\]"),
        ("t_steps", {"region": "middle"}, r"argument 'region'=\"middle\" is not one of \['full', 'front'"),
        ("t_steps", {"region": {"x0": 0, "y0": 0, "x1": 25, "y1": 5}}, r"argument 'region.x1'=25 is outside the allowed range \[0.0, 20.0\]"),
        ("t_steps", {"region": {"x0": 5, "y0": 2, "x1": 5, "y1": 4}}, r"argument 'region' rectangle has x0=5 >= x1=5, so it has zero area"),
        ("t_steps", {"region": {"x0": 0, "y0": 0, "x1": 5}}, r"missing required argument 'region.y1'"),
        ("t_steps", {"region": 3}, r"argument 'region'=3 is neither a region name nor a rectangle"),
        ("t_steps", {"step_height": float("nan"), "region": "full"}, r"t_steps: step_height must be finite"),
        ("t_steps", "{not json", r"t_steps: arguments are not valid JSON"),
        ("t_steps", [1, 2], r"t_steps: arguments must be a JSON object"),
    ],
)
def test_precise_rejections(tool, args, expected):
    with pytest.raises(ValidationError, match=expected):
        validate_call(tool, args, 20.0, 10.0, registry=REGISTRY)


def test_all_problems_reported_together():
    with pytest.raises(ValidationError) as exc:
        validate_call("t_steps", {"step_height": -1, "num_steps": 99, "bogus": 1}, registry=REGISTRY)
    assert len(exc.value.messages) == 4  # extra arg, missing region, two ranges


json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-10**6, 10**6) | st.floats(allow_nan=True, allow_infinity=True) | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=6), inner, max_size=3),
    max_leaves=6,
)
regions = (
    st.sampled_from(["full", "front", "back_left", "middle", ""])
    | st.fixed_dictionaries({k: st.floats(-5, 30) | st.integers(-5, 30) for k in ("x0", "y0", "x1", "y1")})
    | json_values
)
param_values = st.floats(-1, 25) | st.integers(-2, 30) | st.sampled_from(["up", "down", "left"]) | json_values
arguments = st.dictionaries(
    st.sampled_from(["step_height", "num_steps", "direction", "depth", "region", "mode", "extra"]),
    param_values | regions | st.sampled_from(["set", "add", "multiply"]),
    max_size=6,
)


@settings(max_examples=1000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(tool=st.sampled_from(["t_steps", "t_mud", "t_other"]) | st.text(max_size=5), args=arguments | json_values)
def test_random_calls_never_crash(tool, args):
    as_json = isinstance(args, dict) and len(args) % 2 == 0  # half of them go through the JSON-string path
    try:
        call = validate_call(tool, json.dumps(args) if as_json else args, 20.0, 10.0, registry=REGISTRY)
    except ValidationError as exc:
        assert exc.messages and all(isinstance(m, str) and len(m) > 15 for m in exc.messages)
        assert all(m.startswith(f"{tool}: ") or m.startswith("unknown tool") for m in exc.messages), exc.messages
        return
    terrain = REGISTRY[call.tool]
    assert terrain.check_params(call.params) == call.params
    x0, y0, x1, y1 = call.rect(20.0, 10.0)
    assert 0 <= x0 < x1 <= 20.0 and 0 <= y0 < y1 <= 10.0
    assert all(not isinstance(v, float) or math.isfinite(v) for v in call.params.values())


@pytest.mark.parametrize("name", ["forest_trail\n", "forest\ntrail"])
def test_a_spec_name_may_not_hold_a_newline(name):
    document = TerrainSpec(calls=[], name=name).to_dict()
    with pytest.raises(ValidationError) as exc:
        TerrainSpec.from_dict(document)
    # what the name must be, not the schema's regular expression
    assert exc.value.messages == [f"spec: field 'name': {name!r} is not a letter, then letters, digits or "
                                  f"underscores, e.g. forest_trail."]
