"""The terrain grid: ``num_rows`` x ``num_cols`` tiles, a flat border, the material map and spawn origins.

Rows run along world x (``terrain_length`` each), columns along world y (``terrain_width`` each). In
curriculum mode a row is a difficulty level (row 0 easiest, the last row ``max_difficulty``: 1 is the standard
top level) and a column a terrain type, columns allocated to ``terrain_types`` by ``terrain_proportions``.
Cell (i, j) of ``height_field`` lies at world ``origin_xy + (i, j) * resolution``; ``origin_xy ==
(-border_size, -border_size)`` so the first tile starts at world (0, 0).

A ``terrain_types`` entry is an atomic terrain name, optionally with fixed parameters after a colon:
``"stairs:direction=down"`` or ``"water:flow=current,speed=0.5"``; the curriculum sets the others. Several
atomics joined by ``+`` are applied in order to the whole tile, each at the tile's difficulty:
``"river+water"`` (a filled channel), ``"hills+soil:preset=dry_sand"`` (dunes). The first geometric atomic sets
the heights and each later one adds to them: ``"hills+rocks"`` is rocks on hills. Physical terrains alone
(water, soil, low_friction) lie on flat ground. Entries joined by ``|`` make a mosaic: each of the tile's four
quadrants is one of them, drawn from the tile's seed, at the tile's difficulty, and the quadrants meet through the
composition's seam blend as the parts of a generated terrain do (``"pyramid_stairs|rocks|natural_ground"``: where
stairs that rise to a quadrant's edge meet rocks, a step as tall as the stairs). Tile sizes and the border are
whole numbers of cells.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from .composition import (QUADRANTS, Operation, Part, Region, TileSpec, build_tile, quadrant, read_json,
                          tile_spec_from_document)
from .materials import MaterialMap
from .registry import ATOMIC_TERRAINS, MAX_DIFFICULTY

SPAWN_FOOTPRINT = 1.0
"""Side (m) of the square around a spawn point that must be flat and free of obstacles."""

SPAWN_MAX_RANGE = 0.05
"""Largest height difference (m) inside the spawn footprint: more means a slope, a step or an obstacle."""

MODES = ("plane", "curriculum", "random", "selected", "generated")

MOSAIC_STREAM = 1
"""Spawn key (after the tile's row and column) of the random stream that picks a mosaic's quadrants."""


def parse_terrain_type(entry: str) -> tuple[str, dict[str, Any]]:
    """``"name"`` or ``"name:key=value,key=value"`` -> (name, fixed params); values are numbers or choices."""
    name, _, rest = entry.partition(":")
    name = name.strip()
    if name not in ATOMIC_TERRAINS:
        raise ValueError(f"terrain type {entry!r}: unknown atomic terrain {name!r}; use one of {sorted(ATOMIC_TERRAINS)}.")
    fixed: dict[str, Any] = {}
    for item in filter(None, (s.strip() for s in rest.split(","))):
        key, eq, value = item.partition("=")
        if not eq:
            raise ValueError(f"terrain type {entry!r}: {item!r} is not key=value; write e.g. 'stairs:direction=down'.")
        try:
            fixed[key.strip()] = float(value)
        except ValueError:
            fixed[key.strip()] = value.strip()
    ATOMIC_TERRAINS[name].check_params(fixed)  # unknown keys / bad values fail here, naming the terrain
    return name, fixed


def normalised_proportions(proportions: list[float]) -> np.ndarray:
    """``proportions`` as probabilities; raises on negative/empty input, warns when they do not sum to 1."""
    p = np.asarray(proportions, np.float64)
    if p.ndim != 1 or p.size == 0 or np.any(~np.isfinite(p)) or np.any(p < 0) or p.sum() <= 0:
        raise ValueError(f"terrain_proportions {proportions} must be non-negative numbers with a positive sum.")
    if abs(p.sum() - 1.0) > 1e-6:
        warnings.warn(f"terrain_proportions sum to {p.sum():.4f}, not 1; normalising them.", stacklevel=3)
    return p / p.sum()


def parse_tile_type(entry: str) -> list[list[tuple[str, dict[str, Any]]]]:
    """A ``terrain_types`` entry -> its alternatives (joined by ``|``: a mosaic's), each the (name, fixed params)
    of its atomics joined by ``+``. An entry without ``|`` has one alternative: the whole tile."""
    alternatives = [alternative.split("+") for alternative in entry.split("|")]
    if any(not part.strip() for parts in alternatives for part in parts):
        raise ValueError(f"terrain type {entry!r} has an empty name before or after a '|' or '+'; join atomic "
                         f"terrains, e.g. 'hills+rocks' or 'pyramid_stairs|rocks'.")
    return [[parse_terrain_type(part) for part in parts] for parts in alternatives]


def allocate_columns(proportions: list[float], num_cols: int) -> np.ndarray:
    """Type index of every column: contiguous blocks sized by ``proportions`` (largest-remainder rounding)."""
    p = normalised_proportions(proportions)
    quota = p * num_cols
    counts = np.floor(quota).astype(int)
    counts[np.argsort(-(quota - counts), kind="stable")[: num_cols - counts.sum()]] += 1
    starved = np.flatnonzero((p > 0) & (counts == 0))
    if starved.size:
        warnings.warn(
            f"terrain types at indices {starved.tolist()} get no column with num_cols={num_cols}; raise num_cols.",
            stacklevel=3,
        )
    return np.repeat(np.arange(p.size), counts)


def check_ground_friction(mu: float) -> None:
    """``terrain.static_friction`` is a finite Coulomb coefficient >= 0 (MuJoCo takes any value silently)."""
    if not (math.isfinite(mu) and mu >= 0):
        raise ValueError(f"terrain.static_friction={mu} must be a finite coefficient >= 0; set it (1.0 is the "
                         f"default).")


def whole_cells(length: float, resolution: float) -> float:
    """``length`` (m) widened, by less than a cell, to a whole number of ``resolution`` cells: a border the grid
    takes at any resolution."""
    return math.ceil(length / resolution - 1e-6) * resolution


def _cells(length: float, resolution: float, what: str) -> int:
    n = length / resolution
    if n < 1 or abs(n - round(n)) > 1e-6:
        raise ValueError(f"{what}={length} m is not a whole number of resolution={resolution} m cells; adjust it.")
    return int(round(n))


def check_grid_settings(cfg: Any) -> None:
    """The grid settings a ``Terrain`` reads, checked without building it. A plane task's env builds no grid and
    ignores them, but checks them too: an invalid one left unsaid would surface only in a task with a grid."""
    mode = "plane" if cfg.mesh_type == "plane" else cfg.mode
    if mode not in MODES:
        raise ValueError(f"terrain mode {cfg.mode!r} is not one of {MODES}.")
    if mode == "plane" and cfg.mode == "selected" and getattr(cfg, "selected_terrain", None) is not None:
        warnings.warn(f"terrain mode 'selected' with selected_terrain={cfg.selected_terrain!r} builds nothing with "
                      f"mesh_type='plane' (every tile flat); set terrain.mesh_type='heightfield' to build it.",
                      stacklevel=3)
    if cfg.num_rows < 1 or cfg.num_cols < 1:
        raise ValueError(f"num_rows={cfg.num_rows} and num_cols={cfg.num_cols} must both be >= 1.")
    for name in ("terrain_length", "terrain_width", "border_size"):  # NaN passes every comparison below
        if not math.isfinite(getattr(cfg, name)):
            raise ValueError(f"{name}={getattr(cfg, name)} m must be a finite number of metres; set terrain.{name}.")
    check_ground_friction(cfg.static_friction)
    if cfg.border_size < 0:
        raise ValueError(f"border_size must be >= 0 m, got {cfg.border_size}.")
    if mode != "plane" and not (float(cfg.seed) == int(cfg.seed) >= 0):
        raise ValueError(f"terrain seed={cfg.seed} must be a whole number >= 0 (it seeds every tile); set terrain.seed.")
    if not float(cfg.resolution) > 0:
        raise ValueError(f"resolution must be > 0 m, got {cfg.resolution}.")
    for name in ("terrain_length", "terrain_width", "border_size")[:2 + (cfg.border_size > 0)]:
        _cells(getattr(cfg, name), float(cfg.resolution), name)


class Terrain:
    """The whole terrain: ``height_field`` (float32, m), ``material`` (MaterialMap) and tile spawn origins."""

    def __init__(self, cfg: Any, num_robots: int):
        if num_robots < 1:
            raise ValueError(f"num_robots must be >= 1, got {num_robots}.")
        check_grid_settings(cfg)
        self.cfg = cfg
        self.num_robots = int(num_robots)
        self.mode = "plane" if cfg.mesh_type == "plane" else cfg.mode
        self.resolution = float(cfg.resolution)
        self.num_rows, self.num_cols = int(cfg.num_rows), int(cfg.num_cols)
        self.tile_size = (float(cfg.terrain_length), float(cfg.terrain_width))
        self.tile_cells = (
            _cells(cfg.terrain_length, self.resolution, "terrain_length"),
            _cells(cfg.terrain_width, self.resolution, "terrain_width"),
        )
        self.border = _cells(cfg.border_size, self.resolution, "border_size") if cfg.border_size > 0 else 0
        self.origin_xy = (-self.border * self.resolution, -self.border * self.resolution)
        tnx, tny = self.tile_cells
        shape = (self.num_rows * tnx + 2 * self.border, self.num_cols * tny + 2 * self.border)
        self.height_field = np.zeros(shape, np.float32)
        self.material = MaterialMap.rigid(shape, friction=float(cfg.static_friction))
        self.tile_names = np.full((self.num_rows, self.num_cols), "plane", dtype=object)
        self.terrain_types = np.full(self.num_cols, -1, np.int64)
        """Per column: index into ``cfg.terrain_types`` of the column's type (curriculum mode), else -1."""

        if self.mode != "plane":
            for (r, c), (name, build) in self._plan().items():
                heights, material = build()
                if heights.shape != (tnx, tny):
                    raise ValueError(
                        f"tile ({r}, {c}) '{name}' has {heights.shape} cells, the grid needs {(tnx, tny)}: make its "
                        f"size {self.tile_size} m at resolution {self.resolution} m."
                    )
                i0, j0 = self.border + r * tnx, self.border + c * tny
                self.height_field[i0 : i0 + tnx, j0 : j0 + tny] = heights
                self.material.paste(material, i0, j0)
                self.tile_names[r, c] = name
        self.tile_type_names = [
            col[0] if all(n == col[0] for n in col) else "mixed" for col in self.tile_names.T.tolist()
        ]
        """Per column: the name of its tiles' terrain, or "mixed" where the rows differ (random/generated)."""
        self.terrain_origins = self._spawn_origins()

    # ------------------------------------------------------------------------------------------ tile plans
    def _tile_seed(self, r: int, c: int) -> int:
        return int(np.random.SeedSequence(int(self.cfg.seed), spawn_key=(r, c)).generate_state(1)[0])

    def _atomic_tile(self, r: int, c: int, entry: str, alternatives: list[list[tuple[str, dict[str, Any]]]],
                     difficulty: float | None):
        """Builder of the tile ``entry`` at ``difficulty`` (None: the params as given): its one alternative over the
        whole tile, or, for a mosaic, one alternative per quadrant drawn from the tile's seed."""
        size_x, size_y = self.tile_size
        if len(alternatives) == 1:
            parts = [Part(Region(0.0, 0.0, size_x, size_y), self._operations(alternatives[0], difficulty))]
        else:  # a stream of its own, apart from the (part, op) streams of the tile's seed its parts draw from
            rng = np.random.default_rng(np.random.SeedSequence(int(self.cfg.seed), spawn_key=(r, c, MOSAIC_STREAM)))
            picks = rng.integers(len(alternatives), size=len(QUADRANTS))
            parts = [Part(quadrant(name, size_x, size_y), self._operations(alternatives[k], difficulty))
                     for name, k in zip(QUADRANTS, picks)]
        spec = TileSpec(size_x, size_y, self.resolution, self._tile_seed(r, c), parts)

        def build():
            try:
                return build_tile(spec, float(self.cfg.static_friction))
            except ValueError as exc:  # e.g. the height bound: say which tile and entry
                raise ValueError(f"tile ({r}, {c}) {entry!r}: {exc}") from None

        return build

    @staticmethod
    def _operations(ops: list[tuple[str, dict[str, Any]]], difficulty: float | None) -> list[Operation]:
        """One part's operations: the first geometric atomic sets the heights and each later one adds to them
        ("hills+rocks": rocks on hills); physical atomics paint the final ground."""
        operations, heights_set = [], False
        for name, fixed in ops:
            atomic = ATOMIC_TERRAINS[name]
            params = atomic.check_params(fixed) if difficulty is None else atomic.params_for_difficulty(difficulty, fixed)
            geometric = atomic.kind == "geometric"
            operations.append(Operation(name, params, "add" if geometric and heights_set else "set"))
            heights_set = heights_set or geometric
        return operations

    def _plan(self) -> dict[tuple[int, int], tuple[str, Any]]:
        """(row, col) -> (tile name, zero-argument builder of (heights, material))."""
        cfg, rows, cols = self.cfg, self.num_rows, self.num_cols
        plan = {}
        if self.mode in ("curriculum", "random"):
            top = float(cfg.max_difficulty)
            if not 0.0 < top <= MAX_DIFFICULTY:
                raise ValueError(f"terrain.max_difficulty={cfg.max_difficulty} must be in (0, {MAX_DIFFICULTY}]; "
                                 f"1 is the standard top level.")
            types = [parse_tile_type(t) for t in cfg.terrain_types]
            if len(types) != len(cfg.terrain_proportions):
                raise ValueError(
                    f"terrain_types has {len(types)} entries but terrain_proportions {len(cfg.terrain_proportions)}; "
                    f"give one proportion per type."
                )
        if self.mode == "curriculum":
            column_type = allocate_columns(cfg.terrain_proportions, cols)
            self.terrain_types[:] = column_type
            for r in range(rows):
                difficulty = top * r / (rows - 1) if rows > 1 else 0.0
                for c in range(cols):
                    k = column_type[c]
                    entry = cfg.terrain_types[k]
                    plan[r, c] = (entry, self._atomic_tile(r, c, entry, types[k], difficulty))
        elif self.mode == "random":
            p = normalised_proportions(cfg.terrain_proportions)
            rng = np.random.default_rng(int(cfg.seed))
            kinds = rng.choice(len(types), size=(rows, cols), p=p)
            difficulties = rng.uniform(0.0, top, (rows, cols))
            for r in range(rows):
                for c in range(cols):
                    k = kinds[r, c]
                    entry = cfg.terrain_types[k]
                    plan[r, c] = (entry, self._atomic_tile(r, c, entry, types[k], float(difficulties[r, c])))
        elif self.mode == "selected":
            name = cfg.selected_terrain
            if name not in ATOMIC_TERRAINS:
                raise ValueError(f"selected_terrain {name!r} is unknown; use one of {sorted(ATOMIC_TERRAINS)}.")
            ops = [(name, dict(cfg.selected_params or {}))]
            for r in range(rows):
                for c in range(cols):
                    plan[r, c] = (name, self._atomic_tile(r, c, name, [ops], None))
        else:  # generated
            paths = [Path(p) for p in cfg.generated_specs or []]
            if not paths:
                raise ValueError("mode 'generated' needs cfg.generated_specs: a list of spec JSON paths from gente-generate.")
            if len(paths) != rows * cols:
                warnings.warn(
                    f"{len(paths)} generated specs fill {rows * cols} tiles (row-major, repeating); "
                    f"set num_rows * num_cols = {len(paths)} for one tile per spec.",
                    stacklevel=3,
                )
            tiles = [self._generated_tile(path) for path in paths]  # each spec read once, however often it repeats
            for k in range(rows * cols):
                plan[divmod(k, cols)] = tiles[k % len(paths)]
        return plan

    def _generated_tile(self, path: Path) -> tuple[str, Any]:
        """(name, builder) of the tile of spec file ``path``, named by the spec's ``name`` (every gente-generate
        output is a ``spec.json``), or by the file's stem for a spec without one."""
        try:
            document = read_json(path.read_text(), f"terrain spec {path}")
        except FileNotFoundError:
            raise FileNotFoundError(f"terrain spec {path} does not exist; list the spec.json files that "
                                    f"gente-generate wrote in cfg.generated_specs.") from None
        name = document.get("name") if isinstance(document, dict) else None

        def build():
            try:
                tile = tile_spec_from_document(document, path.parent)
                if not math.isclose(tile.resolution, self.resolution, rel_tol=1e-9):  # same cells, other metres
                    raise ValueError(f"its cells are {tile.resolution:g} m, the grid's resolution is {self.resolution:g} "
                                     f"m; set terrain.resolution={tile.resolution:g} and the tile size to the spec's "
                                     f"{tile.size_x:g} x {tile.size_y:g} m")
                return tile.build(ground_friction=float(self.cfg.static_friction))
            except ValueError as exc:  # also a parameter out of its range
                raise ValueError(f"terrain spec {path}: {exc}") from None

        return (name if isinstance(name, str) and name else path.stem), build

    # --------------------------------------------------------------------------------------------- spawning
    def _spawn_origins(self) -> np.ndarray:
        """World (x, y, z) of each tile's spawn point: the centre of the flat footprint nearest the tile centre.

        Searched in the central half of each tile, all tiles at once: sliding max/min over the footprint give
        the height range; windows with range <= SPAWN_MAX_RANGE are clear (no step, slope or obstacle).
        z is the highest ground in the footprint. Tiles without a clear window get the flattest one, with a warning.
        """
        tnx, tny = self.tile_cells
        f = 2 * int(round(SPAWN_FOOTPRINT / (2 * self.resolution))) + 1  # odd: centred on a cell
        # Central half of every tile, but at least one footprint wide.
        ax = [(max(0, n // 4 - f // 2), min(n, n - n // 4 + f // 2)) for n in (tnx, tny)]
        b = self.border
        core = self.height_field[b : b + self.num_rows * tnx, b : b + self.num_cols * tny]
        tiles = core.reshape(self.num_rows, tnx, self.num_cols, tny).transpose(0, 2, 1, 3)
        sub = tiles[:, :, ax[0][0] : ax[0][1], ax[1][0] : ax[1][1]]
        fx, fy = min(f, sub.shape[2]), min(f, sub.shape[3])
        win = np.lib.stride_tricks.sliding_window_view
        hi = win(win(sub, fx, axis=2).max(-1), fy, axis=3).max(-1)
        lo = win(win(sub, fx, axis=2).min(-1), fy, axis=3).min(-1)
        span = hi - lo
        # Window centres in cells from the tile corner.
        cx = ax[0][0] + np.arange(span.shape[2]) + (fx - 1) / 2.0
        cy = ax[1][0] + np.arange(span.shape[3]) + (fy - 1) / 2.0
        dist2 = (cx[:, None] - (tnx - 1) / 2.0) ** 2 + (cy[None, :] - (tny - 1) / 2.0) ** 2
        clear = span <= SPAWN_MAX_RANGE
        cost = np.where(clear, dist2, np.inf).reshape(self.num_rows, self.num_cols, -1)
        best = np.argmin(cost, axis=-1)
        none_clear = ~clear.reshape(self.num_rows, self.num_cols, -1).any(-1)
        if none_clear.any():
            warnings.warn(
                f"no flat {SPAWN_FOOTPRINT} m spawn patch (height range <= {SPAWN_MAX_RANGE} m) on tiles "
                f"{np.argwhere(none_clear).tolist()}; using their flattest patch. Give those terrains a platform.",
                stacklevel=3,
            )
            flattest = np.argmin(span.reshape(self.num_rows, self.num_cols, -1), axis=-1)
            best = np.where(none_clear, flattest, best)
        a, bb = np.divmod(best, span.shape[3])
        rows, cols = np.meshgrid(np.arange(self.num_rows), np.arange(self.num_cols), indexing="ij")
        origins = np.empty((self.num_rows, self.num_cols, 3), np.float32)
        origins[..., 0] = (rows * tnx + cx[a]) * self.resolution
        origins[..., 1] = (cols * tny + cy[bb]) * self.resolution
        origins[..., 2] = hi.reshape(self.num_rows, self.num_cols, -1)[rows, cols, best]
        return origins

    # ---------------------------------------------------------------------------------------------- queries
    def tile_bounds(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """(n, 4) x_lo, y_lo, x_hi, y_hi (m, world) of tiles (rows[k], cols[k]); the first tile starts at (0, 0)."""
        lo = np.stack([np.asarray(rows), np.asarray(cols)], -1) * np.array(self.tile_size)
        return np.concatenate([lo, lo + np.array(self.tile_size)], -1)

    def height_at(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Ground height (m) at world points, bilinear between cells; points off the grid take the edge's height."""
        x, y = np.broadcast_arrays(np.asarray(x, np.float64), np.asarray(y, np.float64))
        nx, ny = self.height_field.shape
        u = np.clip((x - self.origin_xy[0]) / self.resolution, 0.0, nx - 1)
        v = np.clip((y - self.origin_xy[1]) / self.resolution, 0.0, ny - 1)
        i0 = np.minimum(np.floor(u).astype(np.int64), max(nx - 2, 0))
        j0 = np.minimum(np.floor(v).astype(np.int64), max(ny - 2, 0))
        i1, j1 = np.minimum(i0 + 1, nx - 1), np.minimum(j0 + 1, ny - 1)
        fu, fv = u - i0, v - j0
        h = self.height_field
        return (
            h[i0, j0] * (1 - fu) * (1 - fv) + h[i1, j0] * fu * (1 - fv) + h[i0, j1] * (1 - fu) * fv + h[i1, j1] * fu * fv
        )

    # ----------------------------------------------------------------------------------------------- export
    def export_mesh(self, path: str | Path) -> Path:
        """Write the heightfield as a triangle mesh (.obj, .glb, .ply or .stl, by suffix) in world coordinates."""
        import trimesh

        path = Path(path)
        if path.suffix.lower() not in (".obj", ".glb", ".ply", ".stl"):
            raise ValueError(f"export_mesh: unsupported suffix {path.suffix!r}; use .obj, .glb, .ply or .stl.")
        nx, ny = self.height_field.shape
        xs = self.origin_xy[0] + np.arange(nx) * self.resolution
        ys = self.origin_xy[1] + np.arange(ny) * self.resolution
        vertices = np.stack(
            [np.repeat(xs, ny), np.tile(ys, nx), self.height_field.ravel().astype(np.float64)], axis=1
        )
        if path.suffix.lower() == ".glb":  # glTF 2.0 is +Y up (its spec, "Coordinate System and Units"): a rotation
            vertices = vertices[:, [0, 2, 1]] * np.array([1.0, 1.0, -1.0])  # (x, y, z) -> (x, z, -y), faces still up
        v00 = (np.arange(nx - 1)[:, None] * ny + np.arange(ny - 1)[None, :]).ravel()
        v10, v01, v11 = v00 + ny, v00 + 1, v00 + ny + 1
        # Counter-clockwise seen from +z, so normals point up.
        faces = np.concatenate([np.stack([v00, v10, v11], 1), np.stack([v00, v11, v01], 1)])
        path.parent.mkdir(parents=True, exist_ok=True)
        trimesh.Trimesh(vertices=vertices, faces=faces, process=False).export(path)
        return path

    def preview_rgb(self) -> np.ndarray:
        """(ny, nx, 3) float RGB in [0, 1], x to the right and y up: hillshaded heights tinted by material."""
        return preview_rgb(self.height_field, self.material, self.resolution)

    def save_preview(self, path: str | Path, max_size: int = 1200, grid: bool = True) -> Path:
        """Write a PNG preview (longest side at most ``max_size`` px), with tile borders drawn if ``grid``."""
        from PIL import Image

        rgb = self.preview_rgb()
        image = Image.fromarray((rgb * 255).round().astype(np.uint8))
        scale = min(1.0, max_size / max(image.size))
        if scale < 1.0:
            image = image.resize((max(1, round(image.width * scale)), max(1, round(image.height * scale))), Image.LANCZOS)
        if grid and self.mode != "plane":
            pixels = np.asarray(image).copy()
            tnx, tny = self.tile_cells
            ny = self.height_field.shape[1]
            for r in range(self.num_rows + 1):
                col = min(round((self.border + r * tnx) * scale), pixels.shape[1] - 1)
                pixels[:, col] = (pixels[:, col] * 0.4).astype(np.uint8)
            for c in range(self.num_cols + 1):
                row = max(min(round((ny - 1 - self.border - c * tny) * scale), pixels.shape[0] - 1), 0)
                pixels[row, :] = (pixels[row, :] * 0.4).astype(np.uint8)
            image = Image.fromarray(pixels)
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        image.save(path, optimize=True)
        return path


SOIL_COLOURS = {
    "dry_sand": (0.93, 0.83, 0.56),
    "wet_sand": (0.72, 0.60, 0.38),
    "snow": (0.86, 0.93, 1.00),  # blue-white: told apart from the grey of high bare ground
    "mud": (0.40, 0.28, 0.17),
    "clay_loam": (0.62, 0.40, 0.26),
    "poppy_seeds_rft": (0.45, 0.47, 0.52),
}
"""Preview tint of each soil preset; other (custom) soils are drawn in CUSTOM_SOIL_COLOUR."""
CUSTOM_SOIL_COLOUR = (0.80, 0.55, 0.75)
WATER_COLOUR = (0.15, 0.40, 0.90)
LOW_FRICTION_COLOUR = (0.30, 0.95, 0.95)
LOW_FRICTION_TINT_BELOW = 0.5
"""Cells with friction below this coefficient are tinted cyan in previews."""


GROUND_GREY = (0.35, 0.85)
"""Lightness of bare ground in previews, from the tile's lowest to its highest cell: grey, so that only materials
(soil, low friction, water) carry colour."""


def preview_rgb(heights: np.ndarray, material: MaterialMap, resolution: float) -> np.ndarray:
    """Hillshaded heights, bare ground grey (lighter: higher, ``GROUND_GREY``), tinted by material; (ny, nx, 3)
    with x right and y up.

    Hillshade: Lambert shading of the surface normal (-dh/dx, -dh/dy, 1) under a light from the north-west at
    45 degrees elevation (the usual cartographic convention).
    """
    h = heights.astype(np.float64)
    lo, hi = float(h.min()), float(h.max())
    elevation = (h - lo) / (hi - lo) if hi > lo else np.full_like(h, 0.5)
    grey = GROUND_GREY[0] + (GROUND_GREY[1] - GROUND_GREY[0]) * elevation
    rgb = np.repeat(grey[..., None], 3, axis=-1)
    gx, gy = np.gradient(h, resolution) if min(h.shape) > 1 else (np.zeros_like(h), np.zeros_like(h))
    normal = np.stack([-gx, -gy, np.ones_like(h)], -1)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    light = np.array([-1.0, 1.0, math.sqrt(2.0)]) / 2.0
    shade = np.clip(normal @ light, 0.0, 1.0)
    rgb = rgb * (0.35 + 0.65 * shade)[..., None]

    def tint(mask: np.ndarray, colour, alpha) -> None:
        a = np.where(mask, alpha, 0.0)[..., None]
        rgb[:] = rgb * (1 - a) + np.asarray(colour) * a * (0.5 + 0.5 * shade[..., None])

    for k, name in enumerate(material.soil_presets):
        tint(material.soil == k, SOIL_COLOURS.get(name, CUSTOM_SOIL_COLOUR), 0.75)
    tint(material.friction < LOW_FRICTION_TINT_BELOW, LOW_FRICTION_COLOUR, 0.6)
    depth = np.where(material.has_water(), material.water_surface - h, 0.0)
    tint(depth > 0, WATER_COLOUR, 0.35 + 0.5 * np.clip(depth / 0.5, 0.0, 1.0))
    return np.clip(rgb.transpose(1, 0, 2)[::-1], 0.0, 1.0)
