"""gente-view: the scene it builds (plain data, no browser), rollout files, the robot's geoms, the server."""

from __future__ import annotations

import math
import socket
import urllib.request

import mujoco
import numpy as np
import pytest

from legged_gente.terrain.terrain import LOW_FRICTION_COLOUR, SOIL_COLOURS, WATER_COLOUR, Terrain
from legged_gente.viewer.rollout import Kinematics, Rollout, robot_geoms, robot_model
from legged_gente.viewer.scene import BareTerrain, Label, Lines, Points, terrain_scene


class GridCfg:
    mesh_type, mode, resolution, border_size = "heightfield", "curriculum", 0.1, 1.0
    terrain_length = terrain_width = 4.0
    num_rows, num_cols = 2, 3
    terrain_types = ["water:flow=current,speed=0.5,direction=0.0,depth=0.3", "hills+soil:preset=dry_sand",
                     "low_friction"]
    terrain_proportions = [1 / 3, 1 / 3, 1 / 3]
    selected_terrain, selected_params, generated_specs = "flat", {}, []
    max_difficulty, max_init_terrain_level, curriculum, static_friction, seed = 1.0, 0, True, 1.0, 0


@pytest.fixture(scope="module")
def grid():
    return Terrain(GridCfg, num_robots=1)


def rgb255(colour):
    return tuple(round(255 * c) for c in colour)


def test_scene_of_a_grid(grid):
    scene = terrain_scene(grid)
    nx, ny = grid.height_field.shape  # (2*40 + 2*10, 3*40 + 2*10) = (100, 140) cells
    assert (nx, ny) == (100, 140)
    ground = scene.nodes["/terrain/ground"]
    assert ground.vertices.shape == (nx * ny, 3) and ground.faces.shape == (2 * (nx - 1) * (ny - 1), 3)
    np.testing.assert_allclose(ground.vertices[:, 2], grid.height_field.ravel(), atol=1e-6)
    # vertex (i, j) lies at origin + (i, j) * resolution: the last one at (-1 + 99 * 0.1, -1 + 139 * 0.1)
    np.testing.assert_allclose(ground.vertices[-1, :2], [8.9, 12.9], atol=1e-5)
    colours = ground.vertex_colors.reshape(nx, ny, 3)
    sand = grid.material.soil == grid.material.soil_presets.index("dry_sand")
    icy = grid.material.friction < 0.5
    assert sand.any() and icy.any()
    assert (colours[sand] == rgb255(SOIL_COLOURS["dry_sand"])).all()
    assert (colours[icy] == rgb255(LOW_FRICTION_COLOUR)).all()
    # water: a translucent surface at the water's level, over the wet cells only
    water = scene.nodes["/terrain/water"]
    wet = grid.material.has_water()
    assert water.opacity < 1 and water.color == rgb255(WATER_COLOUR)
    used = np.unique(water.faces)
    assert wet.ravel()[used].all()
    np.testing.assert_allclose(water.vertices[used, 2], grid.material.water_surface.ravel()[used])
    # wet quads: 2 rows x 1 column of 40 x 40-cell tiles, each (40 - 1)^2 quads inside a tile
    assert len(water.faces) >= 2 * 2 * 39 * 39
    # flow: 0.5 m/s along +x, an arrow is the travel of 1 s -> 0.5 m long, pointing +x, on the surface
    flow = scene.nodes["/terrain/flow"]
    d = flow.points[:, 1] - flow.points[:, 0]
    np.testing.assert_allclose(d, np.tile([0.5, 0.0, 0.0], (len(d), 1)), atol=1e-5)
    # a tile of 4 m with arrows every 1 m: 4 x 4 per water tile, 2 water tiles
    assert len(flow.points) == 2 * 16
    # tiles: outlines, a label per tile, a spawn per tile
    assert isinstance(scene.nodes["/terrain/tiles/outlines"], Lines)
    assert len(scene.of_type(Label)) == 6
    spawns = scene.nodes["/terrain/tiles/spawns"]
    assert isinstance(spawns, Points) and len(spawns.positions) == 6
    legend = [label for label, _ in scene.legend]
    assert "dry sand" in legend and any("low friction" in x for x in legend) and any("water" in x for x in legend)
    assert any("flow" in x for x in legend) and "spawn point" in legend


def test_scene_heights_tile_and_subsampling(grid):
    heights = terrain_scene(grid, colours="heights")
    ground = heights.nodes["/terrain/ground"]
    z = ground.vertices[:, 2]
    lowest, highest = ground.vertex_colors[z.argmin()], ground.vertex_colors[z.argmax()]
    assert tuple(lowest) != tuple(highest)  # the colormap runs from the lowest to the highest cell
    # one tile alone, at full resolution: (40 + 1)^2 vertices, its own label and spawn, shifted by the offset
    tile = terrain_scene(grid, tile=(1, 2), offset=(100.0, 0.0))
    v = tile.nodes["/terrain/ground"].vertices
    assert len(v) == 41 * 41
    assert v[:, 0].min() == pytest.approx(100.0 + 4.0) and v[:, 1].min() == pytest.approx(8.0)
    assert list(tile.of_type(Label)) == ["/terrain/tiles/label_1_2"]
    # a mesh over the budget keeps every stride-th cell: 14000 cells / 1000 -> stride ceil(sqrt(14)) = 4
    small = terrain_scene(grid, max_vertices=1000).nodes["/terrain/ground"]
    assert len(small.vertices) == (math.ceil(100 / 4) + 1) * (math.ceil(140 / 4) + 1)
    with pytest.raises(ValueError, match="outside the 2 x 3 grid"):
        terrain_scene(grid, tile=(2, 0))
    with pytest.raises(ValueError, match="colours"):
        terrain_scene(grid, colours="rainbow")


def test_robot_geoms_and_kinematics():
    mjm = robot_model("gente_biped")
    shapes = robot_geoms(mjm)
    # MuJoCo's default MjvOption.geomgroup shows groups 0-2: the collision-only group-3 geoms are not drawn
    assert len(shapes) == sum(1 for g in range(mjm.ngeom) if mjm.geom_bodyid[g] != 0 and mjm.geom_rgba[g, 3] > 0
                              and mjm.geom_group[g] < 3)
    opt = mujoco.MjvOption()
    assert list(opt.geomgroup) == [1, 1, 1, 0, 0, 0]
    quad = robot_model("gente_quadruped")
    hidden = [g for g in range(quad.ngeom) if quad.geom_group[g] >= 3 and quad.geom_bodyid[g] != 0]
    assert len(hidden) >= 4 and len(robot_geoms(quad)) == sum(
        1 for g in range(quad.ngeom) if quad.geom_bodyid[g] != 0 and quad.geom_rgba[g, 3] > 0) - len(
        [g for g in hidden if quad.geom_rgba[g, 3] > 0])
    assert all(s.faces.max() < len(s.vertices) for s in shapes)
    kin = Kinematics(mjm)
    qpos = mjm.qpos0.copy()
    qpos[:3] = (1.0, 2.0, 0.9)
    d = kin(qpos)
    np.testing.assert_allclose(d.xpos[1], (1.0, 2.0, 0.9))  # the floating base sits where qpos puts it
    with pytest.raises(ValueError, match="recorded with another robot"):
        kin(np.zeros(mjm.nq + 2))


def test_rollout_file_round_trip(tmp_path, grid):
    t, r, k, nq = 5, 2, 3, 17
    rng = np.random.default_rng(0)
    rollout = Rollout("gente_biped", 0.02, rng.normal(size=(t, r, nq)).astype(np.float32),
                      rng.normal(size=(t, r, 3)).astype(np.float32), rng.normal(size=(t, r, 3)).astype(np.float32),
                      np.eye(t, r, dtype=bool), np.zeros((t, r), bool), ["buoyancy:a", "drag:a", "soil:foot"],
                      rng.normal(size=(t, r, k, 3)).astype(np.float32), rng.normal(size=(t, r, k, 3)).astype(np.float32),
                      grid.height_field, grid.origin_xy, grid.resolution, grid.material)
    back = Rollout.load(rollout.save(tmp_path / "r.npz"))
    assert (back.num_steps, back.num_robots, back.task, back.force_labels) == (t, r, "gente_biped", rollout.force_labels)
    for field in ("qpos", "cmd", "vel", "done", "forces", "force_points", "heights"):
        np.testing.assert_array_equal(getattr(back, field), getattr(rollout, field))
    assert back.material.soil_presets == grid.material.soil_presets
    np.testing.assert_array_equal(back.material.water_surface, grid.material.water_surface)
    scene = terrain_scene(BareTerrain(back.heights, back.material, back.resolution, back.origin))
    assert "/terrain/water" in scene.nodes and not scene.of_type(Label)
    np.savez(tmp_path / "traces.npz", pos=np.zeros(3))
    with pytest.raises(ValueError, match="traces.npz"):
        Rollout.load(tmp_path / "traces.npz")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_server_serves_its_page(grid):
    from legged_gente.viewer.server import TerrainItem, Viewer

    viewer = Viewer([TerrainItem("grid", lambda: grid), TerrainItem("tile", lambda: grid, (50.0, 0.0))],
                    port=free_port())
    try:
        with urllib.request.urlopen(viewer.url, timeout=10) as response:
            page = response.read().decode()
        assert response.status == 200 and "<html" in page.lower()
        assert set(viewer.handles) == set(viewer.scene.nodes)
        viewer.tile_gui.value = "(1, 2) low_friction"  # switching a tile rebuilds the scene at full resolution
        assert len(viewer.scene.nodes["/terrain/ground"].vertices) == 41 * 41
        viewer.colour_gui.value = "heights"
        assert viewer.scene.legend[0][0].endswith(" m")
        # a rollout: robot r at step t stands at x = t, y = r; a 200 N buoyancy on robot 1 is a 2 m arrow
        mjm = robot_model("gente_biped")
        t, r = 4, 2
        qpos = np.tile(mjm.qpos0, (t, r, 1))
        qpos[..., 0] = np.arange(t)[:, None]
        qpos[..., 1] = np.arange(r)[None, :]
        forces = np.zeros((t, r, 1, 3), np.float32)
        forces[:, 1, 0, 2] = 200.0
        rollout = Rollout("gente_biped", 0.02, qpos, np.zeros((t, r, 3)), np.zeros((t, r, 3)), np.zeros((t, r), bool),
                          np.zeros((t, r), bool), ["buoyancy:shin"], forces, np.zeros((t, r, 1, 3), np.float32),
                          grid.height_field, grid.origin_xy, grid.resolution, grid.material)
        player = viewer.attach_rollout(rollout, mjm, play=False)
        player.draw(3)
        base = int(mjm.jnt_bodyid[0])
        np.testing.assert_allclose(player.bodies[1, base].position, (3.0, 1.0, mjm.qpos0[2]), atol=1e-6)
        arrows = player.force_handles["buoyancy"]
        np.testing.assert_allclose(arrows.points[0, 1] - arrows.points[0, 0], (0.0, 0.0, 2.0), atol=1e-5)
    finally:
        viewer.stop()


def test_cli_rejects_an_unknown_file(tmp_path, capsys):
    from legged_gente.scripts.view import main

    bad = tmp_path / "terrain.txt"
    bad.write_text("x")
    with pytest.raises(SystemExit) as exit_info:
        main([str(bad), "--headless"])
    assert exit_info.value.code == 2
    assert "pass a spec .json, a terrain_cfg.py" in capsys.readouterr().err


def test_preview_lies_like_the_input_picture(tmp_path):
    """The picture planner reads a sketch's top row as the front (+x) and its left column as the left (+y):
    the preview must show water placed at large x at its top and sand placed at large y on its left."""
    from legged_gente.terrain.composition import Operation, Part, Region, TileSpec
    from legged_gente.terrain.preview import save_preview_figure, scale_bar_length, top_view

    tile = TileSpec(10.0, 10.0, 0.1, 0, [
        Part(Region(0, 0, 10, 10), [Operation("flat", {})]),
        Part(Region(7, 0, 10, 10), [Operation("water", {"depth": 0.3})]),  # front strip: x in [7, 10] m
        Part(Region(0, 7, 7, 10), [Operation("soil", {"preset": "dry_sand"})]),  # left strip: y in [7, 10] m
    ])
    heights, material = tile.build()
    image = top_view(heights, material, 0.1)
    assert image.shape == (100, 100, 3)
    top, bottom_left, bottom_right = image[5, 50], image[90, 10], image[90, 90]
    assert top[2] > top[0] + 0.1  # blue water at the top (front)
    assert bottom_left[0] > bottom_left[2] + 0.1  # yellow sand at the left
    assert abs(bottom_right[0] - bottom_left[0]) > 0.05  # plain ground at the right differs from sand
    # a scale bar of a round length about a fifth of the extent: 10 m -> 2 m, 20 m -> 2 m (<= 4 m), 160 m -> 20 m
    assert [scale_bar_length(e) for e in (10.0, 20.0, 160.0)] == [2.0, 2.0, 20.0]
    path = save_preview_figure(heights, material, 0.1, tmp_path / "preview.png", title="strips")
    from PIL import Image

    assert min(Image.open(path).size) > 500  # larger than the old 200-600 px previews


def test_a_large_grid_labels_columns_and_rows():
    from legged_gente.terrain.gallery import curriculum_terrain

    terrain = curriculum_terrain()  # 10 x 22 tiles: 220 > MAX_TILE_LABELS
    labels = terrain_scene(terrain).of_type(Label)
    assert len(labels) == 22 + 9  # a label per column on row 0, one per further row on column 0
    assert labels["/terrain/tiles/label_0_17"].text == f"col 17: {terrain.tile_names[0, 17]}"
    assert labels["/terrain/tiles/label_9_0"].text == "row 9"


def test_vertex_colours_reach_the_browser_linear(grid):
    """glTF vertex colours are linear (glTF 2.0, 3.7.2.1); the ground mesh sent to viser holds the sRGB material
    colours decoded by the sRGB formula (IEC 61966-2-1), or the browser shows them washed out."""
    import io

    import trimesh

    from legged_gente.viewer.server import TerrainItem, Viewer, gltf_vertex_colours

    def decoded(c: int) -> int:  # sRGB 8-bit -> linear 8-bit, by hand
        x = c / 255
        return round(255 * (x / 12.92 if x <= 0.04045 else ((x + 0.055) / 1.055) ** 2.4))

    assert decoded(128) == 55 and decoded(255) == 255 and decoded(10) == 1
    np.testing.assert_array_equal(gltf_vertex_colours(np.array([0, 10, 128, 255])), [0, 1, 55, 255])
    viewer = Viewer([TerrainItem("grid", lambda: grid)], port=free_port(), shadows=False)
    try:
        sent = trimesh.load(io.BytesIO(viewer.handles["/terrain/ground"].glb_data), file_type="glb", force="mesh")
        colours = np.asarray(sent.visual.vertex_colors)[:, :3].astype(int)
        sand = np.array(rgb255(SOIL_COLOURS["dry_sand"]))
        expected = [decoded(int(c)) for c in sand]
        assert (np.abs(colours - expected).max(axis=1) <= 1).any()  # the sand, linear
        assert not (np.abs(colours - sand).max(axis=1) <= 1).any()  # never the sRGB values themselves
    finally:
        viewer.stop()


def test_a_preview_tells_bare_ground_from_soil_by_colour():
    """Bare ground was coloured by elevation in matplotlib's 'terrain' map: a 0.5 m block turned as brown as mud beside
    it, low grass as yellow as sand. Bare ground is grey now (shade and lightness: elevation), soil keeps its tint."""
    from legged_gente.terrain.materials import MaterialMap
    from legged_gente.terrain.terrain import preview_rgb

    heights = np.zeros((40, 40), np.float32)
    heights[20:30, 5:15] = 0.5  # a block
    material = MaterialMap.rigid(heights.shape)
    material.soil[5:15, 20:35] = material.soil_index("mud")
    rgb = preview_rgb(heights, material, 0.1)[::-1].transpose(1, 0, 2)  # (ny, nx) with y up -> (nx, ny)
    spread = lambda cells: float((cells.max(-1) - cells.min(-1)).max())  # noqa: E731  (0: grey)
    assert spread(rgb[22:28, 7:13]) < 0.01 and spread(rgb[32:38, 30:38]) < 0.01  # the block and bare ground: grey
    assert rgb[22:28, 7:13].mean() > rgb[32:38, 30:38].mean() + 0.05  # the block lighter: higher
    mud = rgb[7:13, 23:32].reshape(-1, 3).mean(0)
    assert mud[0] - mud[2] > 0.08  # brown: red over blue
