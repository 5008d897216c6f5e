"""Bad benchmark manifests and bad comparisons are one-line errors that name the fix, never a traceback, a silent
misreading or an empty answer. Nothing here is simulated: manifests and report.csv files are written by hand."""

import json

import pytest

from legged_gente.evaluation.benchmark import load_benchmark
from legged_gente.evaluation.compare import compare_reports, main


# ------------------------------------------------------------------------------------------ benchmark manifests
def _manifest(tmp_path, **fields):
    """A one-item manifest: a text item "t0" with its spec path, ``fields`` replacing or adding to its entry."""
    entry = {"id": "t0", "kind": "text", "prompt": "a beach", "spec": "specs/t0.json"} | fields
    (tmp_path / "manifest.json").write_text(json.dumps({"name": "b", "items": [entry]}))
    return tmp_path


@pytest.mark.parametrize("bad_id", [["t0"], 5, None, ""])
def test_an_item_id_that_is_not_a_name_is_refused(tmp_path, bad_id):
    """Report rows, --items and compare name a terrain by its id: a list id crashed (TypeError: unhashable, a
    traceback past the CLI's error handling), a number or null became a row named 5 / None that --items 5 cannot
    select."""
    with pytest.raises(ValueError, match=r"manifest.json: item id .* give every item a non-empty string id"):
        load_benchmark(_manifest(tmp_path, id=bad_id))


def test_image_names_given_as_one_string_are_refused_not_split_into_letters(tmp_path):
    """``names`` is a list of LEGEND classes; "water" was read as the five classes w, a, t, e, r."""
    root = _manifest(tmp_path, kind="image", image="images/t0.png", names="water")
    with pytest.raises(ValueError, match=r"item 't0' has names 'water'; give a list of LEGEND class names"):
        load_benchmark(root)
    root = _manifest(tmp_path, kind="image", image="images/t0.png", names=["water", 3])
    with pytest.raises(ValueError, match=r"item 't0' has names \['water', 3\]"):
        load_benchmark(root)


def test_a_prompt_that_is_not_text_is_refused(tmp_path):
    with pytest.raises(ValueError, match=r"item 't0' has prompt 5; give a string"):
        load_benchmark(_manifest(tmp_path, prompt=5))


def test_a_well_formed_item_still_loads(tmp_path):
    (item,) = load_benchmark(_manifest(tmp_path, kind="image", prompt=None, image="images/t0.png",
                                       names=["water", "grass"]))
    assert (item.id, item.kind, item.names, item.prompt) == ("t0", "image", ("water", "grass"), None)
    assert item.image == tmp_path / "images" / "t0.png" and item.spec_path == tmp_path / "specs" / "t0.json"


# ----------------------------------------------------------------------------------------------------- compare
HEADER = "row,name,kind,categories,robots,success_rate,heading_error\n"


def _report(path, rows):
    """A report.csv of terrain rows (name, success rate, heading error; "" = undefined) and its overall row."""
    text = HEADER + "".join(f"terrain,{name},text,water,8,{rate},{heading}\n" for name, rate, heading in rows)
    path.write_text(text + "overall,all,,,16,0.5,\n")
    return path


def test_a_misspelt_metric_is_named_with_the_columns_to_choose_from(tmp_path):
    """The file is a good report.csv; the metric is what is wrong. The error said the file was not a report and
    asked for another file."""
    a = _report(tmp_path / "a.csv", [("t0", 0.5, ""), ("t1", 0.6, "")])
    with pytest.raises(ValueError, match=r"--metric succes_rate: .*a.csv has no such column; give one of .*success_rate"):
        compare_reports(a, a, metric="succes_rate")


def test_a_metric_no_terrain_has_in_both_reports_is_an_error_not_an_empty_table(tmp_path, capsys):
    """heading_error is empty in yaw-rate mode: no terrain pairs, and the table came out with no row at exit 0."""
    a = _report(tmp_path / "a.csv", [("t0", 0.5, ""), ("t1", 0.6, "")])
    b = _report(tmp_path / "b.csv", [("t0", 0.7, ""), ("t1", 0.6, "4.0")])
    with pytest.raises(ValueError, match=r"no terrain has a heading_error in both .*; compare another --metric"):
        compare_reports(a, b, metric="heading_error")
    with pytest.raises(SystemExit) as info:
        main([str(a), str(b), "--metric", "heading_error"])
    assert info.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "no terrain has a heading_error in both" in err
    # success_rate has both terrains: differences +0.2 and 0, mean 0.1, sample SD sqrt(2 * 0.1^2 / 1), SE SD / sqrt(2)
    every = compare_reports(a, b)["all"]
    assert every["terrains"] == 2 and every["difference"] == pytest.approx(0.1)
    assert every["se"] == pytest.approx((2 * 0.1**2) ** 0.5 / 2**0.5)


def test_a_shipped_benchmark_is_found_beside_a_folder_of_its_name_without_a_manifest(tmp_path, monkeypatch):
    """`gente-evaluate --out gente100` makes ./gente100 (report.csv, report.json, traces.npz); the next run from there
    with the default --benchmark gente100 was refused: "gente100/manifest.json not found; pass ... a shipped
    benchmark: [..., 'gente100', ...]". A folder is the benchmark only when it holds one (or a generated terrain,
    whose spec.json gets its own error); otherwise the shipped one of that name is meant."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "gente100").mkdir()
    (tmp_path / "gente100" / "report.csv").write_text("row,name\n")
    items = load_benchmark("gente100")
    assert len(items) == 100 and items[0].spec_path.is_file()
    (tmp_path / "flat").mkdir()
    (tmp_path / "flat" / "spec.json").write_text("{}")  # what gente-generate writes: still named as such
    with pytest.raises(FileNotFoundError, match="holds one generated terrain, not a benchmark"):
        load_benchmark("flat")
    with pytest.raises(FileNotFoundError, match=r"nothing/manifest.json not found"):
        load_benchmark("nothing")
