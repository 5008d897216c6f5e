"""A terrain as plain scene data: meshes, arrows, lines, labels and points, before any viewer sees it.

:func:`terrain_scene` turns a :class:`~legged_gente.terrain.terrain.Terrain` into a :class:`Scene` (numpy
arrays only), so tests check what would be drawn without a browser and :mod:`.server` only pushes it to viser.

What is drawn:

* ``ground``: the heightfield as a triangle mesh with per-vertex colours: the material map (soil presets in
  their preview colours, low-friction ground in cyan, other ground grey) or the heights (a colormap);
* ``water``: a translucent surface at the water's real level over the wet cells;
* ``flow``: arrows on the water, each as long as the flow travels in ``FLOW_ARROW_SECONDS`` (current and tide
  amplitude), pointing along the flow;
* ``tiles``: tile outlines draped on the ground, a label per tile (row, column, terrain type), spawn points.

Large grids are drawn with every ``stride``-th cell so the mesh stays under ``MAX_VERTICES``; one tile alone
(:func:`terrain_scene` with ``tile=(row, col)``) is drawn at full resolution.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from legged_gente.terrain.materials import FLOW_STILL, MaterialMap
from legged_gente.terrain.terrain import (
    CUSTOM_SOIL_COLOUR,
    LOW_FRICTION_COLOUR,
    LOW_FRICTION_TINT_BELOW,
    SOIL_COLOURS,
    WATER_COLOUR,
    Terrain,
)
from legged_gente.terrain.preview import material_legend

MAX_VERTICES = 250_000
"""Largest ground mesh sent to the browser; bigger grids are subsampled (every ``stride``-th cell)."""
MAX_TILE_LABELS = 60
"""More tiles than this get one label per column (its type) and per row instead of one per tile."""
FLOW_ARROW_SECONDS = 1.0
"""A flow arrow is as long as the water travels in this time (m)."""
FLOW_ARROW_SPACING = 1.0
"""Distance between flow arrows (m)."""
GROUND_COLOUR = (0.62, 0.62, 0.58)
WATER_OPACITY = 0.75
COLOUR_MODES = ("materials", "heights")


@dataclasses.dataclass
class Mesh:
    vertices: np.ndarray  # (N, 3) float32, m
    faces: np.ndarray  # (M, 3) uint32, counter-clockwise seen from +z
    vertex_colors: np.ndarray | None = None  # (N, 3) uint8
    color: tuple[int, int, int] = (200, 200, 200)
    opacity: float | None = None


@dataclasses.dataclass
class Arrows:
    points: np.ndarray  # (N, 2, 3) float32: start, end
    color: tuple[int, int, int]


@dataclasses.dataclass
class Lines:
    points: np.ndarray  # (N, 2, 3) float32: segments
    color: tuple[int, int, int]


@dataclasses.dataclass
class Label:
    text: str
    position: tuple[float, float, float]


@dataclasses.dataclass
class Points:
    positions: np.ndarray  # (N, 3) float32
    color: tuple[int, int, int]
    size: float = 0.25


@dataclasses.dataclass
class Scene:
    """Scene nodes by viser name (``/terrain/ground`` ...), the legend (label, RGB 0-255) and the bounds."""

    nodes: dict[str, Mesh | Arrows | Lines | Label | Points]
    legend: list[tuple[str, tuple[int, int, int]]]
    bounds: tuple[np.ndarray, np.ndarray]  # (3,) min and max corners, m

    def of_type(self, kind: type) -> dict[str, object]:
        return {name: node for name, node in self.nodes.items() if isinstance(node, kind)}


def _rgb255(colour) -> tuple[int, int, int]:
    return tuple(int(round(255 * c)) for c in colour)


def material_colours(material: MaterialMap) -> tuple[np.ndarray, list[tuple[str, tuple[int, int, int]]]]:
    """(nx, ny, 3) float colours of the ground by material and the legend of the materials present."""
    rgb = np.empty(material.shape + (3,))
    rgb[:] = GROUND_COLOUR
    for k, name in enumerate(material.soil_presets):
        rgb[material.soil == k] = SOIL_COLOURS.get(name, CUSTOM_SOIL_COLOUR)
    rgb[material.friction < LOW_FRICTION_TINT_BELOW] = LOW_FRICTION_COLOUR
    legend = [("ground", GROUND_COLOUR)] + material_legend(material)
    return rgb, [(label, _rgb255(c)) for label, c in legend]


def height_colours(heights: np.ndarray) -> tuple[np.ndarray, list[tuple[str, tuple[int, int, int]]]]:
    """(nx, ny, 3) float colours by elevation (matplotlib's 'viridis') and a legend of its range."""
    from matplotlib import colormaps

    lo, hi = float(heights.min()), float(heights.max())
    t = (heights - lo) / (hi - lo) if hi > lo else np.full(heights.shape, 0.5)
    cmap = colormaps["viridis"]
    legend = [(f"{v:+.2f} m", _rgb255(cmap(f)[:3])) for v, f in ((lo, 0.0), ((lo + hi) / 2, 0.5), (hi, 1.0))]
    return cmap(t)[..., :3], legend


def grid_mesh(x: np.ndarray, y: np.ndarray, z: np.ndarray, keep: np.ndarray | None = None):
    """Vertices and counter-clockwise faces of the grid ``z[i, j]`` at ``(x[i], y[j])``; quads whose four
    corners are all in ``keep`` (if given) only."""
    nx, ny = z.shape
    vertices = np.stack([np.repeat(x, ny), np.tile(y, nx), z.ravel()], 1).astype(np.float32)
    v00 = (np.arange(nx - 1)[:, None] * ny + np.arange(ny - 1)[None, :]).ravel()
    if keep is not None:
        quad = keep[:-1, :-1] & keep[1:, :-1] & keep[:-1, 1:] & keep[1:, 1:]
        v00 = v00[quad.ravel()]
    v10, v01, v11 = v00 + ny, v00 + 1, v00 + ny + 1
    faces = np.concatenate([np.stack([v00, v10, v11], 1), np.stack([v00, v11, v01], 1)]).astype(np.uint32)
    return vertices, faces


def _window(terrain: Terrain, tile: tuple[int, int] | None) -> tuple[slice, slice]:
    """Cell window of the whole terrain or of one tile (with its far edge, so neighbouring tiles meet)."""
    if tile is None:
        return slice(0, None), slice(0, None)
    r, c = tile
    if not (0 <= r < terrain.num_rows and 0 <= c < terrain.num_cols):
        raise ValueError(f"tile {tile} is outside the {terrain.num_rows} x {terrain.num_cols} grid; "
                         f"rows 0..{terrain.num_rows - 1}, columns 0..{terrain.num_cols - 1}.")
    tnx, tny = terrain.tile_cells
    i0, j0 = terrain.border + r * tnx, terrain.border + c * tny
    return slice(i0, i0 + tnx + 1), slice(j0, j0 + tny + 1)


def terrain_scene(
    terrain: Terrain,
    colours: str = "materials",
    tile: tuple[int, int] | None = None,
    offset: tuple[float, float] = (0.0, 0.0),
    max_vertices: int = MAX_VERTICES,
    prefix: str = "/terrain",
) -> Scene:
    """The scene of ``terrain`` (or of its ``tile`` alone), shifted by ``offset`` (m) in x and y."""
    if colours not in COLOUR_MODES:
        raise ValueError(f"colours {colours!r}: use one of {COLOUR_MODES}.")
    wi, wj = _window(terrain, tile)
    heights = terrain.height_field[wi, wj]
    mat = terrain.material
    sub = MaterialMap(**{f.name: (getattr(mat, f.name)[wi, wj] if f.name != "soil_presets" else mat.soil_presets)
                         for f in dataclasses.fields(MaterialMap)})
    nx, ny = heights.shape
    stride = max(1, int(np.ceil(np.sqrt(nx * ny / max_vertices))))
    ii = np.unique(np.r_[np.arange(0, nx, stride), nx - 1])
    jj = np.unique(np.r_[np.arange(0, ny, stride), ny - 1])
    i_first, j_first = wi.start, wj.start
    res = terrain.resolution
    x = terrain.origin_xy[0] + offset[0] + (i_first + ii) * res
    y = terrain.origin_xy[1] + offset[1] + (j_first + jj) * res
    h = heights[np.ix_(ii, jj)]
    nodes: dict = {}

    rgb, legend = (material_colours(sub) if colours == "materials" else height_colours(heights))
    vertices, faces = grid_mesh(x, y, h)
    nodes[f"{prefix}/ground"] = Mesh(vertices, faces, (rgb[np.ix_(ii, jj)].reshape(-1, 3) * 255).round().astype(np.uint8))

    wet = sub.has_water()[np.ix_(ii, jj)]
    if wet.any():
        surface = np.where(wet, sub.water_surface[np.ix_(ii, jj)], h)
        wv, wf = grid_mesh(x, y, surface, keep=wet)
        nodes[f"{prefix}/water"] = Mesh(wv, wf, color=_rgb255(WATER_COLOUR), opacity=WATER_OPACITY)
        arrows = _flow_arrows(sub, x[0] - ii[0] * res, y[0] - jj[0] * res, res)
        if len(arrows):
            nodes[f"{prefix}/flow"] = Arrows(arrows, (20, 60, 200))
            legend.append((f"flow: arrow = {FLOW_ARROW_SECONDS:g} s of travel", (20, 60, 200)))

    if terrain.mode not in ("plane", "bare"):
        rows = list(range(terrain.num_rows)) if tile is None else [tile[0]]
        cols = list(range(terrain.num_cols)) if tile is None else [tile[1]]
        nodes[f"{prefix}/tiles/outlines"] = Lines(_tile_outlines(terrain, rows, cols, stride, offset), (30, 30, 30))
        spawns = terrain.terrain_origins[np.ix_(list(rows), list(cols))].reshape(-1, 3).astype(np.float32)
        spawns[:, :2] += offset
        nodes[f"{prefix}/tiles/spawns"] = Points(spawns + np.float32([0, 0, 0.05]), (230, 30, 30))
        legend.append(("spawn point", (230, 30, 30)))
        labels = [(r, c, f"({r}, {c}) {terrain.tile_names[r, c]}") for r in rows for c in cols]
        if len(labels) > MAX_TILE_LABELS:  # a large grid: its columns' types along row 0, its rows along column 0
            labels = ([(rows[0], c, f"col {c}: {terrain.tile_names[rows[0], c]}") for c in cols]
                      + [(r, cols[0], f"row {r}") for r in rows[1:]])
        if terrain.num_rows * terrain.num_cols > 1:  # one tile: its name is the item's
            for r, c, text in labels:
                sx, sy, sz = terrain.terrain_origins[r, c]
                nodes[f"{prefix}/tiles/label_{r}_{c}"] = Label(text, (float(sx + offset[0]), float(sy + offset[1]),
                                                                     float(sz) + 1.2))
    lo = np.array([x[0], y[0], float(h.min())], np.float32)
    hi = np.array([x[-1], y[-1], float(h.max())], np.float32)
    return Scene(nodes, legend, (lo, hi))


@dataclasses.dataclass
class BareTerrain:
    """A heightfield and its material map without tiles (a recorded rollout's terrain)."""

    height_field: np.ndarray
    material: MaterialMap
    resolution: float
    origin_xy: tuple[float, float]
    mode: str = "bare"


def plane_terrain() -> BareTerrain:
    """The ground drawn for a task without a heightfield (``mesh_type = "plane"``): 100 m x 100 m of rigid ground
    around the origin."""
    return BareTerrain(np.zeros((2, 2), np.float32), MaterialMap.rigid((2, 2)), 100.0, (-50.0, -50.0))


def _flow_arrows(material: MaterialMap, x0: float, y0: float, res: float) -> np.ndarray:
    """(N, 2, 3) arrows on the moving water, one every FLOW_ARROW_SPACING m."""
    step = max(1, int(round(FLOW_ARROW_SPACING / res)))
    ii, jj = np.meshgrid(np.arange(step // 2, material.shape[0], step), np.arange(step // 2, material.shape[1], step),
                         indexing="ij")
    ii, jj = ii.ravel(), jj.ravel()
    moving = material.has_water()[ii, jj] & (material.flow_kind[ii, jj] != FLOW_STILL) & (material.flow_speed[ii, jj] > 0)
    ii, jj = ii[moving], jj[moving]
    length = material.flow_speed[ii, jj] * FLOW_ARROW_SECONDS
    angle = material.flow_direction[ii, jj]
    start = np.stack([x0 + ii * res, y0 + jj * res, material.water_surface[ii, jj] + 0.03], 1)
    end = start + np.stack([length * np.cos(angle), length * np.sin(angle), np.zeros_like(length)], 1)
    return np.stack([start, end], 1).astype(np.float32)


def _tile_outlines(terrain: Terrain, rows, cols, stride: int, offset) -> np.ndarray:
    """(N, 2, 3) segments along the tile borders, draped 2 cm above the ground."""
    (lx, ly), res = terrain.tile_size, terrain.resolution
    rows, cols = list(rows), list(cols)
    x_lines = [r * lx for r in range(rows[0], rows[-1] + 2)]
    y_lines = [c * ly for c in range(cols[0], cols[-1] + 2)]
    step = stride * res
    segments = []
    for x in x_lines:  # borders across the x axis: run along y
        y = np.arange(y_lines[0], y_lines[-1] + step / 2, step)
        segments.append(np.stack([np.full_like(y, x), y], 1))
    for y in y_lines:
        x = np.arange(x_lines[0], x_lines[-1] + step / 2, step)
        segments.append(np.stack([x, np.full_like(x, y)], 1))
    out = []
    for line in segments:
        z = terrain.height_at(line[:, 0], line[:, 1]) + 0.02
        p = np.column_stack([line + np.asarray(offset), z])
        out.append(np.stack([p[:-1], p[1:]], 1))
    return np.concatenate(out).astype(np.float32)
