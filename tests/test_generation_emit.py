"""Emitted terrain modules rebuild the identical heightfield; the CLI writes files and rejects bad input."""

from __future__ import annotations

import numpy as np
import pytest

from test_generation_openai import FakeServer, _completion, _png_bytes, ok

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
    (tmp_path / "standin_cfg.py").write_text(
        "from legged_gente.envs.base.legged_robot_config import LeggedRobotCfg\n"
        "class Task:\n    class terrain(LeggedRobotCfg.terrain):\n        mode = 'plane'\n        resolution = 0.1\n"
        "    class env:\n        num_envs = 2\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    spec, _ = generate_spec("stairs", size_x=4.0, size_y=4.0)
    out = emit(spec, tmp_path / "o", base="standin_cfg:Task.terrain", class_name="StairsCfg")
    cfg = load_module(out.module).StairsCfg
    assert cfg.__mro__[1].__qualname__ == "Task.terrain" and cfg.mode == "generated"
    with pytest.raises(ValueError, match="cannot be imported"):
        emit(spec, tmp_path / "p", base="no_such_module_xyz:Cfg")
    with pytest.raises(ValueError, match="has no attribute 'nope'"):
        emit(spec, tmp_path / "p", base="standin_cfg:Task.nope")
    with pytest.raises(ValueError, match="is not a terrain config"):  # training would refuse the emitted class
        emit(spec, tmp_path / "p", base="standin_cfg:Task.env")
    assert class_name_for("forest_trail") == "ForestTrailTerrainCfg"
    assert class_name_for("generated_terrain") == "GeneratedTerrainCfg"  # not GeneratedTerrainTerrainCfg


def test_a_name_from_text_skips_leading_numbers():
    """A prompt that starts with a number names its spec by its first word (a name must start with a letter):
    "123 rivers" was "generated_terrain", "3 small ponds" likewise."""
    from legged_gente.generation.spec import spec_name

    assert spec_name("123 rivers") == "rivers"
    assert spec_name("3 small ponds and a bridge") == "small_ponds_and_bridge"
    assert spec_name("2024") == "generated_terrain"
    assert class_name_for(spec_name("123 rivers")) == "RiversTerrainCfg"


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


def _flag_error(capsys, argv) -> str:
    """The error line of a refused command line (exit status 2; argparse prints its usage above it)."""
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and "Traceback" not in err, err
    return err.strip().splitlines()[-1]


@pytest.mark.parametrize("flags, message", [
    (["--timeout", "inf"], "argument --timeout: must be > 0 and at most 86400, got inf"),
    (["--timeout", "nan"], "argument --timeout: must be > 0 and at most 86400, got nan"),
    (["--timeout", "1e10"], "argument --timeout: must be > 0 and at most 86400, got 1e10"),
    (["--size", "inf"], "argument --size: must be > 0 and finite, got inf"),
    (["--size", "nan"], "argument --size: must be > 0 and finite, got nan"),
    (["--resolution", "nan"], "argument --resolution: must be > 0 and finite, got nan"),
    (["--size", "1000"], "--size 1000: must be in [1, 200]."),
    (["--resolution", "0.01"], "--resolution 0.01: must be in [0.02, 1]."),
    (["--size", "10.05"], "--size 10.05 with --resolution 0.1: the 10.05 m x 10.05 m tile is not a whole number of "
                          "0.1 m cells; pick sizes that are multiples of the resolution."),
    (["--size", "200", "--resolution", "0.02"], "--size 200 with --resolution 0.02: the 200 m x 200 m tile at 0.02 m "
                                                "has 100000000 cells; the limit is 4000000 (e.g. 200 m x 200 m at 0.1 m): "
                                                "use a coarser resolution or a smaller tile."),
    (["--text", "x" * 10_001], "--text: has 10001 characters; at most 10000 are allowed."),
    (["--model", "m" * 257], "--model: has 257 characters; at most 256 are allowed."),
    (["--name", "x" * 65], "--name: has 65 characters; at most 64 are allowed."),
    (["--name", "caf\u00e9"], "--name: must be a letter, then letters, digits or underscores, e.g. forest_trail."),
    (["--name", "forest\n"], "--name: must be a letter, then letters, digits or underscores, e.g. forest_trail."),
])
def test_flags_are_checked_against_the_spec_before_any_request(tmp_path, capsys, flags, message):
    with FakeServer([]) as srv:
        line = _flag_error(capsys, ["--text", "a field", "--backend", "openai", "--base-url", srv.url, "--model", "m",
                                    "--out", str(tmp_path / "o"), *flags])
    assert line == f"gente-generate: error: {message}"
    assert srv.requests == [] and not (tmp_path / "o").exists()


@pytest.mark.parametrize("flag", [["--timeout", "5"], ["--max-retries", "1"], ["--api-key-env", "MY_KEY"]])
def test_the_planner_refuses_the_model_servers_flags(tmp_path, capsys, flag):
    """They were accepted and ignored by the default (offline) planner: a run that did not do what was asked."""
    line = _flag_error(capsys, ["--text", "hills", "--out", str(tmp_path / "o"), *flag])
    assert line == (f"gente-generate: error: {flag[0]} is for --backend openai (the planner sends no request); leave "
                    f"it out or add --backend openai.")
    assert not (tmp_path / "o").exists()


def test_a_malformed_api_key_is_refused_and_never_printed(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("MY_KEY", "sk-SECRET-1234567890\n")
    with FakeServer([]) as srv:
        code = main(["--text", "a field", "--backend", "openai", "--base-url", srv.url, "--model", "m",
                     "--api-key-env", "MY_KEY", "--out", str(tmp_path / "o")])
    captured = capsys.readouterr()
    assert code == 2 and srv.requests == [] and "SECRET" not in captured.out + captured.err
    assert captured.err == ("gente-generate: error: the API key in the environment variable MY_KEY holds whitespace, "
                            "control or non-ASCII characters (a trailing newline?); set MY_KEY to the key alone.\n")


def test_model_text_reaches_the_terminal_escaped(tmp_path, capsys):
    image = tmp_path / "lake.png"
    image.write_bytes(_png_bytes())
    description = _completion(content="\x1b[2J\x1b]0;title\x07 a lake\nand a \u202eshore")
    reply = _completion([{"id": "c0", "type": "function",
                          "function": {"name": "flat", "arguments": '{"height": 0.0, "region": "full"}'}}])
    with FakeServer([ok(description), ok(reply)]) as srv:
        code = main(["--image", str(image), "--backend", "openai", "--base-url", srv.url, "--model", "m",
                     "--two-phase", "--out", str(tmp_path / "o")])
    out = capsys.readouterr().out
    assert code == 0 and "\x1b" not in out and "\u202e" not in out
    assert out.splitlines()[0] == r"note: image description (m): \x1b[2J\x1b]0;title\x07 a lake\nand a \u202eshore"


def test_a_long_text_gives_a_name_the_spec_accepts(tmp_path):
    assert main(["--text", "a " + "x" * 100, "--out", str(tmp_path / "o")]) == 0
    assert TerrainSpec.load(tmp_path / "o" / "spec.json").name == "x" * 64


def test_a_non_ascii_prompt_is_written_as_utf8_whatever_the_locale(tmp_path):
    """Under LC_ALL=C without UTF-8 mode, the emitted module is still UTF-8 Python that imports and keeps the prompt."""
    import os
    import subprocess
    import sys

    prompt = "a caf\u00e9 plaza with stairs \u2014 \u00fcber \u6c34"
    code = f"from legged_gente.scripts.generate import main; raise SystemExit(main(['--text', {ascii(prompt)}, '--out', {ascii(str(tmp_path / 'o'))}]))"
    env = os.environ | {"LC_ALL": "C", "PYTHONUTF8": "0", "PYTHONIOENCODING": ""}
    run = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, errors="replace", timeout=300)
    assert run.returncode == 0, run.stderr
    module = tmp_path / "o" / "terrain_cfg.py"
    module.read_bytes().decode("utf-8")
    assert load_module(module).PROVENANCE["source"] == prompt
    assert TerrainSpec.load(tmp_path / "o" / "spec.json").source["text"] == prompt


@pytest.mark.parametrize("failing", ["save_preview", "save_mesh"])
def test_a_failed_emit_leaves_no_partial_file(tmp_path, monkeypatch, failing):
    import importlib

    emit_module = importlib.import_module("legged_gente.generation.emit")  # the package's ``emit`` is the function

    def fail(*args, **kwargs):
        raise OSError("No space left on device")

    monkeypatch.setattr(emit_module, failing, fail)
    spec, _ = generate_spec("stairs", size_x=4.0, size_y=4.0)
    with pytest.raises(OSError, match="No space left"):
        emit(spec, tmp_path / "new" / "o", mesh="obj")
    assert not (tmp_path / "new").exists()  # the folders the emit made above its own too
    old = tmp_path / "old"
    old.mkdir()
    (old / "spec.json").write_text("the earlier terrain")
    with pytest.raises(OSError, match="No space left"):
        emit(spec, old, mesh="obj")
    assert [p.name for p in old.iterdir()] == ["spec.json"] and (old / "spec.json").read_text() == "the earlier terrain"


def test_bad_input_is_refused_before_any_request(tmp_path, capsys):
    """An unreadable image, a bad --base and an --out that cannot be written: exit 2, one line, and the model is never
    asked."""
    image = tmp_path / "photo.png"
    image.write_text("not an image")
    (tmp_path / "FILE").write_text("")
    cases = [
        (["--image", str(image)], f"gente-generate: error: --image: {image} could not be read as an image "
                                  f"(UnidentifiedImageError); pass a PNG or JPEG file."),
        (["--text", "x", "--base", "no_such_module_xyz:Cfg"],
         "gente-generate: error: --base: base module 'no_such_module_xyz' cannot be imported (No module named "
         "'no_such_module_xyz'); pass --base with an importable module."),
        (["--text", "x", "--base", "os; import sys:Cfg"],
         "gente-generate: error: --base: base 'os; import sys:Cfg' must look like 'package.module:Class.nested'; "
         f"e.g. {DEFAULT_BASE!r}."),
        (["--text", "x", "--base", "zipfile:Path"],  # a class the emitted module's own Path import would lose
         "gente-generate: error: --base: base 'zipfile:Path' is reached through the name 'Path', which the emitted "
         "module binds itself (['Path', 'SPEC_PATH', 'PROVENANCE', 'build']); pass a class reached through another "
         "name."),
        (["--text", "x", "--out", str(tmp_path / "FILE" / "o")],
         f"gente-generate: error: --out {tmp_path / 'FILE' / 'o'}: {tmp_path / 'FILE'} is a file; give a folder "
         f"to write to"),
        # as a path "" is the current folder, whose files the emitted ones would replace
        (["--text", "x", "--out", ""], "gente-generate: error: --out is empty; give a folder"),
        # /proc's permission bits let root write, yet nothing can be made there: refused before, not after, asking
        (["--text", "x", "--out", "/proc/gente_terrain"],
         "gente-generate: error: --out /proc/gente_terrain: nothing can be created in /proc (No such file or "
         "directory); give a folder you can write to"),
        (["--text", "x", "--base", "legged_gente.envs.gente_biped.gente_biped_config:GenteBipedCfg.env"],
         "gente-generate: error: --base: base 'legged_gente.envs.gente_biped.gente_biped_config:GenteBipedCfg.env' "
         f"is not a terrain config (a subclass of LeggedRobotCfg.terrain); pass a task's terrain class, e.g. "
         f"{DEFAULT_BASE!r}."),
    ]
    for flags, message in cases:
        with FakeServer([]) as srv:
            line = _flag_error(capsys, ["--backend", "openai", "--base-url", srv.url, "--model", "m",
                                        "--out", str(tmp_path / "o"), *flags])
        assert line == message and srv.requests == []
    assert not (tmp_path / "o").exists()


def test_an_emitted_config_at_a_resolution_that_does_not_divide_the_border_builds(tmp_path):
    """The base's 5 m border is 33.3 cells of 0.15 m: the emitted class lays it in whole cells, 34 x 0.15 = 5.1 m."""
    from legged_gente.terrain.terrain import Terrain

    spec, _ = generate_spec("stairs", size_x=6.0, size_y=6.0, resolution=0.15)
    out = emit(spec, tmp_path / "stairs")
    cfg = getattr(load_module(out.module), out.class_name)
    assert cfg.border_size == pytest.approx(34 * 0.15)
    terrain = Terrain(cfg, num_robots=1)
    assert terrain.height_field.shape == (40 + 2 * 34, 40 + 2 * 34)  # 6 m = 40 cells, and the border on each side
