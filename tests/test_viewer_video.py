"""Videos: the ground texture (material colours under a 1 m checker, laid out as MuJoCo maps it on a heightfield),
the render-only model (terrain, water sheet, flow arrows) and a rendered frame (offscreen OpenGL: MUJOCO_GL=egl)."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from legged_gente.terrain.terrain import SOIL_COLOURS, Terrain
from legged_gente.viewer.scene import terrain_scene
from legged_gente.viewer.video import CHECKER_DARK, TEXELS_PER_CELL, ground_texture, render_model


class SandAndWater:
    mesh_type, mode, resolution, border_size = "heightfield", "curriculum", 0.1, 0.5
    terrain_length = terrain_width = 4.0
    num_rows, num_cols = 1, 2
    terrain_types = ["soil:preset=dry_sand", "water:flow=current,speed=0.5,direction=0.0,depth=0.3"]
    terrain_proportions = [0.5, 0.5]
    selected_terrain, selected_params, generated_specs = "flat", {}, []
    max_difficulty, max_init_terrain_level, curriculum, static_friction, seed = 1.0, 0, True, 1.0, 0


@pytest.fixture(scope="module")
def terrain():
    return Terrain(SandAndWater, num_robots=1)


def robot_file():
    from legged_gente.envs.task_registry import task_registry
    from legged_gente.sim.assembly import resolve_path

    return resolve_path(task_registry.get_cfgs("gente_biped")[0].asset.file)


def test_ground_texture_layout_and_checker():
    """MuJoCo stretches the texture over the heightfield, from its first sample to its last (render_gl3.c,
    settexture: s = x / (2 half_x) + 1/2 over the geom), and the force kernels read the nearest sample's material:
    each texel shows the sample nearest to it, and the checker is at its place in the world."""
    # 3 x 2 samples 0.5 m apart from (0.5, 0) m: the heightfield spans x in [0.5, 1.5], y in [0, 0.5] m
    colours = np.ones((3, 2, 3))
    colours[2, 0] = (1.0, 0.0, 0.0)  # sample (2, 0) at (1.5, 0) m: nearest for x in [1.25, 1.5], y in [0, 0.25]
    k = TEXELS_PER_CELL
    assert k == 4  # the texel positions below: 1 m / 8 texels = 0.125 m per texel
    image = ground_texture(colours, 0.5, (0.5, 0.0)).astype(int)
    assert image.shape == (1 * k, 2 * k, 3)  # (ny - 1) x (nx - 1) cells; rows along y, columns along x
    # texel column c is centred at x = 0.5 + (c + 0.5) * 0.125 m; row r at y = 0.5 - (r + 0.5) * 0.125 m (row 0 at
    # the largest y): the red sample is in columns 6, 7 (x = 1.3125, 1.4375 m) and rows 2, 3 (y = 0.1875, 0.0625 m)
    dark, light = round(255 * CHECKER_DARK), 255
    red = (image[..., 0] > 0) & (image[..., 1] == 0)
    assert red[2:, 6:].all() and red.sum() == 4
    # the 1 m checker line x = 1 m lies between column 3 (x = 0.9375 m, light) and column 4 (x = 1.0625 m, dark)
    assert (image[:, :4] == light).all() and (image[:, 4:, 0] == dark).all()


def test_render_model_has_the_terrain_the_water_and_the_flow(terrain):
    import mujoco

    from legged_gente.viewer.rollout import robot_model

    model, arrows = render_model(robot_file(), terrain)
    assert model.nq == robot_model("gente_biped").nq  # the task's qpos layout
    assert model.nhfield == 1 and tuple(model.hfield_nrow) == (terrain.height_field.shape[1],)
    assert model.ntex >= 2 and model.tex_width[1] == (terrain.height_field.shape[0] - 1) * TEXELS_PER_CELL
    water = [g for g in range(model.ngeom) if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH
             and model.geom_bodyid[g] == 0]
    assert len(water) == 1 and model.geom_rgba[water[0], 3] == pytest.approx(0.5)
    # the sheet lies at the water's level (the surface of the water tile); MuJoCo stores a mesh's vertices in
    # its own frame, placed by the geom's pos and quat
    mesh, rot = model.geom_dataid[water[0]], np.zeros(9)
    mujoco.mju_quat2Mat(rot, model.geom_quat[water[0]])
    local = model.mesh_vert[model.mesh_vertadr[mesh]:model.mesh_vertadr[mesh] + model.mesh_vertnum[mesh]]
    world = local @ rot.reshape(3, 3).T + model.geom_pos[water[0]]
    level = terrain.material.water_surface[terrain.material.has_water()]
    np.testing.assert_allclose(world[:, 2], level.max(), atol=1e-4)
    assert len(arrows) == len(terrain_scene(terrain).nodes["/terrain/flow"].points) > 0
    np.testing.assert_allclose(arrows[:, 1] - arrows[:, 0], np.tile([0.5, 0.0, 0.0], (len(arrows), 1)), atol=1e-5)
    assert all(model.geom_contype[g] == 0 for g in range(model.ngeom) if model.geom_bodyid[g] == 0)  # render only


FRAME_SCRIPT = """
import sys
import numpy as np
import pytest
sys.path.insert(0, sys.argv[2])
from test_viewer_video import SandAndWater, robot_file
from legged_gente.terrain.terrain import Terrain
from legged_gente.viewer.video import VideoRenderer

terrain = Terrain(SandAndWater, num_robots=1)
renderer = VideoRenderer(robot_file(), terrain, width=160, height=120, elevation=-35.0)
qpos = renderer.model.qpos0.copy()
qpos[:3] = (*terrain.terrain_origins[0, 0, :2], 0.95)  # on the sand tile
frame = renderer.capture(qpos)
with pytest.raises(ValueError, match="another robot"):
    renderer.capture(qpos[:-1])
renderer.close()
np.save(sys.argv[1], frame)
"""


def test_a_frame_shows_the_sand_and_the_robot(tmp_path):
    """Rendered in a fresh interpreter: MuJoCo picks its OpenGL backend (MUJOCO_GL=egl) on its first import."""
    out = tmp_path / "frame.npy"
    env = dict(os.environ, MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl"))
    subprocess.run([sys.executable, "-c", FRAME_SCRIPT, str(out), os.path.dirname(__file__)], check=True, env=env,
                   timeout=600)
    frame = np.load(out).astype(int)
    assert frame.shape == (120, 160, 3)
    r, g, b = frame[..., 0], frame[..., 1], frame[..., 2]
    sandy = (r > b + 25) & (g > b + 15) & (r >= g)  # dry sand (0.93, 0.83, 0.56): warm, lit, checkered
    assert sandy.mean() > 0.1, f"sand on {sandy.mean():.1%} of the frame, colour {SOIL_COLOURS['dry_sand']}"
    water = (b > r + 60) & (b > g + 30)  # the water tile beside it, under its translucent blue sheet
    assert water.mean() > 0.05, f"water on {water.mean():.1%} of the frame"
    # the tracked base is in the middle: the robot's grey (r = g = b) body there, far more than in a sandy corner
    grey = (np.abs(r - b) < 12) & (np.abs(g - b) < 12) & (r > 90)
    assert grey[30:90, 60:100].mean() > 0.1 and grey[30:90, 60:100].mean() > 2.5 * grey[90:, :40].mean()


def test_gente_play_video_on_a_plane(tmp_path):
    """gente-play --video films robot 0 with the same renderer; the flat task's plane is the checker ground."""
    import imageio.v3 as iio

    env = dict(os.environ, MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl"))
    subprocess.run([sys.executable, "-m", "legged_gente.scripts.play", "--task", "gente_biped_flat", "--pretrained",
                    "--video", "--headless", "--steps", "10", "--num_envs", "1", "--device", "cpu",
                    "--log_root", str(tmp_path)], check=True, env=env, timeout=600, stdout=subprocess.DEVNULL)
    video = tmp_path / "gente_biped_flat" / "pretrained" / "exported" / "rollout.mp4"
    frames = iio.imread(video)
    assert frames.shape[0] == 10 and frames.shape[1:] == (480, 640, 3)
    last = frames[-1].astype(int)
    assert last.std() > 10 and (np.abs(last[..., 0] - last[..., 2]) < 40).mean() > 0.5  # grey checker, robot


@pytest.mark.parametrize("gl", ["bogus", "osmesa"])
def test_gente_play_video_without_offscreen_gl_is_one_line(tmp_path, gl):
    """An unknown MUJOCO_GL or osmesa without libOSMesa: one line naming the fix (MUJOCO_GL=egl), no traceback."""
    env = dict(os.environ, MUJOCO_GL=gl)
    done = subprocess.run([sys.executable, "-m", "legged_gente.scripts.play", "--task", "gente_biped_flat",
                           "--pretrained", "--video", "--headless", "--steps", "1", "--num_envs", "1", "--device",
                           "cpu", "--log_root", str(tmp_path)], env=env, timeout=600, capture_output=True, text=True)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert lines[-1].startswith(f"gente-play: error: MUJOCO_GL={gl}: MuJoCo's OpenGL backend does not load") \
        and "set MUJOCO_GL=egl" in lines[-1], lines[-1]


def test_gente_play_video_with_no_gl_set_is_one_line(tmp_path):
    """MUJOCO_GL unset and no display: MuJoCo tries GLFW, whose two warnings came before the one-line error (Warp's
    native CUDA-driver notice on a machine without a GPU is printed before Python can quiet it)."""
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "DISPLAY", "PYOPENGL_PLATFORM")}
    done = subprocess.run([sys.executable, "-m", "legged_gente.scripts.play", "--task", "gente_biped_flat",
                           "--pretrained", "--video", "--headless", "--steps", "1", "--num_envs", "1", "--device",
                           "cpu", "--log_root", str(tmp_path)], env=env, timeout=600, capture_output=True, text=True)
    lines = [line for line in done.stderr.strip().splitlines() if not line.startswith("Warp CUDA warning")]
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert lines[0].startswith("gente-play: error: MUJOCO_GL is unset: offscreen rendering failed") \
        and "set MUJOCO_GL=egl" in lines[0], lines[0]


def test_a_renderer_without_a_gl_context_is_a_one_line_error(terrain, monkeypatch, capsys):
    """MUJOCO_GL=egl without libEGL: the renderer's creation fails; gente-play says so in one line."""
    import mujoco

    from legged_gente.utils.args import build_parser, parse_args, run_command
    from legged_gente.viewer.video import VideoRenderer

    def no_context(*args, **kwargs):
        raise AttributeError("'NoneType' object has no attribute 'eglGetCurrentContext'")

    monkeypatch.setattr(mujoco, "Renderer", no_context)
    with pytest.raises(SystemExit) as exit_info:
        run_command("gente-play", lambda args: VideoRenderer(robot_file(), terrain),
                    parse_args(build_parser("t"), ["--device", "cpu"]))
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and len(err.splitlines()) == 1, err
    assert "offscreen rendering failed (AttributeError: " in err and "set MUJOCO_GL=egl" in err, err


def test_gente_play_video_without_a_gl_context_is_refused_before_the_env_is_built(monkeypatch, capsys):
    """The one-line error comes first, not after the env build and the policy's export."""
    import mujoco

    from legged_gente.envs.task_registry import task_registry
    from legged_gente.scripts import play as play_script

    def no_context(*args, **kwargs):
        raise AttributeError("'NoneType' object has no attribute 'eglGetCurrentContext'")

    def built(*args, **kwargs):
        raise AssertionError("the env was built before the video's OpenGL check")

    monkeypatch.setattr(mujoco, "Renderer", no_context)
    monkeypatch.setattr(task_registry, "make_env", built)
    with pytest.raises(SystemExit) as exit_info:
        play_script.main(["--task", "gente_biped_flat", "--pretrained", "--video", "--headless", "--steps", "1",
                          "--num_envs", "1", "--device", "cpu"])
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and len(err.splitlines()) == 1, err
    assert "offscreen rendering failed (AttributeError: " in err and "set MUJOCO_GL=egl" in err, err
