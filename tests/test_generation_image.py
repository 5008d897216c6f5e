"""The image planner on synthesised photos and a colour-coded sketch map."""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

from legged_gente.generation.backends.image import LEGEND, OBSTACLE_HEIGHT, plan_image
from legged_gente.generation.spec import TerrainSpec

H, W = 120, 160


def _noisy(a, sigma, seed=0):
    rng = np.random.default_rng(seed)
    return np.clip(a + rng.normal(0, sigma, a.shape), 0, 255).astype(np.uint8)


def beach_photo():
    im = np.zeros((H, W, 3), np.float32)
    im[:30] = (150, 200, 250)  # smooth sky
    im[30:70] = (20, 80, 170)  # sea
    im[70:] = (225, 200, 140)  # sand
    out = _noisy(im, 10)
    out[:30] = im[:30].astype(np.uint8)
    return out


def city_stairs_photo():
    im = np.full((H, W, 3), 140, np.float32)  # grey pavement
    for r in range(20, 110):
        im[r, 30:130] = 90 if (r // 6) % 2 else 190  # lit treads and shaded risers
    return _noisy(im, 4)


def forest_photo():
    im = np.zeros((H, W, 3), np.float32)
    im[:] = (40, 140, 50)
    for c in range(5, W, 20):
        im[:, c:c + 5] = (60, 40, 20)  # dark trunks
    return _noisy(im, 15)


def sketch_map():
    im = np.full((H, W, 3), LEGEND["grass"].rgb, np.uint8)
    im[:, :60] = LEGEND["water"].rgb  # left 60 columns: water along the tile's left side
    im[60:100, 100:140] = LEGEND["stairs"].rgb
    im[10:20, 80:90] = LEGEND["obstacle"].rgb
    im[100:, :30] = LEGEND["sand"].rgb
    return im


def _png(a):
    buf = io.BytesIO()
    Image.fromarray(a).save(buf, format="PNG")
    return buf.getvalue()


def test_beach_photo_has_water_at_the_front_and_sand_at_the_back():
    r = plan_image(_png(beach_photo()))
    water = [c for c in r.calls if c.tool == "water"]
    sand = [c for c in r.calls if c.tool == "soil" and c.params["preset"] == "dry_sand"]
    assert water and sand and any("sky" in n for n in r.notes)
    assert min(c.rect(20, 20)[0] for c in water) > max(c.rect(20, 20)[0] for c in sand)  # sea is farther (+x)
    heights, material = TerrainSpec(r.calls).build()
    assert material.has_water()[150:].mean() > 0.8 and not material.has_water()[:50].any()


def test_city_stairs_photo_has_stairs():
    r = plan_image(_png(city_stairs_photo()))
    assert "stairs" in [c.tool for c in r.calls]
    assert "water" not in [c.tool for c in r.calls]


def test_forest_photo_has_trees():
    r = plan_image(_png(forest_photo()))
    assert "pillars" in [c.tool for c in r.calls]
    heights, _ = TerrainSpec(r.calls).build()
    assert heights.max() > 2.0  # trunks stand up


def test_sketch_map_is_read_by_its_legend():
    r = plan_image(_png(sketch_map()))
    assert "read as a colour-coded sketch map" in r.notes
    tools = [c.tool for c in r.calls]
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
    assert material.has_water()[40:, 130:].all() and not material.has_water()[:, :120].any()
    assert material.soil_presets == ["dry_sand"] and material.has_soil()[:25, 175:].all()


def test_image_planner_is_deterministic_and_rejects_garbage():
    a, b = plan_image(_png(forest_photo())), plan_image(_png(forest_photo()))
    assert a.calls == b.calls
    with pytest.raises(ValueError, match="could not be read"):
        plan_image(b"not an image")


def test_docs_list_the_legend():
    from pathlib import Path

    doc = (Path(__file__).parents[1] / "docs" / "generation.md").read_text()
    for name, legend in LEGEND.items():
        r, g, b = legend.rgb
        assert f"| `{name}` | ({r}, {g}, {b}) | `#{r:02x}{g:02x}{b:02x}` |" in doc, name
