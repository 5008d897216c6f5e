"""Tile composition: a tile is a list of parts (rectangles in metres), each a sequence of atomic operations.

Parts are painted in order over the tile's ground: flat at 0 m, or a heightmap (``TileSpec.base``, read from a
``.npy`` file by :mod:`.heightmap`). Inside a part, its operations run on a working copy of
the tile's current heights: ``set`` replaces them with the atomic's heights, ``add`` adds the atomic's heights
(rocks on hills). The part then replaces the tile inside its rectangle, and fades out over a band of
``SEAM_BAND`` metres outside it (the atomic is generated over the rectangle widened by that band, weighted by
a smoothstep of the distance). Features farther than ``SEAM_BAND`` from a seam are kept exactly.

Physical operations (water, soil, low friction) are applied after all heights are final, in part order, to
their part's rectangle: water depth is measured from the lowest final ground of the rectangle. A current or tide
in the channel of a ``river`` flows along the river's meandering course (:func:`_follow_channels`).
Every random draw comes from ``SeedSequence(seed, spawn_key=(part, op))``: a tile is a pure function of its
spec, and changing one part does not reshuffle the others.
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Any, Callable, Literal, Mapping

import jsonschema
import numpy as np
from jsonschema import Draft202012Validator
from scipy import ndimage

from .atomic import river_course
from .heightmap import load_heightmap
from .materials import FLOW_CURRENT, FLOW_TIDE, NO_SOIL, NO_WATER, MaterialMap, MaterialPatch
from .registry import ATOMIC_TERRAINS, AtomicTerrain

SPEC_VERSION = 1
"""Format version of the terrain spec document (``spec.json``) this code reads and writes."""
SEAM_BAND = 0.3
"""Width (m) of the band outside a part over which it blends into what lies below."""

MAX_ABS_HEIGHT = 10.0
"""Largest |height| (m) a tile may have; beyond it a spec is rejected (the hfield and the robot's scan need it)."""


@dataclasses.dataclass
class Region:
    """A rectangle in metres inside a tile: x in [x0, x1), y in [y0, y1), origin at the tile's corner."""

    x0: float
    y0: float
    x1: float
    y1: float

    def check(self, size_x: float, size_y: float) -> None:
        if not (0.0 <= self.x0 < self.x1 <= size_x + 1e-9 and 0.0 <= self.y0 < self.y1 <= size_y + 1e-9):
            raise ValueError(
                f"region {self} is not inside the {size_x} x {size_y} m tile; need 0 <= x0 < x1 <= {size_x} "
                f"and 0 <= y0 < y1 <= {size_y}."
            )

    def cells(self, resolution: float) -> tuple[int, int, int, int]:
        """Cell index range [i0, i1) x [j0, j1) of the cells (at i * resolution) inside the rectangle."""
        i0, j0 = math.ceil(self.x0 / resolution - 1e-6), math.ceil(self.y0 / resolution - 1e-6)
        i1, j1 = math.ceil(self.x1 / resolution - 1e-6), math.ceil(self.y1 / resolution - 1e-6)
        if i1 <= i0 or j1 <= j0:
            raise ValueError(f"region {self} holds no cell at resolution {resolution} m; make it larger.")
        return i0, j0, i1, j1


QUADRANTS: dict[str, Callable[[float, float], Region]] = {
    "front_left": lambda sx, sy: Region(sx / 2, sy / 2, sx, sy),
    "front_right": lambda sx, sy: Region(sx / 2, 0.0, sx, sy / 2),
    "back_left": lambda sx, sy: Region(0.0, sy / 2, sx / 2, sy),
    "back_right": lambda sx, sy: Region(0.0, 0.0, sx / 2, sy / 2),
}
"""GenTe's four quadrants of a tile (+x is front, +y is left)."""


def quadrant(name: str, size_x: float, size_y: float) -> Region:
    if name not in QUADRANTS:
        raise ValueError(f"unknown quadrant {name!r}; use one of {list(QUADRANTS)}.")
    return QUADRANTS[name](size_x, size_y)


def named_regions(size_x: float, size_y: float) -> dict[str, tuple[float, float, float, float]]:
    """Named regions of a ``size_x`` x ``size_y`` m tile as ``(x0, y0, x1, y1)`` metres.

    The four quadrants come from ``QUADRANTS``; the halves ("front", "back", "left",
    "right") and "full" are unions of them, so the layout vocabulary has one source.
    """
    quads = {name: quadrant(name, size_x, size_y) for name in QUADRANTS}
    rects = {name: (float(r.x0), float(r.y0), float(r.x1), float(r.y1)) for name, r in quads.items()}

    def union(*names: str) -> tuple[float, float, float, float]:
        rs = [rects[n] for n in names]
        return (min(r[0] for r in rs), min(r[1] for r in rs), max(r[2] for r in rs), max(r[3] for r in rs))

    out = {"full": union(*rects)}
    for side in ("front", "back", "left", "right"):
        out[side] = union(*[n for n in rects if side in n.split("_")])
    out.update(rects)
    return out


@dataclasses.dataclass
class Operation:
    """One atomic terrain applied to a part: ``set`` replaces heights, ``add`` adds to them.

    The mode of a physical terrain is ignored (materials are always painted).
    """

    terrain: str
    params: dict[str, Any] = dataclasses.field(default_factory=dict)
    mode: Literal["set", "add"] = "set"

    def atomic(self) -> AtomicTerrain:
        if self.terrain not in ATOMIC_TERRAINS:
            raise ValueError(f"unknown atomic terrain {self.terrain!r}; use one of {sorted(ATOMIC_TERRAINS)}.")
        if self.mode not in ("set", "add"):
            raise ValueError(f"operation {self.terrain}: mode {self.mode!r} must be 'set' or 'add'.")
        return ATOMIC_TERRAINS[self.terrain]


@dataclasses.dataclass
class Part:
    region: Region
    ops: list[Operation]


MAX_SMOOTHING_SIGMA = 2.0
"""Largest standard deviation (m) of a smoothing filter."""

MAX_CALLS = 64
"""Most tool calls in one spec (GenTe's prompts ask for 3-20)."""
LAYOUT_ARGS = ("region", "mode")
"""A call's layout, beside its ``params``; no terrain may declare a parameter with one of these names."""

SPEC_SCHEMA: dict[str, Any] = {
    "type": "object",
    "properties": {
        "version": {"const": SPEC_VERSION, "description": f"spec format version; this code reads {SPEC_VERSION}"},
        "name": {"type": "string", "pattern": r"^[A-Za-z][A-Za-z0-9_]*\Z", "maxLength": 64,
                 "description": "a letter, then letters, digits or underscores, e.g. forest_trail"},
        "size_x": {"type": "number", "minimum": 1.0, "maximum": 200.0, "description": "tile length along x [m]"},
        "size_y": {"type": "number", "minimum": 1.0, "maximum": 200.0, "description": "tile width along y [m]"},
        "resolution": {"type": "number", "minimum": 0.02, "maximum": 1.0, "description": "cell size [m]"},
        "seed": {"type": "integer", "minimum": 0, "maximum": 2**32 - 1},
        "calls": {
            "type": "array",
            "maxItems": MAX_CALLS,
            "items": {
                "type": "object",
                "properties": {
                    "tool": {"type": "string"},
                    "region": {},
                    "mode": {"type": "string"},
                    "params": {"type": "object"},
                },
                "required": ["tool", "region", "params"],
                "additionalProperties": False,
            },
        },
        "source": {"type": "object", "maxProperties": 16},
        "backend": {"type": "string", "maxLength": 256},
        "model": {"type": ["string", "null"], "maxLength": 256},
        "smoothing": {
            "type": "array",
            "maxItems": 16,
            "description": "Gaussian filters of the heights after the geometric calls, in order",
            "items": {
                "type": "object",
                "properties": {"region": {}, "axis": {"enum": ["x", "y"]},
                               "sigma": {"type": "number", "exclusiveMinimum": 0, "maximum": MAX_SMOOTHING_SIGMA}},
                "required": ["region", "axis", "sigma"],
                "additionalProperties": False,
            },
        },
        "heightmap": {
            "type": "object",
            "description": "ground under the calls: a .npy array (relative to the spec file), one value per cell "
                           "of `resolution` m, times vertical_scale metres",
            "properties": {"file": {"type": "string", "maxLength": 1000},
                           "vertical_scale": {"type": "number", "exclusiveMinimum": 0, "maximum": 1.0}},
            "required": ["file", "vertical_scale"],
            "additionalProperties": False,
        },
    },
    "required": ["version", "name", "size_x", "size_y", "resolution", "seed", "calls", "source", "backend", "model"],
    "additionalProperties": False,
}
def params_layout_problem(params: Mapping[str, Any]) -> str | None:
    """Why a call's ``params`` cannot go to its terrain as they are (None if they can): a layout argument among them,
    which the terrain function would refuse as unknown."""
    layout = sorted(set(params) & set(LAYOUT_ARGS))
    return (f"'params' holds the layout argument(s) {layout}; put 'region' and 'mode' beside 'params', not in it"
            if layout else None)


TILE_FIELDS = ("size_x", "size_y", "resolution", "seed", "calls")
"""What a spec document needs to be built; the other required fields are gente-generate's records (version, name,
provenance), which a hand-written spec may leave out."""


def clip_text(text: str, limit: int) -> str:
    """``text`` cut to ``limit`` characters, saying how long it was: a huge input is never echoed whole."""
    if len(text) <= limit:
        return text
    tail = f"... ({len(text)} characters in all)"
    return text[: max(limit - len(tail), 0)] + tail


def schema_size_problem(err: jsonschema.ValidationError) -> str | None:
    """'has N items; at most M are allowed' for a list, string or object over its schema's size limit, else None."""
    limits = {"maxItems": "items", "maxLength": "characters", "maxProperties": "entries"}
    if err.validator not in limits:
        return None
    return f"has {len(err.instance)} {limits[err.validator]}; at most {err.validator_value} are allowed"


def _describe_spec_error(err: jsonschema.ValidationError) -> str:
    field = ".".join(map(str, err.absolute_path))[:60] or "(document)"
    too_long = schema_size_problem(err)
    if too_long:
        return f"spec: field {field!r} {too_long}."
    if err.validator == "pattern" and "description" in err.schema:  # what it must be, not the regular expression
        return f"spec: field {field!r}: {clip_text(repr(err.instance), 80)} is not {err.schema['description']}."
    return f"spec: field {field!r}: {clip_text(err.message, 160)}."


def spec_document_problems(data: Any, tile_only: bool = False, most: int = 20) -> list[str]:
    """Where ``data`` departs from :data:`SPEC_SCHEMA` (a field of the wrong type or range, one unknown or missing),
    one sentence each, at most ``most``. ``tile_only`` requires only :data:`TILE_FIELDS`."""
    schema = {**SPEC_SCHEMA, "required": list(TILE_FIELDS)} if tile_only else SPEC_SCHEMA
    errors = sorted(Draft202012Validator(schema).iter_errors(data), key=lambda e: list(map(str, e.absolute_path)))
    return [_describe_spec_error(e) for e in errors[:most]]


@dataclasses.dataclass
class Smoothing:
    """A Gaussian filter of the heights along one axis inside a rectangle, after every geometric part (GenTe
    smooths its tiles so after its calls): each line of cells along ``axis`` is convolved with a Gaussian of
    standard deviation ``sigma`` m, the rectangle's edge cells repeated beyond it (``scipy.ndimage.gaussian_filter1d``,
    mode "nearest"). A convex combination of the heights inside the rectangle: it never leaves their range."""

    region: Region
    axis: Literal["x", "y"]
    sigma: float

    def check(self, size_x: float, size_y: float) -> None:
        self.region.check(size_x, size_y)
        if self.axis not in ("x", "y"):
            raise ValueError(f"smoothing: axis {self.axis!r} must be 'x' or 'y'.")
        if not 0.0 < self.sigma <= MAX_SMOOTHING_SIGMA:
            raise ValueError(f"smoothing: sigma={self.sigma!r} m must be in (0, {MAX_SMOOTHING_SIGMA}] m.")


def read_json(text: str, what: str) -> Any:
    """``json.loads`` of a terrain document, its refusals one line naming ``what``: nesting too deep for Python's
    parser, an integer too long for it to read, or no JSON at all."""
    try:
        return json.loads(text)
    except RecursionError:
        raise ValueError(f"{what} is nested too deeply to read; a terrain spec nests a few levels") from None
    except ValueError as exc:  # json.JSONDecodeError, or int() of more digits than Python reads
        if "integer string conversion" in str(exc):
            raise ValueError(f"{what} holds an integer of more than 4300 digits; use a number below 2**53") from None
        raise ValueError(f"{what} is not valid JSON ({str(exc)[:160]})") from None


TILE_DICT_KEYS = {"size_x", "size_y", "resolution", "seed", "parts", "smoothing"}
"""The keys of :meth:`TileSpec.to_dict`'s form."""


@dataclasses.dataclass
class TileSpec:
    """A tile of ``size_x`` x ``size_y`` m at ``resolution`` m: parts painted in order, random draws from ``seed``.

    ``base``: the ground the parts are painted on (float32 metres, one value per cell), or None for flat 0 m.
    ``smoothing``: filters applied in order after the geometric parts, before the physical ones paint.
    """

    size_x: float
    size_y: float
    resolution: float
    seed: int
    parts: list[Part]
    base: np.ndarray | None = None
    smoothing: list[Smoothing] = dataclasses.field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        if self.base is not None:
            raise ValueError("a tile on a heightmap has no dict form; keep the spec document that names its .npy file.")
        return {
            "size_x": float(self.size_x),
            "size_y": float(self.size_y),
            "resolution": float(self.resolution),
            "seed": int(self.seed),
            "parts": [
                {
                    "region": [float(p.region.x0), float(p.region.y0), float(p.region.x1), float(p.region.y1)],
                    "ops": [{"terrain": o.terrain, "params": _json_params(o.params), "mode": o.mode} for o in p.ops],
                }
                for p in self.parts
            ],
        } | ({"smoothing": [{"region": [float(f.region.x0), float(f.region.y0), float(f.region.x1),
                                        float(f.region.y1)], "axis": f.axis, "sigma": float(f.sigma)}
                             for f in self.smoothing]} if self.smoothing else {})

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "TileSpec":
        try:
            parts = [
                Part(Region(*map(float, p["region"])), [Operation(o["terrain"], dict(o.get("params", {})), o.get("mode", "set")) for o in p["ops"]])
                for p in d["parts"]
            ]
            smoothing = [Smoothing(Region(*map(float, f["region"])), f["axis"], float(f["sigma"]))
                         for f in d.get("smoothing", [])]
            return cls(float(d["size_x"]), float(d["size_y"]), float(d["resolution"]), int(d["seed"]), parts,
                       smoothing=smoothing)
        except (KeyError, TypeError) as exc:
            raise ValueError(
                f"tile spec dict is malformed ({exc!r}); expected keys size_x, size_y, resolution, seed and "
                f"parts = [{{'region': [x0, y0, x1, y1], 'ops': [{{'terrain', 'params', 'mode'}}]}}] (and "
                f"optionally smoothing = [{{'region', 'axis', 'sigma'}}])."
            ) from None

    def build(self, ground_friction: float = 1.0) -> tuple[np.ndarray, MaterialMap]:
        return build_tile(self, ground_friction)


def tile_spec_from_document(data: Any, base_dir: str | Path | None = None) -> TileSpec:
    """The tile of a terrain spec document, the ``spec.json`` that gente-generate writes: ``size_x``, ``size_y``,
    ``resolution``, ``seed`` and ``calls`` of ``{"tool", "region" (a named region or {x0, y0, x1, y1}), "params",
    "mode"}`` applied in order. The document's fields are checked against :data:`SPEC_SCHEMA` (of gente-generate's
    records only the version, if given), the parameters and regions when the tile is built; the generation package
    validates whole documents (``TerrainSpec.load``: every call against its tool) and builds its tiles through this
    function.

    An optional ``"heightmap": {"file": "map.npy", "vertical_scale": 0.005}`` makes the array in ``file`` (a path
    relative to ``base_dir``, the spec file's folder) the ground under the calls: one value per ``resolution``
    cell, times ``vertical_scale`` metres; ``size_x`` and ``size_y`` must be its cells times ``resolution``.
    An optional ``"smoothing": [{"region", "axis": "x" | "y", "sigma" (m)}]`` filters the heights after the
    geometric calls (:class:`Smoothing`). A tile composed in Python is taken in its own form too, the dict of
    :meth:`TileSpec.to_dict` (``parts`` of ``ops`` in place of ``calls``), which builds the very same tile."""
    if isinstance(data, dict) and "parts" in data and "calls" not in data:  # TileSpec.to_dict()'s form
        unknown = sorted(set(data) - TILE_DICT_KEYS)
        if unknown:
            raise ValueError(f"tile spec dict has unknown key(s) {unknown}; its keys are {sorted(TILE_DICT_KEYS)} "
                             f"(TileSpec.to_dict)")
        return TileSpec.from_dict(data)
    if isinstance(data, dict) and data.get("version", SPEC_VERSION) != SPEC_VERSION:
        raise ValueError(f"terrain spec format version {data['version']!r}; this code reads version {SPEC_VERSION}: "
                         f"generate the spec again")
    problems = spec_document_problems(data, tile_only=True, most=3)
    if problems:  # a misspelt field would otherwise be left out unseen, a quoted number read as one
        raise ValueError(f"not a terrain spec document: {' '.join(problems)} Fix the file, or pass a spec.json "
                         f"written by gente-generate")
    size_x, size_y, resolution = (float(data[k]) for k in ("size_x", "size_y", "resolution"))
    if not all(math.isfinite(v) for v in (size_x, size_y, resolution)):  # JSON's NaN passes the schema's bounds
        raise ValueError(f"terrain spec: size_x {size_x:g}, size_y {size_y:g} and resolution {resolution:g} must be "
                         f"finite numbers of metres")
    for i, call in enumerate(data["calls"]):
        problem = params_layout_problem(call["params"])
        if problem:
            raise ValueError(f"terrain spec: calls[{i}]: {problem}")
    regions = named_regions(size_x, size_y)
    parts = [Part(document_region(call["region"], regions),
                  [Operation(call["tool"], dict(call["params"]), call.get("mode") or "set")]) for call in data["calls"]]
    smoothing = [Smoothing(document_region(entry["region"], regions), entry["axis"], float(entry["sigma"]))
                 for entry in data.get("smoothing", [])]
    heightmap = data.get("heightmap")
    base = None if heightmap is None else heightmap_ground(heightmap, size_x, size_y, resolution, base_dir)
    return TileSpec(size_x, size_y, resolution, int(data["seed"]), parts, base, smoothing)


def document_region(region: Any, regions: Mapping[str, tuple[float, float, float, float]]) -> Region:
    """A spec document's region: a named one (``regions``, from :func:`named_regions`) or ``{x0, y0, x1, y1}`` in m."""
    if isinstance(region, str):
        if region not in regions:
            raise ValueError(f"terrain spec: region {region!r} is none of the named regions "
                             f"({', '.join(regions)}); or give a rectangle {{x0, y0, x1, y1}} in metres")
        return Region(*regions[region])
    try:
        return Region(*(float(region[k]) for k in ("x0", "y0", "x1", "y1")))
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"terrain spec: region {region!r} is neither a named region nor a rectangle "
                         f"{{x0, y0, x1, y1}} ({type(exc).__name__}: {exc})") from None


def heightmap_ground(entry: Any, size_x: float, size_y: float, resolution: float,
                     base_dir: str | Path | None = None) -> np.ndarray:
    """A spec document's ``heightmap`` entry read as the ground of a ``size_x`` x ``size_y`` m tile (float32 m)."""
    if not isinstance(entry, dict) or set(entry) != {"file", "vertical_scale"} or not isinstance(entry["file"], str):
        raise ValueError('"heightmap" must be {"file": "<map>.npy", "vertical_scale": <metres per unit>}; '
                         'the cell size is the spec\'s resolution')
    path = Path(entry["file"])
    if not path.is_absolute():
        path = Path(base_dir or ".") / path
    heights = load_heightmap(path, entry["vertical_scale"], MAX_ABS_HEIGHT)
    cells = tuple(n / resolution for n in (size_x, size_y))
    if any(abs(c - n) > 1e-6 for c, n in zip(cells, heights.shape)):
        raise ValueError(f"heightmap {path.name[:100]} has {heights.shape[0]} x {heights.shape[1]} cells; at "
                         f"resolution {resolution:g} m that is size_x={heights.shape[0] * resolution:g}, "
                         f"size_y={heights.shape[1] * resolution:g} m, not {size_x:g} x {size_y:g} m: set those")
    return heights


def stacked_height_bounds(spec: TileSpec, registry: Mapping[str, AtomicTerrain] | None = None) -> "HeightBounds":
    """Bounds on every height the builder can make from ``spec``: interval arithmetic over its parts in order.

    The tile is cut at every part's rectangle and its seam band (``SEAM_BAND`` m wide). It starts as the
    ground's range (0 m, or the heightmap's min..max); inside a rectangle a ``set`` operation gives the
    atomic's declared range (``height_bounds`` on the rectangle widened by the band, as the builder generates
    it) and an ``add`` operation shifts the current range by it; in the band the builder blends old and new
    heights convexly, so the range is the union of both; a smoothing filter mixes the heights inside its rectangle,
    so there the range is that of all of them; ice raises its rectangle's cells to at least its surface, ``depth``
    above the rectangle's lowest height. Parameters are checked and their defaults filled (``check_params``), as the
    builder fills them.
    """
    registry = ATOMIC_TERRAINS if registry is None else registry
    band = SEAM_BAND
    smoothed = [(f.region.x0, f.region.y0, f.region.x1, f.region.y1) for f in spec.smoothing]
    rects = [(p.region.x0, p.region.y0, p.region.x1, p.region.y1) for p in spec.parts]
    edges_x = {v for r in rects for v in (r[0] - band, r[0], r[2], r[2] + band)} | {v for r in smoothed for v in (r[0], r[2])}
    edges_y = {v for r in rects for v in (r[1] - band, r[1], r[3], r[3] + band)} | {v for r in smoothed for v in (r[1], r[3])}
    cut_x = sorted({0.0, float(spec.size_x)} | {min(max(v, 0.0), spec.size_x) for v in edges_x})
    cut_y = sorted({0.0, float(spec.size_y)} | {min(max(v, 0.0), spec.size_y) for v in edges_y})
    cx = (np.array(cut_x[:-1]) + np.array(cut_x[1:]))[:, None] / 2.0
    cy = (np.array(cut_y[:-1]) + np.array(cut_y[1:]))[None, :] / 2.0
    ground = (0.0, 0.0) if spec.base is None else (float(spec.base.min()), float(spec.base.max()))
    lo = np.full((cx.shape[0], cy.shape[1]), ground[0])
    hi = np.full_like(lo, ground[1])
    first_beyond = None
    for k, (part, (x0, y0, x1, y1)) in enumerate(zip(spec.parts, rects)):
        for op in part.ops:
            atomic = registry[op.terrain]
            if atomic.kind != "geometric":
                continue
            a, b = atomic.height_bounds(atomic.check_params(dict(op.params)), x1 - x0 + 2 * band, y1 - y0 + 2 * band)
            new_lo, new_hi = (np.full_like(lo, a), np.full_like(hi, b)) if op.mode == "set" else (lo + a, hi + b)
            inside = (cx > x0) & (cx < x1) & (cy > y0) & (cy < y1)
            near = (cx > x0 - band) & (cx < x1 + band) & (cy > y0 - band) & (cy < y1 + band)
            lo = np.where(inside, new_lo, np.where(near, np.minimum(lo, new_lo), lo))
            hi = np.where(inside, new_hi, np.where(near, np.maximum(hi, new_hi), hi))
            if first_beyond is None and max(-float(lo.min()), float(hi.max())) > MAX_ABS_HEIGHT:
                first_beyond = k
    for x0, y0, x1, y1 in smoothed:  # a filter mixes the heights inside its rectangle: their range bounds it
        inside = (cx > x0) & (cx < x1) & (cy > y0) & (cy < y1)
        if inside.any():
            lo, hi = np.where(inside, lo[inside].min(), lo), np.where(inside, hi[inside].max(), hi)
    for k, (part, (x0, y0, x1, y1)) in enumerate(zip(spec.parts, rects)):  # then the materials: ice raises the
        for op in part.ops:  # ground to its surface, depth above the region's lowest ground
            inside = (cx > x0) & (cx < x1) & (cy > y0) & (cy < y1)
            if op.terrain == "ice" and inside.any():
                depth = float(registry["ice"].check_params(dict(op.params))["depth"])
                lo = np.where(inside, np.maximum(lo, lo[inside].min() + depth), lo)
                hi = np.where(inside, np.maximum(hi, hi[inside].min() + depth), hi)
                if first_beyond is None and float(hi.max()) > MAX_ABS_HEIGHT:
                    first_beyond = k
    return HeightBounds(np.array(cut_x), np.array(cut_y), lo, hi, first_beyond)


@dataclasses.dataclass
class HeightBounds:
    """Height bounds (m) per cell of the grid cut at ``cuts_x`` x ``cuts_y`` m (see :func:`stacked_height_bounds`)."""

    cuts_x: np.ndarray
    cuts_y: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    first_beyond: int | None
    """Index of the first part after which |height| may exceed ``MAX_ABS_HEIGHT`` (None: never)."""

    @property
    def peak(self) -> float:
        return max(-float(self.lo.min()), float(self.hi.max()))

    def at(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) at points (m from the tile corner); a point on a cut takes the looser of its two sides."""
        x, y = np.broadcast_arrays(np.asarray(x, np.float64), np.asarray(y, np.float64))
        nx, ny = self.lo.shape
        bounds = []
        for side in ("left", "right"):
            i = np.clip(np.searchsorted(self.cuts_x, x, side=side) - 1, 0, nx - 1)
            j = np.clip(np.searchsorted(self.cuts_y, y, side=side) - 1, 0, ny - 1)
            bounds.append((self.lo[i, j], self.hi[i, j]))
        (lo_a, hi_a), (lo_b, hi_b) = bounds
        lo = np.minimum(lo_a, lo_b)
        hi = np.maximum(hi_a, hi_b)
        return lo, hi


def _json_params(params: dict[str, Any]) -> dict[str, Any]:
    return {k: (v.item() if isinstance(v, np.generic) else v) for k, v in params.items()}


def _shape(spec: TileSpec) -> tuple[int, int]:
    if not spec.resolution > 0:
        raise ValueError(f"resolution must be > 0 m, got {spec.resolution}.")
    n = (spec.size_x / spec.resolution, spec.size_y / spec.resolution)
    if not all(math.isfinite(v) for v in n) or min(n) < 1 or any(abs(v - round(v)) > 1e-6 for v in n):
        raise ValueError(
            f"tile {spec.size_x} x {spec.size_y} m is not a whole number (>= 1) of {spec.resolution} m cells; "
            f"pick sizes that are multiples of the resolution."
        )
    return int(round(n[0])), int(round(n[1]))


def _seam_weight(lo: int, hi: int, pad: int, resolution: float) -> np.ndarray:
    """Per-axis distance (m) outside [lo, hi) of the padded cells lo - pad .. hi + pad - 1."""
    idx = np.arange(lo - pad, hi + pad)
    return np.maximum(np.maximum(lo - idx, idx - (hi - 1)), 0) * resolution


def height_advice(atomic: AtomicTerrain, params: dict[str, Any], size_x: float, size_y: float) -> str:
    """Which parameters to lower or raise to shrink ``atomic``'s declared heights on a ``size_x`` x ``size_y`` m
    region: those whose bound (lowest or highest value) gives a smaller peak of its ``height_bounds``."""

    def peak(changed: dict[str, Any]) -> float:
        lo, hi = atomic.height_bounds({**params, **changed}, size_x, size_y)
        return max(-lo, hi)

    now = peak({})
    numeric = {k: p for k, p in atomic.params.items() if p.choices is None}
    lower = [k for k, p in numeric.items() if peak({k: p.low}) < now]
    higher = [k for k, p in numeric.items() if peak({k: p.high}) < now]
    return " or ".join(filter(None, [lower and f"lower its {', '.join(lower)}",
                                     higher and f"raise its {', '.join(higher)}"]))


def build_tile(spec: TileSpec, ground_friction: float = 1.0) -> tuple[np.ndarray, MaterialMap]:
    """Heights (float32 (nx, ny), m) and MaterialMap of ``spec``; rigid ground has ``ground_friction``."""
    nx, ny = _shape(spec)
    res = spec.resolution
    if spec.base is not None and spec.base.shape != (nx, ny):
        raise ValueError(f"the tile's heightmap has {spec.base.shape} cells; its {spec.size_x} x {spec.size_y} m at "
                         f"{spec.resolution} m need {(nx, ny)}.")
    heights = np.zeros((nx, ny), np.float64) if spec.base is None else spec.base.astype(np.float64)
    material = MaterialMap.rigid((nx, ny), friction=ground_friction)
    pad = int(math.ceil(SEAM_BAND / res))
    # per cell, the distance across to the nearest river course whose channel the final ground holds (inf: none),
    # that river's axis and its course's tangent (rad) and the flow's speed-up there: a current or tide painted
    # there follows it
    course_distance = np.full((nx, ny), np.inf)
    course_axis = np.zeros((nx, ny))
    course_angle = np.zeros((nx, ny))
    course_speedup = np.ones((nx, ny))
    physical: list[tuple[int, int, int, int, Operation, AtomicTerrain, dict[str, Any], np.random.Generator]] = []

    for k, part in enumerate(spec.parts):
        part.region.check(spec.size_x, spec.size_y)
        i0, j0, i1, j1 = part.region.cells(res)
        geometric = []
        for m, op in enumerate(part.ops):
            atomic = op.atomic()
            params = atomic.check_params(op.params)
            rng = np.random.default_rng(np.random.SeedSequence(spec.seed, spawn_key=(k, m)))
            if atomic.kind == "physical":
                physical.append((i0, j0, i1, j1, op, atomic, params, rng))
            else:
                geometric.append((op, atomic, params, rng))
        if not geometric:
            continue
        _mark_channels(course_distance, course_axis, course_angle, course_speedup, geometric, (i0, j0, i1, j1), res)
        # Working copy over the padded rectangle; cells beyond the tile repeat the tile's edge.
        ii = np.clip(np.arange(i0 - pad, i1 + pad), 0, nx - 1)
        jj = np.clip(np.arange(j0 - pad, j1 + pad), 0, ny - 1)
        work = heights[ii[:, None], jj[None, :]]
        for op, atomic, params, rng in geometric:
            out = atomic.fn(work.shape, res, rng, **params)
            if out.shape != work.shape or not np.all(np.isfinite(out)):
                raise RuntimeError(f"atomic terrain {op.terrain} returned a bad array (shape {out.shape}, or non-finite values).")
            work = out.astype(np.float64) if op.mode == "set" else work + out
        dx = _seam_weight(i0, i1, pad, res)[:, None]
        dy = _seam_weight(j0, j1, pad, res)[None, :]
        t = np.clip(1.0 - np.sqrt(dx * dx + dy * dy) / SEAM_BAND, 0.0, 1.0)
        w = t * t * (3.0 - 2.0 * t)
        # Crop the padding that falls outside the tile.
        ci = slice(max(pad - i0, 0), work.shape[0] - max(i1 + pad - nx, 0))
        cj = slice(max(pad - j0, 0), work.shape[1] - max(j1 + pad - ny, 0))
        ti = slice(max(i0 - pad, 0), min(i1 + pad, nx))
        tj = slice(max(j0 - pad, 0), min(j1 + pad, ny))
        heights[ti, tj] = heights[ti, tj] * (1.0 - w[ci, cj]) + work[ci, cj] * w[ci, cj]
        peak = float(np.abs(heights).max())
        if peak > MAX_ABS_HEIGHT:
            if any(op.mode == "add" for op, *_ in geometric):
                advice = "its 'add' operations stack their heights on those below: lower them or stack fewer"
            else:  # the last 'set' alone made these heights: the seam blend never leaves the range of both sides
                op, atomic, params, _ = geometric[-1]
                advice = f"{op.terrain} alone does: {height_advice(atomic, params, *(n * res for n in work.shape))}"
            raise ValueError(f"part {k} ({[o.terrain for o in part.ops]}) makes |height| reach {peak:.2f} m > "
                             f"{MAX_ABS_HEIGHT} m; {advice}.")

    for f in spec.smoothing:
        f.check(spec.size_x, spec.size_y)
        i0, j0, i1, j1 = f.region.cells(res)
        heights[i0:i1, j0:j1] = ndimage.gaussian_filter1d(heights[i0:i1, j0:j1], f.sigma / res,
                                                          axis=0 if f.axis == "x" else 1, mode="nearest")
    heights = heights.astype(np.float32)
    for i0, j0, i1, j1, op, atomic, params, rng in physical:
        patch = atomic.fn((i1 - i0, j1 - j0), res, rng, heights[i0:i1, j0:j1], **params)
        material.paint(patch, i0, j0)
        if patch.ice_surface is not None:  # frozen water: the ground rises to the ice, water at or below it freezes
            # and soil painted before lies under it (a frozen bog is ice to walk on, not mud)
            win = (slice(i0, i1), slice(j0, j1))
            frozen = patch.ice_surface > NO_WATER / 2
            top = float(patch.ice_surface[frozen].max(initial=0.0))
            if top > MAX_ABS_HEIGHT:
                raise ValueError(f"{op.terrain} on cells ({i0}, {j0})-({i1}, {j1}) stands at {top:.2f} m > "
                                 f"{MAX_ABS_HEIGHT} m; lower its depth or lay it on lower ground.")
            heights[win][frozen] = patch.ice_surface[frozen]
            material.drain(win, frozen & (material.water_surface[win] <= patch.ice_surface))
            material.soil[win][frozen] = NO_SOIL
        if patch.water_surface is not None and patch.flow_kind in (FLOW_CURRENT, FLOW_TIDE):
            _follow_channels(material, patch, i0, j0, course_distance, course_axis, course_angle, course_speedup)
    return heights, material


def _mark_channels(distance: np.ndarray, axis: np.ndarray, angle: np.ndarray, speedup: np.ndarray, geometric: list,
                   cells: tuple[int, int, int, int], res: float) -> None:
    """Record in ``distance`` / ``axis`` / ``angle`` / ``speedup`` (tile arrays, see :func:`build_tile`) the river
    channels a part leaves in its rectangle of ``cells`` (i0, j0, i1, j1); where channels overlap, the nearest
    course's.

    A ``set`` operation replaces the ground, so it erases the channels laid before it (by earlier parts in the
    rectangle, by earlier operations of the part); ``add`` keeps them. A river's frame is centred on the part's
    rectangle, as its padded working copy is. The seam band, where the part only blends in, takes no channel.
    """
    i0, j0, i1, j1 = cells
    rivers: list[dict[str, Any]] = []
    for op, _, params, _ in geometric:
        carves = op.terrain == "river" and params["depth"] > 0.0
        rivers = ([] if op.mode == "set" else rivers) + ([params] if carves else [])
    win = (slice(i0, i1), slice(j0, j1))
    if any(op.mode == "set" for op, *_ in geometric):
        distance[win] = np.inf
    x = (np.arange(i0, i1) - (i0 + i1 - 1) / 2.0)[:, None] * res
    y = (np.arange(j0, j1) - (j0 + j1 - 1) / 2.0)[None, :] * res
    for params in rivers:
        d, a, faster = river_course(x, y, params)
        nearer = (d < params["width"] / 2.0) & (d < distance[win])
        distance[win][nearer] = d[nearer]
        axis[win][nearer] = params["direction"]
        angle[win][nearer] = a[nearer]
        speedup[win][nearer] = np.broadcast_to(faster, d.shape)[nearer]


def _follow_channels(material: MaterialMap, patch: MaterialPatch, i0: int, j0: int, distance: np.ndarray,
                     axis: np.ndarray, angle: np.ndarray, speedup: np.ndarray) -> None:
    """Turn the flow that ``patch`` (at cell i0, j0) painted in a river's channel along the course's tangent, in
    the sense down the river's axis that points the same way as the water's own direction (cos of the difference
    between the axis and the water's direction >= 0): one channel carries its water one way, also where a bend
    turns the tangent more than 90 degrees from a direction given far off the axis.

    The banks guide the water along the channel. The water's speed is that where the course runs along the axis;
    where it runs at slope k to it, the channel's section normal to the flow is sqrt(1 + k^2) times narrower and the
    flow that much faster (continuity). A tide's direction is its axis of oscillation and turns alike. Cells outside
    every channel keep the water's direction and speed.
    """
    win = (slice(i0, i0 + patch.shape[0]), slice(j0, j0 + patch.shape[1]))
    turn = (patch.water_surface > NO_WATER / 2) & np.isfinite(distance[win])
    tangent = angle[win][turn]
    own = material.flow_direction[win][turn]
    course = np.where(np.cos(axis[win][turn] - own) >= 0.0, tangent, tangent + np.pi)
    material.flow_direction[win][turn] = np.arctan2(np.sin(course), np.cos(course))
    material.flow_speed[win][turn] *= speedup[win][turn]
