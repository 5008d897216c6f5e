"""A current or tide in a meandering river flows along the river's course, not along its mean axis.

The river's course, in its region's frame (origin at the region's centre, u along the axis at ``direction``, v
across it), is v = offset + A sin(2 pi u / L), so its tangent makes atan(2 pi A / L cos(2 pi u / L)) with the
axis. The tiles below have 81 x 81 cells of 0.1 m, so the centre cell (40, 40) lies at the region's centre.
"""

import math

import numpy as np

from legged_gente.terrain.composition import Operation, Part, Region, TileSpec

RES = 0.1
SIZE = 8.1  # 81 cells: cell 40 is the centre of the tile
A, L = 0.5, 8.0
K = 2.0 * math.pi * A / L  # steepest slope of the course to the axis


def build(parts):
    return TileSpec(SIZE, SIZE, RES, 0, parts).build()[1]


def river(direction=0.0, amplitude=A, depth=0.5, width=2.0):
    return Operation("river", {"width": width, "depth": depth, "bank_width": 0.4, "direction": direction,
                               "meander_amplitude": amplitude, "meander_wavelength": L})


def water(direction, flow="current", depth=0.3):
    return Operation("water", {"depth": depth, "flow": flow, "speed": 0.0 if flow == "still" else 0.6,
                               "direction": direction})


def cell(x, y):
    """Cell index of the point (x, y) m from the tile's centre."""
    return 40 + round(x / RES), 40 + round(y / RES)


def angle_gap(a, b):
    """|a - b| wrapped into [0, pi]."""
    return abs(math.remainder(a - b, 2.0 * math.pi))


def test_straight_river_keeps_the_water_direction():
    m = build([Part(Region(0.0, 0.0, SIZE, SIZE), [river(direction=math.pi / 2, amplitude=0.0),
                                                    water(math.pi / 2)])])
    wet = m.has_water()
    assert wet.sum() > 100
    np.testing.assert_allclose(m.flow_direction[wet], math.pi / 2, atol=1e-6)


def test_current_across_a_straight_channel_is_turned_along_it():
    # a current given 0.3 rad off the channel's axis (0) flows along the channel: its banks guide it
    m = build([Part(Region(0.0, 0.0, SIZE, SIZE), [river(amplitude=0.0), water(0.3)])])
    wet = m.has_water()
    assert wet.sum() > 100
    np.testing.assert_allclose(m.flow_direction[wet], 0.0, atol=1e-6)


def test_meandering_current_follows_the_course():
    m = build([Part(Region(0.0, 0.0, SIZE, SIZE), [river(), water(0.0)])])
    # points on the course v = A sin(2 pi u / L) and the course's angle atan(2 pi A / L cos(2 pi u / L))
    for u, expected in ((0.0, math.atan(2 * math.pi * 0.5 / 8)),        # 0.3747 rad
                        (2.0, 0.0),                                      # u = L / 4: the crest
                        (4.0, -math.atan(2 * math.pi * 0.5 / 8)),        # u = L / 2
                        (-2.0, 0.0),                                     # u = -L / 4: the trough
                        (1.0, math.atan(2 * math.pi * 0.5 / 8 * math.cos(math.pi / 4)))):
        i, j = cell(u, 0.5 * math.sin(2 * math.pi * u / 8))
        assert m.has_water()[i, j]
        assert abs(m.flow_direction[i, j] - expected) < 1e-5, (u, m.flow_direction[i, j], expected)
    # across the channel at u = 0, the bed's cells take the course's angle at that u
    i, j = cell(0.0, 0.0)
    for dj in (-5, 5):
        assert m.has_water()[i, j + dj]
        assert abs(m.flow_direction[i, j + dj] - math.atan(K)) < 1e-5
    # continuity: at u = 0 the section normal to the flow is width / sqrt(1 + K^2) wide (width across the axis),
    # so the 0.6 m/s given where the course runs along the axis (the crest, u = L / 4) is sqrt(1 + K^2) faster
    assert abs(m.flow_speed[i, j] - 0.6 * math.sqrt(1.0 + K * K)) < 1e-5  # 0.6 * 1.0678 = 0.6407 m/s
    i, j = cell(2.0, 0.5)
    assert abs(m.flow_speed[i, j] - 0.6) < 1e-6


def test_current_flowing_the_other_way_points_back_along_the_course():
    m = build([Part(Region(0.0, 0.0, SIZE, SIZE), [river(), water(math.pi)])])
    i, j = cell(0.0, 0.0)
    assert abs(m.flow_direction[i, j] - (math.atan(K) - math.pi)) < 1e-5  # atan(K) + pi, wrapped into [-pi, pi]
    i, j = cell(4.0, 0.0)
    assert abs(m.flow_direction[i, j] - (math.pi - math.atan(K))) < 1e-5  # -atan(K) + pi
    wet = m.has_water()
    assert (np.cos(m.flow_direction[wet]) < 0.0).all()  # everywhere it still flows towards -x
    assert (np.abs(m.flow_direction[wet]) <= math.pi).all()


def test_tide_oscillates_along_the_course():
    tide = Operation("water", {"depth": 0.3, "flow": "tide", "speed": 0.4, "direction": math.pi, "omega": 1.0})
    m = build([Part(Region(0.0, 0.0, SIZE, SIZE), [river(), tide])])
    i, j = cell(0.0, 0.0)
    assert abs(m.flow_direction[i, j] - (math.atan(K) - math.pi)) < 1e-5


def test_rotated_axis():
    # axis along +y: the course is x = -A sin(2 pi y / L), its tangent (dx, dy) = (-K cos(2 pi y / L), 1)
    m = build([Part(Region(0.0, 0.0, SIZE, SIZE), [river(direction=math.pi / 2), water(math.pi / 2)])])
    for y in (0.0, 1.0, 2.0, 4.0):
        i, j = cell(-A * math.sin(2 * math.pi * y / L), y)
        expected = math.atan2(1.0, -K * math.cos(2 * math.pi * y / L))
        assert m.has_water()[i, j]
        assert abs(m.flow_direction[i, j] - expected) < 1e-5, (y, m.flow_direction[i, j], expected)


def test_banks_outside_the_channel_keep_the_water_direction():
    # water 0.5 m above a 0.2 m deep river floods the banks too; only the channel (|v - course| < 1 m) turns
    m = build([Part(Region(0.0, 0.0, SIZE, SIZE), [river(depth=0.2), water(0.1, depth=0.5)])])
    assert m.has_water().all()
    i, j = cell(0.0, 0.0)
    assert abs(m.flow_direction[i, j] - math.atan(K)) < 1e-5
    for y in (1.2, -1.2, 3.0):  # more than width / 2 = 1 m across from the course v = 0 at u = 0
        assert abs(m.flow_direction[i, j + round(y / RES)] - 0.1) < 1e-6
        assert abs(m.flow_speed[i, j + round(y / RES)] - 0.6) < 1e-6


def test_river_of_a_smaller_region_turns_only_its_own_channel():
    # the river lies in the back half (x < 4.05 m, centred at x = 2.0 m: its cells 0..40 have centre 20); the water
    # covers the whole tile, so cells beyond the river's region keep the water's direction
    river_region = Region(0.0, 0.0, SIZE / 2, SIZE)
    m = build([Part(river_region, [river(depth=0.2)]),
               Part(Region(0.0, 0.0, SIZE, SIZE), [water(0.0, depth=0.5)])])
    assert m.has_water().all()
    i, j = 20, 40  # u = 0 of the river's frame
    assert abs(m.flow_direction[i, j] - math.atan(K)) < 1e-5
    i, j = 20 + round(2.0 / RES), 40 + round(A / RES)  # u = L / 4, on the crest: 0
    assert abs(m.flow_direction[i, j]) < 1e-6
    i, j = 20 + round(1.0 / RES), 40 + round(A * math.sin(math.pi / 4) / RES)  # u = L / 8
    assert abs(m.flow_direction[i, j] - math.atan(K * math.cos(math.pi / 4))) < 1e-5
    # beyond the river's region (cells 41 onwards) the course's formula would still give a channel, but none is carved
    assert np.allclose(m.flow_direction[41:, :], 0.0)


def test_ground_set_over_the_river_ends_its_channel():
    # a flat part set over the front half after the river replaces its channel there
    m = build([Part(Region(0.0, 0.0, SIZE, SIZE), [river(depth=0.2)]),
               Part(Region(SIZE / 2, 0.0, SIZE, SIZE), [Operation("flat", {})]),
               Part(Region(0.0, 0.0, SIZE, SIZE), [water(0.0, depth=0.5)])])
    i, j = cell(-4.0, 0.0)  # u = -L / 2: -atan(K), in the back half
    assert abs(m.flow_direction[i, j] + math.atan(K)) < 1e-5
    assert np.allclose(m.flow_direction[41:, :], 0.0)  # the front half: cells from x = 4.1 m


def test_still_water_keeps_its_direction():
    m = build([Part(Region(0.0, 0.0, SIZE, SIZE), [river(), water(1.0, flow="still")])])
    wet = m.has_water()
    assert wet.sum() > 100
    np.testing.assert_allclose(m.flow_direction[wet], 1.0, atol=1e-6)


def test_crossing_rivers_give_the_nearest_course():
    # two straight channels 2 m wide cross at the centre, along x and along y; a cell inside both takes the
    # direction of the course it is nearer to (across distance |y| to the first, |x| to the second)
    full = Region(0.0, 0.0, SIZE, SIZE)
    along_x, along_y = river(direction=0.0, amplitude=0.0, depth=0.2), river(direction=math.pi / 2, amplitude=0.0,
                                                                            depth=0.2)
    along_x.mode = along_y.mode = "add"
    m = build([Part(full, [along_x]), Part(full, [along_y]), Part(full, [water(math.pi / 4, depth=0.5)])])
    assert abs(m.flow_direction[cell(0.8, 0.1)]) < 1e-6  # 0.1 m from the x course, 0.8 m from the y one
    assert abs(m.flow_direction[cell(0.1, 0.8)] - math.pi / 2) < 1e-6  # the other way round
    assert abs(m.flow_direction[cell(3.0, 3.0)] - math.pi / 4) < 1e-6  # in neither channel


def test_river_of_no_depth_guides_nothing():
    # a river 0 m deep carves no channel: the water standing 0.3 m over the flat ground keeps its direction
    m = build([Part(Region(0.0, 0.0, SIZE, SIZE), [river(depth=0.0), water(0.1)])])
    assert m.has_water().all()
    np.testing.assert_allclose(m.flow_direction, 0.1, atol=1e-6)
