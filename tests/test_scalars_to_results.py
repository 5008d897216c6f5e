"""tools/scalars_to_results.py: the chunks of a resumed run become one results CSV, each iteration once."""

import csv
import subprocess
import sys
from pathlib import Path

TOOL = Path(__file__).resolve().parents[1] / "tools" / "scalars_to_results.py"
TAGS = ["step", "Train/mean_episode_length", "Episode/rew_tracking_lin_vel", "Train/mean_reward", "Perf/total_fps",
        "Episode/terrain_level", "Episode/diverged_resets", "Perf/collection_time", "Perf/learning_time"]


def _chunk(path, steps, level):
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(TAGS)
        for step in steps:
            writer.writerow([step, 900, 0.8, 20, 4e5, level, 1, 0.2, 0.05])


def test_a_chunk_resumed_from_an_older_checkpoint_replaces_the_iterations_it_redid(tmp_path):
    # chunk 1 ran to iteration 14, chunk 2 resumed from the checkpoint of iteration 10 and ran to 19
    _chunk(tmp_path / "a.csv", range(0, 15), level=1.0)
    _chunk(tmp_path / "b.csv", range(11, 20), level=2.0)
    out = tmp_path / "out.csv"
    subprocess.run([sys.executable, str(TOOL), str(out), str(tmp_path / "a.csv"), str(tmp_path / "b.csv")], check=True)
    rows = list(csv.DictReader(open(out)))
    assert [int(r["iteration"]) for r in rows] == list(range(20))
    assert [float(r["terrain_level"]) for r in rows] == [1.0] * 11 + [2.0] * 9
    assert float(rows[-1]["wall_s"]) == round(20 * 0.25, 1)  # 0.2 s collection + 0.05 s learning, 20 iterations
    assert int(rows[-1]["diverged_resets_cumulative"]) == 20


def test_iterations_before_the_first_finished_episode_count(tmp_path):
    """The first iterations of a run log no episode length until an episode ends: they were dropped, with their
    time, so wall_s was short of the training time it says it sums."""
    _chunk(tmp_path / "a.csv", range(0, 5), level=1.0)
    rows = list(csv.reader(open(tmp_path / "a.csv")))
    rows[1][1] = rows[2][1] = ""  # iterations 0 and 1: no episode has ended yet
    with open(tmp_path / "a.csv", "w", newline="") as f:
        csv.writer(f).writerows(rows)
    out = tmp_path / "out.csv"
    subprocess.run([sys.executable, str(TOOL), str(out), str(tmp_path / "a.csv")], check=True)
    results = list(csv.DictReader(open(out)))
    assert [int(r["iteration"]) for r in results] == list(range(5))
    assert [r["mean_episode_length"] for r in results][:3] == ["", "", "900"]
    assert float(results[-1]["wall_s"]) == round(5 * 0.25, 1)
