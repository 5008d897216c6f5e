"""gente-view's inputs that went wrong: traces of another robot or not traces at all, more robots than worlds,
a live rollout opened at a step not recorded yet, and a live recording read halfway through a step."""

from __future__ import annotations

import json
import socket
import time
from pathlib import Path

import numpy as np
import pytest

from legged_gente.scripts import view as view_script
from legged_gente.terrain.materials import MaterialMap
from legged_gente.viewer.rollout import Rollout, robot_model

FLAT_BENCHMARK = Path(__file__).resolve().parents[1] / "legged_gente" / "benchmarks" / "flat"  # one item: "flat"
BIPED_NQ = 7 + 10  # free joint (x y z, quaternion w x y z) + the biped's 10 joints
QUADRUPED_NQ = 7 + 12  # ... + the quadruped's 12 joints


class Started(Exception):
    """The viser server was asked for: the input got past its checks."""


def no_server(*args, **kwargs):
    raise Started


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def one_line_error(capsys, monkeypatch, argv) -> str:
    import viser

    monkeypatch.setattr(viser, "ViserServer", no_server)
    with pytest.raises(SystemExit) as exit_info:
        view_script.main([*argv, "--headless", "--seconds", "0"])
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and "Traceback" not in err, err
    lines = [line for line in err.splitlines() if line.strip()]
    return lines[-1]


def write_traces(path: Path, nq: int, steps: int = 4) -> Path:
    """gente-evaluate's traces.npz of the flat benchmark: its one item, the first robot's arrays."""
    np.savez_compressed(path, ids=np.array(["flat"]), dt=np.array(0.02), qpos=np.zeros((1, steps, nq), np.float32),
                        cmd=np.zeros((1, steps, 3), np.float32), vel=np.zeros((1, steps, 3), np.float32),
                        pos=np.zeros((1, steps, 2), np.float32), active=np.ones((1, steps), bool))
    return path


def test_traces_of_another_robot_name_the_task(capsys, monkeypatch, tmp_path):
    """traces.npz does not say which task made it: a quadruped's traces under the default biped task failed
    only when a robot was drawn (a traceback from --step, nothing at all from the player's thread)."""
    traces = write_traces(tmp_path / "traces.npz", QUADRUPED_NQ)
    line = one_line_error(capsys, monkeypatch, [str(FLAT_BENCHMARK), "--traces", str(traces), "--task",
                                                "gente_biped_flat", "--step", "0"])
    assert f"holds robots of {QUADRUPED_NQ} qpos values, the --task gente_biped_flat robot {BIPED_NQ}" in line
    assert "pass the --task it was evaluated with" in line


def test_a_rollout_given_as_traces_says_how_to_open_it(capsys, monkeypatch, tmp_path):
    steps = 3
    heights = np.zeros((2, 2), np.float32)
    rollout = Rollout("gente_biped_flat", 0.02, np.zeros((steps, 1, BIPED_NQ), np.float32), np.zeros((steps, 1, 3)),
                      np.zeros((steps, 1, 3)), np.zeros((steps, 1), bool), np.zeros((steps, 1), bool), [],
                      np.zeros((steps, 1, 0, 3), np.float32), np.zeros((steps, 1, 0, 3), np.float32), heights,
                      (0.0, 0.0), 1.0, MaterialMap.rigid((2, 2))).save(tmp_path / "rollout.npz")
    line = one_line_error(capsys, monkeypatch, [str(FLAT_BENCHMARK), "--traces", str(rollout)])
    assert f"is a rollout recorded by gente-view, not gente-evaluate's traces; open it as the source: " \
           f"gente-view {rollout}" in line


def test_a_rollout_of_another_robot_is_one_line(capsys, monkeypatch, tmp_path):
    """A rollout whose qpos does not fit its task's robot (recorded before the MJCF changed, or written by hand):
    a traceback with --step, and without it a player thread that died and left the robots unmoved."""
    steps = 3
    rollout = Rollout("gente_biped_flat", 0.02, np.zeros((steps, 1, QUADRUPED_NQ), np.float32), np.zeros((steps, 1, 3)),
                      np.zeros((steps, 1, 3)), np.zeros((steps, 1), bool), np.zeros((steps, 1), bool), [],
                      np.zeros((steps, 1, 0, 3), np.float32), np.zeros((steps, 1, 0, 3), np.float32),
                      np.zeros((2, 2), np.float32), (0.0, 0.0), 1.0, MaterialMap.rigid((2, 2))).save(tmp_path / "r.npz")
    for extra in ([], ["--step", "0"]):
        line = one_line_error(capsys, monkeypatch, [str(rollout), *extra])
        assert line == (f"gente-view: error: {rollout} holds robots of {QUADRUPED_NQ} qpos values, the robot of its "
                        f"task gente_biped_flat {BIPED_NQ}: it was recorded with another robot model; record it again.")


def test_traces_without_their_keys_are_named(capsys, monkeypatch, tmp_path):
    np.savez(tmp_path / "other.npz", qpos=np.zeros((1, 2, BIPED_NQ)), ids=np.array(["flat"]))
    line = one_line_error(capsys, monkeypatch, [str(FLAT_BENCHMARK), "--traces", str(tmp_path / "other.npz")])
    assert "has no dt, cmd, vel, active: it is not a traces.npz of gente-evaluate" in line


def test_more_robots_than_worlds_is_refused(capsys, monkeypatch):
    """--robots 8 --num_envs 4 recorded 4 robots without a word."""
    line = one_line_error(capsys, monkeypatch, ["--task", "gente_biped_flat", "--play", "--policy", "zero",
                                                "--robots", "8", "--num_envs", "4"])
    assert line == ("gente-view: error: --robots 8 exceeds --num_envs 4: only simulated worlds can be drawn; "
                    "raise --num_envs or lower --robots")


def test_fewer_worlds_than_the_default_robots_draws_them_all():
    from legged_gente.utils.args import parse_args

    args = parse_args(view_script.build_arg_parser(), ["--task", "gente_biped_flat", "--device", "cpu", "--play",
                                                       "--policy", "zero", "--num_envs", "2"])
    _, _, recorder = view_script._make_play(args)
    assert len(recorder.robots) == 2  # the default 4 robots, but only 2 worlds


def test_play_opened_at_a_step_starts(capsys):
    """--play --step N focused the camera on a recording that had no step yet: an IndexError traceback."""
    view_script.main(["--task", "gente_biped_flat", "--play", "--policy", "zero", "--robots", "1", "--num_envs", "1",
                      "--steps", "3", "--step", "2", "--seconds", "0", "--headless", "--port", str(free_port())])
    assert "serving" in capsys.readouterr().out


def test_play_stops_rolling_out_when_the_viewer_stops():
    """Without --record the rollout is only watched: when serving ends (--seconds, Ctrl-C) the policy stops too;
    its thread went on stepping the env after main() returned."""
    import threading

    view_script.main(["--task", "gente_biped_flat", "--play", "--policy", "zero", "--robots", "1", "--num_envs", "1",
                      "--steps", "100000", "--seconds", "0", "--headless", "--port", str(free_port())])
    assert not [t for t in threading.enumerate() if "_run_play" in t.name]


class LiveRecording:
    """What the player reads of a :class:`~legged_gente.viewer.rollout.Recorder` that is filling."""

    dt = 0.02

    def __init__(self):
        self.frames = {k: [] for k in ("qpos", "cmd", "vel", "done", "fell", "forces", "force_points")}
        self.labels, self.robots = [], np.arange(1)

    def add(self, qpos, keys=None) -> None:
        values = {"qpos": qpos[None], "cmd": np.zeros((1, 3)), "vel": np.zeros((1, 3)), "done": np.zeros(1, bool),
                  "fell": np.zeros(1, bool), "forces": np.zeros((1, 0, 3)), "force_points": np.zeros((1, 0, 3))}
        for key in keys or values:
            self.frames[key].append(values[key])


def bare_viewer():
    from legged_gente.viewer.scene import BareTerrain
    from legged_gente.viewer.server import TerrainItem, Viewer

    plane = BareTerrain(np.zeros((2, 2), np.float32), MaterialMap.rigid((2, 2)), 1.0, (0.0, 0.0))
    return Viewer([TerrainItem("plane", lambda: plane)], port=free_port(), shadows=False)


def test_a_live_rollout_paused_at_a_step_draws_it_once_recorded():
    """--play --step 3: the robots stayed at the origin after step 3 was recorded, until the slider was moved."""
    mjm = robot_model("gente_biped_flat")
    live = LiveRecording()
    viewer = bare_viewer()
    try:
        player = viewer.attach_rollout(live, mjm, play=False)
        player.step_gui.value = 3
        player.draw(3)
        player.focus(3)  # nothing recorded yet: nothing to draw or look at
        for t in range(5):  # the robot's base at x = t m
            qpos = mjm.qpos0.copy()
            qpos[0] = t
            live.add(qpos)
        base = int(mjm.jnt_bodyid[0])
        for _ in range(100):  # the player's loop wakes every dt (0.02 s)
            if player.bodies[0, base].position[0] == pytest.approx(3.0):
                break
            time.sleep(0.05)
        np.testing.assert_allclose(player.bodies[0, base].position[:2], (3.0, 0.0), atol=1e-6)
        assert viewer.server.initial_camera.look_at[0] == pytest.approx(3.0)  # the camera on robot 0 at step 3
    finally:
        viewer.stop()


def test_a_step_being_recorded_is_not_read_halfway():
    """Recorder.add appends qpos, cmd, ... forces one after the other: a player reading between them took the
    step whose forces were not there yet (an IndexError in its thread, plot series of unequal lengths)."""
    from legged_gente.viewer.server import _frames

    mjm = robot_model("gente_biped_flat")
    live = LiveRecording()
    live.add(mjm.qpos0.copy())
    live.add(mjm.qpos0.copy(), keys=("qpos", "cmd", "vel"))  # step 1 halfway: no done, fell, forces yet
    frames = _frames(live)
    assert {len(frames[k]) for k in live.frames} == {1}  # the one complete step
    viewer = bare_viewer()
    try:
        player = viewer.attach_rollout(live, mjm, play=False)
        player.draw(1)  # the newest complete step, 0
        player._plot()
        assert [len(series) for series in player.plot_gui.data] == [1] * 7
    finally:
        viewer.stop()


def test_force_arrows_hide_when_unticked_while_paused():
    """Unticking "force arrows" on a paused rollout left the arrows drawn until the slider was moved."""
    mjm = robot_model("gente_biped_flat")
    forces = np.zeros((2, 1, 1, 3), np.float32)
    forces[..., 2] = 200.0  # N: a 2 m arrow
    rollout = Rollout("gente_biped_flat", 0.02, np.tile(mjm.qpos0, (2, 1, 1)), np.zeros((2, 1, 3)), np.zeros((2, 1, 3)),
                      np.zeros((2, 1), bool), np.zeros((2, 1), bool), ["buoyancy:shin"], forces,
                      np.zeros((2, 1, 1, 3), np.float32), np.zeros((2, 2), np.float32), (0.0, 0.0), 1.0,
                      MaterialMap.rigid((2, 2)))
    viewer = bare_viewer()
    try:
        player = viewer.attach_rollout(rollout, mjm, play=False)
        player.draw(1)
        assert player.force_handles["buoyancy"].visible and len(player.force_handles["buoyancy"].points) == 1
        player.forces_gui.value = False
        assert not player.force_handles["buoyancy"].visible
        player.forces_gui.value = True
        assert player.force_handles["buoyancy"].visible
    finally:
        viewer.stop()


class _Terrain:
    height_field, origin_xy, resolution = np.zeros((4, 4), np.float32), (0.0, 0.0), 0.1
    material = MaterialMap.rigid((4, 4))


def _trace(steps_active: int, fell: bool | None) -> dict:
    nq, steps = robot_model("gente_biped").nq, 6
    trace = {"qpos": np.zeros((steps, nq), np.float32), "cmd": np.zeros((steps, 3), np.float32),
             "vel": np.zeros((steps, 3), np.float32), "active": np.arange(steps) < steps_active, "dt": 0.02}
    return trace if fell is None else trace | {"fell": np.array(fell)}


@pytest.mark.parametrize("fell", [True, False])
def test_a_replayed_robot_shows_a_fall_only_when_it_fell(fell):
    """A robot's measured episode also ends at its tile's edge (a success may end there): the replay ends it
    there, and marks a fall only for a robot that fell."""
    trace = _trace(4, fell)
    trace["qpos"][4, 2] = 0.3  # the step it ended in: the pose it fell to (the evaluator records it)
    rollout = view_script._trace_rollout(trace, "gente_biped", _Terrain())
    # a fall is shown to its end: the 4 measured steps and the step that ended it; a robot at its tile's edge stops
    assert rollout.qpos.shape[0] == (5 if fell else 4) and rollout.done[-1, 0] and bool(rollout.fell[-1, 0]) is fell
    assert bool(rollout.qpos[-1, 0, 2] == np.float32(0.3)) is fell
    assert not rollout.done[:-1].any() and not rollout.fell[:-1].any()


def test_a_rollout_with_a_task_refuses_the_task_and_a_spec_s_refusal_names_the_source(capsys, monkeypatch, tmp_path):
    """A rollout .npz names its own task: --task with it was silently ignored. A source spec that sets the field
    a --set changes was refused as if given with --terrain, a flag the user never gave; an upper-case suffix
    (SPEC.JSON) was no spec at all."""
    steps = 2
    rollout = Rollout("gente_biped_flat", 0.02, np.zeros((steps, 1, BIPED_NQ), np.float32), np.zeros((steps, 1, 3)),
                      np.zeros((steps, 1, 3)), np.zeros((steps, 1), bool), np.zeros((steps, 1), bool), [],
                      np.zeros((steps, 1, 0, 3), np.float32), np.zeros((steps, 1, 0, 3), np.float32),
                      np.zeros((2, 2), np.float32), (0.0, 0.0), 1.0, MaterialMap.rigid((2, 2))).save(tmp_path / "r.npz")
    line = one_line_error(capsys, monkeypatch, [str(rollout), "--task", "gente_quadruped"])
    assert line == (f"gente-view: error: --task gente_quadruped: the rollout {rollout} was recorded with task "
                    f"gente_biped_flat, whose robot it replays; leave out --task")
    spec = tmp_path / "SPEC.JSON"
    spec.write_text(json.dumps({"size_x": 2.0, "size_y": 2.0, "resolution": 0.1, "seed": 0, "calls": []}))
    line = one_line_error(capsys, monkeypatch, [str(spec), "--set", "terrain.num_rows=3"])
    assert line == f"gente-view: error: the source {spec} sets terrain.num_rows to 1; leave out --set terrain.num_rows=3"
