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
