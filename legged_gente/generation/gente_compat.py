"""GenTe compatibility: GenTe's tool set, its published transcripts and its heightmaps, in this project's terms.

GenTe (Gao et al. 2025, github.com/HaronW/GenTe) has models call terrain functions on a 200 x 200 grid of
0.1 m cells (a 20 m x 20 m tile) with int16 heights of 0.005 m. Its multi-part prompts split the tile into
four parts (argument ``part`` 1-4); its single-part prompts apply every call to the whole tile. GenTe's height
functions add to the current heights (its obstacles, pillars, gap and pyramid stairs write their blocks' heights over
them instead), so translated geometric calls use mode ``add``.

:data:`GENTE_TOOLS` is our own description of the tool schema GenTe serves (names, arguments, their types and
what GenTe's code does with them), written from GenTe's code and schema; :func:`gente_tool_schemas` serves
it to a model (``gente-generate --toolset gente``) so prompts written for GenTe work unchanged, and
:func:`translate_call` maps one GenTe call to validated calls of ours. Nothing is dropped silently: a tool
GenTe never declared, a GenTe tool we cannot express, an argument we ignore and a value moved into our
range are all reported as :class:`Issue` s; a live model's value outside our range is not moved but rejected
(``translate_call(..., live=True)``), so the model corrects it. The mapping table is in docs/generation.md
("GenTe tool set").

Models wrote GenTe's arguments as Python literals (``.5``, implicit string concatenation), which GenTe ran
with ``eval``; here they are parsed as JSON or, failing that, with ``ast.literal_eval`` (literals only,
never executed), after a length bound.
"""

from __future__ import annotations

import ast
import dataclasses
import json
import math
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from legged_gente.generation.spec import TerrainSpec
from legged_gente.generation.validation import (
    MAX_ARGUMENT_CHARS,
    ToolCall,
    ValidationError,
    plain_json_problem,
    validate_call,
    validate_spec_dict,
)
from legged_gente.terrain.heightmap import wrap_edges
from legged_gente.terrain.registry import ATOMIC_TERRAINS

GENTE_CELL = 0.1
"""m, GenTe's horizontal cell size (``horizontal_scale``)."""
GENTE_VERTICAL = 0.005
"""m per int16 unit of GenTe's heightmaps (``vertical_scale``)."""
GENTE_TILE = 20.0
"""m, side of GenTe's tile (200 cells)."""
PART_REGIONS = {1: "back_right", 2: "front_right", 3: "back_left", 4: "front_left"}
"""GenTe's ``part`` -> our named region (GenTe's part 2 is the second half along x, part 3 along y)."""

BLOCKING = ("invented_tool", "no_equivalent", "unreadable_arguments", "bad_value", "rejected")
"""Issue kinds that leave a GenTe call without any translated call."""


@dataclasses.dataclass(frozen=True)
class Issue:
    """Something a translation reports: ``kind`` (see :data:`BLOCKING` and the notes kinds) and a sentence."""

    kind: str
    message: str


@dataclasses.dataclass(frozen=True)
class GenteArg:
    """One argument of a GenTe tool: JSON type, our description of it, whether GenTe's schema requires it."""

    type: str
    doc: str
    required: bool = False
    enum: tuple[str, ...] | None = None


class Issues(list):
    """The issues of one translation; ``live`` says whose call it is. A live model's value outside our range is
    rejected with the range, so that the model corrects it; a recorded transcript's (nobody left to correct it) is
    imported at the nearest bound and reported as ``clamped``."""

    def __init__(self, live: bool):
        super().__init__()
        self.live = live


Translate = Callable[[dict[str, Any], float, float, Issues], list[tuple[str, dict[str, Any]]]]


@dataclasses.dataclass(frozen=True)
class GenteTool:
    """A GenTe tool: its arguments, which of GenTe's schemas declare it, our translation and its one-line summary."""

    name: str
    doc: str
    args: dict[str, GenteArg]
    schemas: tuple[str, ...]
    translate: Translate | None
    mapping: str


# ------------------------------------------------------------------------------------------ translation helpers
def _fit(tool: str, param: str, value: float, source: str, issues: Issues) -> float:
    """``value`` inside our parameter's range: a live model's value outside it raises ValueError with the range; a
    transcript's is moved into it and reported (never a silent clamp)."""
    p = ATOMIC_TERRAINS[tool].params[param]
    lo = -math.inf if p.low is None else p.low
    hi = math.inf if p.high is None else p.high
    fitted = min(max(value, lo), hi)
    if fitted != value and issues.live:
        raise ValueError(f"{source}={value:g} gives {tool}.{param}={value:g} {p.unit}, outside our range "
                         f"[{p.low}, {p.high}]; send a value inside it")
    if fitted != value:
        issues.append(Issue("clamped", f"{source}={value:g} gives {tool}.{param}={value:g} {p.unit}, outside our range "
                                       f"[{p.low}, {p.high}]; imported as {fitted:g}."))
    return float(fitted)  # validation turns a whole number into an integer parameter's int


def _size(value: float, name: str, gente: str, issues: list[Issue]) -> float:
    """``|value|`` for an argument our tool takes as a size; a negative value is reported with what GenTe makes of it."""
    if value < 0:
        issues.append(Issue("coerced", f"{name}={value:g} is negative ({gente}); imported as {-value:g}."))
    return abs(value)


def _ignored(args: Mapping[str, Any], names: tuple[str, ...], why: str, issues: list[Issue]) -> None:
    for name in names:
        if name in args:
            issues.append(Issue("ignored_argument", f"{name}={_short(args[name])} is not imported: {why}."))


def _short(value: Any) -> str:
    text = json.dumps(value) if isinstance(value, (list, dict, str)) else repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _offset(height: float, source: str, issues: Issues) -> list[tuple[str, dict[str, Any]]]:
    """A ``flat`` call that lifts the region by ``height`` m (GenTe's shapes start at 0 where ours are centred)."""
    if abs(height) < 1e-9:
        return []
    return [("flat", {"height": _fit("flat", "height", height, source, issues)})]


def _slope(args, sx, sy, issues, name):
    """GenTe's slopes rise ``slope`` m per m from 0 at the region's edges (sloped_terrain: at its corners, a diamond)
    towards its centre; ours fall from 0 at the platform's edge, so they are lifted to GenTe's peak, slope * d_max
    (pyramid_sloped_terrain: its edges then meet 0; sloped_terrain: its edges stay at GenTe's mid-edge slope * side/2)."""
    slope = float(args["slope"])
    platform = 0.0
    if name == "pyramid_sloped_terrain":  # GenTe's function default platform_size is 1 m
        platform = _fit("pyramid_slope", "platform", float(args.get("platform_size", 1.0)), "platform_size", issues)
    d_max = (sx + sy) / 2.0 if name == "sloped_terrain" else sx / 2.0  # GenTe: Manhattan vs along-x half extent
    rise = d_max - platform / 2.0
    calls = _offset(slope * rise, f"{name}.slope (slope*{rise:g} m to the edges)", issues)
    params = {"slope": _fit("pyramid_slope", "slope", math.atan(abs(slope)), f"atan(|slope|) of {name}.slope", issues),
              "direction": "down" if slope >= 0 else "up", "platform": platform}
    return calls + [("pyramid_slope", params)]


def _flat(args, sx, sy, issues):
    return [("flat", {"height": _fit("flat", "height", float(args["height"]), "height", issues)})]


def _natural(args, sx, sy, issues):
    # GenTe samples Perlin noise at cell / scale: features of ``scale`` cells; heights noise * height_multiplier m.
    lacunarity = float(args.get("lacunarity", 2.0))
    octaves = float(args.get("octaves", 6))
    if lacunarity == 1.0 and octaves != 1.0:
        # noise.pnoise2 (caseman/noise, _perlin.c) samples octave k at lacunarity**k times the frequency and divides
        # by the sum of the weights: at lacunarity 1 every octave is the same noise, so GenTe drew one octave
        _ignored({k: v for k, v in args.items() if k in ("octaves", "persistence")}, ("octaves", "persistence"),
                 "at lacunarity 1 GenTe's octaves all repeat the first (one octave of noise, imported as octaves=1)",
                 issues)
        octaves = 1.0
    else:
        _ignored({k: v for k, v in args.items() if k == "lacunarity" and lacunarity != 2.0}, ("lacunarity",),
                 "our natural_ground doubles the frequency per octave (lacunarity 2)", issues)
    amplitude = _size(float(args.get("height_multiplier", 5.0)), "height_multiplier",
                      "GenTe turns its noise upside down: relief of the same kind", issues)
    params = {"amplitude": _fit("natural_ground", "amplitude", amplitude, "height_multiplier", issues),
              "wavelength": _fit("natural_ground", "wavelength", float(args.get("scale", 10.0)) * GENTE_CELL, "scale*0.1 m", issues),
              "octaves": _fit("natural_ground", "octaves", octaves, "octaves", issues),
              "persistence": _fit("natural_ground", "persistence", float(args.get("persistence", 0.5)), "persistence", issues),
              "platform": 0.0}
    return [("natural_ground", params)]


def _river(args, sx, sy, issues):
    width = float(args["river_width"])
    depth = _size(float(args["river_depth"]), "river_depth", "GenTe would raise the river above its surroundings", issues)
    params = {"width": _fit("river", "width", width, "river_width", issues),
              "depth": _fit("river", "depth", depth, "river_depth", issues)}
    params["bank_width"] = min(0.5, params["width"] / 2.0)
    path = args.get("river_path")
    if isinstance(path, str):  # some models sent the path as a string of a list
        try:
            path = ast.literal_eval(path[:2000])
        except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
            path = None
    try:
        (x0, y0), (x1, y1) = path[0], path[-1]
        params["direction"] = math.atan2(float(y1) - float(y0), float(x1) - float(x0))
        issues.append(Issue("simplified", f"river_path {_short(args.get('river_path'))} is imported as a straight river "
                                          f"through the region's centre along its end-to-end direction."))
    except (TypeError, ValueError, IndexError, KeyError):
        issues.append(Issue("ignored_argument", f"river_path={_short(args.get('river_path'))} is not a list of (x, y) "
                                                f"points; the river runs along y."))
    _ignored(args, ("bank_height", "smoothness"), "our river has cosine banks of fixed shape and no raised levee", issues)
    return [("river", params)]


def _uniform(args, sx, sy, issues):
    lo, hi = float(args["min_height"]), float(args["max_height"])
    if lo > hi:
        issues.append(Issue("clamped", f"min_height={lo:g} > max_height={hi:g}; imported swapped."))
        lo, hi = hi, lo
    step = float(args.get("step", 1.0))  # GenTe's function default (its schema says 0.1, but the code's 1 is what ran)
    # GenTe converts step with the horizontal scale: int(step / 0.1) height units of 0.005 m.
    step_m = int(step / GENTE_CELL) * GENTE_VERTICAL
    spacing = float(args["downsampled_scale"]) * GENTE_CELL if args.get("downsampled_scale") else GENTE_CELL
    params = {"amplitude": _fit("random_uniform", "amplitude", (hi - lo) / 2.0, "(max_height-min_height)/2", issues),
              "spacing": _fit("random_uniform", "spacing", spacing, "downsampled_scale*0.1 m", issues),
              "step": _fit("random_uniform", "step", step_m, "step (GenTe: int(step/0.1)*0.005 m)", issues),
              "platform": 0.0}
    if 0.0 < params["amplitude"] <= params["step"]:
        # GenTe draws from min_height + k*step (k = 0, 1, ...): at least two levels; our random_uniform rounds its
        # nodes in [-amplitude, amplitude] towards 0 by the step, which would make every node 0 (flat ground)
        issues.append(Issue("simplified", f"GenTe's heights are levels {params['step']:g} m apart from {lo:g} m; "
                                          f"a quantum not below the amplitude {params['amplitude']:g} m would flatten "
                                          f"ours, so they are imported without one."))
        params["step"] = 0.0
    return _offset((hi + lo) / 2.0, "(min_height+max_height)/2", issues) + [("random_uniform", params)]


def _obstacles(args, sx, sy, issues):
    lo, hi = float(args["min_size"]), float(args["max_size"])
    if lo > hi:
        issues.append(Issue("clamped", f"min_size={lo:g} > max_size={hi:g}; imported swapped."))
        lo, hi = hi, lo
    height = _size(float(args["max_height"]), "max_height", "GenTe's blocks rise and sink by it either way", issues)
    params = {"max_height": _fit("discrete_obstacles", "max_height", height, "max_height", issues),
              "min_size": _fit("discrete_obstacles", "min_size", lo, "min_size", issues),
              "max_size": _fit("discrete_obstacles", "max_size", hi, "max_size", issues),
              "density": _fit("discrete_obstacles", "density", float(args["num_rects"]) / (sx * sy), "num_rects/area", issues),
              "platform": 0.0}
    _ignored(args, ("platform_size",), "GenTe's discrete_obstacles_terrain converts it but clears no platform", issues)
    return [("discrete_obstacles", params)]  # lo <= hi, and _fit keeps the order


def _waves(args, sx, sy, issues):
    n = float(args["num_waves"])
    if n <= 0:
        issues.append(Issue("no_effect", f"num_waves={n:g}: GenTe draws no waves; nothing to import."))
        return []
    # GenTe: amplitude/2 * (cos(y) + sin(x)) with num_waves periods across the region.
    amplitude = _size(float(args.get("amplitude", 1.0)), "amplitude", "GenTe draws the same waves shifted by half a period", issues)
    params = {"amplitude": _fit("waves", "amplitude", amplitude, "amplitude", issues),
              "wavelength": _fit("waves", "wavelength", sy / n, "region side/num_waves", issues),
              "pattern": "grid", "platform": 0.0}
    return [("waves", params)]


def _stairs(args, sx, sy, issues, name):
    tool = "stairs" if name == "stairs_terrain" else "pyramid_stairs"
    step_height = float(args["step_height"])
    climbs = step_height >= 0  # GenTe's stairs climb with +x (our "up"), its pyramid towards the centre (our "down")
    direction = ("up" if climbs else "down") if tool == "stairs" else ("down" if climbs else "up")
    params = {"step_width": _fit(tool, "step_width", float(args["step_width"]), "step_width", issues),
              "step_height": _fit(tool, "step_height", abs(step_height), "step_height", issues),
              "direction": direction,
              "platform": 0.0 if tool == "stairs" else _fit(tool, "platform", float(args.get("platform_size", 1.0)), "platform_size", issues)}
    if tool == "stairs":
        return [(tool, params)]
    # GenTe's rings are set one step higher each, inwards from the part's edge, while wider than the platform: its
    # edge keeps the ground and its centre is rings * step_height up; ours start at 0 on the platform, so they are
    # lifted by their fall from there to the (nearer) edges.
    rings = math.ceil(round((min(sx, sy) / 2.0 - params["platform"] / 2.0) / params["step_width"], 9))
    lift = math.copysign(max(rings, 0) * params["step_height"], step_height)
    return _offset(lift, f"{name}.step_height ({max(rings, 0)} steps to the centre)", issues) + [(tool, params)]


def _stones(args, sx, sy, issues):
    params = {"stone_size": _fit("stepping_stones", "stone_size", float(args["stone_size"]), "stone_size", issues),
              "stone_distance": _fit("stepping_stones", "stone_distance", float(args["stone_distance"]), "stone_distance", issues),
              "height_noise": _fit("stepping_stones", "height_noise", _size(float(args["max_height"]), "max_height",
                                   "GenTe declares it a height", issues), "max_height", issues),
              "depth": _fit("stepping_stones", "depth", _size(float(args.get("depth", 0.5)), "depth",
                            "GenTe declares it a depth", issues), "depth", issues),
              "platform": _fit("stepping_stones", "platform", float(args.get("platform_size", 1.0)), "platform_size", issues)}
    return [("stepping_stones", params)]


def _pillars(args, sx, sy, issues):
    size = float(args["max_pillar_size"])  # GenTe: rectangles of 0.5-1 times this side, 1.5 m tall
    params = {"height": 1.5,
              "max_radius": _fit("pillars", "max_radius", size / 2.0, "max_pillar_size/2", issues),
              "min_radius": _fit("pillars", "min_radius", size / 4.0, "max_pillar_size/4", issues),
              "density": _fit("pillars", "density", float(args["num_pillars"]) / (sx * sy), "num_pillars/area", issues),
              "platform": 1.5}  # min <= max: size/4 <= size/2 (a negative size meets both low bounds, 0.03 m)
    _ignored(args, ("pillar_gap", "step_height"), "our pillars are round, scattered without a minimum gap, with no ridges "
                                                  "between them", issues)
    return [("pillars", params)]


def _gap(args, sx, sy, issues):
    depth = _size(float(args.get("depth", 1000)), "depth", "GenTe would raise a wall around the platform instead of a trench",
                  issues) * GENTE_VERTICAL  # GenTe: height units, default 1000 (5 m)
    params = {"gap_width": _fit("gap", "gap_width", float(args["gap_size"]), "gap_size", issues),
              "depth": _fit("gap", "depth", depth, "depth*0.005 m", issues),
              "platform": _fit("gap", "platform", float(args.get("platform_size", 1.0)), "platform_size", issues)}
    return [("gap", params)]


def _pit(args, sx, sy, issues):
    depth = _size(float(args["depth"]), "depth", "GenTe would raise a block instead of digging a pit", issues)
    params = {"depth": _fit("pit", "depth", depth, "depth", issues),
              "width": _fit("pit", "width", min(sx, sy) / 2.0, "half the region side", issues)}
    _ignored(args, ("platform_size",), "our pit has no platform; it is half the region wide", issues)
    return [("pit", params)]


def _water(args, sx, sy, issues):
    depth = _size(float(args["depth"]), "depth", "GenTe declares it a depth", issues)
    return [("water", {"depth": _fit("water", "depth", depth, "depth", issues), "flow": "still"})]


WAVE_SPEEDS = {"current": 0.5, "tide": 0.3}
"""m/s of the flow a ``water_wave_terrain`` call imports as (GenTe gives no speed): a walking-pace stream, a gentle tide."""


def _water_wave(args, sx, sy, issues):
    kind = args["water_type"]
    issues.append(Issue("defaulted", f"water_type={kind!r} has no depth or speed in GenTe; imported as 0.3 m of water "
                                     f"flowing at {WAVE_SPEEDS[kind]} m/s."))
    return [("water", {"depth": 0.3, "flow": kind, "speed": WAVE_SPEEDS[kind]})]


SOIL_TYPES = {"sand": "dry_sand", "wet soil": "mud", "dry soil": "clay_loam"}
"""GenTe's ``terrain_type`` -> our soil preset."""


def _soil(args, sx, sy, issues):
    _ignored(args, ("singkage",), "sinkage is an outcome of our pressure-sinkage soil model, not an input", issues)
    return [("soil", {"preset": SOIL_TYPES[args["terrain_type"]]})]


HANDLE = GenteArg("string", "GenTe's terrain handle ('init_terrain' or 'previous_terrain'); it carries no meaning here")
PLATFORM = GenteArg("number", "side of the flat square at the centre [m]")
BOTH, MULTI = ("single", "multi"), ("multi",)

GENTE_TOOLS: dict[str, GenteTool] = {t.name: t for t in [
    GenteTool("flat_ground_terrain", "Raise the part by a constant height.",
              {"terrain": HANDLE, "height": GenteArg("number", "height added to the part [m]", True)},
              BOTH, _flat, "flat(height), mode add"),
    GenteTool("natural_ground_terrain", "Perlin-noise relief.",
              {"terrain": HANDLE, "scale": GenteArg("number", "feature size in cells (0.1 m)"),
               "octaves": GenteArg("integer", "noise octaves"), "persistence": GenteArg("number", "amplitude ratio per octave"),
               "lacunarity": GenteArg("number", "frequency ratio per octave"),
               "height_multiplier": GenteArg("number", "height scale of the noise [m]")},
              ("single",), _natural, "natural_ground(amplitude=height_multiplier, wavelength=0.1*scale, octaves, persistence); lacunarity fixed at 2 "
              "(lacunarity 1: octaves=1, as GenTe's octaves then repeat the first)"),
    GenteTool("random_gaussian_terrain", "Gaussian-noise heights.",
              {"terrain": HANDLE, "mean_height": GenteArg("number", "mean height [m]", True),
               "std_dev": GenteArg("number", "standard deviation of the heights", True),
               "step": GenteArg("number", "height quantum"), "downsampled_scale": GenteArg("number", "sampling distance")},
              MULTI, None, "no equivalent (GenTe declares it without an implementation, and ours has no Gaussian noise); "
              "random_uniform_terrain draws random heights"),
    GenteTool("generate_river_terrain", "A river channel lower than its surroundings.",
              {"terrain": HANDLE, "river_width": GenteArg("number", "river width [m]", True),
               "river_depth": GenteArg("number", "depth below the surroundings [m]", True),
               "river_path": GenteArg("array", "centre line as a list of (x, y) points"),
               "bank_height": GenteArg("number", "bank height above the river bed [m]", True),
               "smoothness": GenteArg("number", "smoothness of the bank transition")},
              BOTH, _river, "river(width, depth, direction of the path's ends); bank_height, smoothness ignored"),
    GenteTool("random_uniform_terrain", "Uniformly random heights.",
              {"terrain": HANDLE, "min_height": GenteArg("number", "lowest height [m]", True),
               "max_height": GenteArg("number", "highest height [m]", True),
               "step": GenteArg("number", "height quantum"), "downsampled_scale": GenteArg("number", "sampling distance in cells")},
              BOTH, _uniform, "flat((min+max)/2) + random_uniform(amplitude=(max-min)/2, spacing=0.1*downsampled_scale, step=int(step/0.1)*0.005)"),
    GenteTool("sloped_terrain", "A four-sided pyramid, peak at the part's centre.",
              {"terrain": HANDLE, "slope": GenteArg("number", "rise per metre towards the centre (negative: a hollow)", True)},
              BOTH, lambda a, sx, sy, i: _slope(a, sx, sy, i, "sloped_terrain"),
              "flat(slope*d_max) + pyramid_slope(atan|slope|, direction down for slope > 0); GenTe's diamond becomes our square pyramid"),
    GenteTool("pyramid_sloped_terrain", "A pyramid rising to a flat top at the centre.",
              {"terrain": HANDLE, "slope": GenteArg("number", "rise per metre towards the centre", True), "platform_size": PLATFORM},
              BOTH, lambda a, sx, sy, i: _slope(a, sx, sy, i, "pyramid_sloped_terrain"),
              "flat(slope*(side/2 - platform/2)) + pyramid_slope(atan|slope|, direction, platform (default 1 m))"),
    GenteTool("discrete_obstacles_terrain", "Random rectangular blocks.",
              {"terrain": HANDLE, "max_height": GenteArg("number", "largest block height [m]", True),
               "min_size": GenteArg("number", "smallest block side [m]", True), "max_size": GenteArg("number", "largest block side [m]", True),
               "num_rects": GenteArg("integer", "number of blocks", True), "platform_size": PLATFORM},
              BOTH, _obstacles, "discrete_obstacles(max_height, min_size, max_size, density=num_rects/area, platform 0); platform_size ignored"),
    GenteTool("wave_terrain", "Sine waves along both axes.",
              {"terrain": HANDLE, "num_waves": GenteArg("integer", "periods across the part", True),
               "amplitude": GenteArg("number", "peak-to-peak height of one axis' wave [m]")},
              BOTH, _waves, "waves(amplitude, wavelength=side/num_waves, pattern grid)"),
    GenteTool("stairs_terrain", "A flight of steps along x.",
              {"terrain": HANDLE, "step_width": GenteArg("number", "tread depth [m]", True),
               "step_height": GenteArg("number", "rise of one step [m]", True)},
              BOTH, lambda a, sx, sy, i: _stairs(a, sx, sy, i, "stairs_terrain"),
              "stairs(step_width, step_height, up, platform 0): one flight through the region's centre"),
    GenteTool("pyramid_stairs_terrain", "Square rings of steps rising to the centre.",
              {"terrain": HANDLE, "step_width": GenteArg("number", "tread depth [m]", True),
               "step_height": GenteArg("number", "rise of one step [m]", True), "platform_size": PLATFORM},
              MULTI, lambda a, sx, sy, i: _stairs(a, sx, sy, i, "pyramid_stairs_terrain"), "flat(rings*step_height) + pyramid_stairs(step_width, step_height, down, platform): GenTe's edges at 0"),
    GenteTool("stepping_stones_terrain", "Stones separated by holes.",
              {"terrain": HANDLE, "stone_size": GenteArg("number", "stone side [m]", True),
               "stone_distance": GenteArg("number", "hole width [m]", True),
               "max_height": GenteArg("number", "largest stone height [m]", True), "platform_size": PLATFORM,
               "depth": GenteArg("number", "depth of the holes [m]")},
              MULTI, _stones, "stepping_stones(stone_size, stone_distance, height_noise=max_height, depth, platform)"),
    GenteTool("pillars_terrain", "Tall rectangular pillars.",
              {"terrain": HANDLE, "num_pillars": GenteArg("integer", "number of pillars", True),
               "max_pillar_size": GenteArg("number", "largest pillar side [m]", True),
               "pillar_gap": GenteArg("number", "free space around a pillar [m]"),
               "step_height": GenteArg("number", "height of ridges between the pillars [m]")},
              BOTH, _pillars, "pillars(height 1.5 m, radii size/4..size/2, density=num_pillars/area); pillar_gap, step_height ignored"),
    GenteTool("gap_terrain", "A trench around a central platform.",
              {"terrain": HANDLE, "gap_size": GenteArg("number", "trench width [m]", True), "platform_size": PLATFORM,
               "depth": GenteArg("number", "trench depth in 0.005 m units (default 1000)")},
              BOTH, _gap, "gap(gap_width=gap_size, depth=0.005*depth, platform)"),
    GenteTool("pit_terrain", "A pit at the centre.",
              {"terrain": HANDLE, "depth": GenteArg("number", "pit depth [m]", True), "platform_size": PLATFORM},
              MULTI, _pit, "pit(depth, width = half the region); platform_size ignored"),
    GenteTool("water_resistance_terrain", "Still water.",
              {"terrain": HANDLE, "depth": GenteArg("number", "water depth [m]", True)},
              MULTI, _water, "water(depth, still)"),
    GenteTool("water_wave_terrain", "Flowing water: a current or a tide.",
              {"terrain": HANDLE, "water_type": GenteArg("string", "kind of flow", True, ("current", "tide"))},
              MULTI, _water_wave, "water(0.3 m, flow=water_type, 0.5 m/s current or 0.3 m/s tide)"),
    GenteTool("deformable_terrain", "Soil the feet sink into.",
              {"terrain": HANDLE, "singkage": GenteArg("number", "expected foot sinkage [m]", True),
               "terrain_type": GenteArg("string", "kind of soil", True, ("wet soil", "dry soil", "sand"))},
              MULTI, _soil, "soil(sand -> dry_sand, wet soil -> mud, dry soil -> clay_loam); singkage ignored"),
]}
"""GenTe's tools (schemas ``single`` and ``multi``: the two tool lists its dataset was generated with)."""

PART_ARG = GenteArg("integer", "which quarter of the map the terrain goes in: 1, 2, 3 or 4 (default 1)", enum=None)


def offered_tools(schema: str) -> list[GenteTool]:
    """The tools of GenTe's ``single`` or ``multi`` list that a model is offered: all but those without a translation
    (``random_gaussian_terrain``, which GenTe declares without an implementation), whose every call is refused."""
    if schema not in ("single", "multi"):
        raise ValueError(f"schema {schema!r}: use 'single' or 'multi'.")
    return [t for t in GENTE_TOOLS.values() if schema in t.schemas and t.translate is not None]


def gente_tool_schemas(schema: str = "multi") -> list[dict[str, Any]]:
    """OpenAI ``tools`` in GenTe's names and arguments: the tools of GenTe's ``single`` or ``multi`` list (``multi``
    adds ``part``) that translate (:func:`offered_tools`), described in our words from :data:`GENTE_TOOLS`."""
    tools = []
    for tool in offered_tools(schema):
        args = dict(tool.args) | ({"part": PART_ARG} if schema == "multi" else {})
        props = {}
        for name, arg in args.items():
            prop: dict[str, Any] = {"type": arg.type, "description": arg.doc}
            if arg.enum:
                prop["enum"] = list(arg.enum)
            if arg.type == "array":
                prop["items"] = {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2}
            props[name] = prop
        required = [n for n, a in args.items() if a.required]
        tools.append({"type": "function", "function": {"name": tool.name, "description": tool.doc,
                                                       "parameters": {"type": "object", "properties": props, "required": required}}})
    return tools


# ------------------------------------------------------------------------------------------------- translation
@dataclasses.dataclass
class Translation:
    """One GenTe call translated: the validated calls of ours (maybe none) and what is reported about it."""

    gente_tool: str
    calls: list[ToolCall]
    issues: list[Issue]

    @property
    def blocked(self) -> bool:
        return any(i.kind in BLOCKING for i in self.issues)


class UnreadableArguments(ValueError):
    """A GenTe call's arguments that are neither JSON nor a Python literal, or not bounded plain data."""


def parse_arguments(arguments: Any) -> dict[str, Any]:
    """A GenTe call's arguments as a dict: JSON, else a Python literal (never executed); ValueError if neither."""
    if isinstance(arguments, str):
        if len(arguments) > MAX_ARGUMENT_CHARS:
            raise UnreadableArguments(f"the arguments are {len(arguments)} characters long; the limit is {MAX_ARGUMENT_CHARS}")
        try:
            arguments = json.loads(arguments) if arguments.strip() else {}
        except (ValueError, RecursionError):
            try:
                arguments = ast.literal_eval(arguments)
            except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError) as exc:
                raise UnreadableArguments(f"the arguments are neither JSON nor a Python literal ({type(exc).__name__})") from None
    problem = plain_json_problem(arguments)
    if problem:
        raise UnreadableArguments(f"the arguments: {problem}")
    if not isinstance(arguments, dict):
        raise UnreadableArguments(f"the arguments are a {type(arguments).__name__}, not an object")
    return arguments


def _region(args: dict[str, Any], schema: str | None, issues: list[Issue]) -> str:
    if schema == "single":
        if "part" in args:
            issues.append(Issue("ignored_argument", f"part={_short(args['part'])} in a single-part transcript; the call covers the whole tile."))
        return "full"
    part = args.get("part")
    if part is None:
        issues.append(Issue("defaulted", "no part given; GenTe's default part 1 (back right)."))
        return PART_REGIONS[1]
    if isinstance(part, str) and part.strip().isdigit():
        issues.append(Issue("coerced", f"part={part!r} is a string; imported as part {int(part)}."))
        part = int(part)
    if isinstance(part, bool) or not isinstance(part, (int, float)) or part not in PART_REGIONS:
        raise ValueError(f"part={_short(part)} is not 1, 2, 3 or 4")
    return PART_REGIONS[int(part)]


def translate_call(
    name: Any, arguments: Any, schema: str | None = "multi", size_x: float = GENTE_TILE, size_y: float = GENTE_TILE,
    live: bool = False, resolution: float | None = None,
) -> Translation:
    """Translate one GenTe call (``schema``: the tool list it was served, ``single`` or ``multi``; None: either).

    ``live``: the call of a model that can correct it (``--toolset gente``), so a value outside our range blocks
    the call (``bad_value``, with the range) instead of being imported at the nearest bound (``clamped``, for
    recorded transcripts). ``resolution`` (m): a translated call finer than the cells is blocked (``rejected``), as
    :func:`validate_call` blocks our own tools' calls. Never raises for bad input: everything is reported in
    ``issues``; blocked calls have no ``calls``.
    """
    tool_name = name if isinstance(name, str) else repr(name)
    tool_name = tool_name[:80]
    issues = Issues(live)
    tool = GENTE_TOOLS.get(name) if isinstance(name, str) else None
    if tool is None and live:  # the whole list, within a rejection's MAX_MESSAGE_CHARS: the name shown is cut short
        shown = tool_name if len(tool_name) <= 24 else tool_name[:24] + "..."
        offered = ", ".join(sorted(t.name for t in offered_tools(schema or "multi")))
        issues.append(Issue("invented_tool", f"{shown!r} is not a tool offered here; call one of {offered}."))
        return Translation(tool_name, [], issues)
    if tool is None:
        issues.append(Issue("invented_tool", f"{tool_name!r} is not a tool GenTe declares; GenTe's tools are {sorted(GENTE_TOOLS)}."))
        return Translation(tool_name, [], issues)
    if schema is not None and schema not in tool.schemas:
        issues.append(Issue("outside_schema", f"{tool.name} is not in GenTe's {schema}-part tool list (only in its "
                                              f"{'/'.join(tool.schemas)}-part list); translated anyway."))
    if tool.translate is None:
        issues.append(Issue("no_equivalent", f"{tool.name}: {tool.mapping}."))
        return Translation(tool.name, [], issues)
    missing: list[str] = []
    try:
        args = parse_arguments(arguments)
        region = _region(args, schema, issues)
        undeclared = sorted(set(args) - set(tool.args) - {"part"})
        if undeclared:
            issues.append(Issue("ignored_argument", f"{tool.name} declares no argument(s) {[u[:40] for u in undeclared[:8]]}; ignored."))
        missing = [n for n, a in tool.args.items() if a.required and n not in args and n != "terrain"]
        args = {k: v for k, v in args.items() if k in tool.args and k != "terrain"}
        for n, a in tool.args.items():
            if n in args and a.type in ("number", "integer") and (isinstance(args[n], bool) or not isinstance(args[n], (int, float))):
                raise ValueError(f"{n}={_short(args[n])} is not a number")
            if n in args and a.type == "integer" and not float(args[n]).is_integer():  # GenTe runs range() on some
                raise ValueError(f"{n}={_short(args[n])} is not a whole number; GenTe declares it an integer")
            if n in args and a.enum and args[n] not in a.enum:
                raise ValueError(f"{n}={_short(args[n])} is not one of {list(a.enum)}")
        ours = tool.translate(args, size_x / (2.0 if region != "full" else 1.0), size_y / (2.0 if region != "full" else 1.0), issues)
    except KeyError as exc:
        issues.append(Issue("bad_value", f"{tool.name}: required argument {exc} is missing (missing: {missing})."))
        return Translation(tool.name, [], issues)
    except (ValueError, TypeError, OverflowError) as exc:
        kind = "unreadable_arguments" if isinstance(exc, UnreadableArguments) else "bad_value"
        issues.append(Issue(kind, f"{tool.name}: {str(exc)[:200]}."))
        return Translation(tool.name, [], issues)
    calls = []
    for our_tool, params in ours:
        layout = {"region": region} | ({"mode": "add"} if ATOMIC_TERRAINS[our_tool].kind == "geometric" else {})
        try:
            calls.append(validate_call(our_tool, {**params, **layout}, size_x, size_y, resolution=resolution))
        except ValidationError as exc:
            issues.append(Issue("rejected", f"{tool.name} -> {our_tool}: {exc}"))
            return Translation(tool.name, [], issues)
    return Translation(tool.name, calls, issues)


# ------------------------------------------------------------------------------------------------- transcripts
@dataclasses.dataclass
class TranscriptImport:
    """A GenTe ``data.json`` imported: the spec (None if it does not validate), every translation, and why not."""

    spec: TerrainSpec | None
    translations: list[Translation]
    error: str | None = None

    @property
    def issues(self) -> list[Issue]:
        return [i for t in self.translations for i in t.issues]


GENTE_SMOOTHING_SIGMA = 2 * GENTE_CELL
"""GenTe's dataset script smooths every tile after its calls with ``smooth_transitions(n=20, sigma=2)``: a Gaussian
of 2 cells (``scipy.ndimage.gaussian_filter1d``, mode "nearest") along x then y."""
GENTE_SEAM_BAND = 20 * GENTE_CELL
"""How far either side of a seam between two parts GenTe's multi-part tiles are smoothed (n = 20 cells)."""


def gente_smoothing(schema: str, size_x: float = GENTE_TILE, size_y: float = GENTE_TILE) -> list[dict[str, Any]]:
    """The filters GenTe applies after a transcript's calls (``generate_dataset.py``, ``smooth_transitions``): a
    single-part tile (``utils/terrain_utils_single.py``) along x then y over the whole tile; a multi-part one
    (``utils/terrain_utils_parts.py``) along x in the band of ``GENTE_SEAM_BAND`` either side of the x seam, one
    half along y at a time, then along y in the band either side of the y seam, one half along x at a time. The
    seams are at the middle of a ``size_x`` x ``size_y`` tile (GenTe's is 20 m); a band stops at the tile's edge."""
    hx, hy, band, sigma = size_x / 2, size_y / 2, GENTE_SEAM_BAND, GENTE_SMOOTHING_SIGMA
    x0, x1 = max(hx - band, 0.0), min(hx + band, size_x)
    y0, y1 = max(hy - band, 0.0), min(hy + band, size_y)

    def rect(x0: float, y0: float, x1: float, y1: float) -> dict[str, float]:
        return {"x0": x0, "y0": y0, "x1": x1, "y1": y1}

    if schema == "single":
        return [{"region": "full", "axis": "x", "sigma": sigma}, {"region": "full", "axis": "y", "sigma": sigma}]
    return [{"region": rect(x0, 0.0, x1, hy), "axis": "x", "sigma": sigma},
            {"region": rect(x0, hy, x1, size_y), "axis": "x", "sigma": sigma},
            {"region": rect(0.0, y0, hx, y1), "axis": "y", "sigma": sigma},
            {"region": rect(hx, y0, size_x, y1), "axis": "y", "sigma": sigma}]


MAX_TRANSCRIPT_CALLS = 256
"""Tool calls a transcript may hold (a bound on the work a file can ask for)."""


def import_transcript(
    data: Any, name: str, schema: str, seed: int = 0, resolution: float = GENTE_CELL,
) -> TranscriptImport:
    """GenTe's ``{"tool_calls": [...]}`` (its scene text is not read) -> a validated :class:`TerrainSpec`.

    The spec is a 20 m x 20 m tile at ``resolution``, smoothed after its calls as GenTe smooths its tiles
    (:func:`gente_smoothing`); its source names GenTe's schema, not the scene text.
    """
    tool_calls = data.get("tool_calls") if isinstance(data, dict) else None
    if not isinstance(tool_calls, list) or not tool_calls:
        return TranscriptImport(None, [], "the transcript has no tool_calls list")
    if len(tool_calls) > MAX_TRANSCRIPT_CALLS:
        return TranscriptImport(None, [], f"the transcript has {len(tool_calls)} tool calls; at most "
                                          f"{MAX_TRANSCRIPT_CALLS} are read")
    translations = []
    for tc in tool_calls:
        fn = tc.get("function") if isinstance(tc, dict) else None
        if not isinstance(fn, dict):
            translations.append(Translation("?", [], [Issue("unreadable_arguments", "a tool call without a function object.")]))
            continue
        translations.append(translate_call(fn.get("name"), fn.get("arguments", ""), schema))
    calls = [c for t in translations for c in t.calls]
    doc = TerrainSpec(calls=calls, name=name, size_x=GENTE_TILE, size_y=GENTE_TILE, resolution=resolution, seed=seed,
                      source={"gente_schema": schema, "gente_calls": str(len(tool_calls))}, backend="gente_import",
                      smoothing=gente_smoothing(schema)).to_dict()
    try:
        _, validated = validate_spec_dict(doc)
    except ValidationError as exc:
        return TranscriptImport(None, translations, str(exc))
    if not validated:
        return TranscriptImport(None, translations, "no call could be translated")
    return TranscriptImport(TerrainSpec.from_dict(doc), translations)


# -------------------------------------------------------------------------------------------------- heightmaps
@dataclasses.dataclass
class GenteHeightmap:
    """A GenTe ``array.npy`` in metres, with where it wrapped around the int16 range (``overflowed``)."""

    heights: np.ndarray
    overflowed: bool
    wrap_edges: int
    raw_range: tuple[int, int]


def import_heightmap(array: Any) -> GenteHeightmap:
    """GenTe's int16 heightmap -> float32 metres (x along axis 0, 0.005 m per unit) and overflow detection.

    GenTe adds heights in int16 without checks, so a tall stack wraps from +32767 to -32768; the terrain
    library's :func:`~legged_gente.terrain.heightmap.wrap_edges` counts the neighbour pairs where it did.
    """
    a = np.asarray(array)
    if a.ndim != 2 or a.dtype != np.int16:
        raise ValueError(f"a GenTe heightmap is a 2-D int16 array; got {a.dtype} of shape {a.shape}.")
    edges = wrap_edges(a)
    a32 = a.astype(np.int32)
    return GenteHeightmap((a32 * GENTE_VERTICAL).astype(np.float32), edges > 0, edges, (int(a32.min()), int(a32.max())))


def heightmap_spec(file: str, name: str, base_dir: str | Path | None = None) -> TerrainSpec:
    """A validated spec whose ground is GenTe's ``array.npy`` at ``file`` (relative to ``base_dir``, the folder the
    spec is saved in): 0.1 m cells, 0.005 m per unit, a 20 m x 20 m tile. Raises ValidationError naming the
    problem (not 200 x 200 int16 cells, wrapped around int16, beyond the height bound)."""
    doc = TerrainSpec(calls=[], name=name, size_x=GENTE_TILE, size_y=GENTE_TILE, resolution=GENTE_CELL,
                      source={"gente_heightmap": Path(file).name}, backend="gente_import",
                      heightmap={"file": str(file), "vertical_scale": GENTE_VERTICAL}).to_dict()
    return TerrainSpec.from_dict(doc, base_dir=base_dir)
