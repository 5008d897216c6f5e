"""tools/plot_learning_curve.py (the learning-curve figures of README.md and docs/performance_log.md): a results CSV
of tools/scalars_to_results.py drawn against wall time; a CSV without a column it draws is a one-line usage error."""

import csv

import pytest

COLUMNS = ["iteration", "wall_s", "mean_episode_length", "rew_tracking_lin_vel", "mean_reward", "terrain_level"]


def results_csv(path, columns=COLUMNS):
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=columns, extrasaction="ignore")
        writer.writeheader()
        for i in range(5):
            writer.writerow({"iteration": i, "wall_s": 30.0 * i, "mean_episode_length": 200.0 * i,
                             "rew_tracking_lin_vel": 0.2 * i, "mean_reward": i, "terrain_level": 0.5 * i})
    return path


@pytest.fixture(scope="module")
def tool(load_file):
    return load_file("tools/plot_learning_curve.py")


def test_a_curriculum_run_with_its_levels(tool, tmp_path):
    tool.main([str(results_csv(tmp_path / "run.csv")), str(tmp_path / "run.png"), "--levels", "10", "--mark", "1.5",
               "--title", "test"])
    assert (tmp_path / "run.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_levels_of_a_csv_without_terrain_level_is_a_usage_error(tool, tmp_path, capsys):
    flat = results_csv(tmp_path / "flat.csv", [c for c in COLUMNS if c != "terrain_level"])
    tool.main([str(flat), str(tmp_path / "flat.png")])  # no --levels: no terrain_level needed
    with pytest.raises(SystemExit) as stop:
        tool.main([str(flat), str(tmp_path / "levels.png"), "--levels", "10"])
    assert stop.value.code == 2 and "no column terrain_level" in capsys.readouterr().err
