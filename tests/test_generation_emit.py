"""Emitted terrain modules rebuild the identical heightfield; the CLI writes files and rejects bad input."""

from __future__ import annotations

import numpy as np
import pytest

from legged_gente.generation.emit import DEFAULT_BASE, class_name_for, emit, load_module
from legged_gente.generation.pipeline import generate_spec
from legged_gente.generation.spec import TerrainSpec
from legged_gente.scripts.generate import main


def test_emitted_module_imports_and_rebuilds_identically(tmp_path):
    spec, _ = generate_spec("a forest trail by a knee-deep stream", seed=5, size_x=10.0, size_y=10.0)
    assert spec.name == "forest_trail_by_knee"
    out = emit(spec, tmp_path / "forest")
    assert out.class_name == "ForestTrailByKneeTerrainCfg" and out.preview.stat().st_size > 1000
    module = load_module(out.module)
    cfg = getattr(module, out.class_name)
    base_module, attr = DEFAULT_BASE.split(":")
    import importlib

    base = importlib.import_module(base_module)
    for part in attr.split("."):
        base = getattr(base, part)
    assert issubclass(cfg, base) and cfg.mode == "generated" and cfg.mesh_type == "heightfield"
    assert cfg.terrain_length == 10.0 and TerrainSpec.load(cfg.generated_specs[0]) == spec
    h_mod, m_mod = module.build()
    h_ref, m_ref = spec.build()
    assert np.array_equal(h_mod, h_ref) and np.array_equal(m_mod.water_surface, m_ref.water_surface)
    # the terrain grid built from the emitted config holds the same tile
    from legged_gente.terrain.terrain import Terrain

    terrain = Terrain(cfg, num_robots=1)
    b = (terrain.height_field.shape[0] - h_ref.shape[0]) // 2
    np.testing.assert_array_equal(terrain.height_field[b:b + h_ref.shape[0], b:b + h_ref.shape[1]], h_ref)


def test_emit_with_a_stand_in_base_and_bad_bases(tmp_path, monkeypatch):
    (tmp_path / "standin_cfg.py").write_text("class Task:\n    class terrain:\n        mode = 'plane'\n        resolution = 0.1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    spec, _ = generate_spec("stairs", size_x=4.0, size_y=4.0)
    out = emit(spec, tmp_path / "o", base="standin_cfg:Task.terrain", class_name="StairsCfg")
    cfg = load_module(out.module).StairsCfg
    assert cfg.__mro__[1].__qualname__ == "Task.terrain" and cfg.mode == "generated"
    with pytest.raises(ValueError, match="cannot be imported"):
        emit(spec, tmp_path / "p", base="no_such_module_xyz:Cfg")
    with pytest.raises(ValueError, match="has no attribute 'nope'"):
        emit(spec, tmp_path / "p", base="standin_cfg:Task.nope")
    assert class_name_for("forest_trail") == "ForestTrailTerrainCfg"


def test_cli(tmp_path, capsys):
    assert main(["--text", "a rocky beach with waves", "--out", str(tmp_path / "beach"), "--size", "10"]) == 0
    out = capsys.readouterr().out
    assert "water(" in out and "wrote" in out and (tmp_path / "beach" / "spec.json").exists()
    assert TerrainSpec.load(tmp_path / "beach" / "spec.json").size_x == 10.0
    with pytest.raises(SystemExit):
        main(["--out", str(tmp_path / "x")])
    assert "give --text, --image, or both" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["--text", "x", "--backend", "openai", "--out", str(tmp_path / "x")])
    assert "needs --base-url and --model" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["--text", "x", "--size", "-3", "--out", str(tmp_path / "x")])
    assert "must be > 0" in capsys.readouterr().err
    # a size that is not a whole number of cells: a clear error, exit code 1
    assert main(["--text", "hills", "--size", "10.05", "--out", str(tmp_path / "y")]) == 1
    assert "multiples of the resolution" in capsys.readouterr().err
