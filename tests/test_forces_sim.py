"""TerrainForces in tiny MuJoCo-Warp worlds on the CPU: drag, energy, floating draft, tide, sinkage, friction."""

import math
import warnings

import mujoco
import mujoco_warp as mjw
import numpy as np
import pytest
import warp as wp

from legged_gente.external_forces.field import ForcesConfig, TerrainForces
from legged_gente.terrain.materials import FLOW_CURRENT, FLOW_TIDE, NO_SOIL, MaterialMap
from legged_gente.terrain.soil import SOIL_PRESETS, register_custom_soil

wp.config.quiet = True
DEV = "cpu"
RES, ORIGIN, SHAPE = 0.1, (-2.0, -2.0), (41, 41)
R, H = 0.04, 0.15  # leg capsule radius and half-length


def world(body: str, option: str = "", ground: str = '<geom name="ground" type="plane" size="3 3 .1"/>'):
    xml = f"""<mujoco><option timestep="0.005" {option}/><worldbody>{ground}{body}</worldbody></mujoco>"""
    return mujoco.MjModel.from_xml_string(xml)


def leg(joints: str, z: float, density: float = 3000.0, damping: float = 0.0) -> str:
    js = "".join(f'<joint name="{a}" type="slide" axis="{v}" damping="{damping}"/>'
                 for a, v in zip(joints, ["1 0 0", "0 1 0", "0 0 1"]) if a != "-")
    return (f'<body name="leg" pos="0 0 {z}">{js}<geom name="shin" type="capsule" size="{R} {H}" '
            f'density="{density}" contype="0" conaffinity="0"/></body>')


class Cfg(ForcesConfig):
    noise_std = 0.0
    drag_coefficient = 1.1
    leg_geom_names = ["shin"]
    foot_geom_names: list = []


def water_map(surface=0.5, kind=0, speed=0.0, direction=0.0, omega=0.0, phase=0.0):
    mat = MaterialMap.rigid(SHAPE)
    mat.water_surface[:] = surface
    mat.flow_kind[:] = kind
    mat.flow_speed[:] = speed
    mat.flow_direction[:] = direction
    mat.flow_omega[:] = omega
    mat.flow_phase[:] = phase
    return mat


def make(mjm, mat, cfg, nworld=2, install=True):
    m = mjw.put_model(mjm)
    d = mjw.make_data(mjm, nworld=nworld, nconmax=16, njmax=64)
    f = TerrainForces(mjm, m, d, np.zeros(SHAPE, np.float32), ORIGIN, RES, mat, cfg, seed=1)
    if install:
        f.install()
    return m, d, f


def set_qvel(d, qvel):
    d.qvel.assign(wp.array(np.asarray(qvel, np.float32), dtype=float, device=DEV))


def test_constant_speed_drag_matches_reference():
    wp.set_device(DEV)
    mjm = world(leg("x", z=0.3), option='gravity="0 0 0"')
    m, d, f = make(mjm, water_map(surface=0.3), Cfg())
    speeds = np.array([[0.5], [-1.2]])
    for _ in range(3):
        set_qvel(d, speeds)
        mjw.step(m, d)
    lsub = H  # surface at the capsule centre: the lower half of its cylinder part is wet (caps: buoyancy only)
    ref = 0.5 * 1000.0 * Cfg.drag_coefficient * (2 * R * lsub) * speeds[:, 0] ** 2  # Morison: 0.5 rho cd D L v^2
    fx = f.seg_force.numpy()[:, 0, 0]
    np.testing.assert_allclose(fx, -np.sign(speeds[:, 0]) * ref, rtol=1e-4)
    # xfrc_applied of the leg body holds the force and its torque about the body's CoM
    xfrc = d.xfrc_applied.numpy()[:, 1]
    np.testing.assert_allclose(xfrc[:, 0], fx, rtol=1e-5)
    assert np.allclose(xfrc[:, 2], 0.0, atol=1e-6)  # gravity off -> no buoyancy
    dz = -0.5 * lsub  # the submerged centroid lies below the CoM: torque (0, 0, dz) x (fx, 0, 0)
    np.testing.assert_allclose(xfrc[:, 4], dz * fx, rtol=1e-4)


def test_drag_never_adds_energy_in_flow_frame():
    wp.set_device(DEV)
    mjm = world(leg("xyz", z=0.3), option='gravity="0 0 0"')
    cfg = type("C", (Cfg,), {"vertical_drag": True, "paper_added_mass": True})
    u = 0.7 * np.array([np.cos(0.6), np.sin(0.6), 0.0])
    m, d, f = make(mjm, water_map(surface=0.35, kind=FLOW_CURRENT, speed=0.7, direction=0.6), cfg(), nworld=4)
    rng = np.random.default_rng(0)
    for _ in range(3):
        v = rng.normal(0, 1.0, (4, 3))
        set_qvel(d, v)
        mjw.step(m, d)
        drag = f.seg_force.numpy()[:, 0]  # g = 0: no buoyancy, the paper's m_eff adds no weight
        power = np.sum(drag * (v - u), axis=1)
        assert np.all(power <= 1e-9), power
        assert np.all(np.abs(drag).sum(1) > 0)


def test_floating_capsule_settles_at_analytic_draft():
    wp.set_device(DEV)
    rho_body = 500.0
    mjm = world(leg("--z", z=0.45, density=rho_body, damping=20.0))
    m, d, f = make(mjm, water_map(surface=0.5), Cfg(), nworld=2)  # 500 kg/m^3: lighter than its added mass
    for _ in range(300):
        mjw.step(m, d)
    mass = mjm.body_mass[1]
    # buoyancy = weight: the bottom hemisphere (2/3 pi r^3) and x of the cylinder under water, draft = r + x
    draft = R + (mass / 1000.0 - 2 / 3 * np.pi * R**3) / (np.pi * R**2)
    bottom = 0.45 + d.qpos.numpy()[:, 0] - H - R
    np.testing.assert_allclose(0.5 - bottom, draft, rtol=0.02)


def test_tide_follows_cos_morison_and_paper_flow_term():
    wp.set_device(DEV)
    mjm = world(leg("x", z=0.3), option='gravity="0 0 0"')
    amp, omega, phase = 0.8, 2.0, 0.4
    cfg = type("C", (Cfg,), {"paper_flow_force": True})
    m, d, f = make(mjm, water_map(surface=1.0, kind=FLOW_TIDE, speed=amp, omega=omega, phase=phase), cfg())
    L = 2 * H  # the cylinder part (the caps get buoyancy only)
    for _ in range(20):
        set_qvel(d, np.zeros((2, 1)))
        t = d.time.numpy()[0]
        mjw.step(m, d)
        u = amp * np.cos(omega * t + phase)
        du = -amp * omega * np.sin(omega * t + phase)
        # Morison on a fixed cylinder: drag 0.5 rho cd (2 R L) |u| u, inertia Froude-Krylov rho V du/dt plus added
        # mass ca rho V du/dt (cm = 1 + ca = 2)
        morison = 0.5 * 1000.0 * cfg.drag_coefficient * 2 * R * L * abs(u) * u + 2.0 * 1000.0 * np.pi * R**2 * L * du
        np.testing.assert_allclose(f.seg_force.numpy()[:, 0, 0], morison + u, rtol=1e-3, atol=1e-4)
    f.after_substep()  # no feet: nothing to do, must not fail
    f.observe()


def test_paper_flow_term_acts_whole_on_a_partly_wet_segment():
    """GenTe's flow term (a current's A = 0.5 N) is added whole to each wet segment, however deep it is wet: the
    leg's x force with the option minus without it is 0.5 N with half the leg and a sixth of it under water."""
    wp.set_device(DEV)
    mjm = world(leg("x", z=1.0), option='gravity="0 0 0"')
    on = type("C", (Cfg,), {"paper_flow_force": True})
    for surface in (1.0, 1.0 - H / 1.5):  # the centre (half the cylinder wet), a sixth of it wet
        force = []
        for cfg in (Cfg, on):
            m, d, f = make(mjm, water_map(surface=surface, kind=FLOW_CURRENT, speed=0.5), cfg())
            mjw.step(m, d)
            force.append(f.seg_force.numpy()[:, 0, 0])
        np.testing.assert_allclose(force[1] - force[0], 0.5, rtol=1e-4)


def test_foot_ball_in_the_legs_end_cap_is_not_buoyed_twice():
    """A calf capsule (r 2 cm, 0.2 m between its cap centres) whose lower cap holds a foot sphere of the same radius,
    both under water: Archimedes on their union, the capsule, rho g (pi r^2 0.2 + 4/3 pi r^3) = 2.794 N. The foot
    keeps its own drag."""
    wp.set_device(DEV)
    r = 0.02
    mjm = world('<body name="calf" pos="0 0 1"><joint type="slide" axis="1 0 0"/>'
                f'<geom name="calf" type="capsule" size="{r}" fromto="0 0 0 0 0 -0.2" mass="0.25" contype="0" '
                'conaffinity="0"/><body name="foot" pos="0 0 -0.2"><geom name="ball" type="sphere" '
                f'size="{r}" mass="0.05" contype="0" conaffinity="0"/></body></body>')
    cfg = type("C", (Cfg,), {"leg_geom_names": ["calf"], "foot_geom_names": ["ball"], "soil": False,
                             "friction_from_map": False, "sole_contact": False})
    m, d, f = make(mjm, water_map(surface=3.0), cfg(), nworld=1)
    mjw.step(m, d)
    lift = f.seg_force.numpy()[0, 0, 2] + f.foot_water_force.numpy()[0, 0, 2]
    exact = 1000.0 * 9.81 * (np.pi * r * r * 0.2 + 4.0 / 3.0 * np.pi * r**3)
    assert abs(exact - 2.794) < 5e-4
    np.testing.assert_allclose(lift, exact, rtol=1e-4)
    set_qvel(d, [[0.5]])
    mjw.step(m, d)
    assert f.foot_water_force.numpy()[0, 0, 0] < 0.0  # the ball's drag against its motion


def test_flags_off_exactly_zero_and_dry_is_zero():
    wp.set_device(DEV)
    mjm = world(leg("xz", z=0.3))
    off = type("C", (Cfg,), {"wading": False, "soil": False, "friction_from_map": False})
    m, d, f = make(mjm, water_map(surface=1.0, kind=FLOW_CURRENT, speed=1.0), off())
    m2, d2, _ = make(mjm, water_map(surface=-1.0), Cfg())  # wading on, but the surface is below the leg
    m3 = mjw.put_model(mjm)
    d3 = mjw.make_data(mjm, nworld=2, nconmax=16, njmax=64)
    for _ in range(5):
        for mm, dd in ((m, d), (m2, d2), (m3, d3)):
            set_qvel(dd, [[0.3, -0.2], [-0.5, 0.1]])
            mjw.step(mm, dd)
    assert not np.any(d.xfrc_applied.numpy()) and not np.any(d2.xfrc_applied.numpy())
    np.testing.assert_array_equal(d.qpos.numpy(), d3.qpos.numpy())
    np.testing.assert_array_equal(d2.qpos.numpy(), d3.qpos.numpy())


def test_reset_draws_noise_per_env_and_keeps_it():
    wp.set_device(DEV)
    mjm = world(leg("x", z=0.3))
    cfg = type("C", (Cfg,), {"noise_std": 0.1})
    m, d, f = make(mjm, water_map(), cfg(), nworld=64)
    eps0 = f.eps.numpy().copy()
    assert abs(eps0.mean() - 1) < 0.05 and 0.05 < eps0.std() < 0.15
    mask = np.zeros(64, bool)
    mask[:10] = True
    f.reset(wp.array(mask, dtype=bool, device=DEV))
    eps1 = f.eps.numpy()
    assert np.all(eps1[10:] == eps0[10:]) and np.all(eps1[:10] != eps0[:10])
    xi0 = f.xi.numpy().copy()
    f.new_policy_step()
    assert np.all(f.xi.numpy() != xi0)


def feet_world(masses=(5.0, 20.0), xs=(-0.5, 0.5)):
    bodies = "".join(
        f'<body name="b{i}" pos="{x} 0 0.02"><joint type="slide" axis="0 0 1" damping="200"/>'
        f'<geom name="foot{i}" type="box" size=".05 .05 .02" mass="{mass}"/></body>'
        for i, (mass, x) in enumerate(zip(masses, xs)))
    return world(bodies)


class SoilCfg(ForcesConfig):
    noise_std = 0.0
    wading = False
    foot_geom_names = ["foot0", "foot1"]


def settle(mat, nworld=2, steps=150):
    mjm = feet_world()
    m, d, f = make(mjm, mat, SoilCfg(), nworld=nworld)
    for _ in range(steps):
        mjw.step(m, d)
        f.after_substep()
    f.observe()
    return mjm, d, f


def test_sinkage_grows_with_load_as_bekker_in_sim():
    wp.set_device(DEV)
    sand = MaterialMap.rigid(SHAPE)
    sand.soil[:] = 0
    sand.soil_presets = ["dry_sand"]
    mjm, d, f = settle(sand)
    _, d_rigid, _ = settle(MaterialMap.rigid(SHAPE))
    fn = f.foot_fn.numpy()
    weight = mjm.body_mass[1:3] * 9.81
    np.testing.assert_allclose(fn, np.broadcast_to(weight, fn.shape), rtol=0.02)
    # this world's draws of Wong's dry sand (kc 0.99 kN/m^2.1, kphi 1528.43 kN/m^3.1, n 1.1; std 20 %, 15 %, 5 %, see
    # test_soil_parameters_are_drawn_per_env_from_the_table_values): within 4 std of the table row
    kc, kphi, n = (f.soil_params.numpy()[:, 0, q][:, None].astype(np.float64) for q in range(3))
    for value, mean, std in ((kc, 0.99e3, 0.2), (kphi, 1528.43e3, 0.15), (n, 1.1, 0.05)):
        assert np.all(np.abs(value / mean - 1.0) < 4 * std), (value, mean)
    z_ref = (weight / 0.01 / (kc / 0.1 + kphi)) ** (1 / n)  # Bekker, sole 0.1 m x 0.1 m: p = W / A, b = 0.1 m
    z = f.foot_sinkage.numpy()
    # the rut keeps the deepest sinkage of the stance: the landing transient may add a little (plastic soil)
    assert np.all(z >= 0.995 * z_ref) and np.all(z <= 1.15 * z_ref), (z, z_ref)
    assert np.all(z[:, 1] > z[:, 0]) and np.all(z[:, 0] > 0.003)  # the heavier foot sinks deeper
    # the foot really sits lower than on rigid ground by the sinkage, shown down to max_rut_depth only
    assert z.max() > SoilCfg.max_rut_depth > z.min()  # both cases occur
    lowered = d_rigid.qpos.numpy() - d.qpos.numpy()
    np.testing.assert_allclose(lowered, np.minimum(z, SoilCfg.max_rut_depth), rtol=0.05)
    obs = f.privileged_obs().numpy().reshape(2, 2, -1)
    assert np.all(obs[..., 3] == 1.0) and np.allclose(obs[..., 4], z)


def test_soil_parameters_are_drawn_per_env_from_the_table_values(custom_soil):
    """Each env draws each soil parameter from N(mean, std) of its preset, truncated below at 10 % of the mean. Dry
    sand is Wong's Table 2.3 row (kc 0.99 kN/m^2.1, kphi 1528.43 kN/m^3.1, n 1.1, c 1.04 kPa, phi 28 deg) with the
    scatter the presets give (std 20 % kc, 15 % kphi, 5 % n, 15 % c, 10 % tan phi, 20 % K = 2.5 cm) and Bekker's
    bulldozing coefficients 0.67 c K_pc = 0.67 * 1040 * 19.70 = 13.7 kN/m^2 and 0.5 gamma K_pgamma = 0.5 * 15.7e3 *
    33.6 = 264 kN/m^3 (test_bulldozing_coefficients_by_hand). A soil whose kphi std equals its mean has Phi(-0.9)
    = 18.4 % of its draws below 10 % of the mean: those are exactly 0.1 mean."""
    wp.set_device(DEV)
    custom_soil("wide_t", kc=0.0, kphi=(1.0e6, 1.0e6), n=1.0, c=0.0, mu=0.5, K=0.02, bulldoze_c=0.0, bulldoze_g=0.0)
    mat = MaterialMap.rigid(SHAPE)
    mat.soil[:] = 0
    mat.soil_presets = ["dry_sand", "wide_t"]
    n = 4000
    _, _, f = make(world(leg("x", z=0.3)), mat, Cfg(), nworld=n, install=False)
    draws = f.soil_params.numpy().astype(np.float64)
    assert draws.shape == (n, 2, 10)
    tan28 = np.tan(np.radians(28.0))
    #               kc      kphi       n    c       mu     K      bulldoze_c          bulldoze_g
    means = np.array([0.99e3, 1528.43e3, 1.1, 1.04e3, tan28, 0.025, 0.67 * 1.04e3 * 19.70, 0.5 * 15.7e3 * 33.6])
    stds = means * np.array([0.2, 0.15, 0.05, 0.15, 0.1, 0.2, 0.2, 0.2])
    sand = draws[:, 0, :8]
    # sample mean within 4 standard errors (sd / sqrt(n)); the bulldozing values are the hand ones to 1 %
    tol = 4 * stds / np.sqrt(n) + np.r_[np.zeros(6), 0.01 * means[6:]]
    np.testing.assert_array_less(np.abs(sand.mean(0) - means), tol)
    np.testing.assert_allclose(sand.std(0), stds, rtol=0.1)
    assert np.all(draws[:, 0, 8:] == 0.0)  # zeta 0 and model 0 (Bekker)
    assert len(np.unique(sand[:, 0])) > n // 2  # one draw per env, not one for all
    kphi = draws[:, 1, 1]
    assert kphi.min() == pytest.approx(0.1e6, rel=1e-6)
    floor = np.mean(np.isclose(kphi, 0.1e6, rtol=1e-6))
    assert floor == pytest.approx(0.5 * math.erfc(0.9 / math.sqrt(2.0)), abs=4 * math.sqrt(0.184 * 0.816 / n))
    assert np.all(draws[:, 1, [0, 2, 3, 4, 5]] == np.float32([0.0, 1.0, 0.0, 0.5, 0.02]))  # std 0: the mean


def test_bulldozing_opposes_motion():
    wp.set_device(DEV)
    mud = MaterialMap.rigid(SHAPE)
    mud.soil[:] = 0
    mud.soil_presets = ["mud"]
    mjm = world("".join(
        f'<body name="b{i}" pos="{x} 0 0.02"><joint type="slide" axis="1 0 0"/><joint type="slide" axis="0 0 1" '
        f'damping="200"/><geom name="foot{i}" type="box" size=".05 .05 .02" mass="{mass}"/></body>'
        for i, (mass, x) in enumerate(zip((5.0, 20.0), (-0.5, 0.5)))))
    m, d, f = make(mjm, mud, SoilCfg())
    for _ in range(60):
        mjw.step(m, d)
        f.after_substep()
    q = d.qvel.numpy()
    q[:, [0, 2]] = 0.3  # both feet along +x
    set_qvel(d, q)
    mjw.step(m, d)
    force = f.foot_force.numpy()
    assert np.all(force[..., 0] < 0) and np.allclose(force[..., 1:], 0.0)  # against +x, horizontal


def test_soil_off_and_rigid_cells_feel_no_soil_force():
    wp.set_device(DEV)
    mat = MaterialMap.rigid(SHAPE)
    mat.soil[:] = NO_SOIL
    mjm, d, f = settle(mat, steps=30)
    assert not np.any(f.foot_sinkage.numpy()) and not np.any(d.xfrc_applied.numpy())


def test_ice_cell_lowers_sliding_friction():
    wp.set_device(DEV)
    mjm = world('<body name="box" pos="0 0 0.05"><joint name="x" type="slide" axis="1 0 0"/>'
                '<joint name="z" type="slide" axis="0 0 1"/><geom type="box" size=".05 .05 .05" mass="1"/></body>')
    mat = MaterialMap.rigid(SHAPE)
    mat.friction[20:, :] = 0.05  # x >= 0: ice
    cfg = type("C", (SoilCfg,), {"soil": False, "foot_geom_names": []})
    m, d, f = make(mjm, mat, cfg())
    d.qpos.assign(np.array([[-1.0, 0.0], [0.2, 0.0]], np.float32))
    set_qvel(d, [[1.0, 0.0], [1.0, 0.0]])
    for _ in range(100):
        mjw.step(m, d)
    travel, v = d.qpos.numpy()[:, 0] - np.array([-1.0, 0.2]), d.qvel.numpy()[:, 0]
    # Coulomb sliding decelerates at mu g. mu = 1: stops after v0^2 / (2 mu g) = 1 / 19.62 = 5.1 cm. Ice, mu = 0.05:
    # still sliding after t = 0.5 s at v0 - mu g t = 1 - 0.245 = 0.755 m/s, having gone v0 t - mu g t^2 / 2 = 0.439 m
    # (the bound tells mu = 0.05 from 0.1, which would leave 0.377 m and 0.51 m/s)
    assert travel[0] == pytest.approx(1.0 / (2 * 1.0 * 9.81), abs=0.003) and abs(v[0]) < 1e-3
    assert travel[1] == pytest.approx(0.5 - 0.5 * 0.05 * 9.81 * 0.25, abs=0.005)
    assert v[1] == pytest.approx(1.0 - 0.05 * 9.81 * 0.5, abs=0.005)


def test_benchmark_reports_a_share():
    from legged_gente.external_forces.benchmark import demo_scene, forces_share

    m, d, forces = demo_scene(2, DEV)
    r = forces_share(m, d, forces, steps=3, warmup=1)
    assert 0.0 <= r["forces_share"] < 1.0 and r["step_with_forces_s"] > 0
    assert m.callback.passive is not None  # left installed
    assert np.any(d.xfrc_applied.numpy())  # the demo's legs stand in water / on sand: forces act


@pytest.fixture
def custom_soil():
    """register_custom_soil for one test: the soils leave SOIL_PRESETS when it ends."""
    names = []

    def register(name, **params):
        names.append(name)
        return register_custom_soil(name, **params)

    yield register
    for name in names:
        SOIL_PRESETS.pop(name)


def test_bulldozing_width_is_the_sole_face_across_the_motion(custom_soil):
    """Bekker's bulldozing R = b (..) takes b as the width of soil the sole pushes: a 0.2 m x 0.1 m sole moved along
    its length pushes 0.1 m, moved sideways 0.2 m, moved at 45 deg 0.2 sin 45 + 0.1 cos 45 = 0.2121 m. The three
    worlds sink alike (a soil without scatter), so the forces stand in the ratio of those widths."""
    wp.set_device(DEV)
    custom_soil("even_mud", kc=0.0, kphi=1.0e6, n=1.0, c=2.0e3, mu=0.2, K=0.02, bulldoze_c=5.0e4,
                         bulldoze_g=1.0e5)
    mud = MaterialMap.rigid(SHAPE)
    mud.soil[:] = 0
    mud.soil_presets = ["even_mud"]
    mjm = world('<body name="b0" pos="0 0 0.02"><joint type="slide" axis="1 0 0"/><joint type="slide" axis="0 1 0"/>'
                '<joint type="slide" axis="0 0 1" damping="200"/><geom name="foot0" type="box" size=".1 .05 .02" '
                'mass="20"/></body>')
    cfg = type("C", (SoilCfg,), {"foot_geom_names": ["foot0"]})
    m, d, f = make(mjm, mud, cfg(), nworld=3)
    for _ in range(100):
        mjw.step(m, d)
        f.after_substep()
    q = d.qvel.numpy()
    q[:] = 0.0
    q[0, 0] = 0.3  # along the sole's length
    q[1, 1] = 0.3  # across it
    q[2, 0] = q[2, 1] = 0.3 / np.sqrt(2.0)  # at 45 deg
    set_qvel(d, q)
    mjw.step(m, d)
    assert np.ptp(f.foot_sinkage.numpy()[:, 0]) < 1e-7
    force = np.linalg.norm(f.foot_force.numpy()[:, 0], axis=-1)
    assert force[0] > 1.0
    np.testing.assert_allclose(force[1:] / force[0], [2.0, (0.2 + 0.1) / np.sqrt(2.0) / 0.1], rtol=1e-4)


def test_sphere_sole_sinks_as_a_circular_plate(custom_soil):
    """A sphere sole's footprint is a disc: Bekker's pressure over pi r^2 and his b the plate's radius (Wong, Theory
    of Ground Vehicles, sec. 2.4: b is the smaller side of a rectangular plate, the radius of a circular one). Dry
    sand of Wong's Table 2.3: n 1.1, kc 0.99 kN/m^(n+1), kphi 1528.43 kN/m^(n+2). A 3 kg foot of radius 2 cm:
    p = 3 * 9.81 / (pi 0.02^2) = 23.42 kPa, z = (p / (kc / 0.02 + kphi))^(1 / 1.1) = 2.18 cm."""
    wp.set_device(DEV)
    r, mass = 0.02, 3.0
    kc, kphi, n = 0.99e3, 1528.43e3, 1.1
    custom_soil("wong_dry_sand", kc=kc, kphi=kphi, n=n, c=1.04e3, mu=np.tan(np.radians(28.0)), K=0.025,
                         bulldoze_c=0.0, bulldoze_g=0.0)
    mjm = mujoco.MjModel.from_xml_string(f"""<mujoco><option timestep="0.005"/>
      <asset><hfield name="hf" nrow="{SHAPE[1]}" ncol="{SHAPE[0]}" size="2 2 1 0.1"/></asset>
      <worldbody><geom name="terrain" type="hfield" hfield="hf"/>
        <body name="foot" pos="0 0 0.025"><joint type="slide" axis="0 0 1"/>
          <geom type="box" size="0.01 0.01 0.01" pos="0 0 0.05" mass="{mass - 0.001}" contype="0" conaffinity="0"/>
          <geom name="sole" type="sphere" size="{r}" mass="0.001" contype="0" conaffinity="0"/>
        </body></worldbody></mujoco>""")
    sand = MaterialMap.rigid(SHAPE)
    sand.soil[:] = 0
    sand.soil_presets = ["wong_dry_sand"]
    cfg = type("C", (SoilCfg,), {"foot_geom_names": ["sole"], "sinkage_rate": 0.02, "sinkage_load_tau": 0.2})
    m, d, f = make(mjm, sand, cfg(), nworld=1)
    assert f.sole_area == pytest.approx(np.pi * r * r)
    for _ in range(1200):
        mjw.step(m, d)
        f.after_substep()
    p = mass * 9.81 / (np.pi * r * r)
    z_hand = (p / (kc / r + kphi)) ** (1.0 / n)
    assert abs(z_hand - 0.0218) < 5e-5
    np.testing.assert_allclose(f.foot_sinkage.numpy()[0, 0], z_hand, rtol=0.02)


def test_packed_arrays_are_disjoint_typed_views_of_one_buffer():
    """Each array a view of its own words of one int32 buffer, in the order given: 6 floats, 3 ints, 6 vec3s
    (18 words) = 27 words; writing one leaves the others, and copying the buffer back restores them all."""
    import gc
    import weakref

    from legged_gente.external_forces.field import PackedArrays

    packed = PackedArrays({"a": ((3, 2), float), "b": (3, int), "c": ((3, 2), wp.vec3)}, DEV)
    a, b, c = (packed.arrays[k] for k in "abc")
    assert packed.buffer.shape == (27,) and packed.buffer.dtype == wp.int32
    assert (a.ptr, b.ptr, c.ptr) == (packed.buffer.ptr, packed.buffer.ptr + 24, packed.buffer.ptr + 36)
    assert (a.shape, b.shape, c.shape) == ((3, 2), (3,), (3, 2)) and c.dtype == wp.vec3
    a.fill_(1.5)
    b.fill_(-1)
    c.fill_(wp.vec3(2.0, 3.0, 4.0))
    saved = wp.clone(packed.buffer)
    assert np.all(a.numpy() == 1.5) and np.all(b.numpy() == -1) and np.all(c.numpy() == [2.0, 3.0, 4.0])
    b.zero_()
    assert np.all(a.numpy() == 1.5) and np.all(c.numpy() == [2.0, 3.0, 4.0])
    wp.copy(packed.buffer, saved)
    assert np.all(b.numpy() == -1)
    buffer = weakref.ref(packed.buffer)
    del packed, a, c, saved
    gc.collect()
    assert buffer() is not None and np.all(b.numpy() == -1)  # a view alone keeps the buffer alive
    del b
    gc.collect()
    assert buffer() is None


def test_packed_arrays_refuse_elements_that_are_not_whole_words():
    from legged_gente.external_forces.field import PackedArrays

    with pytest.raises(ValueError, match=r"\['mask'\] have elements that are not whole 4-byte words"):
        PackedArrays({"a": (3, float), "mask": (3, wp.bool)}, DEV)


def test_feet_cells_go_beside_the_contact_filter_only_when_no_foot_is_in_mujocos_contacts():
    """On a GPU the feet's cells (which clear the feet's contact flags) run beside the contact filter only when no
    foot geom reaches MuJoCo's contacts: a MuJoCo-collided foot's contact makes the filter write those flags, so the
    two must then run one after the other."""
    wp.set_device(DEV)
    hfield = f'<asset><hfield name="hf" nrow="{SHAPE[1]}" ncol="{SHAPE[0]}" size="2 2 1 0.1"/></asset>'

    def forces(foot_geoms: str, names: list):
        mjm = mujoco.MjModel.from_xml_string(f"""<mujoco>{hfield}<worldbody>
          <geom name="terrain" type="hfield" hfield="hf"/>
          <body name="foot" pos="0 0 0.05"><joint type="slide" axis="0 0 1"/>{foot_geoms}</body>
          </worldbody></mujoco>""")
        cfg = type("C", (SoilCfg,), {"foot_geom_names": names})
        return make(mjm, MaterialMap.rigid(SHAPE), cfg(), nworld=1)[2]

    sole = '<geom name="sole" type="sphere" size="0.02" contype="0" conaffinity="0"/>'
    box = '<geom name="plate" type="box" size="0.05 0.05 0.01"/>'
    assert forces(sole, ["sole"]).feet_apart_from_filter
    assert not forces(box, ["plate"]).feet_apart_from_filter
    assert not forces(sole + box, ["sole", "plate"]).feet_apart_from_filter


def test_a_soil_that_would_swallow_the_standing_robot_is_warned_of(custom_soil):
    """Bekker's kphi taken from a table in kN as if in N: 300 N/m^2 (kc 0, n 1) under two 0.1 m square soles
    sharing 25 kg sinks z = p / kphi = (25 * 9.81 / 2 / 0.01) / 300 = 40.9 m standing; 300 kN/m^2 sinks 4.1 cm, no
    warning."""
    wp.set_device(DEV)
    mat = MaterialMap.rigid(SHAPE)
    mat.soil[:] = 0
    for name, kphi, sinks in (("peat_kn", 300.0, 25 * 9.81 / 2 / 0.01 / 300.0), ("peat", 300.0e3, None)):
        custom_soil(name, kc=0.0, kphi=kphi, n=1.0, c=0.0, mu=0.5, K=0.02, bulldoze_c=0.0, bulldoze_g=0.0)
        mat.soil_presets = [name]
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            make(feet_world(), mat, SoilCfg())
        said = [str(w.message) for w in caught if "sinks" in str(w.message)]
        if sinks is None:
            assert said == []
        else:
            assert abs(sinks - 40.875) < 1e-3 and len(said) == 1
            assert f"sinks {sinks:.3g} m" in said[0] and "kN" in said[0]
