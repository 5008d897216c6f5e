"""The small shipped benchmarks, flat and steps: their manifests load and every spec they list validates and builds."""

import json

import numpy as np
import pytest

from legged_gente.evaluation.benchmark import SHIPPED, load_benchmark, tile_geometry
from legged_gente.generation.checker import check_item

STEPS = [10, 15, 20, 25, 30, 35, 40, 45, 50]  # cm, the step up out of the pit of item step_<cm>cm


@pytest.mark.parametrize("name", ["flat", "steps"])
def test_manifest_lists_every_spec_once_at_its_declared_geometry(name):
    manifest = json.loads((SHIPPED / name / "manifest.json").read_text())
    items = load_benchmark(name)
    assert len({i.id for i in items}) == len(items)
    assert sorted(i.spec_path.name for i in items) == sorted(p.name for p in (SHIPPED / name / "specs").glob("*.json"))
    specs = [i.spec() for i in items]  # TerrainSpec.load validates each
    assert [s.name for s in specs] == [i.id for i in items]
    assert tile_geometry(specs) == (*manifest["tile_size"], manifest["resolution"]) == (20.0, 20.0, 0.1)


def test_flat_builds_flat_ground():
    (item,) = load_benchmark("flat")
    heights, material = item.spec().build()
    assert heights.shape == (200, 200) and not heights.any()
    assert not material.has_water().any() and not material.has_soil().any()


@pytest.mark.parametrize("cm", STEPS)
def test_step_item_is_a_2_m_pit_in_raised_ground(cm):
    """Ground at cm / 100 m everywhere but a 2 m pit at 0 m at the tile centre (x, y in 9..11 m: cells 90..109);
    the pit's seam band (0.3 m) leaves its middle cells and the far ground exact."""
    (item,) = load_benchmark("steps", [f"step_{cm}cm"])
    assert check_item(item).ok
    heights, _ = item.spec().build()
    assert np.all(heights[94:106, 94:106] == 0.0)
    assert heights[0, 0] == heights[199, 199] == heights[100, 20] == np.float32(cm / 100)


@pytest.mark.parametrize("name", ["gente100", "gente_val"])
def test_the_shipped_specs_are_what_the_planners_build_now(name):
    """docs/evaluation.md: build.py rebuilds the benchmark from its prompts and pictures. A change to the planners
    that changes a shipped item changes the benchmark scores are reported on (a JPEG fix once dropped thin sketch
    features and rewrote four sketch items): every item's spec must come out again as shipped."""
    import importlib.util
    import sys

    from legged_gente.generation.pipeline import generate_spec

    path = SHIPPED / "gente100" / "build.py"
    build = importlib.util.module_from_spec(spec := importlib.util.spec_from_file_location("gente100_build", path))
    sys.modules["gente100_build"] = build  # its dataclasses look their module up
    spec.loader.exec_module(build)
    plan, root = build.SETS[name], SHIPPED / name
    manifest = json.loads((root / "manifest.json").read_text())
    texts = [i for i in manifest["items"] if i["kind"] == "text"]
    images = [i for i in manifest["items"] if i["kind"] == "image"]
    for seed, item in [(plan.text_seed + k, i) for k, i in enumerate(texts)] + \
                      [(plan.image_seed + k, i) for k, i in enumerate(images)]:
        source = {"image": root / item["image"]} if item["kind"] == "image" else {"text": item["prompt"]}
        made, _ = generate_spec(**source, seed=seed, size_x=build.TILE, size_y=build.TILE,
                                resolution=build.RESOLUTION, name=item["id"])
        shipped = json.loads((root / item["spec"]).read_text())
        assert made.to_dict()["calls"] == shipped["calls"], item["id"]
