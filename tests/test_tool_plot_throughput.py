"""tools/plot_throughput.py: gente-benchmark CSVs (LABEL=PATH) drawn into one PNG; a CSV given without its label
or missing is a one-line usage error, not a traceback."""

import csv

import pytest

COLUMNS = ["num_envs", "raw_substeps_per_s", "env_steps_per_s", "ppo_steps_per_s", "env_over_raw", "ppo_over_raw"]


def benchmark_csv(path, scale: float = 1.0):
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(COLUMNS)
        for n in (1024, 4096):
            raw = 400.0 * n * scale
            writer.writerow([n, raw, 0.7 * raw / 4, 0.5 * raw / 4, 0.7, 0.5])
    return path


@pytest.fixture(scope="module")
def tool(load_file):
    return load_file("tools/plot_throughput.py")


def test_two_benchmarks_in_one_png(tool, tmp_path):
    a, b = benchmark_csv(tmp_path / "a.csv"), benchmark_csv(tmp_path / "b.csv", scale=2.0)
    tool.main([str(tmp_path / "out.png"), f"before={a}", f"after={b}", "--skip_raw", "after"])
    assert (tmp_path / "out.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("item, message", [("a.csv", "give each CSV as LABEL=PATH"), ("x=none.csv", "no such file")])
def test_a_csv_without_label_or_file_is_a_usage_error(tool, tmp_path, capsys, monkeypatch, item, message):
    monkeypatch.chdir(tmp_path)
    benchmark_csv(tmp_path / "a.csv")
    with pytest.raises(SystemExit) as stop:
        tool.main([str(tmp_path / "out.png"), item])
    assert stop.value.code == 2 and message in capsys.readouterr().err
    assert not (tmp_path / "out.png").exists()


def test_a_skip_raw_label_no_csv_has_is_a_usage_error(tool, tmp_path, capsys):
    a = benchmark_csv(tmp_path / "a.csv")
    with pytest.raises(SystemExit) as stop:
        tool.main([str(tmp_path / "out.png"), f"before={a}", "--skip_raw", "befor"])
    assert stop.value.code == 2 and "--skip_raw ['befor']: no CSV has that label" in capsys.readouterr().err
