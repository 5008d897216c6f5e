"""The ``planner`` backend for images: colour, texture and brightness analysis -> terrain tool calls.

The image is read as a map of the tile seen from above: its top edge is the tile's front (+x), its left
edge the tile's left (+y); a photo taken at eye level maps the same way (near ground at the bottom = the
back of the tile, where the robot starts), after the sky above the horizon is cut off.

Two kinds of images:

* **Sketch maps** drawn with the colours of :data:`LEGEND` (any paint program): every pixel is given the
  class of the nearest legend colour. An image is a sketch when almost all of its pixels lie close to a
  legend colour.
* **Photos**: pixels are classified by hue, saturation and brightness (HSV rules below); texture (local
  brightness spread) tells a forest with trunks from grass, rubble from pavement; regular horizontal edges
  in grey areas are stairs; a strong linear brightness gradient over the ground is read as a slope.

The class map is pooled into blocks of about 2 m; the blocks of each class are covered by rectangles, and
each rectangle gets its class's recipe of tool calls (validated against the registry). Black blobs of a
sketch become raised blocks at their exact place.
"""

from __future__ import annotations

import dataclasses
import io
from pathlib import Path
from typing import Mapping

import numpy as np
from PIL import Image
from scipy import ndimage

from legged_gente.generation.backends import GenerationResult
from legged_gente.generation.backends.planner import KNEE_HEIGHT, Step
from legged_gente.generation.validation import ToolCall, ValidationError, validate_call
from legged_gente.terrain.registry import ATOMIC_TERRAINS, AtomicTerrain


@dataclasses.dataclass(frozen=True)
class Legend:
    """One surface class: its sketch colour (RGB), what it means, and its recipe per rectangle."""

    rgb: tuple[int, int, int]
    meaning: str
    steps: tuple[Step, ...]


OBSTACLE_HEIGHT = 0.5
"""Height (m) of a raised block drawn in black on a sketch: too high to step on for a ~1 m biped."""

LEGEND: dict[str, Legend] = {
    "water": Legend((0, 0, 255), f"knee-deep water ({KNEE_HEIGHT} m)", (Step("water", {"depth": KNEE_HEIGHT}),)),
    "sand": Legend((255, 255, 0), "dry sand", (Step("soil", {"preset": "dry_sand"}),)),
    "forest": Legend((0, 128, 0), "forest floor with trees", (
        Step("natural_ground", {"amplitude": 0.08, "wavelength": 2.0, "platform": 0.0}, mode="add"),
        Step("pillars", {"height": 3.0, "min_radius": 0.1, "max_radius": 0.3, "density": 0.08, "platform": 0.0}, mode="add"),
    )),
    "grass": Legend((128, 255, 128), "grass: the gently uneven base ground, nothing added", ()),
    "pavement": Legend((128, 128, 128), "pavement, flat", (Step("flat", {"height": 0.0}),)),
    "rock": Legend((64, 64, 64), "rocks and rubble", (
        Step("rocks", {"max_height": 0.15, "min_radius": 0.1, "max_radius": 0.4, "density": 0.8, "platform": 0.0}, mode="add"),
    )),
    "snow": Legend((255, 255, 255), "snow", (Step("soil", {"preset": "snow"}),)),
    "ice": Legend((0, 255, 255), "ice, slippery", (Step("low_friction", {"preset": "ice"}),)),
    "mud": Legend((139, 69, 19), "mud", (Step("soil", {"preset": "mud"}),)),
    "obstacle": Legend((0, 0, 0), f"raised block / pillar ({OBSTACLE_HEIGHT} m), placed exactly", (
        Step("flat", {"height": OBSTACLE_HEIGHT}),
    )),
    "stairs": Legend((255, 0, 0), "stairs rising towards the top of the image (+x)", (
        Step("stairs", {"step_height": 0.12, "step_width": 0.35, "direction": "up", "platform": 0.0}),
    )),
}
CLASSES = list(LEGEND)
SKETCH_TOLERANCE = 60.0
"""Largest RGB distance of a sketch pixel from its legend colour (antialiasing, JPEG noise)."""
SKETCH_FRACTION = 0.9
"""An image whose pixels lie within the tolerance of a legend colour at least this often is a sketch."""

GRID = 96  # analysis resolution (pixels per image side)
BLOCK = 8  # pixels per block of a photo: 12 blocks per side (1.7 m on a 20 m tile); sketches use half

MIN_FRACTION = 0.02  # a class covering less of the image is ignored


def _load(image: str | Path | bytes | Image.Image) -> tuple[Image.Image, bytes | None]:
    if isinstance(image, Image.Image):
        return image.convert("RGB"), None
    data = Path(image).read_bytes() if isinstance(image, (str, Path)) else bytes(image)
    try:
        return Image.open(io.BytesIO(data)).convert("RGB"), data
    except Exception as exc:  # Pillow raises several types for unreadable data
        raise ValueError(f"the image could not be read ({exc}); pass a PNG or JPEG file.") from None


def _hsv(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hue (degrees), saturation and value in [0, 1] of float RGB in [0, 1]."""
    hsv = np.asarray(Image.fromarray((rgb * 255).astype(np.uint8)).convert("HSV"), np.float32) / 255.0
    return hsv[..., 0] * 360.0, hsv[..., 1], hsv[..., 2]


def _legend_distance(rgb255: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    colours = np.array([LEGEND[c].rgb for c in CLASSES], np.float32)
    d = np.linalg.norm(rgb255[..., None, :] - colours, axis=-1)
    return d.argmin(-1), d.min(-1)


def _local_std(x: np.ndarray, size: int) -> np.ndarray:
    """Standard deviation of ``x`` over a ``size`` x ``size`` window (texture)."""
    mean = ndimage.uniform_filter(x, size, mode="nearest")
    return np.sqrt(np.maximum(ndimage.uniform_filter(x * x, size, mode="nearest") - mean * mean, 0.0))


def _classify_photo(rgb: np.ndarray) -> np.ndarray:
    """Class index per pixel of a photo from HSV rules (first matching rule wins)."""
    h, s, v = _hsv(rgb)
    lum = rgb.mean(-1)
    # Colour texture: spread of all three channels over a block (dark trunks in foliage, stones in gravel).
    texture = np.sqrt(sum(_local_std(rgb[..., c], BLOCK) ** 2 for c in range(3)))
    gy = np.abs(ndimage.sobel(lum, axis=0))
    gx = np.abs(ndimage.sobel(lum, axis=1))
    gy_b, gx_b = ndimage.uniform_filter(gy, BLOCK), ndimage.uniform_filter(gx, BLOCK)
    grey = s < 0.18
    rules = [
        ("obstacle", v < 0.15),
        ("stairs", grey & (gy_b > 0.25) & (gy_b > 3.0 * gx_b)),  # regular horizontal edges: step nosings
        ("snow", (s < 0.12) & (v > 0.85)),
        ("ice", (h >= 170) & (h < 200) & (s >= 0.12) & (s < 0.5) & (v > 0.7)),
        ("water", (h >= 180) & (h < 260) & (s >= 0.25)),
        ("sand", (h >= 35) & (h < 65) & (s >= 0.2) & (v > 0.55)),
        ("forest", (h >= 65) & (h < 170) & (s >= 0.2) & (texture > 0.12)),
        ("grass", (h >= 65) & (h < 170) & (s >= 0.2)),
        ("mud", (h < 45) & (s >= 0.25) & (v <= 0.55)),
        ("rock", grey & ((v < 0.5) | (texture > 0.15))),
        ("pavement", grey),
    ]
    out = np.full(lum.shape, CLASSES.index("pavement"), np.int64)
    done = np.zeros(lum.shape, bool)
    for name, mask in rules:
        take = mask & ~done
        out[take] = CLASSES.index(name)
        done |= take
    return out


def _cut_sky(rgb: np.ndarray) -> tuple[np.ndarray, int]:
    """Drop the rows above the horizon of a photo: top rows that are mostly bright, smooth, bluish or white."""
    h, s, v = _hsv(rgb)
    texture = _local_std(rgb.mean(-1), 5)
    sky = (v > 0.6) & (texture < 0.03) & (((h >= 180) & (h < 250)) | (s < 0.15))
    rows = sky.mean(1) > 0.6
    horizon = 0
    while horizon < len(rows) // 2 and rows[horizon]:
        horizon += 1
    return rgb[horizon:], horizon


def _rectangles(mask: np.ndarray) -> list[tuple[int, int, int, int]]:
    """Cover the true cells of a 2-D mask by rectangles (r0, c0, r1, c1), exclusive ends: row runs, merged down."""
    rects: list[tuple[int, int, int, int]] = []
    open_runs: dict[tuple[int, int], int] = {}  # (c0, c1) -> first row
    for r in range(mask.shape[0] + 1):
        runs = set()
        if r < mask.shape[0]:
            row = np.concatenate([[False], mask[r], [False]])
            edges = np.flatnonzero(row[1:] != row[:-1])
            runs = set(zip(edges[::2].tolist(), edges[1::2].tolist()))
        for run in list(open_runs):
            if run not in runs:
                rects.append((open_runs.pop(run), run[0], r, run[1]))
        for run in runs:
            open_runs.setdefault(run, r)
    return sorted(rects)


def _to_metres(rect, shape, size_x: float, size_y: float) -> dict[str, float]:
    """Image rectangle (rows, cols; top row = front) -> tile rectangle in metres (+x front, +y left)."""
    r0, c0, r1, c1 = rect
    nr, nc = shape
    x0, x1 = size_x * (1 - r1 / nr), size_x * (1 - r0 / nr)
    y0, y1 = size_y * (1 - c1 / nc), size_y * (1 - c0 / nc)
    return {k: round(float(v), 2) for k, v in zip(("x0", "y0", "x1", "y1"), (x0, y0, x1, y1))}


def plan_image(
    image: str | Path | bytes | Image.Image,
    size_x: float = 20.0,
    size_y: float = 20.0,
    registry: Mapping[str, AtomicTerrain] | None = None,
) -> GenerationResult:
    """Deterministic tool calls for a photo or a colour-coded sketch map (see the module docstring)."""
    registry = ATOMIC_TERRAINS if registry is None else registry
    img, _ = _load(image)
    warnings: list[str] = []
    notes: list[str] = []
    sketch_px = np.asarray(img.resize((GRID, GRID), Image.Resampling.NEAREST), np.float32)
    idx, dist = _legend_distance(sketch_px)
    is_sketch = float((dist < SKETCH_TOLERANCE).mean()) >= SKETCH_FRACTION
    if is_sketch:
        classes = idx
        notes.append("read as a colour-coded sketch map")
        slope = 0.0
    else:
        rgb = np.asarray(img.resize((GRID, GRID), Image.Resampling.BOX), np.float32) / 255.0
        ground, horizon = _cut_sky(rgb)
        if horizon:
            notes.append(f"photo: cut {100 * horizon / GRID:.0f}% of the image above the horizon as sky")
        # Back to a square analysis grid so blocks map to equal tile areas.
        ground = np.asarray(Image.fromarray((ground * 255).astype(np.uint8)).resize((GRID, GRID), Image.Resampling.BOX), np.float32) / 255.0
        classes = _classify_photo(ground)
        notes.append("read as a photo (colour, texture and brightness rules)")
        # A linear brightness ramp over the ground that explains most of its variance reads as a slope.
        lum = ground.mean(-1)
        rr, cc = np.mgrid[0:GRID, 0:GRID] / (GRID - 1.0)
        design = np.stack([rr.ravel(), cc.ravel(), np.ones(GRID * GRID)], 1)
        coef, *_ = np.linalg.lstsq(design, lum.ravel(), rcond=None)
        r2 = 1.0 - np.var(lum.ravel() - design @ coef) / max(np.var(lum), 1e-9)
        ramp = float(np.hypot(coef[0], coef[1]))
        slope = min(0.6 * ramp, 0.4) if (r2 > 0.6 and ramp > 0.25) else 0.0

    # Pool classes into blocks: each block takes its majority class (finer blocks for clean sketches).
    bs = BLOCK // 2 if is_sketch else BLOCK
    nb = GRID // bs
    blocks = classes.reshape(nb, bs, nb, bs).transpose(0, 2, 1, 3).reshape(nb, nb, -1)
    counts = np.stack([(blocks == k).sum(-1) for k in range(len(CLASSES))], -1)
    block_class = counts.argmax(-1)
    # Coverage by blocks (what gets built); a sketch's black blobs count at any size, they are placed exactly.
    coverage = {c: float((block_class == k).mean()) for k, c in enumerate(CLASSES)}
    if is_sketch:
        coverage["obstacle"] = float((classes == CLASSES.index("obstacle")).mean())
    present = [c for c in CLASSES if coverage[c] >= MIN_FRACTION or (c == "obstacle" and is_sketch and coverage[c] > 0)]
    notes.append("surfaces: " + ", ".join(f"{c} {100 * coverage[c]:.0f}%" for c in sorted(present, key=lambda c: -coverage[c])))

    geometric: list[tuple[Step, dict]] = []
    physical: list[tuple[Step, dict]] = []
    flat_base = coverage["pavement"] + coverage["ice"] > 0.5
    base = Step("flat", {"height": 0.0}) if flat_base else Step("natural_ground", {"amplitude": 0.04, "wavelength": 3.0, "platform": 0.0})
    geometric.append((base, {"region": "full"}))
    if slope > 0.0:
        geometric.append((Step("pyramid_slope", {"slope": round(slope, 3), "direction": "up", "platform": 2.0}, mode="add"), {"region": "full"}))
        notes.append(f"brightness gradient read as a slope of {slope:.2f} rad")
    for name in present:
        if name == "obstacle" and is_sketch:
            labels, _ = ndimage.label(classes == CLASSES.index("obstacle"))
            rects = [(s[0].start, s[1].start, s[0].stop, s[1].stop) for s in ndimage.find_objects(labels)]
            shape = classes.shape
        else:
            rects = _rectangles(block_class == CLASSES.index(name))
            shape = block_class.shape
        if not rects:
            continue
        for rect in rects:
            region = _to_metres(rect, shape, size_x, size_y)
            for step in LEGEND[name].steps:
                (geometric if registry[step.tool].kind == "geometric" else physical).append((step, {"region": region}))
    calls: list[ToolCall] = []
    for step, layout in geometric + physical:
        args = {**step.params, **layout}
        if registry[step.tool].kind == "geometric":
            args["mode"] = step.mode
        try:
            calls.append(validate_call(step.tool, args, size_x, size_y, registry))
        except ValidationError as exc:  # e.g. a block thinner than a cell: report, keep the rest
            warnings += [f"skipped: {m}" for m in exc.messages]
    return GenerationResult(calls, warnings, notes, model=None)
