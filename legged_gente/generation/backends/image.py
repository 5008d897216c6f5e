"""The ``planner`` backend for images: sketch maps and photos -> terrain tool calls, without a model.

Two kinds of images, told apart by :func:`is_sketch`:

* **Sketch maps**: the tile seen from above, painted with the flat colours of :data:`LEGEND` (any paint
  program): top edge = front (+x), left edge = left (+y). Every pixel takes the class of the nearest legend
  colour, the classes are pooled into blocks and covered by rectangles, and black blobs become raised blocks at
  their exact place. A sketch is an image whose pixels almost all lie *tightly* on legend colours *and* that is
  flat almost everywhere (a photo has noise, texture and gradients even where it is grey).
* **Photos**, read in perspective as a person standing at the back edge of the tile looking along +x:

  1. *Sky*: smooth, bright or bluish / grey / sunset-coloured regions connected to the top edge (or large ones
     starting in the top rows) are dropped; nothing above the horizon is ever read as ground (so a blue sky
     cannot become water, nor a white one snow).
  2. *Horizon*: where the sky ends in the columns that show most of it. Non-sky things rising above it are
     clouds or far scenery (hazy ridges, a thin band: tree line, skyline), a *hill* (a wide smooth-edged region
     of the near ground's surface: a slope; a straight tilted outline is a side slope of the angle of its tilt,
     a curved one a hill ahead), or *tall obstacles* (trees, buildings, walls, towers); below it,
     compact blobs standing at least ``STANDING`` m tall (cars, benches, blocks) are tall obstacles too.
  3. *Ground*: below the horizon, row ``r`` sees the ground at distance ``Z = Z_NEAR * (bottom - horizon) /
     (r - horizon)`` (a pinhole camera over flat ground), so the tile's back half (``Z < Z_NEAR + size_x / 2``)
     is the lower part of the picture and its front half a thin band under the horizon. Pixels are classified
     by colour (water, ice, snow, sand, mud, grass, grey ground) and texture (gravel: rough; trunks: trees).
     Water-coloured blobs taller than a patch lying on the ground can look at their distance (foreshortening)
     stand upright (window panes, doors, blue cars) and are not ground.
  4. *Cues*: foam, wave crests and a water band with land beyond it (a river) make water flow; water across
     the view is one band at its distance; small dark blobs with their shadows on the ground are rocks (low
     obstacles); a run of regular, thick horizontal bands is one flight of stairs.
  5. *Layout*: GenTe's four parts (back/front x left/right); each part takes its dominant surface, and equal
     neighbouring parts are merged, so a photo gives a few calls (at most ``MAX_CALLS``).

A greyscale photo has no colours to read: only sky, horizon, obstacles, stairs, rocks and roughness are found,
with a warning.
"""

from __future__ import annotations

import dataclasses
import io
import warnings
from pathlib import Path
from typing import Mapping

import numpy as np
from PIL import Image, ImageOps, UnidentifiedImageError
from scipy import ndimage

from legged_gente.generation.backends import GenerationResult
from legged_gente.generation.backends.planner import FREEBOARD, KNEE_HEIGHT, WATER_MARGIN, Step, keep_off_seams
from legged_gente.generation.tools import named_regions
from legged_gente.generation.validation import ToolCall, ValidationError, printable, validate_call
from legged_gente.terrain.composition import MAX_CALLS as SPEC_MAX_CALLS
from legged_gente.terrain.composition import SEAM_BAND, clip_text
from legged_gente.terrain.registry import ATOMIC_TERRAINS, AtomicTerrain


@dataclasses.dataclass(frozen=True)
class Legend:
    """One surface class of a sketch map: its colour (RGB), what it means, and its recipe per rectangle."""

    rgb: tuple[int, int, int]
    meaning: str
    steps: tuple[Step, ...]


OBSTACLE_HEIGHT = 0.5
"""Height (m) of a raised block drawn in black on a sketch: too high to step on for a ~1 m biped."""
BLOCK_FILL = 0.5
"""A black blob without holes that fills at least this share of its bounding box (a square; a disc, pi / 4, less
its pixel steps) is one block over that box; any other (a wall, a ring, an L) is covered by rectangles of its own
pixels, so the ground it encloses or passes by stays open."""

WATER_SHORE = 1.5
"""Width (m) of the shelving shore of a basin under image water: 0.4 m down over 1.5 m, at most 22 degrees
(smoothstep's steepest slope is 1.5 depth / width), so a robot can wade in."""
BODY_GAP = SEAM_BAND + 0.2
"""Least distance (m) between the boxes of two sketch water bodies: a basin blends ``SEAM_BAND`` past its box, and
two more 0.1 m cells keep the ground between two bodies whole. Nearer blobs are one body over one box."""
DRY_INSIDE_MIN = 2.0 * WATER_SHORE
"""Side (m) of the smallest dry rectangle inside a sketch water blob's bounding box that is rebuilt as ground: the
land an L or a ring of water encloses. Narrower dry parts (a disc's corners) lie on the basin's shore anyway."""

LEGEND: dict[str, Legend] = {
    "water": Legend((0, 0, 255), f"knee-deep water ({KNEE_HEIGHT} m) in a basin", (
        Step("basin", {"depth": KNEE_HEIGHT + FREEBOARD, "shore_width": WATER_SHORE}, mode="add"),
        Step("water", {"depth": KNEE_HEIGHT}),
    )),
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
SKETCH_TOLERANCE = 24.0
"""Largest RGB distance of a sketch pixel from its legend colour (antialiasing, JPEG noise)."""
SKETCH_FRACTION = 0.85
"""A sketch has at least this share of its pixels within the tolerance of a legend colour ..."""
SKETCH_FLAT = 0.6
"""... and at least this share of pixels whose 3 x 3 neighbourhood varies by less than FLAT_RANGE."""
FLAT_RANGE = 12.0

GRID = 96  # sketch analysis resolution (pixels per side)
SKETCH_BLOCK = 4  # pixels per block of a sketch: 24 blocks per side (0.8 m on a 20 m tile)
MIN_FRACTION = 0.02  # a sketch class covering less of the image is ignored
SKETCH_SURE = 30.0
"""RGB distance (0-255 units) to its nearest legend colour within which a sketch pixel votes for its block's class:
a third of the closest two legend colours' distance (rock and mud, 88)."""
MAX_CALLS = 21
"""Most calls a photo gives (GenTe asks for 3-20; water is two: its basin and itself)."""


def open_image(data: bytes, source: object = None) -> Image.Image:
    """The image encoded in ``data``, decoded; unreadable data is a one-line error naming ``source`` when it is the
    file's path."""
    name = str(source) if isinstance(source, (str, Path)) else "the image"
    try:
        with warnings.catch_warnings():  # beyond MAX_IMAGE_PIXELS Pillow only warns, up to twice it: refuse as well
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            image = Image.open(io.BytesIO(data))
            image.load()
        return image
    except (Image.DecompressionBombError, Image.DecompressionBombWarning) as exc:  # the first clause: pixels, limit
        raise ValueError(f"{name} is too large to decode: {str(exc).split(',')[0]}; downscale it (a few megapixels "
                         f"are plenty) and pass it again.") from None
    except MemoryError:
        raise  # the machine is out of memory, not the file unreadable
    except Exception as exc:  # Pillow raises several types for unreadable data
        # an unknown format's text names only a buffer; a truncated or broken file's says what is wrong with it
        why = type(exc).__name__ if isinstance(exc, UnidentifiedImageError) else \
            f"{type(exc).__name__}: {clip_text(printable(str(exc)), 120)}"
        raise ValueError(f"{name} could not be read as an image ({why}); pass a PNG or JPEG file.") from None


EXIF_ORIENTATION = 0x0112
"""EXIF tag of how a stored picture must be turned to show it upright (1: as stored)."""


def upright(img: Image.Image) -> Image.Image:
    """``img`` turned as its EXIF orientation says (a camera held upright stores the picture turned): the picture a
    viewer shows."""
    return ImageOps.exif_transpose(img) if img.getexif().get(EXIF_ORIENTATION, 1) != 1 else img


def _load(image: str | Path | bytes | Image.Image) -> Image.Image:
    """The picture as 8-bit RGB, upright; transparent pixels (their colour means nothing) and integer or float
    pixels beyond 8 bits (Pillow would clip them) are a one-line error. 16-bit pixels are scaled to 8 bits."""
    if isinstance(image, Image.Image):
        img, name = image, "the image"
    else:
        data = Path(image).read_bytes() if isinstance(image, (str, Path)) else bytes(image)
        img, name = open_image(data, image), str(image) if isinstance(image, (str, Path)) else "the image"
    img = upright(img)
    if img.width == 0 or img.height == 0:  # resampled, an empty picture is black: a block over the whole tile
        raise ValueError(f"{name} has no pixels ({img.width} x {img.height}); pass a picture.")
    if img.mode in ("RGBA", "LA", "PA", "RGBa", "La") or "transparency" in img.info:
        clear = np.asarray(img.convert("RGBA"))[..., 3] < 255
        if clear.any():
            raise ValueError(f"{name} has transparent pixels ({100 * clear.mean():.0f} % of it), whose colour means "
                             f"nothing; flatten it onto an opaque background (a sketch: paint every pixel a legend "
                             f"colour) and pass it again.")
    if img.mode.startswith("I;16"):  # 16-bit grey: 0..65535 onto 0..255
        return Image.fromarray(np.round(np.asarray(img, np.float64) / 257.0).astype(np.uint8)).convert("RGB")
    if img.mode in ("I", "F"):  # Pillow reads these as 0..255 and clips the rest
        pixels = np.asarray(img)
        lo, hi = float(pixels.min()), float(pixels.max())
        if not (lo >= 0.0 and hi <= 255.0):
            raise ValueError(f"{name} has {img.mode} pixels from {lo:g} to {hi:g}, beyond the 0..255 of a picture; "
                             f"save it as an 8- or 16-bit PNG or as a JPEG and pass it again.")
    return img.convert("RGB")


def _hsv(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hue (degrees), saturation and value in [0, 1] of float RGB in [0, 1]."""
    hsv = np.asarray(Image.fromarray((np.clip(rgb, 0, 1) * 255).astype(np.uint8)).convert("HSV"), np.float32) / 255.0
    return hsv[..., 0] * 360.0, hsv[..., 1], hsv[..., 2]


def _legend_distance(rgb255: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    colours = np.array([LEGEND[c].rgb for c in CLASSES], np.float32)
    d = np.linalg.norm(rgb255[..., None, :] - colours, axis=-1)
    return d.argmin(-1), d.min(-1)


def _local_std(x: np.ndarray, size: int) -> np.ndarray:
    """Standard deviation of ``x`` over a ``size`` x ``size`` window (texture)."""
    mean = ndimage.uniform_filter(x, size, mode="nearest")
    return np.sqrt(np.maximum(ndimage.uniform_filter(x * x, size, mode="nearest") - mean * mean, 0.0))


def is_sketch(img: Image.Image) -> bool:
    """Whether ``img`` is a colour-coded sketch map (see the module docstring) rather than a photo."""
    px = np.asarray(img.resize((GRID, GRID), Image.Resampling.NEAREST), np.float32)
    _, dist = _legend_distance(px)
    spread = ndimage.maximum_filter(px, (3, 3, 1)) - ndimage.minimum_filter(px, (3, 3, 1))
    flat = spread.max(-1) < FLAT_RANGE
    return float((dist < SKETCH_TOLERANCE).mean()) >= SKETCH_FRACTION and float(flat.mean()) >= SKETCH_FLAT


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


def _plan_sketch(img: Image.Image, size_x: float, size_y: float, notes: list[str], warnings: list[str]) -> list[tuple[Step, dict]]:
    """Steps and regions of a sketch map: legend classes pooled into blocks, covered by rectangles."""
    classes, distance = _legend_distance(np.asarray(img.resize((GRID, GRID), Image.Resampling.NEAREST), np.float32))
    notes.append("read as a colour-coded sketch map")
    bs, nb = SKETCH_BLOCK, GRID // SKETCH_BLOCK
    to_blocks = lambda a: a.reshape(nb, bs, nb, bs).transpose(0, 2, 1, 3).reshape(nb, nb, -1)  # noqa: E731
    # A lossy codec (JPEG, WebP) leaves a pixel or two at a colour edge between the two colours, some near a third
    # legend colour (red beside grass reads as mud): a pixel votes only if it is near its legend colour and is no
    # such seam, a pixel beside two classes other than its own (a thin stripe drawn between two of one class votes).
    others = np.zeros(classes.shape, np.int32)
    for k in np.unique(classes):
        others += ndimage.binary_dilation(classes == k, np.ones((3, 3), bool)) & (classes != k)
    blocks, sure = to_blocks(classes), to_blocks((others < 2) & (distance <= SKETCH_SURE))
    sure |= ~sure.any(-1, keepdims=True)  # a block of seams only: all of its pixels vote
    block_class = np.stack([((blocks == k) & sure).sum(-1) for k in range(len(CLASSES))], -1).argmax(-1)
    classes = np.where(distance <= SKETCH_SURE, classes, -1)  # an obstacle's own pixels, placed exactly
    coverage = {c: float((block_class == k).mean()) for k, c in enumerate(CLASSES)}
    coverage["obstacle"] = float((classes == CLASSES.index("obstacle")).mean())  # placed exactly, at any size
    present = [c for c in CLASSES if coverage[c] >= MIN_FRACTION or (c == "obstacle" and coverage[c] > 0)]
    if "obstacle" in present:  # placed exactly, so last: a later "set" (stairs, pavement) would flatten them
        present = [c for c in present if c != "obstacle"] + ["obstacle"]
    notes.append("surfaces: " + ", ".join(f"{c} {100 * coverage[c]:.0f}%" for c in sorted(present, key=lambda c: -coverage[c])))
    flat_base = coverage["pavement"] + coverage["ice"] > 0.5
    base = Step("flat", {"height": 0.0}) if flat_base else Step("natural_ground", {"amplitude": 0.04, "wavelength": 3.0, "platform": 0.0})
    out = [(base, {"region": "full"})]
    for name in present:
        if name == "obstacle":
            labels, _ = ndimage.label(classes == CLASSES.index("obstacle"))
            rects = []
            for k, sl in enumerate(ndimage.find_objects(labels), start=1):
                blob = labels[sl] == k
                r, c = sl[0].start, sl[1].start
                compact = blob.mean() >= BLOCK_FILL and not (ndimage.binary_fill_holes(blob) & ~blob).any()
                own = [(0, 0, *blob.shape)] if compact else _rectangles(blob)
                rects += [(r + r0, c + c0, r + r1, c + c1) for r0, c0, r1, c1 in own]
            shape = classes.shape
        elif name == "stairs":
            rects = _stairs_rectangles(block_class)
            shape = block_class.shape
        elif name == "water":  # one rectangle over each water body's box: one basin, so no dry ridge splits it
            water = block_class == CLASSES.index(name)
            labels, _ = ndimage.label(water)
            boxes = _water_bodies([(sl[0].start, sl[1].start, sl[0].stop, sl[1].stop)
                                   for sl in ndimage.find_objects(labels)], block_class.shape, size_x, size_y)
            stairs = ([_to_metres(r, block_class.shape, size_x, size_y) for r in _stairs_rectangles(block_class)]
                      if "stairs" in present else [])  # stairs under MIN_FRACTION are not built
            for box in boxes:
                region = _to_metres(box, block_class.shape, size_x, size_y)
                for flight in stairs:
                    region = region and _keep_off(region, flight)
                if region is None:
                    warnings.append(f"water blob at {_to_metres(box, block_class.shape, size_x, size_y)} left out: "
                                    f"it keeps {WATER_MARGIN:g} m off the stairs beside it and no room is left; draw "
                                    f"it wider or farther from the stairs.")
                    continue
                out += [(step, {"region": region}) for step in LEGEND[name].steps]
                out += [(base, {"region": land}) for land in _dry_inside(water, box, size_x, size_y)]
            continue
        else:
            rects = _rectangles(block_class == CLASSES.index(name))
            shape = block_class.shape
        for rect in rects:
            region = _to_metres(rect, shape, size_x, size_y)
            out += [(step, {"region": region}) for step in LEGEND[name].steps]
    return out


def _water_bodies(boxes: list[tuple[int, int, int, int]], shape, size_x: float, size_y: float
                  ) -> list[tuple[int, int, int, int]]:
    """The boxes of a sketch's water blobs, those nearer each other than ``BODY_GAP`` merged into one box (one
    basin, one water) until none is. Two boxes that overlap or nearly touch would stack two basins or blend one
    into the other's rim, and their two waters' surfaces would stand above each other's ground."""
    row_m, col_m = size_x / shape[0], size_y / shape[1]

    def near(a, b) -> bool:
        gap_x = max(a[0] - b[2], b[0] - a[2], 0) * row_m
        gap_y = max(a[1] - b[3], b[1] - a[3], 0) * col_m
        return np.hypot(gap_x, gap_y) < BODY_GAP

    boxes = list(boxes)
    while pair := next(((i, j) for i in range(len(boxes)) for j in range(i + 1, len(boxes))
                        if near(boxes[i], boxes[j])), None):
        i, j = pair
        a, b = boxes[i], boxes.pop(j)
        boxes[i] = (min(a[0], b[0]), min(a[1], b[1]), max(a[2], b[2]), max(a[3], b[3]))
    return boxes


def _dry_inside(water: np.ndarray, box, size_x: float, size_y: float) -> list[dict[str, float]]:
    """Rectangles (m) of the land a water body (the ``water`` blocks of the sketch over its ``box``) leaves inside
    its box, each holding a square of ``DRY_INSIDE_MIN``: the basin under the box would flood them, so the sketch's
    ground is built again there (its rim drops to the basin's floor over the seam band: a bank)."""
    r0, c0, r1, c1 = box
    shape = water.shape
    rows = int(np.ceil(DRY_INSIDE_MIN * shape[0] / size_x - 1e-9))
    cols = int(np.ceil(DRY_INSIDE_MIN * shape[1] / size_y - 1e-9))
    return [_to_metres((r0 + a, c0 + b, r0 + c, c0 + d), shape, size_x, size_y)
            for a, b, c, d in _largest_rectangles(~water[r0:r1, c0:c1], rows, cols)]


def _largest_rectangles(mask: np.ndarray, rows: int, cols: int) -> list[tuple[int, int, int, int]]:
    """Disjoint rectangles (r0, c0, r1, c1), exclusive ends, of true cells of ``mask``, each at least ``rows`` x
    ``cols``: the largest first, then the largest of the cells left, until none that large is left. Land with stepped
    edges (beside a diagonal band) holds such rectangles though its row runs, merged down, are one row high."""
    free = mask.copy()
    out: list[tuple[int, int, int, int]] = []
    nr, nc = mask.shape
    r0, r1 = (a.ravel() for a in np.meshgrid(np.arange(nr + 1), np.arange(nr + 1), indexing="ij"))
    c0, c1 = (a.ravel() for a in np.meshgrid(np.arange(nc + 1), np.arange(nc + 1), indexing="ij"))
    keep_r, keep_c = r1 - r0 >= rows, c1 - c0 >= cols
    r0, r1, c0, c1 = r0[keep_r][:, None], r1[keep_r][:, None], c0[keep_c][None, :], c1[keep_c][None, :]
    area = (r1 - r0) * (c1 - c0)
    while True:
        total = np.pad(free.astype(np.int64), ((1, 0), (1, 0))).cumsum(0).cumsum(1)
        filled = total[r1, c1] - total[r0, c1] - total[r1, c0] + total[r0, c0] == area
        if not filled.any():
            return sorted(out)
        k = np.unravel_index(np.argmax(np.where(filled, area, -1)), area.shape)
        rect = (int(r0[k[0], 0]), int(c0[0, k[1]]), int(r1[k[0], 0]), int(c1[0, k[1]]))
        out.append(rect)
        free[rect[0]:rect[2], rect[1]:rect[3]] = False


def _stairs_rectangles(block_class: np.ndarray) -> list[tuple[int, int, int, int]]:
    """Block rectangles of a sketch's stairs. A stairs call is a flight centred on its rectangle: one rectangle per
    column band, whole along x, so the flight never falls back; blocks drawn on it do not cut it (they are placed
    over it)."""
    mask = block_class == CLASSES.index("stairs")
    mask |= ndimage.binary_fill_holes(mask) & (block_class == CLASSES.index("obstacle"))
    return [(r0, c0, r1, c1) for c0, r0, c1, r1 in _rectangles(mask.T)]


def _keep_off(water: dict[str, float], flight: dict[str, float]) -> dict[str, float] | None:
    """The largest part of a water blob's rectangle that keeps ``WATER_MARGIN`` off a stairs rectangle (the
    planner's rule): a flight starts about half its rise below the ground and is blended into the ground around it
    over the seam band, which would pull a basin rim there below the waterline. None when no part is left.
    Raised blocks need no margin: their seam band only lifts the rim."""
    x0, y0, x1, y1 = (flight[k] - WATER_MARGIN if k in ("x0", "y0") else flight[k] + WATER_MARGIN
                      for k in ("x0", "y0", "x1", "y1"))
    if water["x1"] <= x0 or water["x0"] >= x1 or water["y1"] <= y0 or water["y0"] >= y1:
        return water
    parts = [{**water, "x1": x0}, {**water, "x0": x1}, {**water, "y1": y0}, {**water, "y0": y1}]
    parts = [{k: round(v, 2) for k, v in p.items()} for p in parts if p["x1"] > p["x0"] and p["y1"] > p["y0"]]
    return max(parts, key=lambda p: (p["x1"] - p["x0"]) * (p["y1"] - p["y0"]), default=None)


# ------------------------------------------------------------------------------------------------ photos
PH, PW = 96, 128  # photo analysis resolution (rows, columns)
Z_NEAR = 3.0
"""Distance (m) of the ground seen at the bottom of a photo: a camera ~1.6 m high with a ~60 degree view."""
CAMERA_HEIGHT = 1.6
"""Eye height (m) of a photo: a thing standing on flat ground whose base is ``b`` rows under the horizon and
that is ``k`` rows tall is ``CAMERA_HEIGHT * k / b`` metres tall (pinhole camera)."""
STANDING = 0.5  # m: a compact blob on the ground at least this tall is a tall obstacle (bench, car, block)
SKY_TEXTURE = 0.03  # brightness spread over 5 x 5 px below which a pixel is smooth enough to be sky
SKY_MAX_ROW = 0.7  # the sky never reaches below this share of the picture height
MIN_SHARE = {"water": 0.1, "gravel": 0.3}
"""Share of a part a surface must cover to be built there besides the dominant one (default DEFAULT_SHARE):
water is distinctive and matters even as a thin river band; gravel-like speckle also comes from joints."""
DEFAULT_SHARE = 0.25
MIN_ROCKS = 4  # small dark blobs in a part that make it rocky

SURFACES = ("water", "ice", "snow", "sand", "mud", "grass", "grey", "gravel", "forest")
SURFACE_STEPS: dict[str, tuple[Step, ...]] = {
    "ice": (Step("low_friction", {"preset": "ice"}),),
    "snow": (Step("soil", {"preset": "snow"}),),
    "sand": (Step("soil", {"preset": "dry_sand"}),),
    "mud": (Step("soil", {"preset": "mud"}),),
    "gravel": (Step("random_uniform", {"amplitude": 0.04, "spacing": 0.1}, mode="add"),),
    "forest": (Step("pillars", {"height": 3.0, "min_radius": 0.1, "max_radius": 0.3, "density": 0.05}, mode="add"),),
    "grass": (),
    "grey": (),
}
"""Recipe of each ground surface of a photo per part (water's depends on its flow, see :func:`_water_steps`).
Obstacles keep the registry's default central platform: the robot spawns on level ground, as with text."""


@dataclasses.dataclass
class PhotoReading:
    """What was read from a photo: masks and per-part findings (inspectable in tests)."""

    sky: np.ndarray
    horizon: int
    ground: np.ndarray
    surface: np.ndarray  # index into SURFACES per pixel; -1 where not ground
    objects: np.ndarray  # tall things standing on the tile
    parts: dict[str, dict[str, float]]
    flow: str  # "still", "current" or "tide"
    slope: float  # rad, 0 when none
    stairs: tuple[int, int] | None  # image columns of the flight
    rocks: dict[str, int]  # rock blobs per part
    tall: dict[str, str]  # part -> "block" (building, wall) or "pillars" (trees, posts)
    grey: bool
    water_band: tuple[float, float] | None  # (near, far) distance from the tile's back edge (m) of water across the view


def _sky_mask(rgb: np.ndarray, h: np.ndarray, s: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, int]:
    """Sky (smooth, sky-coloured, connected to the top edge) and the horizon row.

    The horizon is the 95th percentile, over the columns where sky shows, of the row where a column's sky first
    ends (objects and hills in front of the sky raise that row, so a low percentile would be fooled by them);
    below the horizon nothing is sky, so a white sky cannot run on into a snowfield.
    """
    # Band-pass colour detail: sensor noise (finer) and the sky's smooth gradient (coarser) are not texture.
    detail = ndimage.gaussian_filter(rgb, (1.0, 1.0, 0)) - ndimage.gaussian_filter(rgb, (3.0, 3.0, 0))
    texture = np.sqrt(ndimage.uniform_filter((detail ** 2).sum(-1), 5))
    blue = (h >= 180) & (h < 300) & (v > 0.15)
    pale = (s < 0.25) & (v > 0.5)
    warm = ((h < 50) | (h >= 300)) & (v > 0.45) & (s < 0.85)  # sunset and dusk glow
    candidate = (texture < SKY_TEXTURE) & (blue | pale | warm)
    candidate = ndimage.binary_opening(candidate, iterations=1)  # no leaks through one-pixel gaps
    labels, n = ndimage.label(candidate)
    # Sky regions: touching the top edge, or large and starting in the top rows (sky between tree crowns).
    sizes = ndimage.sum(candidate, labels, np.arange(1, n + 1))
    starts = [sl[0].start for sl in ndimage.find_objects(labels)]
    keep = [k + 1 for k in range(n) if starts[k] == 0 or (starts[k] < 0.15 * rgb.shape[0] and sizes[k] > 0.02 * candidate.size)]
    sky = np.isin(labels, keep) & candidate
    first = np.argmax(sky, axis=0)
    below_first = np.arange(sky.shape[0])[:, None] >= first[None, :]
    run = np.cumprod(np.where(below_first, sky, True), axis=0).sum(0)  # rows down to the end of the first sky run
    skyline = np.where(sky.any(0), run, 0)
    seen = skyline[skyline > 0]
    if len(seen) < 0.1 * rgb.shape[1]:
        return np.zeros_like(sky), 0
    horizon = int(np.clip(np.percentile(seen, 95), 1, SKY_MAX_ROW * rgb.shape[0]))
    sky[horizon:] = False
    return sky, horizon


def _classify_ground(rgb: np.ndarray, h: np.ndarray, s: np.ndarray, v: np.ndarray, lum: np.ndarray) -> np.ndarray:
    """Surface index per pixel from colour (of a smoothed image) and fine texture (of ``lum``, not smoothed)."""
    fine = _local_std(lum - ndimage.uniform_filter(lum, 3), 3)  # speckle: gravel, pebbles
    # Trunks in a forest: dark vertical stripes among green, i.e. strong vertical edges, weak horizontal ones.
    gx = ndimage.uniform_filter(np.abs(ndimage.sobel(lum, axis=1)), 8) / 8
    gy = ndimage.uniform_filter(np.abs(ndimage.sobel(lum, axis=0)), 8) / 8
    green = ndimage.uniform_filter(((h >= 58) & (h < 170) & (s >= 0.18)).astype(np.float32), 8) > 0.4
    trunks = green & (gx > 0.025) & (gx > 1.5 * gy)
    rules = [
        ("snow", (s < 0.14) & (v > 0.78)),
        ("ice", (h >= 170) & (h < 255) & (s >= 0.1) & (s < 0.3) & (v >= 0.62)),
        ("water", _is_water(rgb, h, s, v)),
        ("sand", (h >= 25) & (h < 58) & (s >= 0.16) & (v >= 0.63)),
        ("mud", ((h < 45) | (h >= 340)) & (s >= 0.3) & (v < 0.45)),
        ("forest", trunks),
        ("grass", (h >= 58) & (h < 170) & (s >= 0.18)),
        ("gravel", (s < 0.3) & (fine > 0.05)),
    ]
    out = np.full(lum.shape, SURFACES.index("grey"), np.int64)
    done = np.zeros(lum.shape, bool)
    for name, mask in rules:
        if name == "water":  # water is a coherent surface; scattered blue-ish pixels are colour noise
            mask = mask & (ndimage.uniform_filter(mask.astype(np.float32), 3) > 0.4)
        take = mask & ~done
        out[take] = SURFACES.index(name)
        done |= take
    return out


def _part_masks(shape: tuple[int, int], horizon: int, ground: np.ndarray, size_x: float) -> dict[str, np.ndarray]:
    """GenTe's four parts in image space: back = near ground (bottom), front = the band under the horizon; the
    tile (``size_x`` m deep) starts at the bottom edge, ``Z_NEAR`` m from the camera."""
    rows, cols = np.mgrid[0:shape[0], 0:shape[1]]
    t = (rows + 0.5 - horizon) / max(shape[0] - horizon, 1)  # 1 at the bottom, 0 at the horizon
    z = Z_NEAR / np.maximum(t, 1e-6)
    on_tile = ground & (z <= Z_NEAR + size_x * 1.25)  # a little beyond the tile: small tiles and haze
    far = z >= Z_NEAR + size_x / 2
    left = cols < shape[1] / 2
    return {"back_left": on_tile & ~far & left, "back_right": on_tile & ~far & ~left,
            "front_left": on_tile & far & left, "front_right": on_tile & far & ~left}


def _stairs(lum: np.ndarray, usable: np.ndarray) -> tuple[int, int] | None:
    """Columns of a flight of stairs: >= 5 alternating thick bright / dark horizontal bands in >= 2 windows."""
    win = 8
    hits = []
    for c0 in range(0, lum.shape[1] - win + 1, win):
        rows = usable[:, c0:c0 + win].mean(1) > 0.8
        prof = np.where(rows, lum[:, c0:c0 + win].mean(1), np.nan)
        idx = np.flatnonzero(rows)
        if len(idx) < 16:
            continue
        p = prof[idx[0]:idx[-1] + 1]
        p = np.where(np.isnan(p), np.nanmean(p), p)
        detr = p - ndimage.uniform_filter1d(p, 9, mode="nearest")
        dark = detr < -0.03
        edges = np.flatnonzero(np.diff(dark.astype(int)) != 0)
        runs = np.diff(np.concatenate([[0], edges + 1, [len(dark)]]))
        kinds = [dark[i] for i in np.concatenate([[0], edges + 1])]
        dark_runs = [r for r, k in zip(runs, kinds) if k and r >= 2]
        contrast = float(np.percentile(p, 90) - np.percentile(p, 10))
        if len(dark_runs) >= 5 and contrast > 0.12:
            hits.append(c0)
    runs = np.split(np.array(hits), np.flatnonzero(np.diff(hits) > win) + 1) if hits else []
    best = max(runs, key=len, default=np.array([]))
    if len(best) < 3:  # at least 3 adjacent windows: a flight is wide
        return None
    return int(best[0]), int(best[-1]) + win


def _rock_blobs(lum: np.ndarray, usable: np.ndarray) -> np.ndarray:
    """Pixels of small, compact dark blobs on the ground: rocks and their shadows."""
    local = ndimage.median_filter(lum, 9)
    dark = (lum < local - 0.1) & usable
    labels, n = ndimage.label(dark)
    if n == 0:
        return np.zeros_like(dark)
    sizes = ndimage.sum(dark, labels, np.arange(1, n + 1))
    spans = ndimage.find_objects(labels)
    keep = np.zeros(n + 1, bool)
    for k, (sl, size) in enumerate(zip(spans, sizes), start=1):
        height, width = sl[0].stop - sl[0].start, sl[1].stop - sl[1].start
        keep[k] = (3 <= size <= 80 and min(width, height) >= 2 and width >= height * 0.8
                   and size >= 0.5 * width * height and width <= 0.2 * lum.shape[1])
    return keep[labels]


def _standing(rgb: np.ndarray, ground: np.ndarray, horizon: int, classes: np.ndarray) -> np.ndarray:
    """Compact blobs below the horizon that stand at least STANDING metres tall (cars, benches, blocks)."""
    out = np.zeros_like(ground)
    ref = np.array([np.median(rgb[r][ground[r]], 0) if ground[r].sum() > 8 else np.full(3, np.nan) for r in range(rgb.shape[0])])
    odd = ground & (np.linalg.norm(rgb - ref[:, None, :], axis=-1) > 0.2) & (classes != SURFACES.index("water"))
    labels, n = ndimage.label(ndimage.binary_opening(odd))
    for k, sl in enumerate(ndimage.find_objects(labels), start=1):
        blob = labels[sl] == k
        rows, cols = blob.shape
        base = sl[0].stop - horizon
        if sl[0].stop >= rgb.shape[0] - 1 or base <= 0 or blob.sum() < 10 or blob.mean() < 0.7:
            continue  # touching the bottom edge (near ground), not on the ground, a speck or a ragged patch
        if CAMERA_HEIGHT * rows / base >= STANDING and cols >= rows:
            out[sl] |= blob
    return out


def _is_water(rgb: np.ndarray, h: np.ndarray, s: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Blue to cyan water. Saturation alone is unreliable on dark pixels (a grey asphalt's slight tint), so the
    colour must also stand out in absolute terms (chroma = max - min channel)."""
    chroma = rgb.max(-1) - rgb.min(-1)
    return (h >= 170) & (h < 255) & ((s >= 0.15) | ((s >= 0.08) & (v < 0.6))) & (chroma >= 0.05)


HILL_SLOPE = 0.15
"""rad (~9 degrees): the slope ahead when a hill rises above the horizon; its steepness cannot be read from its
outline, whose height depends on how far away it is."""
SIDE_TILT = 0.1
"""Rows per column (in the original's square pixels) from which a straight skyline reads as a side slope."""


def _hill_slope(cols: np.ndarray, top: np.ndarray, aspect: float) -> float:
    """Slope (rad) of ground whose upper edge against the sky is ``top[k]`` (analysis rows) in column ``cols[k]``.

    A plane sloping sideways at angle theta, seen by a level pinhole camera, rises tan(theta) * dx over dx across
    at any depth Z: f * tan(theta) * dx / Z rows for f * dx / Z columns, so its skyline is a straight line tilted
    by tan(theta) in square pixels, whatever the distance and the focal length. ``aspect`` (height / width of the
    original) converts the analysis grid's rows per column into the original's. A curved outline is a hill
    ahead, of :data:`HILL_SLOPE`.
    """
    k, b = np.polyfit(cols, top, 1)
    tilt = abs(k) * (PW / PH) * aspect
    residual = top - (k * cols + b)
    straight = float(np.var(residual)) < 0.1 * float(np.var(top)) if np.var(top) > 0 else False
    if tilt > SIDE_TILT and straight:
        return float(np.clip(np.arctan(tilt), HILL_SLOPE, ATOMIC_TERRAINS["pyramid_slope"].params["slope"].high))
    return HILL_SLOPE


WATER_ELONGATION = 4.0
"""Longest a patch of water on the ground may be along the view, in widths (a stream running away from the camera)."""


def _upright_water(water: np.ndarray, ground: np.ndarray, horizon: int) -> np.ndarray:
    """Water-coloured blobs that cannot lie on the ground: window panes, doors, signs, blue cars.

    Foreshortening (pinhole camera at ``CAMERA_HEIGHT`` over flat ground): a patch dX wide and dZ deep at
    distance Z spans f * dX / Z columns and f * CAMERA_HEIGHT * dZ / Z**2 rows, so rows / columns =
    (CAMERA_HEIGHT / Z) * (dZ / dX). A blob taller than that allows with dZ / dX = :data:`WATER_ELONGATION`, at
    the distance of its nearest (lowest) row, is upright, unless it narrows towards the horizon as a strip
    lying on the ground does (its width in the picture is f * dX / Z): a stream running away from the camera.
    """
    labels, n = ndimage.label(water & ground)
    out = np.zeros_like(water)
    for k, sl in enumerate(ndimage.find_objects(labels), start=1):
        blob = labels[sl] == k
        rows, cols = blob.shape
        z = Z_NEAR * (PH - horizon) / max(sl[0].stop - 0.5 - horizon, 0.5)  # distance of its lowest row's centre
        widths = blob.sum(1)
        quarter = max(rows // 4, 1)
        narrows = widths[:quarter].mean() < 0.6 * widths[-quarter:].mean()
        if rows / cols > WATER_ELONGATION * CAMERA_HEIGHT / z and not narrows:
            out[sl] |= blob
    return out


def read_photo(img: Image.Image, size_x: float = 20.0) -> PhotoReading:
    """Read a photo in perspective (module docstring) for a tile ``size_x`` m deep; the findings, before any tool
    call is made."""
    rgb = np.asarray(img.resize((PW, PH), Image.Resampling.BOX), np.float32) / 255.0
    h, s, v = _hsv(rgb)
    lum = rgb.mean(-1)
    grey = float(s.mean()) < 0.03
    sky, horizon = _sky_mask(rgb, h, s, v)
    rows = np.arange(PH)[:, None]
    above = ~sky & (rows < horizon)
    # Above the horizon: a hill (slope), clouds and far scenery (ignored), or tall obstacles.
    near_ground = np.median(rgb[int(0.8 * PH):].reshape(-1, 3), 0)
    classes = _classify_ground(rgb, h, s, v, lum)
    near_class = np.bincount(classes[int(0.8 * PH):].ravel(), minlength=len(SURFACES)).argmax()
    gx = np.abs(ndimage.sobel(ndimage.gaussian_filter(lum, 0.7), axis=1)) / 8
    sky_colour = np.median(rgb[sky], 0) if sky.any() else np.ones(3)
    objects = np.zeros_like(sky)
    slope = 0.0
    labels, _ = ndimage.label(above)
    for k, sl in enumerate(ndimage.find_objects(labels), start=1):
        comp = labels == k
        cols = np.flatnonzero(comp.any(0))
        rise = horizon - sl[0].start
        colour = rgb[comp].mean(0)
        width = len(cols) / PW
        inner = ndimage.binary_erosion(comp, iterations=2)
        detail = float(gx[inner].mean()) if inner.any() else 1.0  # windows, trunks and edges: not a hillside
        lower = comp & (rows >= (sl[0].start + horizon) / 2)
        same = np.bincount(classes[lower], minlength=len(SURFACES)).argmax() == near_class if lower.any() else False
        if width > 0.6 and rise >= 0.1 * PH and detail < 0.012 and (same or np.linalg.norm(colour - near_ground) < 0.2):
            top = np.argmax(comp[:, cols], axis=0).astype(float)  # the ridge: upper edge per column
            slope = max(slope, _hill_slope(cols, top, img.height / img.width))
            continue
        hue, sat = float(np.median(h[comp])), float(s[comp].mean())
        hazy = 180 <= hue < 260 and 0.05 <= sat < 0.45  # far mountains, blue with distance
        cloud = (sat < 0.25 and float(v[comp].mean()) > 0.6) or np.linalg.norm(colour - sky_colour) < 0.18
        if cloud or hazy or sl[0].stop < horizon - 1 or rise < 0.06 * PH:
            continue  # clouds, far scenery, a tree line on the horizon, or something not standing on the ground
        objects |= comp
    # Tall things reach down into the ground (building fronts, walls): grow them over similar colours.
    if objects.any():
        lab, m = ndimage.label(objects)
        for k in range(1, m + 1):
            comp = lab == k
            similar = (np.linalg.norm(rgb - rgb[comp].mean(0), axis=-1) < 0.1) & ~sky
            objects |= ndimage.binary_propagation(comp, mask=similar | comp)
        objects = ndimage.binary_fill_holes(objects)  # windows and doors belong to their building
    objects |= _standing(rgb, ~sky & ~objects & (rows >= horizon), horizon, classes)
    ground = ~sky & ~objects & (rows >= horizon)
    upright = _upright_water(classes == SURFACES.index("water"), ground, horizon)
    ground &= ~upright
    surface = np.where(ground, classes, -1)
    if grey:
        surface = np.where(surface >= 0, np.where(surface == SURFACES.index("gravel"), surface, SURFACES.index("grey")), -1)
    parts = _part_masks((PH, PW), horizon, ground, size_x)
    # Flow: foam or wave crests on the water (bright streaks), or a water band with land beyond (a river).
    water = surface == SURFACES.index("water")
    on_tile = np.any(list(parts.values()), axis=0)
    flow = "still"
    wrows = np.flatnonzero((water & on_tile).mean(1) > 0.3)  # rows mostly water
    if (water & on_tile).sum() > 0.03 * on_tile.sum() and len(wrows):
        band = np.zeros_like(water)
        band[wrows[0]:wrows[-1] + 1] = True  # rows from the first to the last mostly-water row
        # Foam and wave crests: streaks brighter and paler than the water across the band (read as ice or snow
        # pixel by pixel); reflected clouds are blobs and do not fill a row.
        pale = band & ground & (surface >= 0) & ((surface == SURFACES.index("ice")) | (surface == SURFACES.index("snow"))
                                                  | ((v > np.median(v[water]) + 0.1) & (s < 0.35)))
        wide = (water | pale)[wrows[0]:wrows[-1] + 1].mean(1) > 0.6
        streak_rows = int(((pale[wrows[0]:wrows[-1] + 1].mean(1) > 0.3) & wide).sum())
        surface[pale & ~water] = SURFACES.index("water")  # the crests are part of the water
        reaches_horizon = wrows[0] <= horizon + 0.1 * (PH - horizon)
        spans = (water & on_tile)[wrows].mean(1).min() > 0.85 if len(wrows) else False
        land_beyond = not reaches_horizon and spans and (water[horizon:wrows[0]] & on_tile[horizon:wrows[0]]).mean() < 0.1
        if streak_rows >= 2 or land_beyond:
            flow = "tide" if reaches_horizon else "current"
    water = surface == SURFACES.index("water")
    usable = ground & ~water
    stairs = _stairs(lum, usable)
    if stairs is not None:  # the flight is built as stairs: its edges are neither gravel nor rocks
        flight = np.zeros_like(usable)
        flight[horizon:, stairs[0]:stairs[1]] = True
        surface[flight & (surface == SURFACES.index("gravel"))] = SURFACES.index("grey")
        usable &= ~flight
    fractions = {name: {sf: float((surface[m] == i).mean()) if m.any() else 0.0 for i, sf in enumerate(SURFACES)}
                 for name, m in parts.items()}
    rocks_mask = _rock_blobs(lum, usable)
    rock_counts = {name: ndimage.label(rocks_mask & m)[1] for name, m in parts.items()}
    tall = {}
    for side, half in (("left", objects[:, :PW // 2]), ("right", objects[:, PW // 2:])):
        if half.sum() > 0.01 * PH * PW:
            tall[side] = "block" if half.any(0).mean() > 0.6 else "pillars"
    # Water across the whole view (a river, the sea) is one band at its distance, not a share of parts.
    band_rows = np.flatnonzero((surface == SURFACES.index("water")).mean(1) > 0.7)
    water_band = None
    if len(band_rows) and len(band_rows) >= 0.5 * (band_rows[-1] - band_rows[0] + 1):
        distance = lambda r: Z_NEAR * (PH - horizon) / max(r + 0.5 - horizon, 1e-6) - Z_NEAR  # noqa: E731
        far = 1e9 if band_rows[0] <= horizon + 0.1 * (PH - horizon) else distance(band_rows[0])
        water_band = (max(distance(band_rows[-1] + 1), 0.0), far)
    return PhotoReading(sky, horizon, ground, surface, objects, fractions, flow, slope, stairs, rock_counts, tall, grey,
                        water_band)


def _water_steps(flow: str) -> tuple[Step, ...]:
    """Knee-deep water, still or flowing, in the basin of the sketch's water (``LEGEND``) set in place of the
    part's relief: water over stairs or a hill read ahead would run off down them."""
    held, still = LEGEND["water"].steps
    held = dataclasses.replace(held, mode="set")
    if flow == "current":
        return held, Step("water", {**still.params, "flow": "current", "speed": 0.8, "direction": np.pi / 2})
    if flow == "tide":
        return held, Step("water", {**still.params, "flow": "tide", "speed": 0.4, "omega": 0.5, "direction": 0.0})
    return held, still


def _water_region(region: str | dict, size_x: float, size_y: float) -> dict[str, float]:
    """A photo's water region kept ``WATER_MARGIN`` off its edges inside the tile (the planner's rule): the parts
    beside it blend over them, and the spawn square at the tile's centre stays level. A band too thin to lose that
    (narrower than 2 * WATER_MARGIN once kept off) keeps its extent across: the water lies on the part's own ground."""
    rect = named_regions(size_x, size_y)[region] if isinstance(region, str) else tuple(region.values())
    x0, y0, x1, y1 = keep_off_seams(rect, rect, size_x, size_y, water=False)
    if x1 - x0 < 2 * WATER_MARGIN:
        x0, x1 = rect[0], rect[2]
    if y1 - y0 < 2 * WATER_MARGIN:
        y0, y1 = rect[1], rect[3]
    return {"x0": x0, "y0": y0, "x1": x1, "y1": y1}


def _merge(per_part: dict[str, tuple[str, ...]]) -> list[tuple[str, tuple[str, ...]]]:
    """Equal neighbouring parts merged into halves or the whole tile: (region name, surfaces)."""
    bl, br, fl, fr = (per_part[k] for k in ("back_left", "back_right", "front_left", "front_right"))
    if bl == br == fl == fr:
        return [("full", bl)]
    out = []
    if bl == br and fl == fr:
        return [("back", bl), ("front", fl)]
    if bl == fl and br == fr:
        return [("left", bl), ("right", br)]
    for band, (a, b) in (("back", (bl, br)), ("front", (fl, fr))):
        out += [(band, a)] if a == b else [(f"{band}_left", a), (f"{band}_right", b)]
    return out


def _plan_photo(img: Image.Image, size_x: float, size_y: float, notes: list[str], warnings: list[str]) -> list[tuple[Step, dict]]:
    r = read_photo(img, size_x)
    notes.append(f"read as a photo in perspective: sky above row {r.horizon} of {PH} dropped")
    if r.grey:
        warnings.append("greyscale photo: water, snow, sand, mud and ice cannot be told apart by colour; only "
                        "obstacles, stairs, slopes and roughness were read.")
    per_part: dict[str, tuple[str, ...]] = {}
    for name, frac in r.parts.items():
        ranked = sorted(frac, key=lambda k: -frac[k])
        # The dominant surface and at most one more (water: a basin and the water): with the base, slope, stairs,
        # 2 tall and 4 rock calls this bounds a photo to 1 + 1 + 1 + 4 * 3 + 2 + 4 = 21 <= MAX_CALLS calls; a water
        # band takes the parts' water, so with it 1 + 1 + 1 + 2 + 4 * 2 + 2 + 4 = 19.
        kept = [k for k in ranked if frac[k] >= MIN_SHARE.get(k, DEFAULT_SHARE) or (k == ranked[0] and frac[k] > 0)]
        chosen = tuple(sorted(kept[:2]))
        per_part[name] = chosen
    notes.append("parts: " + "; ".join(f"{k} {'+'.join(v) or 'nothing'}" for k, v in per_part.items()))
    grey_share = np.mean([f["grey"] for f in r.parts.values()])
    base = Step("flat", {"height": 0.0}) if grey_share > 0.5 else Step("natural_ground", {"amplitude": 0.04, "wavelength": 3.0, "platform": 0.0})
    out: list[tuple[Step, dict]] = [(base, {"region": "full"})]
    if r.slope > 0:
        out.append((Step("pyramid_slope", {"slope": r.slope, "direction": "up", "platform": 2.0}, mode="add"), {"region": "front"}))
        notes.append(f"a hill rises above the horizon: slope of {r.slope:.2f} rad ahead")
    if r.stairs is not None:
        c0, c1 = r.stairs
        y1, y0 = size_y * (1 - c0 / PW), size_y * (1 - c1 / PW)
        out.append((Step("stairs", {"step_height": 0.15, "step_width": 0.32, "direction": "up"}),
                    {"region": {"x0": 0.0, "y0": round(y0, 2), "x1": round(size_x, 2), "y1": round(y1, 2)}}))
        notes.append("one flight of stairs ahead")
    if r.water_band is not None:
        near, far = (round(min(d, size_x), 1) for d in r.water_band)
        if far - near >= 0.5:
            per_part = {k: tuple(sf for sf in v if sf != "water") for k, v in per_part.items()}
            region = "full" if (near, far) == (0.0, size_x) else {"x0": near, "y0": 0.0, "x1": far, "y1": size_y}
            out += [(step, {"region": _water_region(region, size_x, size_y)}) for step in _water_steps(r.flow)]
            notes.append(f"water across the view from {near:g} m to {far:g} m ahead ({r.flow})")
    for region, surfaces in _merge(per_part):
        for sf in surfaces:
            if sf == "water":
                out += [(step, {"region": _water_region(region, size_x, size_y)}) for step in _water_steps(r.flow)]
            else:
                out += [(step, {"region": region}) for step in SURFACE_STEPS[sf]]
    regions = named_regions(size_x, size_y)
    for side, kind in r.tall.items():
        x0, y0, x1, y1 = regions["front_" + side]
        if kind == "block":  # a building front or wall along that side of the tile
            strip = (y1 - 2.0, y1) if side == "left" else (y0, y0 + 2.0)
            out.append((Step("flat", {"height": 2.0}), {"region": {"x0": 2.0, "y0": strip[0], "x1": x1, "y1": strip[1]}}))
        else:
            out.append((SURFACE_STEPS["forest"][0], {"region": "front_" + side}))
        notes.append(f"tall obstacles on the {side} ({'building or wall' if kind == 'block' else 'trees or posts'})")
    rocky = {k: ("rocks",) if n >= MIN_ROCKS else () for k, n in r.rocks.items()}
    for region, found in _merge(rocky):
        if found:
            out.append((Step("rocks", {"max_height": 0.15, "min_radius": 0.1, "max_radius": 0.4, "density": 0.5}, mode="add"), {"region": region}))
    return out


SKETCH_STRETCH = 0.05
"""A sketch whose proportions differ from its tile's by more than this share is said to be stretched to it."""


def plan_image(
    image: str | Path | bytes | Image.Image,
    size_x: float = 20.0,
    size_y: float = 20.0,
    registry: Mapping[str, AtomicTerrain] | None = None,
    resolution: float | None = None,
) -> GenerationResult:
    """Deterministic tool calls for a photo or a colour-coded sketch map (see the module docstring); with the tile's
    ``resolution`` (m), a rectangle that holds no cell is skipped with a warning."""
    registry = ATOMIC_TERRAINS if registry is None else registry
    img = _load(image)
    name = str(image) if isinstance(image, (str, Path)) else "the image"
    warnings: list[str] = []
    notes: list[str] = []
    if is_sketch(img):
        # its top row is the tile's front: rows run along x, columns along y
        stretch = (img.height / img.width) / (size_x / size_y)
        if abs(stretch - 1.0) > SKETCH_STRETCH:
            warnings.append(f"the sketch is {img.width} x {img.height} pixels (width along y, height along x) and the "
                            f"tile {size_x:g} x {size_y:g} m: it is stretched {max(stretch, 1 / stretch):.2f} times "
                            f"more along {'y' if stretch > 1 else 'x'}; draw it in the tile's proportions (height / width = "
                            f"{size_x / size_y:g}) to keep its shapes.")
        steps = _plan_sketch(img, size_x, size_y, notes, warnings)
    elif img.width * img.height < PW * PH:  # upsampled, it has no sky texture, speckle or edges to read
        raise ValueError(f"{name} is a {img.width} x {img.height} pixel photo, fewer pixels than the {PW} x {PH} the "
                         f"photo reader analyses; pass a larger photo (or a sketch map in the legend's colours).")
    else:
        steps = _plan_photo(img, size_x, size_y, notes, warnings)
    geometric = [sr for sr in steps if registry[sr[0].tool].kind == "geometric"]
    physical = [sr for sr in steps if registry[sr[0].tool].kind == "physical"]
    calls: list[ToolCall] = []
    for step, layout in geometric + physical:
        args = {**step.params, **layout}
        if registry[step.tool].kind == "geometric":
            args["mode"] = step.mode
        try:
            calls.append(validate_call(step.tool, args, size_x, size_y, registry, resolution))
        except ValidationError as exc:  # e.g. a block thinner than a cell: report, keep the rest
            warnings += [f"skipped: {m}" for m in exc.messages]
    if len(calls) > SPEC_MAX_CALLS:  # only a sketch can: a photo gives at most MAX_CALLS
        raise ValueError(f"{name} needs {len(calls)} tool calls, more than a terrain holds ({SPEC_MAX_CALLS}); draw "
                         f"fewer, simpler shapes (each black blob and each rectangle of a surface is a call) and pass "
                         f"it again.")
    return GenerationResult(calls, warnings, notes, model=None)
