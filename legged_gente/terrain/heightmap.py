"""A heightmap array (``.npy``) as the ground of a tile: its units stated, its integer overflow detected.

A heightmap is a 2-D array, axis 0 along x and axis 1 along y, one value per cell of the tile's ``resolution``
(the cell size); a value times ``vertical_scale`` is the height in metres. GenTe's maps are int16 with
0.1 m cells and 0.005 m per unit. Integer maps built by adding heights without a range check wrap around
(int16: +32767 + 1 -> -32768); a wrap shows as a jump of more than half the integer range between
neighbouring cells, which no terrain makes (half the int16 range is 164 m at 0.005 m per unit). Such a map
is refused, naming how high it would reach unwrapped, never built with its garbage heights. 8-bit maps are not
checked: half their range is 128 units, 1.28 m at 0.01 m per unit, a step real terrains have, so a jump that
large tells nothing.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

MAX_HEIGHTMAP_CELLS = 4_000_000
"""Most cells of one heightmap (the generation limit on a tile)."""


def wrap_edges(raw: np.ndarray) -> int:
    """Neighbour pairs of a 16-bit or wider integer array whose difference exceeds half the dtype's range
    (wrap-arounds); 0 for float and 8-bit maps, whose range is too small to tell a wrap from a real step."""
    if not np.issubdtype(raw.dtype, np.integer) or raw.dtype.itemsize < 2:
        return 0
    half = (int(np.iinfo(raw.dtype).max) - int(np.iinfo(raw.dtype).min) + 1) // 2
    a = raw.astype(np.int64)
    return int((np.abs(np.diff(a, axis=0)) > half).sum() + (np.abs(np.diff(a, axis=1)) > half).sum())


def unwrapped(raw: np.ndarray) -> np.ndarray:
    """An integer map with its wrap-arounds undone (int64): along x on the first column, then along y per row."""
    period = int(np.iinfo(raw.dtype).max) - int(np.iinfo(raw.dtype).min) + 1
    a = raw.astype(np.float64)
    a[:, 0] = np.unwrap(a[:, 0], period=period)
    a = np.unwrap(a, period=period, axis=1)
    return np.rint(a).astype(np.int64)


def heightmap_heights(raw: np.ndarray, vertical_scale: float, max_abs_height: float, what: str = "the heightmap") -> np.ndarray:
    """``raw * vertical_scale`` as float32 metres; raises ValueError (one line, with the fix, no final full stop)
    for a map that
    is not 2-D numbers, is empty, holds NaN/inf, wrapped around its integer range or exceeds ``max_abs_height``."""
    if isinstance(vertical_scale, bool) or not (isinstance(vertical_scale, (int, float)) and np.isfinite(vertical_scale) and vertical_scale > 0):
        raise ValueError(f"{what}: vertical_scale={vertical_scale!r} must be a positive number of metres per unit "
                         f"(GenTe's maps: 0.005)")
    raw = np.asarray(raw)
    if raw.ndim != 2 or min(raw.shape) < 2:
        raise ValueError(f"{what} has shape {raw.shape}; a heightmap is a 2-D array of at least 2 x 2 cells "
                         f"(axis 0 along x, axis 1 along y)")
    if raw.size > MAX_HEIGHTMAP_CELLS:
        raise ValueError(f"{what} has {raw.size} cells; the limit is {MAX_HEIGHTMAP_CELLS}: downsample it")
    if raw.dtype == np.bool_ or not (np.issubdtype(raw.dtype, np.integer) or np.issubdtype(raw.dtype, np.floating)):
        raise ValueError(f"{what} holds {raw.dtype} values; a heightmap holds integers or floats")
    if np.issubdtype(raw.dtype, np.floating) and not np.all(np.isfinite(raw)):
        raise ValueError(f"{what} holds {int((~np.isfinite(raw)).sum())} NaN or infinite values; fill them with heights")
    edges = wrap_edges(raw)
    if edges:
        true = unwrapped(raw)
        peak = float(np.abs(true).max()) * vertical_scale
        raise ValueError(f"{what} wrapped around the {raw.dtype} range at {edges} cell edges (its heights overflowed; "
                         f"unwrapped they reach |height| {peak:.1f} m): rebuild it without overflow, e.g. from its tool "
                         f"calls")
    heights = raw.astype(np.float64) * vertical_scale
    peak = float(np.abs(heights).max())
    if peak > max_abs_height:
        raise ValueError(f"{what} reaches |height| {peak:.2f} m > {max_abs_height} m; lower vertical_scale or "
                         f"rebuild the map lower")
    return heights.astype(np.float32)


def load_heightmap(path: str | Path, vertical_scale: float, max_abs_height: float) -> np.ndarray:
    """A ``.npy`` heightmap file in metres (see :func:`heightmap_heights`); never unpickles."""
    path = Path(path)
    if not path.is_file():
        what = "is a folder, not a file" if path.is_dir() else "does not exist"
        raise ValueError(f"heightmap file {str(path)[:200]} {what}; give a .npy path (relative to the spec file)")
    try:
        raw = np.load(path, mmap_mode="r", allow_pickle=False)
    except (ValueError, OSError, EOFError) as exc:
        raise ValueError(f"heightmap file {str(path)[:200]} is not a readable .npy array ({str(exc)[:120]}); save it "
                         f"with numpy.save") from None
    return heightmap_heights(raw, vertical_scale, max_abs_height, f"heightmap {path.name[:100]}")
