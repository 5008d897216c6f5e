"""tools/tile_edge_paths.py: where straight commanded paths leave their tile, and the step they meet there."""

import json

import numpy as np
import pytest


@pytest.fixture(scope="module")
def tool(load_file):
    return load_file("tools/tile_edge_paths.py")


def test_exit_times_by_hand(tool):
    start = np.array([[1.0, 1.0], [1.0, 1.0], [3.0, 2.0], [2.0, 2.0]])
    velocity = np.array([[1.0, 0.0], [-0.5, 0.25], [0.0, -1.0], [0.0, 0.0]])
    lo, hi = np.zeros((4, 2)), np.full((4, 2), 4.0)
    # +x from x=1 to the wall at 4: 3 s; -x at 0.5 m/s from x=1: 2 s (before +y at 0.25 m/s from y=1: 12 s);
    # -y from y=2: 2 s; standing still: never
    assert tool.exit_times(start, velocity, lo, hi).tolist() == [3.0, 2.0, 2.0, np.inf]


def _flat_spec(name: str, height: float) -> dict:
    return {"version": 1, "name": name, "size_x": 4.0, "size_y": 4.0, "resolution": 0.1, "seed": 0,
            "calls": [{"tool": "flat", "region": "full", "params": {"height": height}, "mode": "add"}],
            "source": {"text": name}, "backend": "test", "model": None}


def test_a_tile_two_metres_above_its_neighbour_is_a_two_metre_step_at_the_shared_edge(tool, tmp_path):
    """Two 4 m flat tiles side by side along y (the evaluation's 1 x 2 grid), the second 2 m higher, in the border
    at height 0. Every path of the high tile meets a 2 m drop wherever it leaves; a path of the low tile meets
    the 2 m rise only at the shared edge, and no step at the border. From a spawn point within the tile's
    central half, at >= 0.3 m/s, every path leaves within 2 m / (0.3 / sqrt(2)) m/s."""
    (tmp_path / "specs").mkdir()
    items = []
    for name, height in (("low", 0.0), ("high", 2.0)):
        (tmp_path / "specs" / f"{name}.json").write_text(json.dumps(_flat_spec(name, height)))
        items.append({"id": name, "kind": "text", "prompt": name, "spec": f"specs/{name}.json"})
    (tmp_path / "manifest.json").write_text(json.dumps({"name": "two", "tile_size": [4.0, 4.0], "resolution": 0.1,
                                                         "items": items}))
    r = tool.edge_paths(str(tmp_path), robots_per_terrain=32, seed=0)
    leave, step = r["leave"], r["step"]
    assert r["terrains"] == 2 and np.isfinite(leave).all() and (leave <= 2.0 / (0.3 / np.sqrt(2.0)) + 1e-6).all()
    high = step < -1.0
    assert np.allclose(step[high], -2.0) and np.allclose(step[~high][np.abs(step[~high]) > 1e-6], 2.0)
    assert high.sum() > 0 and (np.abs(step[~high]) > 1.0).sum() > 0 and (np.abs(step[~high]) < 1e-6).sum() > 0
