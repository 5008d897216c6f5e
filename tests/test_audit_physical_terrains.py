"""Physical terrains and the material map, checked by hand: what water, soil and low friction a terrain declares.

Water fills its region up to ``depth`` above the region's lowest ground (docs/terrain.md, "Physical layers"); a
river's bank is a cosine profile ``-D (1 + cos(pi t)) / 2``, ``t`` from 0 at the bed edge to 1 at the bank top.
"""

import math

import numpy as np
import pytest

from legged_gente.envs.gente_biped.gente_biped_config import GenteBipedCfg
from legged_gente.envs.gente_quadruped.gente_quadruped_config import GenteQuadrupedCfg
from legged_gente.generation.checker import water_walls
from legged_gente.terrain.composition import Operation, Part, Region, TileSpec, tile_spec_from_document
from legged_gente.terrain.materials import FLOW_CURRENT
from legged_gente.terrain.registry import ATOMIC_TERRAINS
from legged_gente.terrain.terrain import Terrain, parse_terrain_type


# ------------------------------------------------------------------------------------ still water with a speed

def test_a_speed_on_still_water_is_refused_naming_the_flow():
    """``water:speed=0.5`` (flow left at its default, still) built still water and threw the 0.5 m/s away."""
    water = ATOMIC_TERRAINS["water"]
    with pytest.raises(ValueError, match=r"water: speed=0.5 m/s .*still.*flow=current or flow=tide"):
        water.check_params({"speed": 0.5})
    with pytest.raises(ValueError, match=r"water: speed=0.5 m/s"):
        parse_terrain_type("water:speed=0.5")  # a curriculum entry
    document = {"size_x": 2.0, "size_y": 2.0, "resolution": 0.1, "seed": 0,
                "calls": [{"tool": "water", "region": "full", "params": {"depth": 0.2, "flow": "still", "speed": 1.0}}]}
    with pytest.raises(ValueError, match=r"water: speed=1.0 m/s"):
        tile_spec_from_document(document).build()


def test_water_with_a_consistent_flow_still_builds():
    water = ATOMIC_TERRAINS["water"]
    assert water.check_params({"flow": "current", "speed": 0.5})["speed"] == 0.5
    assert water.check_params({"flow": "tide", "speed": 0.3})["flow"] == "tide"
    assert water.check_params({"flow": "still", "speed": 0.0})["speed"] == 0.0
    # zero means none, as depth 0 is no water: a current of 0 m/s is still water (the scorer's "no flow")
    assert water.check_params({"flow": "current", "speed": 0.0})["speed"] == 0.0


# ------------------------------------------------------------------------------------ river + water by hand

@pytest.mark.parametrize("difficulty", [0.0, 0.5, 1.0, 1.65])
def test_river_plus_water_surface_and_wet_width_by_hand(difficulty):
    """The curriculum's "river+water": bed at -D, surface at -D + w, wet where the bank is below the surface.

    Channel along y (direction pi/2) through the centre of an 8 m tile at 0.1 m: node i lies at
    x = (i - 39.5) * 0.1 m from the axis. D = 0.1 + 0.5 d, W = 2 + 2 d (river), w = 0.05 + 0.45 d (water),
    bank b = 0.5 m. On the bank -D (1 + cos(pi t)) / 2 < -D + w  <=>  cos(pi t) > 1 - 2 w / D, so the water
    reaches |x| < W / 2 - b + b acos(1 - 2 w / D) / pi.
    """
    d = difficulty
    depth_river, width, bank, depth_water = 0.1 + 0.5 * d, 2.0 + 2.0 * d, 0.5, 0.05 + 0.45 * d
    river = ATOMIC_TERRAINS["river"].params_for_difficulty(d)
    water = ATOMIC_TERRAINS["water"].params_for_difficulty(d)
    assert (river["depth"], river["width"], river["bank_width"], water["depth"]) == pytest.approx(
        (depth_river, width, bank, depth_water))
    spec = TileSpec(8.0, 8.0, 0.1, 0, [Part(Region(0.0, 0.0, 8.0, 8.0), [Operation("river", river),
                                                                        Operation("water", water)])])
    heights, material = spec.build()
    surface = -depth_river + depth_water
    assert heights.min() == pytest.approx(-depth_river, abs=1e-6)
    reach = width / 2 - bank + bank * math.acos(1.0 - 2.0 * depth_water / depth_river) / math.pi
    x = np.abs((np.arange(80) - 39.5) * 0.1)
    wet = material.has_water()
    assert (wet == (x < reach - 1e-6)[:, None]).all()  # no node within 1e-6 m of the reach at these difficulties
    np.testing.assert_allclose(material.water_surface[wet], surface, atol=1e-6)
    assert surface < 0.0  # below the bank tops (0 m): the channel holds its water


# ------------------------------------------------------------------------------- the curriculum's current

def _current_column(cfg) -> str:
    return next(t for t in cfg.terrain.terrain_types if "flow=current" in t)


@pytest.mark.parametrize("cfg, basin, water", [
    # the basin's depth ramps 0.1 + 0.5 d (its registry map), the water's 0.05 + 0.45 d
    (GenteBipedCfg, lambda d: 0.1 + 0.5 * d, lambda d: 0.05 + 0.45 * d),
    (GenteQuadrupedCfg, lambda d: 0.2, lambda d: 0.12),  # both fixed: 12 cm of water for the short legs
])
def test_the_curriculum_current_flows_in_a_basin_that_holds_it(cfg, basin, water):
    """The curriculum's current tile was water on flat ground: its water stood as a wall at the column's edges. It
    lies in a basin now: the surface stays below the rim and no wet cell stands over a dry neighbour's ground."""

    class Cfg:
        mesh_type, mode, resolution, border_size = "heightfield", "curriculum", 0.1, 0.5
        terrain_length = terrain_width = 8.0
        num_rows, num_cols, max_difficulty = 3, 1, 1.0
        terrain_types, terrain_proportions = [_current_column(cfg)], [1.0]
        static_friction, seed = 1.0, 0

    t = Terrain(Cfg, num_robots=1)
    h, m, b, n = t.height_field, t.material, 5, 80  # border cells, tile cells
    assert water_walls(h, m)[0] == 0
    speed = float(parse_terrain_type(_current_column(cfg).split("+")[-1])[1]["speed"])
    for row, d in enumerate((0.0, 0.5, 1.0)):
        tile = (slice(b + row * n, b + (row + 1) * n), slice(b, b + n))
        wet = m.has_water()[tile]
        assert h[tile].min() == pytest.approx(-basin(d), abs=1e-6)  # the basin's flat bottom
        np.testing.assert_allclose(m.water_surface[tile][wet], -basin(d) + water(d), atol=1e-6)
        assert -basin(d) + water(d) < 0.0  # below the rim
        assert wet[n // 2, n // 2] and not wet[0, 0]  # wet in the middle, dry on the rim
        assert (m.flow_kind[tile][wet] == FLOW_CURRENT).all()
        np.testing.assert_allclose(m.flow_speed[tile][wet], speed)
        np.testing.assert_allclose(m.flow_direction[tile][wet], 0.0)  # towards +x
