"""A tile composed in Python (docs/terrain.md, "Composition") is trained on as it is: the JSON of
``TileSpec.to_dict()`` is a --terrain file, and builds the very same heights and materials. Before, --terrain took
gente-generate's document form only ('calls'), and said ''parts' was unexpected'."""

import json

import numpy as np
import pytest

from legged_gente.envs.task_registry import task_registry
from legged_gente.envs.terrain_arg import apply_terrain_arg
from legged_gente.terrain.composition import Operation, Part, Region, TileSpec, quadrant
from legged_gente.terrain.terrain import Terrain


def tile():
    return TileSpec(size_x=8.0, size_y=8.0, resolution=0.1, seed=3, parts=[
        Part(quadrant("back_right", 8, 8), [Operation("river", {"depth": 0.5}), Operation("water", {"depth": 0.3})]),
        Part(quadrant("front_left", 8, 8), [Operation("stairs", {"step_height": 0.12})]),
        Part(Region(0.0, 0.0, 8.0, 8.0), [Operation("rocks", {"max_height": 0.1}, mode="add")]),
        Part(quadrant("front_right", 8, 8), [Operation("soil", {"preset": "wet_sand"})]),
    ])


def test_the_tile_dict_trains_as_the_tile_it_came_from(tmp_path):
    path = tmp_path / "my_tile.json"
    path.write_text(json.dumps(tile().to_dict()))
    env_cfg, _ = task_registry.get_cfgs("gente_biped")
    apply_terrain_arg(str(path), env_cfg)
    terrain = Terrain(env_cfg.terrain, num_robots=1)
    heights, material = tile().build(ground_friction=float(env_cfg.terrain.static_friction))
    border = int(round(env_cfg.terrain.border_size / 0.1))
    inner = terrain.height_field[border:border + 80, border:border + 80]
    np.testing.assert_array_equal(inner, heights)
    assert terrain.material.soil_presets == material.soil_presets == ["wet_sand"]
    assert (terrain.material.water_surface[border:border + 80, border:border + 80] == material.water_surface).all()


def test_a_misspelt_key_of_the_tile_dict_is_refused(tmp_path):
    path = tmp_path / "my_tile.json"
    path.write_text(json.dumps(tile().to_dict() | {"smoothin": []}))
    env_cfg, _ = task_registry.get_cfgs("gente_biped")
    with pytest.raises(ValueError, match=r"unknown key\(s\) \['smoothin'\]"):
        apply_terrain_arg(str(path), env_cfg)
