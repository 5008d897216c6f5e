"""Generation safety: no code injection through emitted configs; the validator accepts only what builds; bounded input."""

from __future__ import annotations

import json

import pytest

from legged_gente.terrain.soil import SOIL_PRESETS
from legged_gente.generation.emit import emit, load_module
from legged_gente.generation.spec import TerrainSpec
from legged_gente.generation.validation import (
    MAX_MESSAGE_CHARS,
    ToolCall,
    ValidationError,
    validate_call,
)
from legged_gente.terrain.composition import MAX_ABS_HEIGHT, MAX_CALLS


# ------------------------------------------------------------------------------------------- code injection
PAYLOADS = [
    '"""\nimport pathlib; pathlib.Path(MARKER).write_text("pwned")\n"""',
    "'''\nimport pathlib; pathlib.Path(MARKER).write_text('pwned')\n'''",
    'x\\"""; __import__("pathlib").Path(MARKER).write_text("pwned") #',
    "back\\slash\\\nnewline\r\n\"quote' \x00 \u2028 end",
]


@pytest.mark.parametrize("payload", PAYLOADS)
def test_emitted_module_escapes_model_and_backend(tmp_path, payload):
    marker = tmp_path / "marker.txt"
    payload = payload.replace("MARKER", repr(str(marker)))
    spec = TerrainSpec([ToolCall("flat", {"height": 0.1}, "full", "set")], name="inj", size_x=2.0, size_y=2.0,
                       backend=payload, model=payload, source={"text": payload}).validated()
    out = emit(spec, tmp_path / "out", mesh="obj")  # mesh= imports the module
    module = load_module(out.module)
    assert not marker.exists()
    assert module.PROVENANCE == {"backend": payload, "model": payload, "source": payload[:200]}
    assert TerrainSpec.load(out.spec).model == payload


def test_emit_rejects_a_base_that_is_not_a_dotted_name(tmp_path):
    spec = TerrainSpec([ToolCall("flat", {"height": 0.1}, "full", "set")], size_x=2.0, size_y=2.0)
    with pytest.raises(ValueError, match="must look like"):
        emit(spec, tmp_path, base="os; import sys:Cfg")


# ------------------------------------------------------------------------------------ validator == builder
@pytest.mark.parametrize("tool, args, expected", [
    ("rocks", {"min_radius": 0.8, "max_radius": 0.2}, "min_radius=0.8 must not exceed max_radius=0.2"),
    ("pillars", {"min_radius": 0.9, "max_radius": 0.3}, "min_radius=0.9 must not exceed max_radius=0.3"),
    ("discrete_obstacles", {"min_size": 2.0, "max_size": 0.5}, "min_size=2.0 must not exceed max_size=0.5"),
    ("river", {"width": 2.0, "bank_width": 1.5}, "bank_width=1.5 m exceeds half the width"),
])
def test_cross_field_rules_reject_what_the_builder_cannot_build(tool, args, expected):
    with pytest.raises(ValidationError, match=expected):
        validate_call(tool, {**args, "region": "full"})
    # the builder applies the same rule (one place: the registry), with the same message
    with pytest.raises(ValueError, match=expected):
        TerrainSpec([ToolCall(tool, args, "full", "set")]).build()


def test_unregistered_soil_preset_is_rejected(monkeypatch):
    monkeypatch.delitem(SOIL_PRESETS, "custom", raising=False)
    with pytest.raises(ValidationError, match="preset 'custom' is not registered"):
        validate_call("soil", {"preset": "custom", "region": "full"})


def test_region_smaller_than_a_cell_is_rejected():
    thin = {"x0": 1.01, "y0": 1.0, "x1": 1.06, "y1": 3.0}  # 5 cm between the cells at x = 1.0 and x = 1.1
    validate_call("flat", {"height": 0.1, "region": thin})  # without a resolution only the geometry is checked
    with pytest.raises(ValidationError, match="holds no cell at resolution 0.1"):
        validate_call("flat", {"height": 0.1, "region": thin}, resolution=0.1)
    doc = TerrainSpec([]).to_dict()
    doc["calls"] = [{"tool": "flat", "region": thin, "mode": "set", "params": {"height": 0.1}}]
    with pytest.raises(ValidationError, match="holds no cell"):
        TerrainSpec.from_dict(doc)


def test_stacked_heights_above_the_bound_are_rejected_where_they_stack():
    up = {"tool": "flat", "mode": "add", "params": {"height": 2.0}}
    doc = TerrainSpec([]).to_dict()
    # six 2 m layers on one quadrant: 12 m > 10 m
    doc["calls"] = [dict(up, region="front_left") for _ in range(6)]
    with pytest.raises(ValidationError, match=f"reach 12.00 m > {MAX_ABS_HEIGHT}"):
        TerrainSpec.from_dict(doc)
    # the same six layers over three rectangles 1 m apart (more than the 0.3 m seam band) stack to 4 m at most
    rects = [{"x0": x, "y0": 2.0, "x1": x + 4.0, "y1": 6.0} for x in (1.0, 6.0, 11.0)]
    doc["calls"] = [dict(up, region=r) for r in rects] * 2
    heights, _ = TerrainSpec.from_dict(doc).build()
    assert heights.max() == pytest.approx(4.0)


# ------------------------------------------------------------------------------------------- input limits
def _spec_file(tmp_path, text):
    path = tmp_path / "spec.json"
    path.write_text(text)
    return path


def test_spec_file_with_nan_or_huge_numbers_is_a_validation_error(tmp_path):
    doc = TerrainSpec([ToolCall("flat", {"height": 0.1}, "full", "set")]).to_dict()
    text = json.dumps(doc)
    with pytest.raises(ValidationError, match="NaN is not a number JSON allows"):
        TerrainSpec.load(_spec_file(tmp_path, text.replace('"size_x": 20.0', '"size_x": NaN')))
    with pytest.raises(ValidationError, match=r"integer of more than 4300 digits; use a number below 2\*\*53"):
        TerrainSpec.load(_spec_file(tmp_path, text.replace('"seed": 0', '"seed": 1' + "0" * 5000)))
    with pytest.raises(ValidationError, match="nested too deeply|not valid JSON"):
        TerrainSpec.load(_spec_file(tmp_path, "[" * 100_000 + "]" * 100_000))
    doc["size_x"] = float("nan")  # a dict built in Python
    with pytest.raises(ValidationError, match="size_x must be finite"):
        TerrainSpec.from_dict(doc)


def test_huge_tiles_and_many_calls_are_rejected_before_building():
    doc = TerrainSpec([], size_x=200.0, size_y=200.0, resolution=0.02).to_dict()
    with pytest.raises(ValidationError, match="100000000 cells; the limit is"):
        TerrainSpec.from_dict(doc)
    doc = TerrainSpec([ToolCall("flat", {"height": 0.0}, "full", "set")] * (MAX_CALLS + 1)).to_dict()
    with pytest.raises(ValidationError, match=f"field 'calls' has {MAX_CALLS + 1} items; at most {MAX_CALLS}"):
        TerrainSpec.from_dict(doc)
    doc = TerrainSpec([], size_x=20.05).to_dict()
    with pytest.raises(ValidationError, match="not a whole number of 0.1 m cells"):
        TerrainSpec.from_dict(doc)


@pytest.mark.parametrize("arguments, expected", [
    ('{"region": "full", "height": 1' + "0" * 5000 + "}", "integer of more than 4300 digits"),
    ('{"region": "full", "height": ' + "[" * 100_000 + "]" * 100_000 + "}", "200030 characters long"),
    ('{"region": "full", "height": ' + "[" * 7000 + "]" * 7000 + "}", "nested too deeply"),
    ('{"region": "full", "height": ' + "[" * 50 + "]" * 50 + "}", "nested more than"),
    ('{"region": "full", "height": NaN}', "NaN is not a number JSON allows"),
    ({"region": "full", "height": 10**400}, "integer of 401 digits"),
    ({"region": "full", "height": float("nan")}, "height must be finite"),
    ({"region": "x" * 1_000_000}, "string of 1000000 characters"),
    ('{"region": "' + "x" * 1_000_000 + '"}', "characters long; the limit is"),
    ({"region": "full", "y" * 1_000_000: 1}, "unexpected argument"),
])
def test_tool_call_input_limits(arguments, expected):
    with pytest.raises(ValidationError, match=expected) as info:
        validate_call("flat", arguments)
    assert all(len(m) <= MAX_MESSAGE_CHARS for m in info.value.messages)


def test_unknown_tool_of_any_type_is_a_validation_error():
    for tool in ("x" * 1_000_000, None, 3, ["flat"], object()):
        with pytest.raises(ValidationError, match="unknown tool") as info:
            validate_call(tool, {"region": "full"})
        assert len(str(info.value)) < 1000
