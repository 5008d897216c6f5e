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

BENCHMARK = Path(__file__).resolve().parents[1] / "benchmarks" / "gente100"
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
    assert report["overall"]["robots"] == 4 and report["overall"]["terrains"] == 2
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
    assert list(traces["ids"]) == ITEMS
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


def test_one_evaluation_runs_several_times():
    """The waypoint figure reruns one Evaluation per reach distance: the second run must start cleanly."""
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import Evaluation

    evaluation = Evaluation("gente_biped", load_benchmark(str(BENCHMARK), ITEMS[:1]), 1, "cpu", 0.2, "waypoints")
    # its hooks branch on host values every step: no whole-step graph, no torch.compile (on a GPU)
    assert evaluation.env_cfg.sim.cuda_graph == "physics" and evaluation.env_cfg.sim.torch_compile is False

    def still(obs):
        return torch.zeros(evaluation.env.num_envs, evaluation.env.num_actions)

    for d in (0.1, 20.0):
        result = evaluation.run(still, evaluation.make_task(reach_distance=d), progress=False)
        assert result.traces["pos"].shape[1] == round(0.2 / 0.02)
