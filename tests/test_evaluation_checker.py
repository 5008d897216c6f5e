"""The checker accepts good items and rejects empty, out-of-bounds, blocked-spawn and incomplete ones."""

import dataclasses

import pytest

from legged_gente.generation.checker import check_spec, required_tools
from legged_gente.evaluation.report import BASE_GROUND, CATEGORY_OF_TOOL, categories_of
from legged_gente.generation.pipeline import generate_spec
from legged_gente.generation.validation import ToolCall
from legged_gente.terrain.composition import stacked_height_bounds
from legged_gente.terrain.registry import ATOMIC_TERRAINS

PROMPT = "a knee-deep river crossing a meadow with trees and muddy banks"


@pytest.fixture(scope="module")
def good(tmp_path_factory):
    spec, _ = generate_spec(PROMPT, seed=3)
    return spec, spec.save(tmp_path_factory.mktemp("good") / "spec.json")


def test_good_item_passes(good):
    _, path = good
    result = check_spec(path, PROMPT)
    assert result.ok, result.problems
    assert {"river", "water", "pillars"} <= set(result.required)


def test_required_tools_come_from_planner_vocabulary():
    assert "water" in required_tools("a lake")
    assert "stairs" in required_tools("steep stairs")
    assert "pillars" in required_tools("a dense forest")
    assert "soil" in required_tools("sand dunes")
    assert "low_friction" in required_tools("an icy road")
    assert "low_friction" in required_tools("a slippery park")  # a modifier's extra step
    assert required_tools(names=("water", "grass")) == ["basin", "water"]  # sketch water lies in a basin
    with pytest.raises(ValueError, match="LEGEND"):
        required_tools(names=("lava",))


def test_missing_named_feature_is_rejected(good, tmp_path):
    spec, _ = good
    dry = dataclasses.replace(spec, calls=[c for c in spec.calls if c.tool != "water"])
    result = check_spec(dry.save(tmp_path / "dry.json"), PROMPT)
    assert any("'water'" in p and "missing" in p for p in result.problems)
    # a prompt naming stairs against a spec without any
    result = check_spec(dry.save(tmp_path / "dry.json"), "a river and stairs")
    assert any("'stairs'" in p for p in result.problems)


def test_empty_item_is_rejected(good, tmp_path):
    spec, _ = good
    flat = dataclasses.replace(spec, calls=[ToolCall("flat", {"height": 0.0}, "full", "set")])
    result = check_spec(flat.save(tmp_path / "flat.json"))
    assert any(p.startswith("empty") for p in result.problems)


def test_blocked_spawn_is_rejected(good, tmp_path):
    spec, _ = good
    rough = ATOMIC_TERRAINS["random_uniform"].check_params({"amplitude": 0.2, "platform": 0.0})
    blocked = dataclasses.replace(spec, calls=[ToolCall("random_uniform", rough, "full", "set")])
    result = check_spec(blocked.save(tmp_path / "blocked.json"))
    assert any(p.startswith("untraversable") for p in result.problems)


def test_out_of_bounds_is_rejected(good, tmp_path, monkeypatch):
    spec, path = good
    bounds = stacked_height_bounds(spec.to_tile_spec())
    assert bounds.lo.min() < 0 < bounds.hi.max()  # the river cuts below 0; pillars rise above
    # Declare every geometric atomic 10 cm lower than it builds: the built tile must then exceed its bounds.
    for name, atomic in ATOMIC_TERRAINS.items():
        if atomic.kind == "geometric":
            monkeypatch.setitem(ATOMIC_TERRAINS, name, dataclasses.replace(
                atomic, bounds=lambda p, sx, sy, a=atomic: tuple(v - 0.1 for v in a.height_bounds(p, sx, sy))))
    result = check_spec(path, PROMPT)
    assert any(p.startswith("out of bounds") for p in result.problems)


def test_every_atomic_has_a_category_decision(good):
    assert set(CATEGORY_OF_TOOL) | set(BASE_GROUND) == set(ATOMIC_TERRAINS)
    assert set(CATEGORY_OF_TOOL).isdisjoint(BASE_GROUND)
    spec, _ = good
    assert categories_of(spec) == ["water", "soil", "obstacles"]
