"""Rejects benchmark items that are empty, out of bounds, untraversable at the spawn, hold water that would run
off (a water wall), or miss what they name.

What an item *names* comes from the generation planner's own vocabulary, never from a second table:
a text prompt names the tools the planner's recipes build for it (``recipe_steps``: its cues with their
modifiers applied: "river" -> natural_ground, river, water; "slippery" -> low_friction); an image item
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
from legged_gente.generation.backends.planner import Step, recipe_steps
from legged_gente.generation.spec import TerrainSpec
from legged_gente.terrain.composition import MAX_ABS_HEIGHT, Region, stacked_height_bounds
from legged_gente.terrain.terrain import SPAWN_FOOTPRINT, SPAWN_MAX_RANGE, Terrain

MIN_RELIEF = 0.02
"""Height range or offset (m) that makes a geometric feature visible; flatter ground counts as nothing built."""
BOUNDS_TOLERANCE = 1e-3
"""Slack (m) on the declared height bounds: float32 storage and seam blending round."""
GROUND_FRICTION = 1.0
"""Friction of plain ground when the checker builds a tile (the terrain config's default static_friction)."""
WATER_WALL_TOLERANCE = 0.05
"""Height (m) by which a water surface may stand above the ground of a dry neighbouring cell. A wet cell's
surface is level; the dry neighbour's ground may lie a little below it where the shore is sampled at 0.1 m cells
(a shelving shore drops a few cm per cell near the waterline) and where the base relief's bumps (natural ground of
a few cm) meet the waterline. 5 cm is a third of ankle depth for the ~1 m biped: below it the edge is a sampling
detail, above it the water stands up against nothing and would run off."""


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
        steps += recipe_steps(prompt)
    for name in names:
        if name not in LEGEND:
            raise ValueError(f"image class {name!r} is not in the planner LEGEND {sorted(LEGEND)}.")
        steps += list(LEGEND[name].steps)
    return sorted({s.tool for s in _named_steps(steps)})


def _visible(tool: str, heights: np.ndarray, material, window: tuple[slice, slice], ground_friction: float) -> bool:
    if tool == "water":
        return bool(material.has_water()[window].any())
    if tool == "soil":
        return bool(material.has_soil()[window].any())
    if tool in ("low_friction", "ice"):
        return bool((material.friction[window] < ground_friction).any())
    h = heights[window]
    return bool(h.size) and (float(h.max() - h.min()) > MIN_RELIEF or float(np.abs(h).max()) > MIN_RELIEF)


def water_walls(heights: np.ndarray, material) -> tuple[int, float, tuple[int, int]]:
    """Wet cells beside a dry 4-neighbour of the tile whose ground lies more than ``WATER_WALL_TOLERANCE`` below
    their water surface: (how many, the largest such drop in m, a wet cell (i, j) with it)."""
    wet, surface = material.has_water(), material.water_surface
    drop = np.zeros(heights.shape)
    for a, b in ((np.s_[:-1, :], np.s_[1:, :]), (np.s_[1:, :], np.s_[:-1, :]),
                 (np.s_[:, :-1], np.s_[:, 1:]), (np.s_[:, 1:], np.s_[:, :-1])):
        drop[a] = np.maximum(drop[a], np.where(wet[a] & ~wet[b], surface[a] - heights[b], 0.0))
    i, j = np.unravel_index(int(drop.argmax()), drop.shape)
    return int((drop > WATER_WALL_TOLERANCE).sum()), float(drop[i, j]), (int(i), int(j))


def water_wall_problem(heights: np.ndarray, material, resolution: float) -> str | None:
    """The water wall rule's message for a built tile, or None when its water stands in ground that holds it."""
    count, worst, (i, j) = water_walls(heights, material)
    if not count:
        return None
    return (f"water wall: {count} wet cells stand beside dry ground up to {worst:.3f} m below their water surface "
            f"(> {WATER_WALL_TOLERANCE} m), e.g. at ({i * resolution:.1f}, {j * resolution:.1f}) m: the water would "
            f"run off; put it in a depression at least as deep (a river, pit or basin under the water's region).")


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
    """Check one spec file against the five rules; ``prompt``/``names`` say what the item names."""
    spec_path = Path(spec_path)
    spec = TerrainSpec.load(spec_path)
    terrain = build_single_tile(spec_path, spec)
    heights, material, res = terrain.height_field, terrain.material, terrain.resolution
    problems: list[str] = []

    has_material = material.has_water().any() or material.has_soil().any() or (material.friction < GROUND_FRICTION).any()
    if float(heights.max() - heights.min()) <= MIN_RELIEF and not has_material:  # a heightmap's relief counts too
        problems.append("empty: the spec builds flat, plain ground (no relief, water, soil or low friction).")

    # Per cell, against the terrain's own worst-case bound on stacked heights (the one validation uses).
    bounds = stacked_height_bounds(spec.to_tile_spec())
    ii, jj = np.meshgrid(np.arange(heights.shape[0]) * res, np.arange(heights.shape[1]) * res, indexing="ij")
    lo, hi = bounds.at(ii, jj)
    lo, hi = np.maximum(lo, -MAX_ABS_HEIGHT), np.minimum(hi, MAX_ABS_HEIGHT)
    outside = (heights < lo - BOUNDS_TOLERANCE) | (heights > hi + BOUNDS_TOLERANCE)
    if outside.any():
        i, j = np.argwhere(outside)[0]
        problems.append(f"out of bounds: {int(outside.sum())} cells lie outside the heights their calls can make, e.g. "
                        f"{float(heights[i, j]):.3f} m at ({i * res:.1f}, {j * res:.1f}) m, where the calls allow "
                        f"[{float(lo[i, j]):.3f}, {float(hi[i, j]):.3f}] m.")

    wall = water_wall_problem(heights, material, res)
    if wall:
        problems.append(wall)

    ox, oy = (float(v) for v in terrain.terrain_origins[0, 0, :2])
    # The window the spawn search judged (Terrain._spawn_origins): f cells, fewer on a tile narrower than that,
    # centred on the origin.
    f = 2 * int(round(SPAWN_FOOTPRINT / (2 * res))) + 1
    fx, fy = min(f, heights.shape[0]), min(f, heights.shape[1])
    i0, j0 = round(ox / res - (fx - 1) / 2), round(oy / res - (fy - 1) / 2)
    patch = heights[i0:i0 + fx, j0:j0 + fy]
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
            i0, j0, i1, j1 = Region(*c.rect(spec.size_x, spec.size_y)).cells(res)  # the cells the builder paints
            windows.append((slice(i0, i1), slice(j0, j1)))
        if not any(_visible(tool, heights, material, w, GROUND_FRICTION) for w in windows):
            problems.append(f"missing: the item names {tool!r}; the spec calls it but the built tile shows none of it.")
    return CheckResult(problems, required, (ox, oy))


def check_item(item) -> CheckResult:
    """Check a benchmark :class:`~legged_gente.evaluation.benchmark.Item`."""
    return check_spec(item.spec_path, item.prompt, item.names)
