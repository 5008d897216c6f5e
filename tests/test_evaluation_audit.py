"""The report states the success rule its task used: gente-evaluate refuses the velocity task's flags in the
waypoint task, so a waypoint report must not carry a velocity threshold either."""

import numpy as np

from legged_gente.evaluation.benchmark import load_benchmark
from legged_gente.evaluation.evaluator import RunResult
from legged_gente.evaluation.report import build_report


def result(task: str) -> RunResult:
    """Two robots on the flat benchmark's one tile: one reached its goal (or tracked its command), one did not."""
    n = 2
    metrics = {
        "fell": np.zeros(n, bool), "finished": np.array([True, False]), "standing": np.zeros(n, bool),
        "diverged": np.zeros(n, bool), "left_tile": np.zeros(n, bool), "tracking_error": np.array([0.1, 0.5]),
        "progress": np.array([0.9, 0.2]), "heading_error": np.array([3.0, 40.0]), "distance": np.array([5.0, 1.0]),
        "displacement": np.array([4.0, 1.0]), "collisions": np.zeros(n), "energy": np.array([100.0, 50.0]),
    }
    return RunResult(np.zeros(n, int), metrics, {}, task, {"settle_s": 1.0})


def test_a_waypoint_report_names_no_velocity_threshold():
    items = load_benchmark("flat", None)
    meta = build_report(result("waypoints"), items)["meta"]
    assert meta["task_mode"] == "waypoints"
    assert "tracking_threshold" not in meta and "min_progress" not in meta


def test_a_velocity_report_names_its_thresholds():
    items = load_benchmark("flat", None)
    report = build_report(result("velocity"), items, tracking_threshold=0.3, min_progress=0.8)
    assert report["meta"]["tracking_threshold"] == 0.3 and report["meta"]["min_progress"] == 0.8
    # robot 0 (error 0.1 < 0.3, progress 0.9 >= 0.8) succeeds, robot 1 does not
    assert report["overall"]["success_rate"] == 0.5
