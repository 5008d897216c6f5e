"""The viewer and playback checked against values computed by hand: the force arrows' buoyancy (Archimedes on
the submerged volume), the time each recorded pose belongs to, the scene's geometry and water level, and the
ground mesh's budget."""

from __future__ import annotations

import math
import threading
import types

import mujoco
import numpy as np
import pytest
import torch

from legged_gente.terrain.materials import MaterialMap
from legged_gente.viewer.rollout import Kinematics, Rollout, robot_forces
from legged_gente.viewer.scene import terrain_scene

RHO, G = 1000.0, 9.81  # water density (kg/m^3), gravity (m/s^2)


class _Wp:
    """A stand-in for a Warp array: what ``robot_forces`` reads with ``.numpy()``."""

    def __init__(self, array):
        self.array = np.asarray(array)

    def numpy(self):
        return self.array


# Three free bodies, each one leg segment of radius 0.05 m and cylinder half-length 0.15 m, in still water whose
# surface is at z = 0.3 m: a vertical capsule and a vertical cylinder centred at z = 0.4 m, a level capsule with its
# axis on the surface.
SEGMENTS_XML = """
<mujoco><worldbody>
  <body pos="0 0 0.4"><freejoint/><geom name="capsule" type="capsule" size="0.05 0.15"/></body>
  <body pos="2 0 0.4"><freejoint/><geom name="cylinder" type="cylinder" size="0.05 0.15"/></body>
  <body pos="4 0 0.3"><freejoint/><geom name="level" type="capsule" size="0.05 0.15" euler="0 90 0"/></body>
</worldbody></mujoco>
"""


def _water_env(segment_force: np.ndarray):
    mjm = mujoco.MjModel.from_xml_string(SEGMENTS_XML)
    geoms = [mujoco.mj_name2id(mjm, mujoco.mjtObj.mjOBJ_GEOM, n) for n in ("capsule", "cylinder", "level")]
    shape = (80, 20)  # 0.1 m cells from (-1, -1) m: x in [-1, 6.9], y in [-1, 0.9]
    material = MaterialMap.rigid(shape)
    material.water_surface[:] = 0.3
    terrain = types.SimpleNamespace(material=material, origin_xy=(-1.0, -1.0), resolution=0.1)
    forces = types.SimpleNamespace(
        cfg=types.SimpleNamespace(water_density=RHO), g=G, nseg=3, nfoot=0,
        seg_geom=_Wp(geoms), seg_radius=_Wp([0.05] * 3), seg_halflen=_Wp([0.15] * 3), seg_caps=_Wp([1, 0, 1]),
        seg_force=_Wp(segment_force[None]), foot_force=_Wp(np.zeros((1, 0, 3))), eps=_Wp([1.0]),
        foot_body=_Wp(np.zeros(0, int)), foot_offset=_Wp(np.zeros((0, 3))))
    sim = types.SimpleNamespace(qpos=torch.tensor(mjm.qpos0[None]))
    return types.SimpleNamespace(forces=forces, terrain=terrain, sim=sim), Kinematics(mjm)


def test_buoyancy_arrow_is_archimedes_of_the_submerged_volume():
    """Archimedes: F = rho g V, V the submerged volume. r = 0.05 m, cylinder part 0.3 m long, surface z = 0.3 m.
    Vertical capsule centred at 0.4 m: its cylinder part reaches down to 0.25 m, so 0.05 m of it is wet, plus
    the whole lower hemisphere: V = pi r^2 0.05 + 2/3 pi r^3. Vertical cylinder (no caps): V = pi r^2 0.05.
    Level capsule with its axis on the surface: half of it, V = (pi r^2 0.3 + 4/3 pi r^3) / 2. A robot standing
    in still water feels only buoyancy, so with the kernel's total equal to it no drag arrow is left."""
    r = 0.05
    volumes = np.array([math.pi * r**2 * 0.05 + 2 / 3 * math.pi * r**3,
                        math.pi * r**2 * 0.05,
                        (math.pi * r**2 * 0.3 + 4 / 3 * math.pi * r**3) / 2])
    buoyancy = RHO * G * volumes  # 6.42 N, 3.85 N, 14.13 N
    total = np.zeros((3, 3))
    total[:, 2] = buoyancy
    env, kin = _water_env(total)
    forces, points = robot_forces(env, np.array([0]), kin)
    np.testing.assert_allclose(forces[0, :3, 2], buoyancy, rtol=1e-4)
    np.testing.assert_allclose(forces[0, :3, :2], 0.0, atol=1e-6)
    np.testing.assert_allclose(forces[0, 3:6], 0.0, atol=1e-3)  # drag: none in still water at rest
    # where it acts: on each axis, in the wet part (bottom of the capsule 0.2 m, of the cylinder 0.25 m, to 0.3 m)
    np.testing.assert_allclose(points[0, :3, :2], [[0.0, 0.0], [2.0, 0.0], [4.0, 0.0]], atol=1e-6)
    assert 0.2 < points[0, 0, 2] < 0.3 and 0.25 < points[0, 1, 2] < 0.3
    assert points[0, 2, 2] == pytest.approx(0.3, abs=1e-6)


def _still_rollout(steps: int, dt: float = 0.02) -> Rollout:
    """A recorded rollout of the flat biped standing in its default pose, ``steps`` policy steps of ``dt`` s."""
    from legged_gente.viewer.rollout import robot_model

    mjm = robot_model("gente_biped_flat")
    z = lambda *shape: np.zeros((steps, 1, *shape), np.float32)  # noqa: E731
    return Rollout("gente_biped_flat", dt, np.tile(mjm.qpos0, (steps, 1, 1)).astype(np.float32), z(3), z(3),
                   np.zeros((steps, 1), bool), np.zeros((steps, 1), bool), [], z(0, 3), z(0, 3),
                   np.zeros((2, 2), np.float32), (-1.0, -1.0), 1.0, MaterialMap.rigid((2, 2)))


def _free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_a_recorded_pose_is_shown_at_the_time_it_was_reached():
    """Row k of a rollout is the state after policy step k + 1 (the recorder adds a row after each env.step), so it
    is shown at t = (k + 1) dt: with dt = 0.02 s, 3 rows are 0.02, 0.04 and 0.06 s, and the rollout lasts 0.06 s."""
    from legged_gente.viewer.rollout import robot_model
    from legged_gente.viewer.scene import BareTerrain
    from legged_gente.viewer.server import TerrainItem, Viewer

    rollout = _still_rollout(3)
    terrain = BareTerrain(rollout.heights, rollout.material, rollout.resolution, rollout.origin)
    viewer = Viewer([TerrainItem("rollout", lambda: terrain)], port=_free_port(), shadows=False)
    try:
        player = viewer.attach_rollout(rollout, robot_model(rollout.task), play=False)
        player.draw(0)
        assert player.time_gui.content.startswith("t = 0.02 s of 0.06 s")
        player.draw(2)
        assert player.time_gui.content.startswith("t = 0.06 s of 0.06 s")
        for _ in range(100):  # the player's loop draws the velocity plot once it sees the rows
            if player.plot_gui is not None:
                break
            threading.Event().wait(0.05)
        np.testing.assert_allclose(player.plot_gui.data[0], [0.02, 0.04, 0.06])
    finally:
        viewer.stop()


def test_gente_play_plots_each_step_at_the_time_it_was_reached(tmp_path, monkeypatch):
    """gente-play logs robot 0 after each policy step: 3 steps of 0.02 s are plotted at 0.02, 0.04, 0.06 s."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from legged_gente.scripts.play import plot_tracking

    figures = []
    monkeypatch.setattr(plt, "close", figures.append)
    log = {"cmd": np.zeros((3, 3)), "vel": np.zeros((3, 3)), "reset": np.array([False, False, True]),
           "fall": np.zeros(3, bool)}
    plot_tracking(log, 0.02, tmp_path / "tracking.png")
    (figure,) = figures
    np.testing.assert_allclose(figure.axes[0].lines[0].get_xdata(), [0.02, 0.04, 0.06])
    reset_line = [line for line in figure.axes[0].lines if line.get_label() == "robot 0 reset"][0]
    assert reset_line.get_xdata()[0] == pytest.approx(0.06)  # the episode ended at the third step


class _TileCfg:
    """One 20 m x 20 m tile with a 1 m border, flat, at ``resolution``."""

    mesh_type, mode, border_size = "heightfield", "selected", 1.0
    terrain_length = terrain_width = 20.0
    num_rows = num_cols = 1
    terrain_types, terrain_proportions = ["flat"], [1.0]
    selected_terrain, selected_params, generated_specs = "flat", {}, []
    max_difficulty, max_init_terrain_level, curriculum, static_friction, seed = 1.0, 0, True, 1.0, 0


@pytest.mark.parametrize("resolution, drawn", [(0.05, 401), (0.04, 251)])
def test_a_tile_alone_is_drawn_whole_up_to_the_budget(resolution, drawn):
    """A tile alone is drawn with its far edge: 20 m / 0.05 m = 400 cells -> 401 x 401 = 160 801 samples, under
    the 250 000 budget, all drawn; at 0.04 m, 501 x 501 = 251 001 samples, over it: every 2nd sample
    (ceil(sqrt(251 001 / 250 000)) = 2), 0, 2, ..., 500 -> 251 per axis."""
    from legged_gente.terrain.terrain import Terrain

    cfg = type("Cfg", (_TileCfg,), {"resolution": resolution})
    terrain = Terrain(cfg, num_robots=1)
    ground = terrain_scene(terrain, tile=(0, 0)).nodes["/terrain/ground"]
    assert len(ground.vertices) == drawn * drawn
    # the tile's first sample at world (0, 0), its last at (20, 20): the first tile starts at the origin
    np.testing.assert_allclose(ground.vertices[[0, -1], :2], [[0.0, 0.0], [20.0, 20.0]], atol=1e-4)


def test_recorded_poses_are_the_env_state_after_each_step():
    """The recorder keeps, after each policy step, the env's qpos; the viewer draws body poses from it with MuJoCo's
    kinematics, and they are the bodies MuJoCo-Warp places from that state. A time-out after 5 steps (episode
    0.1 s, dt 0.02 s) is marked on row 4, which holds the ended episode's last state (the env's state before the
    reset within that step), not the respawn: the robot dropped from 3 cm above its 1.0 m stance has landed by
    then (a 3 cm fall takes sqrt(2 * 0.03 / 9.81) = 0.078 s), one step's travel from row 3, while the env after
    the step holds the spawn, (0, 0) + the task's initial base position (z = 1.03 m)."""
    from legged_gente.scripts import view as view_script
    from legged_gente.utils.args import parse_args

    args = parse_args(view_script.build_arg_parser(), ["--task", "gente_biped_flat", "--device", "cpu", "--play",
                                                       "--policy", "zero", "--robots", "1",
                                                       "--set", "env.episode_length_s=0.1"])
    env, policy, recorder = view_script._make_play(args)
    assert env.dt == pytest.approx(0.02) and env.max_episode_length == 5
    seen, ended = [], None
    obs = env.get_observations()
    with torch.inference_mode():
        for step in range(7):
            obs, _, _, _ = env.step(policy(obs))
            recorder.add()
            seen.append(env.sim.qpos[0].clone().numpy())
            if step == 4:
                ended = env.terminal_qpos[0].clone().numpy()
    rollout = recorder.rollout()
    live = [0, 1, 2, 3, 5, 6]
    np.testing.assert_array_equal(rollout.qpos[live, 0], np.stack(seen)[live].astype(np.float32))
    np.testing.assert_array_equal(rollout.qpos[4, 0], ended)
    assert rollout.done[:, 0].tolist() == [False] * 4 + [True, False, False]
    assert not rollout.fell.any()  # a time-out, not a fall
    spawn = env.init_base_state[:3].numpy()  # the tile origin of a plane is (0, 0, 0)
    np.testing.assert_allclose(seen[4][:3], spawn, atol=1e-6)  # the env after the step: respawned
    assert rollout.qpos[4, 0, 2] < 1.01 < spawn[2]  # landed: not the spawn
    assert np.abs(rollout.qpos[4, 0, :3] - rollout.qpos[3, 0, :3]).max() < 0.05  # one step of 0.02 s from row 3
    # bodies: MuJoCo's kinematics of the last row against MuJoCo-Warp's bodies of the same state
    env.sim.forward(torch.ones(env.num_envs, dtype=torch.bool))
    d = Kinematics(env.mjm)(rollout.qpos[-1, 0].astype(np.float64))
    np.testing.assert_allclose(d.xpos, env.sim.xpos[0].numpy(), atol=1e-5)
    np.testing.assert_allclose(d.xquat, env.sim.xquat[0].numpy(), atol=1e-5)


class _WaterMudCfg:
    """A 1 x 2 grid of 4 m tiles at 0.1 m with a 1 m border: a tide 0.3 m deep (0.4 m/s along +y), then mud."""

    mesh_type, mode, resolution, border_size = "heightfield", "curriculum", 0.1, 1.0
    terrain_length = terrain_width = 4.0
    num_rows, num_cols = 1, 2
    terrain_types = ["water:depth=0.3,flow=tide,speed=0.4,direction=1.5707963", "soil:preset=mud"]
    terrain_proportions = [0.5, 0.5]
    selected_terrain, selected_params, generated_specs = "flat", {}, []
    max_difficulty, max_init_terrain_level, curriculum, static_friction, seed = 1.0, 0, True, 1.0, 0


def test_scene_geometry_colours_and_water_level_by_hand():
    """Vertex (i, j) at (-1 + 0.1 i, -1 + 0.1 j) m (a 1 m border before the first tile at the origin) with the
    heightfield's height; tile (0, 1) covers x in [0, 4], y in [4, 8]. Physical terrains lie on flat ground (z = 0),
    so the water surface is 0 + 0.3 m; mud in its colour, the rest grey ground. The tide's arrows: one per 1 m
    (cells 5, 15, ... of the grid: x, y = -0.5, 0.5, ... m), on wet cells only (x, y in [0, 3.9]: 0.5 ... 3.5, four
    per axis), 3 cm above the surface, 0.4 m (its amplitude times 1 s) along +y."""
    from legged_gente.terrain.terrain import SOIL_COLOURS, Terrain
    from legged_gente.viewer.scene import GROUND_COLOUR

    terrain = Terrain(_WaterMudCfg, num_robots=1)
    assert terrain.height_field.shape == (4 / 0.1 + 20, 8 / 0.1 + 20) and not terrain.height_field.any()
    scene = terrain_scene(terrain)
    ground = scene.nodes["/terrain/ground"]
    xy = ground.vertices[:, :2].reshape(60, 100, 2)
    np.testing.assert_allclose(xy[13, 57], [-1 + 1.3, -1 + 5.7], atol=1e-5)
    np.testing.assert_allclose(ground.vertices[:, 2], 0.0)
    colours = ground.vertex_colors.reshape(60, 100, 3)
    mud = [round(255 * c) for c in SOIL_COLOURS["mud"]]
    grey = [round(255 * c) for c in GROUND_COLOUR]
    assert (colours[10:50, 50:90] == mud).all()  # tile (0, 1): x cells 10..49, y cells 50..89
    assert (colours[:10] == grey).all() and (colours[10:50, 10:50] == grey).all()  # border, water tile's floor
    water = scene.nodes["/terrain/water"]
    used = np.unique(water.faces)
    np.testing.assert_allclose(water.vertices[used, 2], 0.3, atol=1e-6)
    wx, wy = water.vertices[used, 0], water.vertices[used, 1]
    assert wx.min() == pytest.approx(0.0) and wx.max() == pytest.approx(3.9)  # wet cells 10..49 of the tile
    assert wy.min() == pytest.approx(0.0) and wy.max() == pytest.approx(3.9)
    arrows = scene.nodes["/terrain/flow"].points
    assert len(arrows) == 16
    np.testing.assert_allclose(np.unique(arrows[:, 0, 0]), [0.5, 1.5, 2.5, 3.5], atol=1e-5)
    np.testing.assert_allclose(arrows[:, 0, 2], 0.33, atol=1e-6)
    np.testing.assert_allclose(arrows[:, 1] - arrows[:, 0], np.tile([0.0, 0.4, 0.0], (16, 1)), atol=1e-5)


class _SceneOnlyRenderer:
    """mujoco.Renderer without OpenGL: builds the abstract scene (cameras included), renders nothing."""

    def __init__(self, model, height, width):
        self.model, self.scene = model, mujoco.MjvScene(model, 1000)
        self.option, self.perturb = mujoco.MjvOption(), mujoco.MjvPerturb()

    def update_scene(self, data, camera):
        mujoco.mjv_updateScene(self.model, data, self.option, self.perturb, camera, mujoco.mjtCatBit.mjCAT_ALL,
                               self.scene)

    def render(self):
        return np.zeros((2, 2, 3), np.uint8)

    def close(self):
        pass


def test_the_video_camera_follows_the_base_from_the_side(monkeypatch):
    """MuJoCo's camera looks along (cos el cos az, cos el sin az, sin el) at the tracked body's subtree centre of
    mass from ``distance`` away. Distance 3.5 m, elevation -20 deg, azimuth 60 deg: the camera sits at
    com + 3.5 (-cos 20 cos 60, -cos 20 sin 60, sin 20) = com + (-1.645, -2.848, 1.197) m, to the robot's right
    (-y) as it walks along +x, and stays there wherever the robot goes."""
    from legged_gente.envs.task_registry import task_registry
    from legged_gente.sim.assembly import resolve_path
    from legged_gente.viewer import video

    monkeypatch.setattr(video.mujoco, "Renderer", _SceneOnlyRenderer)
    env_cfg, _ = task_registry.get_cfgs("gente_biped_flat")
    renderer = video.VideoRenderer(resolve_path(env_cfg.asset.file), None)
    el, az = math.radians(-20.0), math.radians(60.0)
    offset = -3.5 * np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    qpos = renderer.model.qpos0.copy()
    for x in (0.0, 1.0, 5.0):
        qpos[0] = x
        renderer.capture(qpos)
        eyes = renderer.renderer.scene.camera
        position = (np.array(eyes[0].pos) + np.array(eyes[1].pos)) / 2
        com = renderer.data.subtree_com[int(renderer.model.jnt_bodyid[0])]
        np.testing.assert_allclose(position - com, offset, atol=1e-4)
    assert len(renderer.frames) == 3


def test_a_video_lasts_its_steps_at_one_frame_per_policy_step(tmp_path):
    """gente-play writes one frame per policy step at fps = 1 / dt: 12 steps of 0.02 s -> 12 frames at 50 fps,
    0.24 s, 640 x 480."""
    import imageio

    from legged_gente.scripts.play import VideoRecorder

    recorder = VideoRecorder.__new__(VideoRecorder)  # its renderer's frames only: no OpenGL needed
    recorder.renderer = types.SimpleNamespace(frames=[np.full((480, 640, 3), 20 * k, np.uint8) for k in range(12)],
                                              close=lambda: None)
    recorder.save(tmp_path / "rollout.mp4", fps=1.0 / 0.02)
    reader = imageio.get_reader(tmp_path / "rollout.mp4")
    meta = reader.get_meta_data()
    assert meta["fps"] == pytest.approx(50.0) and meta["duration"] == pytest.approx(0.24)
    assert meta["size"] == (640, 480) and sum(1 for _ in reader) == 12
    reader.close()


def test_a_reset_row_draws_no_force_arrows_of_the_ended_episode():
    """Standing in water 0.35 m deep, the biped's shanks are wet (buoyancy > 0 on every row of an episode). Row 4
    ends the 0.1 s episode (5 steps of 0.02 s): its qpos is the ended episode's last state while the env's forces
    were redrawn and recomputed for the respawned robot by the reset, so that row has no force arrows; the next
    episode's rows have them again."""
    from legged_gente.scripts import view as view_script
    from legged_gente.utils.args import parse_args

    args = parse_args(view_script.build_arg_parser(), [
        "--task", "gente_biped", "--device", "cpu", "--play", "--policy", "zero", "--robots", "1",
        "--set", "env.episode_length_s=0.1", "--set", "terrain.terrain_types=['water:depth=0.35']",
        "--set", "terrain.terrain_proportions=[1.0]", "--set", "terrain.num_rows=1", "--set", "terrain.num_cols=1"])
    env, policy, recorder = view_script._make_play(args)
    view_script._run_play(env, policy, recorder, 6, None)
    rollout = recorder.rollout()
    assert rollout.done[:, 0].tolist() == [False] * 4 + [True, False]
    buoyancy = [k for k, label in enumerate(rollout.force_labels) if label.startswith("buoyancy:")]
    lift = rollout.forces[:, 0, buoyancy, 2].sum(1)
    assert (lift[[0, 1, 2, 3, 5]] > 1.0).all()
    assert not rollout.forces[4].any() and not rollout.force_points[4].any()
