"""Packaging: every third-party import is declared, the shipped data is package data found from any directory,
and the README's two commands are the ones CI runs."""

import ast
import fnmatch
import re
import shutil
import sys
from importlib import metadata
from pathlib import Path

import pytest

try:
    import tomllib
except ImportError:  # Python 3.10
    import tomli as tomllib

from legged_gente.envs import task_registry
from legged_gente.evaluation.benchmark import load_benchmark
from legged_gente.sim.assembly import resolve_path

REPO = Path(__file__).resolve().parents[1]
PACKAGE = REPO / "legged_gente"
PYPROJECT = tomllib.loads((REPO / "pyproject.toml").read_text())
WRITTEN_BY_TESTS = {"my_robot_config", "my_robot_tasks"}  # the robot tutorial's modules, written from docs/new_robot.md


def distribution_name(requirement: str) -> str:
    return re.split(r"[<>=!~\[; ]", requirement, maxsplit=1)[0].strip().lower().replace("_", "-")


def third_party_imports(files) -> dict[str, str]:
    """Top-level module -> first place it is imported, for every absolute import that is not stdlib or ours."""
    local = {f.stem for f in files} | WRITTEN_BY_TESTS  # tests import their siblings
    found = {}
    for f in files:
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            else:
                continue
            for name in names:
                top = name.split(".")[0]
                if top not in sys.stdlib_module_names and top != "legged_gente" and top not in local:
                    found.setdefault(top, f"{f.relative_to(REPO)}:{node.lineno}")
    return found


@pytest.mark.parametrize("where, extras", [("legged_gente", []), ("tests", ["test"])])
def test_every_third_party_import_is_declared(where, extras):
    """A fresh `pip install` installs only what pyproject.toml declares: an import of anything else fails there."""
    declared = {distribution_name(r) for r in PYPROJECT["project"]["dependencies"]}
    for extra in extras:
        declared |= {distribution_name(r) for r in PYPROJECT["project"]["optional-dependencies"][extra]}
    providers = metadata.packages_distributions()
    undeclared = {module: place for module, place in third_party_imports(sorted((REPO / where).rglob("*.py"))).items()
                  if not declared & {d.lower().replace("_", "-") for d in providers.get(module, [module])}}
    assert not undeclared, f"imported but not declared in pyproject.toml (module: first import): {undeclared}"


def shipped(relative: str) -> bool:
    return any(fnmatch.fnmatch(relative, pattern) for pattern in PYPROJECT["tool"]["setuptools"]["package-data"]["legged_gente"])


def test_shipped_files_are_package_data():
    """What the tasks and the evaluation read from the package is in the wheel's package-data globs."""
    assert (PACKAGE / "py.typed").is_file() and shipped("py.typed")
    for name in task_registry.task_registry.tasks:
        env_cfg, _ = task_registry.task_registry.get_cfgs(name)
        path = resolve_path(env_cfg.asset.file)
        assert path.is_relative_to(PACKAGE) and shipped(str(path.relative_to(PACKAGE))), (name, path)
    items = load_benchmark(PACKAGE / "benchmarks" / "gente100")
    assert len(items) == 100
    needed = ["benchmarks/gente100/manifest.json"] + [str(i.spec_path.relative_to(PACKAGE)) for i in items]
    needed += [str(i.image.relative_to(PACKAGE)) for i in items if i.image]
    assert [n for n in needed if not shipped(n)] == []


def test_flat_benchmark_is_one_flat_tile():
    """`--benchmark flat` (the tracking-error-on-flat measurement): one 20 m tile, every height 0, no material."""
    (item,) = load_benchmark("flat")
    heights, materials = item.spec().build()
    assert heights.shape == (200, 200) and not heights.any()
    assert shipped("benchmarks/flat/manifest.json") and shipped(str(item.spec_path.relative_to(PACKAGE)))
    assert not materials.has_water().any() and not materials.has_soil().any() and (materials.friction == 1.0).all()


def test_shipped_data_is_found_from_any_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    biped = "resources/robots/gente_biped/gente_biped.xml"
    assert resolve_path(biped) == PACKAGE / biped
    assert [i.id for i in load_benchmark("gente100")] == [i.id for i in load_benchmark("benchmarks/gente100")]
    # a user's own file at the same relative path wins over the shipped one
    (tmp_path / biped).parent.mkdir(parents=True)
    shutil.copy(PACKAGE / biped, tmp_path / biped)
    assert resolve_path(biped) == Path(biped)
    with pytest.raises(FileNotFoundError, match="robot file 'my_robot.xml' not found"):
        resolve_path("my_robot.xml")
    with pytest.raises(FileNotFoundError, match=r"shipped benchmark: \['flat', 'gente100', 'gente_original', 'gente_val', 'steps'\]"):
        load_benchmark("gente1000")


def test_readme_gives_the_two_commands_ci_runs():
    """The README opens with exactly two commands, each creating its own environment; .ci/run runs the second."""
    readme = (REPO / "README.md").read_text()
    block = readme.split("```bash\n", 1)[1].split("```", 1)[0].splitlines()
    commands = [line for line in block if not line.startswith("#")]
    setup = "python3 -m venv .venv && . .venv/bin/activate && pip install torch==2.13.0 && "
    assert len(commands) == 2 and all(c.startswith(setup) for c in commands), block
    assert commands[0].endswith("gente-train --task=gente_biped --headless")
    assert commands[1].endswith('pip install -e ".[test]" && python -m pytest -q')
    assert block[block.index(commands[1]) - 1] == "# set up and run the tests (CPU)"
    assert "grep -A1 -x '# set up and run the tests (CPU)' README.md" in (REPO / ".ci" / "run").read_text()


def test_steps_benchmark_is_a_pit_in_ground_raised_by_each_height():
    """`--benchmark steps`: nine 20 m tiles; the pit at the centre lies at 0 (its walls at 9 m and 11 m blend over
    the composition's 0.3 m seam band into it, so its floor is cells 92-107 at 0.1 m), the ground 1.5 m and more
    off the centre in every direction at the item's height, 0.10 to 0.50 m."""
    items = load_benchmark("steps")
    assert [i.id for i in items] == [f"step_{cm}cm" for cm in (10, 15, 20, 25, 30, 35, 40, 45, 50)]
    for item, height in zip(items, (0.10, 0.15, 0.20, 0.25, 0.30, 0.35, 0.40, 0.45, 0.50)):
        heights, materials = item.spec().build()
        assert heights.shape == (200, 200)
        assert not heights[92:108, 92:108].any() and heights[91, 100] > 0.0 and heights[108, 100] > 0.0
        for i, j in ((85, 100), (115, 100), (100, 85), (100, 115), (85, 85), (115, 115), (0, 0), (199, 199)):
            assert heights[i, j] == pytest.approx(height)
        assert not materials.has_water().any() and not materials.has_soil().any()
        assert shipped(str(item.spec_path.relative_to(PACKAGE)))
    assert shipped("benchmarks/steps/manifest.json")
