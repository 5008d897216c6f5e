"""tools/terrain_roughness.py refuses in one line what it would ignore: --set without --curriculum, --report
without --benchmark, and a report with none of the benchmark's terrains (every bin printed '-')."""

import sys

import pytest


@pytest.fixture(scope="module")
def tool(load_file):
    return load_file("tools/terrain_roughness.py")


def run(tool, monkeypatch, *argv):
    monkeypatch.setattr(sys, "argv", ["terrain_roughness.py", *argv])
    with pytest.raises(SystemExit) as stop:
        tool.main()
    return stop.value.code


@pytest.mark.parametrize("argv, named", [
    (("--benchmark", "flat", "--set", "terrain.num_rows=2"), "--set"),
    (("--curriculum", "gente_biped", "--report", "report.csv"), "--report"),
])
def test_a_flag_of_the_other_mode_is_refused(tool, monkeypatch, capsys, argv, named):
    assert run(tool, monkeypatch, *argv) == 2
    assert named in capsys.readouterr().err.strip().splitlines()[-1]


def test_a_report_of_another_benchmark_is_refused(tool, monkeypatch, capsys, tmp_path):
    report = tmp_path / "report.csv"
    report.write_text("row,name,success_rate,fall_rate,tracking_error\nterrain,single_text_01,0.5,0.1,0.2\n")
    assert run(tool, monkeypatch, "--benchmark", "flat", "--report", str(report)) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert str(report) in err and "flat" in err


def test_a_report_of_some_terrains_bins_those_and_says_so(tool, monkeypatch, capsys, tmp_path):
    """An evaluation of two of the steps benchmark's items (gente-evaluate --items): the bins count those two, not
    the benchmark's others with no score, and the output says how many of its terrains the report scores."""
    from legged_gente.evaluation.benchmark import load_benchmark

    count = len(load_benchmark("steps"))
    report = tmp_path / "report.csv"
    report.write_text("row,name,success_rate,fall_rate,tracking_error\n"
                      "terrain,step_10cm,1.0,0.0,0.1\nterrain,step_15cm,0.5,0.5,0.3\n")
    monkeypatch.setattr(sys, "argv", ["terrain_roughness.py", "--benchmark", "steps", "--report", str(report)])
    tool.main()
    out = capsys.readouterr().out.splitlines()
    assert out[0] == f"{report} scores 2 of the {count} terrains of steps: the bins hold those"
    counts = [int(line.split()[2]) for line in out[2:]]
    assert sum(counts) == 2 and count > 2
