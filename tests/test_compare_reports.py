"""Two evaluations of the same benchmark compared terrain by terrain (`python -m legged_gente.evaluation.compare`):
the paired mean difference and its standard error, worked out by hand here."""

import math

import pytest

from legged_gente.evaluation.compare import compare_reports, main

HEADER = "row,name,kind,categories,robots,success_rate,tracking_error\n"


def _report(path, rows):
    text = HEADER + "".join(f"terrain,{name},{kind},{cats},64,{rate},0.1\n" for name, kind, cats, rate in rows)
    path.write_text(text + "overall,all,,,256,0.5,0.1\n")
    return path


A_ROWS = [("t0", "text", "water", 0.50), ("t1", "text", "soil", 0.60), ("i0", "image", "water+obstacles", 0.70),
          ("i1", "image", "", 0.80)]
B_ROWS = [("t0", "text", "water", 0.60), ("t1", "text", "soil", 0.60), ("i0", "image", "water+obstacles", 0.90),
          ("i1", "image", "", 0.70)]


def test_paired_difference_and_its_standard_error(tmp_path):
    rows = compare_reports(_report(tmp_path / "a.csv", A_ROWS), _report(tmp_path / "b.csv", B_ROWS))
    every = rows["all"]
    # differences B - A: +0.1, 0, +0.2, -0.1; mean 0.05; sample SD sqrt(((.05)^2+(.05)^2+(.15)^2+(.15)^2)/3)
    sd = math.sqrt((0.05**2 + 0.05**2 + 0.15**2 + 0.15**2) / 3)
    assert every["terrains"] == 4
    assert every["a"] == pytest.approx(0.65) and every["b"] == pytest.approx(0.70)
    assert every["difference"] == pytest.approx(0.05) and every["se"] == pytest.approx(sd / 2)
    assert not every["resolved"]  # 0.05 < 2 x 0.065
    water = rows["water"]  # t0 and i0: +0.1 and +0.2
    assert water["terrains"] == 2 and water["difference"] == pytest.approx(0.15)
    assert water["se"] == pytest.approx(math.sqrt(2 * 0.05**2) / math.sqrt(2))
    assert rows["image"]["terrains"] == 2 and rows["obstacles"]["terrains"] == 1
    assert math.isnan(rows["obstacles"]["se"])  # one terrain: no spread to measure


def test_a_clear_difference_is_resolved(tmp_path):
    better = [(n, k, c, r + 0.2 + 0.01 * i) for i, (n, k, c, r) in enumerate(A_ROWS)]
    rows = compare_reports(_report(tmp_path / "a.csv", A_ROWS), _report(tmp_path / "b.csv", better))
    assert rows["all"]["resolved"] and rows["all"]["difference"] == pytest.approx(0.215)


def test_reports_of_other_terrains_are_refused(tmp_path):
    other = A_ROWS[:3] + [("x9", "image", "", 0.8)]
    with pytest.raises(ValueError, match=r"compare evaluations of the same benchmark: .*b.csv lacks \['i1'\], has \['x9'\]"):
        compare_reports(_report(tmp_path / "a.csv", A_ROWS), _report(tmp_path / "b.csv", other))


def test_cli_prints_a_table_and_errors_are_one_line(tmp_path, capsys):
    a, b = _report(tmp_path / "a.csv", A_ROWS), _report(tmp_path / "b.csv", B_ROWS)
    main([str(a), str(b)])
    out = capsys.readouterr().out
    assert "all" in out and "+5.00" in out and "not resolved" in out
    (tmp_path / "bad.csv").write_text("name,success_rate\nx,1\n")
    with pytest.raises(SystemExit) as info:
        main([str(a), str(tmp_path / "bad.csv")])
    assert info.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "bad.csv is not a gente-evaluate report.csv" in err
    with pytest.raises(SystemExit):
        main([str(a), str(tmp_path / "missing.csv")])
    assert "missing.csv: no such file; give the report.csv that gente-evaluate --out wrote" in capsys.readouterr().err
