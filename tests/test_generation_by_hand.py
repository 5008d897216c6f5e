"""Generation checked by hand: GenTe's calls against what GenTe's own code builds, the scorer's thresholds, and the
tool schemas against the terrain's parameters.

GenTe facts below are read from its terrain functions (github.com/HaronW/GenTe, utils/terrain_utils_single.py and
terrain_utils_parts.py, commit 60ceed6): a 200 x 200 grid of 0.1 m cells, int16 heights of 0.005 m.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from legged_gente.generation.gente_compat import translate_call
from legged_gente.generation.score import features, load_items, main
from legged_gente.generation.spec import TerrainSpec
from legged_gente.generation.tools import tool_schemas
from legged_gente.generation.validation import ValidationError, validate_call
from legged_gente.terrain.registry import ATOMIC_TERRAINS


def _build(translation):
    heights, _ = TerrainSpec(calls=translation.calls, name="gente").build()
    return heights.astype(np.float64)


# ------------------------------------------------------------------------------------------------ GenTe calls
def test_gente_uniform_roughness_finer_than_its_step_is_not_flattened():
    # GenTe random_uniform_terrain(min_height=-0.05, max_height=0.05), step left at its default 1:
    #   min = int(-0.05 / 0.005) = -10, max = 10, step = int(1 / 0.1) = 10 units
    #   heights drawn from np.arange(-10, 10 + 10, 10) = [-10, 0, 10] units = {-0.05, 0, 0.05} m
    # so GenTe's ground is rough by +-0.05 m; the translation must not build it flat.
    t = translate_call("random_uniform_terrain", {"min_height": -0.05, "max_height": 0.05}, "single")
    assert not t.blocked
    heights = _build(t)
    assert heights.max() - heights.min() > 0.05  # cells spaced 0.1 m, a node per cell: close to the full 0.1 m
    assert heights.min() >= -0.05 - 1e-6 and heights.max() <= 0.05 + 1e-6
    assert [i.kind for i in t.issues] == ["simplified"]


def test_gente_uniform_step_finer_than_the_amplitude_is_kept():
    # min 0, max 0.2, step 1 -> 0.05 m levels; amplitude 0.1 m > 0.05 m: our quantum keeps some relief, so it stays
    _, uni = translate_call("random_uniform_terrain", {"min_height": 0.0, "max_height": 0.2, "part": 1}).calls
    assert uni.params["step"] == pytest.approx(0.05)


def test_gente_pyramid_sloped_edges_stay_at_zero():
    # GenTe pyramid_sloped_terrain(slope=0.2, platform_size=2) on the 200-cell tile:
    #   xx = (100 - |100 - i|) / 100 is 0 on the edge rows i = 0, so height = max_height * xx * yy = 0 there;
    #   along the centre column (yy = 1) the height rises 0.2 m per m, (max_height = 0.2 * 20 * 100 units = 10 m).
    t = translate_call("pyramid_sloped_terrain", {"slope": 0.2, "platform_size": 2.0}, "single")
    heights = _build(t)
    half_cell_of_slope = 0.2 * 0.05  # our cell points sit half a cell inside the edge
    assert abs(heights[0, 100]) <= half_cell_of_slope + 1e-4
    assert abs(heights[199, 100]) <= half_cell_of_slope + 1e-4
    assert heights[20, 100] - heights[10, 100] == pytest.approx(0.2 * 1.0, abs=1e-4)  # 10 cells of 0.1 m on the flank


def test_gente_pyramid_sloped_platform_defaults_to_gentes_one_metre():
    # GenTe: def pyramid_sloped_terrain(terrain, slope=0.2, platform_size=1.)
    (_, pyr) = translate_call("pyramid_sloped_terrain", {"slope": 0.1, "part": 1}).calls
    assert pyr.params["platform"] == 1.0
    # sloped_terrain has no platform: peak slope * (5 + 5) m on a 10 m part, as before
    flat, pyr = translate_call("sloped_terrain", {"slope": 0.1, "part": 1}).calls
    assert flat.params["height"] == pytest.approx(1.0) and pyr.params["platform"] == 0.0


def test_gente_discrete_obstacles_clear_no_platform():
    # GenTe's discrete_obstacles_terrain computes platform_size = int(platform_size / 0.1) and never uses it:
    # its blocks may cover the centre
    t = translate_call("discrete_obstacles_terrain", {"max_height": 0.2, "min_size": 0.5, "max_size": 1.0,
                                                      "num_rects": 20, "platform_size": 3.0, "part": 2})
    assert t.calls[0].params["platform"] == 0.0
    assert [i.kind for i in t.issues] == ["ignored_argument"] and "platform_size=3.0" in t.issues[0].message
    default = translate_call("discrete_obstacles_terrain", {"max_height": 0.2, "min_size": 0.5, "max_size": 1.0,
                                                            "num_rects": 20, "part": 2})
    assert default.calls[0].params["platform"] == 0.0 and not default.issues


def test_gente_flat_ground_adds_its_height_in_its_part():
    # GenTe part 4: x = w2 = 100, y = l2 = 100 -> height_field_raw[100:200, 100:200] += int(0.3 / 0.005) = 60 units
    heights = _build(translate_call("flat_ground_terrain", {"height": 0.3, "part": 4}))
    assert heights[150, 150] == pytest.approx(0.3) and heights[50, 50] == 0.0 and heights[150, 50] == 0.0


def test_gente_waves_wavelength_and_amplitude():
    # GenTe wave_terrain(num_waves=2, amplitude=0.2), single: div = 200 / (2 * 2 pi) cells; cos(y / div) has a
    # period of 2 pi div = 100 cells = 10 m; each axis' wave has amplitude int(0.5 * 0.2 / 0.005) = 20 units = 0.1 m
    (w,) = translate_call("wave_terrain", {"num_waves": 2, "amplitude": 0.2}, "single").calls
    assert w.params["wavelength"] == pytest.approx(10.0) and w.params["amplitude"] == pytest.approx(0.2)
    heights = _build(translate_call("wave_terrain", {"num_waves": 2, "amplitude": 0.2}, "single"))
    assert heights.max() <= 0.2 + 1e-6 and heights.max() > 0.19  # both axes' crests meet: 0.1 + 0.1 m


# ------------------------------------------------------------------------------------------------------- score
def _call(tool, region="full", **args):
    return validate_call(tool, {"region": region, **args})


@pytest.mark.parametrize("call, expected", [
    (lambda: _call("pillars", height=0.3), {"tall"}),  # TALL = 0.3 m is tall
    (lambda: _call("rocks", max_height=0.29), {"low"}),
    (lambda: _call("rocks", max_height=0.3), {"tall"}),
    (lambda: _call("rocks", max_height=0.2, density=0.0), set()),  # no rocks
    (lambda: _call("low_friction", preset="custom", mu=0.15), set()),  # ice is mu < 0.15
    (lambda: _call("low_friction", preset="custom", mu=0.14), {"ice"}),
    (lambda: _call("pyramid_slope", slope=0.05), {"slope"}),
    (lambda: _call("pyramid_slope", slope=0.04), set()),
    (lambda: _call("hills", amplitude=0.3), {"slope"}),
    (lambda: _call("random_uniform", amplitude=0.02), {"rough"}),
    (lambda: _call("random_uniform", amplitude=0.019), set()),
    (lambda: _call("water", depth=0.0), set()),  # no water
    (lambda: _call("water", depth=0.3, flow="tide", speed=0.2), {"water", "flowing"}),
    # a raised block: 10 m x 10 m is a quarter of the 20 m x 20 m tile (< half): tall
    (lambda: _call("flat", "back_left", height=0.3), {"tall"}),
    # 10 m x 20 m is exactly half: the ground raised, not an obstacle
    (lambda: _call("flat", "back", height=0.5), set()),
])
def test_features_at_their_thresholds(call, expected):
    assert features([call()]) == expected


@pytest.mark.parametrize("item", [{"text": "a beach"}, "a beach", {"text": "a beach", "labels": "sand"}])
def test_an_item_without_a_labels_list_is_a_one_line_error(tmp_path, capsys, item):
    (tmp_path / "texts.json").write_text(json.dumps({"items": [item]}))
    with pytest.raises(ValueError, match=r"texts.json: item 0 has no 'labels' list"):
        load_items(tmp_path, "text")
    assert main(["--set", str(tmp_path), "--kind", "text"]) == 2
    assert "item 0 has no 'labels' list" in capsys.readouterr().err


def test_an_item_without_its_text_or_file_is_a_one_line_error(tmp_path):
    (tmp_path / "texts.json").write_text(json.dumps({"items": [{"labels": ["sand"]}]}))
    with pytest.raises(ValueError, match=r"texts.json: item 0 has no 'text'"):
        load_items(tmp_path, "text")
    (tmp_path / "photos").mkdir()
    (tmp_path / "photos" / "manifest.json").write_text(json.dumps({"items": [{"labels": ["sand"]}]}))
    with pytest.raises(ValueError, match=r"manifest.json: item 0 has no 'file'"):
        load_items(tmp_path, "photo")


# ------------------------------------------------------------------------------------- schemas vs the builder
def test_schema_bounds_are_the_parameters_and_the_validator_holds_them():
    """Every numeric parameter offered to a model has the terrain's own range and default; a bound passes validation
    and the builder's check, and a value just beyond it is refused by both (never clamped)."""
    schemas = {t["function"]["name"]: t["function"]["parameters"]["properties"] for t in tool_schemas()}
    for name, terrain in ATOMIC_TERRAINS.items():
        for pname, p in terrain.params.items():
            prop = schemas[name][pname]
            assert prop["default"] == p.default, (name, pname)
            if p.choices is not None:
                continue
            assert (prop.get("minimum"), prop.get("maximum")) == (p.low, p.high), (name, pname)
            assert prop["type"] == ("integer" if p.integer else "number")
            for bound, beyond in ((p.low, p.low - 1e-6 * max(1.0, abs(p.low))),
                                  (p.high, p.high + 1e-6 * max(1.0, abs(p.high)))):
                if beyond != beyond or (p.integer and bound is None):
                    continue
                with pytest.raises(ValidationError):
                    validate_call(name, {"region": "full", pname: beyond})
                with pytest.raises(ValueError):
                    terrain.check_params({pname: beyond})
                try:  # the bound itself: refused only by a cross-field rule (min <= max, the river's banks)
                    call = validate_call(name, {"region": "full", pname: bound})
                except ValidationError as exc:
                    rules = ("must not exceed", "exceeds half the width", "can make |height| reach",  # the third: a
                             "is not above step",  # flight over the whole tile; the fourth: flat roughness
                             "steeper than 45 degrees to the axis",  # meanders too tight for their wavelength
                             "has no effect on still water")  # a speed with the default flow, still
                    assert any(r in str(exc) for r in rules), (name, pname, str(exc))
                    continue
                assert call.params[pname] == bound, (name, pname)  # kept as sent, never moved
