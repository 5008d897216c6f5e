"""Two evaluations of the same benchmark compared terrain by terrain (`python -m legged_gente.evaluation.compare`):
the paired mean difference and its standard error, worked out by hand here."""

import json
import math
import re

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
    assert not every["resolved"]  # 0.05 < t(0.975, 3 dof) 3.18 x 0.065
    assert every["t"] == pytest.approx(3.1824, abs=1e-4)  # Student's t table, 3 degrees of freedom
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
    with pytest.raises(ValueError, match=r"compare evaluations of the same benchmark: .*b.csv lacks \['i1'\] and has "
                                         r"\['x9'\] that .*a.csv has not\.$"):
        compare_reports(_report(tmp_path / "a.csv", A_ROWS), _report(tmp_path / "b.csv", other))
    # an evaluation of fewer terrains (--items): what it lacks, with no empty list of extras
    with pytest.raises(ValueError, match=r"b.csv lacks \['i1'\]\.$"):
        compare_reports(_report(tmp_path / "a.csv", A_ROWS), _report(tmp_path / "b.csv", A_ROWS[:3]))


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


def _evaluation(folder, rows, **meta):
    """An --out folder: report.csv and the report.json whose meta holds the scoring settings."""
    folder.mkdir()
    (folder / "report.json").write_text(json.dumps({"meta": {
        "task_mode": "velocity", "tracking_threshold": 0.25, "min_progress": 0.7, "min_speed": 0.3,
        "stand_fraction": 0.125, "episode_length_s": 10.0, "settle_s": 1.0, "tile_edge_margin": 0.5,
        "max_base_speed": 10.0, "seed": 0, "policy": "a", **meta}}))
    return _report(folder / "report.csv", rows)


def test_evaluations_scored_differently_are_not_compared(tmp_path, capsys):
    """A velocity evaluation against a waypoint one (or another episode length, speed floor, share of standing
    robots) differs by how it was scored, not by the policy: refused, naming the settings. The policy and seed may
    differ, and a report.csv alone is compared with a line saying its settings were not checked."""
    a = _evaluation(tmp_path / "a", A_ROWS)
    b = _evaluation(tmp_path / "b", B_ROWS, seed=1, policy="b")
    assert compare_reports(a, b)["all"]["terrains"] == 4
    waypoints = _evaluation(tmp_path / "w", B_ROWS, task_mode="waypoints", episode_length_s=2.0)
    with pytest.raises(ValueError, match=r"the two evaluations were scored differently \(task_mode velocity against "
                                         r"waypoints; episode_length_s 10.0 against 2.0, from their report.json\); "
                                         r"evaluate both with the same flags"):
        compare_reports(a, waypoints)
    slower = _evaluation(tmp_path / "s", B_ROWS, min_speed=0.8, stand_fraction=0.5)
    with pytest.raises(ValueError, match=r"min_speed 0.3 against 0.8; stand_fraction 0.125 against 0.5"):
        compare_reports(a, slower)
    lone = _report(tmp_path / "lone.csv", B_ROWS)
    compare_reports(a, lone)
    assert f"no report.json beside {lone}: the two evaluations' settings are not checked" in capsys.readouterr().out


def test_a_cut_or_binary_report_is_one_line_naming_the_file(tmp_path, capsys):
    a = _report(tmp_path / "a.csv", A_ROWS)
    cut = tmp_path / "cut.csv"
    cut.write_text(a.read_text()[:120])
    binary = tmp_path / "binary.csv"
    binary.write_bytes(b"\xff\xfe\x00garbage")
    for path, message in ((cut, r"cut.csv, line \d: \d fields where the header has 7 \(cut short or edited\)"),
                          (binary, r"binary.csv is not a gente-evaluate report.csv .*'utf-8' codec")):
        with pytest.raises(SystemExit) as info:
            main([str(a), str(path)])
        err = capsys.readouterr().err.strip()
        assert info.value.code == 2 and len(err.splitlines()) == 1 and "Traceback" not in err, err
        assert re.search(message, err), err


def test_compare_takes_the_out_folders_and_names_the_metrics_unit(tmp_path, capsys):
    a = _evaluation(tmp_path / "a", A_ROWS)
    _evaluation(tmp_path / "b", B_ROWS)
    main([str(a.parent), str(tmp_path / "b"), "--metric", "tracking_error"])
    assert capsys.readouterr().out.startswith("tracking_error, per terrain, B - A (m/s)")


def test_a_terrain_changed_between_two_evaluations_is_not_compared(tmp_path):
    """gente-generate --out over a benchmark item's folder changes the terrain under the same name: the reports'
    terrain digests (report.json) differ and the comparison is refused, naming the terrain; a report without
    digests (made before they were kept) is compared as before."""
    a = _evaluation(tmp_path / "a", A_ROWS, terrain_digests={"t0": "aa", "t1": "bb", "i0": "cc", "i1": "dd"})
    same = _evaluation(tmp_path / "s", B_ROWS, terrain_digests={"t0": "aa", "t1": "bb", "i0": "cc", "i1": "dd"})
    assert compare_reports(a, same)["all"]["terrains"] == 4
    changed = _evaluation(tmp_path / "c", B_ROWS, terrain_digests={"t0": "aa", "t1": "XX", "i0": "cc", "i1": "dd"})
    with pytest.raises(ValueError, match=r"built different terrains under the same name \(t1: their spec changed"):
        compare_reports(a, changed)
    older = _evaluation(tmp_path / "o", B_ROWS)
    assert compare_reports(a, older)["all"]["terrains"] == 4


def test_the_terrain_digest_follows_what_builds_the_terrain(tmp_path):
    from legged_gente.generation.spec import TerrainSpec

    doc = {"version": 1, "name": "creek", "size_x": 8.0, "size_y": 8.0, "resolution": 0.1, "seed": 0,
           "calls": [{"tool": "soil", "region": "left", "params": {"preset": "mud"}}],
           "source": {"text": "a muddy creek"}, "backend": "planner", "model": None}
    digest = TerrainSpec.from_dict(doc).terrain_digest()
    renamed = TerrainSpec.from_dict(doc | {"name": "other", "source": {"text": "words"}}).terrain_digest()
    reseeded = TerrainSpec.from_dict(doc | {"seed": 1}).terrain_digest()
    sand = TerrainSpec.from_dict(doc | {"calls": [{"tool": "soil", "region": "left", "params": {"preset": "dry_sand"}}]})
    assert digest == renamed and len({digest, reseeded, sand.terrain_digest()}) == 3


def test_two_terrains_get_no_verdict_and_small_metrics_keep_their_digits(tmp_path, capsys):
    """Two terrains with alike differences have a standard error of about 0: "resolved" on nothing. And a
    tracking error 3 mm/s apart printed as -0.00 SE 0.00."""
    a = _report(tmp_path / "a.csv", [("t0", "text", "water", 0.5), ("t1", "text", "water", 0.5)])
    b = _report(tmp_path / "b.csv", [("t0", "text", "water", 0.75), ("t1", "text", "water", 0.75)])
    water = compare_reports(a, b)["water"]
    assert water["se"] == 0.0 and water["difference"] == pytest.approx(0.25) and not water["resolved"]
    main([str(a), str(b)])
    assert "too few terrains (< 3)" in capsys.readouterr().out
    slow = tmp_path / "slow.csv"
    slow.write_text(HEADER + "".join(f"terrain,t{i},text,water,64,0.5,{0.1 + 0.003 + 0.001 * i}\n" for i in range(4)))
    fast = tmp_path / "fast.csv"
    fast.write_text(HEADER + "".join(f"terrain,t{i},text,water,64,0.5,0.1\n" for i in range(4)))
    main([str(slow), str(fast), "--metric", "tracking_error"])
    row = [line for line in capsys.readouterr().out.splitlines() if line.strip().startswith("all")][0]
    assert "-0.0045" in row, row  # mean of -(0.003, 0.004, 0.005, 0.006)
