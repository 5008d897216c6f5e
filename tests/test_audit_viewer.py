"""gente-view and the video renderer: inputs that went wrong (malformed rollout files, a --record path numpy would
rename, a frame size H.264 cannot encode, a --seconds that is no number) are refused in one line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from test_viewer_inputs import no_server, one_line_error

from legged_gente.scripts import view as view_script
from legged_gente.terrain.materials import MaterialMap
from legged_gente.viewer.rollout import Rollout

BIPED_NQ = 7 + 10  # free joint (x y z, quaternion w x y z) + the biped's 10 joints


def rollout(steps: int = 3, robots: int = 1, labels: tuple[str, ...] = ("soil:foot",)) -> Rollout:
    """A well-formed rollout of the flat biped: T steps, R robots, one force arrow per label, a 2 x 2 terrain."""
    k = len(labels)
    return Rollout("gente_biped_flat", 0.02, np.zeros((steps, robots, BIPED_NQ), np.float32),
                   np.zeros((steps, robots, 3)), np.zeros((steps, robots, 3)), np.zeros((steps, robots), bool),
                   np.zeros((steps, robots), bool), list(labels), np.zeros((steps, robots, k, 3), np.float32),
                   np.zeros((steps, robots, k, 3), np.float32), np.zeros((2, 2), np.float32), (0.0, 0.0), 0.5,
                   MaterialMap.rigid((2, 2)))


def malformed(name: str) -> Rollout:
    r = rollout()
    if name == "no steps":  # gente-view: AttributeError traceback ('Rollout' object has no attribute 'robots')
        r = rollout(steps=0)
    elif name == "cmd rows":  # 2 commands for 3 poses: the velocity plot's series of unequal length
        r.cmd = np.zeros((2, 1, 3))
    elif name == "done robots":
        r.done = np.zeros((3, 2), bool)
    elif name == "qpos not 3-D":  # each pose drawn as 17 robots of one number
        r.qpos = np.zeros((3, BIPED_NQ), np.float32)
    elif name == "forces vs labels":  # 1 label, 2 arrows per robot
        r.forces = r.force_points = np.zeros((3, 1, 2, 3), np.float32)
    elif name == "label kind":
        r.force_labels = ["wind:foot"]
    elif name == "dt zero":  # the play loop spins without waiting, every time shown as 0 s
        r.dt = 0.0
    elif name == "dt nan":  # the play loop's wait raises: the player thread dies
        r.dt = float("nan")
    elif name == "resolution zero":
        r.resolution = 0.0
    elif name == "heights vs material":  # gente-view: IndexError traceback building the ground's colours
        r.heights = np.zeros((3, 3), np.float32)
    elif name == "qpos nan":
        r.qpos[1, 0, 0] = np.nan
    return r


CASES = {
    "no steps": "qpos has shape (0, 1, 17): a rollout holds (T, R, nq) with at least one step and one robot",
    "cmd rows": "cmd has shape (2, 1, 3), qpos's (T, R) = (3, 1) needs (3, 1, 3)",
    "done robots": "done has shape (3, 2), qpos's (T, R) = (3, 1) needs (3, 1)",
    "qpos not 3-D": "qpos has shape (3, 17): a rollout holds (T, R, nq) with at least one step and one robot",
    "forces vs labels": "forces has shape (3, 1, 2, 3), qpos's (T, R) = (3, 1) needs (3, 1, 1, 3)",
    "label kind": "force label 'wind:foot' is not <kind>:<name> with kind one of ('buoyancy', 'drag', 'soil')",
    "dt zero": "dt = 0.0 s must be a finite number > 0",
    "dt nan": "dt = nan s must be a finite number > 0",
    "resolution zero": "terrain_resolution = 0.0 m must be a finite number > 0",
    "heights vs material": "terrain_water_surface has shape (2, 2), terrain_heights (3, 3)",
    "qpos nan": "qpos is not finite at step 1",
}


@pytest.mark.parametrize("name", CASES)
def test_a_malformed_rollout_file_is_refused_in_one_line(name, tmp_path, capsys, monkeypatch):
    """Rollout.load read any arrays under the right keys: a file of no steps or of mismatched shapes crashed
    gente-view with a traceback (or a player thread that died) instead of saying what is wrong with the file."""
    path = malformed(name).save(tmp_path / "r.npz")
    with pytest.raises(ValueError) as error:
        Rollout.load(path)
    assert str(error.value) == f"{path}: {CASES[name]}; record it again."
    line = one_line_error(capsys, monkeypatch, [str(path)])
    assert line == f"gente-view: error: {path}: {CASES[name]}; record it again."


def test_a_well_formed_rollout_still_loads(tmp_path):
    path = rollout(steps=4, robots=2, labels=("buoyancy:shin", "drag:shin", "soil:foot")).save(tmp_path / "r.npz")
    back = Rollout.load(path)
    assert (back.num_steps, back.num_robots, back.forces.shape) == (4, 2, (4, 2, 3, 3))


def test_a_rollout_of_version_1_is_refused_in_one_line(tmp_path, capsys, monkeypatch):
    """Version 1 files put the next episode's start on a done row; version 2 puts the ended episode's last state
    there. The arrays are the same, so an old file would load and show respawns as the poses episodes ended in."""
    path = rollout().save(tmp_path / "r.npz")
    with np.load(path) as f:
        arrays = {k: f[k] for k in f.files}
    np.savez(path, **(arrays | {"version": np.array(1)}))
    line = one_line_error(capsys, monkeypatch, [str(path)])
    assert line == f"gente-view: error: {path}: rollout version 1, this viewer reads 2; record it again."


def test_a_rollout_file_missing_arrays_names_them(tmp_path, capsys, monkeypatch):
    """A file without some of the arrays: 'cmd is not a file in the archive', naming neither the file nor the fix."""
    path = rollout().save(tmp_path / "r.npz")
    with np.load(path) as f:
        arrays = {k: f[k] for k in f.files if k not in ("cmd", "terrain_friction")}
    np.savez(path, **arrays)
    line = one_line_error(capsys, monkeypatch, [str(path)])
    assert line == (f"gente-view: error: {path} has no cmd, terrain_friction: it is not a complete rollout file; "
                    f"record it again.")


def test_a_rollout_saved_without_npz_is_where_it_says(tmp_path):
    """np.savez_compressed adds .npz to a name without it: save('rollout') wrote rollout.npz and returned (and
    gente-view --record printed) 'rollout', a file that does not exist."""
    written = rollout().save(tmp_path / "rollout")
    assert written == tmp_path / "rollout.npz" and written.is_file()
    assert not (tmp_path / "rollout").exists()


def test_record_without_npz_is_refused_before_playing(tmp_path, capsys, monkeypatch):
    """gente-view opens a rollout by its .npz suffix: `--record out` wrote out.npz, printed 'wrote out', and
    `gente-view out` was then taken for a benchmark folder."""
    line = one_line_error(capsys, monkeypatch, ["--task", "gente_biped_flat", "--play", "--policy", "zero",
                                                "--steps", "1", "--record", str(tmp_path / "out")])
    assert line == (f"gente-view: error: --record {tmp_path / 'out'}: name the rollout file *.npz "
                    f"(gente-view opens rollouts by that suffix)")
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("seconds", ["nan", "-1"])
def test_seconds_that_is_no_duration_is_refused(seconds, capsys, monkeypatch):
    """--seconds nan passed the `< 0` check (NaN compares false) and the viewer stopped at once."""
    import viser

    monkeypatch.setattr(viser, "ViserServer", no_server)
    with pytest.raises(SystemExit) as exit_info:
        view_script.main(["--task", "gente_biped_flat", "--headless", "--seconds", seconds])
    assert exit_info.value.code == 2
    assert capsys.readouterr().err.strip().splitlines()[-1].endswith(
        f"error: --seconds {float(seconds)} must be >= 0")


@pytest.mark.parametrize("size", [(641, 480), (640, 481), (0, 480)])
def test_a_video_size_h264_cannot_encode_is_refused_before_rendering(size, monkeypatch):
    """H.264 in yuv420p stores colour per 2 x 2 pixels: libx264 refuses an odd width or height ('width not
    divisible by 2'), so tools/make_videos.py --size 641 481 rendered every frame and then failed in ffmpeg; a size
    of 0 was reported as a missing OpenGL context ('set MUJOCO_GL=egl')."""
    import mujoco

    from legged_gente.viewer.video import VideoRenderer

    monkeypatch.setattr(mujoco, "Renderer", no_server)  # no OpenGL here: the size is refused before any context
    robot = Path(view_script.__file__).resolve().parents[1] / "resources" / "robots" / "gente_biped" / "gente_biped.xml"
    with pytest.raises(ValueError) as error:
        VideoRenderer(robot, None, width=size[0], height=size[1])
    assert str(error.value) == (f"video size {size[0]} x {size[1]} pixels: width and height must be even and >= 2 "
                                f"(H.264 in yuv420p encodes 2 x 2 pixel blocks); use e.g. 640 x 480.")


FLAT_SPEC = Path(view_script.__file__).resolve().parents[1] / "benchmarks" / "flat" / "specs" / "flat.json"
TERRAIN_MODULE = """
from legged_gente.envs.base.legged_robot_config import LeggedRobotCfg


class SmallTerrain(LeggedRobotCfg.terrain):
    mesh_type, mode, curriculum = "heightfield", "random", False
    num_rows = num_cols = 1
    terrain_length = terrain_width = 2.0
    border_size, resolution = 0.5, 0.1
    terrain_types, terrain_proportions = ["flat"], [1.0]
"""


def view_terrain(argv):
    from legged_gente.utils.args import parse_args

    args = parse_args(view_script.build_arg_parser(), argv)
    return view_script._task_terrain(args, Path(args.source))()


def test_set_terrain_applies_to_a_terrain_cfg_source(tmp_path):
    """`gente-view terrain_cfg.py --set terrain.static_friction=0.3`: the module replaced the terrain section after
    the --set had been applied to the task's, so the view showed the module's friction (1.0) without a word
    (gente-train --terrain applies the --set on top of the module)."""
    module = tmp_path / "terrain_cfg.py"
    module.write_text(TERRAIN_MODULE)
    terrain = view_terrain([str(module), "--task", "gente_biped_flat", "--set", "terrain.static_friction=0.3"])
    assert terrain.material.shape == (2 * 5 + 20, 2 * 5 + 20)  # the module's 2 m tile at 0.1 m, 0.5 m border
    np.testing.assert_allclose(terrain.material.friction, 0.3)


def test_a_set_the_spec_source_overrides_is_refused(capsys, monkeypatch):
    """`gente-view flat.json --set terrain.num_rows=3`: the spec is one tile and set num_rows back to 1 silently."""
    line = one_line_error(capsys, monkeypatch, [str(FLAT_SPEC), "--set", "terrain.num_rows=3"])
    # the rule of gente-train's --terrain, the file named as what it is here: the source
    assert line == (f"gente-view: error: the source {FLAT_SPEC} sets terrain.num_rows to 1; leave out --set "
                    f"terrain.num_rows=3")


@pytest.mark.parametrize("source", ["spec", "rollout"])
def test_terrain_flag_with_a_source_is_refused(source, tmp_path, capsys, monkeypatch):
    """`gente-view flat.json --terrain plane` showed the spec, a rollout its recorded ground: --terrain was
    dropped without a word."""
    path = FLAT_SPEC if source == "spec" else rollout().save(tmp_path / "r.npz")
    line = one_line_error(capsys, monkeypatch, [str(path), "--terrain", "plane"])
    assert line == (f"gente-view: error: --terrain plane and the source {path} both give the terrain; give one "
                    f"(a rollout .npz brings its own)")


def test_set_with_a_rollout_source_is_refused(tmp_path, capsys, monkeypatch):
    """A rollout is replayed as recorded: a --set changed nothing and said nothing."""
    path = rollout().save(tmp_path / "r.npz")
    line = one_line_error(capsys, monkeypatch, [str(path), "--set", "terrain.static_friction=0.3"])
    assert line == (f"gente-view: error: --set terrain.static_friction=0.3: the rollout {path} is replayed as "
                    f"recorded; leave out --set")
