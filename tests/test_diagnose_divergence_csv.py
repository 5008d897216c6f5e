"""tools/diagnose_divergence.py --csv when no robot diverged: the CSV is written with its header alone, and the
tool says so (a missing file read as 'the run failed')."""

import csv


def test_no_divergence_writes_the_header_and_says_so(load_file, tmp_path, capsys):
    tool = load_file("tools/diagnose_divergence.py")
    out = tmp_path / "diverged.csv"
    tool.main(["--task", "gente_biped", "--benchmark", "flat", "--robots_per_terrain", "1", "--episode_s", "0.1",
               "--no_progress", "--csv", str(out)])
    printed = capsys.readouterr().out
    assert "diverged robots: 0" in printed
    with open(out, newline="") as f:
        assert list(csv.reader(f)) == [list(tool.COLUMNS)]
    assert f"{out}: header only, no robot diverged" in printed.splitlines()[-1]
