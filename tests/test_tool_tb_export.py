"""python -m legged_gente.utils.tb_export (tools/gpu_evidence.sh, tools/scalars_to_results.py): a run's TensorBoard
scalars as one CSV, one row per step; a folder without a run is a one-line error."""

import csv

import pytest
from torch.utils.tensorboard import SummaryWriter

from legged_gente.utils.tb_export import export_scalars, main


def write_run(folder):
    writer = SummaryWriter(log_dir=str(folder))
    for step in range(3):
        writer.add_scalar("Train/mean_reward", 10.0 * step, step)
        if step != 1:  # a tag not logged at every step (no episode ended in iteration 1)
            writer.add_scalar("Train/mean_episode_length", 100.0 + step, step)
    writer.close()


def test_one_row_per_step_one_column_per_tag(tmp_path):
    write_run(tmp_path / "run")
    out = export_scalars(tmp_path / "run", tmp_path / "new" / "folder" / "scalars.csv")  # its folder made
    rows = list(csv.reader(open(out)))
    assert rows[0] == ["step", "Train/mean_episode_length", "Train/mean_reward"]
    assert rows[1:] == [["0", "100.0", "0.0"], ["1", "", "10.0"], ["2", "102.0", "20.0"]]


@pytest.mark.parametrize("what", ["missing", "empty", "file"])
def test_a_folder_that_is_no_run_is_a_one_line_error(tmp_path, capsys, what):
    run = tmp_path / "run"
    if what == "empty":
        run.mkdir()
    elif what == "file":
        run.write_text("")
    with pytest.raises(SystemExit) as stop:
        main([str(run), str(tmp_path / "scalars.csv")])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("tb_export: error: ") and str(run) in err, err
    assert not (tmp_path / "scalars.csv").exists()
