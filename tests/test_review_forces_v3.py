"""Review of the water and terrain-contact changes of 4825471, 737ee9f and 2bf7fbb: what their tests missed.
Expected values from the geometry by hand."""

import math

import mujoco
import numpy as np
import pytest
import warp as wp

from legged_gente.external_forces import field as F
from legged_gente.external_forces import water as W
from legged_gente.external_forces import water_models as WM

wp.config.quiet = True


def _geom(mjm, name):
    return mjm.geom(name).id


def test_foot_ball_welded_to_its_leg_through_a_common_parent_is_found_inside_it():
    # The leg capsule (R 4 cm, half-length 15 cm along z) and the foot ball (r 3 cm, 5 cm up its axis) sit on two
    # jointless children of one jointed body: they move as one. The ball's centre is 0.05 m from the leg's centre
    # along its axis and on it, |t| = 0.05 <= 0.15 - 0.03 and radial 0 <= 0.04 - 0.03: wholly inside the straight
    # part, so the leg's strips hold its volume (no buoyancy, drag or added mass of its own).
    mjm = mujoco.MjModel.from_xml_string("""<mujoco><worldbody>
      <body name="knee" pos="0 0 1"><joint type="slide" axis="1 0 0"/><geom size="0.01" mass="1"/>
        <body name="shank_link" pos="0.1 0 0"><geom name="leg" type="capsule" size="0.04 0.15"/></body>
        <body name="foot_link" pos="0.1 0 0.05"><geom name="ball" type="sphere" size="0.03"/></body>
      </body></worldbody></mujoco>""")
    inside, in_straight = F._foot_spheres_inside_legs(mjm, [_geom(mjm, "ball")], [_geom(mjm, "leg")])
    assert inside.tolist() == [True] and in_straight.tolist() == [True]
    # a ball on a child body with a joint of its own is not welded: it keeps its loads
    moving = mujoco.MjModel.from_xml_string("""<mujoco><worldbody>
      <body name="knee" pos="0 0 1"><joint type="slide" axis="1 0 0"/><geom size="0.01" mass="1"/>
        <body name="shank_link" pos="0.1 0 0"><geom name="leg" type="capsule" size="0.04 0.15"/></body>
        <body name="foot_link" pos="0.1 0 0.05"><joint type="hinge"/>
          <geom name="ball" type="sphere" size="0.03" mass="0.1"/></body>
      </body></worldbody></mujoco>""")
    inside, in_straight = F._foot_spheres_inside_legs(moving, [_geom(moving, "ball")], [_geom(moving, "leg")])
    assert inside.tolist() == [False] and in_straight.tolist() == [False]


def test_a_terrain_contact_cap_within_the_shown_rut_is_refused():
    # A MuJoCo-collided foot on soil sits in its rut: the contact filter first caps the penetration at
    # terrain_contact_max_depth, then shows the rut, dist += min(rut, max_rut_depth). With a 5 mm cap and a 10 mm
    # rut a foot 5 mm or more in the ground gets dist = -0.005 + 0.010 = +0.005 m: no contact force at all, and it
    # sinks through the soil (a 20 kg box sole on dry sand was 19 cm under its rut after 1.5 s). The cap must
    # exceed max_rut_depth; without soil there is no rut and any positive cap holds.
    from test_forces_config import build

    message = r"forces.terrain_contact_max_depth=0.005 must exceed max_rut_depth=0.01"
    with pytest.raises(ValueError, match=message):
        build(soil=True, terrain_contact_max_depth=0.005, max_rut_depth=0.01)
    with pytest.raises(ValueError, match=r"terrain_contact_max_depth=0.01 must exceed max_rut_depth=0.01"):
        build(soil=True, terrain_contact_max_depth=0.01, max_rut_depth=0.01)
    build(soil=True, terrain_contact_max_depth=0.011, max_rut_depth=0.01)
    build(soil=False, terrain_contact_max_depth=0.005, max_rut_depth=0.01)



@wp.kernel
def _frontal_area(x: wp.array2d[float], out: wp.array[float]):
    i = wp.tid()
    out[i] = W.sphere_wet_frontal_area_fn(x[i, 0], x[i, 1], wp.vec3(x[i, 2], x[i, 3], x[i, 4]))


def test_wet_frontal_area_kernel_matches_its_reference_at_the_edge_cases():
    # The Warp twin of water_models.sphere_wet_frontal_area on the directions and depths where its branches meet:
    # flow vertical, within TINY of it (s < 1e-6) and just past it, level; dry, barely wet, wet to the centre, just
    # under full and full. Both against the hand values where they are known: the waterline disk pi (r^2 - h^2) for
    # vertical flow (pi r^2 past the centre), the circular segment for level flow.
    r = 0.05
    directions = [(1, 0, 0), (0, 0, 1), (0, 0, -1), (1e-7, 0, 1), (2e-6, 0, -1), (1e-3, 1e-3, 1), (1, 1, 1),
                  (1, 0, -1e-6), (3, -4, 0.5), (0.6, 0.8, -1.2)]
    depths = [0.0, 1e-4, 0.3 * r, r - 1e-6, r, r + 1e-6, 1.5 * r, 2 * r - 1e-6, 2 * r, 3 * r, -1e-3]
    x = np.asarray([[r, d, *v] for d in depths for v in directions], np.float32)
    got = wp.zeros(len(x), float, device="cpu")
    wp.launch(_frontal_area, dim=len(x), inputs=[wp.array(x, dtype=float, device="cpu"), got], device="cpu")
    ref = [WM.sphere_wet_frontal_area(*row[:2], row[2:5]) for row in x.astype(np.float64)]
    np.testing.assert_allclose(got.numpy(), ref, atol=1e-5 * math.pi * r * r)
    for row, area in zip(x.astype(np.float64), got.numpy()):
        r_, depth, v = row[0], row[1], row[2:5]
        h = depth - r_
        if 0.0 < depth < 2 * r_ and v[0] == v[1] == 0.0:
            hand = math.pi * r_ * r_ if h >= 0 else math.pi * (r_ * r_ - h * h)
            assert area == pytest.approx(hand, rel=1e-4, abs=1e-9)
        if 0.0 < depth < 2 * r_ and v[2] == 0.0:
            hand = r_ * r_ * math.acos(-h / r_) + h * math.sqrt(r_ * r_ - h * h)
            assert area == pytest.approx(hand, rel=1e-4, abs=1e-9)

