"""The evaluator's per-step accounting and the evaluation figures, worked out by hand (docs/evaluation.md, "Metrics"
and "Figures"). The recorder reads a stand-in for the env's state after each step; one test simulates a single
robot for two steps on the flat benchmark."""

import math
from types import SimpleNamespace

import numpy as np
import pytest
import torch

from legged_gente.evaluation import figures
from legged_gente.evaluation.evaluator import MAX_BASE_SPEED, Recorder, RunResult
from recorder_stand_in import record_step, stand_in_env


# ------------------------------------------------------------------------------------------------ recorder
def test_collisions_count_each_contact_once_from_its_onset_and_only_while_measured():
    """A penalised body's contact force (N) over six steps. Robot 0: 0.5 (below 1 N: no contact), 2 (onset 1),
    3 (the same contact), 0, 5 (onset 2), 5: two collisions. Robot 1: 1.0 exactly (not above 1 N), then 2 (onset
    1); it falls in step 3 with 4 N (the env already reset it: not measured), and its 9 N after that count for
    nothing: one collision."""
    env = stand_in_env(2, vx=0.5, penalized_bodies=(0,))
    forces = [[0.5, 1.0], [2.0, 2.0], [3.0, 4.0], [0.0, 0.0], [5.0, 9.0], [5.0, 9.0]]
    recorder = Recorder(env, settle_s=0.0, trace_robots=torch.tensor([0]))
    for k, (f0, f1) in enumerate(forces, start=1):
        env.contact_forces[:, 0, 2] = torch.tensor([f0, f1])
        record_step(recorder, env, torch.tensor([False, k == 3]))
    assert recorder.collisions.tolist() == [2.0, 1.0]
    assert recorder.fell.tolist() == [False, True]


def test_the_trace_of_a_fall_keeps_the_pose_it_fell_to():
    """Robot 0 walks 0.01 m a step along +x; in step 3 it falls at x = 0.03 m, z = 0.2 m, and the env resets it
    within the step (qpos back at the spawn, the fall's pose in terminal_qpos): the traced pose and position of
    that step are the fall's, so gente-view --traces shows the fall; robot 1's world diverged in step 3 and is
    reset as well: its trace keeps the respawn (its last state may be non-finite)."""
    env = stand_in_env(2, vx=0.5, penalized_bodies=(0,))
    recorder = Recorder(env, settle_s=0.0, trace_robots=torch.tensor([0, 1]))
    for k in range(1, 4):
        env.base_pos[:, 0] = env.sim.qpos[:, 0] = 0.01 * k
        done = torch.tensor([k == 3, k == 3])
        if k == 3:
            env.terminal_qpos[:] = env.sim.qpos
            env.terminal_qpos[:, 2] = 0.2
            env.terminal_qpos[1] = math.nan
            env.base_pos[:] = env.sim.qpos[:] = 0.0
            env.diverged_buf[1] = True
        record_step(recorder, env, done)
    qpos, pos = torch.stack(recorder.trace["qpos"]), torch.stack(recorder.trace["pos"])
    assert qpos[2, 0, 0] == pytest.approx(0.03) and qpos[2, 0, 2] == pytest.approx(0.2)
    assert pos[2, 0].tolist() == pytest.approx([0.03, 0.0])
    assert qpos[2, 1].tolist() == [0.0] * 7 and pos[2, 1].tolist() == [0.0, 0.0]
    assert recorder.fell.tolist() == [True, False] and recorder.diverged.tolist() == [False, True]


def test_a_launched_or_flagged_robot_is_diverged_not_fallen_and_its_step_is_not_measured():
    """Four robots walk 0.01 m a step along +x at 0.5 m/s for two steps. In step 3: robot 0 walks on; robot 1 is
    launched at 30 m/s (> MAX_BASE_SPEED = 24.8 m/s, not done: the env does not check it); robot 2's velocity is
    NaN; robot 3's world the env flagged (diverged_buf, reset as a time-out: done). Robots 1-3 are diverged, none
    fell, and each keeps the 2 steps and 0.02 m it had: the launched step's 0.6 m is not distance."""
    env = stand_in_env(4, vx=0.5, penalized_bodies=(0,))
    recorder = Recorder(env, settle_s=0.0, trace_robots=torch.tensor([0]))
    for k in range(1, 4):
        env.sim.qvel[:, 0] = env.base_lin_vel[:, 0] = 0.5
        env.base_pos[:, 0] += 0.01
        done = torch.zeros(4, dtype=torch.bool)
        if k == 3:
            env.sim.qvel[1, 0], env.base_pos[1, 0] = 30.0, 0.62
            env.sim.qvel[2, 0] = math.nan
            env.diverged_buf = env.time_out_buf = done = torch.tensor([False, False, False, True])
        record_step(recorder, env, done)
    assert 30.0 > MAX_BASE_SPEED
    assert recorder.diverged.tolist() == [False, True, True, True] and not recorder.fell.any()
    assert recorder.alive_steps.tolist() == [3.0, 2.0, 2.0, 2.0]
    assert recorder.distance.tolist() == pytest.approx([0.03, 0.02, 0.02, 0.02], abs=1e-6)
    assert recorder.active.tolist() == [True, False, False, False]


def test_a_fallen_robots_progress_is_over_the_whole_commanded_distance():
    """Two robots commanded 0.5 m/s for ten 0.02 s steps (0.1 m). Robot 0 walks it: progress 1. Robot 1 lunges
    forward at 1 m/s for two steps (0.04 m) and falls in step 3: over the 0.1 m it was told to cover, 0.4, where
    taking only its two live steps' 0.02 m made it 2.0, better than walking."""
    env = stand_in_env(2, vx=0.5)
    recorder = Recorder(env, settle_s=0.0, trace_robots=torch.tensor([0]))
    for k in range(1, 11):
        env.sim.qvel[:, 0] = env.base_lin_vel[:, 0] = torch.tensor([0.5, 1.0])
        record_step(recorder, env, torch.tensor([False, k == 3]))
    progress = (recorder.along_cmd / recorder.cmd_distance).tolist()
    assert recorder.fell.tolist() == [False, True]
    assert progress == pytest.approx([1.0, 0.04 / 0.1])


def test_the_heading_error_is_taken_after_the_settle_time_only():
    """Heading mode, commanded heading 0.5 rad, both robots facing +x (yaw 0): |0.5 - 0| rad = 28.65 deg. settle_s
    = 0.06 s = 3 steps of 0.02 s. Robot 0 is measured for 5 steps: 28.65 deg. Robot 1 falls in step 3, so its last
    measured step (2) lies inside the settle time: no heading error (NaN), as it has no tracking error."""
    env = stand_in_env(2, vx=0.5, penalized_bodies=(0,))
    env.heading_command, env.commands[:, 3] = True, 0.5
    recorder = Recorder(env, settle_s=0.06, trace_robots=torch.tensor([0]))
    for k in range(1, 6):
        record_step(recorder, env, torch.tensor([False, k == 3]))
    assert float(recorder.heading_error[0]) == pytest.approx(math.degrees(0.5), abs=1e-4)
    assert math.isnan(recorder.heading_error[1]) and float(recorder.err_steps[1]) == 0.0


def test_a_run_without_a_task_turns_its_waypoint_paths_back_by_its_own_tile_edge_margin():
    """One robot on the flat 20 m tile, its spawn moved to x = 12 m; the run's margin is 3 m, so its terrain ends
    at x = 17 m. The zigzag needs 4 x 1.8 = 7.2 m: ahead there are 17 - 12 = 5 m, behind 12 - 3 = 9 m, so the
    path runs along -x: x = 12 - 1.8 k = 10.2, 8.4, 6.6, 4.8 m. Built for the default 0.5 m margin instead (7.5 m
    ahead), it ran along +x to 19.2 m, past where the run ends the robot's measured episode."""
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import Evaluation

    evaluation = Evaluation("gente_biped_flat", load_benchmark("flat"), 1, "cpu", 0.04, mode="waypoints")
    evaluation.env.env_origins[:, 0] = 12.0
    result = evaluation.run(lambda obs: torch.zeros(1, evaluation.env.num_actions), settle_s=0.0, progress=False,
                            tile_edge_margin=3.0)
    assert result.traces["waypoints"][0, :, 0].tolist() == pytest.approx([10.2, 8.4, 6.6, 4.8], abs=1e-4)


# ------------------------------------------------------------------------------------------------ figures
def _keep_figure(monkeypatch):
    """Figures drawn by the figures module, kept open instead of written."""
    kept = []
    monkeypatch.setattr(figures, "_save", lambda fig, out: kept.append(fig) or out)
    return kept


def test_figure_c_draws_the_tile_as_its_preview_does_in_metres(tmp_path, monkeypatch):
    """A 20 m x 10 m tile at 0.1 m (200 x 100 cells) with a 1 m block at x >= 15 m, drawn as preview.png draws it:
    +x (forward) up, +y (left) to the left, axes in metres. The picture spans y 10..0 m left to right and x 0..20 m
    bottom to top; the block shows in its top quarter (pixel rows 0-49), at x = 17 m, y = 5 m (row 30, column 50).
    The path and the waypoints are drawn at (y, x)."""
    heights = np.zeros((200, 100), np.float32)
    heights[150:, :] = 1.0
    path = np.array([[2.0, 5.0], [3.0, 5.5], [4.0, 6.0]])
    waypoints = np.array([[3.8, 6.5], [5.6, 3.5]])
    kept = _keep_figure(monkeypatch)
    figures.plot_trajectories(heights, 0.1, {1.0: {"pos": path, "waypoints": waypoints}}, tmp_path / "c.png")
    ax = kept[0].axes[0]
    image = ax.images[0]
    assert image.get_extent() == pytest.approx([10.0, 0.0, 0.0, 20.0])  # left, right, bottom, top
    shown = np.asarray(image.get_array())
    assert shown.shape == (200, 100) and (shown[:50] == 1.0).all() and (shown[50:] == 0.0).all()
    assert shown[30, 50] == 1.0 and shown[170, 50] == 0.0
    assert np.allclose(ax.lines[0].get_xydata(), path[:, ::-1])
    assert np.allclose(ax.lines[-1].get_xydata(), waypoints[:, ::-1])
    assert ax.get_xlabel().startswith("y (m)") and ax.get_ylabel().startswith("x (m)")


def test_figure_d_plots_each_terrains_success_rate_over_its_moving_robots(tmp_path, monkeypatch):
    """Three checkpoints (iterations 0 and 50 in a run's folder, 100 in the folder of its resume), two terrains of
    four robots. At iteration 0 every robot tracks at 1 m/s error: 0 %. Later, terrain 0: one success, one tracking
    0.4 m/s (fails), one told to stand (left out), one diverged (a failure): 1 of 3 = 33.3 %; terrain 1: three
    successes and a fall: 75 %."""
    import legged_gente.evaluation.benchmark as benchmark
    import legged_gente.evaluation.evaluator as evaluator

    run_dir, resumed = tmp_path / "run", tmp_path / "run_resumed"  # --resume continues in a new folder
    for folder, iterations in ((run_dir, (50, 0)), (resumed, (100,))):
        folder.mkdir()
        for iteration in iterations:
            (folder / f"model_{iteration}.pt").write_bytes(b"")

    def metrics(trained):
        n = 8
        m = {"fell": np.zeros(n, bool), "diverged": np.zeros(n, bool), "standing": np.zeros(n, bool),
             "tracking_error": np.full(n, 0.1 if trained else 1.0), "progress": np.full(n, 0.9)}
        m["tracking_error"][1] = 0.4 if trained else 1.0
        m["standing"][2], m["diverged"][3], m["fell"][7] = True, True, True
        return m

    class StubEvaluation:
        def __init__(self, task, items, robots_per_terrain, device, episode_s, mode):
            assert robots_per_terrain == 4

        def run(self, policy, progress=False):
            return RunResult(np.repeat([0, 1], 4), metrics(not policy.endswith("model_0.pt")), {}, "velocity", {})

    monkeypatch.setattr(benchmark, "load_benchmark", lambda name, ids: [SimpleNamespace(id=i) for i in ids])
    monkeypatch.setattr(evaluator, "Evaluation", StubEvaluation)
    monkeypatch.setattr(evaluator, "load_policy", lambda evaluation, checkpoint: checkpoint)
    kept = _keep_figure(monkeypatch)
    figures.success_over_training("gente_biped", [run_dir, resumed], ["a", "b"], tmp_path / "d.png",
                                  robots_per_terrain=4)
    ax = kept[0].axes[0]
    assert ax.get_ylabel() == "success rate (%)" and ax.get_xlabel() == "training iteration"
    a, b = ax.lines
    assert a.get_xdata().tolist() == [0, 50, 100] and b.get_xdata().tolist() == [0, 50, 100]
    assert a.get_ydata().tolist() == pytest.approx([0.0, 100 / 3, 100 / 3])
    assert b.get_ydata().tolist() == pytest.approx([0.0, 75.0, 75.0])


def test_the_figures_command_reports_a_mistake_in_one_line(tmp_path, monkeypatch, capsys):
    """A missing traces file, a terrain id the traces do not hold, an abbreviated flag and --max_checkpoints 0 are
    each one line naming the problem, exit status 2, no traceback; none is accepted."""
    import legged_gente.evaluation.evaluator as evaluator

    traces = tmp_path / "traces.npz"
    cmd = np.zeros((1, 3, 3), np.float32)
    np.savez(traces, ids=np.array(["t0"]), dt=np.array(0.02), active=np.ones((1, 3), bool), cmd=cmd, vel=cmd)
    run_dir = tmp_path / "run"
    run_dir.mkdir()
    (run_dir / "model_0.pt").write_bytes(b"")
    monkeypatch.setattr(evaluator, "Evaluation", lambda *a, **k: SimpleNamespace())  # nothing to simulate
    out = str(tmp_path / "x.png")
    cases = {
        "no_such.npz": ["tracking", str(tmp_path / "no_such.npz"), "--out", out],
        "nope": ["tracking", str(traces), "--ids", "nope", "--out", out],
        "--col": ["reward", str(tmp_path / "a.csv"), "--col", "terrain_level", "--out", out],
        "max_checkpoints": ["training", "--run", str(run_dir), "--benchmark", "flat", "--items", "flat",
                            "--max_checkpoints", "0", "--out", out],
        "model_0.pt is in both": ["training", "--run", str(run_dir), str(run_dir), "--benchmark", "flat", "--items",
                                  "flat", "--out", out],
    }
    for expected, argv in cases.items():
        with pytest.raises(SystemExit) as exit_info:
            figures.main(argv)
        err = capsys.readouterr().err
        assert exit_info.value.code == 2, argv
        assert "Traceback" not in err and len(err.strip().splitlines()) == 1 and expected in err, err
    assert not (tmp_path / "x.png").exists()


def test_the_figures_command_keeps_third_party_output_off_the_console_unless_verbose(monkeypatch, tmp_path):
    """As the gente-* commands: the waypoints and training figures build an env, whose Warp module loads would
    flood the console."""
    calls = []
    monkeypatch.setattr(figures, "quiet_third_party", calls.append)
    run = tmp_path / "seed.csv"
    run.write_text("iteration,mean_reward\n0,1.0\n1,2.0\n")
    figures.main(["reward", str(run), "--out", str(tmp_path / "a.png")])
    figures.main(["reward", str(run), "--out", str(tmp_path / "b.png"), "--verbose"])
    assert calls == [False, True] and (tmp_path / "a.png").is_file()


def test_the_waypoint_figure_takes_the_shipped_policy(monkeypatch, tmp_path):
    """`waypoints --pretrained` draws with the policy shipped for --task, as gente-evaluate --pretrained does: the
    figure asks the evaluator for that policy and no other."""
    import legged_gente.evaluation.evaluator as evaluator

    asked = []

    class Asked(Exception):
        pass

    def load_policy(evaluation, **sources):
        asked.append({k: v for k, v in sources.items() if v})
        raise Asked

    monkeypatch.setattr(evaluator, "Evaluation", lambda *a, **k: SimpleNamespace())  # nothing to simulate
    monkeypatch.setattr(evaluator, "load_policy", load_policy)
    with pytest.raises(Asked):
        figures.main(["waypoints", "--pretrained", "--benchmark", "flat", "--item", "flat",
                      "--out", str(tmp_path / "c.png")])
    assert asked == [{"pretrained": True}]
