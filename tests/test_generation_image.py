"""The image planner: sketch maps by their legend, photos in perspective (sky dropped, near = bottom)."""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from legged_gente.generation.backends.image import HILL_SLOPE, LEGEND, MAX_CALLS, OBSTACLE_HEIGHT, is_sketch, plan_image, read_photo
from legged_gente.generation.score import DEFAULT_SET, features
from legged_gente.generation.spec import TerrainSpec

H, W = 120, 160
PHOTOS = DEFAULT_SET / "photos"
MANIFEST = json.loads((PHOTOS / "manifest.json").read_text())["items"]


def _png(a, fmt="PNG"):
    buf = io.BytesIO()
    Image.fromarray(np.asarray(a, np.uint8)).save(buf, format=fmt)
    return buf.getvalue()


def _photo(sky_top, sky_low, ground, horizon=45, noise=6.0, seed=0, sea=None):
    """A plain eye-level photo: a vertical sky gradient over a textured ground (optionally a sea band)."""
    rng = np.random.default_rng(seed)
    im = np.zeros((H, W, 3), np.float32)
    t = (np.arange(horizon) / horizon)[:, None, None]
    im[:horizon] = np.asarray(sky_top) * (1 - t) + np.asarray(sky_low) * t
    im[horizon:] = ground
    im[horizon:] += rng.normal(0, 18, (H - horizon, W, 3))  # ground texture
    if sea is not None:
        im[horizon:sea] = (30, 90, 160)
        for r in range(horizon + 2, sea, 4):  # wave crests: pale streaks across the view
            im[r:r + 2] = (215, 230, 240)
    return np.clip(im + rng.normal(0, noise, im.shape), 0, 255).astype(np.uint8)


def _tools(result):
    return [c.tool for c in result.calls]


SKIES = {
    "blue": ((40, 90, 200), (170, 210, 250)),
    "white": ((235, 235, 238), (250, 250, 252)),
    "overcast": ((150, 152, 158), (200, 202, 206)),
    "sunset": ((70, 50, 120), (250, 160, 70)),
    "dusk": ((15, 25, 70), (90, 120, 160)),
}
GROUNDS = {"grass": (70, 130, 50), "asphalt": (80, 80, 84), "dirt": (140, 110, 75)}


@pytest.mark.parametrize("sky", SKIES)
@pytest.mark.parametrize("ground", GROUNDS)
def test_sky_never_becomes_water_or_snow(sky, ground):
    r = plan_image(_png(_photo(*SKIES[sky], GROUNDS[ground])))
    assert not {"water", "snow"} & features(r.calls), (sky, ground, r.notes)
    assert "read as a colour-coded sketch map" not in r.notes


def test_no_eval_photo_reads_its_sky_as_ground():
    """In every photo of the evaluation set, nothing above the horizon is classified as a ground surface."""
    for item in MANIFEST:
        r = read_photo(Image.open(PHOTOS / item["file"]).convert("RGB"))
        assert (r.surface[: r.horizon] == -1).all(), item["file"]
        assert not (r.surface[r.sky] >= 0).any(), item["file"]


def test_photo_calls_are_bounded_and_build():
    for item in MANIFEST[::4]:
        r = plan_image(PHOTOS / item["file"])
        assert 1 <= len(r.calls) <= MAX_CALLS, item["file"]
        heights, _ = TerrainSpec(r.calls).build()
        assert np.isfinite(heights).all()


def test_beach_is_read_in_perspective_with_waves():
    # horizon at row 40, sea rows 40-58 (far: beyond ~13 m), sand below (near the camera)
    r = plan_image(_png(_photo(*SKIES["blue"], (225, 200, 140), horizon=40, sea=58)))
    water = [c for c in r.calls if c.tool == "water"]
    sand = [c for c in r.calls if c.tool == "soil" and c.params["preset"] == "dry_sand"]
    assert water and sand
    # The sea's near edge, 18 rows under the horizon of 80 ground rows, is Z = 3 m * 80 / 18 = 13 m from the
    # camera, 10 m from the tile's back edge (a pixel or two of blur either way: 8-11 m); it reaches the horizon.
    assert [(round(c.rect(20, 20)[2]), 8 <= c.rect(20, 20)[0] <= 11) for c in water] == [(20, True)]
    assert any(c.rect(20, 20)[0] == 0.0 for c in sand)  # the sand is at the back, where the robot starts
    assert {c.params["flow"] for c in water} == {"tide"}  # crests on water that reaches the horizon
    heights, material = TerrainSpec(r.calls).build()
    # the water lies in a basin: its shelving shore is dry within about 0.5 m of the basin's edges (tile edges too)
    assert material.has_water()[150:195, 10:190].all() and not material.has_water()[:80].any()


def test_calm_sea_is_still():
    calm = _photo(*SKIES["blue"], (225, 200, 140), horizon=40, seed=1)
    calm[40:58] = np.clip(np.array((30, 90, 160)) + np.random.default_rng(2).normal(0, 4, (18, W, 3)), 0, 255)
    r = plan_image(_png(calm))
    assert {c.params["flow"] for c in r.calls if c.tool == "water"} == {"still"}


def test_grey_photo_is_not_a_sketch_but_a_sketch_is():
    grey = _photo(*SKIES["overcast"], GROUNDS["asphalt"], noise=3.0)
    assert not is_sketch(Image.open(io.BytesIO(_png(grey))))
    smooth_grey = np.zeros((H, W, 3), np.uint8)
    smooth_grey[:50] = np.linspace(150, 215, 50)[:, None, None]  # overcast sky gradient, no noise
    smooth_grey[50:] = 128  # pavement grey, exactly the legend's
    smooth_grey[50:] += np.random.default_rng(0).integers(0, 20, (H - 50, W, 1)).astype(np.uint8)
    assert not is_sketch(Image.fromarray(smooth_grey))
    assert is_sketch(Image.open(io.BytesIO(_png(sketch_map(), fmt="JPEG"))))


def test_stairs_photo_gives_one_flight():
    for name in ("08_stone_stairs.jpg", "44_grey_concrete_stairs.jpg"):
        r = plan_image(PHOTOS / name)
        stairs = [c for c in r.calls if c.tool == "stairs"]
        assert len(stairs) == 1, name
        x0, _, x1, _ = stairs[0].rect(20, 20)
        assert x1 - x0 == 20.0  # one flight along the walking direction, not patches


@pytest.mark.parametrize("name, expected", [
    ("02_river_crossing.jpg", {"water", "flowing"}),
    ("11_grassy_hill.jpg", {"slope"}),
    ("06_city_street.png", {"tall"}),
    ("18_rubble.png", {"low"}),
])
def test_photo_cues(name, expected):
    assert expected <= features(plan_image(PHOTOS / name).calls)


def sketch_map():
    im = np.full((H, W, 3), LEGEND["grass"].rgb, np.uint8)
    im[:, :60] = LEGEND["water"].rgb  # left 60 columns: water along the tile's left side
    im[60:100, 100:140] = LEGEND["stairs"].rgb
    im[10:20, 80:90] = LEGEND["obstacle"].rgb
    im[100:, :30] = LEGEND["sand"].rgb
    return im


def test_sketch_map_is_read_by_its_legend():
    r = plan_image(_png(sketch_map()))
    assert "read as a colour-coded sketch map" in r.notes
    tools = _tools(r)
    assert {"water", "stairs", "flat"} <= set(tools) and "pillars" not in tools
    water = [c.rect(20, 20) for c in r.calls if c.tool == "water"]
    # water: the left 60/160 of the width (y > 12.5 m), all along x except the sand in the back-left corner
    assert all(11.5 < y0 < 13.5 for _, y0, _, _ in water) and max(y1 for *_, y1 in water) == 20.0
    assert max(x1 for _, _, x1, _ in water) == 20.0 and min(x0 for x0, *_ in water) == 0.0
    block = [c for c in r.calls if c.tool == "flat" and c.params["height"] == OBSTACLE_HEIGHT]
    assert len(block) == 1
    x0, y0, x1, y1 = block[0].rect(20, 20)
    assert 16.0 < x0 < x1 < 19.5 and 8.0 < y0 < y1 < 10.5  # rows 10..20 of 120, columns 80..90 of 160
    heights, material = TerrainSpec(r.calls).build()
    i, j = int((x0 + x1) / 2 / 0.1), int((y0 + y1) / 2 / 0.1)
    assert heights[i, j] == pytest.approx(OBSTACLE_HEIGHT, abs=1e-4)
    # the water lies in a basin: its shelving shore is dry within about 0.5 m of the basin's edges (tile edges too)
    assert material.has_water()[45:195, 135:195].all() and not material.has_water()[:, :120].any()
    assert material.soil_presets == ["dry_sand"] and material.has_soil()[:25, 175:].all()


def test_image_planner_is_deterministic_and_rejects_garbage():
    a, b = plan_image(PHOTOS / MANIFEST[5]["file"]), plan_image(PHOTOS / MANIFEST[5]["file"])
    assert a.calls == b.calls
    with pytest.raises(ValueError, match="could not be read"):
        plan_image(b"not an image")


def test_an_image_beyond_the_pixel_limit_says_so(monkeypatch):
    monkeypatch.setattr(Image, "MAX_IMAGE_PIXELS", 1000)  # Pillow refuses images of more than twice this
    with pytest.raises(ValueError) as info:
        plan_image(_png(np.zeros((64, 64, 3))))
    assert str(info.value) == ("the image is too large to decode: Image size (4096 pixels) exceeds limit of 2000 "
                               "pixels; downscale it (a few megapixels are plenty) and pass it again.")


def test_an_image_between_pillows_warning_and_its_limit_is_refused_in_one_line(monkeypatch, recwarn):
    """Pillow only warns (two lines naming its own source file) between MAX_IMAGE_PIXELS and twice it, and decodes
    the image, three times on the way to a spec: refused like a larger one, without Pillow's warning."""
    monkeypatch.setattr(Image, "MAX_IMAGE_PIXELS", 1000)
    with pytest.raises(ValueError) as info:
        plan_image(_png(np.zeros((40, 40, 3))))
    assert str(info.value) == ("the image is too large to decode: Image size (1600 pixels) exceeds limit of 1000 "
                               "pixels; downscale it (a few megapixels are plenty) and pass it again.")
    assert not [w for w in recwarn if issubclass(w.category, Image.DecompressionBombWarning)]


def test_greyscale_photo_warns():
    grey = _photo(*SKIES["blue"], GROUNDS["grass"]).mean(-1, keepdims=True).repeat(3, -1)
    assert any("greyscale photo" in w for w in plan_image(_png(grey)).warnings)


def test_docs_list_the_legend():
    doc = (Path(__file__).parents[1] / "docs" / "generation.md").read_text()
    for name, legend in LEGEND.items():
        r, g, b = legend.rgb
        assert f"| `{name}` | ({r}, {g}, {b}) | `#{r:02x}{g:02x}{b:02x}` |" in doc, name


def _ground_to_skyline(skyline_rows, ground=(70, 130, 50), seed=0):
    """A photo whose ground (textured) reaches up to ``skyline_rows[c]`` in column c, a blue sky gradient above."""
    rng = np.random.default_rng(seed)
    rows = np.arange(H)[:, None]
    t = (rows / H)[..., None]
    sky = np.asarray(SKIES["blue"][0]) * (1 - t) + np.asarray(SKIES["blue"][1]) * t
    im = np.where((rows >= np.asarray(skyline_rows)[None, :])[..., None],
                  np.asarray(ground) + rng.normal(0, 18, (H, W, 3)), sky + rng.normal(0, 3, (H, W, 3)))
    return np.clip(im, 0, 255).astype(np.uint8)


def test_level_ground_gives_no_slope():
    r = plan_image(_png(_ground_to_skyline(np.full(W, 50))))
    assert "slope" not in features(r.calls)


def test_tilted_horizon_gives_the_side_slope():
    # A plane sloping sideways at angle theta, seen by a level pinhole camera: a line of constant depth on it
    # (its far edge against the sky) rises tan(theta) * dx in height for dx across, i.e. f * tan(theta) * dx / Z
    # rows for f * dx / Z columns: the skyline's tilt in the picture is tan(theta) (square pixels).
    tilt = 0.4  # rows per column
    skyline = 76 - tilt * np.arange(W)  # 76 at the left edge, 12 at the right
    slopes = [c for c in plan_image(_png(_ground_to_skyline(skyline))).calls if c.tool == "pyramid_slope"]
    assert len(slopes) == 1
    assert slopes[0].params["slope"] == pytest.approx(np.arctan(0.4), abs=0.03)  # 0.38 rad
    # the same scene stretched to twice the width: 0.2 rows per column, a gentler slope of atan(0.2) = 0.20 rad
    wide = Image.fromarray(_ground_to_skyline(skyline)).resize((2 * W, H))
    slopes = [c for c in plan_image(wide).calls if c.tool == "pyramid_slope"]
    assert slopes[0].params["slope"] == pytest.approx(np.arctan(0.4 / 2), abs=0.03)


def test_hill_rising_above_the_horizon_is_a_slope_ahead():
    c = np.arange(W)
    skyline = 60 - 25 * np.sin(np.pi * np.clip((c - 15) / 130, 0, 1))  # a smooth ridge 25 rows above the horizon
    r = plan_image(_png(_ground_to_skyline(skyline)))
    slopes = [c for c in r.calls if c.tool == "pyramid_slope"]
    assert len(slopes) == 1 and slopes[0].params["direction"] == "up"
    assert slopes[0].params["slope"] == HILL_SLOPE  # a curved outline: how steep cannot be read from it
    assert slopes[0].rect(20, 20)[0] == 10.0  # ahead: the front half of the tile


def test_upright_blue_panes_are_not_water_but_a_pond_and_a_stream_are():
    # Overcast sky over a grey plaza, horizon at row 40; a grey facade standing from row 5 down to row 56 with
    # slate-blue window panes, the lowest row of panes (rows 44-50) below the horizon and on the facade's darker
    # base, so not enclosed by the facade. Each pane is 6 x 6 pixels: lying on the ground 4-10 rows under the
    # horizon it would be tens of metres away, and 6 rows tall it would be a puddle ~30 times longer than wide.
    im = _photo(*SKIES["overcast"], (150, 150, 150), horizon=40, noise=3.0)
    im[5:56, 20:70] = (140, 140, 140)
    im[50:56, 20:70] = (90, 90, 92)  # the facade's darker base, right under the lowest panes
    for r0 in (10, 27, 44):
        for c0 in (26, 42, 58):
            im[r0:r0 + 6, c0:c0 + 6] = (40, 60, 80)  # hue 210, the colour of dark water
    panes = plan_image(_png(im))
    assert "water" not in features(panes.calls), panes.notes
    # A pond on the ground at those rows is foreshortened: 6 rows for 100 columns lies flat.
    pond = _photo(*SKIES["overcast"], (150, 150, 150), horizon=40, noise=3.0)
    pond[44:50, 30:130] = (40, 60, 80)
    assert "water" in features(plan_image(_png(pond)).calls)
    # A stream running away from the camera, 30 columns wide at the bottom and 4 at the horizon: 80 rows for 30
    # columns is taller than a patch 4 times longer than wide can look at 3 m (4 * 1.6 / 3 = 2.1), but it
    # narrows towards the horizon as a strip lying on the ground does.
    stream = _photo(*SKIES["overcast"], (120, 110, 90), horizon=40, noise=3.0)
    for r in range(40, H):
        half = 2 + 13 * (r - 40) / (H - 40)
        stream[r, int(80 - half):int(80 + half)] = (40, 70, 110)
    assert "water" in features(plan_image(_png(stream)).calls)
