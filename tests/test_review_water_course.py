"""Review of the water course changes: a river's current or tide along its meandering course, and the land a
sketch lake encloses.

River frame (as in tests/test_river_flow_course.py): 81 x 81 cells of 0.1 m, so cell (40, 40) is the region's
centre; the course is v = A sin(2 pi u / L) with u along the axis at ``direction`` and v across it, its tangent at
atan(2 pi A / L cos(2 pi u / L)) to the axis.
"""

import math

import numpy as np
from test_sketch_water_shapes import _build as sketch
from test_water_bodies import worst_wall

from legged_gente.generation.backends.image import LEGEND
from legged_gente.generation.checker import WATER_WALL_TOLERANCE
from legged_gente.terrain.composition import Operation, Part, Region, TileSpec

RES = 0.1
SIZE = 8.1
A, L = 0.5, 8.0
K = 2.0 * math.pi * A / L  # 0.3927: the course's steepest slope to the axis, atan(K) = 0.3747 rad (21.5 deg)


def _cell(x, y):
    return 40 + round(x / RES), 40 + round(y / RES)


def _river_with(water):
    river = Operation("river", {"width": 2.0, "depth": 0.5, "bank_width": 0.4, "direction": 0.0,
                                "meander_amplitude": A, "meander_wavelength": L})
    return TileSpec(SIZE, SIZE, RES, 0, [Part(Region(0.0, 0.0, SIZE, SIZE), [river, water])]).build()[1]


def test_a_current_far_off_the_axis_flows_one_way_down_the_whole_channel():
    # the current is given at 1.4 rad (80 deg) to the river's axis (0): its component along the axis, cos 1.4 = +0.17,
    # points down +u, so the banks guide all of it down +u. On the course at u = 0 the tangent is +atan(K) = 0.3747 rad
    # and at u = L / 2 = 4 m it is -atan(K) = -0.3747 rad; the latter is 1.775 rad from 1.4 (cos < 0), yet turning it
    # to pi - 0.3747 would send that bend's water up -u, head-on into the water coming down from u = 0: by continuity
    # one channel carries one discharge, in one sense.
    for flow in ("current", "tide"):
        m = _river_with(Operation("water", {"depth": 0.3, "flow": flow, "speed": 0.6, "direction": 1.4}))
        for u, expected in ((0.0, math.atan(K)), (4.0, -math.atan(K)), (-4.0, -math.atan(K))):
            i, j = _cell(u, A * math.sin(2.0 * math.pi * u / L))
            assert m.has_water()[i, j]
            assert abs(m.flow_direction[i, j] - expected) < 1e-5, (flow, u, m.flow_direction[i, j], expected)
        wet = m.has_water()
        assert (np.cos(m.flow_direction[wet]) > 0.0).all(), flow  # every wet cell of the channel flows down +u


def test_the_land_beside_a_diagonal_sketch_river_stays_dry():
    # a water band 20 px (4.2 m) across from the back-right to the front-left corner of a 20 m tile's sketch (96 px:
    # image row r is x = 20 (1 - r / 96) m, column c is y = 20 (1 - c / 96) m): its box is the whole tile, and the
    # two triangles of grass beside it, legs of 76 px (15.8 m), hold squares far larger than DRY_INSIDE_MIN = 3 m.
    # Their edges are stepped, so their row runs are one block high, yet this land is no less enclosed than an L's.
    # Pixel (row 15, col 80) is 45 / sqrt(2) = 32 px (6.6 m) from the band and over 3 m from the tile's edges, past
    # the basin's 1.5 m shore: on the basin's floor, 0.4 m down under 0.3 m of water, unless rebuilt as ground.
    _, _, heights, material = sketch(lambda d: d.polygon([(0, 0), (20, 0), (95, 75), (95, 95), (75, 95), (0, 20)],
                                                         fill=LEGEND["water"].rgb))
    wet = material.has_water()
    for row, col in ((15, 80), (80, 15)):
        i, j = round(20.0 * (1 - row / 96) / 0.1), round(20.0 * (1 - col / 96) / 0.1)
        assert not wet[i, j], (row, col)
        assert abs(float(heights[i, j])) < 0.1, (row, col)  # the sketch's gently uneven ground, not the basin's floor
    assert wet[100, 100]  # the band's middle, at the tile's centre
    assert worst_wall(heights, material) <= WATER_WALL_TOLERANCE  # the rebuilt land meets the water at a bank
