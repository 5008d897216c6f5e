"""Soil under a foot in tiny MuJoCo-Warp worlds on the CPU (analytic sole contacts on a heightfield): the
Mohr-Coulomb traction limit, dissipation, lift-off, the shown rut (snow, mud) and the edge cases."""

import math

import mujoco
import mujoco_warp as mjw
import numpy as np
import pytest
import warp as wp

from legged_gente.external_forces import contact as C
from legged_gente.external_forces import kernels as K
from legged_gente.external_forces.field import ForcesConfig, TerrainForces
from legged_gente.terrain.soil import SOIL_PRESETS, register_custom_soil
from legged_gente.terrain.materials import MaterialMap

wp.config.quiet = True
DEV = "cpu"
G = 9.81
SHAPE, RES, ORIGIN = (41, 41), 0.1, (-2.0, -2.0)
# four 2 cm sole spheres at the corners of a 0.22 m x 0.09 m sole (their discs' footprint)
SOLE_XY = [(0.09, 0.025), (0.09, -0.025), (-0.09, 0.025), (-0.09, -0.025)]
SOLE_AREA = 0.22 * 0.09

@pytest.fixture(scope="module", autouse=True)
def registered_test_soils():
    """Wong, Theory of Ground Vehicles, Table 2.3: dry sand (LLL), snow (U.S.) and sandy loam at 32 % moisture
    (Hanamoto, the "mud" preset's means), with no bulldozing and no scatter so the tests see the traction limit and
    the sinkage alone; and dry sand with bulldozing. Removed again after this module's tests."""
    tan = lambda deg: math.tan(math.radians(deg))  # noqa: E731
    register_custom_soil("t_sand", kc=0.99e3, kphi=1528.43e3, n=1.1, c=1.04e3, mu=tan(28.0), K=0.025,
                         bulldoze_c=0.0, bulldoze_g=0.0)
    register_custom_soil("t_snow", kc=4.37e3, kphi=196.72e3, n=1.6, c=1.03e3, mu=tan(19.7), K=0.04,
                         bulldoze_c=0.0, bulldoze_g=0.0)
    register_custom_soil("t_mud", kc=0.77e3, kphi=51.91e3, n=0.5, c=5.17e3, mu=tan(11.0), K=0.05,
                         bulldoze_c=0.0, bulldoze_g=0.0)
    register_custom_soil("t_sand_bull", kc=0.99e3, kphi=1528.43e3, n=1.1, c=1.04e3, mu=tan(28.0), K=0.025,
                         bulldoze_c=1.4e4, bulldoze_g=2.6e5)
    register_custom_soil("t_mud_bull", kc=0.77e3, kphi=51.91e3, n=0.5, c=5.17e3, mu=tan(11.0), K=0.05,
                         bulldoze_c=2.87e4, bulldoze_g=4.79e4)
    register_custom_soil("t_clay", kc=41.6e3, kphi=2471e3, n=0.73, c=6.1e3, mu=tan(26.6), K=0.01,  # clay loam
                         bulldoze_c=0.0, bulldoze_g=0.0)
    # closely packed poppy seeds under resistive force theory (Li et al. 2013): zeta = 0.464 N/cm^3
    register_custom_soil("t_rft", kc=0.0, kphi=4.64e5, n=1.0, c=0.0, mu=tan(28.0), K=0.025, bulldoze_c=0.0,
                         bulldoze_g=0.0, zeta=4.64e5, model="rft")
    # the same seeds with a frictionless sole-seed interface (mu below min_friction): a dragged sole's contact
    # carries its weight alone (MuJoCo's sliding contacts hop, which disturbs the load)
    register_custom_soil("t_rft_slick", kc=0.0, kphi=4.64e5, n=1.0, c=0.0, mu=1e-3, K=0.025, bulldoze_c=0.0,
                         bulldoze_g=0.0, zeta=4.64e5, model="rft")
    yield
    for name in ("t_sand", "t_snow", "t_mud", "t_sand_bull", "t_mud_bull", "t_clay", "t_rft", "t_rft_slick"):
        SOIL_PRESETS.pop(name)


def foot_world(mass, joints="xz", sole_xy=SOLE_XY, z0=0.025, option=""):
    axes = {"x": "1 0 0", "y": "0 1 0", "z": "0 0 1"}
    js = "".join(f'<joint name="{a}" type="slide" axis="{axes[a]}"/>' for a in joints)
    soles = "".join(f'<geom name="sole{k}" type="sphere" size="0.02" pos="{x} {y} 0" contype="0" conaffinity="0"/>'
                    for k, (x, y) in enumerate(sole_xy))
    xml = f"""<mujoco><option timestep="0.005" {option}/>
      <asset><hfield name="hf" nrow="{SHAPE[1]}" ncol="{SHAPE[0]}" size="2 2 1 0.1"/></asset>
      <worldbody><geom name="terrain" type="hfield" hfield="hf"/>
        <body name="foot" pos="0 0 {z0}">{js}
          <geom type="box" size="0.1 0.04 0.01" pos="0 0 0.03" mass="{mass}" contype="0" conaffinity="0"/>{soles}
        </body></worldbody></mujoco>"""
    return mujoco.MjModel.from_xml_string(xml)


class Cfg(ForcesConfig):
    noise_std = 0.0
    wading = False
    foot_geom_names = [f"sole{k}" for k in range(4)]


def soil_map(name=None, friction=1.0):
    mat = MaterialMap.rigid(SHAPE, friction=friction)
    if name is not None:
        mat.soil[:] = 0
        mat.soil_presets = [name]
    return mat


def make(mjm, mat, nworld=1, **cfg):
    m = mjw.put_model(mjm)
    d = mjw.make_data(mjm, nworld=nworld, nconmax=16, njmax=64)
    f = TerrainForces(mjm, m, d, np.zeros(SHAPE, np.float32), ORIGIN, RES, mat, type("C", (Cfg,), cfg)(), seed=1)
    f.install()
    return m, d, f


def run(m, d, f, steps, push=0.0):
    """``steps`` substeps with a force ``push`` (N, per world) on the x joint."""
    qfrc = np.zeros((d.nworld, m.nv), np.float32)
    qfrc[:, 0] = push
    d.qfrc_applied.assign(qfrc)
    for _ in range(steps):
        mjw.step(m, d)
        f.after_substep()


def ramp_and_hold(m, d, f, target, ramp=200, hold=150):
    """Push along x rising linearly to ``target`` (per world) over ``ramp`` substeps, then held: quasi-static
    loading, as Janosi and Hanamoto's shear tests."""
    for k in range(ramp + hold):
        run(m, d, f, 1, push=min(k / ramp, 1.0) * np.asarray(target))


def test_dry_sand_limits_traction():
    wp.set_device(DEV)
    mass = 20.0
    # Mohr-Coulomb: T_max = c A + W tan(phi); dry sand c = 1.04 kPa, phi = 28 deg (Wong), A = 0.22 m x 0.09 m
    t_max = 1.04e3 * 0.22 * 0.09 + mass * G * math.tan(math.radians(28.0))  # 20.6 + 104.3 = 124.9 N
    m, d, f = make(foot_world(mass), soil_map("t_sand"), nworld=2)
    run(m, d, f, 60)  # settle into the rut
    x0 = d.qpos.numpy()[:, 0].copy()
    ramp_and_hold(m, d, f, [0.9 * t_max, 1.1 * t_max])
    travel, v = d.qpos.numpy()[:, 0] - x0, d.qvel.numpy()[:, 0]
    # below the limit: it slips while the traction mobilises (Janosi-Hanamoto: j = -K ln(1 - 0.9) = 5.8 cm
    # quasi-statically; MuJoCo's sliding contacts hop, which adds some), then holds
    assert abs(v[0]) < 0.01 and 0.02 < travel[0] < 0.2, (travel, v)
    # above it: it slides away, accelerated by the excess push
    assert v[1] > 0.3 and travel[1] > 0.3, (travel, v)

    # rigid ground (mu = 1, limit W = 196 N): the same pushes hold
    m, d, f = make(foot_world(mass), soil_map(None), nworld=2)
    run(m, d, f, 60)
    x0 = d.qpos.numpy()[:, 0].copy()
    ramp_and_hold(m, d, f, [0.9 * t_max, 1.1 * t_max])
    assert np.all(np.abs(d.qpos.numpy()[:, 0] - x0) < 0.005) and np.all(np.abs(d.qvel.numpy()[:, 0]) < 0.01)


def test_soil_shear_never_pushes_back():
    """The former shear opposed the accumulated slip like a spring: a foot dragged forward and released was
    pulled back. Soil traction is friction now: released, the foot stays where it was left."""
    wp.set_device(DEV)
    m, d, f = make(foot_world(20.0), soil_map("t_sand"))
    run(m, d, f, 60)
    run(m, d, f, 60, push=np.array([200.0]))  # far above the 125 N limit: dragged ~10 cm
    d.qvel.zero_()
    x_release = d.qpos.numpy()[0, 0]
    assert f.foot_slip.numpy()[0, 0] > 0.02  # the soil has been sheared
    run(m, d, f, 100)
    assert d.qpos.numpy()[0, 0] >= x_release - 1e-3 and abs(d.qvel.numpy()[0, 0]) < 0.01


def test_a_foot_held_still_in_a_mud_rut_does_not_chatter():
    """Bulldozing was an explicit force against the last substep's velocity, a damper of R_b / 0.05 m/s below
    0.05 m/s: with R_b dt / 0.05 above twice the foot's mass the velocity overshot and flipped sign each substep,
    and a 6 kg foot nudged at 0.02 m/s in a mud rut swung to about 0.3 m/s. In the contact's friction limit the
    solver applies it implicitly: the nudge dies out."""
    wp.set_device(DEV)
    m, d, f = make(foot_world(6.0, sole_xy=[(0.0, 0.0)]), soil_map("t_mud_bull"), foot_geom_names=["sole0"])  # a 4 cm disc
    run(m, d, f, 400)  # 2 s: settled in its rut
    z = f.foot_sinkage.numpy()[0, 0]
    r_b = 0.04 * (2.87e4 * z + 4.79e4 * z * z)  # Bekker's bulldozing across the disc's diameter, by hand
    assert r_b * 0.005 / 0.05 > 2 * 6.0  # the explicit damper's stability bound, exceeded
    q = d.qvel.numpy()
    q[0, 0] = 0.02
    d.qvel.assign(q)
    speeds = []
    for _ in range(20):  # 0.1 s
        run(m, d, f, 1)
        speeds.append(abs(d.qvel.numpy()[0, 0]))
    assert max(speeds) <= 0.02 + 1e-6 and speeds[-1] < 1e-3, speeds


def test_slip_survives_load_dips_and_resets_at_liftoff():
    wp.set_device(DEV)
    m, d, f = make(foot_world(20.0), soil_map("t_sand"))
    run(m, d, f, 60)
    f.foot_slip.assign(np.array([[0.05]], np.float32))
    rut = f.foot_sinkage.numpy()[0, 0]
    assert rut > 0.005
    rest = d.qpos.numpy().copy()

    def lifted(substeps, height=0.05):
        for _ in range(substeps):
            up = rest.copy()
            up[0, 1] += height
            d.qpos.assign(up)
            d.qvel.zero_()
            mjw.step(m, d)
            f.after_substep()
        d.qpos.assign(rest)
        d.qvel.zero_()
        run(m, d, f, 1)

    lifted(1)  # one substep without load (5 ms < liftoff_time 50 ms): same stance
    assert f.foot_slip.numpy()[0, 0] >= 0.05 and f.foot_sinkage.numpy()[0, 0] >= rut
    lifted(8)  # 40 ms: a sliding foot's hop (MuJoCo's sliding contacts push the body up)
    assert f.foot_slip.numpy()[0, 0] >= 0.05
    lifted(20, height=0.015)  # 100 ms, 1.5 cm up: a fast sliding foot's hop, within liftoff_clearance (2.5 cm)
    assert f.foot_slip.numpy()[0, 0] >= 0.05
    lifted(11)  # 55 ms in the air: lift-off, a new stance starts from a fresh rut and no slip
    assert f.foot_slip.numpy()[0, 0] < 1e-3 and f.foot_sinkage.numpy()[0, 0] < rut


def sole_normals(d, mjm):
    n = int(d.nacon.numpy()[0])
    soles = {mujoco.mj_name2id(mjm, mujoco.mjtObj.mjOBJ_GEOM, f"sole{k}") for k in range(4)}
    mask = np.isin(d.contact.geom.numpy()[:n, 1], list(soles))
    return d.contact.frame.numpy()[:n][mask, 0]


def test_snow_foot_shown_at_full_bekker_sinkage_with_vertical_normals():
    wp.set_device(DEV)
    mass = 20.0
    # Bekker: z = (p / (kc/b + kphi))^(1/n); snow (U.S.) kc = 4.37 kN/m^(n+1), kphi = 196.72 kN/m^(n+2),
    # n = 1.6 (Wong Table 2.3); p = 20 kg * 9.81 / (0.22 * 0.09 m^2) = 9909 Pa, b = 0.09 m
    z_bekker = (mass * G / (0.22 * 0.09) / (4.37e3 / 0.09 + 196.72e3)) ** (1 / 1.6)  # 0.1346 m
    mjm = foot_world(mass, z0=0.02)
    m, d, f = make(mjm, soil_map("t_snow"), sinkage_rate=0.25, sinkage_load_tau=0.2)  # a slow landing
    normals = []
    for _ in range(50):
        run(m, d, f, 5)
        normals.append(sole_normals(d, mjm))
    shown = -d.qpos.numpy()[0, 1]  # the sole spheres rest on the rigid surface at qpos z = 0
    rut = f.foot_sinkage.numpy()[0, 0]
    assert 0.99 * z_bekker <= rut <= 1.08 * z_bekker, (rut, z_bekker)  # the landing may dig a little deeper
    assert shown == pytest.approx(rut, abs=0.002), (shown, rut)
    normals = np.concatenate(normals)
    assert len(normals) > 50
    np.testing.assert_allclose(normals, np.tile([0.0, 0.0, 1.0], (len(normals), 1)), atol=1e-6)


def test_mud_sinks_centimetres_under_a_biped_foot():
    wp.set_device(DEV)
    # the mud preset is Wong's sandy loam at 32 % moisture (Hanamoto): n = 0.5, kc = 0.77 kN/m^1.5,
    # kphi = 51.91 kN/m^2.5, c = 5.17 kPa (Table 2.3)
    mud = SOIL_PRESETS["mud"]
    assert (mud.kc[0], mud.kphi[0], mud.n[0], mud.c[0]) == (0.77e3, 51.91e3, 0.5, 5.17e3)
    # the 41.5 kg biped on one foot: its soles span 0.22 m x 0.096 m (spheres r 2 cm at x 0.14 / -0.04,
    # y +-0.028): p = 41.5 * 9.81 / 0.02112 = 19.3 kPa -> z = (19.3e3 / (0.77e3 / 0.096 + 51.91e3))^2
    z_bekker = (41.5 * G / (0.22 * 0.096) / (0.77e3 / 0.096 + 51.91e3)) ** (1 / 0.5)  # 0.103 m
    sole = [(0.14, 0.028), (0.14, -0.028), (-0.04, 0.028), (-0.04, -0.028)]
    m, d, f = make(foot_world(41.5, sole_xy=sole, z0=0.02), soil_map("t_mud"), sinkage_rate=0.1, sinkage_load_tau=0.2)
    run(m, d, f, 300)  # 1.5 s: the rut deepens at most 0.1 m/s
    shown = -d.qpos.numpy()[0, 1]
    assert shown > 0.01 and shown == pytest.approx(z_bekker, rel=0.15), (shown, z_bekker)


@pytest.mark.parametrize("soil, kc, kphi, n", [("t_mud", 0.77e3, 51.91e3, 0.5), ("t_rft", 0.0, 4.64e5, 1.0),
                                              ("t_snow", 4.37e3, 196.72e3, 1.6)])
def test_a_slowly_loaded_foot_settles_at_bekker_s_depth(soil, kc, kphi, n):
    """At the default sinkage settings a 41.5 kg foot whose weight comes on linearly over 4 s settles at
    z = (p / (kc / b + kphi))^(1 / n) (RFT: p / zeta, zeta = kphi). A deepening rut makes the contact chatter
    (F_N 0 to 4 W); through one 50 ms low-pass the rut kept its peaks and settled 1.39 x (mud) and 1.42 x (RFT)
    deeper (CPU), and a rising sole was given a dragged sole's RFT support."""
    wp.set_device(DEV)
    mass = 41.5
    m, d, f = make(foot_world(mass, joints="z", z0=0.02), soil_map(soil))
    weight = mass * G
    for k in range(1000):  # 4 s ramp, 1 s held
        d.qfrc_applied.assign(np.array([[weight * max(1.0 - k * 0.005 / 4.0, 0.0)]], np.float32))
        mjw.step(m, d)
        f.after_substep()
    z_bekker = (weight / SOLE_AREA / (kc / 0.09 + kphi)) ** (1.0 / n)  # b: the sole's 9 cm side
    rut = f.foot_sinkage.numpy()[0, 0]
    assert rut == pytest.approx(z_bekker, rel=0.10), (rut, z_bekker)  # 1.08 / 1.01 / 1.02 x (CPU)


def test_zero_friction_on_soil_neither_launches_nor_sinks_through():
    wp.set_device(DEV)
    # map friction 0 on sand (pyramidal cone) and on rigid ground with the elliptic cone
    for mat, option in ((soil_map("t_sand", friction=0.0), ""), (soil_map(None, friction=0.0), 'cone="elliptic"')):
        mjm = foot_world(20.0, option=option)
        m, d, f = make(mjm, mat)
        run(m, d, f, 60)
        z0 = d.qpos.numpy()[0, 1]
        run(m, d, f, 60, push=np.array([30.0]))  # frictionless: it glides
        z, v = d.qpos.numpy()[0, 1], d.qvel.numpy()[0]
        assert -0.03 < z0 <= 0.001 and abs(z - z0) < 0.003 and abs(v[1]) < 0.02, (option, z0, z, v)
        assert v[0] == pytest.approx(30.0 / 20.0 * 0.3, rel=0.05)  # a = F/m for 0.3 s


def test_foot_soil_is_the_cell_under_the_sole_centre():
    wp.set_device(DEV)
    mat = soil_map(None)
    mat.soil[21:, :] = 0  # cells centred at x >= 0.1: sand; the border at x = 0.05
    mat.soil_presets = ["t_sand"]
    m, d, f = make(foot_world(20.0), mat, nworld=2)
    q = d.qpos.numpy()
    q[:, 0] = [0.08, 0.02]  # centre on sand (heels on rigid ground) / on rigid ground (toes on sand)
    d.qpos.assign(q)
    for _ in range(3):
        run(m, d, f, 10)
        np.testing.assert_array_equal(f.foot_soil.numpy()[:, 0], [0, -1])


def test_bulldozing_adds_to_the_traction_limit():
    """A foot sunk in a sand with bulldozing holds a push above the Mohr-Coulomb limit T = c A + W tan(phi) but
    below T + R_b, Bekker's bulldozing resistance b (bulldoze_c z + bulldoze_g z^2) of its rut z (b the sole's
    smaller side, 0.09 m), and slides away above T + R_b; without bulldozing the same lower push slides."""
    wp.set_device(DEV)
    mass = 20.0
    t_max = 1.04e3 * 0.22 * 0.09 + mass * G * math.tan(math.radians(28.0))  # 124.9 N, as above
    m, d, f = make(foot_world(mass), soil_map("t_sand_bull"), nworld=2)
    run(m, d, f, 60)
    z = f.foot_sinkage.numpy()[:, 0]
    r_b = 0.09 * (1.4e4 * z + 2.6e5 * z * z)
    assert np.all(r_b > 0.1 * t_max), r_b  # a resistance worth telling apart
    below = t_max + 0.5 * r_b  # above T, below T + R_b
    x0 = d.qpos.numpy()[:, 0].copy()
    ramp_and_hold(m, d, f, [below[0], 1.15 * (t_max + r_b[1])], hold=400)
    travel, v = d.qpos.numpy()[:, 0] - x0, d.qvel.numpy()[:, 0]
    assert abs(v[0]) < 0.01 and travel[0] < 0.2, (travel, v, r_b)
    assert v[1] > 0.3 and travel[1] > 0.3, (travel, v)
    m, d, f = make(foot_world(mass), soil_map("t_sand"))  # no bulldozing: T alone
    run(m, d, f, 60)
    x0 = d.qpos.numpy()[:, 0].copy()
    ramp_and_hold(m, d, f, [below[0]], hold=400)
    assert d.qvel.numpy()[0, 0] > 0.3 and d.qpos.numpy()[0, 0] - x0[0] > 0.3


def test_bulldozing_adds_to_a_slippery_surface():
    """Sand on a slippery surface (the cell's friction 0.2: ice under snow): the sole's shear is the surface's,
    0.2 W, below the sand's T; bulldozing is pressure on the sunk sole's leading face, not shear, so it adds to
    it: a push of 0.2 W + R_b / 2 is held, 1.15 (0.2 W + R_b) slides away."""
    wp.set_device(DEV)
    mass = 20.0
    surface = 0.2 * mass * G  # 39.2 N, below T = 124.9 N
    m, d, f = make(foot_world(mass), soil_map("t_sand_bull", friction=0.2), nworld=2)
    run(m, d, f, 60)
    z = f.foot_sinkage.numpy()[:, 0]
    r_b = 0.09 * (1.4e4 * z + 2.6e5 * z * z)
    assert np.all(r_b > 0.3 * surface), r_b
    x0 = d.qpos.numpy()[:, 0].copy()
    ramp_and_hold(m, d, f, [surface + 0.5 * r_b[0], 1.15 * (surface + r_b[1])], hold=400)
    travel, v = d.qpos.numpy()[:, 0] - x0, d.qvel.numpy()[:, 0]
    assert abs(v[0]) < 0.01 and travel[0] < 0.2, (travel, v, r_b)
    assert v[1] > 0.3 and travel[1] > 0.3, (travel, v)


def test_rft_sole_sinks_to_zeta_and_drags_with_alpha_x():
    """A 20 kg foot on an RFT medium sinks until zeta |z| A carries its weight, and dragged sideways in its rut
    the medium resists with RFT's horizontal stress on its sole plate, alpha_x(0, 0) |z| A = 0.136 zeta z A =
    0.136 m g (z = m g / (zeta A)), applied element by element at the contact plane; and on its leading face, the
    soil wall 0.09 m wide (the sole's width across the motion) from the surface down to z: vertical-plate strips,
    alpha_x(pi/2, 0) = 0.370 zeta, integrated over the depth, 0.370 zeta z^2 / 2 * 0.09, at z / 3 above the
    contact plane."""
    wp.set_device(DEV)
    mass, zeta, area, width = 20.0, 4.64e5, 0.22 * 0.09, 0.09
    z_rft = mass * G / area / zeta  # 9909 Pa / 4.64e5 N/m^3 = 0.0214 m
    m, d, f = make(foot_world(mass, z0=0.02), soil_map("t_rft"), sinkage_rate=0.25, sinkage_load_tau=0.2)
    run(m, d, f, 200)
    assert -d.qpos.numpy()[0, 1] == pytest.approx(z_rft, rel=0.08)
    # dragged along +x at 0.3 m/s (above the 0.05 m/s fade); the last substep's forces are those of the state
    # it started from: its velocity (0.3 m/s along x; sinking at vz, as the dragged sole's rut deepens) and its
    # depth (the contact plane, 2 cm (the spheres' radius) below the body origin, under the flat surface at 0:
    # d.xpos after the step, whose forward computed the bodies before integrating)
    for _ in range(5):
        q = d.qvel.numpy()
        q[0, 0] = 0.3
        d.qvel.assign(q)
        vz = q[0, 1]
        mjw.step(m, d)
        f.after_substep()
    contact_z, com = d.xpos.numpy()[0, 1, 2] - 0.02, d.xipos.numpy()[0, 1]
    z = -contact_z
    assert z == pytest.approx(z_rft, rel=0.08)
    # gamma = atan2(-vz, 0.3): alpha_x(0, gamma) = 0.136 cos(gamma), alpha_x(pi/2, gamma) = 0.370 cos(gamma)
    cos_gamma = 0.3 / math.hypot(0.3, vz)
    plate = (-0.124 + 0.253 + 0.007) * cos_gamma * zeta * z * area  # C11 + C01 + C-11 = 0.136: 26.7 N at z_rft
    face = (0.253 + 0.124 - 0.007) * cos_gamma * zeta * z * z / 2 * width  # C01 - C11 - C-11 = 0.370: 3.5 N
    fx = f.foot_force.numpy()[0, 0]
    assert fx[0] == pytest.approx(-(plate + face), rel=1e-3) and abs(fx[1]) < 1e-3 and fx[2] == 0.0
    # its moment: the plate's elements at the contact plane, the face's centre of pressure z / 3 above it
    torque_y = (contact_z - com[2]) * fx[0] + z / 3 * -face
    assert d.xfrc_applied.numpy()[0, 1, 4] == pytest.approx(torque_y, rel=2e-3)


def drag(m, d, f, substeps, vx):
    """``substeps`` substeps with the foot's x velocity held at ``vx`` (its z free)."""
    for _ in range(substeps):
        q = d.qvel.numpy()
        q[:, 0] = vx
        d.qvel.assign(q)
        mjw.step(m, d)
        f.after_substep()


@pytest.mark.parametrize("collided", [False, True])
def test_rft_sole_dragged_sideways_sinks_to_alpha_z_of_its_motion(collided):
    """RFT's vertical stress depends on the sole's motion: at rest (or pushed straight down) a level sole gets
    alpha_z(0, pi/2) = zeta and sinks to m g / (zeta A); dragged sideways it gets alpha_z(0, gamma), gamma the
    angle of its velocity below the horizontal, and sinks on to m g / (alpha_z(0, gamma) A): 0.375 zeta level.
    Analytic sole contacts, and soles MuJoCo collides (``sole_contact=False``: the rut is shown at most
    ``max_rut_depth``, 1 cm, but is as deep)."""
    wp.set_device(DEV)
    mass, zeta, area = 20.0, 4.64e5, 0.22 * 0.09
    mjm = foot_world(mass, z0=0.02)
    if collided:
        for k in range(4):
            mjm.geom(f"sole{k}").contype[0] = mjm.geom(f"sole{k}").conaffinity[0] = 1
    m, d, f = make(mjm, soil_map("t_rft_slick"), sinkage_rate=0.25, sinkage_load_tau=0.2, sole_contact=not collided)
    run(m, d, f, 200)
    z_rest = mass * G / (zeta * area)  # 2.14 cm
    assert f.foot_sinkage.numpy()[0, 0] == pytest.approx(z_rest, rel=0.08)
    if not collided:
        assert -d.qpos.numpy()[0, 1] == pytest.approx(z_rest, rel=0.08)
    drag(m, d, f, 400, 0.3)  # 2 s at 0.3 m/s, six times the 0.05 m/s fade
    vx, vz = d.qvel.numpy()[0]
    # Li et al.'s generic fit for a level sole (beta = 0): alpha_z / zeta = A00 + A10 cos(2 beta)
    # + B11 sin(2 beta + gamma) + B01 sin(gamma) + B-11 sin(-2 beta + gamma)
    gamma = math.atan2(-vz, vx)
    alpha_z = 0.206 + 0.169 + (0.212 + 0.358 + 0.055) * math.sin(gamma)
    z_drag = mass * G / (alpha_z * zeta * area)  # 5.70 cm at gamma = 0
    # measured (CPU): |gamma| < 1e-3, rut 5.89 cm analytic, 5.80 cm collided (the rut is plastic: load
    # ripples while sliding ratchet it 2-3 % deeper than the filtered load's 5.73 cm)
    rut = f.foot_sinkage.numpy()[0, 0]
    assert abs(gamma) < 0.01 and rut == pytest.approx(z_drag, rel=0.05), (gamma, rut, z_drag)
    if not collided:
        assert -d.qpos.numpy()[0, 1] == pytest.approx(z_drag, rel=0.05)


def test_bekker_ruts_ignore_the_rft_support():
    """Only RFT soils read a sole's RFT support: two worlds given supports 1 and 0.2 before every substep stay
    bit-identical on snow (Bekker) and part on the RFT seeds (the lower support digs a deeper rut)."""
    wp.set_device(DEV)
    for soil, same in (("t_snow", True), ("t_rft_slick", False)):
        m, d, f = make(foot_world(20.0, z0=0.02), soil_map(soil), nworld=2, sinkage_rate=0.25)
        for _ in range(80):
            f.foot_support.assign(np.array([[1.0], [0.2]], np.float32))
            drag(m, d, f, 1, 0.3)
        q, rut = d.qpos.numpy(), f.foot_sinkage.numpy()[:, 0]
        if same:
            assert np.array_equal(q[0], q[1]) and rut[0] == rut[1] and rut[0] > 0.02, (q, rut)
        else:
            assert rut[1] > rut[0] + 0.01, rut


def test_rft_preset_is_an_option_and_bekker_stays_the_default():
    for name in ("dry_sand", "wet_sand", "snow", "mud", "clay_loam"):
        assert SOIL_PRESETS[name].model == "bekker"
    p = SOIL_PRESETS["poppy_seeds_rft"]
    assert p.model == "rft" and p.zeta[0] == pytest.approx(0.094e6 + 0.092e6 + 0.092e6 + 0.151e6 + 0.035e6)
    # RFT's vertical law p = zeta z is Bekker's with kc = 0, kphi = zeta, n = 1
    assert (p.kc[0], p.kphi[0], p.n[0]) == (0.0, p.zeta[0], 1.0)
    with pytest.raises(ValueError, match="zeta > 0"):
        register_custom_soil("t_bad", kc=0.0, kphi=1e5, n=1.0, c=0.0, mu=0.5, K=0.02, bulldoze_c=0.0,
                             bulldoze_g=0.0, model="rft")
    with pytest.raises(ValueError, match="model"):
        register_custom_soil("t_bad", kc=0.0, kphi=1e5, n=1.0, c=0.0, mu=0.5, K=0.02, bulldoze_c=0.0,
                             bulldoze_g=0.0, model="dem")


def test_rft_spinning_sole_gets_the_moment_of_its_elements():
    """A sole spun about its vertical axis in an RFT medium: each of its 4 x 2 elements is dragged along its own
    circle, so the forces cancel and leave a couple, -0.136 zeta z dA sum(r_i) (alpha_x of a flat element moved
    horizontally, every element faster than the 5 cm/s fade). Element centres of the 0.22 m x 0.09 m sole at
    x = +-0.0275, +-0.0825 m, y = +-0.0225 m: r = 0.0355 m (4) and 0.0855 m (4), sum 0.4842 m; dA = A / 8."""
    wp.set_device(DEV)
    mass, zeta, area = 20.0, 4.64e5, 0.22 * 0.09
    z_rft = mass * G / area / zeta
    radii = [math.hypot(x, y) for x in (-0.0825, -0.0275, 0.0275, 0.0825) for y in (-0.0225, 0.0225)]
    couple = -0.136 * zeta * z_rft * (area / 8) * sum(radii)  # -1.61 N m
    soles = "".join(f'<geom name="sole{k}" type="sphere" size="0.02" pos="{x} {y} 0" contype="0" conaffinity="0"/>'
                    for k, (x, y) in enumerate(SOLE_XY))
    mjm = mujoco.MjModel.from_xml_string(f"""<mujoco><option timestep="0.005"/>
      <asset><hfield name="hf" nrow="{SHAPE[1]}" ncol="{SHAPE[0]}" size="2 2 1 0.1"/></asset>
      <worldbody><geom name="terrain" type="hfield" hfield="hf"/>
        <body name="foot" pos="0 0 0.02"><joint type="slide" axis="0 0 1"/><joint name="yaw" type="hinge" axis="0 0 1"/>
          <geom type="box" size="0.1 0.04 0.01" pos="0 0 0.03" mass="{mass}" contype="0" conaffinity="0"/>{soles}
        </body></worldbody></mujoco>""")
    m, d, f = make(mjm, soil_map("t_rft"), sinkage_rate=0.25, sinkage_load_tau=0.2)
    run(m, d, f, 200)
    for _ in range(3):  # spun at 5 rad/s: the slowest elements move at 0.18 m/s
        q = d.qvel.numpy()
        q[0, 1] = 5.0
        d.qvel.assign(q)
        mjw.step(m, d)
        f.after_substep()
    force, torque = d.xfrc_applied.numpy()[0, 1, :3], d.xfrc_applied.numpy()[0, 1, 3:]
    # its rut's support is its elements' mean, each dragged level: A00 + A10 = 0.375 (not its resting centre's 1)
    assert f.foot_support.numpy()[0, 0] == pytest.approx(0.375, abs=1e-5)
    assert torque[2] == pytest.approx(couple, rel=0.1), (torque, couple)
    assert np.linalg.norm(force[:2]) < 1e-3 * abs(couple) / 0.05


def body_world(mass):
    """A 'knee': a body that is no foot, touching the ground through two colliding spheres, sliding along x."""
    xml = f"""<mujoco><option timestep="0.005"/>
      <asset><hfield name="hf" nrow="{SHAPE[1]}" ncol="{SHAPE[0]}" size="2 2 1 0.1"/></asset>
      <worldbody><geom name="terrain" type="hfield" hfield="hf"/>
        <body name="knee" pos="0 0 0.03"><joint type="slide" axis="1 0 0"/><joint type="slide" axis="0 0 1"/>
          <geom type="sphere" size="0.03" pos="0.05 0 0" mass="{mass / 2}"/>
          <geom type="sphere" size="0.03" pos="-0.05 0 0" mass="{mass / 2}"/>
        </body></worldbody></mujoco>"""
    return mujoco.MjModel.from_xml_string(xml)


def test_a_body_other_than_a_foot_gets_at_most_tan_phi_on_soil():
    """Mohr-Coulomb without the cohesion share (the contact area of a knee or a trunk is unknown): a 20 kg body on
    dry sand (phi = 28 deg) holds a push below W tan(phi) = 104.3 N and slides under one above it; on rigid ground
    (mu = 1) it holds both."""
    wp.set_device(DEV)
    mass = 20.0
    limit = mass * G * math.tan(math.radians(28.0))  # 104.3 N
    for soil, slides in (("t_sand", True), (None, False)):
        m, d, f = make(body_world(mass), soil_map(soil), nworld=2, foot_geom_names=[])
        run(m, d, f, 60)
        x0 = d.qpos.numpy()[:, 0].copy()
        ramp_and_hold(m, d, f, [0.8 * limit, 1.2 * limit])
        travel, v = d.qpos.numpy()[:, 0] - x0, d.qvel.numpy()[:, 0]
        assert abs(travel[0]) < 0.01 and abs(v[0]) < 0.01, (soil, travel, v)
        assert (v[1] > 0.3 and travel[1] > 0.3) if slides else (abs(travel[1]) < 0.01 and abs(v[1]) < 0.01), \
            (soil, travel, v)


def leg_world(mass, leg_contype, leg="0 0 0.05 0 0 0.15", foot_z=0.0, heights=None):
    """A 'calf' on a vertical slide carrying a capsule leg (r 2 cm, ``leg`` its fromto) and, on a welded child
    body, a 2 cm foot ball centred ``foot_z`` below the calf's origin; ``mass`` kg in all."""
    xml = f"""<mujoco><option timestep="0.005"/>
      <asset><hfield name="hf" nrow="{SHAPE[1]}" ncol="{SHAPE[0]}" size="2 2 1 0.1"/></asset>
      <worldbody><geom name="terrain" type="hfield" hfield="hf"/>
        <body name="calf" pos="0 0 0.3"><joint name="z" type="slide" axis="0 0 1"/>
          <geom type="box" size="0.02 0.02 0.02" pos="0 0 0.2" mass="{mass - 0.05}" contype="0" conaffinity="0"/>
          <geom name="leg" type="capsule" size="0.02" fromto="{leg}" mass="0" contype="{leg_contype}"
                conaffinity="{leg_contype}"/>
          <body name="foot" pos="0 0 {-foot_z}">
            <geom name="sole" type="sphere" size="0.02" mass="0.05" contype="0" conaffinity="0"/></body>
        </body></worldbody></mujoco>"""
    mjm = mujoco.MjModel.from_xml_string(xml)
    if heights is not None:
        mjm.hfield_data[:] = heights.T.ravel()  # MuJoCo's rows are y
    return mjm


def settle_on(mjm, mat, z0, substeps, heights=None, **cfg):
    """Drop the calf from ``z0`` and run; returns the calf's height, the foot's rut, the leg's contacts."""
    m = mjw.put_model(mjm)
    d = mjw.make_data(mjm, nworld=1, nconmax=16, njmax=64)
    h = np.zeros(SHAPE, np.float32) if heights is None else heights
    f = TerrainForces(mjm, m, d, h, ORIGIN, RES, mat, type("C", (Cfg,), {"foot_geom_names": ["sole"], **cfg})(),
                      seed=1)
    f.install()
    qpos = d.qpos.numpy()
    qpos[0, 0] = z0 - 0.3
    d.qpos.assign(qpos)
    run(m, d, f, substeps)
    n = int(d.nacon.numpy()[0])
    leg = mujoco.mj_name2id(mjm, mujoco.mjtObj.mjOBJ_GEOM, "leg")
    mask = d.contact.geom.numpy()[:n, 1] == leg
    return 0.3 + d.qpos.numpy()[0, 0], f.foot_sinkage.numpy()[0, 0], d.contact.dist.numpy()[:n][mask], \
        d.contact.frame.numpy()[:n][mask, 0]


def test_a_calf_as_wide_as_its_foot_follows_it_into_its_rut():
    """The quadruped's case in mud: 3.5 kg on a 2 cm foot ball, p = 3.5 * 9.81 / (pi 0.02^2) = 27.3 kPa, sinks
    z = (27.3e3 / (0.77e3 / 0.02 + 51.91e3))^2 = 9.1 cm (Bekker, b = r; Wong Table 2.3), deeper than the leg's
    capsule clears the sole (its lowest point 5 cm up). Held rigid by the soil's surface, the leg stops the foot
    at about 5 cm and carries the load; following its foot into the rut, it never touches and the foot sinks the
    whole 9.1 cm."""
    wp.set_device(DEV)
    z_bekker = (3.5 * G / (math.pi * 0.02**2) / (0.77e3 / 0.02 + 51.91e3)) ** 2
    slow = dict(sinkage_rate=0.1, sinkage_load_tau=0.2)
    height, rut, leg_dist, _ = settle_on(leg_world(3.5, 0), soil_map("t_mud"), 0.021, 400,
                                         rut_leg_geom_names=["leg"], **slow)
    assert rut == pytest.approx(z_bekker, rel=0.06), (rut, z_bekker)
    assert 0.02 - height == pytest.approx(rut, abs=0.003)  # the sole's centre 2 cm above its rut's floor
    assert len(leg_dist) == 0
    height, rut, leg_dist, _ = settle_on(leg_world(3.5, 1), soil_map("t_mud"), 0.021, 400, **slow)
    assert 0.045 < 0.02 - height < 0.056 and rut < 0.056, (height, rut)  # held up by the leg, 5 cm down
    assert len(leg_dist) > 0


def leg_rut(mass):
    """Bekker's sinkage (Wong Table 2.3, the sandy loam at 32 % moisture) of the test leg lying flat, pressing
    ``mass`` kg through its capsule's horizontal projection: 2r wide (Bekker's b), 0.14 + 2r long."""
    pressure = mass * G / (0.04 * (0.14 + 0.04))
    return (pressure / (0.77e3 / 0.04 + 51.91e3)) ** 2


def test_a_rut_leg_sinks_into_soil_under_its_own_load():
    """A leg lying flat on mud (its foot 0.2 m above it, touching nothing), 8 kg on a 0.04 m x 0.18 m projection:
    p = 8 * 9.81 / 0.0072 = 10.9 kPa sinks z = (10.9e3 / (0.77e3 / 0.04 + 51.91e3))^2 = 2.35 cm (Bekker, b = 2r), so
    its axis settles at r - z = -0.35 cm; 20 kg sinks 14.7 cm. On rigid ground it rests at r = 2 cm."""
    wp.set_device(DEV)
    flat = "-0.07 0 0 0.07 0 0"
    slow = dict(sinkage_rate=0.1, sinkage_load_tau=0.2)
    for mass in (8.0, 20.0):
        z = leg_rut(mass)
        height, foot_rut, dist, normals = settle_on(leg_world(mass, 0, leg=flat, foot_z=-0.2), soil_map("t_mud"),
                                                    0.03, 600, rut_leg_geom_names=["leg"], **slow)
        assert 0.02 - height == pytest.approx(z, rel=0.06), (mass, height, z)
        assert foot_rut == 0.0  # the leg's rut is its own, not its foot's
        assert len(dist) == 2
        np.testing.assert_allclose(normals, [[0.0, 0.0, 1.0]] * 2, atol=1e-6)
    height, *_ = settle_on(leg_world(8.0, 0, leg=flat, foot_z=-0.2), soil_map(), 0.03, 600,
                           rut_leg_geom_names=["leg"], **slow)
    assert height == pytest.approx(0.02, abs=0.002)


def test_a_rut_legs_rut_is_forgotten_after_lift_off():
    """Lifted out of its rut and held clear for longer than liftoff_time, the leg meets the undisturbed surface
    again: dropped on it, it sinks the same Bekker depth afresh (not twice)."""
    wp.set_device(DEV)
    flat = "-0.07 0 0 0.07 0 0"
    mjm = leg_world(8.0, 0, leg=flat, foot_z=-0.2)
    m = mjw.put_model(mjm)
    d = mjw.make_data(mjm, nworld=1, nconmax=16, njmax=64)
    cfg = type("C", (Cfg,), {"foot_geom_names": ["sole"], "rut_leg_geom_names": ["leg"], "sinkage_rate": 0.1,
                             "sinkage_load_tau": 0.2})()
    f = TerrainForces(mjm, m, d, np.zeros(SHAPE, np.float32), ORIGIN, RES, soil_map("t_mud"), cfg, seed=1)
    f.install()
    z = leg_rut(8.0)
    for _ in range(2):
        qpos, qvel = d.qpos.numpy(), d.qvel.numpy()
        qpos[0, 0], qvel[0, 0] = 0.03 - 0.3, 0.0
        d.qpos.assign(qpos), d.qvel.assign(qvel)
        run(m, d, f, 600)
        assert 0.02 - (0.3 + d.qpos.numpy()[0, 0]) == pytest.approx(z, rel=0.06)
        assert f.leg_sinkage.numpy()[0, 0] == pytest.approx(z, rel=0.06)
        qpos = d.qpos.numpy()
        qpos[0, 0] = 0.3 - 0.3  # lifted 30 cm clear
        d.qpos.assign(qpos)
        run(m, d, f, int(2 * cfg.liftoff_time / 0.005) + 1, push=0.0)
        assert f.leg_sinkage.numpy()[0, 0] == 0.0


def test_a_rut_leg_lying_on_rigid_ground_touches_with_its_two_ends():
    """A leg lying flat (along x, 0.14 m of axis, r 2 cm) on rigid ground rests on its end spheres, as MuJoCo's
    capsule against a plane: its axis r above the ground, two contacts with vertical normals, none from the inner
    spheres of its chain."""
    wp.set_device(DEV)
    flat = "-0.07 0 0 0.07 0 0"
    height, _, dist, normals = settle_on(leg_world(2.0, 0, leg=flat, foot_z=-0.2), soil_map(), 0.03, 200,
                                         rut_leg_geom_names=["leg"])
    assert height == pytest.approx(0.02, abs=0.002)
    assert len(dist) == 2
    np.testing.assert_allclose(normals, [[0.0, 0.0, 1.0]] * 2, atol=1e-6)


def test_a_rut_leg_across_a_ridge_rests_on_the_ridge():
    """Across a ridge 5 cm high (one row of vertices, slopes of 0.5 down to the neighbouring rows) the leg's ends
    hang over the slopes: an inner sphere of its chain carries it, as MuJoCo's own capsule collision does (on its
    ends alone it would sink to 1.5 + 2 cm, through the ridge)."""
    wp.set_device(DEV)
    h = np.zeros(SHAPE, np.float32)
    h[20, :] = 0.05  # x = ORIGIN + 20 * RES = 0
    flat = "-0.07 0 0 0.07 0 0"
    ours, _, dist, _ = settle_on(leg_world(2.0, 0, leg=flat, foot_z=-0.2, heights=h), soil_map(), 0.08, 200,
                                 heights=h, rut_leg_geom_names=["leg"])
    mujocos, *_ = settle_on(leg_world(2.0, 1, leg=flat, foot_z=-0.2, heights=h), soil_map(), 0.08, 200, heights=h)
    # resting on the apex line (x = 0, z = 0.05): the axis at most r above it, and at least above the ridge
    assert 0.05 < ours < 0.07 + 0.002 and ours == pytest.approx(mujocos, abs=0.003), (ours, mujocos)
    assert 1 <= len(dist) <= 2


@pytest.mark.parametrize("leg, problem", [
    ("-0.07 0 0 0.07 0 0", None),
    ("wide", "wider than the sole"),
    ("other", "with 0 feet at or below it"),
])
def test_rut_legs_are_checked(leg, problem):
    wp.set_device(DEV)
    if leg == "wide":  # a 3 cm leg on a 2 cm foot ball
        mjm = leg_world(2.0, 0)
        mjm.geom_size[mujoco.mj_name2id(mjm, mujoco.mjtObj.mjOBJ_GEOM, "leg"), 0] = 0.03
    elif leg == "other":  # the leg on the foot, the foot ball on the calf: no foot below the leg's body
        mjm = mujoco.MjModel.from_xml_string(f"""<mujoco><option timestep="0.005"/>
          <asset><hfield name="hf" nrow="{SHAPE[1]}" ncol="{SHAPE[0]}" size="2 2 1 0.1"/></asset>
          <worldbody><geom name="terrain" type="hfield" hfield="hf"/>
            <body name="calf" pos="0 0 0.3"><joint type="slide" axis="0 0 1"/>
              <geom name="sole" type="sphere" size="0.02" mass="1" contype="0" conaffinity="0"/>
              <body name="other" pos="0.2 0 0"><geom name="leg" type="capsule" size="0.02" fromto="0 0 0 0 0 0.1"
                mass="1" contype="0" conaffinity="0"/></body></body></worldbody></mujoco>""")
    else:
        mjm = leg_world(2.0, 0, leg=leg)
    m = mjw.put_model(mjm)
    d = mjw.make_data(mjm, nworld=1, nconmax=16, njmax=64)
    cfg = type("C", (Cfg,), {"foot_geom_names": ["sole"], "rut_leg_geom_names": ["leg"]})()
    args = (mjm, m, d, np.zeros(SHAPE, np.float32), ORIGIN, RES, soil_map(), cfg)
    if problem is None:
        # the soles' kernel compiled with the legs' branch only for a robot that has rut legs
        for legs, kernel in ((["leg"], C.sole_and_leg_contact_kernel), ([], C.sole_contact_kernel)):
            cfg.rut_leg_geom_names = legs
            assert TerrainForces(*args, seed=1)._recorded_filter(m, d)[-1].kernel is kernel
        cfg.rut_leg_geom_names = ["leg"]
        cfg.sole_contact = False
        with pytest.raises(ValueError, match="forces.sole_contact is off"):
            TerrainForces(*args, seed=1)
    else:
        with pytest.raises(ValueError, match=problem):
            TerrainForces(*args, seed=1)


def test_a_foot_pushed_below_its_traction_limit_on_a_firm_soil_stops():
    """A 41.5 kg foot resting on a clay loam (c = 6.1 kPa, phi = 26.6 deg, K = 1 cm; no bulldozing) pushed at once
    with 0.95 T, T = c A + W tan(phi) = 6100 x 0.0198 + 407.1 x 0.5008 = 324.6 N. It slides while Janosi-Hanamoto's
    traction mobilises, then holds: as a dynamic friction limit, where the push's work past T(j) is spent,
    0.05 j = K (1 - exp(-j / K)), j ~ 20 K = 0.2 m. While it slid, MuJoCo's sliding contact hopped the foot off for
    20-30 ms at a time; with a 20 ms lift-off each hop forgot the slip, the traction restarted from 0, and the foot
    accelerated to 3 m/s within 1 s, across the map (12 m/s after 4 s on a longer strip)."""
    mjm = foot_world(41.5)
    weight = float(sum(mjm.body_mass)) * 9.81
    limit = 6.1e3 * SOLE_AREA + weight * math.tan(math.radians(26.6))
    m, d, f = make(mjm, soil_map("t_clay"))
    qpos = d.qpos.numpy()
    qpos[:, 0] = -1.5
    d.qpos.assign(qpos)
    run(m, d, f, 400)
    start = float(d.qpos.numpy()[0, 0])
    run(m, d, f, 300, push=0.95 * limit)
    assert float(d.qpos.numpy()[0, 0]) - start < 0.5  # it held: within a few 20 K
    assert abs(float(d.qvel.numpy()[0, 0])) < 0.05


@pytest.mark.parametrize("soil, c, phi", [("t_mud", 5.17e3, 11.0), ("t_clay", 6.1e3, 26.6)])
def test_a_foot_driven_along_the_soil_meets_its_shear_strength_at_any_speed(soil, c, phi):
    """A 41.5 kg foot driven along x at 1 and 2 m/s (a stiff servo on a moving target; no bulldozing) meets the
    soil's shear strength, T = c A + W tan(phi) (Mohr-Coulomb; Janosi-Hanamoto's j is metres, K centimetres, so the
    traction is all mobilised): the servo's mean force over the second half of the drive. MuJoCo's sliding contact
    hops the foot off for most substeps (F_N is 0 in 80-90 % of them, the foot up to 2 cm high), and two defects made
    the resistance depend on the speed: the cohesion share c A / F_N divided by a load low-passed over 50 ms, which
    sags in each hop and is lowest at the landings' impacts (1.25 T at 1 m/s and 1.68 T at 2 m/s on the mud), and
    hops longer than liftoff_time forgot the slip, so each landing restarted the traction from 0 (0.74 T and 0.47 T
    on the clay loam)."""
    mjm = foot_world(41.5)
    weight = float(sum(mjm.body_mass)) * 9.81
    limit = c * SOLE_AREA + weight * math.tan(math.radians(phi))
    speeds = np.array([1.0, 2.0])
    m, d, f = make(mjm, soil_map(soil), nworld=len(speeds))
    qpos = d.qpos.numpy()
    qpos[:, 0] = -1.7
    d.qpos.assign(qpos)
    run(m, d, f, 200)
    x0 = d.qpos.numpy()[:, 0].copy()
    forces = []
    qfrc = np.zeros((d.nworld, m.nv), np.float32)
    for k in range(300):  # 1.5 s: at most 3 m along the 4 m map
        x, v = d.qpos.numpy()[:, 0], d.qvel.numpy()[:, 0]
        qfrc[:, 0] = 2.0e4 * (x0 + speeds * (k + 1) * 0.005 - x) + 2.0e3 * (speeds - v)
        d.qfrc_applied.assign(qfrc)
        mjw.step(m, d)
        f.after_substep()
        if k >= 150:
            forces.append(qfrc[:, 0].copy())
    resistance = np.mean(forces, axis=0) / limit
    assert np.all(np.abs(resistance - 1.0) < 0.08), resistance


@pytest.mark.parametrize("gap, on_floor", [(0.020, True), (0.030, False)])
def test_a_sole_is_on_the_floor_by_its_gap_along_the_slope_s_normal(gap, on_floor):
    """A sole sphere above a 30 degree slope is on the floor it stands on (its stance goes on) within
    liftoff_clearance (2.5 cm) of it along the face's normal: measured vertically, 2 cm along the normal read
    (2 + 2) / cos 30 - 2 = 2.62 cm, and on steeper faces less still."""
    wp.set_device(DEV)
    slope = math.radians(30.0)
    xs = ORIGIN[0] + RES * np.arange(SHAPE[0])
    heights = np.repeat((xs * math.tan(slope))[:, None], SHAPE[1], axis=1).astype(np.float32)
    mjm = foot_world(1.0, sole_xy=[(0.0, 0.0)], z0=0.0)
    m = mjw.put_model(mjm)
    d = mjw.make_data(mjm, nworld=1, nconmax=16, njmax=64)
    f = TerrainForces(mjm, m, d, heights, ORIGIN, RES, soil_map(),
                      type("C", (Cfg,), {"foot_geom_names": ["sole0"]})(), seed=1)
    f.install()
    x = 0.55  # the sphere's centre: (x, 0), (0.02 + gap) along the normal above the plane z = x tan 30
    qpos = d.qpos.numpy()
    qpos[0] = [x, x * math.tan(slope) + (0.02 + gap) / math.cos(slope)]
    d.qpos.assign(qpos)
    mjw.step(m, d)
    f.after_substep()
    assert bool(f.foot_near.numpy()[0, 0] & int(K.ON_FLOOR)) == on_floor
