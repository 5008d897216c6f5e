"""Spec documents and emitted folders: what the validator accepts is what training reads and builds."""

from __future__ import annotations

import json

import numpy as np
import pytest

from legged_gente.generation.emit import emit, load_module
from legged_gente.generation.gente_compat import heightmap_spec
from legged_gente.generation.spec import TerrainSpec
from legged_gente.generation.validation import ToolCall, ValidationError
from legged_gente.terrain.composition import tile_spec_from_document


def _doc(calls):
    return {"version": 1, "name": "t", "size_x": 20.0, "size_y": 20.0, "resolution": 0.1, "seed": 0, "calls": calls,
            "source": {}, "backend": "planner", "model": None}


@pytest.mark.parametrize("key", ["mode", "region"])
def test_layout_arguments_inside_params_are_refused(key, tmp_path):
    # Training reads a spec file with tile_spec_from_document: the params would go to the terrain function as they
    # are, where a 'mode' or 'region' among them does not build; both readers refuse it with the same advice.
    call = {"tool": "flat", "region": "back", "params": {"height": 0.2, key: "add" if key == "mode" else "front"}}
    doc = _doc([{"tool": "flat", "region": "full", "params": {"height": 0.5}}, call])
    with pytest.raises(ValueError) as refused:
        tile_spec_from_document(doc)
    assert str(refused.value) == (f"terrain spec: calls[1]: 'params' holds the layout argument(s) ['{key}']; put "
                                  f"'region' and 'mode' beside 'params', not in it")
    path = tmp_path / "spec.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(ValidationError) as info:
        TerrainSpec.load(path)
    assert info.value.messages == [f"{path}: spec: calls[1]: 'params' holds the layout argument(s) ['{key}']; put "
                                   f"'region' and 'mode' beside 'params', not in it."]


def test_an_emitted_heightmap_spec_rebuilds_from_its_folder(tmp_path):
    ground = tmp_path / "gente"
    ground.mkdir()
    np.save(ground / "array.npy", (np.random.default_rng(0).random((200, 200)) * 100).astype(np.int16))
    spec = heightmap_spec("array.npy", "gente_map", ground)  # relative to the folder the spec came from
    expected = spec.build()[0]
    out = emit(spec, tmp_path / "out")
    assert TerrainSpec.load(out.spec).heightmap["file"] == "heightmap.npy"  # a copy beside spec.json
    moved = tmp_path / "moved"
    (tmp_path / "out").rename(moved)  # the folder stands alone: moved, and with the map it came from gone
    (ground / "array.npy").unlink()
    heights, _ = load_module(moved / "terrain_cfg.py").build()
    assert np.array_equal(heights, expected)


@pytest.mark.parametrize("change, message", [
    ({"model": "m" * 300}, "field 'model' has 300 characters; at most 256 are allowed"),
    ({"size_x": float("inf")}, "size_x"),
    ({"source": {"image_sha256": 5}}, None),  # a hand-edited provenance is written as text
])
def test_emit_writes_only_a_spec_that_loads(tmp_path, change, message):
    spec = TerrainSpec([ToolCall("flat", {"height": 0.0}, "full")], name="t", **change)
    if message is None:
        out = emit(spec, tmp_path / "o")
        assert TerrainSpec.load(out.spec).source == {"image_sha256": 5}
        return
    with pytest.raises(ValidationError, match=message):
        emit(spec, tmp_path / "o")
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("class_name", ["class", "None", "1Cfg", "a-b"])
def test_emit_refuses_a_class_name_python_cannot_define(tmp_path, class_name):
    spec = TerrainSpec([ToolCall("flat", {"height": 0.0}, "full")], name="t")
    with pytest.raises(ValueError, match="is not a name Python can give a class"):
        emit(spec, tmp_path / "o", class_name=class_name)


def test_emit_refuses_an_unknown_mesh_format_before_writing(tmp_path):
    spec = TerrainSpec([ToolCall("flat", {"height": 0.0}, "full")], name="t")
    with pytest.raises(ValueError, match=r"mesh format '\.\./\.\./x\.obj' is none of \['obj', 'glb', 'ply', 'stl'\]"):
        emit(spec, tmp_path / "o", mesh="../../x.obj")
    assert not (tmp_path / "o").exists()


def test_checker_does_not_call_a_heightmap_without_calls_empty(tmp_path):
    from legged_gente.generation.checker import check_spec

    rows = np.arange(200)[:, None] * np.ones(200)
    np.save(tmp_path / "array.npy", (20 * np.sin(rows / 10)).astype(np.int16))  # +-0.1 m waves, no call on them
    spec = heightmap_spec("array.npy", "waves", tmp_path)
    path = spec.save(tmp_path / "spec.json")
    assert not [p for p in check_spec(path).problems if p.startswith("empty")]
    np.save(tmp_path / "array.npy", np.zeros((200, 200), np.int16))  # flat: empty, calls or not
    assert [p for p in check_spec(path).problems if p.startswith("empty")]


def test_an_integer_too_long_for_python_is_named_without_python_s_advice():
    """A model's (or a file's) 5000-digit integer: Python's parser refuses it and advises sys.set_int_max_str_digits,
    which is no fix for the model; the refusal asks for a number below 2**53."""
    from legged_gente.generation.validation import ValidationError, parse_json

    with pytest.raises(ValidationError) as error:
        parse_json('{"height": 1' + "0" * 5000 + "}", "the arguments", 1_000_000)
    (message,) = error.value.messages
    assert message == "the arguments hold an integer of more than 4300 digits; use a number below 2**53."
