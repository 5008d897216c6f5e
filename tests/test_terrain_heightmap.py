"""A heightmap array as a trainable terrain: a spec naming a .npy (cell size = resolution, vertical_scale in m
per unit) builds through every path training, evaluation and play use; bad arrays fail with one-line errors."""

import json
import types

import numpy as np
import pytest

from legged_gente.envs.gente_biped.gente_biped_config import GenteBipedCfg
from legged_gente.envs.terrain_arg import apply_terrain_arg
from legged_gente.generation.gente_compat import heightmap_spec
from legged_gente.generation.spec import TerrainSpec
from legged_gente.generation.validation import ValidationError
from legged_gente.terrain.heightmap import heightmap_heights
from legged_gente.terrain.terrain import Terrain

CELL, SCALE = 0.1, 0.005  # GenTe's 0.1 m cells and 0.005 m per int16 unit


def write_spec(folder, raw, name="hm", calls=(), resolution=CELL, size=None):
    np.save(folder / f"{name}.npy", raw)
    sx, sy = size or (raw.shape[0] * resolution, raw.shape[1] * resolution)
    doc = {"version": 1, "name": name, "size_x": sx, "size_y": sy, "resolution": resolution, "seed": 0,
           "calls": list(calls), "source": {}, "backend": "hand", "model": None,
           "heightmap": {"file": f"{name}.npy", "vertical_scale": SCALE}}
    path = folder / f"{name}.json"
    path.write_text(json.dumps(doc))
    return path


def ramp_int16(n=40, units_per_row=25):
    """Row i (along x) at i * units_per_row int16 units; a 1 m x 1 m block of 300 units at cells 30..39 x 5..14."""
    raw = (np.arange(n, dtype=np.int32)[:, None] * units_per_row * np.ones((1, n), np.int32)).astype(np.int16)
    raw[30:40, 5:15] += 300
    return raw


def one_tile_cfg(spec_path, size):
    return types.SimpleNamespace(mesh_type="heightfield", mode="generated", resolution=CELL, border_size=0.0,
                                 terrain_length=size, terrain_width=size, num_rows=1, num_cols=1,
                                 generated_specs=[str(spec_path)], static_friction=1.0, seed=0)


def test_int16_heightmap_builds_the_terrain_in_metres(tmp_path):
    path = write_spec(tmp_path, ramp_int16())
    with pytest.warns(UserWarning, match="no flat 1.0 m spawn patch"):  # a ramp everywhere
        terrain = Terrain(one_tile_cfg(path, 4.0), 1)
    h = terrain.height_field
    assert h.shape == (40, 40)
    # height = units * 0.005 m: row 7 -> 7 * 25 * 0.005 = 0.875 m; row 35 in the block -> (35 * 25 + 300) * 0.005
    assert h[7, 20] == pytest.approx(7 * 25 * 0.005)
    assert h[35, 10] == pytest.approx((35 * 25 + 300) * 0.005)
    assert h[35, 20] == pytest.approx(35 * 25 * 0.005)
    # world x of cell i is i * 0.1 m (the cell size stated by resolution): halfway between rows 7 and 8
    assert terrain.height_at(np.array([0.75]), np.array([2.0]))[0] == pytest.approx(7.5 * 25 * 0.005)


def test_spec_on_a_heightmap_with_water_on_top(tmp_path):
    raw = np.zeros((40, 40), np.int16)
    raw[:, 20:] = 100  # 0.5 m terrace on the left half
    water = {"tool": "water", "region": "right", "params": {"depth": 0.2, "flow": "still"}}
    path = write_spec(tmp_path, raw, calls=[water])
    spec = TerrainSpec.load(path)  # what evaluation reads
    heights, material = spec.build()
    assert heights[5, 5] == pytest.approx(0.0) and heights[5, 30] == pytest.approx(100 * 0.005)
    # water depth from the lowest ground of its region (the flat right half at 0 m): surface at 0.2 m
    assert material.water_surface[5, 5] == pytest.approx(0.2)


def test_terrain_arg_takes_the_heightmap_spec(tmp_path):
    path = write_spec(tmp_path, ramp_int16(), name="ramp")
    cfg = GenteBipedCfg()
    apply_terrain_arg(str(path), cfg)
    assert (cfg.terrain.terrain_length, cfg.terrain.terrain_width, cfg.terrain.resolution) == (4.0, 4.0, CELL)
    cfg.terrain.border_size = 0.0
    with pytest.warns(UserWarning, match="no flat 1.0 m spawn patch"):
        terrain = Terrain(cfg.terrain, 1)
    assert terrain.height_field[7, 20] == pytest.approx(7 * 25 * 0.005)
    with pytest.raises(ValueError, match="no cell size or height scale"):
        apply_terrain_arg(str(tmp_path / "ramp.npy"), cfg)


def test_overflowed_int16_heightmap_is_refused(tmp_path):
    # GenTe-style stacking in int16: 40 rows of 1000 units; 33 * 1000 = 33000 > 32767 wraps to 33000 - 65536
    true = np.arange(40, dtype=np.int64)[:, None] * 1000 * np.ones((1, 40), np.int64)
    raw = true.astype(np.int16)
    assert raw[33, 0] == 33000 - 65536
    path = write_spec(tmp_path, raw, name="wrapped")
    # 40 wrap edges (one per column, between rows 32 and 33); unwrapped peak 39 * 1000 * 0.005 = 195 m
    with pytest.raises(ValueError, match=r"wrapped around the int16 range at 40 cell edges .* reach \|height\| 195\.0 m"):
        Terrain(one_tile_cfg(path, 4.0), 1)
    with pytest.raises(ValidationError, match="wrapped around the int16 range"):
        TerrainSpec.load(path)


def test_an_8_bit_map_with_a_tall_block_keeps_its_heights():
    """A 2 x 2 block of 150 uint8 units at 0.01 m per unit is a 1.5 m block, not a wrap-around: 8-bit maps span
    too few units to tell one from the other (half the uint8 range is 1.28 m here), so none is refused."""
    raw = np.zeros((4, 4), np.uint8)
    raw[1:3, 1:3] = 150
    expected = np.zeros((4, 4))
    expected[1:3, 1:3] = 1.5
    assert np.allclose(heightmap_heights(raw, 0.01, 10.0), expected, atol=1e-6)
    signed = np.array([[-100, 100], [100, -100]], np.int8)  # neighbours 200 units (2 m) apart
    assert np.allclose(heightmap_heights(signed, 0.01, 10.0), [[-1.0, 1.0], [1.0, -1.0]], atol=1e-6)
    wrapped = np.array([[32767, -32768], [32767, -32768]], np.int16)  # +32767 + 1 wrapped: 2 edges
    with pytest.raises(ValueError, match="wrapped around the int16 range at 2 cell edges"):
        heightmap_heights(wrapped, SCALE, 10.0)


@pytest.mark.parametrize("raw, size, expected", [
    (np.full((40, 40), 2500, np.int16), None, r"reaches \|height\| 12.50 m > 10.0 m"),  # 2500 * 0.005
    (np.zeros((40, 40, 2), np.int16), (4.0, 4.0), "2-D array"),
    (np.zeros((40, 40), np.int16), (4.0, 2.0), r"size_x=4, size_y=4 m, not 4 x 2 m"),
    (np.where(np.eye(40, dtype=bool), np.nan, 0.0), None, "40 NaN or infinite values"),
    (np.zeros((40, 40), bool), None, "holds bool values"),
])
def test_bad_heightmaps_fail_in_one_line(tmp_path, raw, size, expected):
    path = write_spec(tmp_path, raw, size=size)
    for load in (lambda: TerrainSpec.load(path), lambda: Terrain(one_tile_cfg(path, 4.0), 1)):
        with pytest.raises(ValueError, match=expected) as info:
            load()
        assert "\n" not in str(info.value) and ".." not in str(info.value)


def test_unreadable_and_missing_files(tmp_path):
    path = write_spec(tmp_path, np.zeros((40, 40), np.int16))
    np.save(tmp_path / "hm.npy", np.array([{"a": 1}] * 4, dtype=object))  # a pickle: never loaded
    with pytest.raises(ValidationError, match="not a readable .npy array"):
        TerrainSpec.load(path)
    (tmp_path / "hm.npy").unlink()
    with pytest.raises(ValidationError, match="hm.npy does not exist"):
        TerrainSpec.load(path)
    (tmp_path / "hm.npy").mkdir()
    with pytest.raises(ValidationError, match="hm.npy is a folder, not a file; give a .npy path"):
        TerrainSpec.load(path)


def test_gente_heightmap_spec(tmp_path):
    raw = np.zeros((200, 200), np.int16)
    raw[100:, :] = 400  # a 2 m step halfway along x
    np.save(tmp_path / "array.npy", raw)
    spec = heightmap_spec("array.npy", "gente_map", tmp_path)
    assert (spec.size_x, spec.size_y, spec.resolution) == (20.0, 20.0, 0.1)
    path = spec.save(tmp_path / "gente_map.json")
    heights, _ = TerrainSpec.load(path).build()
    assert heights[99, 0] == 0.0 and heights[100, 0] == pytest.approx(400 * 0.005)
