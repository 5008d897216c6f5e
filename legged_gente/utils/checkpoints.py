"""Finding runs and checkpoints under logs/<experiment>/<date>_<run>/model_<iter>.pt."""

from __future__ import annotations

import re
from pathlib import Path


def _iteration(path: Path) -> int:
    match = re.fullmatch(r"model_(\d+)\.pt", path.name)
    return int(match.group(1)) if match else -1


def find_checkpoint(experiment_root: Path | None, load_run=-1, checkpoint=-1) -> Path:
    """The checkpoint file to load: the latest run and iteration unless named."""
    if experiment_root is None or not Path(experiment_root).is_dir():
        raise FileNotFoundError(f"no runs under {experiment_root}; train first or pass --experiment_name.")
    root = Path(experiment_root)
    runs = sorted(p for p in root.iterdir() if p.is_dir() and any(p.glob("model_*.pt")))
    if not runs:
        raise FileNotFoundError(f"no checkpoints (model_*.pt) in any run under {root}; train first.")
    if load_run in (-1, "-1", None):
        run = runs[-1]
    else:
        run = root / str(load_run)
        if not run.is_dir():
            raise FileNotFoundError(f"run {load_run!r} not found under {root}; runs: {[r.name for r in runs]}")
    models = sorted(run.glob("model_*.pt"), key=_iteration)
    if not models:
        raise FileNotFoundError(f"run {run} has no model_*.pt checkpoints.")
    if checkpoint in (-1, "-1", None):
        return models[-1]
    path = run / f"model_{checkpoint}.pt"
    if not path.is_file():
        raise FileNotFoundError(f"{path} not found; available: {[m.name for m in models]}")
    return path
