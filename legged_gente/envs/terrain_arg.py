"""The --terrain flag: 'plane', a generated terrain spec (JSON) or an emitted terrain_cfg.py module."""

from __future__ import annotations

import importlib.util
import inspect
import math
import traceback
from pathlib import Path

from legged_gente.envs.base.legged_robot_config import LeggedRobotCfg
from legged_gente.terrain.composition import read_json, tile_spec_from_document
from legged_gente.terrain.terrain import whole_cells


def apply_terrain_arg(value: str, env_cfg) -> None:
    if value == "plane":
        env_cfg.terrain.mesh_type = "plane"
        return
    path = Path(value)
    if path.is_dir():  # gente-generate's output folder: name the files in it that --terrain takes
        inside = [str(path / name) for name in ("spec.json", "terrain_cfg.py") if (path / name).is_file()]
        raise ValueError(f"--terrain {value} is a folder; pass a file: "
                         + (" or ".join(inside) if inside else "a spec .json or a terrain_cfg.py"))
    if not path.is_file():
        raise FileNotFoundError(f"--terrain {value!r}: no such file; pass 'plane', a spec .json or a terrain_cfg.py")
    if path.suffix.lower() == ".json":
        try:
            document = read_json(path.read_text(), f"--terrain {value}")
        except UnicodeDecodeError as exc:
            raise ValueError(f"--terrain {value} is not valid JSON ({exc}); pass a spec.json written by "
                             f"gente-generate") from None
        except ValueError as exc:
            raise ValueError(f"{exc}; pass a spec.json written by gente-generate") from None
        try:  # the terrain takes the spec's own tile size and resolution; its calls are checked when it is built
            spec = tile_spec_from_document(document, path.parent)
        except ValueError as exc:
            raise ValueError(f"--terrain {value}: {exc}") from None
        terrain = env_cfg.terrain
        terrain.mesh_type, terrain.mode, terrain.curriculum = "heightfield", "generated", False
        terrain.generated_specs = [str(path.resolve())]
        terrain.terrain_length, terrain.terrain_width = float(spec.size_x), float(spec.size_y)
        terrain.resolution = float(spec.resolution)
        # the flat border around the tile is laid in the spec's cells: widened (by less than a cell) to whole ones
        if not math.isfinite(terrain.border_size):
            raise ValueError(f"terrain.border_size={terrain.border_size} m must be a finite number of metres; set "
                             f"it (--set terrain.border_size=<m>)")
        terrain.border_size = whole_cells(terrain.border_size, terrain.resolution)
        terrain.num_rows = terrain.num_cols = 1
        return
    if path.suffix.lower() == ".py":
        spec = importlib.util.spec_from_file_location(f"gente_terrain_{abs(hash(path.resolve()))}", path)
        module = importlib.util.module_from_spec(spec)
        try:
            spec.loader.exec_module(module)
        except Exception as exc:  # the user's module: its error, with its line
            raise ValueError(f"--terrain {value}:{_error_line(exc, path)}; fix the module or emit it again with "
                             f"gente-generate") from None
        classes = [c for _, c in inspect.getmembers(module, inspect.isclass)
                   if c.__module__ == module.__name__ and issubclass(c, LeggedRobotCfg.terrain)]
        if not classes:
            raise ValueError(f"--terrain {value}: the module defines no subclass of LeggedRobotCfg.terrain")
        if len(classes) > 1:  # which one is meant cannot be guessed
            names = ", ".join(c.__name__ for c in classes)
            raise ValueError(f"--terrain {value}: the module defines {len(classes)} subclasses of "
                             f"LeggedRobotCfg.terrain ({names}); keep only the one to train on")
        env_cfg.terrain = classes[0]()
        return
    if path.suffix.lower() == ".npy":
        raise ValueError(f"--terrain {value}: a bare heightmap has no cell size or height scale; pass a spec .json "
                         f"naming it: {{..., \"resolution\": <cell m>, \"heightmap\": {{\"file\": \"{path.name}\", "
                         f"\"vertical_scale\": <m per unit>}}}} (docs/terrain.md)")
    raise ValueError(f"--terrain {value!r}: expected 'plane', a .json spec or a .py terrain config module")


def _error_line(exc: Exception, path: Path) -> str:
    """``line: Error: message`` of ``exc``, raised by the module ``path``: a SyntaxError in it at its own line,
    else at the module's last line in the traceback ('?' if none)."""
    if isinstance(exc, SyntaxError) and exc.filename and Path(exc.filename).resolve() == path.resolve():
        return f"{exc.lineno}: SyntaxError: {exc.msg}"
    lines = [frame.lineno for frame in traceback.extract_tb(exc.__traceback__)
             if Path(frame.filename).resolve() == path.resolve()]
    return f"{lines[-1] if lines else '?'}: {type(exc).__name__}: {exc}"
