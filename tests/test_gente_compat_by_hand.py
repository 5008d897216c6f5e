"""GenTe's calls translated, checked by hand against what GenTe's own code builds.

GenTe facts are read from github.com/HaronW/GenTe at commit 60ceed6 (utils/terrain_utils_single.py,
utils/terrain_utils_parts.py, generate_dataset.py): a 200 x 200 grid of 0.1 m cells, int16 heights of 0.005 m,
part p of the multi-part tile at x0 = 100 cells for p in (2, 4), y0 = 100 cells for p in (3, 4). Its noise is
``noise.pnoise2`` (github.com/caseman/noise, _perlin.c ``py_noise2``).
"""

from __future__ import annotations

import numpy as np
import pytest

from legged_gente.generation.gente_compat import translate_call
from legged_gente.generation.spec import TerrainSpec


def _heights(translation) -> np.ndarray:
    assert not translation.blocked, translation.issues
    heights, _ = TerrainSpec(calls=translation.calls, name="gente").build()
    return heights.astype(np.float64)


# ---------------------------------------------------------------------------------------------- natural ground
@pytest.mark.parametrize("octaves, persistence", [(6, 0.1), (5, 0.2)])
def test_natural_ground_of_lacunarity_one_is_one_octave(octaves, persistence):
    # GenTe: pnoise2(x / scale, y / scale, octaves, persistence, lacunarity) (terrain_utils_single.py l. 28,
    # terrain_utils_parts.py l. 34). pnoise2 sums noise2(x * f_k, y * f_k) * p**k with f_k = lacunarity**k and
    # divides by sum(p**k). With lacunarity 1 every f_k is 1, every octave the same noise, and the sum is
    # noise2(x, y) * sum(p**k) / sum(p**k): one octave, whatever octaves and persistence say.
    t = translate_call("natural_ground_terrain", {"scale": 10.0, "octaves": octaves, "persistence": persistence,
                                                  "lacunarity": 1, "height_multiplier": 0.3}, "single")
    (ground,) = t.calls
    assert ground.params["octaves"] == 1
    assert ground.params["wavelength"] == pytest.approx(10.0 * 0.1) and ground.params["amplitude"] == pytest.approx(0.3)
    # the octaves GenTe asked for and did not draw are reported, not dropped silently
    assert any(i.kind == "ignored_argument" and f"octaves={octaves}" in i.message for i in t.issues)


def test_natural_ground_of_lacunarity_two_keeps_its_octaves():
    # lacunarity 2 is our natural_ground's own frequency doubling: octaves and persistence import as given
    (ground,) = translate_call("natural_ground_terrain", {"scale": 20.0, "octaves": 4, "persistence": 0.5,
                                                          "lacunarity": 2.0, "height_multiplier": 0.2}, "single").calls
    assert (ground.params["octaves"], ground.params["persistence"]) == (4, 0.5)


# ---------------------------------------------------------------------------------------------- pyramid stairs
def test_pyramid_stairs_rise_from_the_ground_at_the_part_edge():
    # GenTe pyramid_stairs_terrain(step_width=0.4, step_height=0.1, platform_size=1) in part 1
    # (terrain_utils_parts.py l. 302-317): 4 cells, 20 units, 10 cells; height starts at 0 and ring k (cells
    # [4k, 100 - 4k)) is set to 20 k units while 100 - 8 (k - 1) > 10, i.e. k = 1 .. 12. So the part's outer
    # ring keeps the ground (0 m), no cell goes below it, and the centre is 12 * 0.1 = 1.2 m up.
    h = _heights(translate_call("pyramid_stairs_terrain", {"step_width": 0.4, "step_height": 0.1,
                                                           "platform_size": 1.0, "part": 1}))
    part = h[:100, :100]  # part 1: x and y in [0, 10) m
    assert h[50, 50] == pytest.approx(1.2, abs=1e-6)  # x = y = 5.0 m, the part's centre
    assert part.max() == pytest.approx(1.2, abs=1e-6) and part.min() == pytest.approx(0.0, abs=1e-6)
    assert h[0, 50] == pytest.approx(0.0, abs=1e-6) and h[50, 0] == pytest.approx(0.0, abs=1e-6)  # its edges


def test_pyramid_stairs_of_negative_step_fall_from_the_ground_at_the_part_edge():
    # the same with step_height=-0.1: ring k at -20 k units, a hollow 1.2 m deep at the centre, the edge at 0 m
    h = _heights(translate_call("pyramid_stairs_terrain", {"step_width": 0.4, "step_height": -0.1,
                                                           "platform_size": 1.0, "part": 1}))
    part = h[:100, :100]
    assert h[50, 50] == pytest.approx(-1.2, abs=1e-6)
    assert part.min() == pytest.approx(-1.2, abs=1e-6) and part.max() == pytest.approx(0.0, abs=1e-6)
    assert h[0, 50] == pytest.approx(0.0, abs=1e-6)


def test_pyramid_stairs_lift_beyond_a_flat_call_is_reported_or_rejected():
    # step_height=0.2 in the same part: 12 rings, a centre 2.4 m up, beyond the 2 m a flat lift carries
    imported = translate_call("pyramid_stairs_terrain", {"step_width": 0.4, "step_height": 0.2, "platform_size": 1.0,
                                                         "part": 1})
    lift, _ = imported.calls
    assert (lift.tool, lift.params["height"]) == ("flat", 2.0)
    assert [i.kind for i in imported.issues] == ["clamped"] and "2.4" in imported.issues[0].message
    live = translate_call("pyramid_stairs_terrain", {"step_width": 0.4, "step_height": 0.2, "platform_size": 1.0,
                                                     "part": 1}, live=True)
    assert live.blocked and not live.calls and "send a value inside it" in live.issues[-1].message
