"""Water lies in ground that holds it: the `basin` terrain, the checker's water-wall rule, and the planner's and the
image reader's water, each on prompts and pictures of this file's own (no evaluation item).

A *water wall* is a wet cell beside a dry cell of the tile whose ground lies below the wet cell's water surface:
water standing up against nothing, which would run off.
"""

import numpy as np
import pytest
from PIL import Image, ImageDraw
from scipy import ndimage

from legged_gente.generation.backends.image import LEGEND
from legged_gente.generation.backends.planner import FREEBOARD
from legged_gente.generation.checker import WATER_WALL_TOLERANCE, check_spec
from legged_gente.generation.pipeline import generate_spec
from legged_gente.generation.spec import TerrainSpec
from legged_gente.generation.validation import ToolCall
from legged_gente.terrain.registry import ATOMIC_TERRAINS

RES = 0.1


def basin(params, shape):
    a = ATOMIC_TERRAINS["basin"]
    return a.fn(shape, RES, np.random.default_rng(0), **a.check_params(params)).astype(np.float64)


def worst_wall(heights, material) -> float:
    """Largest height (m) by which a wet cell's surface stands above the ground of a dry 4-neighbour in the tile."""
    wet, surface = material.has_water(), material.water_surface
    worst = 0.0
    for a, b in ((np.s_[:-1, :], np.s_[1:, :]), (np.s_[1:, :], np.s_[:-1, :]),
                 (np.s_[:, :-1], np.s_[:, 1:]), (np.s_[:, 1:], np.s_[:, :-1])):
        drop = np.where(wet[a] & ~wet[b], surface[a] - heights[b], 0.0)
        worst = max(worst, float(drop.max()))
    return worst


# ------------------------------------------------------------------------------------------------ basin
def test_basin_falls_from_its_edges_by_a_smoothstep_to_a_flat_bottom():
    """41 x 61 cells of 0.1 m: x = -2..2 m, y = -3..3 m; the edge cells are 0 m from the rectangle's edge.
    depth 0.4 m, shore 1.0 m: h = -0.4 (3t^2 - 2t^3), t = (distance to the nearest edge) / 1.0 m.
    Edge: 0. 0.5 m in (t = 0.5): 3/4 - 1/4 = 1/2 -> -0.2 m. 0.2 m in: 3*0.04 - 2*0.008 = 0.104 -> -0.0416 m.
    1 m in and beyond (the bottom, the centre): -0.4 m."""
    h = basin({"depth": 0.4, "shore_width": 1.0}, (41, 61))
    assert h[0, 30] == pytest.approx(0.0, abs=1e-6) and h[20, 0] == pytest.approx(0.0, abs=1e-6)
    assert h[5, 30] == pytest.approx(-0.2, abs=1e-6) and h[20, 55] == pytest.approx(-0.2, abs=1e-6)
    assert h[2, 30] == pytest.approx(-0.0416, abs=1e-6)
    assert h[20, 30] == pytest.approx(-0.4, abs=1e-6) and h[10, 10] == pytest.approx(-0.4, abs=1e-6)
    # a corner cell 0.5 m in along x but 0.2 m in along y is 0.2 m from its nearest edge
    assert h[5, 2] == pytest.approx(-0.0416, abs=1e-6)


def test_a_narrow_basin_narrows_its_shore_so_the_bottom_still_lies_depth_down():
    """11 cells across x (x = -0.5..0.5 m) under a 1.0 m shore: the shore narrows to half the side, 0.5 m, so the
    centre line is at -depth and 0.25 m in (t = 0.5) at -depth / 2."""
    h = basin({"depth": 0.3, "shore_width": 1.0}, (11, 61))
    assert h[5, 30] == pytest.approx(-0.3, abs=1e-6)
    # x = -0.3 m (cell 2) is 0.2 m in: t = 0.4, 3*0.16 - 2*0.064 = 0.352 -> -0.1056 m
    assert h[2, 30] == pytest.approx(-0.1056, abs=1e-6)


def test_basin_is_a_registered_tool_with_declared_bounds_and_difficulty():
    a = ATOMIC_TERRAINS["basin"]
    assert a.kind == "geometric"
    p = a.check_params({"depth": 0.7})
    assert a.height_bounds(p, 8.0, 8.0) == (-0.7, 0.0)
    assert a.params_for_difficulty(0.0)["depth"] < a.params_for_difficulty(1.0)["depth"]
    with pytest.raises(ValueError, match="shore_width"):
        a.check_params({"shore_width": 0.0})


# ------------------------------------------------------------------------------------------ checker rule
def _spec(calls, tmp_path, name):
    spec = TerrainSpec(calls=calls, name=name, size_x=8.0, size_y=8.0, resolution=RES, seed=0)
    return spec.save(tmp_path / f"{name}.json")


def _call(tool, region, mode="set", **params):
    return ToolCall(tool, ATOMIC_TERRAINS[tool].check_params(params), region,
                    mode if ATOMIC_TERRAINS[tool].kind == "geometric" else None)


def test_water_on_flat_ground_is_a_water_wall(tmp_path):
    """Water 0.3 m deep on flat ground at 0 m: its surface is 0 + 0.3 m, every cell of its rectangle is wet, and
    the dry ground just outside lies 0.3 m below the surface: a 0.300 m wall."""
    path = _spec([_call("flat", "full", height=0.0), _call("water", (5.0, 0.0, 8.0, 4.0), depth=0.3)], tmp_path, "wall")
    walls = [p for p in check_spec(path).problems if p.startswith("water wall")]
    assert len(walls) == 1, walls
    assert "0.300 m" in walls[0] and "basin" in walls[0] and "(" in walls[0]


def test_water_in_a_basin_deep_enough_is_no_wall(tmp_path):
    """The same water in a basin 0.4 m deep (0.1 m freeboard): the surface is -0.4 + 0.3 = -0.1 m, below the 0 m
    ground around it, so every wet cell's dry neighbour stands above it."""
    rect = (5.0, 0.0, 8.0, 4.0)
    path = _spec([_call("flat", "full", height=0.0), _call("basin", rect, "add", depth=0.4, shore_width=1.0),
                  _call("water", rect, depth=0.3)], tmp_path, "held")
    assert not [p for p in check_spec(path).problems if p.startswith("water wall")]


def test_water_wall_tolerance_is_the_named_constant():
    assert WATER_WALL_TOLERANCE == pytest.approx(0.05)


# ------------------------------------------------------------------------------------------------ planner
def _built(text, seed=0):
    spec, _ = generate_spec(text, seed=seed)
    heights, material = spec.build()
    return spec, heights, material


def test_a_knee_deep_creek_keeps_its_water_inside_a_channel_deep_enough():
    """Knee-deep is 0.3 m; the creek's channel must be at least 0.3 + FREEBOARD deep, and its water must cover the
    whole channel (its slot), so that no bank stands dry next to the water's edge."""
    spec, heights, material = _built("a knee-deep creek through a meadow")
    river = next(c for c in spec.calls if c.tool == "river")
    water = next(c for c in spec.calls if c.tool == "water")
    assert water.params["depth"] == pytest.approx(0.3)
    assert river.params["depth"] >= 0.3 + FREEBOARD - 1e-9
    (rx0, ry0, rx1, ry1), (wx0, wy0, wx1, wy1) = river.rect(20, 20), water.rect(20, 20)
    assert wx0 <= rx0 and wy0 <= ry0 and wx1 >= rx1 and wy1 >= ry1
    assert material.has_water().any()
    assert worst_wall(heights, material) <= WATER_WALL_TOLERANCE


@pytest.mark.parametrize("text", [
    "a wide river beside a park",            # a meandering river on half the tile
    "a deep river",                          # 'deep' water (0.6 m) in a channel of its own depth
    "waist-deep rapids below a cliff",
    "a waterfall near some trees",
    "a sandy beach",
    "a calm sea with waves",
    "a tidal flat",
    "a lakeshore with rocks",
    "a deep pond",
    "a harbour next to a street",
    "deep puddles in a muddy field",
    "a marsh",
    "a flooded street",
    "a rocky beach, a river, a forest and stairs",   # four quadrant slots
])
def test_planner_water_stands_in_ground_that_holds_it(text):
    _, heights, material = _built(text)
    assert material.has_water().any(), text
    assert worst_wall(heights, material) <= WATER_WALL_TOLERANCE, text


@pytest.mark.parametrize("resolution", [0.05, 0.1, 0.2])
@pytest.mark.parametrize("text", ["a flooded plaza next to stairs", "a sandy beach next to stairs"])
def test_water_beside_a_neighbouring_part_keeps_out_of_its_blend_band(text, resolution):
    """The water reaches SEAM_BAND (0.3 m) past its basin, and the stairs on the front half blend 0.3 m into the
    back half: with the basin only 0.5 m off the seam, the water's last 0.1 m lay in the stairs' band, whose low
    end pulled the ground 0.34 m below the water's surface at 0.05 m cells. Kept 0.8 m off, the water ends 0.2 m
    before the band at every resolution."""
    spec, result = generate_spec(text, resolution=resolution)
    heights, material = spec.build()
    assert worst_wall(heights, material) <= WATER_WALL_TOLERANCE
    assert not [w for w in result.warnings if w.startswith("water wall")], result.warnings
    (x0, y0, x1, y1), = [c.rect(20.0, 20.0) for c in spec.calls if c.tool == "water"]
    assert x1 <= 10.0 - 0.3 - 0.2 + 1e-9


def test_open_water_is_paired_with_a_basin_under_it():
    """The beach's water front on the back half (x 0-10 m) of a 20 m tile: the basin keeps 0.8 m (WATER_MARGIN)
    off the slot's front edge at x = 10 m, inside the tile; the water covers it and the 0.3 m (SEAM_BAND) it blends
    over; the basin is at least the water's depth plus FREEBOARD deep."""
    spec, _, _ = _built("a sandy beach and a meadow")
    (water,), (basin_call,) = ([c for c in spec.calls if c.tool == t] for t in ("water", "basin"))
    assert basin_call.rect(20, 20) == pytest.approx((6.0, 0.0, 9.2, 20.0))
    assert water.rect(20, 20) == pytest.approx((5.7, 0.0, 9.5, 20.0))
    assert basin_call.params["depth"] >= water.params["depth"] + FREEBOARD - 1e-9


# ------------------------------------------------------------------------------------------------ images
def _sketch(draw) -> Image.Image:
    img = Image.new("RGB", (96, 96), LEGEND["grass"].rgb)
    draw(ImageDraw.Draw(img))
    return img


def _wet_bodies(material) -> int:
    return ndimage.label(material.has_water())[1]


@pytest.mark.parametrize("name, draw, bodies", [
    ("disc", lambda d: d.ellipse([10, 30, 50, 70], fill=LEGEND["water"].rgb), 1),
    ("band", lambda d: d.rectangle([0, 10, 95, 30], fill=LEGEND["water"].rgb), 1),
    ("two discs", lambda d: (d.ellipse([5, 5, 35, 30], fill=LEGEND["water"].rgb),
                             d.ellipse([55, 60, 90, 90], fill=LEGEND["water"].rgb)), 2),
    ("L", lambda d: (d.rectangle([5, 5, 20, 90], fill=LEGEND["water"].rgb),
                     d.rectangle([5, 75, 90, 90], fill=LEGEND["water"].rgb)), 1),
])
def test_sketch_water_is_one_body_per_blob_and_has_no_wall(tmp_path, name, draw, bodies):
    path = tmp_path / "sketch.png"
    _sketch(draw).save(path)
    spec, _ = generate_spec(image=path)
    heights, material = spec.build()
    assert _wet_bodies(material) == bodies, name
    assert worst_wall(heights, material) <= WATER_WALL_TOLERANCE, name


def test_a_model_that_paints_a_pond_on_flat_ground_is_warned():
    """The checker's rule on what a model writes: water on ground that does not hold it is a warning of
    gente-generate (0.3 m of water on flat ground stands 0.3 m above the dry ground beside it), and none once a
    basin at least as deep lies under the water."""
    from test_generation_openai import FakeServer, _completion, _tool_call, ok


    pond = {"x0": 5.0, "y0": 5.0, "x1": 15.0, "y1": 15.0}
    on_flat = _completion([_tool_call("water", {"depth": 0.3, "region": pond})])
    in_basin = _completion([_tool_call("basin", {"depth": 0.4, "shore_width": 1.5, "region": pond}, 0),
                            _tool_call("water", {"depth": 0.3, "region": pond}, 1)])
    with FakeServer([ok(on_flat), ok(in_basin)]) as srv:
        _, flat = generate_spec("a pond", backend="openai", base_url=srv.url, model="m")
        _, held = generate_spec("a pond", backend="openai", base_url=srv.url, model="m")
    walls = [w for w in flat.warnings if w.startswith("water wall:")]
    assert len(walls) == 1 and "up to 0.300 m below their water surface" in walls[0]
    assert not [w for w in held.warnings if w.startswith("water wall:")]
