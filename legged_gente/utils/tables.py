"""Tables of result rows (one dict per row) written as CSV, and the result archives (.npz) read back."""

from __future__ import annotations

import csv
import zipfile
from pathlib import Path

import numpy as np


def write_rows(path: str | Path, rows: list[dict]) -> Path:
    """``rows`` to a CSV at ``path`` (its folder made if missing): a header of the first row's keys, then one line
    per row."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return Path(path)


def open_npz(path: str | Path):
    """``np.load`` of a rollout or traces archive (never unpickling), or a one-line error naming the file."""
    if not Path(path).is_file():
        raise FileNotFoundError(f"{path}: no such file; give a rollout written by gente-view --record or a "
                                f"traces.npz written by gente-evaluate.")
    try:
        return np.load(path, allow_pickle=False)
    except (ValueError, OSError, EOFError, zipfile.BadZipFile):  # a text file, a truncated or foreign archive
        raise ValueError(f"{path} is not a readable NumPy .npz archive; give a rollout written by gente-view "
                         f"--record or a traces.npz written by gente-evaluate.") from None
