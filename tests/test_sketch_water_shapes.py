"""A sketch's water blob that is not compact (an L, a ring) keeps the land it encloses in its box dry.

Each water blob is one basin over its bounding box (no dry ridge splits a lake); the land the blob leaves inside
that box is rebuilt as ground when it holds a square of DRY_INSIDE_MIN = 3 m (twice the basin's 1.5 m shore):
narrower dry parts, such as a disc's corners, lie on the basin's shelving shore anyway. The sketches here are 96 px
on a 20 m tile: 4.8 px per metre; image row r is x = 20 (1 - r / 96) m, column c is y = 20 (1 - c / 96) m.
"""

import io

import numpy as np
from PIL import Image, ImageDraw
from test_water_bodies import worst_wall

from legged_gente.generation.backends.image import LEGEND
from legged_gente.generation.checker import WATER_WALL_TOLERANCE
from legged_gente.generation.pipeline import generate_spec

WATER = LEGEND["water"].rgb


def _build(draw):
    img = Image.new("RGB", (96, 96), LEGEND["grass"].rgb)
    draw(ImageDraw.Draw(img))
    buf = io.BytesIO()
    img.save(buf, "PNG")
    spec, result = generate_spec(image=buf.getvalue())
    heights, material = spec.build()
    return spec, result, heights, material


def _cell(x, y):
    return round(x / 0.1), round(y / 0.1)


def test_an_l_shaped_lake_leaves_its_inner_corner_dry():
    # an L: a band along the front edge (rows 0-20: x 15.6-20 m) and one along the left edge (cols 0-20: y 15.6-20 m);
    # the grass in the corner they enclose is 78 % of the tile, its centre included
    _, result, heights, material = _build(lambda d: (d.rectangle([0, 0, 95, 20], fill=WATER),
                                                     d.rectangle([0, 0, 20, 95], fill=WATER)))
    wet = material.has_water()
    assert not wet[_cell(10.0, 10.0)]  # the tile's centre, where the robots spawn
    assert not wet[_cell(5.0, 5.0)]
    assert wet[_cell(18.0, 5.0)] and wet[_cell(5.0, 18.0)] and wet[_cell(18.0, 18.0)]  # both arms and their corner
    assert wet.mean() < 0.4  # the L is 2 * 0.22 - 0.22^2 = 39 % of the sketch (blocks of 0.83 m round it)
    assert worst_wall(heights, material) <= WATER_WALL_TOLERANCE
    assert not [w for w in result.warnings if w.startswith("water wall")], result.warnings


def test_a_moat_leaves_its_island_dry():
    # a square ring of water 10 px wide around an island 36 px (7.5 m) across
    _, _, heights, material = _build(lambda d: (d.rectangle([20, 20, 75, 75], fill=WATER),
                                                d.rectangle([30, 30, 65, 65], fill=LEGEND["grass"].rgb)))
    wet = material.has_water()
    assert not wet[_cell(10.0, 10.0)]  # the island's centre
    assert wet[_cell(10.0, 20 * (1 - 25 / 96))] and wet[_cell(20 * (1 - 25 / 96), 10.0)]  # the ring's sides
    assert worst_wall(heights, material) <= WATER_WALL_TOLERANCE


def test_a_round_pond_keeps_one_basin_over_its_box():
    # a disc's box corners are narrower than 3 m: the pond stays one basin and one water, nothing rebuilt
    spec, _, heights, material = _build(lambda d: d.ellipse([30, 30, 65, 65], fill=WATER))
    assert [c.tool for c in spec.calls].count("basin") == 1
    assert [c.tool for c in spec.calls].count("flat") + [c.tool for c in spec.calls].count("natural_ground") == 1
    assert material.has_water()[_cell(10.0, 10.0)]
    assert worst_wall(heights, material) <= WATER_WALL_TOLERANCE


def test_a_pond_inside_an_l_lakes_box_is_one_body_with_it():
    # an L (a band down the right edge from row 8, cols 72-95, and one along the back, rows 72-95) and a pond at rows
    # 8-30, cols 20-40, inside the L's box and scanned first. As two bodies the L's box rebuilt the pond's ground as
    # land after the pond's basin was cut, and the pond's water stood 0.3 m above it. Blobs whose boxes overlap are
    # one body: one basin and one water over the union of their boxes, the land around the pond rebuilt.
    def draw(d):
        d.rectangle([72, 8, 95, 95], fill=WATER)
        d.rectangle([0, 72, 95, 95], fill=WATER)
        d.rectangle([20, 8, 40, 30], fill=WATER)
    spec, result, heights, material = _build(draw)
    assert [c.tool for c in spec.calls].count("water") == 1
    assert worst_wall(heights, material) <= WATER_WALL_TOLERANCE
    assert not [w for w in result.warnings if w.startswith("water wall")], result.warnings
    wet = material.has_water()
    assert wet[_cell(20 * (1 - 19 / 96), 20 * (1 - 30 / 96))]  # the pond's middle (row 19, col 30)
    assert not wet[_cell(20 * (1 - 50 / 96), 20 * (1 - 40 / 96))]  # the land between pond and L (row 50, col 40)


def test_water_blobs_nearer_than_the_seam_band_are_one_body():
    # on a 10 m tile a block (4 px) is 0.42 m: two ponds one block apart (gap 0.42 m < BODY_GAP = 0.5 m) are one
    # body; two blocks apart (0.83 m) they stay two
    def ponds(gap_px):
        return lambda d: (d.rectangle([8, 8, 39, 87], fill=WATER), d.rectangle([40 + gap_px, 8, 87, 87], fill=WATER))
    for gap_px, bodies in ((4, 1), (8, 2)):
        img = Image.new("RGB", (96, 96), LEGEND["grass"].rgb)
        ponds(gap_px)(ImageDraw.Draw(img))
        buf = io.BytesIO()
        img.save(buf, "PNG")
        spec, _ = generate_spec(image=buf.getvalue(), size_x=10.0, size_y=10.0)
        assert [c.tool for c in spec.calls].count("water") == bodies, gap_px
        heights, material = spec.build()
        assert worst_wall(heights, material) <= WATER_WALL_TOLERANCE
