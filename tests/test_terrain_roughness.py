"""tools/terrain_roughness.py: the rough cells of a step, counted by hand."""

import importlib.util
from pathlib import Path

import numpy as np

TOOL = Path(__file__).resolve().parents[1] / "tools" / "terrain_roughness.py"


def _tool():
    spec = importlib.util.spec_from_file_location("terrain_roughness", TOOL)
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    return tool


def test_a_step_is_rough_within_half_a_window_of_its_edge():
    tool = _tool()
    heights = np.zeros((100, 100), np.float32)
    heights[:, 60:] = 0.2  # a 0.2 m step between columns 59 and 60, at 0.1 m cells
    rough = tool.rough_cells(heights, 0.1, window=0.3, step=0.15)
    # a 3-cell window around column j holds both sides of the edge for j = 59 and j = 60 only
    assert rough.all(axis=0).sum() == 2 and rough[:, 59].all() and rough[:, 60].all()
    assert not tool.rough_cells(heights, 0.1, window=0.3, step=0.25).any()  # a 0.2 m step is below 0.25 m
    # the 8 m square around the centre: 80 x 80 cells, of which 2 columns of 80 are rough
    assert tool.rough_share(heights, 0.1, centre=8.0) == 2 * 80 / (80 * 80)
    assert tool.rough_share(np.zeros((100, 100)), 0.1) == 0.0


def test_the_curriculum_table_takes_gente_train_overrides(capsys):
    """--set terrain.num_rows=2 --set terrain.num_cols=1: one flat column, two levels (both smooth)."""
    _tool().curriculum_table("gente_biped", ["terrain.num_rows=2", "terrain.num_cols=1", "terrain.terrain_types=['flat']",
                                             "terrain.terrain_proportions=[1.0]"])
    lines = capsys.readouterr().out.splitlines()
    assert lines[1:] == ["    0             0.000  0.000 (flat)", "    1             0.000  0.000 (flat)"]
