"""Sketch water drawn against sketch stairs stands in ground that holds it.

A flight of stairs starts about half its rise below the ground and is blended into its surroundings over the seam
band (0.3 m), so a basin rim within that band is pulled down below the waterline; water must keep the planner's
margin (the seam band and two more 0.1 m cells: 0.3 + 0.2 = 0.5 m) off every stairs rectangle it meets.
"""

import pytest
from PIL import Image, ImageDraw

from legged_gente.generation.backends.image import LEGEND, plan_image
from legged_gente.generation.checker import water_walls
from legged_gente.generation.pipeline import generate_spec

WATER, STAIRS = LEGEND["water"].rgb, LEGEND["stairs"].rgb
MARGIN = 0.3 + 0.2  # seam band + two 0.1 m cells (m)


def _sketch(tmp_path, draw):
    img = Image.new("RGB", (96, 96), LEGEND["grass"].rgb)
    draw(ImageDraw.Draw(img))
    path = tmp_path / "sketch.png"
    img.save(path)
    return path


def _gap(a, b) -> float:
    """Distance (m) between two rectangles (x0, y0, x1, y1); 0 when they touch or overlap."""
    dx = max(a[0] - b[2], b[0] - a[2], 0.0)
    dy = max(a[1] - b[3], b[1] - a[3], 0.0)
    return max(dx, dy)


@pytest.mark.parametrize("name, draw", [
    # The stairs rise towards the top (+x): their foot is their bottom edge, here on the pond's top edge.
    ("pond at the foot of the stairs", lambda d: (d.rectangle([30, 10, 65, 47], fill=STAIRS),
                                                  d.rectangle([30, 48, 65, 80], fill=WATER))),
    ("pond beside the stairs", lambda d: (d.rectangle([10, 10, 40, 85], fill=STAIRS),
                                          d.rectangle([41, 30, 80, 70], fill=WATER))),
    ("stairs across a river", lambda d: (d.rectangle([10, 30, 85, 70], fill=WATER),
                                         d.rectangle([40, 5, 55, 90], fill=STAIRS))),
])
def test_sketch_water_against_stairs_has_no_water_wall(tmp_path, name, draw):
    path = _sketch(tmp_path, draw)
    calls = plan_image(path).calls
    stairs = [c.region for c in calls if c.tool == "stairs"]
    water = [c.region for c in calls if c.tool in ("water", "basin")]
    assert stairs and water, name
    assert min(_gap(w, s) for w in water for s in stairs) >= MARGIN - 1e-9, name
    spec, _ = generate_spec(image=path)
    heights, material = spec.build()
    assert material.has_water().any(), name
    assert water_walls(heights, material)[0] == 0, name


def test_water_with_no_room_beside_stairs_is_left_out_with_a_warning(tmp_path):
    # A 4 px (one block, 20 / 24 = 0.83 m) water strip between two flights: 0.83 m < 2 * 0.5 m, nothing is left.
    path = _sketch(tmp_path, lambda d: (d.rectangle([0, 0, 47, 95], fill=STAIRS),
                                        d.rectangle([48, 0, 51, 95], fill=WATER),
                                        d.rectangle([52, 0, 95, 95], fill=STAIRS)))
    result = plan_image(path)
    assert not [c for c in result.calls if c.tool in ("water", "basin")]
    assert any("water" in w and "stairs" in w for w in result.warnings), result.warnings
