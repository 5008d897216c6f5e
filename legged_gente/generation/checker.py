"""Rejects benchmark items that are empty, out of bounds, untraversable at the spawn, or miss what they name.

What an item *names* comes from the generation planner's own vocabulary, never from a second table:
a text prompt names the tools of the planner cues and modifiers it mentions (``find_cues``,
``find_modifiers``: "river" -> natural_ground, river, soil, water; "slippery" -> low_friction); an image item
names the tools of the ``LEGEND`` classes its picture was drawn with. Each named tool must appear in the
spec *and* be visible in the built tile inside that call's rectangle (water cells, soil cells, lowered
friction, or relief for geometry).
"""

from __future__ import annotations

import dataclasses
import types
import warnings
from pathlib import Path

import numpy as np

from legged_gente.generation.backends.image import LEGEND
from legged_gente.generation.backends.planner import Step, find_cues, find_modifiers
from legged_gente.generation.spec import TerrainSpec
from legged_gente.terrain.composition import MAX_ABS_HEIGHT
from legged_gente.terrain.registry import ATOMIC_TERRAINS
from legged_gente.terrain.terrain import SPAWN_FOOTPRINT, SPAWN_MAX_RANGE, Terrain

MIN_RELIEF = 0.02
"""Height range or offset (m) that makes a geometric feature visible; flatter ground counts as nothing built."""
BOUNDS_TOLERANCE = 1e-3
"""Slack (m) on the declared height bounds: float32 storage and seam blending round."""
GROUND_FRICTION = 1.0
"""Friction of plain ground when the checker builds a tile (the terrain config's default static_friction)."""


@dataclasses.dataclass
class CheckResult:
    problems: list[str]
    required: list[str]
    spawn_xy: tuple[float, float]

    @property
    def ok(self) -> bool:
        return not self.problems


def _named_steps(steps) -> list[Step]:
    """Steps that build something visible: every step but level ground (``flat`` at height 0)."""
    return [s for s in steps if not (s.tool == "flat" and float(s.params.get("height", 0.0)) == 0.0)]


def required_tools(prompt: str | None = None, names: tuple[str, ...] = ()) -> list[str]:
    """Tools a prompt's planner cues/modifiers or an image's LEGEND classes ask for (sorted, unique)."""
    steps: list[Step] = []
    if prompt:
        steps += [s for _, cue in find_cues(prompt) for s in cue.steps]
        steps += [s for _, mod in find_modifiers(prompt) for s in mod.extra]
    for name in names:
        if name not in LEGEND:
            raise ValueError(f"image class {name!r} is not in the planner LEGEND {sorted(LEGEND)}.")
        steps += list(LEGEND[name].steps)
    return sorted({s.tool for s in _named_steps(steps)})


def declared_bounds(spec: TerrainSpec) -> tuple[float, float]:
    """(min, max) heights the spec's calls can make, from each atomic's declared ``height_bounds``.

    Interval arithmetic over the calls in order, from flat ground at 0 m: a ``set`` call's region takes the
    atomic's range, an ``add`` call's region the current range shifted by it; cells outside a region keep
    theirs, and seam blending mixes the two convexly, so the tile's range is the union of both.
    """
    lo = hi = 0.0
    for call in spec.calls:
        atomic = ATOMIC_TERRAINS[call.tool]
        if atomic.kind != "geometric":
            continue
        x0, y0, x1, y1 = call.rect(spec.size_x, spec.size_y)
        a, b = atomic.height_bounds(dict(call.params), x1 - x0, y1 - y0)
        new_lo, new_hi = (a, b) if call.mode == "set" else (lo + a, hi + b)
        lo, hi = min(lo, new_lo), max(hi, new_hi)
    return lo, hi


def _visible(tool: str, heights: np.ndarray, material, window: tuple[slice, slice], ground_friction: float) -> bool:
    if tool == "water":
        return bool(material.has_water()[window].any())
    if tool == "soil":
        return bool(material.has_soil()[window].any())
    if tool == "low_friction":
        return bool((material.friction[window] < ground_friction).any())
    h = heights[window]
    return bool(h.size) and (float(h.max() - h.min()) > MIN_RELIEF or float(np.abs(h).max()) > MIN_RELIEF)


def build_single_tile(spec_path: Path, spec: TerrainSpec) -> Terrain:
    """The spec as a one-tile, borderless ``Terrain`` (its spawn search is the one training uses)."""
    cfg = types.SimpleNamespace(
        mesh_type="heightfield", mode="generated", resolution=spec.resolution, border_size=0.0,
        terrain_length=spec.size_x, terrain_width=spec.size_y, num_rows=1, num_cols=1,
        generated_specs=[str(spec_path)], static_friction=GROUND_FRICTION, seed=0)
    with warnings.catch_warnings():  # a missing spawn patch is reported below as a problem, not a warning
        warnings.simplefilter("ignore")
        return Terrain(cfg, 1)


def check_spec(spec_path: str | Path, prompt: str | None = None, names: tuple[str, ...] = ()) -> CheckResult:
    """Check one spec file against the four rules; ``prompt``/``names`` say what the item names."""
    spec_path = Path(spec_path)
    spec = TerrainSpec.load(spec_path)
    terrain = build_single_tile(spec_path, spec)
    heights, material, res = terrain.height_field, terrain.material, terrain.resolution
    problems: list[str] = []

    has_material = material.has_water().any() or material.has_soil().any() or (material.friction < GROUND_FRICTION).any()
    if not spec.calls or (float(heights.max() - heights.min()) <= MIN_RELIEF and not has_material):
        problems.append("empty: the spec builds flat, plain ground (no relief, water, soil or low friction).")

    lo, hi = declared_bounds(spec)
    lo, hi = max(lo, -MAX_ABS_HEIGHT), min(hi, MAX_ABS_HEIGHT)
    hmin, hmax = float(heights.min()), float(heights.max())
    if hmin < lo - BOUNDS_TOLERANCE or hmax > hi + BOUNDS_TOLERANCE:
        problems.append(f"out of bounds: heights span [{hmin:.3f}, {hmax:.3f}] m but the calls declare "
                        f"[{lo:.3f}, {hi:.3f}] m.")

    ox, oy = (float(v) for v in terrain.terrain_origins[0, 0, :2])
    half = SPAWN_FOOTPRINT / 2
    i0, i1 = max(0, round((ox - half) / res)), round((ox + half) / res) + 1
    j0, j1 = max(0, round((oy - half) / res)), round((oy + half) / res) + 1
    patch = heights[i0:i1, j0:j1]
    span = float(patch.max() - patch.min())
    if span > SPAWN_MAX_RANGE + 1e-6:
        problems.append(f"untraversable at the spawn: the flattest {SPAWN_FOOTPRINT} m patch near the centre, at "
                        f"({ox:.1f}, {oy:.1f}) m, has a height range of {span:.3f} m > {SPAWN_MAX_RANGE} m.")

    required = required_tools(prompt, names)
    for tool in required:
        calls = [c for c in spec.calls if c.tool == tool]
        if not calls:
            problems.append(f"missing: the item names {tool!r} but the spec has no {tool} call.")
            continue
        windows = []
        for c in calls:
            x0, y0, x1, y1 = c.rect(spec.size_x, spec.size_y)
            windows.append((slice(round(x0 / res), round(x1 / res)), slice(round(y0 / res), round(y1 / res))))
        if not any(_visible(tool, heights, material, w, GROUND_FRICTION) for w in windows):
            problems.append(f"missing: the item names {tool!r}; the spec calls it but the built tile shows none of it.")
    return CheckResult(problems, required, (ox, oy))


def check_item(item) -> CheckResult:
    """Check a benchmark :class:`~legged_gente.evaluation.benchmark.Item`."""
    return check_spec(item.spec_path, item.prompt, item.names)
