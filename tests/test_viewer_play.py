"""gente-view --play: the shipped policies played live on the CPU, and the live recorder followed by the viewer
while it fills (no browser)."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import torch

from legged_gente.scripts import view as view_script
from legged_gente.utils.args import parse_args
from legged_gente.utils.checkpoints import load_checkpoint, policies_root
from legged_gente.viewer.rollout import Rollout

SMALL = ["--set", "terrain.num_rows=1", "--set", "terrain.num_cols=2"]  # two tiles: a quick terrain


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("task", ["gente_biped", "gente_quadruped"])
def test_play_pretrained_uses_the_shipped_actor(task):
    args = parse_args(view_script.build_arg_parser(),
                      ["--task", task, "--device", "cpu", "--play", "--pretrained", "--robots", "2", *SMALL])
    env, policy, recorder = view_script._make_play(args)
    shipped = load_checkpoint(policies_root() / task / "model.pt")["actor_state_dict"]
    state = policy.state_dict()
    assert state and all(torch.equal(value, shipped[key]) for key, value in state.items())
    view_script._run_play(env, policy, recorder, 5, None)
    rollout = recorder.rollout()
    assert (rollout.num_steps, rollout.num_robots, rollout.task) == (5, 2, task)
    # the policy acts: the joints leave the pose they started in, and nothing blows up
    assert np.isfinite(rollout.qpos).all() and np.abs(rollout.qpos[-1, :, 7:] - rollout.qpos[0, :, 7:]).max() > 1e-3


def test_view_cli_plays_pretrained_and_records(tmp_path, capsys):
    out = tmp_path / "rollout.npz"
    view_script.main(["--task", "gente_biped", "--play", "--pretrained", "--robots", "2", "--steps", "4",
                      "--seconds", "0", "--headless", "--port", str(free_port()), "--record", str(out), *SMALL])
    printed = capsys.readouterr().out
    assert "policy shipped for gente_biped" in printed and f"wrote {out}" in printed
    lines = printed.splitlines()  # said before the file is written, never after it (nor once it has finished)
    finishing = [i for i, line in enumerate(lines) if "finishing the rollout" in line]
    assert all(i < lines.index(f"wrote {out}") for i in finishing)
    rollout = Rollout.load(out)
    assert (rollout.num_steps, rollout.num_robots) == (4, 2)


@pytest.mark.parametrize("argv, message", [
    (["--task", "gente_biped", "--pretrained"], "add --play"),
    (["--task", "gente_biped", "--play", "--pretrained", "--policy", "zero"], "leave out --policy zero"),
    (["--task", "gente_biped", "--play", "--pretrained", "--checkpoint", "3"], "--load_run and --checkpoint"),
    (["--task", "gente_quadruped_flat", "--play", "--pretrained"],
     "no policy is shipped for task 'gente_quadruped_flat'"),
])
def test_pretrained_errors(argv, message, capsys):
    with pytest.raises(SystemExit) as exit_info:
        view_script.main([*argv, "--headless", "--seconds", "0", "--port", str(free_port())])
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err.strip().splitlines()[-1]


def test_the_viewer_follows_the_live_recorder():
    """The recorder fills while the policy plays; the player's slider grows with it and, playing, shows the
    newest step: robot r drawn where its newest qpos puts it."""
    from legged_gente.viewer.server import TerrainItem, Viewer

    args = parse_args(view_script.build_arg_parser(), ["--task", "gente_biped", "--device", "cpu", "--play",
                                                       "--policy", "zero", "--robots", "2", *SMALL])
    env, policy, recorder = view_script._make_play(args)
    viewer = Viewer([TerrainItem("play", lambda: env.terrain)], port=free_port(), shadows=False)
    try:
        player = viewer.attach_rollout(recorder, env.mjm, play=True)
        assert player.num_robots == 2
        steps = 6
        play = threading.Thread(target=view_script._run_play, args=(env, policy, recorder, steps, None))
        play.start()
        play.join(timeout=300)
        assert not play.is_alive()
        deadline = threading.Event()
        for _ in range(100):  # the player's loop wakes every dt (0.02 s) to pick up new steps
            if int(player.step_gui.value) == steps - 1 and player.step_gui.max == steps - 1:
                break
            deadline.wait(0.05)
        assert player.step_gui.max == steps - 1 and int(player.step_gui.value) == steps - 1
        player.play_gui.value = False
        player.draw(steps - 1)
        base = int(env.mjm.jnt_bodyid[0])
        newest = np.stack(recorder.frames["qpos"])[-1]
        for r in range(2):
            np.testing.assert_allclose(player.bodies[r, base].position, newest[r, :3], atol=1e-5)
        np.testing.assert_allclose(newest, env.sim.qpos[:2].numpy(), atol=1e-6)  # the last step is the env's now
        assert player.plot_gui is not None and len(player.plot_gui.data[0]) == steps  # the velocity plot grew too
        rollout = recorder.rollout()
        assert rollout.num_steps == steps and rollout.forces.shape[:2] == (steps, 2)
    finally:
        viewer.stop()


def test_a_plane_task_records_the_ground_the_viewer_shows():
    """A task without a heightfield: the recorded rollout's ground is the viewer's plane, 100 m x 100 m of rigid
    ground around the origin (2 x 2 samples 100 m apart from (-50, -50) m)."""
    from legged_gente.viewer.scene import plane_terrain

    args = parse_args(view_script.build_arg_parser(), ["--task", "gente_biped_flat", "--device", "cpu", "--play",
                                                       "--policy", "zero", "--robots", "1"])
    env, policy, recorder = view_script._make_play(args)
    assert env.terrain is None
    view_script._run_play(env, policy, recorder, 1, None)
    rollout, plane = recorder.rollout(), plane_terrain()
    assert (rollout.origin, rollout.resolution) == ((-50.0, -50.0), 100.0) == (plane.origin_xy, plane.resolution)
    np.testing.assert_array_equal(rollout.heights, np.zeros((2, 2)))
    assert not rollout.material.has_water().any() and not rollout.material.has_soil().any()


def test_a_seeded_play_is_repeatable():
    """--seed fixes what the env draws (commands, spawn yaws), so the same seed plays the same rollout."""
    def play(seed: int) -> Rollout:
        argv = ["--task", "gente_biped", "--device", "cpu", "--play", "--pretrained", "--robots", "2",
                "--seed", str(seed), *SMALL]
        args = parse_args(view_script.build_arg_parser(), argv)
        env, policy, recorder = view_script._make_play(args)
        view_script._run_play(env, policy, recorder, 5, None)
        return recorder.rollout()

    first, again, other = play(3), play(3), play(4)
    np.testing.assert_array_equal(first.qpos, again.qpos)
    np.testing.assert_array_equal(first.cmd, again.cmd)
    assert not np.array_equal(first.cmd, other.cmd)  # another seed: other commands


CTRL_C_AFTER_A_LIBRARY = """
import ctypes, faulthandler, signal, sys
from legged_gente.scripts import view

faulthandler.register(signal.SIGUSR1, all_threads=True)  # the test's failure message shows where each thread is
# as started from a terminal: a test run that inherited SIGINT ignored (a background job of a script) passes that on,
# Python then installs no handler (getsignal gives SIG_IGN), and the viewer's take_back rightly keeps it ignored
signal.signal(signal.SIGINT, signal.default_int_handler)

libc_signal = ctypes.CDLL(None).signal
libc_signal.argtypes, libc_signal.restype = [ctypes.c_int, ctypes.c_void_p], ctypes.c_void_p
play = view._run_play


def play_after_a_library(*args):
    libc_signal(signal.SIGINT, 1)  # SIG_IGN behind Python's back, as Triton's LLVM installs its own handler
    print("library loaded", flush=True)
    play(*args)


view._run_play = play_after_a_library
view.main(sys.argv[1:])
"""


def ignores_sigint(pid: int) -> bool:
    """Whether process ``pid`` ignores SIGINT at the C level (Linux's /proc status: SigIgn, a hex mask whose bit
    signo - 1 is set for each ignored signal)."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("SigIgn:"):
            return bool(int(line.split()[1], 16) >> (signal.SIGINT - 1) & 1)
    raise AssertionError(f"/proc/{pid}/status has no SigIgn line")


def test_ctrl_c_still_stops_the_viewer_after_the_play_thread_loaded_a_library(tmp_path):
    """With --set sim.torch_compile=True on a GPU (play turns it off by default) the play thread's first compiled
    step loads Triton, which installs LLVM's SIGINT handler over Python's at the C level: Ctrl-C would end
    gente-view at once, before --record's rollout is written. A stand-in library replaces the handler too (it makes
    SIGINT ignored): the viewer must take SIGINT back, and Ctrl-C then finish the rollout and write it."""
    out = tmp_path / "rollout.npz"
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1]), "PYTHONUNBUFFERED": "1"}
    cmd = [sys.executable, "-c", CTRL_C_AFTER_A_LIBRARY, "--task", "gente_biped_flat", "--play", "--policy", "zero",
           "--robots", "1", "--num_envs", "1", "--steps", "20", "--headless", "--port", str(free_port()),
           "--record", str(out)]
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    seen = []
    for line in proc.stdout:
        seen.append(line)
        if "library loaded" in "".join(seen) and "serving" in "".join(seen):
            break
    # Ctrl-C only once the viewer's loop has taken SIGINT back: while it is ignored the signal is lost. The loop ticks
    # every 0.2 s, but the play thread's rollout can hold it back for seconds; never taken back, the test fails here.
    deadline = time.monotonic() + 60.0
    while ignores_sigint(proc.pid):
        if time.monotonic() > deadline:
            proc.send_signal(signal.SIGUSR1)
            time.sleep(1.0)
            proc.kill()
            rest, _ = proc.communicate()
            pytest.fail("gente-view still ignores SIGINT after 60 s: it did not take it back; its output and "
                        "threads:\n" + "".join(seen) + rest)
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    try:
        rest, _ = proc.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        proc.kill()
        rest, _ = proc.communicate()
    printed = "".join(seen) + rest
    assert proc.returncode == 0, printed
    assert "finishing the rollout to record it" in printed and f"wrote {out}" in printed, printed
    assert Rollout.load(out).num_steps == 20
