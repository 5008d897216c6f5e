"""The image planner's geometry and its refusals, on pictures whose terrain is known by construction.

A sketch is drawn on a 96 x 96 canvas (the planner's analysis grid), so pixel (r, c) is the tile's square
x in [20 (1 - (r + 1) / 96), 20 (1 - r / 96)], y in [20 (1 - (c + 1) / 96), 20 (1 - c / 96)] m on a 20 m tile:
top row = front (+x), left column = left (+y).
"""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

from legged_gente.generation.backends.image import LEGEND, OBSTACLE_HEIGHT, plan_image
from legged_gente.generation.pipeline import generate_spec
from legged_gente.generation.spec import TerrainSpec
from legged_gente.generation.validation import ValidationError
from legged_gente.terrain.composition import MAX_CALLS
from legged_gente.terrain.composition import SEAM_BAND

N, SIZE, RES = 96, 20.0, 0.1
PX = SIZE / N  # metres per sketch pixel


def _png(a: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(np.asarray(a, np.uint8)).save(buf, format="PNG")
    return buf.getvalue()


def _canvas(name: str = "grass") -> np.ndarray:
    return np.full((N, N, 3), LEGEND[name].rgb, np.uint8)


def _height_at_pixel(heights: np.ndarray, r: int, c: int) -> float:
    """Height of the tile cell under the centre of sketch pixel (r, c)."""
    x, y = SIZE * (1 - (r + 0.5) / N), SIZE * (1 - (c + 0.5) / N)
    return float(heights[int(x / RES), int(y / RES)])


def _heights(sketch: np.ndarray) -> np.ndarray:
    heights, _ = TerrainSpec(plan_image(_png(sketch)).calls, size_x=SIZE, size_y=SIZE, resolution=RES).build()
    return heights


def _raised_area(heights: np.ndarray) -> float:
    # grass is natural_ground of 0.04 m amplitude: anything above half the block height is a block
    return float((heights > OBSTACLE_HEIGHT / 2).sum()) * RES * RES


HALF_SEAM = SEAM_BAND / 2
"""A block fades out over SEAM_BAND outside its rectangle by a smoothstep, which passes half height half-way."""


def test_a_diagonal_black_wall_raises_the_wall_not_its_bounding_box():
    # A wall 3 px (0.625 m) thick running diagonally over rows 20..70, columns 19..71: one black blob whose
    # bounding box is a 10.4 m square. Only the wall may stand 0.5 m high; the open ground on either side stays.
    sketch = _canvas()
    for i in range(20, 70):
        sketch[i, i - 1:i + 2] = LEGEND["obstacle"].rgb
    drawn = 50 * PX * (3 * PX + 2 * HALF_SEAM)  # 50 rows of 3 px, each side widened by the seam: 9.6 m2
    heights = _heights(sketch)
    assert _height_at_pixel(heights, 45, 45) == pytest.approx(OBSTACLE_HEIGHT, abs=1e-4)  # on the wall
    assert _height_at_pixel(heights, 25, 65) < 0.1  # inside the bounding box, 40 px right of the wall
    assert _height_at_pixel(heights, 65, 25) < 0.1  # inside the bounding box, 40 px left of it
    assert abs(_raised_area(heights) - drawn) < 0.25 * drawn  # not the bounding box's 108 m2


def test_a_walled_enclosure_keeps_its_open_inside():
    # A square ring of black 3 px thick around rows / columns 20..76: the yard inside is open ground.
    sketch = _canvas()
    sketch[20:76, 20:76] = LEGEND["obstacle"].rgb
    sketch[23:73, 23:73] = LEGEND["grass"].rgb
    drawn = (56 * 56 - 50 * 50) * PX * PX + 4 * (56 + 50) * PX * HALF_SEAM  # 636 px = 27.6 m2, + seams: 40.9 m2
    heights = _heights(sketch)
    assert _height_at_pixel(heights, 48, 48) < 0.1  # the yard
    assert _height_at_pixel(heights, 21, 48) == pytest.approx(OBSTACLE_HEIGHT, abs=1e-4)  # the ring's front side
    assert abs(_raised_area(heights) - drawn) < 0.25 * drawn  # not the bounding box's 136 m2


def test_a_round_pillar_is_still_one_block():
    # A disc covers pi / 4 of its bounding box: one block over that box, not a staircase of rectangles.
    sketch = _canvas()
    rows, cols = np.mgrid[0:N, 0:N]
    sketch[(rows - 40.0) ** 2 + (cols - 60.0) ** 2 <= 5.0 ** 2] = LEGEND["obstacle"].rgb
    blocks = [c for c in plan_image(_png(sketch)).calls if c.tool == "flat" and c.params["height"] == OBSTACLE_HEIGHT]
    assert len(blocks) == 1


def test_a_black_block_inside_stairs_stays_raised():
    # Red stairs over the front half; two black blocks drawn on them, one smaller than a 4 px pooling block and
    # one not aligned to the pooling blocks. Blocks are placed exactly: later stairs must not flatten them.
    sketch = _canvas("pavement")
    sketch[:48] = LEGEND["stairs"].rgb
    sketch[20:22, 40:42] = LEGEND["obstacle"].rgb
    sketch[30:37, 60:67] = LEGEND["obstacle"].rgb
    heights = _heights(sketch)
    for r, c in [(20, 40), (21, 41)] + [(r, c) for r in range(30, 37) for c in range(60, 67)]:
        assert _height_at_pixel(heights, r, c) == pytest.approx(OBSTACLE_HEIGHT, abs=1e-4), (r, c)


def test_a_sketch_needing_more_calls_than_a_terrain_holds_is_refused_as_bad_input():
    # 10 x 10 separate black dots: 100 blocks + the base ground = 101 calls; a terrain holds MAX_CALLS (64).
    sketch = _canvas()
    for r in range(0, N, 10):
        for c in range(0, N, 10):
            sketch[r:r + 3, c:c + 3] = LEGEND["obstacle"].rgb
    with pytest.raises(ValueError) as info:
        plan_image(_png(sketch))
    message = str(info.value)
    assert "\n" not in message and f"needs 101 tool calls, more than a terrain holds ({MAX_CALLS})" in message
    assert "draw fewer" in message
    # the CLI's exit status 2 (bad input), not 1 (a server or model failed: ValidationError)
    with pytest.raises(ValueError) as info:
        generate_spec(image=_png(sketch))
    assert not isinstance(info.value, ValidationError)


def test_an_image_without_pixels_is_refused():
    # Python callers may hand over an empty crop: resampling it gives black, a 0.5 m block over the whole tile.
    for size in ((0, 0), (0, 5), (5, 0)):
        with pytest.raises(ValueError, match=r"^the image has no pixels \(\d x \d\); pass a picture"):
            plan_image(Image.new("RGB", size))


def test_a_photo_too_small_to_read_is_refused_but_a_tiny_sketch_is_read():
    # One pixel (or a 2 x 1 strip) of a non-legend colour has no sky, horizon or texture to read.
    for size in ((1, 1), (2, 1), (64, 48)):
        with pytest.raises(ValueError, match=rf"^the image is a {size[0]} x {size[1]} pixel photo, fewer pixels "
                                             r"than the 128 x 96 the photo reader analyses; pass a larger"):
            plan_image(Image.new("RGB", size, (10, 200, 30)))
    # A one-pixel sketch is one legend colour over the whole tile: water everywhere.
    calls = plan_image(_png(np.full((1, 1, 3), LEGEND["water"].rgb))).calls
    assert [(c.tool, c.rect(SIZE, SIZE)) for c in calls if c.tool == "water"] == [("water", (0.0, 0.0, SIZE, SIZE))]


STEP_HEIGHT = 0.12  # the legend's stairs: treads 0.35 m deep rising 0.12 m each towards +x


def _never_falls_along_x(heights: np.ndarray, inside: np.ndarray) -> None:
    """Along +x, through the cells of ``inside``, the ground rises by 0 or one step, never falls."""
    for j in np.flatnonzero(inside.any(0)):
        i = np.flatnonzero(inside[:, j])
        rises = np.diff(heights[i, j])[np.diff(i) == 1]
        assert rises.min() > -1e-4 and rises.max() < STEP_HEIGHT + 1e-4, (j, rises.min(), rises.max())


def _cells() -> tuple[np.ndarray, np.ndarray]:
    """x and y (m) of every cell's centre."""
    centres = (np.arange(int(SIZE / RES)) + 0.5) * RES
    return np.meshgrid(centres, centres, indexing="ij")


def test_stairs_drawn_as_an_ellipse_are_one_flight_rising_towards_the_front():
    # A red ellipse 72 px along x by 40 px across on pavement: stairs rising towards the top (+x). Walking along
    # +x over it the ground may only rise, one step at a time; cut into slabs along x, each slab is its own
    # flight centred on its own middle and the ground falls back at every slab's front edge.
    sketch = _canvas("pavement")
    rows, cols = np.mgrid[0:N, 0:N]
    sketch[((rows - 47.5) / 36) ** 2 + ((cols - 47.5) / 20) ** 2 <= 1] = LEGEND["stairs"].rgb
    heights = _heights(sketch)
    x, y = _cells()
    centre, a, b = SIZE / 2, 36 * PX, 20 * PX  # the ellipse in metres: centre (10, 10), semi-axes 7.5 and 4.2 m
    margin = 2 * SEAM_BAND + 4 * PX  # the pooling blocks' steps along the outline and the seams along them
    inside = ((x - centre) / (a - margin)) ** 2 + ((y - centre) / (b - margin)) ** 2 <= 1
    _never_falls_along_x(heights, inside)
    assert heights[inside].max() - heights[inside].min() > 10 * STEP_HEIGHT  # a flight, not a landing


def test_stairs_around_a_black_block_stay_one_flight():
    # Red stairs over rows 12..84 (x from 2.5 to 17.5 m) across the whole width, a black block drawn on them at
    # rows 40..56, columns 40..56: the stairs before and after the block are one flight, the block stands on it.
    sketch = _canvas("pavement")
    sketch[12:84] = LEGEND["stairs"].rgb
    sketch[40:56, 40:56] = LEGEND["obstacle"].rgb
    heights = _heights(sketch)
    x, y = _cells()
    block_x, block_y = (SIZE * (1 - 56 / N), SIZE * (1 - 40 / N)), (SIZE * (1 - 56 / N), SIZE * (1 - 40 / N))
    near_block = ((x > block_x[0] - SEAM_BAND) & (x < block_x[1] + SEAM_BAND)
                  & (y > block_y[0] - SEAM_BAND) & (y < block_y[1] + SEAM_BAND))
    stairs = (x > SIZE * (1 - 84 / N) + SEAM_BAND) & (x < SIZE * (1 - 12 / N) - SEAM_BAND)
    columns = (y > block_y[0]) & (y < block_y[1])  # the columns through the block
    for part in (stairs & columns & (x < block_x[0] - SEAM_BAND), stairs & columns & (x > block_x[1] + SEAM_BAND)):
        _never_falls_along_x(heights, part)
    # the flight continues behind the block: the same height at the same x beside the block and through it
    beside = stairs & (y > block_y[1] + 2 * SEAM_BAND) & ~near_block
    _never_falls_along_x(heights, beside)  # the block does not cut the flight beside it into three
    for i in np.flatnonzero((stairs & columns & ~near_block).any(1)):
        j_through = np.flatnonzero((stairs & columns & ~near_block)[i])
        j_beside = np.flatnonzero(beside[i])
        assert np.allclose(heights[i, j_through], heights[i, j_beside[0]], atol=1e-4), i
    on_block = (x > block_x[0] + RES) & (x < block_x[1] - RES) & (y > block_y[0] + RES) & (y < block_y[1] - RES)
    assert heights[on_block] == pytest.approx(OBSTACLE_HEIGHT, abs=1e-4)


def test_a_photo_splits_back_and_front_at_the_middle_of_the_tile_it_builds():
    # A 128 x 96 photo (the reader's own grid) with its horizon at row 30: row r sees the ground at
    # Z = 3 m * (96 - 30) / (r + 0.5 - 30) (pinhole camera over flat ground, the bottom row at 3 m). On a 40 m
    # tile the back half ends 20 m from the back edge, Z = 23 m, at r = 38.1; the front half ends at Z = 43 m,
    # r = 34.1. Snow is painted over rows 38..45 (Z = 13..23 m: the back half's far end), sand over rows 30..38
    # (the front half), grass below (the near ground).
    rng = np.random.default_rng(0)
    im = np.zeros((96, 128, 3), np.float32)
    t = (np.arange(30) / 30)[:, None, None]
    im[:30] = np.asarray((40, 90, 200)) * (1 - t) + np.asarray((170, 210, 250)) * t
    im[30:38] = (225, 200, 140)
    im[38:45] = (240, 240, 245)
    im[45:] = (70, 130, 50)
    im[45:] += rng.normal(0, 18, (51, 128, 3))
    im = np.clip(im + rng.normal(0, 3, im.shape), 0, 255)
    calls = plan_image(_png(im), 40.0, 40.0).calls
    soil = {(c.params["preset"], c.rect(40.0, 40.0)[0]) for c in calls if c.tool == "soil"}
    assert ("dry_sand", 20.0) in soil  # the sand lies on the front half (x0 = 20 m)
    assert not any(preset == "snow" and x0 >= 20.0 for preset, x0 in soil)  # the snow is not 20 m further out


def test_a_sketch_in_other_proportions_than_its_tile_is_said_to_be_stretched():
    """A 2:1 sketch on a square tile was stretched to it with no note: its top row is the tile's front (x), its
    columns y, so a sketch W x H pixels fits a size_x x size_y tile unstretched when H / W = size_x / size_y."""
    wide = np.concatenate([_canvas(), _canvas("mud")], axis=1)  # 96 rows x 192 columns
    warnings = plan_image(_png(wide), size_x=SIZE, size_y=SIZE).warnings
    said = [w for w in warnings if "stretched" in w]
    assert len(said) == 1 and "192 x 96" in said[0] and "20 x 20 m" in said[0] and "2.00 times more along x" in said[0], warnings
    assert not [w for w in plan_image(_png(wide), size_x=10.0, size_y=20.0).warnings if "stretched" in w]
    assert not [w for w in plan_image(_png(_canvas())).warnings if "stretched" in w]


@pytest.mark.parametrize("quality", [90, 75])
def test_a_jpeg_sketch_reads_as_its_png(quality):
    """JPEG's ringing at a colour edge makes pixels between two legend colours (red beside grass reads as mud): a red
    rectangle became three flights of stairs and two mud patches at its corners. Pixels far from every legend colour
    do not vote, so the JPEG gives the PNG's calls."""
    sketch = np.full((128, 128, 3), LEGEND["grass"].rgb, np.uint8)  # resized to the reader's grid of 96
    sketch[10:31, 90:111] = LEGEND["obstacle"].rgb
    sketch[70:121, 80:121] = LEGEND["stairs"].rgb
    sketch[8:49, 8:57] = LEGEND["water"].rgb
    sketch[80:128, 0:51] = LEGEND["mud"].rgb
    buf = io.BytesIO()
    Image.fromarray(sketch.astype(np.uint8)).save(buf, format="JPEG", quality=quality)
    png, jpeg = plan_image(_png(sketch)).calls, plan_image(buf.getvalue()).calls
    assert [(c.tool, c.region_json()) for c in jpeg] == [(c.tool, c.region_json()) for c in png]
