"""Terrain regions -> per-cell maps -> what a foot at a world position reads, checked by hand.

A 2 x 2 grid of asymmetric tiles (2.0 m along x, 1.5 m along y, 0.25 m cells, a 0.5 m border) carries water,
soil and water on soil in regions placed so that an x/y swap, a row/column mix-up, a tile offset or a half-cell
shift reads another cell. Cell (i, j) of the maps lies at world ``origin_xy + (i, j) * resolution`` and a world
point reads its nearest cell (docs/terrain.md, ``kernels.cell_of``); a region [x0, x1) holds the cells at
i * resolution inside it, so its material reaches half a cell before x0 and ends half a cell before x1, as the
heightfield's ramp between its last inside sample and the first outside one is centred there.
"""

import json
import math
import warnings

import mujoco
import mujoco_warp as mjw
import numpy as np
import pytest
import warp as wp

from legged_gente.external_forces.field import ForcesConfig, TerrainForces
from legged_gente.terrain.materials import (FLOW_CURRENT, FLOW_STILL, FLOW_TIDE, NO_SOIL, NO_WATER, MaterialMap,
                                            MaterialPatch)
from legged_gente.terrain.terrain import Terrain

wp.config.quiet = True
DEV = "cpu"
RES, BORDER, LX, LY = 0.25, 0.5, 2.0, 1.5  # cell (m), border (m), tile size along x and y (m)
B, TNX, TNY = 2, 8, 6  # border cells, tile cells along x and y
CURRENT = dict(speed=0.6, direction=1.0)  # tile (0, 0)
TIDE = dict(speed=0.4, omega=2.0, phase=0.5, direction=-2.0)  # tile (1, 0)
PIT_WATER = 0.2  # tile (1, 1): water 0.2 m above the bottom of a 0.3 m pit


def call(tool, rect, **params):
    x0, y0, x1, y1 = rect
    return {"tool": tool, "region": {"x0": x0, "y0": y0, "x1": x1, "y1": y1}, "params": params}


TILES = [  # row-major: (0, 0), (0, 1), (1, 0), (1, 1); rectangles in metres from the tile's corner
    [call("water", (0.0, 0.0, 1.0, 0.5), depth=0.3, flow="current", **CURRENT)],
    [call("soil", (1.0, 0.75, 2.0, 1.5), preset="mud")],
    [call("soil", (0.0, 0.0, 2.0, 1.5), preset="dry_sand"),
     call("water", (0.0, 0.0, 0.5, 1.5), depth=0.3, flow="tide", **TIDE),
     call("soil", (1.5, 0.0, 2.0, 0.25), preset="mud")],
    [call("pit", (0.0, 0.0, 2.0, 1.5), depth=0.3, width=1.0),
     call("water", (0.0, 0.0, 2.0, 1.5), depth=PIT_WATER)],
]


@pytest.fixture(scope="module")
def terrain(tmp_path_factory):
    folder = tmp_path_factory.mktemp("specs")
    paths = []
    for k, calls in enumerate(TILES):
        path = folder / f"tile{k}.json"
        path.write_text(json.dumps({"size_x": LX, "size_y": LY, "resolution": RES, "seed": k, "calls": calls}))
        paths.append(str(path))

    class Cfg:
        mesh_type, mode, resolution, border_size = "heightfield", "generated", RES, BORDER
        terrain_length, terrain_width, num_rows, num_cols = LX, LY, 2, 2
        generated_specs, static_friction, seed, max_difficulty = paths, 1.0, 0, 1.0

    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", "no flat")  # the pit tile has no spawn patch: no robot spawns here
        return Terrain(Cfg, num_robots=4)


def cells(r, c, i, j):
    """Global map index of cell (i, j) of tile (r, c)."""
    return B + r * TNX + i, B + c * TNY + j


# ------------------------------------------------------------------------------------------------ the maps


def test_terrain_grid_shape_and_origin(terrain):
    assert terrain.height_field.shape == terrain.material.shape == (2 * TNX + 2 * B, 2 * TNY + 2 * B)
    assert terrain.origin_xy == (-BORDER, -BORDER)


def test_water_region_fills_the_cells_of_its_rectangle_only(terrain):
    mat = terrain.material
    wet = mat.has_water()
    expected = np.zeros(mat.shape, bool)
    # tile (0, 0): x in [0, 1) -> i 0..3, y in [0, 0.5) -> j 0..1
    expected[B:B + 4, B:B + 2] = True
    # tile (1, 0): x in [0, 0.5) -> i 0..1, all j
    expected[B + TNX:B + TNX + 2, B:B + TNY] = True
    # tile (1, 1): the pit's cells only (ground -0.3 m < surface -0.1 m)
    pit = terrain.height_field < -0.29
    pit[:B + TNX] = False
    pit[:, :B + TNY] = False
    assert pit.sum() > 0
    expected |= pit
    np.testing.assert_array_equal(wet, expected)
    i, j = cells(0, 0, 0, 0)
    assert mat.water_surface[i, j] == np.float32(0.3)
    assert mat.flow_kind[i, j] == FLOW_CURRENT
    assert mat.flow_speed[i, j] == np.float32(0.6) and mat.flow_direction[i, j] == np.float32(1.0)
    i, j = cells(1, 0, 1, 5)
    assert mat.flow_kind[i, j] == FLOW_TIDE and mat.flow_omega[i, j] == np.float32(2.0)
    assert mat.flow_phase[i, j] == np.float32(0.5) and mat.flow_direction[i, j] == np.float32(-2.0)
    # a dry cell keeps a still, zero flow
    i, j = cells(0, 0, 4, 0)
    assert mat.flow_kind[i, j] == FLOW_STILL and mat.flow_speed[i, j] == 0.0


def test_soil_regions_keep_their_preset_across_tiles(terrain):
    mat = terrain.material
    names = np.array(mat.soil_presets + ["-"], dtype=object)[mat.soil]  # -1 -> "-"
    expected = np.full(mat.shape, "-", dtype=object)
    expected[B + 4:B + 8, B + TNY + 3:B + TNY + 6] = "mud"  # tile (0, 1): x [1, 2) -> i 4..7, y [0.75, 1.5) -> j 3..5
    expected[B + TNX:B + 2 * TNX, B:B + TNY] = "dry_sand"  # tile (1, 0) whole
    expected[B + TNX + 6:B + TNX + 8, B] = "mud"  # tile (1, 0): x [1.5, 2) -> i 6..7, y [0, 0.25) -> j 0
    np.testing.assert_array_equal(names, expected)


def test_paint_water_over_soil_keeps_soil_and_later_water_replaces_only_its_wet_cells():
    mat = MaterialMap.rigid((4, 3))
    mat.paint(MaterialPatch((4, 3), soil="snow"), 0, 0)
    surface = np.full((2, 3), NO_WATER, np.float32)
    surface[:, 1:] = 0.2
    mat.paint(MaterialPatch((2, 3), water_surface=surface, flow_kind=FLOW_CURRENT, flow_speed=0.5,
                            flow_direction=0.3), 1, 0)
    assert (mat.soil == 0).all() and mat.soil_presets == ["snow"]
    np.testing.assert_array_equal(mat.has_water(), [[0, 0, 0], [0, 1, 1], [0, 1, 1], [0, 0, 0]])
    # a second, still water wet in its first row only: the other row keeps the current
    second = np.full((2, 3), NO_WATER, np.float32)
    second[0] = 0.1
    mat.paint(MaterialPatch((2, 3), water_surface=second, flow_kind=FLOW_STILL, flow_speed=0.0), 1, 0)
    np.testing.assert_allclose(mat.water_surface[1], [0.1, 0.1, 0.1])
    np.testing.assert_allclose(mat.water_surface[2, 1:], [0.2, 0.2])
    np.testing.assert_array_equal(mat.flow_kind[1:3], [[0, 0, 0], [0, 1, 1]])
    np.testing.assert_allclose(mat.flow_speed[1:3], [[0, 0, 0], [0, 0.5, 0.5]])
    # soil painted over water keeps the water
    mat.paint(MaterialPatch((4, 3), soil="mud"), 0, 0)
    assert mat.has_water().sum() == 5 and (mat.soil == 1).all()


def test_paste_maps_soil_indices_by_name():
    a, b = MaterialMap.rigid((2, 2)), MaterialMap.rigid((1, 2))
    a.paint(MaterialPatch((1, 2), soil="mud"), 0, 0)
    b.paint(MaterialPatch((1, 1), soil="snow"), 0, 0)
    b.paint(MaterialPatch((1, 1), soil="mud"), 0, 1)
    a.paste(b, 1, 0)  # b's mud (its index 1) is a's mud (index 0); snow is new (index 1)
    assert a.soil_presets == ["mud", "snow"]
    np.testing.assert_array_equal(a.soil, [[0, 0], [1, 0]])
    c = MaterialMap.rigid((1, 1))
    a.paste(c, 0, 1)  # rigid stays rigid
    assert a.soil[0, 1] == NO_SOIL


# ------------------------------------------------------------------------------- lookups in TerrainForces

QUERIES = {  # name: world (x, y)
    "water_00": (0.6, 0.2),  # tile (0, 0) cell (2, 1): wet
    "swapped_00": (0.2, 0.6),  # cell (1, 2): dry (a swapped x/y lookup would read the water)
    "edge_in": (0.86, 0.2),  # x 3.44 cells -> cell 3: wet
    "edge_out": (0.9, 0.2),  # x 3.6 cells -> cell 4 (x = 1.0 m): dry, half a cell inside the region's [0, 1)
    "border_out": (-0.2, 0.2),  # global x index 1.2 -> 1: the border, dry
    "border_in": (-0.1, 0.2),  # global x index 1.6 -> 2: tile (0, 0) cell 0, wet
    "mud_01": (1.5, 2.5),  # tile (0, 1) local (1.5, 1.0): cell (6, 4): mud
    "mud_01_swapped": (2.5, 1.5),  # tile (1, 1) local (0.5, 0): rigid, dry (the pit is at the tile's centre)
    "tide_10": (2.25, 0.75),  # tile (1, 0) local (0.25, 0.75): cell (1, 3): tide over dry sand
    "mud_10": (3.75, 0.0),  # tile (1, 0) local (1.75, 0): cell (7, 0): mud
    "pit_11": (3.0, 2.25),  # tile (1, 1) centre: pit bottom under 0.2 m of water
    "rim_11": (2.0, 1.5),  # tile (1, 1) corner: ground 0 m above the water surface: dry
    "far_low": (-30.0, -30.0),  # off the grid: the corner border cell
    "far_high": (30.0, 30.0),
}


class FeetCfg(ForcesConfig):
    noise_std = 0.0  # eps = xi = 1
    sole_contact = False  # no terrain geom in these scenes
    leg_geom_names: list = []
    foot_geom_names = [f"foot_{name}" for name in QUERIES]


def feet_model(radius=0.02):
    bodies = "".join(f'<body name="{n}"><freejoint/><geom name="foot_{n}" type="sphere" size="{radius}" '
                     f'contype="0" conaffinity="0" density="500"/></body>' for n in QUERIES)
    return mujoco.MjModel.from_xml_string(f'<mujoco><worldbody>{bodies}</worldbody></mujoco>')


@pytest.fixture(autouse=True)
def _lone_free_feet():
    """The feet are lone free bodies, whose mass matrix MuJoCo keeps diagonal: TerrainForces warns (exact here)."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", "forces: water geoms")
        yield


def place(terrain, times, z=None):
    """Feet at the QUERIES points (sphere centres at ``z``, or 1 m above the ground) in worlds at ``times``; the
    fields' lookups as the contact filter and the after-substep hook make them."""
    wp.set_device(DEV)
    mjm = feet_model()
    m = mjw.put_model(mjm)
    nworld = len(times)
    d = mjw.make_data(mjm, nworld=nworld, nconmax=8, njmax=32)
    f = TerrainForces(mjm, m, d, terrain.height_field, terrain.origin_xy, terrain.resolution, terrain.material,
                      FeetCfg(), seed=3)
    qpos = np.zeros((nworld, mjm.nq), np.float32)
    for k, (x, y) in enumerate(QUERIES.values()):
        qpos[:, 7 * k:7 * k + 3] = (x, y, 1.0 if z is None else z)
        qpos[:, 7 * k + 3] = 1.0
    d.qpos.assign(wp.array(qpos, dtype=float, device=DEV))
    d.time.assign(wp.array(np.asarray(times, np.float32), dtype=float, device=DEV))
    mjw.forward(m, d)  # callbacks not installed: kinematics only, no forces
    f.contact_filter(m, d)
    f.after_substep()
    f.observe()
    return m, d, f


def by_name(f, column):
    obs = f.privileged_obs().numpy().reshape(f.nworld, len(QUERIES), -1)
    return {n: obs[:, k, column] for k, n in enumerate(QUERIES)}


def soils(f, terrain):
    s = f.foot_soil.numpy()[0]
    return {n: (terrain.material.soil_presets[s[k]] if s[k] >= 0 else None) for k, n in enumerate(QUERIES)}


def test_a_foot_reads_the_water_depth_of_its_cell(terrain):
    _, _, f = place(terrain, [0.0])
    depth = {n: float(v[0]) for n, v in by_name(f, 0).items()}
    expected = dict.fromkeys(QUERIES, 0.0)
    expected.update(water_00=0.3, edge_in=0.3, border_in=0.3, tide_10=0.3,
                    pit_11=PIT_WATER)  # the pit bottom (-0.3 m) under its water's surface at -0.3 + 0.2 m
    assert depth == pytest.approx(expected, abs=1e-6)


def test_a_foot_reads_the_soil_of_its_cell(terrain):
    _, _, f = place(terrain, [0.0])
    expected = dict.fromkeys(QUERIES)
    expected.update(mud_01="mud", tide_10="dry_sand", mud_10="mud")
    assert soils(f, terrain) == expected
    on_soil = {n: float(v[0]) for n, v in by_name(f, 3).items()}
    assert on_soil == {n: float(expected[n] is not None) for n in QUERIES}


def test_current_and_tide_are_world_frame_velocities_of_the_documented_formula(terrain):
    times = [0.0, 1.3, 7.9]  # per world: its own time since its reset
    _, _, f = place(terrain, times)
    vx, vy = by_name(f, 1), by_name(f, 2)
    a, th = CURRENT["speed"], CURRENT["direction"]
    for n in ("water_00", "edge_in", "border_in"):  # current: speed along direction, from +x towards +y
        np.testing.assert_allclose(vx[n], [a * math.cos(th)] * 3, atol=1e-6)
        np.testing.assert_allclose(vy[n], [a * math.sin(th)] * 3, atol=1e-6)
    # tide: speed cos(omega t + phase) along direction, t the world's own time
    u = [TIDE["speed"] * math.cos(TIDE["omega"] * t + TIDE["phase"]) for t in times]
    np.testing.assert_allclose(vx["tide_10"], np.multiply(u, math.cos(TIDE["direction"])), atol=1e-6)
    np.testing.assert_allclose(vy["tide_10"], np.multiply(u, math.sin(TIDE["direction"])), atol=1e-6)
    for n in set(QUERIES) - {"water_00", "edge_in", "border_in", "tide_10"}:  # still or dry
        assert not vx[n].any() and not vy[n].any(), n


def test_only_feet_in_wet_cells_are_buoyed(terrain):
    """Feet (r = 2 cm spheres) 5 cm above the local ground: in a wet cell wholly under water, Archimedes
    rho g (4/3 pi r^3) up; in a dry cell nothing. The water kernel looks the cell up as the observation does."""
    m, d, f = place(terrain, [0.0], z=0.0)
    ground = {n: float(terrain.height_at(x, y)) for n, (x, y) in QUERIES.items()}
    qpos = d.qpos.numpy()
    for k, n in enumerate(QUERIES):
        qpos[0, 7 * k + 2] = ground[n] + 0.05
    d.qpos.assign(qpos)
    mjw.forward(m, d)
    f.passive(m, d)
    fz = {n: float(v) for n, v in zip(QUERIES, f.foot_water_force.numpy()[0, :, 2])}
    archimedes = 1000.0 * 9.81 * 4.0 / 3.0 * math.pi * 0.02 ** 3
    expected = dict.fromkeys(QUERIES, 0.0)
    expected.update(water_00=archimedes, edge_in=archimedes, border_in=archimedes, tide_10=archimedes,
                    pit_11=archimedes)
    assert fz == pytest.approx(expected, rel=1e-4, abs=1e-6)


# ------------------------------------------------------------------------------------ inconsistent maps


def _forces(mat, shape=(4, 3)):
    wp.set_device(DEV)
    mjm = feet_model()
    return TerrainForces(mjm, mjw.put_model(mjm), mjw.make_data(mjm, nworld=1, nconmax=8, njmax=32),
                         np.zeros(shape, np.float32), (0.0, 0.0), RES, mat, FeetCfg())


@pytest.mark.parametrize("field, value, message", [
    ("friction", np.ones((1, 1), np.float32), r"material.friction has shape \(1, 1\); the heights' grid is \(4, 3\)"),
    ("flow_direction", np.zeros((3, 4), np.float32), r"material.flow_direction has shape \(3, 4\)"),
    ("flow_kind", np.full((4, 3), 3, np.int8), r"material.flow_kind holds 3; use 0 \(still\), 1 \(current\) or 2"),
    ("soil", np.full((4, 3), -2, np.int8), r"material.soil holds -2"),
    ("water_surface", np.full((4, 3), np.nan, np.float32), r"material.water_surface holds nan"),
    ("flow_speed", np.full((4, 3), np.inf, np.float32), r"material.flow_speed holds inf"),
    ("friction", np.full((4, 3), -0.2, np.float32), r"material.friction holds -0.2"),
])
def test_a_map_whose_layers_do_not_fit_the_grid_or_their_kinds_is_refused(field, value, message):
    """Each layer is read at the heights' cell indices by the kernels: a layer of another shape would be read out
    of its bounds, a flow kind other than still/current/tide would silently be still water, a soil index below -1
    rigid ground, a non-finite value NaN forces, a negative friction a frictionless contact."""
    mat = MaterialMap.rigid((4, 3))
    setattr(mat, field, value)
    with pytest.raises(ValueError, match=message):
        _forces(mat)


def test_a_reset_world_starts_the_tide_at_its_phase(terrain):
    """t is the world's time since its reset (docs/forces.md): after mjw.reset_data the tide is A cos(phase)."""
    m, d, f = place(terrain, [7.9])
    qpos = d.qpos.numpy().copy()  # numpy() of a CPU array is a view
    mjw.reset_data(m, d)
    assert d.time.numpy()[0] == 0.0
    d.qpos.assign(qpos)
    mjw.forward(m, d)
    f.after_substep()
    f.observe()
    u = TIDE["speed"] * math.cos(TIDE["phase"])
    assert float(by_name(f, 1)["tide_10"][0]) == pytest.approx(u * math.cos(TIDE["direction"]), abs=1e-6)
    assert float(by_name(f, 2)["tide_10"][0]) == pytest.approx(u * math.sin(TIDE["direction"]), abs=1e-6)
