"""Water forces against textbook values computed here: Archimedes for a tilted box sole, the added mass of a tilted
cylinder across its axis only, Morison with the independence principle on a tilted leg in a tide, the buoyancy
torque of a leg crossing the surface about its hinge."""

import math

import mujoco_warp as mjw
import numpy as np
import pytest
from test_forces_water import DIAGONAL_M, RHO, Cfg, G, assign, make, model, water

from legged_gente.external_forces import water_models as WM
from legged_gente.terrain.materials import FLOW_TIDE

HX, HY, HZ = 0.1, 0.05, 0.02  # box sole half sizes (m): 0.2 x 0.1 x 0.04


def pitched_sole_wet_volume(theta, u):
    """A box sole pitched by theta about y, its lowest edge u below the surface: its wet part is a prism 2 HY wide
    over a right triangle whose legs run up the two edges from the lowest corner, u / sin(theta) along the long
    edge and u / cos(theta) along the short one (valid while u <= 2 HZ cos(theta) and u <= 2 HX sin(theta))."""
    return 2 * HY * u * u / (2 * math.sin(theta) * math.cos(theta))


def test_pitched_box_sole_gets_archimedes_buoyancy():
    # 20 deg: vertical extent 2 e_z = 0.2 sin 20 + 0.04 cos 20 = 0.10599 m. 3 cm of it wet: V = 0.1 * 0.03^2 /
    # (2 sin cos) = 1.400e-4 m^3 (1.37 N), not 0.03 / 0.106 of the box (2.22 N); 3 cm of it dry: 8e-4 - 1.400e-4.
    theta = math.radians(20.0)
    e_z = HX * math.sin(theta) + HZ * math.cos(theta)
    u = 0.03
    wet_low = pitched_sole_wet_volume(theta, u)
    assert wet_low == pytest.approx(1.4002e-4, rel=1e-3)
    box = 8 * HX * HY * HZ
    rot = np.array([[math.cos(theta), 0, math.sin(theta)], [0, 1, 0], [-math.sin(theta), 0, math.cos(theta)]])
    for depth, expect in ((u, wet_low), (2 * e_z - u, box - wet_low)):
        assert WM.box_submerged_volume([HX, HY, HZ], rot, 0.0, depth - e_z) == pytest.approx(expect, rel=1e-6)
    # the kernel, at rest in still water: the foot's water force is its buoyancy alone
    z_w = 0.5
    got = []
    for depth in (u, 2 * e_z - u):
        mjm = model(f'<body name="foot" pos="0 0 {z_w - depth + e_z}" euler="0 20 0"><joint type="slide" '
                    f'axis="0 0 1"/><geom name="box" type="box" size="{HX} {HY} {HZ}" mass="1"/></body>',
                    gravity=True)
        m, d, f = make(mjm, water(surface=z_w), type("C", (Cfg,), {"leg_geom_names": [], "foot_geom_names": ["box"]}))
        mjw.step(m, d)
        got.append(f.foot_water_force.numpy()[0, 0])
    np.testing.assert_allclose(got, [[0, 0, RHO * G * wet_low], [0, 0, RHO * G * (box - wet_low)]], rtol=1e-4,
                               atol=1e-5)


def test_box_tilted_about_two_axes_wets_a_corner_tetrahedron():
    # A corner dipped u deep: the wet part is the tetrahedron cut off the corner by the surface, its edges along the
    # box's axes reaching u / n_i up (n_i = |z . axis_i|): V = u^3 / (6 n_0 n_1 n_2), while u <= 2 h_i n_i.
    a, b = math.radians(25.0), math.radians(35.0)
    rx = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])
    rot = rx @ ry
    n = np.abs(rot[2])
    u = 0.5 * min(2 * np.array([HX, HY, HZ]) * n)
    e_z = float(n @ [HX, HY, HZ])
    expect = u**3 / (6 * n[0] * n[1] * n[2])
    assert WM.box_submerged_volume([HX, HY, HZ], rot, 0.0, u - e_z) == pytest.approx(expect, rel=1e-9)
    # and by symmetry the box is half wet with the surface through its centre
    assert WM.box_submerged_volume([HX, HY, HZ], rot, 0.0, 0.0) == pytest.approx(4 * HX * HY * HZ, rel=1e-12)


@pytest.mark.filterwarnings(DIAGONAL_M)
def test_tilted_cylinder_has_added_mass_across_its_axis_only():
    # A cylinder (r 4 cm, L 0.3 m, 3000 kg/m^3) tilted 30 deg from the vertical, deep under water, released at rest
    # on a slide along its axis a = (sin, 0, cos) and another across it e = (cos, 0, -sin). Gravity less buoyancy
    # along a slide: (m - rho V) g (-z . s); added mass ca rho V across the axis only (Newman 4.13), none along it:
    # along a: -g cos(30) (m - rho V) / m; along e: g sin(30) (m - rho V) / (m + rho V).
    r, half, th = 0.04, 0.15, math.radians(30.0)
    a = (math.sin(th), 0, math.cos(th))
    e = (math.cos(th), 0, -math.sin(th))
    mjm = model(''.join(f'<body pos="{x} 0 1"><joint type="slide" axis="{s[0]} {s[1]} {s[2]}"/><geom name="{name}" '
                        f'type="cylinder" size="{r} {half}" euler="0 30 0" density="3000" contype="0" '
                        'conaffinity="0"/></body>' for x, s, name in ((0, a, "along"), (1, e, "across"))),
                gravity=True)
    m, d, f = make(mjm, water(surface=3.0), type("C", (Cfg,), {"leg_geom_names": ["along", "across"]}))
    mjw.step(m, d)
    vol = math.pi * r * r * 2 * half
    mass = 3000.0 * vol
    expect = [-G * math.cos(th) * (mass - RHO * vol) / mass, G * math.sin(th) * (mass - RHO * vol) / (mass + RHO * vol)]
    np.testing.assert_allclose(d.qacc.numpy()[0], expect, rtol=1e-4)


def test_fixed_tilted_leg_in_tide_feels_morison_by_the_independence_principle():
    # A leg (axis a = (sin, 0, cos), 40 deg) held still in a tide along x, u = A cos(w t + p): the cross-flow
    # u_n = u - (u.a) a = u cos(40) (cos, 0, -sin) gives the drag 0.5 rho cd 2 r L |u_n| u_n; the inertia is
    # Froude-Krylov rho V du (the whole acceleration) plus the added mass ca rho V du_n (across the axis).
    amp, om, ph, th = 0.8, 2.0, 0.4, math.radians(40.0)
    r, half, cd = 0.04, 0.15, 1.1
    mjm = model(f'<body pos="0 0 1"><joint type="slide" axis="1 0 0"/><geom name="leg" type="cylinder" '
                f'size="{r} {half}" euler="0 40 0" density="3000" contype="0" conaffinity="0"/></body>')
    m, d, f = make(mjm, water(surface=3.0, kind=FLOW_TIDE, speed=amp, omega=om, phase=ph))
    vol = math.pi * r * r * 2 * half
    normal = np.array([math.cos(th), 0.0, -math.sin(th)])
    for _ in range(10):
        assign(d.qvel, [[0.0]])
        t = float(d.time.numpy()[0])
        mjw.step(m, d)
        u, du = amp * math.cos(om * t + ph), -amp * om * math.sin(om * t + ph)
        un, dun = u * math.cos(th) * normal, du * math.cos(th) * normal
        expect = (0.5 * RHO * cd * 2 * r * 2 * half * np.linalg.norm(un) * un + RHO * vol * np.array([du, 0, 0])
                  + RHO * vol * dun)
        np.testing.assert_allclose(f.seg_force.numpy()[0, 0], expect, rtol=1e-3, atol=1e-4)


def test_buoyancy_torque_of_a_leg_crossing_the_surface_about_its_hinge():
    # A thin rod (r 1 cm, L 0.6 m) hinged at its top end h = 0.2 m above the surface, tilted theta = 60 deg from the
    # vertical: its submerged length x = L - h / cos(theta) = 0.2 m, whose buoyancy rho g pi r^2 x acts at its
    # middle, (L - x / 2) sin(theta) from the hinge horizontally: torque about y -rho g pi r^2 x (L - x/2) sin(theta)
    # (slender rod; the cut cross-sections near the surface shift it by O(r / L)).
    r, length, h, th = 0.01, 0.6, 0.2, math.radians(60.0)
    x = length - h / math.cos(th)
    mjm = model(f'<body name="b" pos="0 0 {h}"><joint type="hinge" axis="0 1 0"/><geom name="leg" type="cylinder" '
                f'fromto="0 0 0 {length * math.sin(th)} 0 {-length * math.cos(th)}" size="{r}" density="500" '
                'contype="0" conaffinity="0"/></body>', gravity=True)
    m, d, f = make(mjm, water(surface=0.0))
    mjw.step(m, d)
    xf = d.xfrc_applied.numpy()[0, 1]
    com = np.array([0.5 * length * math.sin(th), 0.0, h - 0.5 * length * math.cos(th)])  # body CoM from the hinge
    torque = xf[3:] + np.cross(com - [0.0, 0.0, h], xf[:3])
    buoyancy = RHO * G * math.pi * r * r * x
    assert xf[2] == pytest.approx(buoyancy, rel=0.01)
    assert torque[1] == pytest.approx(-buoyancy * (length - x / 2) * math.sin(th), rel=0.01)


@pytest.mark.parametrize("z_w, expect", [(0.99 - 0.15 - 0.04, 0.0), (1.0, 0.5), (1.0 + 0.15 + 0.04, 1.0)])
def test_vertical_capsule_at_its_tips_and_middle(z_w, expect):
    # A vertical capsule (r 4 cm, cylinder 0.3 m) centred at z = 1: dry below its lower tip, half its volume with the
    # surface through its centre, all of it at its upper tip: rho g (pi r^2 L + 4/3 pi r^3) times 0, 1/2, 1.
    r, half = 0.04, 0.15
    mjm = model(f'<body pos="0 0 1"><joint type="slide" axis="1 0 0"/><geom name="leg" type="capsule" '
                f'size="{r} {half}" density="3000" contype="0" conaffinity="0"/></body>', gravity=True)
    m, d, f = make(mjm, water(surface=z_w))
    mjw.step(m, d)
    full = RHO * G * (math.pi * r * r * 2 * half + 4 / 3 * math.pi * r**3)
    got = f.seg_force.numpy()[0, 0]
    assert np.all(np.isfinite(got))
    np.testing.assert_allclose(got, [0.0, 0.0, expect * full], rtol=1e-4, atol=1e-5)
