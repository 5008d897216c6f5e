"""The planner's evaluation scorer: features of calls, the arithmetic of the scores, the CLI and the set."""

from __future__ import annotations

import json

import pytest

from legged_gente.generation.score import DEFAULT_SET, FEATURES, features, load_items, main, score
from legged_gente.generation.validation import validate_call


def _call(tool, **args):
    return validate_call(tool, {"region": "full", **args})


def test_features_of_calls():
    assert features([_call("water", depth=0.3)]) == {"water"}
    assert features([_call("water", depth=0.3, flow="current", speed=0.5)]) == {"water", "flowing"}
    assert features([_call("water", depth=0.3, flow="current", speed=0.0)]) == {"water"}  # no speed, no flow
    assert features([_call("soil", preset="wet_sand"), _call("soil", preset="clay_loam")]) == {"sand"}
    assert features([_call("low_friction", preset="wet_tiles")]) == set()  # slippery, but not ice
    assert features([_call("pillars", height=2.0)]) == {"tall"}
    assert features([_call("rocks", max_height=0.15)]) == {"low"}
    assert features([_call("discrete_obstacles", max_height=0.5)]) == {"tall"}
    assert features([_call("flat", height=1.2)]) == set()  # the whole tile raised is not an obstacle
    block = validate_call("flat", {"height": 1.2, "region": {"x0": 0, "y0": 0, "x1": 2, "y1": 20}})
    assert features([block]) == {"tall"}
    assert features([_call("hills", amplitude=0.8), _call("natural_ground", amplitude=0.04)]) == {"slope"}
    assert features([_call("natural_ground", amplitude=0.1), _call("stairs")]) == {"rough", "stairs"}


def test_score_arithmetic():
    items = [{"labels": ["water", "sand"]}, {"labels": ["tall"]}, {"labels": []}]
    preds = [({"water", "sand", "snow"}, 3), ({"low"}, 5), (set(), 1)]
    out = score(items, preds)
    # tp = water, sand = 2; fp = snow, low = 2; fn = tall = 1 -> F1 = 2*2 / (2*2 + 2 + 1) = 4/7
    assert out["micro_f1"] == pytest.approx(4 / 7)
    assert out["complete"] == pytest.approx(2 / 3) and out["exact"] == pytest.approx(1 / 3)
    assert out["median_calls"] == 3 and out["false_water_or_snow"] == 1
    assert out["per_feature"]["snow"] == {"tp": 0, "fp": 1, "fn": 0}


def test_cli_on_a_small_set(tmp_path, capsys):
    (tmp_path / "texts.json").write_text(json.dumps({"items": [
        {"text": "a frozen lake", "labels": ["ice"]}, {"text": "stairs", "labels": ["stairs"]}]}))
    assert main(["--set", str(tmp_path), "--kind", "text"]) == 0
    out = capsys.readouterr().out
    assert "micro-F1 1.000" in out and "| ice | 1.00 | 1.00 | 1 | 0 | 0 |" in out
    (tmp_path / "texts.json").write_text(json.dumps({"items": [{"text": "x", "labels": ["lava"]}]}))
    assert main(["--set", str(tmp_path), "--kind", "text"]) == 2
    assert "unknown label(s) ['lava']" in capsys.readouterr().err


def test_the_evaluation_set():
    texts, photos = load_items(DEFAULT_SET, "text"), load_items(DEFAULT_SET, "photo")
    assert len(texts) >= 40 and len(photos) >= 40
    for items in (texts, photos):
        assert {i["split"] for i in items} == {"tune", "held_out"}
        assert {f for i in items for f in i["labels"]} == set(FEATURES)  # every feature is exercised
    for item in photos:
        assert item["path"].stat().st_size < 60_000, item["file"]


def test_an_item_file_without_an_items_list_is_a_one_line_error(tmp_path):
    (tmp_path / "texts.json").write_text(json.dumps([{"text": "a beach", "labels": ["sand"]}]))
    with pytest.raises(ValueError, match=r"texts.json holds no 'items' list; write \{\"items\""):
        load_items(tmp_path, "text")
