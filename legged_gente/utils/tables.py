"""Tables of result rows (one dict per row) written as CSV."""

from __future__ import annotations

import csv
from pathlib import Path


def write_rows(path: str | Path, rows: list[dict]) -> Path:
    """``rows`` to a CSV at ``path`` (its folder made if missing): a header of the first row's keys, then one line
    per row."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return Path(path)
