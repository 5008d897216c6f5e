"""Geometry at the resolution of the cells: edges that pass through cell points, features thinner than a cell."""

import numpy as np

from legged_gente.terrain.atomic import _clear_centre, _discs
from legged_gente.terrain.registry import ATOMIC_TERRAINS

RES = 0.1


def trench_cells(shape, gap_width):
    """Trench cells on one side of the centre, along the row through the centre."""
    gap = ATOMIC_TERRAINS["gap"]
    h = gap.fn(shape, RES, None, **gap.check_params({"gap_width": gap_width, "platform": 2.0}))
    row = h[:, shape[1] // 2]
    return int((row[shape[0] // 2:] < 0).sum())


def test_a_gap_is_as_wide_on_an_odd_region_as_on_an_even_one():
    """A 2 m platform, then the trench: cells with 1.0 m < |x| <= 1.0 m + gap_width. On 41 cells x = k * 0.1 m
    (k = -20..20): a 0.2 m gap holds k = 11, 12 and a 0.4 m gap k = 11..14. On 40 cells x = (k + 0.5) * 0.1 m:
    1.05, 1.15 m (0.2 m) and 1.05..1.35 m (0.4 m). Either way 0.2 m is 2 cells and 0.4 m is 4."""
    for shape in ((40, 40), (41, 41)):
        assert [trench_cells(shape, w) for w in (0.2, 0.4)] == [2, 4], shape


def test_a_platform_holds_the_cells_on_its_edge():
    """A 1.2 m platform on 41 x 41 cells at 0.1 m: the cells with |x|, |y| <= 0.6 m, k = -6..6, are 13 x 13."""
    h = _clear_centre(np.ones((41, 41), np.float32), RES, 1.2)
    assert int((h == 0).sum()) == 13 * 13


def test_a_pillar_thinner_than_a_cell_fills_the_cell_nearest_its_axis():
    """A 3 cm pillar at (0.43, 0.52) m holds no cell point (the nearest, (0.4, 0.5) m, lies 3.6 cm away): it still
    stands, as the one cell (4, 5)."""
    h = _discs((10, 10), RES, np.array([[0.43, 0.52]]), np.array([0.03]), np.array([2.0]))
    assert np.argwhere(h > 0).tolist() == [[4, 5]] and h[4, 5] == 2.0


def test_every_thin_pillar_of_the_density_stands():
    """0.3 pillars per m^2 on 8 m x 8 m: round(0.3 * 64) = 19 pillars of 3 cm radius, one cell each (two cell
    points 0.1 m apart never both lie in a 6 cm disc). With seed 1 no two share a nearest cell and none lies in the
    last half cell beyond the grid's points."""
    pillars = ATOMIC_TERRAINS["pillars"]
    params = pillars.check_params({"min_radius": 0.03, "max_radius": 0.03, "density": 0.3, "platform": 0.0})
    h = pillars.fn((80, 80), RES, np.random.default_rng(1), **params)
    assert int((h > 0).sum()) == 19


def test_a_pit_leaves_out_the_cells_on_its_edge_at_any_resolution():
    """A 1.8 m pit holds the points with |x|, |y| < 0.9 m. On 21 cells of 0.15 m, x = k * 0.15 m: k = -5..5, 11
    cells (k = 6 lies on the edge; 6 * 0.15 is 0.8999999999999999 in floating point)."""
    pit = ATOMIC_TERRAINS["pit"]
    h = pit.fn((21, 21), 0.15, None, **pit.check_params({"width": 1.8, "depth": 0.3}))
    assert int((h[:, 10] < 0).sum()) == 11
