"""Strip-theory water forces in tiny MuJoCo-Warp worlds on the CPU, against hand-computed strip theory, Morison and
Archimedes; and the water kernels against their numpy references (water_models.py)."""

import math

import mujoco
import mujoco_warp as mjw
import numpy as np
import pytest
import warp as wp

from legged_gente.external_forces import water as W
from legged_gente.external_forces import water_models as WM
from legged_gente.external_forces.field import ForcesConfig, TerrainForces
from legged_gente.terrain.materials import FLOW_TIDE, MaterialMap

wp.config.quiet = True
DEV = "cpu"
RES, ORIGIN, SHAPE = 0.1, (-2.0, -2.0), (41, 41)
RHO, CD, G = 1000.0, 1.1, 9.81
R, H = 0.04, 0.15  # leg radius and cylinder half-length: L = 0.3 m
L = 2 * H
DIAGONAL_M = "ignore:forces. water geoms"  # a lone free body: MuJoCo keeps its M diagonal (warned, exact here)


class Cfg(ForcesConfig):
    noise_std = 0.0
    drag_coefficient = CD
    soil = False
    friction_from_map = False
    sole_contact = False  # water only: these scenes have no terrain geom for analytic sole contacts
    leg_geom_names = ["leg"]
    foot_geom_names: list = []


def model(body: str, gravity: bool = False, dt: float = 0.005):
    opt = "" if gravity else 'gravity="0 0 0"'
    return mujoco.MjModel.from_xml_string(
        f'<mujoco><option timestep="{dt}" {opt}/><worldbody>{body}</worldbody></mujoco>')


def water(surface=2.0, kind=0, speed=0.0, direction=0.0, omega=0.0, phase=0.0):
    mat = MaterialMap.rigid(SHAPE)
    mat.water_surface[:] = surface
    mat.flow_kind[:] = kind
    mat.flow_speed[:] = speed
    mat.flow_direction[:] = direction
    mat.flow_omega[:] = omega
    mat.flow_phase[:] = phase
    return mat


def make(mjm, mat, cfg=Cfg, nworld=1):
    wp.set_device(DEV)
    m = mjw.put_model(mjm)
    d = mjw.make_data(mjm, nworld=nworld, nconmax=8, njmax=32)
    f = TerrainForces(mjm, m, d, np.zeros(SHAPE, np.float32), ORIGIN, RES, mat, cfg(), seed=1)
    f.install()
    return m, d, f


def assign(arr, values):
    arr.assign(wp.array(np.asarray(values, np.float32), dtype=float, device=DEV))


def circle_wet_area(r, h):
    """Hand formula: circular segment of height h (0..2r): r^2 acos((r - h)/r) - (r - h) sqrt(2 r h - h^2)."""
    h = np.clip(h, 0.0, 2 * r)
    return r * r * np.arccos((r - h) / r) - (r - h) * np.sqrt(2 * r * h - h * h)


def tilted_wet_volume(r, half, tilt, z_surface_above_centre):
    """Hand strip integral: V = int_{-H}^{H} A(h(s)) ds, the cross-section at s (axis tilted `tilt` from the
    vertical) cut by the surface at height h(s) = r + (z_w - s cos(tilt)) / sin(tilt) above its lowest chord."""
    s = np.linspace(-half, half, 200001)
    h = r + (z_surface_above_centre - s * np.cos(tilt)) / np.sin(tilt)
    return np.trapezoid(circle_wet_area(r, h), s)


def leg_body(joints: str, euler="0 0 0", z=1.0, density=3000.0, geom="cylinder"):
    """A body at height z with ``joints`` (in world axes) and a leg geom rotated by ``euler`` about its centre."""
    return (f'<body name="b" pos="0 0 {z}">{joints}<geom name="leg" type="{geom}" size="{R} {H}" euler="{euler}" '
            f'density="{density}" contype="0" conaffinity="0"/></body>')


SLIDE_X = '<joint type="slide" axis="1 0 0"/>'


# ------------------------------------------------------------------------------------------------ item 4: drag


@pytest.mark.parametrize("tilt_deg", [0.0, 30.0, 60.0, 90.0])
def test_crossflow_drag_on_tilted_legs(tilt_deg):
    # A leg tilted by theta from the vertical in the x-z plane, axis a = (sin, 0, cos), towed along x at v: the
    # cross-flow is v_n = v cos(theta) (cos(theta), 0, -sin(theta)); strip theory: F = -0.5 rho cd (2 r L) |v_n| v_n.
    # At 90 deg the leg moves along its axis: no cross-flow, no drag (no axial skin term is modelled).
    th, v = math.radians(tilt_deg), 0.8
    mjm = model(leg_body(SLIDE_X, euler=f"0 {tilt_deg} 0"))
    m, d, f = make(mjm, water(surface=2.0))
    assign(d.qvel, [[v]])
    mjw.step(m, d)
    vn = v * math.cos(th) * np.array([math.cos(th), 0.0, -math.sin(th)])
    expect = -0.5 * RHO * CD * (2 * R * L) * np.linalg.norm(vn) * vn
    got = f.seg_force.numpy()[0, 0]
    np.testing.assert_allclose(got, expect, rtol=1e-3, atol=1e-4)
    # uniform load on a symmetric leg: no torque about its centre
    np.testing.assert_allclose(d.xfrc_applied.numpy()[0, 1, 3:], 0.0, atol=1e-4)


SLIDE_Z = '<joint type="slide" axis="0 0 1"/>'


def test_the_papers_leg_options_by_hand():
    """A leg tilted 45 deg (axis a = (sin 45, 0, cos 45)) deep under water. Sinking at v = 0.6 m/s its cross-flow is
    v_n = v - (v.a) a = (v/2, 0, -v/2), |v_n| = v / sqrt 2: F = -0.5 rho cd (2 r L) |v_n| v_n. GenTe's options:
    vertical_drag=False drops the vertical part of the relative velocity first (a sinking leg feels none);
    paper_drag_area takes 2 pi r L instead of 2 r L (pi times the force). At rest under gravity the leg is buoyed by
    rho g V, V = pi r^2 L; paper_added_mass adds the added mass ca rho V as weight instead: (1 - ca) rho g V, half
    of it at ca = 0.5. The paper's eps (noise_std) scales drag and buoyancy per env."""
    v = 0.6
    vn = np.array([v / 2, 0.0, -v / 2])
    drag = -0.5 * RHO * CD * (2 * R * L) * np.linalg.norm(vn) * vn
    for options, expect in (({}, drag), ({"vertical_drag": False}, np.zeros(3)),
                            ({"paper_drag_area": True}, math.pi * drag)):
        m, d, f = make(model(leg_body(SLIDE_Z, euler="0 45 0")), water(surface=3.0), type("C", (Cfg,), options))
        assign(d.qvel, [[-v]])
        mjw.step(m, d)
        np.testing.assert_allclose(f.seg_force.numpy()[0, 0], expect, rtol=1e-3, atol=1e-4, err_msg=str(options))
    weight = RHO * G * math.pi * R**2 * L  # rho g V of the displaced water: 14.5 N
    for options, expect in (({}, weight), ({"paper_added_mass": True, "added_mass_coefficient": 0.5}, 0.5 * weight)):
        m, d, f = make(model(leg_body(SLIDE_Z, euler="0 45 0"), gravity=True), water(surface=3.0),
                       type("C", (Cfg,), options))
        mjw.step(m, d)
        np.testing.assert_allclose(f.seg_force.numpy()[0, 0], [0.0, 0.0, expect], rtol=1e-3, atol=1e-4,
                                   err_msg=str(options))
    m, d, f = make(model(leg_body(SLIDE_Z, euler="0 45 0"), gravity=True), water(surface=3.0),
                   type("C", (Cfg,), {"noise_std": 0.1}), nworld=4)
    eps = f.eps.numpy()
    assert np.ptp(eps) > 0.01  # four different draws
    assign(d.qvel, np.full((4, 1), -v))
    mjw.step(m, d)
    np.testing.assert_allclose(f.seg_force.numpy()[:, 0], eps[:, None] * (drag + [0.0, 0.0, weight]), rtol=1e-3,
                               atol=1e-4)


def test_crossflow_drag_on_tilted_leg_crossing_the_surface():
    # 45 deg, surface 5 cm above the centre: the drag acts on the wetted volume V (strip integral of circular
    # segments, by hand below) as on a wetted length V / (pi r^2): F = -0.5 rho cd 2 r V/(pi r^2) |v_n| v_n.
    th, v, dz = math.radians(45.0), 0.6, 0.05
    mjm = model(leg_body(SLIDE_X, euler="0 45 0", z=1.0))
    m, d, f = make(mjm, water(surface=1.0 + dz))
    assign(d.qvel, [[v]])
    mjw.step(m, d)
    vol = tilted_wet_volume(R, H, th, dz)
    vn = v * math.cos(th) * np.array([math.cos(th), 0.0, -math.sin(th)])
    expect = -0.5 * RHO * CD * 2 * R * vol / (math.pi * R**2) * np.linalg.norm(vn) * vn
    np.testing.assert_allclose(f.seg_force.numpy()[0, 0], expect, rtol=1e-2)


def test_rotating_leg_damping_torque_and_spin_down():
    # A leg of length L hinged at its top end spins at omega about y in still water. Strip theory: the damping
    # torque is int_0^L 0.5 rho cd (2 r) (omega s)^2 s ds = 0.5 rho cd 2 r omega^2 L^4 / 4.
    w0 = 3.0
    mjm = model(f'<body name="b" pos="0 0 1"><joint type="hinge" axis="0 1 0"/><geom name="leg" type="cylinder" '
                f'size="{R} {H}" pos="0 0 {-H}" density="3000" contype="0" conaffinity="0"/></body>')
    m, d, f = make(mjm, water(surface=3.0))
    assign(d.qvel, [[w0]])
    mjw.step(m, d)
    c = 0.5 * RHO * CD * 2 * R * L**4 / 4
    xf = d.xfrc_applied.numpy()[0, 1]
    lever = np.array([0.0, 0.0, -H])  # body CoM relative to the hinge
    torque = xf[3:] + np.cross(lever, xf[:3])
    np.testing.assert_allclose(torque[1], -c * w0**2, rtol=1e-3)
    # Spin-down: (I + I_a) dw/dt = -c w^2 -> w(t) = w0 / (1 + c w0 t / (I + I_a)), with the leg's inertia about its
    # end I = m (r^2/4 + L^2/3) and the added inertia of its strips I_a = int_0^L ca rho pi r^2 s^2 ds.
    mass = 3000.0 * math.pi * R**2 * L
    inertia = mass * (R**2 / 4 + L**2 / 3)
    added = RHO * math.pi * R**2 * L**3 / 3
    steps = 200
    for _ in range(steps - 1):
        mjw.step(m, d)
    t = steps * mjm.opt.timestep
    expect = w0 / (1 + c * w0 * t / (inertia + added))
    np.testing.assert_allclose(d.qvel.numpy()[0, 0], expect, rtol=1e-2)


# ------------------------------------------------------------------------------- item 5: added mass and tide


@pytest.mark.filterwarnings(DIAGONAL_M)
def test_light_free_body_with_twice_its_mass_added_is_stable_and_coasts_down():
    # A free horizontal cylinder of density 500 kg/m^3 in water: added mass m_a = ca rho pi r^2 L = 2 m.
    # Coast-down across its axis: (m + m_a) dv/dt = -k v|v|, k = 0.5 rho cd 2 r L -> v = v0 / (1 + k v0 t/(m + m_a)).
    v0 = 1.0
    mjm = model(leg_body("<freejoint/>", euler="0 90 0", density=500.0), dt=0.002)
    m, d, f = make(mjm, water(surface=3.0))
    mass = 500.0 * math.pi * R**2 * L
    m_a = RHO * math.pi * R**2 * L
    assert m_a == pytest.approx(2 * mass)
    k = 0.5 * RHO * CD * 2 * R * L
    assign(d.qvel, [[0.0, v0, 0.0, 0.0, 0.0, 0.0]])
    dt, got = mjm.opt.timestep, []
    for _ in range(4):
        for _ in range(125):
            mjw.step(m, d)
        got.append(d.qvel.numpy()[0, 1])
    t = dt * 125 * np.arange(1, 5)
    np.testing.assert_allclose(got, v0 / (1 + k * v0 * t / (mass + m_a)), rtol=1e-2)


@pytest.mark.filterwarnings(DIAGONAL_M)
def test_light_floating_body_stays_bounded_and_heaves_at_the_added_mass_period():
    # Dropped from 1 cm above its floating position (axis at the surface: half its volume's buoyancy equals its
    # weight at density 500), the same light cylinder bobs with heave stiffness rho g (2 r L) (its waterplane) and
    # mass m + m_a, m_a = ca rho V_sub = m there: period 2 pi sqrt(2 m / (rho g 2 r L)), bounded, around z = 0.5.
    mjm = model(leg_body("<freejoint/>", euler="0 90 0", density=500.0, z=0.51), gravity=True, dt=0.002)
    m, d, f = make(mjm, water(surface=0.5))
    mass = 500.0 * math.pi * R**2 * L
    period = 2 * math.pi * math.sqrt(2 * mass / (RHO * G * 2 * R * L))
    zs = []
    for _ in range(1000):
        mjw.step(m, d)
        zs.append(d.qpos.numpy()[0, 2] - 0.5)
    zs = np.asarray(zs)
    assert np.all(np.isfinite(zs)) and np.abs(zs).max() < 0.015
    up = np.nonzero((zs[:-1] < 0) & (zs[1:] >= 0))[0]
    t_up = (up + zs[up] / (zs[up] - zs[up + 1])) * mjm.opt.timestep  # interpolated upward zero crossings
    assert len(up) >= 3
    assert np.mean(np.diff(t_up)) == pytest.approx(period, rel=0.03)


def test_fixed_leg_in_tide_feels_morison_with_cm_one_plus_ca():
    # A fixed vertical leg in a tide u = A cos(w t + p): Morison's force with cm = 1 + ca (Froude-Krylov + added mass)
    # F = 0.5 rho cd (2 r L) |u| u + rho (1 + ca) pi r^2 L du/dt, from the first substep on.
    amp, om, ph = 0.8, 2.0, 0.4
    mjm = model(leg_body(SLIDE_X))
    m, d, f = make(mjm, water(surface=3.0, kind=FLOW_TIDE, speed=amp, omega=om, phase=ph))
    for _ in range(20):
        assign(d.qvel, [[0.0]])
        t = float(d.time.numpy()[0])
        mjw.step(m, d)
        u, du = amp * math.cos(om * t + ph), -amp * om * math.sin(om * t + ph)
        morison = 0.5 * RHO * CD * 2 * R * L * abs(u) * u + RHO * (1 + 1.0) * math.pi * R**2 * L * du
        assert f.seg_force.numpy()[0, 0, 0] == pytest.approx(morison, rel=1e-3, abs=1e-3)


@pytest.mark.filterwarnings(DIAGONAL_M)
def test_feet_released_in_still_water_start_with_their_added_mass():
    # Released at rest deep under water, a foot starts at a = g (m - rho V) / (m + m_a) (no drag at v = 0).
    # A sphere (density 3000): m_a = rho V / 2 (potential flow), a = g (3000 - 1000) / (3000 + 500).
    # A box sole 0.22 x 0.09 x 0.04 m of 1 kg, level: its 0.22 x 0.09 face moves normal to itself, a thin plate's
    # m_a = C_A rho (pi/4) a^2 b with DNV-RP-C205's C_A interpolated in a/b = 0.409 between 0.801 (a/b 0.4) and
    # 0.757 (a/b 0.5). The same sole on its edge (turned 90 deg about x) moves its 0.22 x 0.04 face: a/b = 0.182,
    # between 0.917 (a/b 0.16) and 0.897 (a/b 0.2).
    r, hx, hy, hz, m_sole = 0.03, 0.11, 0.045, 0.02, 1.0
    slide = '<joint type="slide" axis="0 0 1"/>'
    mjm = model(f'<body pos="0 0 1">{slide}<geom name="ball" type="sphere" size="{r}" density="3000"/></body>'
                f'<body pos="1 0 1">{slide}<geom name="sole" type="box" size="{hx} {hy} {hz}" mass="{m_sole}"/></body>'
                f'<body pos="-1 0 1">{slide}<geom name="edge" type="box" size="{hx} {hy} {hz}" mass="{m_sole}" '
                'euler="90 0 0"/></body>', gravity=True)
    cfg = type("C", (Cfg,), {"leg_geom_names": [], "foot_geom_names": ["ball", "sole", "edge"]})
    m, d, f = make(mjm, water(surface=3.0), cfg)
    mjw.step(m, d)

    def plate(a, b, ca_lo, x_lo, ca_hi, x_hi):  # DNV's C_A at a/b by linear interpolation, times rho pi/4 a^2 b
        ca = ca_lo + (a / b - x_lo) / (x_hi - x_lo) * (ca_hi - ca_lo)
        return ca * RHO * math.pi / 4 * a * a * b

    v_ball, v_sole = 4 / 3 * math.pi * r**3, 8 * hx * hy * hz
    m_ball = 3000.0 * v_ball
    m_flat = plate(2 * hy, 2 * hx, 0.801, 0.4, 0.757, 0.5)
    m_edge = plate(2 * hz, 2 * hx, 0.917, 0.16, 0.897, 0.2)
    assert m_flat == pytest.approx(1.11, abs=0.01)  # the 1.1 kg docs/forces.md quotes for the biped's sole
    expect = [-G * (m_ball - RHO * v_ball) / (m_ball + RHO * v_ball / 2),
              -G * (m_sole - RHO * v_sole) / (m_sole + m_flat),
              -G * (m_sole - RHO * v_sole) / (m_sole + m_edge)]
    np.testing.assert_allclose(d.qacc.numpy()[0], expect, rtol=1e-4)


def test_fixed_sphere_foot_in_tide_feels_morison_with_cm_one_and_a_half():
    # A fixed sphere in a tide u = A cos(w t + p): drag 0.5 rho cd pi r^2 |u| u plus Froude-Krylov and added mass
    # (rho V + rho V / 2) du/dt (Morison's cm = 1.5 for a sphere).
    amp, om, ph, r = 0.8, 2.0, 0.4, 0.03
    mjm = model(f'<body pos="0 0 1">{SLIDE_X}<geom name="ball" type="sphere" size="{r}" density="3000"/></body>')
    cfg = type("C", (Cfg,), {"leg_geom_names": [], "foot_geom_names": ["ball"]})
    m, d, f = make(mjm, water(surface=3.0, kind=FLOW_TIDE, speed=amp, omega=om, phase=ph), cfg)
    vol = 4 / 3 * math.pi * r**3
    for _ in range(20):
        assign(d.qvel, [[0.0]])
        t = float(d.time.numpy()[0])
        mjw.step(m, d)
        u, du = amp * math.cos(om * t + ph), -amp * om * math.sin(om * t + ph)
        morison = 0.5 * RHO * 0.47 * math.pi * r * r * abs(u) * u + 1.5 * RHO * vol * du
        assert f.foot_water_force.numpy()[0, 0, 0] == pytest.approx(morison, rel=1e-3, abs=1e-4)


# -------------------------------------------------------------------------------------- item 6: buoyancy


def test_horizontal_capsule_buoyancy_is_continuous_through_the_surface():
    # A horizontal capsule (axis x) whose lowest point is h below the surface displaces
    # A(h) * L (circular segment, hand formula) + pi h^2 (3 r - h) / 3 (its two caps make one sphere).
    hs = np.linspace(-0.01, 2 * R + 0.01, 23)
    z_w = 1.0
    mjm = model('<body name="b" pos="0 0 0" euler="0 90 0"><joint type="slide" axis="1 0 0"/>'
                f'<geom name="leg" type="capsule" size="{R} {H}" density="3000" contype="0" conaffinity="0"/></body>',
                gravity=True)
    m, d, f = make(mjm, water(surface=z_w), nworld=len(hs))
    # the slide axis is the body's x = world -z (euler 0 90 0): qpos = -(centre height)
    assign(d.qpos, -(z_w - hs + R)[:, None])
    mjw.step(m, d)
    hc = np.clip(hs, 0, 2 * R)
    expect = RHO * G * (circle_wet_area(R, hs) * L + math.pi * hc**2 * (3 * R - hc) / 3)
    got = f.seg_force.numpy()[:, 0, 2]
    np.testing.assert_allclose(got, expect, rtol=1e-3, atol=1e-4)
    assert np.all(np.diff(got) >= -1e-6)
    assert np.abs(np.diff(got)).max() < 0.1 * RHO * G * (math.pi * R**2 * L)  # no jump as the axis crosses


@pytest.mark.parametrize("tilt_deg", [20.0, 45.0, 70.0])
def test_tilted_cylinder_buoyancy_matches_the_strip_integral(tilt_deg):
    th = math.radians(tilt_deg)
    for dz in (-0.1, 0.0, 0.07):
        mjm = model(leg_body(SLIDE_X, euler=f"0 {tilt_deg} 0", z=1.0), gravity=True)
        m, d, f = make(mjm, water(surface=1.0 + dz))
        mjw.step(m, d)
        expect = RHO * G * tilted_wet_volume(R, H, th, dz)
        assert f.seg_force.numpy()[0, 0, 2] == pytest.approx(expect, rel=1e-3, abs=1e-4)


def two_soles(z_w, axis="0 0 1", gravity=False, **settings):
    """A box sole 0.2 x 0.1 x 0.04 m and a sphere sole r = 3 cm, each on a slide joint along ``axis``, their centres
    at height ``z_w`` (the water surface in the tests), 1 m apart; their forces (ForcesConfig ``settings``), feet 0
    and 1."""
    mjm = model(f'<body name="foot0" pos="0 0 {z_w}"><joint type="slide" axis="{axis}"/>'
                '<geom name="box" type="box" size=".1 .05 .02" mass="1"/></body>'
                f'<body name="foot1" pos="1 0 {z_w}"><joint type="slide" axis="{axis}"/>'
                '<geom name="ball" type="sphere" size=".03" mass="1"/></body>', gravity=gravity)
    cfg = type("C", (Cfg,), {"leg_geom_names": [], "foot_geom_names": ["box", "ball"], **settings})
    return make(mjm, water(surface=z_w), cfg)


def test_foot_soles_half_submerged_get_archimedes_and_plate_drag():
    # A level box sole 0.2 x 0.1 x 0.04 m and a sphere sole r = 3 cm, each with its centre at the surface:
    # buoyancy rho g V/2. The box moving down at 0.5 m/s: its bottom face (0.2 x 0.1, all wet) takes plate drag
    # 0.5 rho 1.17 A v^2 upwards (Hoerner's flat plate); the sphere moving down: its wet hemisphere faces the flow
    # with the whole waterline disk, 0.5 rho 0.47 (pi r^2) v^2.
    z_w, v = 0.5, 0.5
    m, d, f = two_soles(z_w, gravity=True)
    mjw.step(m, d)
    box_v, ball_v = 0.2 * 0.1 * 0.04, 4 / 3 * math.pi * 0.03**3
    np.testing.assert_allclose(f.foot_water_force.numpy()[0, :, 2], [RHO * G * box_v / 2, RHO * G * ball_v / 2],
                               rtol=1e-4)
    expect = [RHO * G * box_v / 2 + 0.5 * RHO * 1.17 * 0.2 * 0.1 * v * v,
              RHO * G * ball_v / 2 + 0.5 * RHO * 0.47 * math.pi * 0.03**2 * v * v]
    # vertical_drag=False (the paper's horizontal drag) concerns the legs' model only: the feet keep theirs
    for vertical_drag in (True, False):
        m, d, f = two_soles(z_w, gravity=True, vertical_drag=vertical_drag)
        assign(d.qvel, [[-v, -v]])
        mjw.step(m, d)
        np.testing.assert_allclose(f.foot_water_force.numpy()[0, :, 2], expect, rtol=1e-4)


def test_half_submerged_soles_moving_sideways_get_the_drag_of_their_wet_part():
    """The same soles, centres at the surface, towed horizontally at 0.5 m/s: only the wet half of each side face
    resists. Box 0.2 x 0.1 x 0.04 m along x: its 0.1 x 0.04 m face pair, half wet, 0.5 rho 1.17 (0.004 / 2) v^2 =
    0.2925 N; along y its 0.2 x 0.04 m pair, 0.585 N (Hoerner's flat plate). The sphere (r 3 cm) shows the flow a
    half disc: 0.5 rho 0.47 (pi r^2 / 2) v^2 = 0.0831 N."""
    z_w, v = 0.5, 0.5
    for axis in ("1 0 0", "0 1 0"):
        m, d, f = two_soles(z_w, axis)
        assign(d.qvel, [[v, v]])
        mjw.step(m, d)
        k = 0 if axis == "1 0 0" else 1
        face = 4 * 0.05 * 0.02 if k == 0 else 4 * 0.1 * 0.02  # m^2, the face pair normal to the motion
        expect = [-0.5 * RHO * 1.17 * face / 2 * v * v, -0.5 * RHO * 0.47 * math.pi * 0.03**2 / 2 * v * v]
        got = f.foot_water_force.numpy()[0]
        np.testing.assert_allclose(got[:, k], expect, rtol=1e-4)
        np.testing.assert_allclose(got[:, 1 - k], 0.0, atol=1e-6)


def test_feet_lifted_out_of_the_water_lose_their_forces_and_added_mass():
    # The box and sphere soles half submerged, each on a vertical slide of 1 kg: each one's added mass is its wet
    # fraction, 1/2, of the wholly wet one's. The box's 0.2 x 0.1 face moves normal to itself: DNV-RP-C205's thin
    # plate, C_A = 0.757 at a/b = 0.5, m_a = C_A rho (pi/4) a^2 b; the sphere's m_a = rho V / 2. Raised 0.1 m (above
    # their half-heights of 0.02 and 0.03 m) they are dry: no water force, no force on their bodies, and no added
    # mass left over from the wet substep.
    m, d, f = two_soles(0.5)
    mjw.step(m, d)
    plate = 0.757 * RHO * math.pi / 4 * 0.1**2 * 0.2
    ball = RHO * 4 / 3 * math.pi * 0.03**3 / 2
    np.testing.assert_allclose(d.M.numpy()[0], [1.0 + plate / 2, 1.0 + ball / 2], rtol=1e-4)
    assign(d.qpos, [[0.1, 0.1]])
    mjw.step(m, d)
    assert np.all(f.foot_water_force.numpy() == 0.0)
    np.testing.assert_allclose(d.M.numpy()[0], [1.0, 1.0], rtol=1e-6)
    assert np.all(d.xfrc_applied.numpy() == 0.0)


@pytest.mark.filterwarnings(DIAGONAL_M)
def test_foot_drag_never_adds_energy_under_random_motions():
    # Drag is dissipative: the power of the water force on a foot, F . v(p) for a force F acting at p (here read back
    # as the spatial force on the body: F . v_com + tau . omega), is never positive. Gravity off (no buoyancy),
    # still water (no flow inertia) and the paper's added mass (none on the feet): the feet's water force is their
    # drag alone. A box sole 0.2 x 0.1 x 0.04 m and a sphere sole (r 3 cm) cut by the surface at random depths and
    # tilts, moving and spinning at random (a sole whose wetted part, 1 cm below its centre at half depth, moves
    # against its centre when it spins at 20 rad/s).
    n = 64
    mjm = model('<body name="box" pos="0 0 0.5"><freejoint/><geom name="box" type="box" size=".1 .05 .02" mass="1"/>'
                '</body><body name="ball" pos="1 0 0.5"><freejoint/><geom name="ball" type="sphere" size=".03" '
                'mass="1"/></body>')
    cfg = type("C", (Cfg,), {"leg_geom_names": [], "foot_geom_names": ["box", "ball"], "paper_added_mass": True})
    m, d, f = make(mjm, water(surface=0.5), cfg, nworld=n)
    m.callback.passive = None
    rng = np.random.default_rng(7)
    qpos = np.tile(mjm.qpos0, (n, 1))
    qvel = np.zeros((n, mjm.nv))
    for b in range(2):
        qpos[:, 7 * b + 2] += rng.uniform(-0.03, 0.03, n)
        quat = np.c_[np.ones(n), rng.normal(0, 0.15, (n, 3))]
        qpos[:, 7 * b + 3:7 * b + 7] = quat / np.linalg.norm(quat, axis=1, keepdims=True)
        qvel[:, 6 * b:6 * b + 3] = rng.normal(0, 0.2, (n, 3))
        qvel[:, 6 * b + 3:6 * b + 6] = rng.normal(0, 20.0, (n, 3))
    assign(d.qpos, qpos)
    assign(d.qvel, qvel)
    mjw.forward(m, d)
    f.passive(m, d)
    xfrc = d.xfrc_applied.numpy()
    md = mujoco.MjData(mjm)
    jp, jr = np.zeros((3, mjm.nv)), np.zeros((3, mjm.nv))
    power = np.zeros((n, 2))
    for w in range(n):
        md.qpos[:], md.qvel[:] = qpos[w], qvel[w]
        mujoco.mj_forward(mjm, md)
        for b in (1, 2):
            mujoco.mj_jac(mjm, md, jp, jr, md.xipos[b], b)
            power[w, b - 1] = xfrc[w, b, :3] @ (jp @ md.qvel) + xfrc[w, b, 3:] @ (jr @ md.qvel)
    assert np.count_nonzero(np.abs(xfrc).sum(-1)) > n  # most feet are wet
    assert np.all(power <= 1e-9), power.max()


# ----------------------------------------------------------------------------- kernels vs numpy references


def test_water_kernels_match_references():
    """Free base, thigh (capsule) and shank (cylinder) on hinges, a box and a sphere foot, in a tide over a water
    surface with a step: forces and torques per body and the mass-matrix addition against water_models with
    MuJoCo's own Jacobians (mj_jac, mj_jacDot)."""
    mjm = model(
        '<body name="base" pos="0 0 0.6"><freejoint/><geom type="box" size=".1 .1 .05" mass="5"/>'
        '<body name="thigh" pos="0 0 -0.05"><joint type="hinge" axis="0 1 0"/><joint type="hinge" axis="1 0 0"/>'
        '<geom name="thigh" type="capsule" fromto="0 0 0 0.05 0 -0.2" size="0.04" mass="2"/>'
        '<body name="shank" pos="0.05 0 -0.2"><joint type="hinge" axis="0 1 0"/>'
        '<geom name="shank" type="cylinder" fromto="0 0 0 -0.03 0.02 -0.2" size="0.03" mass="1"/>'
        '<geom name="ball" type="sphere" pos="-0.03 0.02 -0.22" size="0.025" mass="0.2"/>'
        '<geom name="sole" type="box" pos="0 0 -0.24" euler="10 5 20" size=".06 .03 .015" mass="0.2"/>'
        '</body></body></body>', gravity=True)
    mat = water(kind=FLOW_TIDE, speed=0.5, direction=0.7, omega=1.5, phase=0.3)
    mat.water_surface[:] = 0.45
    mat.water_surface[20:] = 0.3  # x >= 0: a step in the surface under the leg
    cfg = type("C", (Cfg,), {"leg_geom_names": ["thigh", "shank"], "foot_geom_names": ["ball", "sole"]})
    nworld = 6
    rng = np.random.default_rng(3)
    qpos = np.tile(mjm.qpos0, (nworld, 1))
    qpos[:, 2] += rng.uniform(-0.4, 0.1, nworld)
    qpos[:, 3:7] = [np.r_[1.0, rng.normal(0, 0.2, 3)] for _ in range(nworld)]
    qpos[:, 3:7] /= np.linalg.norm(qpos[:, 3:7], axis=1, keepdims=True)
    qpos[:, 7:] = rng.uniform(-0.8, 0.8, (nworld, 3))
    qvel = rng.normal(0, 1.0, (nworld, mjm.nv))
    times = rng.uniform(0, 3, nworld)
    m, d, f = make(mjm, mat, cfg, nworld=nworld)
    m.callback.passive = None
    assign(d.qpos, qpos)
    assign(d.qvel, qvel)
    assign(d.time, times)
    mjw.forward(m, d)
    m0 = d.M.numpy().copy()
    f.passive(m, d)
    dm, xfrc = d.M.numpy() - m0, d.xfrc_applied.numpy()

    md = mujoco.MjData(mjm)
    surface = mat.water_surface

    def surface_at(p):
        i = int(np.clip(np.round((p[0] - ORIGIN[0]) / RES), 0, SHAPE[0] - 1))
        j = int(np.clip(np.round((p[1] - ORIGIN[1]) / RES), 0, SHAPE[1] - 1))
        return float(surface[i, j])

    for w in range(nworld):
        md.qpos[:], md.qvel[:], md.time = qpos[w], qvel[w], times[w]
        mujoco.mj_forward(mjm, md)
        t = times[w]
        direction = np.array([math.cos(0.7), math.sin(0.7), 0.0])
        flow_at = lambda p: 0.5 * math.cos(1.5 * t + 0.3) * direction  # noqa: E731
        flow_accel_at = lambda p: -0.5 * 1.5 * math.sin(1.5 * t + 0.3) * direction  # noqa: E731
        ref_x, ref_m = np.zeros((mjm.nbody, 6)), np.zeros((mjm.nv, mjm.nv))
        for name in ("thigh", "shank", "ball", "sole"):
            g = mjm.geom(name)
            b = int(g.bodyid[0])
            jp, jd = np.zeros((3, mjm.nv)), np.zeros((3, mjm.nv))

            def jac(p, b=b, jp=jp):
                mujoco.mj_jac(mjm, md, jp, None, p, b)
                return jp.copy()

            def jacdot(p, b=b, jd=jd):
                mujoco.mj_jacDot(mjm, md, jd, None, p, b)
                return jd.copy()

            c, rot = md.geom_xpos[g.id].copy(), md.geom_xmat[g.id].reshape(3, 3)
            if name in ("thigh", "shank"):
                axis = rot[:, 2]
                loads, masses = WM.segment_loads(
                    c, axis, g.size[0], g.size[1], name == "thigh", surface_at, lambda p: jac(p) @ md.qvel,
                    lambda p: jacdot(p) @ md.qvel, flow_at, flow_accel_at, rho=RHO, cd=CD, ca=1.0, g=G)
                for p, mk in masses:
                    jk = jac(p)
                    pj = jk - np.outer(axis, axis @ jk)
                    ref_m += mk * jk.T @ pj
            else:
                # the drag at the middle of the wetted part, with that point's velocity
                z_w = surface_at(c)
                if name == "ball":
                    r = g.size[0]
                    vol = WM.sphere_cap_volume(r, z_w - (c[2] - r))
                    frac = vol / (4 / 3 * math.pi * r**3)
                    p = c
                    fr = WM.sphere_drag(RHO, 0.47, r, z_w - (c[2] - r), jac(p) @ md.qvel - flow_at(c))
                else:
                    vol = WM.box_submerged_volume(g.size, rot, c[2], z_w)
                    frac = vol / (8 * np.prod(g.size))
                    e_z = float(np.abs(rot[2]) @ g.size)
                    p = c - np.array([0, 0, e_z * (1 - frac)])
                    fr = WM.plate_drag(RHO, 1.17, g.size, rot, z_w - (c[2] - e_z), jac(p) @ md.qvel - flow_at(c))
                # the wet fraction of the foot's added mass tensor, along its geom's axes
                added = frac * rot @ np.diag(WM.foot_added_mass("sphere" if name == "ball" else "box", g.size,
                                                                RHO)) @ rot.T
                fr = fr + WM.foot_inertia_force(RHO, vol, added, flow_accel_at(c), jacdot(p) @ md.qvel)
                loads = [(p, fr + np.array([0, 0, RHO * G * vol]))] if vol > 0 else []
                if vol > 0:
                    ref_m += jac(p).T @ added @ jac(p)
            for p, fk in loads:
                ref_x[b, :3] += fk
                ref_x[b, 3:] += np.cross(p - md.xipos[b], fk)
        scale = np.abs(ref_x).max()
        assert scale > 1.0  # the worlds are wet
        np.testing.assert_allclose(xfrc[w], ref_x, atol=2e-4 * scale)
        dense = np.zeros((mjm.nv, mjm.nv))
        mujoco.mju_sym2dense(dense, dm[w].astype(np.float64), mjm.M_rownnz, mjm.M_rowadr, mjm.M_colind)
        np.testing.assert_allclose(dense, ref_m, atol=2e-4 * max(np.abs(ref_m).max(), 1e-3))


@wp.kernel
def _eval_water(x: wp.array2d[float], out: wp.array2d[float]):
    i = wp.tid()
    r = x[i, 0]
    v = wp.vec3(x[i, 6], x[i, 7], x[i, 8])
    a = wp.normalize(wp.vec3(x[i, 9], x[i, 10], x[i, 11]))
    half = wp.vec3(x[i, 12], x[i, 13], x[i, 14])
    rot = wp.quat_to_matrix(wp.normalize(wp.quat(x[i, 16], x[i, 17], x[i, 18], x[i, 15])))  # (w, x, y, z) in x
    out[i, 0] = W.circle_wet_area_fn(r, x[i, 1])
    out[i, 1] = W.cylinder_slice_volume_fn(r, x[i, 2], x[i, 3], x[i, 4], x[i, 5], 0.1)
    out[i, 2] = W.sphere_cap_volume_fn(r, x[i, 1] + r)
    d = W.crossflow_drag_fn(1000.0, 1.1, r, 1.0e-3, v, a, 0)
    fi = W.inertia_force_fn(1000.0, 1.0, 1.0e-3, v, a)
    pd = W.plate_drag_fn(1000.0, 1.17, half, rot, x[i, 1] + r, v)
    sd = W.sphere_drag_fn(1000.0, 0.47, r, x[i, 1] + r, v)
    for k in range(3):
        out[i, 3 + k] = d[k]
        out[i, 6 + k] = fi[k]
        out[i, 9 + k] = pd[k]
        out[i, 12 + k] = sd[k]


def test_water_functions_match_references():
    rng = np.random.default_rng(0)
    n = 300
    u = lambda lo, hi: rng.uniform(lo, hi, n)  # noqa: E731
    x = np.stack([u(0.01, 0.06), u(-0.08, 0.08), u(0.0, 1.0), u(-0.2, 0.2), u(-0.2, 0.2), u(-0.1, 0.1),
                  *[u(-1, 1) for _ in range(6)], u(0.01, 0.1), u(0.01, 0.1), u(0.01, 0.1),
                  *[u(-1, 1) for _ in range(4)]], 1).astype(np.float32)
    x[:30, 2] = 0.0  # vertical slices
    x[30:60, 4] = x[30:60, 3] + 1e-3  # nearly level slices
    out = wp.zeros((n, 15), dtype=float, device=DEV)
    wp.launch(_eval_water, dim=n, inputs=[wp.array(x, dtype=float, device=DEV), out], device=DEV)
    got = out.numpy()
    x = x.astype(np.float64)
    ref = []
    for row in x:
        r, v, a = row[0], row[6:9], row[9:12] / np.linalg.norm(row[9:12])
        q = row[15:19] / np.linalg.norm(row[15:19])
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, q)
        rot = rot.reshape(3, 3)
        ref.append(np.r_[WM.circle_wet_area(r, row[1]),
                         WM.cylinder_slice_volume(r, row[2], row[3], row[4], row[5], 0.1),
                         WM.sphere_cap_volume(r, row[1] + r), WM.crossflow_drag(1000.0, 1.1, r, 1e-3, v, a),
                         WM.inertia_force(1000.0, 1.0, 1e-3, v, a), WM.plate_drag(1000.0, 1.17, row[12:15], rot,
                                                                                  row[1] + r, v),
                         WM.sphere_drag(1000.0, 0.47, r, row[1] + r, v)])
    ref = np.asarray(ref)
    scale = np.abs(ref).max(0) + 1e-12
    err = (np.abs(got - ref) / scale).max(0)
    assert np.all(err < 2e-4), err


def test_water_references_textbook_values():
    r = 0.05
    # added mass: a sphere's is half its displaced mass; a square plate's C_A is 0.579 (DNV-RP-C205); a long strip
    # of width a tends to rho pi (a/2)^2 per length
    assert WM.foot_added_mass("sphere", [r], RHO) == pytest.approx(np.full(3, 0.5 * RHO * 4 / 3 * math.pi * r**3))
    assert WM.plate_added_mass(RHO, 0.1, 0.1) == pytest.approx(0.579 * RHO * math.pi / 4 * 0.1**3)
    assert WM.plate_added_mass(RHO, 0.01, 2.0) == pytest.approx(RHO * math.pi * 0.005**2 * 2.0, rel=0.01)
    # a box 0.2 x 0.1 x 0.1 along x moves its 0.1 x 0.1 face pair (a square plate)
    assert WM.foot_added_mass("box", [0.1, 0.05, 0.05], RHO)[0] == pytest.approx(WM.plate_added_mass(RHO, 0.1, 0.1))
    # a chord through the centre halves the circle; a sphere wet to its centre is a hemisphere
    assert WM.circle_wet_area(r, 0.0) == pytest.approx(math.pi * r * r / 2)
    assert WM.sphere_cap_volume(r, r) == pytest.approx(2 / 3 * math.pi * r**3)
    assert WM.sphere_cap_volume(r, 3 * r) == pytest.approx(4 / 3 * math.pi * r**3)
    # a vertical slice from z = -0.1 to 0.1 under a surface at 0.02: pi r^2 * 0.12
    assert WM.cylinder_slice_volume(r, 0.0, -0.1, 0.1, 0.02, 0.2) == pytest.approx(math.pi * r * r * 0.12)
    # tilted 45 deg with its middle at the surface: by symmetry half the slice is under water
    lv = 0.3 * math.cos(math.pi / 4)
    assert WM.cylinder_slice_volume(r, math.sin(math.pi / 4), -lv / 2, lv / 2, 0.0, 0.3) == pytest.approx(
        math.pi * r * r * 0.15)
