"""Mosaic tiles: a ``terrain_types`` entry of alternatives joined by ``|`` gives each of a tile's quadrants one of
them, at the tile's difficulty, blended at the seams as a generated terrain's parts are."""

import math

import numpy as np
import pytest

from legged_gente.terrain.composition import SEAM_BAND
from legged_gente.terrain.materials import NO_SOIL
from legged_gente.terrain.terrain import Terrain, parse_tile_type

RES = 0.1
TILE = 8.0  # m: quadrants of 4 m, 40 cells


def grid_cfg(**overrides):
    base = dict(mesh_type="heightfield", mode="curriculum", resolution=RES, border_size=0.0, terrain_length=TILE,
                terrain_width=TILE, num_rows=6, num_cols=2, max_difficulty=1.0, max_init_terrain_level=0,
                curriculum=True, static_friction=1.0, seed=3, selected_terrain=None, selected_params={},
                generated_specs=[], terrain_types=["flat:height=0.5|flat:height=-0.5|flat:height=0.25"],
                terrain_proportions=[1.0])
    base.update(overrides)
    return type("Cfg", (), base)


def tiles(terrain):
    """(rows, cols, 80, 80) heights of every tile."""
    n = int(round(TILE / RES))
    h = terrain.height_field
    return h.reshape(terrain.num_rows, n, terrain.num_cols, n).transpose(0, 2, 1, 3)


# Cells of each quadrant farther than the seam band (and a cell) from the tile's middle lines, where the
# quadrant's own atomic is kept exactly: x, y of cell k at k * RES from the tile's corner; +x is front, +y left.
INNER = int(round((TILE / 2 - SEAM_BAND) / RES)) - 1
QUADRANT_CELLS = {
    "back_right": (slice(0, INNER), slice(0, INNER)),
    "back_left": (slice(0, INNER), slice(80 - INNER, 80)),
    "front_right": (slice(80 - INNER, 80), slice(0, INNER)),
    "front_left": (slice(80 - INNER, 80), slice(80 - INNER, 80)),
}


def quadrant_levels(tile):
    """The one height inside each quadrant (asserts it is one height)."""
    levels = {}
    for name, (si, sj) in QUADRANT_CELLS.items():
        values = np.unique(tile[si, sj])
        assert values.size == 1, f"{name} holds {values}"
        levels[name] = float(values[0])
    return levels


def test_an_entry_with_bars_parses_into_alternatives():
    assert parse_tile_type("flat:height=0.5|hills+rocks") == [[("flat", {"height": 0.5})], [("hills", {}), ("rocks", {})]]
    assert parse_tile_type("hills+rocks") == [[("hills", {}), ("rocks", {})]]
    with pytest.raises(ValueError, match="unknown atomic terrain 'hils'"):
        parse_tile_type("flat|hils")
    for entry in ("flat||rocks", "flat|", "|rocks", "hills+|rocks", "hills+"):
        with pytest.raises(ValueError, match=r"has an empty name before or after a '\|' or '\+'"):
            parse_tile_type(entry)


def test_each_quadrant_is_one_alternative_drawn_per_tile():
    terrain = Terrain(grid_cfg(), num_robots=4)
    seen, mixed = set(), 0
    for row in tiles(terrain):
        for tile in row:
            levels = quadrant_levels(tile)
            assert set(levels.values()) <= {0.5, -0.5, 0.25}
            seen.update(levels.values())
            mixed += len(set(levels.values())) > 1
            # the seams blend: no cell outside the alternatives' range, and no step of a quadrant's full 1 m in a cell
            assert -0.5 <= tile.min() and tile.max() <= 0.5
            assert max(np.abs(np.diff(tile, axis=0)).max(), np.abs(np.diff(tile, axis=1)).max()) < 0.75
    assert seen == {0.5, -0.5, 0.25}
    assert mixed >= 6  # 12 tiles of four draws from three: almost all mixed
    assert terrain.tile_type_names == ["flat:height=0.5|flat:height=-0.5|flat:height=0.25"] * 2


def test_the_draw_follows_the_seed():
    a, b = Terrain(grid_cfg(), 4), Terrain(grid_cfg(), 4)
    np.testing.assert_array_equal(a.height_field, b.height_field)
    c = Terrain(grid_cfg(seed=4), 4)
    assert not np.array_equal(a.height_field, c.height_field)


def test_each_quadrant_takes_the_rows_difficulty():
    # pyramid_slope: h = ±tan(0.4 d) * (ρ - platform / 2) at Chebyshev distance ρ from its centre, platform 1.2 m.
    # A quadrant's atomic spans it widened by the seam band: 46 cells, centred 1.95 m from the tile's corner.
    rows = 6
    terrain = Terrain(grid_cfg(num_rows=rows, terrain_types=["pyramid_slope|pyramid_slope:direction=down"]), 4)
    centre = (40 + 2 * 3 - 1) / 2 * RES - 3 * RES  # 1.95 m
    i, j = 33, 19  # x 3.3 m, y 1.9 m in the back-right quadrant: ρ = max(1.35, 0.05) m, 0.7 m from the seam
    rho = max(abs(i * RES - centre), abs(j * RES - centre))
    assert rho == pytest.approx(1.35)
    for r, row in enumerate(tiles(terrain)):
        d = r / (rows - 1)
        rise = math.tan(0.4 * d) * (rho - 0.6)
        for tile in row:
            assert abs(float(tile[i, j])) == pytest.approx(rise, abs=1e-6)


def test_a_physical_alternative_covers_whole_quadrants():
    terrain = Terrain(grid_cfg(terrain_types=["flat|soil:preset=mud"]), 4)
    n = 80
    soil = (terrain.material.soil != NO_SOIL).reshape(terrain.num_rows, n, terrain.num_cols, n).transpose(0, 2, 1, 3)
    counts = []
    for row in soil:
        for tile in row:
            covered = 0
            for i0 in (0, 40):
                for j0 in (0, 40):
                    q = tile[i0:i0 + 40, j0:j0 + 40]
                    assert q.all() or not q.any()  # a quadrant is mud or it is not
                    covered += int(q.all())
            counts.append(covered)
    assert 0 < sum(counts) < 4 * len(counts)
    np.testing.assert_array_equal(terrain.height_field, 0.0)  # mud alone lies on flat ground


def test_random_mode_draws_mosaics_too():
    terrain = Terrain(grid_cfg(mode="random", terrain_types=["flat:height=0.5|flat:height=-0.5", "flat"],
                               terrain_proportions=[0.5, 0.5]), 4)
    names = set(terrain.tile_names.ravel())
    assert names == {"flat:height=0.5|flat:height=-0.5", "flat"}
    for (r, c), name in np.ndenumerate(terrain.tile_names):
        levels = set(quadrant_levels(tiles(terrain)[r, c]).values())
        assert levels <= ({0.5, -0.5} if "|" in name else {0.0})
