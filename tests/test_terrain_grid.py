"""The Terrain grid: modes, curriculum layout, spawn points, height sampling, material map, export, preview."""

import re
import warnings

import numpy as np
import pytest

from legged_gente.terrain.materials import NO_SOIL
from legged_gente.terrain.registry import ATOMIC_TERRAINS
from legged_gente.terrain.terrain import (
    SPAWN_FOOTPRINT,
    SPAWN_MAX_RANGE,
    Terrain,
    allocate_columns,
    parse_terrain_type,
    parse_tile_type,
)


class TerrainCfg:
    """Mirror of LeggedRobotCfg.terrain's attributes (small sizes for tests)."""

    mesh_type = "heightfield"
    mode = "curriculum"
    resolution = 0.1
    border_size = 1.0
    terrain_length = 4.0
    terrain_width = 4.0
    num_rows = 3
    num_cols = 6
    terrain_types = ["pyramid_slope", "stairs:direction=down", "pillars", "rocks", "river+water", "soil:preset=wet_sand"]
    terrain_proportions = [0.2, 0.2, 0.2, 0.2, 0.1, 0.1]
    selected_terrain = "pyramid_stairs"
    selected_params = {"step_height": 0.12}
    generated_specs = []
    max_difficulty = 1.0
    max_init_terrain_level = 1
    curriculum = True
    static_friction = 0.9
    seed = 5


def cfg(**overrides):
    return type("Cfg", (TerrainCfg,), overrides)


@pytest.fixture(scope="module")
def curriculum():
    return Terrain(TerrainCfg, num_robots=12)


def test_allocate_columns_by_proportions():
    assert allocate_columns([0.5, 0.25, 0.25], 8).tolist() == [0, 0, 0, 0, 1, 1, 2, 2]
    assert np.bincount(allocate_columns([0.3, 0.3, 0.4], 10)).tolist() == [3, 3, 4]
    with pytest.warns(UserWarning, match="normalising"):
        allocate_columns([1.0, 1.0], 4)
    with pytest.warns(UserWarning, match="no column"):
        allocate_columns([0.9, 0.1], 3)
    with pytest.raises(ValueError, match="non-negative"):
        allocate_columns([-1.0, 2.0], 3)


def test_parse_terrain_type():
    assert parse_tile_type("river+water:depth=0.2") == [[("river", {}), ("water", {"depth": 0.2})]]
    assert parse_terrain_type("water:flow=current,speed=0.5") == ("water", {"flow": "current", "speed": 0.5})
    with pytest.raises(ValueError, match="unknown atomic terrain 'lava'"):
        parse_terrain_type("lava")
    with pytest.raises(ValueError, match="not key=value"):
        parse_terrain_type("stairs:down")
    with pytest.raises(ValueError, match="step_height=2.0 m is outside"):
        parse_terrain_type("stairs:step_height=2")


@pytest.mark.parametrize("value", ["inf", "-inf", "nan"])
@pytest.mark.parametrize("entry, expected", [
    ("natural_ground:octaves", r"natural_ground: octaves={} is not a finite number; choose a value in \[1, 6\] 1\."),
    ("stairs:step_height", r"stairs: step_height={} is not a finite number; choose a value in \[0.0, 0.3\] m\."),
], ids=["octaves", "step_height"])
def test_a_non_finite_parameter_names_the_terrain_the_parameter_and_its_range(value, entry, expected):
    """octaves is a whole number in [1, 6] (unit 1), step_height a length in [0, 0.3] m: inf and nan are neither."""
    with pytest.raises(ValueError, match=f"^{expected.format(value)}$"):
        parse_terrain_type(f"{entry}={value}")


def test_a_whole_number_too_large_for_a_float_is_out_of_range():
    """A spec's JSON may hold any integer: 10**400 is finite, and above octaves' 6."""
    with pytest.raises(ValueError, match=r"^natural_ground: octaves=1000*0 1 is outside \[1, 6\] 1; choose"):
        ATOMIC_TERRAINS["natural_ground"].check_params({"octaves": 10**400})


def test_curriculum_layout(curriculum):
    t = curriculum
    assert t.height_field.shape == (3 * 40 + 20, 6 * 40 + 20) and t.height_field.dtype == np.float32
    assert t.material.shape == t.height_field.shape
    assert t.origin_xy == (-1.0, -1.0)
    assert (t.num_rows, t.num_cols, t.tile_size) == (3, 6, (4.0, 4.0))
    assert t.tile_type_names == TerrainCfg.terrain_types
    assert t.terrain_types.tolist() == [0, 1, 2, 3, 4, 5]
    assert t.terrain_origins.shape == (3, 6, 3)
    # 4 m tiles from world (0, 0): tile (row 2, column 5) spans x 8-12 m, y 20-24 m
    assert t.tile_bounds(np.array([0, 2]), np.array([0, 5])).tolist() == [[0, 0, 4, 4], [8, 20, 12, 24]]
    # Rows get harder: the slope column's highest point grows with the row.
    peaks = [t.height_field[10 + r * 40 : 50 + r * 40, 10:50].max() for r in range(3)]
    assert peaks[0] < peaks[1] < peaks[2]
    # Border is flat, rigid, at the configured friction.
    assert np.all(t.height_field[:10] == 0) and np.all(t.material.friction[:10] == np.float32(0.9))


def test_max_difficulty_extends_every_ramp_past_the_standard_top_level():
    """Rows 0, 0.75, 1.5: the stairs' ramp (0.05 m + 0.15 m per unit of difficulty) goes on to 0.275 m steps;
    friction's (1.0 - 0.9 per unit) reaches ice, 0.1, at difficulty 1 and stays there."""
    t = Terrain(cfg(num_cols=2, terrain_types=["pyramid_stairs", "low_friction"], terrain_proportions=[0.5, 0.5],
                    max_difficulty=1.5), num_robots=2)
    for row, difficulty in enumerate((0.0, 0.75, 1.5)):
        stairs = t.height_field[10 + 40 * row : 50 + 40 * row, 10:50]
        assert np.allclose(np.diff(np.unique(stairs)), 0.05 + 0.15 * difficulty, atol=1e-6)
        friction = t.material.friction[10 + 40 * row : 50 + 40 * row, 50:90]
        assert np.allclose(friction, max(1.0 - 0.9 * difficulty, 0.1))


def test_max_difficulty_errors_name_the_terrain_and_the_fix():
    with pytest.raises(ValueError, match=r"max_difficulty=2.5 must be in \(0, 2.0\]"):
        Terrain(cfg(max_difficulty=2.5), num_robots=2)
    # stepping stones: 1.2 m - 0.8 m per unit of difficulty, below their 0.2 m minimum past 1.25 (-0.08 m at 1.6)
    with pytest.raises(ValueError, match=r"difficulty 1.6: stepping_stones: stone_size=-0.080*7? m is outside .* "
                                         r"Lower terrain.max_difficulty, or fix .*'stepping_stones:<param>=<value>'"):
        Terrain(cfg(num_cols=1, terrain_types=["stepping_stones"], terrain_proportions=[1.0], max_difficulty=1.6),
                num_robots=2)
    Terrain(cfg(num_cols=1, terrain_types=["stepping_stones:stone_size=0.5"], terrain_proportions=[1.0],
                max_difficulty=1.6), num_robots=2)  # the fix the message names


def one_tile(terrain_type):
    """A terrain of one 4 m tile (40 x 40 cells, no border) of ``terrain_type`` at difficulty 0."""
    return Terrain(cfg(num_rows=1, num_cols=1, border_size=0.0, terrain_types=[terrain_type], terrain_proportions=[1.0]),
                   num_robots=1)


def test_a_plus_entry_adds_its_geometric_atomics_in_order():
    """An entry "a+b" is b on a: the first geometric atomic sets the heights, each later one adds to them."""
    assert np.allclose(one_tile("flat:height=0.5+flat:height=0.25").height_field, 0.75, atol=1e-6)
    # A pyramid slope of 0.3 rad with its 1.2 m platform on ground raised 0.5 m: cell i lies at
    # x = (i - 19.5) * 0.1 m from the tile centre; it rises tan(0.3) per metre beyond 0.6 m (Chebyshev distance).
    x = (np.arange(40) - 19.5) * 0.1
    distance = np.maximum(np.abs(x)[:, None], np.abs(x)[None, :])
    expected = 0.5 + np.tan(0.3) * np.maximum(distance - 0.6, 0.0)
    assert np.allclose(one_tile("flat:height=0.5+pyramid_slope:slope=0.3").height_field, expected, atol=1e-5)
    assert np.allclose(one_tile("pyramid_slope:slope=0.3+flat:height=0.5").height_field, expected, atol=1e-5)
    # A physical atomic between them changes no height: the water lies on the summed ground.
    t = one_tile("flat:height=0.5+water:depth=0.2+flat:height=0.25")
    assert np.allclose(t.height_field, 0.75, atol=1e-6)
    assert np.allclose(t.material.water_surface, 0.75 + 0.2, atol=1e-6)


def test_a_plus_entry_higher_than_the_tile_bound_names_the_entry():
    """Six 2 m raises stack to 12 m, over the 10 m bound."""
    entry = "+".join(["flat:height=2"] * 6)
    with pytest.raises(ValueError, match=rf"tile \(0, 0\) '{re.escape(entry)}': .*reach 12.00 m > 10.0 m"):
        one_tile(entry)


def test_a_border_of_part_of_a_cell_is_refused():
    with pytest.raises(ValueError, match=r"^border_size=0.25 m is not a whole number of resolution=0.1 m cells; "
                                         r"adjust it.$"):
        Terrain(cfg(border_size=0.25), 1)
    assert Terrain(cfg(border_size=0.3), 1).origin_xy == pytest.approx((-0.3, -0.3))


def test_curriculum_materials(curriculum):
    t = curriculum
    water_tile = (slice(10 + 40, 50 + 40), slice(10 + 4 * 40, 50 + 4 * 40))
    soil_tile = (slice(10, 50), slice(10 + 5 * 40, 50 + 5 * 40))
    wet = t.material.has_water()[water_tile]
    assert wet.any() and not wet.all()  # the river's channel holds the water, its banks are dry
    ground = t.height_field[water_tile]
    assert np.all(ground[wet] < t.material.water_surface[water_tile][wet])
    assert t.material.soil_presets == ["wet_sand"]
    assert (t.material.soil[soil_tile] == 0).all()
    assert (t.material.soil[water_tile] == NO_SOIL).all() and not t.material.has_water()[soil_tile].any()


def footprint(t, origin):
    i = int(round((origin[0] - t.origin_xy[0]) / t.resolution))
    j = int(round((origin[1] - t.origin_xy[1]) / t.resolution))
    half = int(round(SPAWN_FOOTPRINT / t.resolution / 2))
    return t.height_field[i - half : i + half + 1, j - half : j + half + 1]


def test_spawn_points_clear(curriculum):
    t = curriculum
    for r in range(t.num_rows):
        for c in range(t.num_cols):
            o = t.terrain_origins[r, c]
            assert r * 4.0 < o[0] < (r + 1) * 4.0 and c * 4.0 < o[1] < (c + 1) * 4.0
            patch = footprint(t, o)
            assert np.ptp(patch) <= SPAWN_MAX_RANGE + 1e-6, (r, c)
            assert abs(o[2] - patch.max()) <= SPAWN_MAX_RANGE + 1e-6


def test_spawn_moves_off_obstacles_when_the_centre_is_blocked():
    # Dense pillars with no central clearing: the spawn must still land on a clear patch.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        t = Terrain(cfg(mode="selected", selected_terrain="pillars",
                        selected_params={"density": 0.3, "platform": 0.0, "max_radius": 0.2}), 4)
    for o in t.terrain_origins.reshape(-1, 3):
        assert np.ptp(footprint(t, o)) <= SPAWN_MAX_RANGE + 1e-6 and o[2] < 0.01
    with pytest.warns(UserWarning, match="no flat"):
        Terrain(cfg(mode="selected", selected_terrain="natural_ground",
                    selected_params={"amplitude": 0.5, "wavelength": 0.5, "platform": 0.0}), 1)


def test_height_at_bilinear(curriculum):
    t = curriculum
    rng = np.random.default_rng(0)
    i = rng.integers(0, t.height_field.shape[0] - 1, 50)
    j = rng.integers(0, t.height_field.shape[1] - 1, 50)
    x = t.origin_xy[0] + i * t.resolution
    y = t.origin_xy[1] + j * t.resolution
    assert np.allclose(t.height_at(x, y), t.height_field[i, j], atol=1e-6)
    mid = t.height_at(x + 0.5 * t.resolution, y + 0.5 * t.resolution)
    expected = t.height_field[i, j] + t.height_field[i + 1, j] + t.height_field[i, j + 1] + t.height_field[i + 1, j + 1]
    assert np.allclose(mid, expected / 4, atol=1e-6)
    assert t.height_at(np.zeros((2, 3)), np.zeros((2, 3))).shape == (2, 3)


def test_random_selected_plane_modes():
    r1, r2 = Terrain(cfg(mode="random"), 1), Terrain(cfg(mode="random"), 1)
    assert np.array_equal(r1.height_field, r2.height_field)
    assert set(r1.tile_names.ravel()) <= set(TerrainCfg.terrain_types)
    assert (r1.terrain_types == -1).all()
    s = Terrain(cfg(mode="selected"), 1)
    assert set(s.tile_type_names) == {"pyramid_stairs"}
    tile = s.height_field[10:50, 10:50]
    assert np.allclose(np.unique(np.round(tile, 6)) % 0.12, 0.0, atol=1e-5)
    p = Terrain(cfg(mesh_type="plane"), 1)
    assert not p.height_field.any() and p.tile_type_names == ["plane"] * 6
    with pytest.raises(ValueError, match="selected_terrain 'lava'"):
        Terrain(cfg(mode="selected", selected_terrain="lava"), 1)
    with pytest.raises(ValueError, match="one proportion per type"):
        Terrain(cfg(terrain_proportions=[1.0]), 1)
    with pytest.raises(ValueError, match="terrain_length=4.05 m is not a whole number"):
        Terrain(cfg(terrain_length=4.05), 1)
    with pytest.raises(ValueError, match="mode 'lava'"):
        Terrain(cfg(mode="lava"), 1)


def test_generated_mode(tmp_path):
    from legged_gente.generation.spec import TerrainSpec
    from legged_gente.generation.validation import ToolCall

    def call(tool, params, rect, mode):
        return ToolCall(tool, ATOMIC_TERRAINS[tool].check_params(params), rect, mode)

    paths = []
    for k, (tool, params) in enumerate([("pyramid_slope", {"slope": 0.3}), ("rocks", {"max_height": 0.2})]):
        calls = [call(tool, params, (0.0, 0.0, 4.0, 4.0), "set"), call("water", {"depth": 0.1}, (0.0, 0.0, 2.0, 2.0), None)]
        spec = TerrainSpec(calls=calls, name=f"spec{k}", size_x=4.0, size_y=4.0, resolution=0.1, seed=k)
        paths.append(str(spec.save(tmp_path / f"spec{k}.json")))
    t = Terrain(cfg(mode="generated", num_rows=1, num_cols=2, generated_specs=paths), 2)
    assert t.tile_type_names == ["spec0", "spec1"]
    h0, _ = TerrainSpec.load(paths[0]).build()
    assert np.array_equal(t.height_field[10:50, 10:50], h0)
    assert t.material.has_water()[10:50, 10:50].any()
    assert np.all(t.material.friction == np.float32(0.9))
    with pytest.warns(UserWarning, match="2 generated specs fill 4 tiles"):
        Terrain(cfg(mode="generated", num_rows=2, num_cols=2, generated_specs=paths), 2)
    with pytest.raises(ValueError, match="needs cfg.generated_specs"):
        Terrain(cfg(mode="generated"), 1)
    (tmp_path / "bad.json").write_text('{"size_x": 4.0, "calls": []}')
    with pytest.raises(ValueError, match=r"bad.json: not a terrain spec document: spec: field '\(document\)': "
                                         r"'size_y' is a required property\. .*'seed' is a required property\."):
        Terrain(cfg(mode="generated", num_rows=1, num_cols=1, generated_specs=[str(tmp_path / "bad.json")]), 1)
    with pytest.raises(ValueError, match="has \\(40, 40\\) cells, the grid needs \\(80, 80\\)"):
        Terrain(cfg(mode="generated", num_rows=1, num_cols=1, generated_specs=paths[:1],
                    terrain_length=8.0, terrain_width=8.0), 1)


def test_export_mesh_roundtrip(tmp_path):
    import trimesh

    t = Terrain(cfg(num_rows=1, num_cols=2, terrain_length=2.0, terrain_width=2.0, border_size=0.5,
                    terrain_types=["pyramid_stairs"], terrain_proportions=[1.0]), 1)
    nx, ny = t.height_field.shape
    for suffix in (".obj", ".glb"):
        path = t.export_mesh(tmp_path / f"terrain{suffix}")
        mesh = trimesh.load(path, force="mesh")
        assert len(mesh.vertices) == nx * ny and len(mesh.faces) == 2 * (nx - 1) * (ny - 1)
    mesh = trimesh.load(tmp_path / "terrain.obj", force="mesh")
    assert np.isclose(mesh.vertices[:, 2].max(), t.height_field.max(), atol=1e-5)
    assert np.allclose(mesh.bounds[0][:2], t.origin_xy, atol=1e-5)
    assert mesh.face_normals[:, 2].min() > 0  # counter-clockwise seen from above
    with pytest.raises(ValueError, match="unsupported suffix"):
        t.export_mesh(tmp_path / "terrain.fbx")


def test_save_preview(tmp_path, curriculum):
    from PIL import Image

    path = curriculum.save_preview(tmp_path / "preview.png", max_size=200)
    image = Image.open(path)
    assert max(image.size) <= 200 and image.mode == "RGB"
    pixels = np.asarray(image).astype(int)
    assert pixels.std() > 5  # not a blank image


def test_benchmark_grid_small():
    from legged_gente.terrain.benchmark import BENCHMARK_TYPES, benchmark_grid

    result = benchmark_grid(num_rows=2, num_cols=len(BENCHMARK_TYPES), tile_size=2.0, repeats=1)
    assert result["types"] == BENCHMARK_TYPES and result["best_s"] > 0
    assert result["cells"] == (2 * 20 + 100) * (len(BENCHMARK_TYPES) * 20 + 100)


def test_a_generated_spec_at_another_resolution_is_refused(tmp_path):
    """A 4 m spec at 0.05 m cells has 80 x 80 cells, as many as an 8 m tile at 0.1 m: laid there, its 0.3 m treads
    would become 0.6 m. The grid refuses it, naming both cell sizes."""
    import json

    spec = {"version": 1, "size_x": 4.0, "size_y": 4.0, "resolution": 0.05, "seed": 0,
            "calls": [{"tool": "stairs", "region": "full", "params": {"step_width": 0.3}, "mode": "set"}]}
    path = tmp_path / "fine.json"
    path.write_text(json.dumps(spec))
    with pytest.raises(ValueError, match=r"fine.json: its cells are 0.05 m, the grid's resolution is 0.1 m; set "
                                         r"terrain.resolution"):
        Terrain(cfg(mode="generated", num_rows=1, num_cols=1, terrain_length=8.0, terrain_width=8.0,
                    generated_specs=[str(path)]), 1)


def test_a_negative_seed_is_refused_naming_the_field():
    with pytest.raises(ValueError, match=r"^terrain seed=-1 must be a whole number >= 0"):
        Terrain(cfg(seed=-1), 1)
