"""Every gente100 item passes the checker; the benchmark has 50 text and 50 image items and stays small."""

from pathlib import Path

import pytest

from legged_gente.evaluation.benchmark import load_benchmark, tile_geometry
from legged_gente.generation.checker import check_item

ROOT = Path(__file__).resolve().parents[1] / "legged_gente" / "benchmarks" / "gente100"
ITEMS = load_benchmark(ROOT)


def test_fifty_text_and_fifty_image_items_of_one_tile_size():
    kinds = [i.kind for i in ITEMS]
    assert kinds.count("text") == 50 and kinds.count("image") == 50
    assert len({i.id for i in ITEMS}) == 100
    assert tile_geometry([i.spec() for i in ITEMS]) == (20.0, 20.0, 0.1)
    assert all(i.image.is_file() for i in ITEMS if i.kind == "image")


def test_benchmark_is_small():
    total = sum(p.stat().st_size for p in ROOT.rglob("*") if p.is_file())
    images = sum(p.stat().st_size for p in (ROOT / "images").glob("*.png"))
    assert total < 6e6 and images < 2e6


@pytest.mark.parametrize("item", ITEMS, ids=[i.id for i in ITEMS])
def test_item_passes_checker(item):
    result = check_item(item)
    assert result.ok, result.problems
    if item.kind == "text":
        assert result.required, f"{item.prompt!r} names nothing the planner knows"
