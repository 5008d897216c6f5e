"""tools/terrain_roughness.py: the rough cells of a step, counted by hand."""

import numpy as np
import pytest


@pytest.fixture(scope="module")
def tool(load_file):
    return load_file("tools/terrain_roughness.py")


def test_a_step_is_rough_within_half_a_window_of_its_edge(tool):
    heights = np.zeros((100, 100), np.float32)
    heights[:, 60:] = 0.2  # a 0.2 m step between columns 59 and 60, at 0.1 m cells
    rough = tool.rough_cells(heights, 0.1, window=0.3, step=0.15)
    # a 3-cell window around column j holds both sides of the edge for j = 59 and j = 60 only
    assert rough.all(axis=0).sum() == 2 and rough[:, 59].all() and rough[:, 60].all()
    assert not tool.rough_cells(heights, 0.1, window=0.3, step=0.25).any()  # a 0.2 m step is below 0.25 m
    # the 8 m square around the centre: 80 x 80 cells, of which 2 columns of 80 are rough
    assert tool.rough_share(heights, 0.1, centre=8.0) == 2 * 80 / (80 * 80)
    assert tool.rough_share(np.zeros((100, 100)), 0.1) == 0.0


def test_the_curriculum_table_takes_gente_train_overrides(tool, capsys):
    """--set terrain.num_rows=2 --set terrain.num_cols=1: one flat column, two levels (both smooth)."""
    tool.curriculum_table("gente_biped", ["terrain.num_rows=2", "terrain.num_cols=1", "terrain.terrain_types=['flat']",
                                             "terrain.terrain_proportions=[1.0]"])
    lines = capsys.readouterr().out.splitlines()
    assert lines[1:] == ["    0             0.000  0.000 (flat)", "    1             0.000  0.000 (flat)"]


def test_bins_average_success_falls_and_tracking_over_their_terrains(tool, tmp_path, capsys):
    """Two rough terrains (success 0.5 and 1.0, fall rate 0.25 and 0, tracking 0.2 and 0.4 m/s) average to
    75 %, 12.5 %, 0.300; a terrain with no moving robot (empty cells) enters no mean; an empty bin prints '-'."""
    report = tmp_path / "report.csv"
    report.write_text("row,name,success_rate,fall_rate,tracking_error\n"
                      "terrain,a,0.5,0.25,0.2\nterrain,b,1.0,0.0,0.4\nterrain,c,,,\nterrain,d,0.0,1.0,0.9\n"
                      "overall,all,0.6,0.2,0.3\n")
    metrics = tool.read_report(str(report))
    assert set(metrics) == {"a", "b", "c", "d"} and np.isnan(metrics["c"]["success_rate"])
    tool.print_bins([("a", 0.5, metrics["a"]), ("b", 0.9, metrics["b"]), ("c", 0.4, metrics["c"]),
                     ("d", 0.05, metrics["d"])])
    lines = capsys.readouterr().out.splitlines()
    assert lines[1].split()[2:] == ["0", "-", "-", "-"]  # [0.00, 0.02): no terrain
    assert lines[2].split()[2:] == ["1", "0.0%", "100.0%", "0.900"]
    assert lines[4].split()[2:] == ["3", "75.0%", "12.5%", "0.300"]
