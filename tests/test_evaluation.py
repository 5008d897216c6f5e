"""Waypoint logic on tensors; gente-evaluate on 2 terrains with a few robots writes well-formed reports."""

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
import torch

from legged_gente.evaluation.evaluator import grid_shape
from legged_gente.evaluation.tasks import WaypointTask, zigzag_waypoints

BENCHMARK = Path(__file__).resolve().parents[1] / "legged_gente" / "benchmarks" / "gente100"
ITEMS = ["text_02_wide_river_strong_current", "image_05_sketch_blocks"]


def test_waypoints_advance_in_order_and_finish():
    points = torch.tensor([[[1.0, 0.0], [2.0, 0.0], [2.0, 1.0]]] * 2)
    task = WaypointTask(points, reach_distance=0.3, speed=0.5)
    active = torch.tensor([True, True])
    pos = torch.tensor([[0.0, 0.0], [0.0, 0.0]])
    task.update(pos, active)
    assert task.index.tolist() == [0, 0]
    cmd = task.commands(pos, torch.zeros(2, 4))
    assert torch.allclose(cmd[:, 0], torch.tensor(0.5)) and torch.allclose(cmd[:, 3], torch.tensor(0.0))
    pos = torch.tensor([[0.8, 0.1], [0.0, 0.0]])  # robot 0 reaches waypoint 0; robot 1 does not move
    task.update(pos, active)
    assert task.index.tolist() == [1, 0]
    pos = torch.tensor([[2.0, 0.0], [0.0, 0.0]])
    task.update(pos, active)
    cmd = task.commands(pos, torch.zeros(2, 4))
    assert task.index.tolist() == [2, 0]
    assert cmd[0, 3].item() == pytest.approx(math.pi / 2)  # heading turns to the next waypoint (+y)
    task.update(torch.tensor([[2.0, 0.9], [0.0, 0.0]]), active)
    assert task.finished.tolist() == [True, False]
    cmd = task.commands(torch.tensor([[2.0, 0.9], [0.0, 0.0]]), torch.full((2, 4), 0.7))
    assert cmd[0, 0].item() == 0.0 and cmd[0, 3].item() == pytest.approx(0.7)  # finished: stand, keep heading


def test_large_reach_distance_passes_several_waypoints_and_inactive_robots_stay():
    points = torch.tensor([[[1.0, 0.0], [2.0, 0.0], [3.0, 0.0]]] * 2)
    task = WaypointTask(points, reach_distance=20.0, speed=0.5)
    task.update(torch.zeros(2, 2), torch.tensor([True, False]))
    assert task.finished.tolist() == [True, False] and task.index.tolist() == [3, 0]


def test_zigzag_waypoints_alternate_sides():
    pts = zigzag_waypoints(torch.tensor([[10.0, 10.0]]), 4, 2.0, 1.5, seed=1)
    assert pts.shape == (1, 4, 2)
    assert torch.allclose(pts[0, :, 0], torch.tensor([12.0, 14.0, 16.0, 18.0]))
    offsets = pts[0, :, 1] - 10.0
    assert torch.allclose(offsets.abs(), torch.tensor(1.5)) and (offsets[:-1] * offsets[1:] < 0).all()


def test_zigzag_waypoints_turn_back_where_the_path_would_leave_its_terrain():
    """Tiles span x in [0, 20] (within a 0.5 m margin: [0.5, 19.5]); 4 waypoints 1.8 m apart need 7.2 m. From x = 10
    the path runs +x to 17.2; from x = 15 (4.5 m of room ahead, 14.5 behind) it runs -x to 7.8; on a 4 m tile, from
    x = 1.5 (room for neither, 2 m ahead, 1 m behind) it keeps +x."""
    starts = torch.tensor([[10.0, 3.0], [15.0, 3.0], [1.5, 3.0]])
    x_range = torch.tensor([[0.5, 19.5], [0.5, 19.5], [0.5, 3.5]])
    pts = zigzag_waypoints(starts, 4, 1.8, 1.5, seed=1, x_range=x_range)
    assert torch.allclose(pts[:, -1, 0], torch.tensor([10.0 + 7.2, 15.0 - 7.2, 1.5 + 7.2]))
    assert torch.allclose(pts[1, :, 0], torch.tensor([13.2, 11.4, 9.6, 7.8]))
    assert torch.allclose((pts[:, :, 1] - 3.0).abs(), torch.tensor(1.5))


def test_the_waypoint_episode_gives_half_again_the_time_to_walk_the_zigzag():
    """4 waypoints 1.8 m apart, 1.5 m to either side: legs of sqrt(1.8^2 + 1.5^2) = 2.343 m, then 3 of
    sqrt(1.8^2 + 3^2) = 3.499 m: 12.839 m, 21.40 s at 0.6 m/s, 32.10 s with half again."""
    from legged_gente.evaluation.tasks import waypoint_episode_s, zigzag_length

    assert zigzag_length() == pytest.approx(2.3431 + 3 * 3.4986, abs=1e-3)
    assert waypoint_episode_s(0.6) == pytest.approx(1.5 * 12.8388 / 0.6, abs=1e-2)
    with pytest.raises(ValueError, match="speed must be > 0 m/s"):
        waypoint_episode_s(0.0)


def test_grid_shape():
    assert grid_shape(100) == (10, 10) and grid_shape(2) == (1, 2) and grid_shape(7) == (1, 7)
    assert grid_shape(50) == (5, 10)


@pytest.mark.parametrize("mode", ["velocity", "waypoints"])
def test_evaluate_writes_reports(tmp_path, mode):
    from legged_gente.scripts.evaluate import main

    out = tmp_path / mode
    main(["--task", "gente_biped", "--baseline", "random", "--benchmark", str(BENCHMARK), "--items", *ITEMS,
          "--robots_per_terrain", "2", "--episode_s", "0.6", "--settle_s", "0.2", "--mode", mode,
          "--device", "cpu", "--out", str(out), "--no_progress"])
    report = json.loads((out / "report.json").read_text())
    assert [t["id"] for t in report["terrains"]] == ITEMS
    standing = report["groups"].get("stand_still", {"robots": 0})["robots"]
    assert report["overall"]["robots"] + standing == 4 and report["overall"]["terrains"] == 2
    assert report["meta"]["task_mode"] == mode
    assert set(report["groups"]) >= {"text", "image", "water", "obstacles"}
    assert report["terrains"][1]["categories"] == ["obstacles"]  # the sketch's raised blocks
    for row in report["terrains"] + [report["overall"]]:
        assert 0.0 <= row["success_rate"] <= 1.0 and 0 <= row["falls"] <= row["robots"]
        assert row["distance"] >= row["displacement"] - 1e-6 >= 0.0
        assert row["energy_per_m"] is None or row["energy_per_m"] > 0.0
        if mode == "velocity":
            assert row["tracking_error"] >= 0.0
    with open(out / "report.csv") as f:
        rows = list(csv.DictReader(f))
    assert [r["row"] for r in rows].count("terrain") == 2 and rows[-1]["row"] == "overall"
    assert float(rows[-1]["success_rate"]) == pytest.approx(report["overall"]["success_rate"], abs=1e-3)
    traces = np.load(out / "traces.npz")
    steps = round(0.6 / 0.02)
    assert traces["pos"].shape == (2, steps, 2) and traces["cmd"].shape == (2, steps, 3)
    np.testing.assert_allclose(traces["qpos"][..., :2], traces["pos"], atol=1e-5)  # gente-view --traces replays it
    assert list(traces["ids"]) == ITEMS
    assert traces["fell"].dtype == bool and traces["fell"].shape == (2,)  # the traced robot of each terrain
    assert all(fell <= row["falls"] for fell, row in zip(traces["fell"], report["terrains"]))
    assert traces["heading"].shape == (2, steps) and traces["world_vel"].shape == (2, steps, 3)
    # the world velocity is the one progress integrates: its xy moves the base as pos records (within a step's
    # change of velocity over 0.02 s)
    moved = np.diff(traces["pos"], axis=1)
    live = traces["active"][:, 1:].astype(bool) & traces["active"][:, :-1].astype(bool)
    np.testing.assert_allclose(moved[live], traces["world_vel"][:, 1:, :2][live] * 0.02, atol=0.01)
    if mode == "waypoints":
        assert traces["waypoints"].shape == (2, 4, 2)


def test_figures(tmp_path):
    from legged_gente.evaluation import figures

    for seed, offset in enumerate((0.0, 1.0, 2.0)):
        rows = "\n".join(f"{i},{i * 0.1 + offset}" for i in range(20))
        (tmp_path / f"s{seed}.csv").write_text("iteration,mean_reward\n" + rows + "\n")
    its, values = figures.read_curve(tmp_path / "s1.csv")
    assert its[-1] == 19 and values[0] == pytest.approx(1.0)
    assert figures.plot_reward_seeds(sorted(tmp_path.glob("s*.csv")), tmp_path / "a.png").stat().st_size > 0
    steps = 30
    np.savez(tmp_path / "traces.npz", ids=np.array(["t0", "t1"]), dt=np.array(0.02),
             cmd=np.zeros((2, steps, 3)), vel=np.ones((2, steps, 3)), active=np.ones((2, steps), bool))
    assert figures.plot_tracking(tmp_path / "traces.npz", tmp_path / "b.png").stat().st_size > 0
    with pytest.raises(KeyError, match="nope"):
        figures.plot_tracking(tmp_path / "traces.npz", tmp_path / "b.png", ids=["nope"])
    run = {"pos": np.array([[10.0, 10.0], [12.0, 11.0]]), "waypoints": np.array([[12.0, 11.5]]), "finished": True}
    path = figures.plot_trajectories(np.zeros((200, 200)), 0.1, {0.1: run, 1.0: run}, tmp_path / "c.png")
    assert path.stat().st_size > 0


def test_the_figures_tool_says_the_file_it_wrote_and_names_a_bad_traces_file(tmp_path, capsys):
    """--out without a suffix writes (and says) name.png; a folder as --out, a traces.npz cut short, a CSV
    renamed .npz (numpy's advice would be to unpickle it) and another archive are each one line naming the file."""
    from legged_gente.evaluation import figures

    steps = 30
    traces = tmp_path / "traces.npz"
    np.savez(traces, ids=np.array(["t0", "t1"]), dt=np.array(0.02), cmd=np.zeros((2, steps, 3)),
             vel=np.ones((2, steps, 3)), active=np.ones((2, steps), bool))
    figures.main(["tracking", str(traces), "--out", str(tmp_path / "fig")])
    assert capsys.readouterr().out.strip() == f"wrote {tmp_path / 'fig.png'}" and (tmp_path / "fig.png").is_file()
    (tmp_path / "cut.npz").write_bytes(traces.read_bytes()[:200])
    (tmp_path / "csv.npz").write_text("row,name\nterrain,t0\n")
    np.savez(tmp_path / "other.npz", qpos=np.zeros(3))
    cases = [(str(traces), str(tmp_path), f"--out {tmp_path} is a folder; give the PNG's path"),
             (str(tmp_path / "cut.npz"), str(tmp_path / "x.png"), "cut.npz is not a readable NumPy .npz archive"),
             (str(tmp_path / "csv.npz"), str(tmp_path / "x.png"), "csv.npz is not a readable NumPy .npz archive"),
             (str(tmp_path / "other.npz"), str(tmp_path / "x.png"), "other.npz is not a traces.npz of gente-evaluate")]
    for source, out, message in cases:
        with pytest.raises(SystemExit) as info:
            figures.main(["tracking", source, "--out", out])
        err = capsys.readouterr().err.strip()
        assert info.value.code == 2 and len(err.splitlines()) == 1 and message in err, err
        assert "pickle" not in err
    with pytest.raises(SystemExit):
        figures.main(["tracking", str(traces), "--ids", "nope", "--out", str(tmp_path / "y.png")])
    err = capsys.readouterr().err
    assert "['nope'] not in" in err and "it has ['t0', 't1']" in err and "np.str_" not in err, err


def test_one_evaluation_runs_several_times():
    """The waypoint figure reruns one Evaluation per reach distance: the second run must start cleanly."""
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import Evaluation

    evaluation = Evaluation("gente_biped", load_benchmark(str(BENCHMARK), ITEMS[:1]), 1, "cpu", 0.2, "waypoints")

    def still(obs):
        return torch.zeros(evaluation.env.num_envs, evaluation.env.num_actions)

    for d in (0.1, 20.0):
        result = evaluation.run(still, evaluation.make_task(reach_distance=d), settle_s=0.1, progress=False)
        assert result.traces["pos"].shape[1] == round(0.2 / 0.02)
    # the episode is 0.2 s, 10 steps of 0.02 s: settling through it leaves nothing to measure, and 0.195 s rounds
    # to the 10th step
    for settle_s in (0.2, 1.0, 0.195):
        with pytest.raises(ValueError, match=f"settle_s {settle_s} s leaves nothing"):
            evaluation.run(still, progress=False, settle_s=settle_s)
    with pytest.raises(ValueError, match="settle_s must be >= 0 s, got -0.1"):
        evaluation.run(still, progress=False, settle_s=-0.1)
    with pytest.raises(ValueError, match="speed must be > 0"):
        evaluation.make_task(speed=-1.0)


def test_success_needs_progress_and_tight_tracking():
    """The velocity task's rule, case by case: moving commands need tracking < 0.25 m/s and >= 70 % of the
    commanded distance; stand-still commands need only to stand (tracking < 0.25 m/s) without falling."""
    from legged_gente.evaluation.report import success

    #            follows  too slow  stands   error 0.3  fell    stands(cmd 0)  drifts(cmd 0)
    metrics = {
        "fell": np.array([False, False, False, False, True, False, False]),
        "tracking_error": np.array([0.05, 0.20, 0.50, 0.30, 0.05, 0.02, 0.40]),
        "progress": np.array([0.98, 0.60, 0.00, 0.90, 0.98, np.nan, np.nan]),
        "standing": np.array([False, False, False, False, False, True, True]),
    }
    assert success(metrics, "velocity").tolist() == [True, False, False, False, False, True, False]


def test_velocity_commands_are_fast_enough_or_standing():
    from types import SimpleNamespace

    from legged_gente.evaluation.tasks import VelocityTask

    ranges = SimpleNamespace(lin_vel_x=[-1.0, 1.0], lin_vel_y=[-0.5, 0.5], ang_vel_yaw=[-1.0, 1.0],
                             heading=[-math.pi, math.pi])
    task = VelocityTask(2000, ranges, heading_command=False, device="cpu", seed=3, min_speed=0.3, stand_fraction=0.1)
    cmd = task.commands(torch.zeros(2000, 2), torch.zeros(2000, 4))
    speed = torch.linalg.norm(cmd[:, :2], dim=1)
    assert bool((speed[~task.standing] >= 0.3).all()) and bool((cmd[task.standing, :3] == 0).all())
    assert abs(task.standing.float().mean().item() - 0.1) < 0.03  # binomial(2000, 0.1): sd 0.0067
    assert cmd[~task.standing, 0].abs().max() <= 1.0 and cmd[~task.standing, 1].abs().max() <= 0.5
    narrow = SimpleNamespace(lin_vel_x=[0.0, 0.2], lin_vel_y=[-0.1, 0.1], ang_vel_yaw=[0, 0], heading=[0, 0])
    with pytest.raises(ValueError, match="min_speed 0.3"):
        VelocityTask(4, narrow, heading_command=False, device="cpu", min_speed=0.3)


def test_a_standing_policy_scores_zero(tmp_path):
    """A policy that holds the default pose (zero actions) must not pass a moving command: it covers none of the
    commanded distance, and its tracking error is the command's speed (>= 0.3 m/s > 0.25 m/s)."""
    from legged_gente.scripts.evaluate import main

    main(["--task", "gente_biped", "--baseline", "zero", "--benchmark", str(BENCHMARK), "--items", ITEMS[1],
          "--robots_per_terrain", "4", "--episode_s", "1.0", "--settle_s", "0.2", "--stand_fraction", "0",
          "--device", "cpu", "--out", str(tmp_path), "--no_progress"])
    overall = json.loads((tmp_path / "report.json").read_text())["overall"]
    assert overall["robots"] == 4 and overall["success_rate"] == 0.0
    assert overall["tracking_error"] > 0.25


def test_the_evaluation_steps_the_tasks_own_env_as_in_training():
    """No hooks inside the step and no graph or compile switch: the evaluation reads what a step leaves, so the
    step may run as one CUDA graph with its torch logic compiled (cfg.sim's defaults) on a GPU."""
    from legged_gente.envs.task_registry import task_registry
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import Evaluation

    evaluation = Evaluation("gente_biped", load_benchmark(str(BENCHMARK), ITEMS[:1]), 1, "cpu", 0.1)
    default, _ = task_registry.get_cfgs("gente_biped")
    assert evaluation.env_cfg.sim.cuda_graph == default.sim.cuda_graph == "env_step"
    assert evaluation.env_cfg.sim.torch_compile is default.sim.torch_compile is True
    env_class = task_registry.tasks["gente_biped"][0]
    assert type(evaluation.env) is env_class  # no subclass: nothing of the evaluation runs inside the step


def test_set_commands_reaches_the_next_observation_and_stand_still_does_not_turn():
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import Evaluation

    env = Evaluation("gente_biped", load_benchmark(str(BENCHMARK), ITEMS[:1]), 2, "cpu", 0.1).env
    env.reset()
    heading = torch.tensor([2.0, 2.0])  # rad; both robots face about 0 rad after the reset (yaw randomised)
    commands = torch.stack([torch.tensor([0.6, 0.0]), torch.zeros(2), torch.zeros(2), heading], 1)
    obs = env.set_commands(commands, still=torch.tensor([False, True]))
    names = env.observation_names["policy"]
    vx = obs["policy"][:, names.index("commands[0]")]
    yaw_rate = obs["policy"][:, names.index("commands[2]")]
    assert vx.tolist() == pytest.approx([0.6 * 2.0, 0.0])  # the commands term's scale is 2 for vx
    assert yaw_rate[0].abs() > 0 and yaw_rate[1] == 0.0  # robot 1 stands still: no turn to its heading
    with pytest.raises(ValueError, match="vx, vy, yaw rate, heading"):
        env.set_commands(torch.zeros(2, 3))


def test_diverged_robots_are_failures_counted_apart_and_enter_no_mean(tmp_path):
    """Two of four robots blow up at step 5: robot 2 is launched at 300 m/s (below sim.max_qvel, so the env
    does not flag it; no robot base moves faster than MAX_BASE_SPEED), robot 3 gets a NaN joint angle (the env
    flags and resets it). Both count as diverged and failed, neither as a fall, and the report's means are
    those of robots 0 and 1 alone."""
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import MAX_BASE_SPEED, Evaluation
    from legged_gente.evaluation.report import build_report

    items = load_benchmark(str(BENCHMARK), ITEMS[1:])
    evaluation = Evaluation("gente_biped", items, 4, "cpu", 0.4)
    env = evaluation.env
    assert 300.0 > MAX_BASE_SPEED and 300.0 < env.max_qvel
    calls = []

    def policy(obs):
        calls.append(1)
        if len(calls) == 5:
            env.sim.qvel[2, 0] = 300.0  # m/s, world x
            env.sim.qpos[3, 7] = math.nan
        return torch.zeros(env.num_envs, env.num_actions)

    task = evaluation.make_task(stand_fraction=0.0)
    result = evaluation.run(policy, task, settle_s=0.04, progress=False)
    m = result.metrics
    assert m["diverged"].tolist() == [False, False, True, True]
    assert not m["fell"][2:].any()
    report = build_report(result, items)
    overall, terrain = report["overall"], report["terrains"][0]
    assert overall["diverged"] == terrain["diverged"] == 2 and overall["robots"] == 4
    assert overall["success_rate"] <= 0.5  # the diverged half fails
    healthy = slice(0, 2)
    assert overall["tracking_error"] == pytest.approx(float(np.mean(m["tracking_error"][healthy])))
    assert overall["distance"] == pytest.approx(float(np.mean(m["distance"][healthy])))
    assert overall["progress"] == pytest.approx(float(np.mean(m["progress"][healthy])))
    energy_per_m = float(m["energy"][healthy].sum() / m["distance"][healthy].sum())
    assert overall["energy_per_m"] == pytest.approx(energy_per_m)
    # a zero-action biped stands: well under a metre in 0.4 s, and its tracking error is about its command
    assert overall["distance"] < 1.0 and overall["tracking_error"] < 1.5


def test_the_evaluation_gives_the_same_metrics_through_the_compiled_step():
    """The env's step with its torch logic compiled (cfg.sim.torch_compile's torch.compile, here on the CPU with
    eager random numbers), run twice, gives the per-robot metrics of the plain step: the evaluation reads only
    what a step leaves."""
    from unittest.mock import patch

    import torch._inductor.config as inductor_config

    from legged_gente.envs.base.step_runner import StepRunner
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import Evaluation

    evaluation = Evaluation("gente_biped", load_benchmark(str(BENCHMARK), ITEMS[1:]), 2, "cpu", 0.2)
    env = evaluation.env

    def policy(obs):
        return 0.3 * torch.tanh(obs["policy"][:, :env.num_actions])  # depends on what the env observes

    plain = evaluation.run(policy, settle_s=0.04, progress=False).metrics
    env._runner = StepRunner(env, compile=True)
    with patch.object(inductor_config, "fallback_random", True):
        runs = [evaluation.run(policy, settle_s=0.04, progress=False).metrics for _ in range(2)]
    for metrics in runs:
        for name in ("tracking_error", "progress", "distance", "energy", "time_s"):
            np.testing.assert_allclose(metrics[name], plain[name], rtol=1e-4, atol=1e-5, err_msg=name)
        for name in ("fell", "diverged"):
            assert (metrics[name] == plain[name]).all()


def _still_env(yaw: list[float], heading: list[float], standing: list[bool], heading_mode: bool = True):
    """The state the recorder reads after a step, for robots facing ``yaw`` (rad) and commanded vx = 0.6 m/s and
    ``heading``; at rest until a test sets ``sim.qvel`` (world frame): nothing simulated."""
    from types import MethodType, SimpleNamespace

    from legged_gente.envs.base.legged_robot import LeggedRobot

    n = len(yaw)
    commands = torch.zeros(n, 4)
    commands[:, 0], commands[:, 3] = 0.6, torch.tensor(heading)
    zeros = torch.zeros(n, dtype=torch.bool)
    env = SimpleNamespace(
        num_envs=n, device="cpu", dt=0.02, commands=commands, heading_command=heading_mode,
        standing_still=torch.tensor(standing), base_pos=torch.zeros(n, 3), base_lin_vel=torch.zeros(n, 3),
        base_ang_vel=torch.zeros(n, 3), sim=SimpleNamespace(qvel=torch.zeros(n, 6), qpos=torch.zeros(n, 7)),
        diverged_buf=zeros, time_out_buf=zeros, torques=torch.zeros(n, 2), dof_vel=torch.zeros(n, 2),
        penalized_bodies=torch.zeros(0, dtype=torch.long), contact_forces=torch.zeros(n, 1, 3),
        reset_buf=zeros, terminal_qpos=torch.zeros(n, 7), terminal_qvel=torch.zeros(n, 6),
        terminal_commands=torch.zeros(n, 4))
    env.episode_end = MethodType(LeggedRobot.episode_end, env)  # the env's own rule for what a step's row shows
    _face(env, yaw)
    return env


def _face(env, yaw: list[float]) -> None:
    half = torch.tensor(yaw) / 2
    env.base_quat = torch.stack([half.cos(), torch.zeros(len(yaw)), torch.zeros(len(yaw)), half.sin()], 1)  # wxyz


def test_heading_error_is_the_wrapped_angle_to_the_commanded_heading():
    """The base-frame metrics cannot see a robot that walks but faces away from its commanded heading; the heading
    error (degrees, the last measured step) can. Values by hand: |0.5 - 0| rad = 28.65 deg; 3.0 and -3.0 rad are
    2 pi - 6 = 0.2832 rad = 16.23 deg apart; a stand-still robot and the yaw-rate mode have none."""
    from legged_gente.evaluation.evaluator import Recorder

    env = _still_env(yaw=[0.0, -3.0, 1.0, 0.2], heading=[0.5, 3.0, 1.0, 2.0], standing=[False, False, False, True])
    recorder = Recorder(env, settle_s=0.0, trace_robots=torch.tensor([0]))
    recorder.record(env, torch.zeros(4, dtype=torch.bool))
    expected = [28.648, 16.226, 0.0]
    assert recorder.heading_error[:3].tolist() == pytest.approx(expected, abs=1e-3)
    assert math.isnan(recorder.heading_error[3])
    env = _still_env(yaw=[0.0], heading=[0.5], standing=[False], heading_mode=False)
    recorder = Recorder(env, settle_s=0.0, trace_robots=torch.tensor([0]))
    recorder.record(env, torch.zeros(1, dtype=torch.bool))
    assert math.isnan(recorder.heading_error[0])


def test_progress_is_measured_along_the_path_a_perfect_follower_would_take():
    """Walking the commanded speed in the wrong direction is not progress. Robots spawned facing +x, commanded
    vx = 0.6 m/s; each then moves at 0.6 m/s in the world: (0) along +x, heading 0: progress 1; (1) along +y with
    its base turned to +y (the base-frame velocity matches the command), heading 0: progress 0 (the env commands
    it back, but the reference starts at the heading and stays); (2) heading 0.5 rad, still facing +x, commanded
    0.5 * 0.5 = 0.25 rad/s (heading_stiffness 0.5 /s): the reference turns 0.005 rad a step and stops at 0.5
    after 100 steps; moving along +x it scores the mean of cos(reference yaw) over 150 steps."""
    from legged_gente.evaluation.evaluator import Recorder

    steps = 150
    env = _still_env(yaw=[0.0, 0.0, 0.0], heading=[0.0, 0.0, 0.5], standing=[False, False, False])
    env.commands[:, 2] = torch.tensor([0.0, 0.5 * -math.pi / 2, 0.25])  # the env's heading controller
    recorder = Recorder(env, settle_s=0.0, trace_robots=torch.tensor([0]))
    _face(env, [0.0, math.pi / 2, 0.0])
    env.sim.qvel[:, :2] = torch.tensor([[0.6, 0.0], [0.0, 0.6], [0.6, 0.0]])
    env.base_lin_vel[:, 0] = 0.6  # in its own frame every robot walks as commanded
    for _ in range(steps):
        recorder.record(env, torch.zeros(3, dtype=torch.bool))
    progress = recorder.along_cmd / recorder.cmd_distance
    reference = [min(0.005 * k, 0.5) for k in range(1, steps + 1)]
    expected = [1.0, 0.0, sum(math.cos(y) for y in reference) / steps]
    assert progress.tolist() == pytest.approx(expected, abs=1e-4)
    assert float(recorder.reference_yaw[2]) == pytest.approx(0.5, abs=1e-6)
    assert expected[2] < 0.97  # the reference turned: the check can fail


def test_the_reference_yaw_follows_the_commanded_yaw_rate_without_a_heading():
    """Yaw-rate mode: the reference turns at the commanded rate, 1 rad/s for 50 steps of 0.02 s = 1 rad; a robot
    moving at 0.6 m/s along (cos 1, sin 1) at the end is on the path."""
    from legged_gente.evaluation.evaluator import Recorder

    env = _still_env(yaw=[0.0], heading=[0.0], standing=[False], heading_mode=False)
    env.commands[:, 2] = 1.0
    recorder = Recorder(env, settle_s=0.0, trace_robots=torch.tensor([0]))
    for _ in range(50):
        recorder.record(env, torch.zeros(1, dtype=torch.bool))
    assert float(recorder.reference_yaw[0]) == pytest.approx(1.0, abs=1e-5)
    env.sim.qvel[:, :2] = 0.6 * torch.tensor([[math.cos(1.0), math.sin(1.0)]])
    before = float(recorder.along_cmd[0])
    recorder.record(env, torch.zeros(1, dtype=torch.bool))  # the reference turns to 1.02 rad in this step
    assert float(recorder.along_cmd[0]) - before == pytest.approx(0.6 * math.cos(0.02) * 0.02, abs=1e-6)


def test_an_evaluation_without_moving_robots_says_so(tmp_path, capsys):
    """All robots told to stand: no success rate over zero robots without a word on why."""
    from legged_gente.scripts.evaluate import main

    main(["--task", "gente_biped_flat", "--baseline", "zero", "--benchmark", "flat", "--robots_per_terrain", "2",
          "--stand_fraction", "1", "--episode_s", "0.2", "--settle_s", "0.1", "--device", "cpu", "--out",
          str(tmp_path), "--no_progress"])
    out = capsys.readouterr().out
    assert "no robot had a moving command (all were told to stand still" in out
    assert "success - over 0 robots" in out and "nan" not in out, out


def test_a_robot_at_its_tiles_edge_ends_its_measured_episode_there_with_a_tile_edge_margin():
    """Robots 2 and 3 stand on the second of two 20 m tiles (a 1 x 2 grid: y from 20 to 40 m). At step 3 robot 3's
    base is put 0.3 m from the tile's edge at y = 20; with a 0.5 m margin its measured episode ends at that
    step (left_tile, not a fall): it is measured for 3 steps, robot 2 for all 10. Without a margin it goes on."""
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import Evaluation

    items = load_benchmark(str(BENCHMARK), ITEMS)
    evaluation = Evaluation("gente_biped", items, 2, "cpu", 0.2)
    env = evaluation.env
    assert evaluation.tile_bounds(0.5)[2:].tolist() == [[0.5, 20.5, 19.5, 39.5]] * 2
    with pytest.raises(ValueError, match="tile_edge_margin"):
        evaluation.tile_bounds(10.0)

    def run(margin):
        calls = []

        def policy(obs):
            calls.append(1)
            if len(calls) == 3:
                env.sim.qpos[3, 1] = 20.3  # m, world y: 0.3 m inside tile 1's edge at y = 20
            return torch.zeros(env.num_envs, env.num_actions)

        task = evaluation.make_task(stand_fraction=0.0)
        return evaluation.run(policy, task, settle_s=0.04, progress=False, tile_edge_margin=margin).metrics

    m = run(0.5)
    assert m["left_tile"].tolist() == [False, False, False, True] and not m["fell"].any()
    assert m["time_s"][3] == pytest.approx(3 * env.dt) and m["time_s"][2] == pytest.approx(10 * env.dt)
    m = run(None)
    assert not m["left_tile"].any() and m["time_s"][3] == pytest.approx(10 * env.dt)


def test_an_evaluation_meets_the_same_soil_and_water_each_run_and_for_its_seed():
    """On a mud item (the robots stand in soil, whose per-env draws decide their sinkage): one evaluation run
    twice, and a second evaluation with the same seed, give the same trajectories and energy; the force fields'
    seed follows the evaluation's seed."""
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import Evaluation

    items = load_benchmark(str(BENCHMARK), ["text_29_mud_field_deep_puddles"])
    first = Evaluation("gente_biped", items, 2, "cpu", 0.4, seed=0)
    assert first.env.forces is not None

    def run(evaluation):
        return evaluation.run(lambda obs: torch.zeros(2, evaluation.env.num_actions), settle_s=0.04, progress=False)

    a, b = run(first), run(first)
    np.testing.assert_array_equal(a.traces["qpos"], b.traces["qpos"])
    np.testing.assert_array_equal(a.metrics["energy"], b.metrics["energy"])
    second = Evaluation("gente_biped", items, 2, "cpu", 0.4, seed=0)
    assert second.env.forces.seed == first.env.forces.seed
    np.testing.assert_array_equal(run(second).traces["qpos"], a.traces["qpos"])


def test_energy_counts_the_torque_a_robot_applied_whatever_other_robots_do():
    """env.torques after a step are the actuator forces of its last substep in every world: the forward after
    another robot's reset (which recomputes every world's) leaves those of the worlds not reset as they were."""
    from legged_gente.envs.task_registry import task_registry

    def torques_after(reset_other: bool):
        torch.manual_seed(0)
        env_cfg, _ = task_registry.get_cfgs("gente_biped_flat")
        env_cfg.env.num_envs = 2
        env_cfg.domain_rand.push_robots = False
        env, _ = task_registry.make_env("gente_biped_flat", env_cfg=env_cfg)
        actions = torch.Generator().manual_seed(1)
        for step in range(6):
            if step == 5 and reset_other:
                env.episode_length_buf[1] = env.max_episode_length - 1  # robot 1 times out in this step
            env.step(0.5 * torch.randn(2, env.num_actions, generator=actions))
        assert bool(env.reset_buf[1]) is reset_other
        return env.torques[0].clone(), env.sim.qpos[0].clone()

    (alone, qpos_alone), (beside_reset, qpos_beside) = torques_after(False), torques_after(True)
    assert torch.equal(qpos_alone, qpos_beside)
    assert torch.equal(alone, beside_reset)


def test_the_stand_still_group_counts_the_terrains_it_has_robots_on():
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import Evaluation
    from legged_gente.evaluation.report import build_report

    items = load_benchmark(str(BENCHMARK), ITEMS)
    evaluation = Evaluation("gente_biped", items, 2, "cpu", 0.1)
    result = evaluation.run(lambda obs: torch.zeros(4, evaluation.env.num_actions), settle_s=0.04, progress=False)
    assert result.tile.tolist() == [0, 0, 1, 1]
    result.metrics["standing"] = np.array([True, False, False, False])  # one standing robot, on the first terrain
    group = build_report(result, items)["groups"]["stand_still"]
    assert group["robots"] == 1 and group["terrains"] == 1
