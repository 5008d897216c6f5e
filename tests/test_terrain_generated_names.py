"""What the terrain grid reports about generated tiles (docs/terrain.md)."""

import json

from legged_gente.terrain.terrain import Terrain


class GeneratedCfg:
    mesh_type = "heightfield"
    mode = "generated"
    resolution = 0.1
    border_size = 1.0
    terrain_length = 4.0
    terrain_width = 4.0
    num_rows = 1
    num_cols = 2
    terrain_types = []
    terrain_proportions = []
    selected_terrain = "flat"
    selected_params = {}
    max_difficulty = 1.0
    curriculum = False
    static_friction = 1.0
    seed = 0


def _spec(folder, name):
    """A spec.json as gente-generate writes it: every output folder holds a file of that same name."""
    folder.mkdir()
    document = {"version": 1, "name": name, "size_x": 4.0, "size_y": 4.0, "resolution": 0.1, "seed": 0,
                "calls": [{"tool": "flat", "region": "full", "params": {"height": 0.1}, "mode": "set"}],
                "source": {"text": name}, "backend": "planner", "model": None}
    (folder / "spec.json").write_text(json.dumps(document))
    return str(folder / "spec.json")


def test_generated_tiles_are_named_by_their_spec(tmp_path):
    # docs/terrain.md: tile_names holds "the entry (or spec name) of every tile"; two gente-generate outputs are
    # both spec.json, so the file name cannot tell them apart
    specs = [_spec(tmp_path / "forest", "forest_trail"), _spec(tmp_path / "city", "city_street")]

    class Cfg(GeneratedCfg):
        generated_specs = specs

    terrain = Terrain(Cfg, 2)
    assert terrain.tile_names.tolist() == [["forest_trail", "city_street"]]
    assert terrain.tile_type_names == ["forest_trail", "city_street"]
