"""The spec path by hand: the checker looks at the cells the builder and the spawn search use; emitted modules
give back the class they name."""

from __future__ import annotations

import json

import numpy as np
import pytest

from legged_gente.generation.checker import check_spec
from legged_gente.generation.emit import emit, load_module
from legged_gente.generation.spec import TerrainSpec
from legged_gente.generation.validation import ToolCall


def _doc(calls, resolution=0.1, **extra):
    return {"version": 1, "name": "t", "size_x": 20.0, "size_y": 20.0, "resolution": resolution, "seed": 0,
            "calls": calls, "source": {}, "backend": "planner", "model": None, **extra}


def test_checker_sees_a_feature_on_the_cells_its_region_holds(tmp_path):
    # Region.cells: the cells at i * 0.1 m with x0 <= x < x1. Soil on x in [0.15, 0.25) m lies on the one cell
    # at x = 0.2 m (index 2); rounding 0.15 / 0.1 and 0.25 / 0.1 half-to-even gives the empty window [2, 2).
    soil = {"tool": "soil", "region": {"x0": 0.15, "y0": 0.0, "x1": 0.25, "y1": 20.0}, "params": {"preset": "mud"}}
    path = tmp_path / "spec.json"
    path.write_text(json.dumps(_doc([soil])))
    _, material = TerrainSpec.load(path).build()
    assert material.has_soil()[2].all() and not material.has_soil()[[1, 3]].any()  # the builder's one cell
    result = check_spec(path, names=("mud",))
    assert result.required == ["soil"]
    assert not [p for p in result.problems if p.startswith("missing")]


def test_checker_judges_the_spawn_patch_the_spawn_search_chose(tmp_path):
    # At 0.2 m cells the spawn footprint is 2 * round(1.0 m / (2 * 0.2 m)) + 1 = 2 * round(2.5) + 1 = 5 cells
    # (Terrain._spawn_origins; Python rounds half to even). A ground of 0.1 m ridges on every other row and column
    # is flat nowhere but on one 5 x 5 patch at cells 49..53: the spawn search picks that patch (range 0 m), so
    # the spawn is traversable. The 1.0 m around its centre (10.2 m +- 0.5 m) would reach cells 48..54: ridges.
    i = np.arange(100)
    units = 10 * ((i[:, None] % 2) | (i[None, :] % 2)).astype(np.int16)  # 0 or 10 units of 0.01 m
    units[49:54, 49:54] = 0
    np.save(tmp_path / "ground.npy", units)
    path = tmp_path / "spec.json"
    path.write_text(json.dumps(_doc([], resolution=0.2, heightmap={"file": "ground.npy", "vertical_scale": 0.01})))
    result = check_spec(path)
    assert result.spawn_xy == pytest.approx((51 * 0.2, 51 * 0.2))  # the patch's centre cell
    assert not [p for p in result.problems if p.startswith("untraversable")]


@pytest.mark.parametrize("class_name", ["build", "SPEC_PATH", "PROVENANCE", "Path", "__debug__", "ﬁeldTerrainCfg"])
def test_emit_refuses_a_class_name_the_module_cannot_give_back(tmp_path, class_name):
    # The module binds Path, SPEC_PATH, PROVENANCE and build itself (a class of that name is lost or breaks
    # build()); Python refuses to bind __debug__; it reads the ligature "ﬁ" as "fi" (NFKC), so no attribute holds
    # the name asked for. Each is refused before anything is written, or the module gives the class back.
    spec = TerrainSpec([ToolCall("flat", {"height": 0.1}, "full")], name="t", size_x=2.0, size_y=2.0)
    try:
        out = emit(spec, tmp_path / "o", class_name=class_name)
    except ValueError as exc:
        assert "is not a name" in str(exc) and "\n" not in str(exc)
        assert not (tmp_path / "o").exists()
        return
    module = load_module(out.module)
    cls = getattr(module, out.class_name)
    assert isinstance(cls, type) and cls.terrain_length == 2.0
    heights, _ = module.build()
    assert np.allclose(heights, 0.1)


ODD = ['"""', "'''", "\\", "\\'", "a\nb\r\nc", "\u2028\u2029\x85", "\x00\x1b[2J", "\ud800", "{class_name}", "\u202e",
       "é漢🙂", "' + __import__('os').system('x') + '"]


def test_emitted_module_and_spec_give_back_every_odd_string_and_number(tmp_path):
    text = "".join(ODD)
    calls = [ToolCall("flat", {"height": -1.5}, (0.0, 0.0, 1.0, 2.0), "set"),
             ToolCall("water", {"depth": 1e-3, "flow": "current", "speed": 0.25, "direction": -3.0, "omega": 0.5,
                                "phase": 0.0}, "front", None)]
    spec = TerrainSpec(calls, name="odd", size_x=2.0, size_y=2.0, resolution=0.02, seed=2**32 - 1, backend=text,
                       model=text, source={"text": text, "nested": {"k\n'": [1.25, -0.0, 2**53, None, True]}})
    out = emit(spec, tmp_path / "o")
    module = load_module(out.module)  # imports: every string was written as a literal
    assert module.PROVENANCE == {"backend": text, "model": text, "source": text}  # under 200 characters: whole
    cls = getattr(module, "OddTerrainCfg")
    assert (cls.terrain_length, cls.terrain_width, cls.resolution) == (2.0, 2.0, 0.02)
    loaded = TerrainSpec.load(module.SPEC_PATH)
    assert loaded == spec.validated() and loaded.to_json() == out.spec.read_text(encoding="utf-8")
    assert loaded.source["nested"] == {"k\n'": [1.25, -0.0, 2**53, None, True]} and loaded.seed == 2**32 - 1
    heights, material = module.build()
    assert np.allclose(heights[:50, :100], -1.5)  # the flat call's cells, x < 1 m


def test_a_recipe_too_tall_for_a_large_tile_names_a_fix_the_user_can_make():
    # The stairs recipe rises 0.12 m every 0.35 m; over a 100 m tile that is far beyond the 10 m height bound, and
    # the planner's user cannot change the recipe's step_height or region: the fix to name is a smaller tile.
    from legged_gente.generation.backends.planner import plan_text
    from legged_gente.generation.validation import ValidationError

    assert 100.0 / 2 / 0.35 * 0.12 > 10.0  # half the tile's treads alone pass the bound
    with pytest.raises(ValidationError) as info:
        plan_text("stairs", 100.0, 100.0)
    (message,) = info.value.messages
    # the fix first: a long reason may be cut at MAX_MESSAGE_CHARS, the fix is not
    assert message.startswith("planner cue 'stairs' does not fit on a 100 m x 100 m tile: ask for a smaller tile, or "
                              "write the calls yourself in a spec (") and "\n" not in message


def test_every_recipe_with_every_modifier_plans_a_spec_that_loads_on_the_default_tile():
    # What the planner's error above relies on: on the default 20 m tile no recipe fails validation.
    from legged_gente.generation.backends.planner import CUES, MODIFIERS, plan_text

    for cue in CUES:
        for modifier in (None, *(m for m in MODIFIERS if m.applies_to(cue))):
            text = cue.keywords[0] if modifier is None else f"{modifier.keywords[0]} {cue.keywords[0]}"
            TerrainSpec(plan_text(text).calls, name="t").validated()


@pytest.mark.parametrize("content, expected", [
    ('{"items": [{"text": "a beach", "labels": [["sand"]]}]}', "item 0 has unknown label(s)"),  # a list is no label
    ('{"items": [', "texts.json is not valid JSON"),
])
def test_a_malformed_evaluation_set_is_a_one_line_error(tmp_path, capsys, content, expected):
    from legged_gente.generation.score import main

    (tmp_path / "texts.json").write_text(content)
    assert main(["--set", str(tmp_path), "--kind", "text"]) == 2
    err = capsys.readouterr().err
    assert expected in err and err.count("\n") == 1


def test_a_negation_word_negates_cues_and_nouns_alike():
    # "avoid" negates a cue ("hills, avoid the river" builds no river), so it negates a noun too: "avoid sand"
    # removes the beach's sand as "without sand" does.
    from legged_gente.generation.backends.planner import plan_text

    assert [c.tool for c in plan_text("hills, avoid the river").calls] == ["hills"]
    presets = lambda text: [c.params.get("preset") for c in plan_text(text).calls if c.tool == "soil"]  # noqa: E731
    assert presets("a beach without sand") == []
    assert presets("a beach, avoid sand") == []
