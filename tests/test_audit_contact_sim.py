"""Analytic sole contacts, the TerrainForces config checks and the sim layer's per-body contact forces, each
against values worked out by hand: a sphere on a plane (MuJoCo's sphere-plane contact), the nearest point of a
heightfield's vertex and of its edge, Newton's equilibrium of a box at rest."""

import math
import types

import mujoco
import mujoco_warp as mjw
import numpy as np
import pytest
import torch
import warp as wp

from legged_gente.external_forces import contact as C
from legged_gente.external_forces.field import ForcesConfig, TerrainForces
from legged_gente.sim.backend import Simulation
from legged_gente.terrain.materials import MaterialMap

wp.config.quiet = True
R = 0.02  # sole sphere radius (m)


def sole_on_plane():
    """A plane at z = 0 and one sole sphere on x, y, z slides that MuJoCo does not collide (the sole contacts do)."""
    return mujoco.MjModel.from_xml_string(
        f'<mujoco><option timestep="0.002"/><worldbody><geom name="ground" type="plane" size="5 5 .1"/>'
        f'<body name="foot"><joint type="slide" axis="1 0 0"/><joint type="slide" axis="0 1 0"/>'
        f'<joint type="slide" axis="0 0 1"/><geom name="sole" type="sphere" size="{R}" mass="1" contype="0" '
        f'conaffinity="0"/></body></worldbody></mujoco>')


class PlaneCfg(ForcesConfig):
    noise_std, wading, foot_geom_names = 0.0, False, ["sole"]


def test_sole_contact_on_a_plane_is_mujocos_sphere_plane_contact():
    """TerrainForces on a plane (heights (1, 1), as its docstring gives a plane): the sole contact of a sphere of
    radius R with its centre at height z is MuJoCo's sphere-plane contact: dist = z - R, normal (0, 0, 1), point
    (x, y, (z - R) / 2) midway between the sphere's bottom and the plane. The plane's contact grid is one cell
    2e4 m wide; float32 points 1e4 m from its vertices tilted the normal by up to 8 degrees and moved the depth by
    0.1 mm, worst along the cell's diagonal x = y."""
    mjm = sole_on_plane()
    starts = [(0.3, 0.7, R - 0.001), (-2.1, 1.3, R - 0.004), (0.5, 0.5004, R - 0.001), (1.2345, 1.2341, R - 0.002),
              (-0.8, -0.8003, -0.005), (2.7, -1.9, R - 0.0005)]
    with wp.ScopedDevice("cpu"):
        m = mjw.put_model(mjm)
        d = mjw.make_data(mjm, nworld=len(starts), nconmax=16, njmax=64)
        forces = TerrainForces(mjm, m, d, np.zeros((1, 1), np.float32), (0.0, 0.0), 0.1, MaterialMap.rigid((1, 1)),
                               PlaneCfg(), seed=0)
        forces.install()
        d.qpos.assign(np.asarray(starts, np.float32))
        mjw.forward(m, d)
    n = int(d.nacon.numpy()[0])
    world = d.contact.worldid.numpy()[:n]
    assert sorted(world) == list(range(len(starts)))
    order = np.argsort(world)
    dist, pos = d.contact.dist.numpy()[:n][order], d.contact.pos.numpy()[:n][order]
    normal = d.contact.frame.numpy()[:n, 0][order]
    for (x, y, z), dd, p, nn in zip(starts, dist, pos, normal):
        assert dd == pytest.approx(z - R, abs=1e-6), (x, y, z)
        np.testing.assert_allclose(nn, [0.0, 0.0, 1.0], atol=1e-6, err_msg=str((x, y, z)))
        np.testing.assert_allclose(p, [x, y, (z - R) / 2], atol=1e-5)


def bump():
    """21 x 21 samples 0.1 m apart from (-1, -1), flat at 0 but for vertex (10, 10) at (0, 0) raised 0.2 m."""
    h = np.zeros((21, 21))
    h[10, 10] = 0.2
    return h


@wp.kernel
def _contact(heights: wp.array2d[float], origin: wp.vec2, res: float, centre: wp.vec3, out: wp.array[wp.vec4]):
    out[0] = C.sphere_contact_fn(heights, origin, res, centre, R, 0.0, R, 1.0e10)


def kernel_contact(h, centre):
    out = wp.zeros(1, dtype=wp.vec4, device="cpu")
    wp.launch(_contact, dim=1, device="cpu", inputs=[wp.array(np.asarray(h, np.float32), dtype=float, device="cpu"),
                                                      wp.vec2(-1.0, -1.0), 0.1, wp.vec3(*centre), out])
    return out.numpy()[0]


def test_a_sphere_on_a_peak_touches_its_vertex():
    """A sphere resting on the tip of a one-vertex peak (slopes 2 m/m on every side): the nearest point is the tip,
    the normal the direction from the tip to the centre, whatever the six triangles around the tip. Centre at the
    tip + (R - 1 mm) (0.3, 0.4, sqrt(0.75)): dist -1 mm."""
    u = np.array([0.3, 0.4, math.sqrt(0.75)])
    centre = np.array([0.0, 0.0, 0.2]) + (R - 0.001) * u
    dist, normal, pos = C.sphere_contact(bump(), (-1.0, -1.0), 0.1, centre, R)
    assert dist == pytest.approx(-0.001, abs=1e-9)
    np.testing.assert_allclose(normal, u, atol=1e-9)
    np.testing.assert_allclose(pos, [0.0, 0.0, 0.2] - 0.0005 * u, atol=1e-9)
    np.testing.assert_allclose(kernel_contact(bump(), centre), [*u, -0.001], atol=2e-6)


def test_a_sphere_past_the_edge_of_the_map_touches_the_edge():
    """Flat ground at 0 ends at x = 1 (the last samples): a sphere centred 5 mm past it, 19 mm up, touches the edge
    line (MuJoCo's heightfield ends there too): distance sqrt(0.005^2 + 0.019^2) - R, normal along (0.005, 0, 0.019)."""
    h = np.zeros((21, 21))
    centre = (1.005, 0.33, 0.019)
    d = math.hypot(0.005, 0.019)
    n = np.array([0.005, 0.0, 0.019]) / d
    dist, normal, _ = C.sphere_contact(h, (-1.0, -1.0), 0.1, centre, R)
    assert dist == pytest.approx(d - R, abs=1e-9)
    np.testing.assert_allclose(normal, n, atol=1e-9)
    np.testing.assert_allclose(kernel_contact(h, centre), [*n, d - R], atol=2e-6)


# --------------------------------------------------------------------------------------------------------
# config checks


def forces_with(**values):
    mjm = sole_on_plane()
    with wp.ScopedDevice("cpu"):
        m = mjw.put_model(mjm)
        d = mjw.make_data(mjm, nworld=1, nconmax=8, njmax=32)
        cfg = type("C", (PlaneCfg,), values)()
        return TerrainForces(mjm, m, d, np.zeros((5, 5), np.float32), (-1.0, -1.0), 0.5, MaterialMap.rigid((5, 5)),
                             cfg)


@pytest.mark.parametrize("name", ["water_density", "noise_std", "friction_reference", "sinkage_load_tau"])
def test_infinite_settings_are_refused(name):
    """inf passes every '> 0' check: water_density inf gives infinite buoyancy, noise_std inf NaN draws,
    friction_reference inf frictionless contacts (map friction / inf = 0), sinkage_load_tau inf a rut that never
    follows the load."""
    with pytest.raises(ValueError, match=f"forces.{name}=inf must be a finite number"):
        forces_with(**{name: math.inf})


@pytest.mark.parametrize("given", [{"sole_length": 0.2}, {"sole_width": 0.08}])
def test_a_sole_size_on_one_side_only_is_refused(given):
    """sole_length without sole_width (or the reverse) was ignored: the sole came from the geoms' footprint (here a
    disc of radius 2 cm), so the Bekker pressure used another area than the one configured."""
    with pytest.raises(ValueError, match="give both"):
        forces_with(**given)
    f = forces_with(sole_length=0.2, sole_width=0.08)
    assert f.sole_area == pytest.approx(0.2 * 0.08)


def test_an_infinite_sole_is_refused():
    """An infinite sole area makes every Bekker pressure 0: no sinkage, silently."""
    with pytest.raises(ValueError, match="sole size must be a finite number > 0 m"):
        forces_with(sole_length=math.inf, sole_width=0.08)


def test_the_geoms_footprint_is_used_when_neither_is_given():
    f = forces_with()
    assert f.sole_disc and f.sole_area == pytest.approx(math.pi * R**2)


# --------------------------------------------------------------------------------------------------------
# sim layer: per-body contact forces


@pytest.mark.parametrize("cone", ["pyramidal", "elliptic"])
def test_contact_force_on_a_box_at_rest_on_a_slope_carries_its_weight(cone):
    """A 2 kg box at rest on a plane tilted 20 deg about x (friction 1 > tan 20 deg = 0.36): Newton, the contacts'
    total force on it is its weight reversed, (0, 0, m g) in the world frame, the friction's share along the slope
    included (m g sin 20 = 6.7 N); the world body gets the opposite."""
    mass, g, tilt = 2.0, 9.81, math.radians(20.0)
    normal = (0.0, -math.sin(tilt), math.cos(tilt))
    centre = 0.05 * np.array(normal)  # half the box's height along the plane's normal
    mjm = mujoco.MjModel.from_xml_string(
        f'<mujoco><option timestep="0.002" cone="{cone}"/><worldbody>'
        f'<geom type="plane" size="3 3 .1" zaxis="{normal[0]} {normal[1]} {normal[2]}" friction="1 0.005 0.0001"/>'
        f'<body name="box" pos="{centre[0]} {centre[1]} {centre[2] - 0.0004}" euler="{math.degrees(tilt)} 0 0">'
        f'<freejoint/><geom type="box" size="0.1 0.08 0.05" mass="{mass}" friction="1 0.005 0.0001"/></body>'
        f'</worldbody></mujoco>')
    sim = Simulation(mjm, 2, "cpu", types.SimpleNamespace(cuda_graph="off", nconmax=32, njmax=128),
                     batch_model=False)
    for _ in range(50):
        sim.step(4)  # 0.4 s: settled
    box = mjm.body("box").id
    force = sim.body_contact_force
    assert float(sim.qvel.abs().max()) < 2e-3  # at rest (MuJoCo's soft friction creeps mm/s at most)
    expected = torch.tensor([0.0, 0.0, mass * g])
    for w in range(2):
        torch.testing.assert_close(force[w, box], expected, atol=0.02 * mass * g, rtol=0.0)
        torch.testing.assert_close(force[w, 0], -expected, atol=0.02 * mass * g, rtol=0.0)


def test_a_soil_without_bekker_sinkage_for_this_sole_is_refused():
    """Bekker's p = (kc / b + kphi) z^n gives no sinkage where kc / b + kphi <= 0 (kc may be negative in Wong's
    fits): z = (p / k)^(1/n) is NaN for k < 0. The lone 2 cm sphere sole is a disc of b = its radius 0.02 m, so
    kc = -1e3 N/m^(n+1) with kphi = 4e4 N/m^(n+2) gives -1e3 / 0.02 + 4e4 = -1e4 N/m^(n+2): refused, naming both."""
    from legged_gente.terrain.soil import SOIL_PRESETS, register_custom_soil

    register_custom_soil("t_negative_k", kc=-1.0e3, kphi=4.0e4, n=1.1, c=1.0e3, mu=0.5, K=0.025, bulldoze_c=0.0,
                         bulldoze_g=0.0)
    try:
        mjm = sole_on_plane()
        mat = MaterialMap.rigid((1, 1))
        mat.soil[:] = mat.soil_index("t_negative_k")
        with wp.ScopedDevice("cpu"):
            m = mjw.put_model(mjm)
            d = mjw.make_data(mjm, nworld=1, nconmax=16, njmax=64)
            with pytest.raises(ValueError, match=r"t_negative_k.*kc/b \+ kphi = -1e\+04"):
                TerrainForces(mjm, m, d, np.zeros((1, 1), np.float32), (0.0, 0.0), 0.1, mat, PlaneCfg(), seed=0)
    finally:
        SOIL_PRESETS.pop("t_negative_k")


def test_a_geom_listed_twice_is_refused():
    """A leg or foot geom named twice would get its forces twice (two strips of the same leg in the water)."""
    mjm = sole_on_plane()
    cfg = type("TwiceCfg", (PlaneCfg,), {"foot_geom_names": ["sole", "sole"]})()
    with wp.ScopedDevice("cpu"):
        m = mjw.put_model(mjm)
        d = mjw.make_data(mjm, nworld=1, nconmax=16, njmax=64)
        with pytest.raises(ValueError, match=r"forces.foot_geom_names lists 'sole' 2 times; list each geom once"):
            TerrainForces(mjm, m, d, np.zeros((1, 1), np.float32), (0.0, 0.0), 0.1, MaterialMap.rigid((1, 1)), cfg)
