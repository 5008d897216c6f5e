"""A call whose feature is finer than the tile's cells is refused wherever the resolution is known: the builder
samples heights at cell points, so a tread, gap, stone, pit or rock smaller than the rule's span can fall between
them and vanish (or merge with its neighbour)."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage
from test_generation_openai import FakeServer, _completion, _tool_call, ok

from legged_gente.generation.backends.image import plan_image
from legged_gente.generation.backends.openai_backend import OpenAIBackend
from legged_gente.generation.backends.planner import plan_text
from legged_gente.generation.pipeline import generate_spec
from legged_gente.generation.spec import TerrainSpec
from legged_gente.generation.validation import ToolCall, ValidationError, validate_call
from legged_gente.terrain.registry import ATOMIC_TERRAINS

EVAL_SET = Path(__file__).resolve().parents[1] / "legged_gente" / "benchmarks" / "generation_eval"


def _build(tool, shape, resolution, seed=0, **params):
    terrain = ATOMIC_TERRAINS[tool]
    return terrain.fn(shape, resolution, np.random.default_rng(seed), **terrain.check_params(params))


# ------------------------------------------------------------------------------- the defects the rules prevent
def test_a_tread_narrower_than_a_cell_merges_two_risers():
    """Every riser of a 0.1 m step is one step high while the tread is at least a cell; a 0.15 m tread at 0.2 m
    puts two risers between neighbouring cells (a 0.2 m step). One half of the flight, many region sizes."""
    def tallest_riser(step_width, resolution):
        risers = [np.abs(np.diff(_build("stairs", (n, 1), resolution, step_height=0.1, step_width=step_width,
                                         platform=platform)[n // 2 + 1:, 0])).max()
                  for n in range(20, 60) for platform in (0.0, 0.3, 1.2, 1.25)]
        return max(risers)

    assert tallest_riser(0.15, 0.2) == pytest.approx(0.2, abs=1e-6)
    assert tallest_riser(0.2, 0.2) == pytest.approx(0.1, abs=1e-6)
    assert tallest_riser(0.15, 0.1) == pytest.approx(0.1, abs=1e-6)


def test_a_gap_narrower_than_a_cell_joins_stepping_stones():
    """0.6 m stones hold 6 or 7 cells of 0.1 m along x; with 0.05 m gaps (the curriculum's easiest level) some gap
    holds no cell point and two stones become one run of 12+ cells, with 0.1 m gaps never (50 layouts each)."""
    def longest_stone(stone_distance, seed):
        h = _build("stepping_stones", (100, 100), 0.1, seed, stone_size=0.6, stone_distance=stone_distance,
                   depth=0.5, height_noise=0.0, platform=0.0)
        on_stone = (h > -0.5).any(axis=1)
        return max(len(run) for run in np.split(on_stone, np.flatnonzero(np.diff(on_stone)) + 1) if run[0])

    assert all(longest_stone(0.05, seed) >= 12 for seed in range(50))
    assert all(longest_stone(0.1, seed) <= 7 for seed in range(50))


def test_a_rock_under_half_a_cell_diagonal_can_vanish():
    """A rock shows only if a cell point lies strictly inside its radius rho. At rho = resolution / 2 the discs
    around the four corners of a cell cover pi * rho^2 / resolution^2 = pi / 4 of it: 1 - pi / 4 = 21.5 % of the
    rocks vanish. From rho = resolution / sqrt(2) every point of a cell is that close to a corner: none vanish.
    500 rocks on 100 m x 100 m (overlaps and the tile's far edge are negligible)."""
    def share_missing(radius):
        h = _build("rocks", (1000, 1000), 0.1, 3, max_height=0.2, min_radius=radius, max_radius=radius,
                   density=0.05, platform=0.0)
        return 1.0 - ndimage.label(h > 0)[1] / 500

    expected = 1.0 - math.pi / 4.0
    assert share_missing(0.05) == pytest.approx(expected, abs=4 * math.sqrt(expected * (1 - expected) / 500))
    assert share_missing(0.1 / math.sqrt(2) + 1e-4) < 0.01


# --------------------------------------------------------------------------------------------------- the rules
RULES = [
    # tool, params, resolution, the refused parameter, the allowed values, a finer resolution that accepts it
    ("stairs", {"step_width": 0.15}, 0.2, "step_width=0.15 m", "step_width >= 0.2 m", "0.15 m"),
    ("pyramid_stairs", {"step_width": 0.3}, 0.5, "step_width=0.3 m", "step_width >= 0.5 m", "0.3 m"),
    ("stepping_stones", {"stone_distance": 0.05}, 0.1, "stone_distance=0.05 m", "stone_distance 0 or >= 0.1 m", "0.05 m"),
    ("stepping_stones", {"stone_size": 0.3, "stone_distance": 0.0}, 0.4, "stone_size=0.3 m", "stone_size >= 0.4 m", "0.3 m"),
    ("gap", {"gap_width": 0.05}, 0.1, "gap_width=0.05 m", "gap_width 0 or >= 0.1 m", "0.05 m"),
    ("gap", {"platform": 0.5, "gap_width": 1.0}, 1.0, "platform=0.5 m", "platform >= 1 m", "0.5 m"),
    ("pit", {"width": 0.5}, 0.5, "width=0.5 m", "width > 0.5 m", "below 0.5 m"),
    ("discrete_obstacles", {"min_size": 0.1}, 0.2, "min_size=0.1 m", "min_size >= 0.2 m", "0.1 m"),
    ("rocks", {"min_radius": 0.05}, 0.1, "min_radius=0.05 m", "min_radius >= 0.0708 m", "0.0707 m"),
    ("river", {"width": 0.5, "bank_width": 0.2}, 0.5, "width=0.5 m", "width > 0.5 m", "below 0.5 m"),
    ("waves", {"wavelength": 0.5}, 0.25, "wavelength=0.5 m", "wavelength > 0.5 m", "below 0.25 m"),
]


@pytest.mark.parametrize("tool, params, resolution, named, allowed, finer", RULES)
def test_a_feature_finer_than_the_grid_is_refused_in_one_line(tool, params, resolution, named, allowed, finer):
    args = {**params, "region": "full"}
    validate_call(tool, args)  # without a resolution the parameters alone decide
    with pytest.raises(ValidationError) as info:
        validate_call(tool, args, resolution=resolution)
    (message,) = info.value.messages
    assert message.startswith(f"{tool}: {named} ") and "\n" not in message
    assert f"{resolution:g} m" in message and f"use {allowed}" in message and f"--resolution {finer}" in message
    finer_resolution = float(finer.split()[-2]) * (0.999 if finer.startswith("below") else 1.0)
    validate_call(tool, args, resolution=finer_resolution)


@pytest.mark.parametrize("tool, params, resolution", [
    ("stairs", {"step_width": 0.2}, 0.2),  # a tread of exactly one cell keeps every riser
    ("stepping_stones", {"stone_distance": 0.0}, 0.1),  # touching stones: no gap to lose
    ("stepping_stones", {"stone_distance": 0.1}, 0.1),
    ("gap", {"gap_width": 0.0}, 0.1),
    ("pit", {"width": 0.51}, 0.5),
    ("rocks", {"min_radius": 0.0708}, 0.1),
    ("waves", {"wavelength": 0.51}, 0.25),
    ("pillars", {"min_radius": 0.03, "max_radius": 0.03}, 0.1),  # the builder fills the cell nearest the axis
])
def test_a_feature_the_grid_holds_is_accepted(tool, params, resolution):
    validate_call(tool, {**params, "region": "full"}, resolution=resolution)


def test_no_finer_resolution_is_suggested_below_the_finest_a_spec_allows():
    with pytest.raises(ValidationError) as info:
        validate_call("stepping_stones", {"stone_distance": 0.01, "region": "full"}, resolution=0.1)
    assert info.value.messages[0].endswith("; use stone_distance 0 or >= 0.1 m.")  # --resolution stops at 0.02 m


def test_every_problem_of_a_call_is_reported_together():
    with pytest.raises(ValidationError) as info:
        validate_call("stepping_stones", {"stone_size": 0.3, "stone_distance": 0.1, "region": "full"}, resolution=0.4)
    assert [m.split("=")[0] for m in info.value.messages] == ["stepping_stones: stone_size", "stepping_stones: stone_distance"]


# ----------------------------------------------------------------------------- every path that knows the cells
def test_a_spec_is_checked_at_its_own_resolution(tmp_path):
    calls = [ToolCall("stairs", {"step_width": 0.15}, "full")]
    TerrainSpec(calls, resolution=0.1).validated()
    path = TerrainSpec(calls, resolution=0.2).save(tmp_path / "spec.json")
    with pytest.raises(ValidationError, match=r"spec.json: spec: calls\[0\]: stairs: step_width=0\.15 m .*0\.2 m cell"):
        TerrainSpec.load(path)


def test_the_openai_backend_sends_a_sub_cell_call_back_to_the_model():
    narrow = _completion([_tool_call("stairs", {"step_width": 0.15, "region": "full", "mode": "set"}, 0)])
    wide = _completion([_tool_call("stairs", {"step_width": 0.3, "region": "full", "mode": "set"}, 1)])
    with FakeServer([ok(narrow), ok(wide)]) as srv:
        result = OpenAIBackend(srv.url, "test-model", timeout=5.0, resolution=0.2).generate(text="stairs")
    assert [c.params["step_width"] for c in result.calls] == [0.3]
    (answer,) = [m["content"] for m in srv.requests[1]["messages"] if m["role"] == "tool"]
    assert "REJECTED" in answer and "step_width=0.15 m" in answer and "step_width >= 0.2 m" in answer


def test_the_planners_are_checked_at_the_tile_resolution():
    """The planners' rocks (min_radius 0.1 m) need cells of at most 0.1 * sqrt(2) m: at 0.2 m the text planner's
    spec and the image planner's skip the call with a warning naming the fix, keeping the rest."""
    assert "rocks" in [c.tool for c in generate_spec("a rocky field", resolution=0.1)[0].calls]
    spec, result = generate_spec("a rocky field", resolution=0.2)
    assert "rocks" not in [c.tool for c in spec.calls] and spec.calls
    assert [w for w in result.warnings
            if re.match(r"skipped: planner cue '\w+': rocks: min_radius=0\.1 m .* 0\.2 m cell .*--resolution 0\.1414 m", w)]
    photo = EVAL_SET / "photos" / "18_rubble.png"
    assert "rocks" in [c.tool for c in plan_image(photo, resolution=0.1).calls]
    coarse = plan_image(photo, resolution=0.2)
    assert "rocks" not in [c.tool for c in coarse.calls] and coarse.calls
    assert [w for w in coarse.warnings if w.startswith("skipped: rocks: min_radius=0.1 m")]
    TerrainSpec(coarse.calls, resolution=0.2).validated()


def test_the_planners_outputs_on_the_evaluation_set_hold_at_0_1_m():
    texts = json.loads((EVAL_SET / "texts.json").read_text())["items"]
    for item in texts:
        TerrainSpec(plan_text(item["text"]).calls, resolution=0.1).validated()
    for item in json.loads((EVAL_SET / "photos" / "manifest.json").read_text())["items"]:
        result = plan_image(EVAL_SET / "photos" / item["file"], resolution=0.1)
        assert not [w for w in result.warnings if w.startswith("skipped")], item["file"]
