"""Layers: a module imports only its own package and the layers below it (lazy imports inside functions too).

    terrain (numpy), utils  <  sim, external_forces  <  envs  <  generation, evaluation, viewer  <  scripts

utils holds helpers for the layers above it and imports none of them. evaluation reads generation's spec
format (spec, validation, tools) but none of its backends or pipeline (models, images, planners).
"""

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "legged_gente"
LAYERS = {"terrain": 0, "utils": 0, "sim": 1, "external_forces": 1, "envs": 2, "generation": 3, "evaluation": 3,
          "viewer": 3, "scripts": 4, "benchmarks": 4}  # benchmarks/: the benchmark's build script
SIDEWAYS = {"evaluation": ("legged_gente.generation.spec", "legged_gente.generation.validation",
                           "legged_gente.generation.tools")}


def imported_modules(path: Path, root: Path):
    """(line, absolute module name) of every import in ``path`` (a file of the package at ``root``), relative
    imports resolved."""
    package = ".".join(("legged_gente",) + path.relative_to(root).parent.parts)
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            yield from ((node.lineno, alias.name) for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parent = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                base = f"{parent}.{base}" if base else parent
            # `from legged_gente.x import y` may import the module legged_gente.x.y
            yield from ((node.lineno, f"{base}.{alias.name}") for alias in node.names)


def layer_of(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if parts[0] == "legged_gente" and len(parts) > 1 and parts[1] in LAYERS else None


def upward_imports(root: Path = PACKAGE) -> list[str]:
    found = []
    for path in sorted(root.rglob("*.py")):
        relative = path.relative_to(root)
        if len(relative.parts) == 1:
            continue  # legged_gente/__init__.py
        own = relative.parts[0]
        assert own in LAYERS, f"{relative}: package {own!r} has no layer; add it to LAYERS (and ARCHITECTURE)"
        for line, module in imported_modules(path, root):
            target = layer_of(module)
            if target is None or target == own:
                continue
            sideways_ok = LAYERS[target] == LAYERS[own] and module.startswith(SIDEWAYS.get(own, ()))
            if LAYERS[target] >= LAYERS[own] and not sideways_ok:
                found.append(f"{relative}:{line} ({own}) imports {module} ({target})")
    return found


def test_no_module_imports_an_upper_layer():
    assert upward_imports() == []


def test_the_check_finds_upward_imports(tmp_path):
    """The check itself: an upward import, a lazy one, a relative one and a sideways backend import are found."""
    files = {"terrain/a.py": "def f():\n    from legged_gente.generation.spec import TerrainSpec\n",
             "utils/b.py": "from legged_gente.envs import task_registry\n",
             "evaluation/c.py": "from legged_gente.generation.backends.planner import find_cues\n"
                                "from legged_gente.generation.spec import TerrainSpec\n"
                                "from ..scripts import evaluate\n",
             "envs/d.py": "from legged_gente.terrain.terrain import Terrain\nfrom . import e\n"}
    for name, text in files.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text)
    assert upward_imports(tmp_path) == [
        "evaluation/c.py:1 (evaluation) imports legged_gente.generation.backends.planner.find_cues (generation)",
        "evaluation/c.py:3 (evaluation) imports legged_gente.scripts.evaluate (scripts)",
        "terrain/a.py:2 (terrain) imports legged_gente.generation.spec.TerrainSpec (generation)",
        "utils/b.py:1 (utils) imports legged_gente.envs.task_registry (envs)",
    ]


def test_evaluation_loads_no_generation_pipeline_at_run_time():
    """What the static scan cannot see: a package's __init__ importing its modules. Importing evaluation (which
    reads generation's spec format) must not load generation's pipeline or backends."""
    import subprocess
    import sys

    code = ("import sys, legged_gente.evaluation.benchmark, legged_gente.evaluation.evaluator; "
            "print(sorted(m for m in sys.modules if m.startswith('legged_gente.generation')))")
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert "legged_gente.generation.spec" in loaded, loaded
    for module in ("pipeline", "backends"):
        assert f"legged_gente.generation.{module}" not in loaded, loaded


def test_the_generation_package_still_exports_its_api():
    import legged_gente.generation as generation
    from legged_gente.generation.emit import emit
    from legged_gente.generation.pipeline import generate_spec

    assert generation.emit is emit and generation.generate_spec is generate_spec
    assert all(callable(getattr(generation, name)) for name in generation.__all__)
