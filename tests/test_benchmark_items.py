"""Every item of our own benchmarks passes the checker: gente100 (50 text and 50 image items, for measuring) and
gente_val (30 text and 20 image items, for choosing between training candidates); both stay small, and the
validation set shares no prompt, picture or terrain with the sets that measure."""

import hashlib
import json
from pathlib import Path

import pytest

from legged_gente.evaluation.benchmark import load_benchmark, tile_geometry
from legged_gente.generation.checker import check_item

BENCHMARKS = Path(__file__).resolve().parents[1] / "legged_gente" / "benchmarks"
SETS = {"gente100": (50, 50), "gente_val": (30, 20)}
ITEMS = {name: load_benchmark(BENCHMARKS / name) for name in SETS}


@pytest.mark.parametrize("name", SETS)
def test_text_and_image_items_of_one_tile_size(name):
    items = ITEMS[name]
    kinds = [i.kind for i in items]
    assert (kinds.count("text"), kinds.count("image")) == SETS[name]
    assert len({i.id for i in items}) == len(items)
    assert tile_geometry([i.spec() for i in items]) == (20.0, 20.0, 0.1)
    assert all(i.image.is_file() for i in items if i.kind == "image")


@pytest.mark.parametrize("name", SETS)
def test_benchmark_is_small(name):
    root = BENCHMARKS / name
    total = sum(p.stat().st_size for p in root.rglob("*") if p.is_file())
    images = sum(p.stat().st_size for p in (root / "images").glob("*.png"))
    assert total < 6e6 and images < 2e6


def _terrain(item) -> str:
    """What the terrain is made of, whatever the item is called: the spec without its name."""
    spec = json.loads(item.spec_path.read_text())
    spec.pop("name")
    return json.dumps(spec, sort_keys=True)


def test_the_validation_set_shares_nothing_with_the_sets_that_measure():
    measuring = ITEMS["gente100"] + load_benchmark(BENCHMARKS / "gente_original")
    val = ITEMS["gente_val"]
    assert not {i.prompt for i in val if i.prompt} & {i.prompt for i in measuring if i.prompt}
    digest = lambda path: hashlib.sha256(path.read_bytes()).hexdigest()  # noqa: E731
    assert not {digest(i.image) for i in val if i.image} & {digest(i.image) for i in measuring if i.image}
    assert not {_terrain(i) for i in val} & {_terrain(i) for i in measuring}


@pytest.mark.parametrize("item", [i for items in ITEMS.values() for i in items],
                         ids=[f"{name}/{i.id}" for name, items in ITEMS.items() for i in items])
def test_item_passes_checker(item):
    result = check_item(item)
    assert result.ok, result.problems
    if item.kind == "text":
        assert result.required, f"{item.prompt!r} names nothing the planner knows"
