"""--terrain: plane, a generated spec JSON (any tile size), an emitted terrain_cfg.py, and bad input."""

import json

import pytest

from legged_gente.envs.gente_biped.gente_biped_config import GenteBipedCfg
from legged_gente.generation.emit import emit
from legged_gente.generation.pipeline import generate_spec
from legged_gente.terrain.terrain import Terrain
from legged_gente.envs.terrain_arg import apply_terrain_arg


@pytest.fixture(scope="module")
def emitted(tmp_path_factory):
    out = tmp_path_factory.mktemp("gen")
    spec, _ = generate_spec(text="a rocky beach with knee-deep water", image=None, backend="planner", seed=3,
                            size_x=20.0, size_y=12.0)
    emit(spec, out)
    return out


def test_spec_json_sets_its_own_tile_size(emitted):
    cfg = GenteBipedCfg()
    apply_terrain_arg(str(emitted / "spec.json"), cfg)
    assert (cfg.terrain.terrain_length, cfg.terrain.terrain_width) == (20.0, 12.0)
    terrain = Terrain(cfg.terrain, 4)
    assert terrain.material.has_water().any()


def test_emitted_module_replaces_the_terrain_cfg(emitted):
    cfg = GenteBipedCfg()
    apply_terrain_arg(str(emitted / "terrain_cfg.py"), cfg)
    assert cfg.terrain.mode == "generated" and cfg.terrain.num_rows == 1
    assert Terrain(cfg.terrain, 2).height_field.shape[0] > 200


def test_plane_and_bad_input():
    cfg = GenteBipedCfg()
    apply_terrain_arg("plane", cfg)
    assert cfg.terrain.mesh_type == "plane"
    with pytest.raises(FileNotFoundError, match="no such file"):
        apply_terrain_arg("missing.json", cfg)


@pytest.mark.parametrize("source, message", [
    ("x = (\n", ":1: SyntaxError: '(' was never closed"),
    ("import math\nimport nonexistent_mod\n", ":2: ModuleNotFoundError: No module named 'nonexistent_mod'"),
    ("\n\nraise RuntimeError('no')\n", ":3: RuntimeError: no"),
])
def test_a_terrain_module_that_fails_names_its_file_and_line(tmp_path, source, message):
    path = tmp_path / "terrain_cfg.py"
    path.write_text(source)
    with pytest.raises(ValueError) as error:
        apply_terrain_arg(str(path), GenteBipedCfg())
    assert str(error.value).startswith(f"--terrain {path}{message}") and "\n" not in str(error.value), error.value


def test_a_terrain_module_error_is_one_line_in_the_commands(tmp_path, capsys):
    from legged_gente.scripts import train as train_script

    path = tmp_path / "terrain_cfg.py"
    path.write_text("x = (\n")
    with pytest.raises(SystemExit) as exit_info:
        train_script.main(["--task", "gente_biped_flat", "--device", "cpu", "--num_envs", "1", "--terrain", str(path)])
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and "Traceback" not in err and f"--terrain {path}:1: SyntaxError" in err, err


def test_a_folder_names_the_files_to_pass(emitted):
    """gente-generate writes a folder: passing it says so and names the files in it, not 'no such file'."""
    with pytest.raises(ValueError) as error:
        apply_terrain_arg(str(emitted), GenteBipedCfg())
    message = str(error.value)
    assert "is a folder" in message and str(emitted / "spec.json") in message and "no such file" not in message


def test_a_module_with_several_terrain_classes_is_ambiguous(tmp_path):
    """Which of two terrain configs a module means cannot be guessed (inspect lists them by name, so the first
    in the alphabet would silently win)."""
    path = tmp_path / "terrain_cfg.py"
    path.write_text("from legged_gente.envs.base.legged_robot_config import LeggedRobotCfg\n\n"
                    "class Rough(LeggedRobotCfg.terrain):\n    mesh_type = 'heightfield'\n\n"
                    "class Rougher(Rough):\n    max_difficulty = 2.0\n")
    with pytest.raises(ValueError, match=r"defines 2 subclasses of LeggedRobotCfg.terrain \(Rough, Rougher\)"):
        apply_terrain_arg(str(path), GenteBipedCfg())


def test_a_spec_at_a_resolution_that_does_not_divide_the_border_builds(tmp_path):
    """gente-generate --resolution 0.15: the task's 5 m border is 33.3 cells of it; the border grows to whole cells
    (34 x 0.15 m = 5.1 m) instead of the terrain refusing a border size the user never set."""
    spec = {"size_x": 3.0, "size_y": 3.0, "resolution": 0.15, "seed": 0,
            "calls": [{"tool": "flat", "region": {"x0": 0.0, "y0": 0.0, "x1": 3.0, "y1": 3.0}, "params": {}}]}
    path = tmp_path / "spec.json"
    path.write_text(json.dumps(spec))
    cfg = GenteBipedCfg()
    assert cfg.terrain.border_size == 5.0
    apply_terrain_arg(str(path), cfg)
    assert cfg.terrain.border_size == pytest.approx(34 * 0.15)
    assert Terrain(cfg.terrain, 2).height_field.shape == (2 * 34 + 20,) * 2  # border, tile, border cells


def test_a_border_that_is_not_finite_is_refused_in_one_line(emitted):
    """The spec's border is widened to whole cells before the grid (whose own check names it) is built: an
    infinite border is refused there, naming the setting, not with an OverflowError."""
    cfg = GenteBipedCfg()
    cfg.terrain.border_size = float("inf")
    with pytest.raises(ValueError, match=r"terrain.border_size=inf m must be a finite number of metres"):
        apply_terrain_arg(str(emitted / "spec.json"), cfg)


@pytest.mark.parametrize("change, problem", [
    ({"calls": {}}, "spec: field 'calls': {} is not of type 'array'."),
    ({"colour": "red"}, "spec: field '(document)': Additional properties are not allowed ('colour' was unexpected)."),
    ({"smothing": []}, "spec: field '(document)': Additional properties are not allowed ('smothing' was unexpected)."),
    ({"resolution": "0.1"}, "spec: field 'resolution': '0.1' is not of type 'number'."),
])
def test_a_spec_json_that_departs_from_the_format_is_refused(emitted, tmp_path, change, problem):
    """Training read spec.json loosely: calls {} trained on a flat tile, a misspelt or extra field was dropped
    unseen, a quoted number was read as one, where TerrainSpec.load refuses all of them."""
    document = {**json.loads((emitted / "spec.json").read_text()), **change}
    path = tmp_path / "spec.json"
    path.write_text(json.dumps(document))
    with pytest.raises(ValueError) as refused:
        apply_terrain_arg(str(path), GenteBipedCfg())
    assert str(refused.value) == (f"--terrain {path}: not a terrain spec document: {problem} Fix the file, or pass a "
                                  f"spec.json written by gente-generate")


def test_a_set_of_the_tile_size_against_a_generated_module_is_refused_naming_the_set(emitted):
    """A terrain_cfg.py of gente-generate repeats its spec's tile size: --set terrain.terrain_length=10.0 with it
    failed later, at the tile's build, with a cell count that did not name the --set."""
    from legged_gente.envs.task_registry import apply_terrain_with_overrides

    cfg = GenteBipedCfg()
    with pytest.raises(ValueError, match=r"generated terrain whose spec sets terrain.terrain_length to 20.0; leave "
                                         r"out --set terrain.terrain_length=10.0"):
        apply_terrain_with_overrides(str(emitted / "terrain_cfg.py"), cfg, ["terrain.terrain_length=10.0"])
    cfg = GenteBipedCfg()
    apply_terrain_with_overrides(str(emitted / "terrain_cfg.py"), cfg, ["terrain.num_rows=2"])  # others apply
    assert cfg.terrain.num_rows == 2 and cfg.terrain.terrain_length == 20.0


@pytest.mark.parametrize("height, said", [
    ("[" * 100000 + "0" + "]" * 100000, "is nested too deeply to read"),
    ("1" + "0" * 5000, "holds an integer of more than 4300 digits; use a number below 2**53"),
])
def test_a_spec_python_cannot_parse_is_one_line_naming_the_file(tmp_path, height, said):
    """--terrain (train, play, view) and a generated terrain's spec read JSON themselves: a spec nested 100000 deep
    was a RecursionError traceback, an integer of 5000 digits Python's advice to call sys.set_int_max_str_digits."""
    path = tmp_path / "spec.json"
    path.write_text('{"size_x": 2.0, "size_y": 2.0, "resolution": 0.1, "seed": 0, "calls": [{"tool": "flat", '
                    '"region": "full", "params": {"height": ' + height + '}}]}')
    with pytest.raises(ValueError) as error:
        apply_terrain_arg(str(path), GenteBipedCfg())
    assert str(error.value).startswith(f"--terrain {path} {said}") and "set_int_max_str_digits" not in str(error.value)
    cfg = GenteBipedCfg()
    cfg.terrain.mode, cfg.terrain.generated_specs, cfg.terrain.num_rows, cfg.terrain.num_cols = \
        "generated", [str(path)], 1, 1
    cfg.terrain.terrain_length = cfg.terrain.terrain_width = 2.0
    with pytest.raises(ValueError, match=f"terrain spec {path} {said}".replace("*", r"\*")):
        Terrain(cfg.terrain, 1)
