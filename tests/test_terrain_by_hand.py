"""Atomic terrains and tile composition against heights worked out by hand from each terrain's documented rule.

Cell i of an n-cell region lies at x = (i - (n - 1) / 2) * resolution from the region's centre: on an odd number
of cells the centre cell is at x = 0, on an even number the two middle cells are at x = -+resolution / 2.
"""

import math

import numpy as np
import pytest

from legged_gente.terrain.composition import Operation, Part, Region, TileSpec
from legged_gente.terrain.registry import ATOMIC_TERRAINS

RES = 0.1


def heights(name, params, shape, seed=0, resolution=RES):
    a = ATOMIC_TERRAINS[name]
    return a.fn(shape, resolution, np.random.default_rng(seed), **a.check_params(params)).astype(np.float64)


# ----------------------------------------------------------------------------------------------- slopes
def test_pyramid_slope_rises_tan_slope_per_metre_past_the_platform():
    """slope = atan(0.5): 0.5 m per metre. 41 x 41 cells, centre cell 20 at x = 0; platform 1.0 m (|x|, |y| <= 0.5).
    Cell 40 (x = 2.0 m) rises 0.5 * (2.0 - 0.5) = 0.75 m, along the row and on the diagonal (Chebyshev rings);
    cell 30 (x = 1.0 m) 0.25 m; cell 25 (x = 0.5 m) is the platform's edge, 0 m."""
    h = heights("pyramid_slope", {"slope": math.atan(0.5), "platform": 1.0, "direction": "up"}, (41, 41))
    assert h[40, 20] == pytest.approx(0.75, abs=1e-6) and h[0, 20] == pytest.approx(0.75, abs=1e-6)
    assert h[40, 40] == pytest.approx(0.75, abs=1e-6) and h[40, 30] == pytest.approx(0.75, abs=1e-6)
    assert h[30, 20] == pytest.approx(0.25, abs=1e-6) and h[20, 10] == pytest.approx(0.25, abs=1e-6)
    assert np.all(h[15:26, 15:26] == 0.0)
    down = heights("pyramid_slope", {"slope": math.atan(0.5), "platform": 1.0, "direction": "down"}, (41, 41))
    assert down[40, 20] == pytest.approx(-0.75, abs=1e-6)


# ----------------------------------------------------------------------------------------------- stairs
def test_stairs_landing_treads_and_risers_on_even_and_odd_cells():
    """step 0.15 m, tread 0.3 m, landing 1.2 m (|x| <= 0.6 m), rising with +x.
    40 cells: x = (i - 19.5) * 0.1; landing x = -0.55..0.55 (i = 14..25, 12 cells); tread 1 x in (0.6, 0.9]: i = 26..28
    at 0.15 m; tread 2 i = 29..31 at 0.30 m; the first tread down, i = 11..13, at -0.15 m.
    41 cells: x = (i - 20) * 0.1; landing x = -0.6..0.6 (i = 14..26, 13 cells); tread 1 i = 27..29 (0.7, 0.8, 0.9)."""
    params = {"step_height": 0.15, "step_width": 0.3, "platform": 1.2, "direction": "up"}
    even = heights("stairs", params, (40, 3))[:, 1]
    assert np.all(even[14:26] == 0.0) and even[13] != 0.0 and even[26] != 0.0
    assert np.allclose(even[26:29], 0.15) and np.allclose(even[29:32], 0.30) and np.allclose(even[11:14], -0.15)
    assert np.allclose(even[32], 0.45) and np.allclose(even[10], -0.30)
    odd = heights("stairs", params, (41, 3))[:, 1]
    assert np.all(odd[14:27] == 0.0) and odd[13] != 0.0 and odd[27] != 0.0
    assert np.allclose(odd[27:30], 0.15) and np.allclose(odd[30:33], 0.30) and np.allclose(odd[11:14], -0.15)
    # every column of a flight along x is the same
    assert np.all(heights("stairs", params, (40, 7)) == even[:, None])


def test_pyramid_stairs_rings_by_hand():
    """Platform 0.6 m, tread 0.3 m, step 0.1 m on 21 x 21 cells (centre cell 10 at 0): a cell k cells from the centre
    (Chebyshev) lies at d = 0.1 k m; d <= 0.3 is the platform (k = 0..3), d in (0.3, 0.6] ring 1 (k = 4..6), (0.6, 0.9]
    ring 2 (k = 7..9), (0.9, 1.2] ring 3 (k = 10)."""
    h = heights("pyramid_stairs", {"step_height": 0.1, "step_width": 0.3, "platform": 0.6, "direction": "up"},
                (21, 21))
    ring = [0, 0, 0, 0, 1, 1, 1, 2, 2, 2, 3]
    assert np.allclose(h[10, 10:], 0.1 * np.array(ring)) and np.allclose(h[10:, 10], 0.1 * np.array(ring))
    assert np.allclose(h[10 + 5, 10 - 2], 0.1) and np.allclose(h[20, 0], 0.3)  # Chebyshev: max(|dx|, |dy|)
    assert np.array_equal(h, h[::-1]) and np.array_equal(h, h[:, ::-1]) and np.array_equal(h, h.T)


@pytest.mark.parametrize("cells", [20, 21])
@pytest.mark.parametrize("direction", ["up", "down"])
def test_pyramid_stairs_without_a_platform_have_no_one_cell_hole_at_the_centre(cells, direction):
    """platform 0: no flat square at the centre, the first ring (d <= tread 0.3 m) covers it. On 20 cells the middle
    cells (x = -0.25..0.25 m, 6 of them) are one square at step_height; on 21 cells the same square is 7 cells,
    x = -0.3..0.3 m, the centre cell at x = 0 included: it used to stay at 0 alone, a one-cell pit (up) or post
    (down) 0.1 m deep in the top (bottom) step, where a foot sinks in."""
    sign = 1.0 if direction == "up" else -1.0
    h = heights("pyramid_stairs", {"step_height": 0.1, "step_width": 0.3, "platform": 0.0, "direction": direction},
                (cells, cells))
    side = 6 if cells == 20 else 7
    lo = (cells - side) // 2
    assert np.allclose(h[lo:lo + side, lo:lo + side], sign * 0.1), h[lo:lo + side, lo:lo + side]
    assert np.allclose(h[lo - 1, lo:lo + side], sign * 0.2)


# ------------------------------------------------------------------------------------------- gap and pit
@pytest.mark.parametrize("cells, platform_cells, trench_cells", [(40, 20, 5), (41, 21, 5)])
def test_gap_platform_trench_and_depth(cells, platform_cells, trench_cells):
    """Platform 2.0 m (d <= 1.0), trench 0.5 m wide (1.0 < d <= 1.5), 0.8 m deep. 40 cells: platform x = -0.95..0.95
    (20 cells), trench 1.05..1.45 (5 cells each side); 41 cells: platform -1.0..1.0 (21), trench 1.1..1.5 (5)."""
    h = heights("gap", {"gap_width": 0.5, "depth": 0.8, "platform": 2.0}, (cells, cells))
    row = h[:, cells // 2]
    assert int((row == 0.0).sum()) == cells - 2 * trench_cells
    assert set(np.round(row, 6).tolist()) == {0.0, -0.8}
    lo = (cells - platform_cells) // 2
    assert np.all(row[lo:lo + platform_cells] == 0.0)
    assert np.allclose(row[lo - trench_cells:lo], -0.8) and np.allclose(row[lo + platform_cells:lo + platform_cells + trench_cells], -0.8)
    assert row[lo - trench_cells - 1] == 0.0 and row[lo + platform_cells + trench_cells] == 0.0


def test_pit_depth_and_side():
    """A 1.0 m pit 0.3 m deep on 20 x 20 cells: |x|, |y| < 0.5 m holds x = -0.45..0.45, 10 x 10 cells at -0.3 m."""
    h = heights("pit", {"width": 1.0, "depth": 0.3}, (20, 20))
    assert np.allclose(h[5:15, 5:15], -0.3) and int((h < 0).sum()) == 100 and h.max() == 0.0


# ------------------------------------------------------------------------------------------------ relief
def test_waves_are_sines_of_the_declared_wavelength():
    """amplitude 0.1 m, wavelength 2.0 m, no platform, 41 x 41 cells (centre cell 20 at 0): pattern x is
    0.1 sin(pi x): 0.1 m at x = 0.5 (cell 25), -0.1 m at x = 1.5 (cell 35), 0 at x = 1.0 (cell 30), the same in every
    column; grid is 0.05 (sin(pi x) + sin(pi y)): 0.1 at (0.5, 0.5), 0 at (0.5, -0.5), -0.1 at (-0.5, -0.5)."""
    x = heights("waves", {"amplitude": 0.1, "wavelength": 2.0, "pattern": "x", "platform": 0.0}, (41, 41))
    assert x[25, 3] == pytest.approx(0.1, abs=1e-6) and x[35, 7] == pytest.approx(-0.1, abs=1e-6)
    assert x[30, 0] == pytest.approx(0.0, abs=1e-6) and np.all(x == x[:, :1])
    y = heights("waves", {"amplitude": 0.1, "wavelength": 2.0, "pattern": "y", "platform": 0.0}, (41, 41))
    assert np.allclose(y, x.T, atol=1e-7)
    g = heights("waves", {"amplitude": 0.1, "wavelength": 2.0, "pattern": "grid", "platform": 0.0}, (41, 41))
    assert g[25, 25] == pytest.approx(0.1, abs=1e-6) and g[25, 15] == pytest.approx(0.0, abs=1e-6)
    assert g[15, 15] == pytest.approx(-0.1, abs=1e-6)


def test_random_uniform_is_bilinear_between_quantised_nodes():
    """spacing 0.2 m = 2 cells: even cells are the nodes, multiples of the 0.01 m step within +-0.08 m; an odd cell
    between two nodes along one axis is their mean, and one between four nodes is the mean of the four."""
    h = heights("random_uniform", {"amplitude": 0.08, "spacing": 0.2, "step": 0.01, "platform": 0.0}, (21, 21), seed=3)
    nodes = h[::2, ::2]
    assert np.allclose(nodes / 0.01, np.round(nodes / 0.01), atol=1e-4) and np.abs(nodes).max() <= 0.08 + 1e-7
    assert np.ptp(nodes) > 0.05  # really random
    assert np.allclose(h[1::2, ::2], (h[0:-1:2, ::2] + h[2::2, ::2]) / 2, atol=1e-6)
    assert np.allclose(h[::2, 1::2], (h[::2, 0:-1:2] + h[::2, 2::2]) / 2, atol=1e-6)
    mid = (h[0:-1:2, 0:-1:2] + h[2::2, 0:-1:2] + h[0:-1:2, 2::2] + h[2::2, 2::2]) / 4
    assert np.allclose(h[1::2, 1::2], mid, atol=1e-6)


@pytest.mark.parametrize("amplitude", [0.01, 0.02])
def test_random_uniform_refuses_an_amplitude_its_step_rounds_to_flat_ground(amplitude):
    """Nodes are drawn in [-amplitude, amplitude] and rounded towards 0 by the step: with amplitude <= step every
    node is 0, a flat tile asked for as rough; refused, naming both values. Just above the step, levels 0 and
    +-step appear."""
    with pytest.raises(ValueError, match=r"random_uniform: amplitude .* step 0.02"):
        ATOMIC_TERRAINS["random_uniform"].check_params({"amplitude": amplitude, "step": 0.02})
    h = heights("random_uniform", {"amplitude": 0.03, "spacing": 0.2, "step": 0.02, "platform": 0.0}, (21, 21))
    assert set(np.round(np.unique(h[::2, ::2]), 6)) == {-0.02, 0.0, 0.02}


def test_river_cross_section():
    """Along x (direction 0), 2.0 m wide bank top to bank top, banks 0.5 m, 0.4 m deep, on 41 cells of 0.05 m across
    (y = (j - 20) * 0.05): the bed |y| <= 0.5 (j = 10..30) at -0.4 m; mid-bank |y| = 0.75 (j = 5, 35) at
    -0.4 * (1 + cos(pi / 2)) / 2 = -0.2 m; |y| >= 1.0 (j = 0, 40) at 0. Offset 0.25 m moves it all 5 cells to +y."""
    p = {"width": 2.0, "bank_width": 0.5, "depth": 0.4, "direction": 0.0, "offset": 0.0}
    h = heights("river", p, (3, 41), resolution=0.05)
    assert np.allclose(h[:, 10:31], -0.4) and np.allclose(h[:, [5, 35]], -0.2)
    assert np.allclose(h[:, [0, 40]], 0.0) and np.all(h == h[:1])
    shifted = heights("river", {**p, "offset": 0.25}, (3, 41), resolution=0.05)
    assert np.allclose(shifted[:, 15:36], -0.4) and np.allclose(shifted[:, [10, 40]], -0.2)


# --------------------------------------------------------------------------------------------- obstacles
def test_stepping_stones_are_stone_size_wide_with_stone_distance_gaps():
    """Stones 0.4 m (4 cells), gaps 0.2 m (2 cells), floor 0.3 m deep, tops within +-0.02 m; away from the cleared
    1.2 m centre a row alternates runs of 4 stone cells and 2 floor cells (the end runs may be cut)."""
    p = {"stone_size": 0.4, "stone_distance": 0.2, "depth": 0.3, "height_noise": 0.02, "platform": 1.2}
    h = heights("stepping_stones", p, (60, 60), seed=2)
    floor = np.isclose(h, -0.3)
    assert np.all(floor | (np.abs(h) <= 0.02 + 1e-7))
    for j in (2, 57):  # rows far from the platform
        row = floor[:, j]
        if row.all():  # a row through a gap is all floor
            continue
        edges = np.flatnonzero(np.diff(row.astype(int))) + 1
        runs = np.diff(edges)
        assert set(runs[row[edges[:-1]]].tolist()) == {2} and set(runs[~row[edges[:-1]]].tolist()) == {4}, runs
    assert np.all(h[24:36, 24:36] == 0.0)  # 1.2 m platform: x = -0.55..0.55, 12 cells on 60


@pytest.mark.parametrize("cells", [20, 21])
def test_without_a_platform_stepping_stones_keep_their_centre(cells):
    """platform 0 clears nothing. Every cell is then the floor (-0.3 m) or a stone top drawn in +-0.05 m (never
    exactly 0): on an odd number of cells the centre cell was set to 0, a 0.3 m post one cell wide in the floor."""
    p = {"stone_size": 0.2, "stone_distance": 0.6, "depth": 0.3, "height_noise": 0.05, "platform": 0.0}
    for seed in range(4):
        h = heights("stepping_stones", p, (cells, cells), seed=seed)
        assert not np.any(h == 0.0), (seed, np.argwhere(h == 0.0))


def test_without_a_platform_obstacles_keep_the_centre_cell():
    """platform 0 clears nothing, on an odd number of cells too (the centre cell at x = y = 0 used to be cleared).
    discrete_obstacles: 3 m blocks centred in a 2.1 m region each cover its centre; every block is 0.25..1 times
    max_height high, so the centre cell is too. pillars: one pillar (round(0.5 * 1.1^2) = 1) of radius >= 1.0 m
    centred in a 1.1 m region, at most 0.6 * sqrt(2) = 0.85 m from the centre: the centre cell is the pillar's 2 m.
    rocks: round(3 * 1.1^2) = 4 rocks of radius 1.0 m, each at most 0.85 m from the centre: the centre cell is on
    a rock, higher than 0."""
    h = heights("discrete_obstacles", {"max_height": 0.2, "min_size": 3.0, "max_size": 3.0, "density": 2.0,
                                       "platform": 0.0}, (21, 21))
    assert 0.05 - 1e-7 <= abs(h[10, 10]) <= 0.2 + 1e-7
    h = heights("pillars", {"height": 2.0, "min_radius": 1.0, "max_radius": 1.5, "density": 0.5, "platform": 0.0},
                (11, 11))
    assert h[5, 5] == 2.0
    h = heights("rocks", {"max_height": 0.3, "min_radius": 1.0, "max_radius": 1.0, "density": 3.0, "platform": 0.0},
                (11, 11))
    assert h[5, 5] > 0.0


def test_discrete_obstacles_count_heights_and_cleared_platform():
    """density 0.2 per m^2 on 10 m x 10 m: 20 blocks; blocks of 0.1 m (one cell each, the one point in
    [c - 0.05, c + 0.05), the centres drawn over the points' span [0, 9.9] m); heights +-(0.25..1) * 0.16 m. With
    seed 1 no two blocks share a cell."""
    h = heights("discrete_obstacles", {"max_height": 0.16, "min_size": 0.1, "max_size": 0.1, "density": 0.2,
                                       "platform": 0.0}, (100, 100), seed=1)
    blocks = h[h != 0.0]
    assert blocks.size == 20
    assert np.all((np.abs(blocks) >= 0.04 - 1e-7) & (np.abs(blocks) <= 0.16 + 1e-7))
    assert (blocks > 0).any() and (blocks < 0).any()  # raised and sunk
    cleared = heights("discrete_obstacles", {"max_height": 0.16, "min_size": 2.0, "max_size": 3.0, "density": 2.0,
                                             "platform": 1.2}, (40, 40))
    assert np.all(cleared[14:26, 14:26] == 0.0)  # |x|, |y| <= 0.6 m: x = -0.55..0.55, 12 cells


def test_pillars_are_the_declared_height_and_count():
    """Pillars of 0.04 m radius stand one cell each (two points 0.1 m apart never both lie in a 0.08 m disc);
    density 0.1 per m^2 on 10 m x 10 m: 10 pillars, each 1.5 m high; with seed 0 none share a cell."""
    h = heights("pillars", {"height": 1.5, "min_radius": 0.04, "max_radius": 0.04, "density": 0.1, "platform": 0.0},
                (100, 100))
    assert int((h > 0).sum()) == 10 and set(h[h > 0].tolist()) == {1.5}


class _FixedDraws:
    """A stand-in generator whose every uniform draw is the fraction ``u`` of its range and whose signs are all +."""

    def __init__(self, u):
        self.u = u

    def uniform(self, low, high, size):
        return np.full(size, low + (high - low) * self.u)

    def choice(self, options, size):
        return np.full(size, max(options))


SCATTERED = [  # sizes and radii fixed (low == high), so only the centres' draw moves an obstacle
    ("discrete_obstacles", {"max_height": 0.2, "min_size": 0.33, "max_size": 0.33, "density": 0.1}),
    ("pillars", {"min_radius": 0.17, "max_radius": 0.17, "density": 0.1}),
    ("rocks", {"min_radius": 0.17, "max_radius": 0.17, "density": 0.1}),
]


def _scattered(name, params, u, shape):
    a = ATOMIC_TERRAINS[name]
    return a.fn(shape, RES, _FixedDraws(u), **a.check_params({**params, "platform": 0.0}))


@pytest.mark.parametrize("name,params", SCATTERED)
def test_obstacle_centres_span_the_cell_points_so_mirrored_draws_give_mirrored_obstacles(name, params):
    """The cell points of 41 x 31 cells span x in [0, 4.0] m and y in [0, 3.0] m. Centres drawn at the fraction
    u = 0.23 of that span, (0.92, 0.69) m, and at 0.77, (3.08, 2.31) m, are mirror images through the region's
    centre, so the obstacles' footprints are too. (Drawn over [0, n * 0.1) m the second centre moved 0.1 * 0.77 m
    further than the first, half a cell further out on average.)"""
    near = _scattered(name, params, 0.23, (41, 31)) != 0.0
    far = _scattered(name, params, 0.77, (41, 31)) != 0.0
    assert near.any() and np.array_equal(far, near[::-1, ::-1])


def test_a_pillar_drawn_at_the_end_of_the_centres_range_stands_on_the_last_cell():
    """A 0.04 m pillar covers one cell. A centre drawn at the fraction 0.9999999 of its range lies on the last cell
    point, (40, 30) at (4.0, 3.0) m; at 0, on cell (0, 0). (Drawn over [0, n * 0.1) m it was at 4.1 m, past the
    region: it vanished.)"""
    p = {"min_radius": 0.04, "max_radius": 0.04, "density": 0.1}
    for u, cell in ((0.9999999, [40, 30]), (0.0, [0, 0])):
        h = _scattered("pillars", p, u, (41, 31))
        assert np.argwhere(h > 0).tolist() == [cell], u


# ------------------------------------------------------------------------------------------- composition
def test_a_part_covers_its_cells_and_fades_over_the_seam_band():
    """Flat 1.0 m on Region x in [0.35, 1.05) of a 2 m x 1 m tile at 0.1 m: the cells at 0.4..1.0 m (i = 4..10) are
    1.0 exactly. Outside, the weight is the smoothstep of t = 1 - distance / 0.3 m, the distance counted from the
    part's edge cells: i = 3 and 11 (one cell, t = 2/3) take 3t^2 - 2t^3 = 20/27, i = 2 and 12 (t = 1/3) 7/27, the
    rest 0."""
    spec = TileSpec(2.0, 1.0, RES, 0, [Part(Region(0.35, 0.0, 1.05, 1.0), [Operation("flat", {"height": 1.0})])])
    h, _ = spec.build()
    row = h[:, 5].astype(np.float64)
    expected = np.zeros(20)
    expected[4:11] = 1.0
    expected[[3, 11]] = 20 / 27
    expected[[2, 12]] = 7 / 27
    assert np.allclose(row, expected, atol=1e-6), row
    assert np.all(h == h[:, :1])


def test_add_stacks_a_pyramid_slope_on_raised_ground():
    """flat 0.5 m (set) then pyramid_slope atan(0.5), platform 0 (add), on a 4.1 m tile at 0.1 m (41 cells): the part
    is generated over the tile widened by 3 cells each side (47 cells, same centre, cell 20 at x = 0): the height at
    x = 2.0 m (cell 40) is 0.5 + 0.5 * 2.0 = 1.5 m, the centre 0.5 m."""
    spec = TileSpec(4.1, 4.1, RES, 0, [Part(Region(0.0, 0.0, 4.1, 4.1), [
        Operation("flat", {"height": 0.5}),
        Operation("pyramid_slope", {"slope": math.atan(0.5), "platform": 0.0}, "add")])])
    h, _ = spec.build()
    assert h[20, 20] == pytest.approx(0.5, abs=1e-6)
    assert h[40, 20] == pytest.approx(1.5, abs=1e-6) and h[0, 40] == pytest.approx(1.5, abs=1e-6)
    assert h[30, 25] == pytest.approx(1.0, abs=1e-6)


def test_a_river_whose_channel_misses_its_region_is_refused():
    """The channel's axis lies |offset| from the region's centre: with offset 10 m on a 10 m x 10 m region (axis
    along y) the whole channel (2.5 m wide) lies beyond the region's edge at 5 m, and nothing was carved, silently.
    Validation refuses it (the channel's edge at 10 - 1.25 m lies 3.75 m beyond the region's at 5 m); a direct build
    warns; offset 6 m (channel edge at 4.75 m) validates and carves its bank."""
    from legged_gente.generation.validation import ValidationError, validate_call

    params = {"width": 2.5, "depth": 0.4, "bank_width": 0.5, "direction": math.pi / 2, "offset": 10.0}
    with pytest.raises(ValidationError, match=r"river: the channel .* outside its 10 m x 10 m region, 3.75 m from it "
                                              r"at the nearest; move it in by changing offset"):
        validate_call("river", {"region": {"x0": 0, "y0": 0, "x1": 10, "y1": 10}, **params}, 10.0, 10.0)
    with pytest.warns(UserWarning, match="misses its region"):
        assert heights("river", params, (101, 101)).min() == 0.0
    validate_call("river", {"region": {"x0": 0, "y0": 0, "x1": 10, "y1": 10}, **params, "offset": 6.0}, 10.0, 10.0)
    h = heights("river", {**params, "offset": 6.0}, (101, 101))
    assert h.min() < -0.01  # the cells within 4.75-5 m lie on the bank
