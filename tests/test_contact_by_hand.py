"""Foot-terrain contact checked by hand on tiny CPU sims: a sole point (a sphere on three slide joints, so it
slides and never rolls) on heightfields laid down by sim/assembly.py, touching them through the analytic sole
contacts of external_forces/contact.py (or MuJoCo's own heightfield collision where said). Every expected value
is worked out in the test from MuJoCo's documented soft-contact law or from Coulomb friction."""

import math
from types import SimpleNamespace

import mujoco
import mujoco_warp as mjw
import numpy as np
import pytest
import warp as wp

from legged_gente.external_forces import contact as C
from legged_gente.external_forces.field import ForcesConfig, TerrainForces
from legged_gente.sim.assembly import _add_terrain
from legged_gente.terrain.materials import MaterialMap

wp.config.quiet = True
G, DT, R, MASS = 9.81, 0.002, 0.02, 1.0
RES, ORIGIN = 0.1, (-1.0, -1.0)


def foot_model(heights, mu, origin=ORIGIN, piece=20.0, analytic=True, capsule_half=0.0):
    """Terrain (as the env lays it down) + one foot body on x, y, z slide joints whose sole is a sphere (or a
    capsule lying along x); analytic: the sole does not collide in MuJoCo (the sole contacts own it)."""
    spec = mujoco.MjSpec()
    spec.option.timestep = DT
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    _add_terrain(spec, SimpleNamespace(static_friction=mu, hfield_piece_size=piece),
                 SimpleNamespace(height_field=heights, resolution=RES, origin_xy=origin))
    body = spec.worldbody.add_body(name="foot")
    for axis in ((1, 0, 0), (0, 1, 0), (0, 0, 1)):
        body.add_joint(type=mujoco.mjtJoint.mjJNT_SLIDE, axis=axis)
    collide = (0, 0) if analytic else (2, 0)
    if capsule_half:
        body.add_geom(name="sole", type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[R, 0, 0], mass=MASS,
                      fromto=[-capsule_half, 0, 0, capsule_half, 0, 0], contype=collide[0], conaffinity=collide[1],
                      friction=[mu, 0.005, 0.0001])
    else:
        body.add_geom(name="sole", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[R, 0, 0], mass=MASS,
                      contype=collide[0], conaffinity=collide[1], friction=[mu, 0.005, 0.0001])
    return spec.compile()


def run(mjm, heights, starts, mu, steps, origin=ORIGIN, friction_map=None, analytic=True, qvel=None):
    """Step worlds starting at ``starts`` (x, y, z of the body); returns (m, d, body velocities per step)."""

    class Cfg(ForcesConfig):
        noise_std, wading, foot_geom_names, friction_reference = 0.0, False, ["sole"], mu
        friction_from_map = friction_map is not None

    material = MaterialMap.rigid(heights.shape, friction=mu)
    if friction_map is not None:
        material.friction[:] = friction_map
    m = mjw.put_model(mjm)
    d = mjw.make_data(mjm, nworld=len(starts), nconmax=16, njmax=64)
    forces = TerrainForces(mjm, m, d, heights, origin, RES, material, Cfg(), seed=0) if analytic else None
    if forces is not None:
        forces.install()
    d.qpos.assign(np.asarray(starts, np.float32))
    if qvel is not None:
        d.qvel.assign(np.asarray(qvel, np.float32))
    velocities = []
    for _ in range(steps):
        mjw.step(m, d)
        if forces is not None:
            forces.after_substep()
        velocities.append(d.qvel.numpy().copy())
    return m, d, np.array(velocities)


def contacts(d):
    n = int(d.nacon.numpy()[0])
    c = d.contact
    return (c.worldid.numpy()[:n], c.dist.numpy()[:n], c.pos.numpy()[:n], c.frame.numpy()[:n, 0],
            c.friction.numpy()[:n])


def resting_depth(mass, g=G, tc=0.02, dr=1.0, solimp=(0.9, 0.95, 0.001, 0.5, 2.0)):
    """Penetration of a body at rest on one frictionless-direction contact, from MuJoCo's soft-contact law (docs,
    "Computation" > "Soft constraints"): a_ref = -k d(r) r with k = 1 / (dmax^2 tc^2 dr^2), R = (1 - d) / d * A,
    A = 1 / m (the contact acts through the centre of mass). At rest f = m g and f = (a_ref + g) / (A + R), so
    k d r = g (1 - d) / d. d(r) is solimp's sigmoid; solved by fixed point."""
    d0, dmax, width, mid, power = solimp
    k = 1.0 / (dmax**2 * tc**2 * dr**2)
    r = 0.0
    for _ in range(200):
        x = min(r / width, 1.0)
        y = x**power / mid ** (power - 1) if x <= mid else 1 - (1 - x) ** power / (1 - mid) ** (power - 1)
        imp = d0 + y * (dmax - d0)
        r = g * (1 - imp) / (k * imp**2)
    return r


def test_sphere_sole_rests_on_flat_ground_at_its_height():
    # ground at h = 0.3 m; a 2 cm, 1 kg sphere put down touching it settles r_soft deeper
    h = np.full((21, 21), 0.3, np.float32)
    depth = resting_depth(MASS)
    assert 2e-4 < depth < 6e-4  # 0.37 mm with MuJoCo's default solref / solimp
    mjm = foot_model(h, 1.0)
    _, d, vel = run(mjm, h, [(0.03, -0.04, 0.3 + R)], 1.0, 400)
    q = d.qpos.numpy()[0]
    assert q[2] == pytest.approx(0.3 + R - depth, abs=2e-5)
    np.testing.assert_allclose(q[:2], [0.03, -0.04], atol=1e-6)
    world, dist, pos, normal, _ = contacts(d)
    assert len(world) == 1 and dist[0] == pytest.approx(-depth, abs=2e-5)
    np.testing.assert_allclose(normal[0], [0, 0, 1], atol=1e-6)
    # contact point midway between the sphere's bottom and the ground (MuJoCo's convention)
    np.testing.assert_allclose(pos[0], [0.03, -0.04, 0.3 - depth / 2], atol=2e-5)


def slope(grad):
    """Ground z = gx x + gy y + 0.2 sampled on the 21 x 21 grid: a plane, whatever the triangulation."""
    i, j = np.meshgrid(np.arange(21), np.arange(21), indexing="ij")
    x, y = ORIGIN[0] + RES * i, ORIGIN[1] + RES * j
    return (grad[0] * x + grad[1] * y + 0.2).astype(np.float32)


@pytest.mark.parametrize("mu", [0.5, 0.1])
def test_on_a_slope_the_normal_tilts_and_coulomb_decides_stick_or_slide(mu):
    """Slope gradient (0.24, -0.18): tan a = 0.3, a = 16.7 deg. Normal (-dz/dx, -dz/dy, 1) / |.|. With mu = 0.5 >
    tan a the sole stays (MuJoCo's soft friction lets it creep, mm/s); with mu = 0.1 < tan a it slides down the
    gradient at g (sin a - mu cos a) = 1.96 m/s^2."""
    grad = np.array([0.24, -0.18])
    a = math.atan(np.hypot(*grad))
    normal = np.array([-grad[0], -grad[1], 1.0]) / math.sqrt(1 + grad @ grad)
    down = np.array([-grad[0], -grad[1], -(grad @ grad)]) / np.linalg.norm([*grad, grad @ grad])
    h = slope(grad)
    start = np.array([0.0, 0.0, 0.2]) + R * normal  # touching the slope at (0, 0)
    mjm = foot_model(h, mu)
    _, d, vel = run(mjm, h, [start], mu, 250)
    world, _, _, frames, friction = contacts(d)
    if len(world):
        np.testing.assert_allclose(frames[0], normal, atol=1e-5)
    along = vel[:, 0] @ down
    if mu > math.tan(a):
        assert np.linalg.norm(d.qpos.numpy()[0] - start) < 5e-3 and abs(along[-1]) < 5e-3
    else:
        t = 150 * DT  # from step 100 (settled) to 250
        assert (along[-1] - along[99]) / t == pytest.approx(G * (math.sin(a) - mu * math.cos(a)), rel=0.02)


def test_capsule_straddling_a_step_touches_only_the_upper_level():
    """A 0.15 m step: ground 0 for x <= 0, 0.15 for x >= 0.1 (the riser a one-cell ramp). A capsule (ends at
    x = -0.05 and 0.15) rests with its +x end on the top: one contact, at that end's bottom; its -x end hangs
    over the lower level (0.17 m above it, 0.135 m from the riser's ramp)."""
    h = np.zeros((21, 21), np.float32)
    h[11:, :] = 0.15  # x = -1 + 0.1 i >= 0.1
    mjm = foot_model(h, 1.0, capsule_half=0.1)
    centre = (0.05, 0.0, 0.15 + R - 0.001)  # 1 mm into the top
    m, d, _ = run(mjm, h, [centre], 1.0, 1)
    # the contacts of the step's collision were made at the start pose
    world, dist, pos, frames, _ = contacts(d)
    assert len(world) == 1
    assert dist[0] == pytest.approx(-0.001, abs=1e-6)
    np.testing.assert_allclose(frames[0], [0, 0, 1], atol=1e-6)
    np.testing.assert_allclose(pos[0], [0.15, 0.0, 0.15 - 0.0005], atol=1e-6)


def test_contact_friction_is_the_cells_material_friction():
    """Ground friction 0.8 (the geoms'), material map 0.3 for x >= 0 (vertices i >= 10), 0.8 elsewhere: a sole at
    x = 0.32 gets 0.3, one at x = -0.42 gets 0.8 (rest of the map scaled by map / friction_reference = 1)."""
    h = np.zeros((21, 21), np.float32)
    fmap = np.full((21, 21), 0.8, np.float32)
    fmap[10:, :] = 0.3
    mjm = foot_model(h, 0.8)
    starts = [(0.32, 0.11, R - 0.001), (-0.42, 0.11, R - 0.001)]
    _, d, _ = run(mjm, h, starts, 0.8, 1, friction_map=fmap)
    world, _, _, _, friction = contacts(d)
    assert sorted(world) == [0, 1]
    np.testing.assert_allclose(friction[np.argsort(world), :2], [[0.3, 0.3], [0.8, 0.8]], atol=1e-6)


def test_mujocos_surface_is_the_sole_contacts_surface_with_an_offset_origin_and_pieces():
    """A bumpy terrain with origin (-3.7, 5.2) laid down in 0.5 m pieces: MuJoCo's ray-cast surface at random points
    (inside cells, off the vertices) equals the triangulated surface the sole contacts use (same origin, same split
    of each cell), and at the vertices the numpy heights."""
    rng = np.random.default_rng(7)
    origin = (-3.7, 5.2)
    i, j = np.meshgrid(np.arange(17), np.arange(12), indexing="ij")
    h = (0.05 * i - 0.03 * j + rng.uniform(-0.04, 0.04, i.shape) + 1.0).astype(np.float64)
    spec = mujoco.MjSpec()
    _add_terrain(spec, SimpleNamespace(static_friction=1.0, hfield_piece_size=0.5),
                 SimpleNamespace(height_field=h, resolution=RES, origin_xy=origin))
    mjm = spec.compile()
    data = mujoco.MjData(mjm)
    mujoco.mj_forward(mjm, data)
    geomid = np.zeros(1, np.int32)

    def ray(x, y):
        dist = mujoco.mj_ray(mjm, data, np.array([x, y, 10.0]), np.array([0.0, 0.0, -1.0]), None, 1, -1, geomid)
        assert geomid[0] >= 0, (x, y)
        return 10.0 - dist

    for x, y in rng.uniform((origin[0] + 0.01, origin[1] + 0.01), (origin[0] + 1.59, origin[1] + 1.09), (60, 2)):
        assert ray(x, y) == pytest.approx(C.surface_height(h, origin, RES, x, y)[0], abs=1e-5), (x, y)
    for a, b in [(3, 4), (7, 2), (12, 9), (15, 1)]:
        x, y = origin[0] + a * RES + 1e-5, origin[1] + b * RES + 1e-5  # 10 um inside the cell (i, j)
        assert ray(x, y) == pytest.approx(h[a, b], abs=1e-4)


@pytest.mark.parametrize("analytic", [True, False])
def test_a_sole_sliding_across_a_seam_of_the_pieces_does_not_bump(analytic):
    """Flat ground at 0.1 m in 1 m pieces (seam at x = 0). A sole sliding at 1.5 m/s in +x from x = -0.4 with
    mu = 0.2 decelerates at mu g = 1.962 m/s^2 (Coulomb), crossing the seam at t ~ 0.3 s. It moves exactly as on
    the same ground in one piece: the pieces join without a step or a ridge. (Sliding under MuJoCo's soft elliptic
    cone makes a sole chatter a few cm/s up and down on any ground, one piece or many, and for MuJoCo's own
    collision as much as for the sole contacts: the one-piece run is the reference, not zero.)"""
    h = np.full((21, 21), 0.1, np.float32)
    mu, v0 = 0.2, 1.5
    start = (-0.4, 0.05, 0.1 + R - resting_depth(MASS))
    runs = {}
    for piece in (1.0, 20.0):
        mjm = foot_model(h, mu, piece=piece, analytic=analytic)
        assert mjm.nhfield == (4 if piece == 1.0 else 1)
        _, d, vel = run(mjm, h, [start], mu, 300, analytic=analytic, qvel=[(v0, 0.0, 0.0)])
        runs[piece] = d.qpos.numpy()[0], vel[:, 0]
    (q, vel), (q_one, vel_one) = runs[1.0], runs[20.0]
    assert q[0] > 0.05  # crossed the seam
    assert v0 - vel[-1, 0] == pytest.approx(mu * G * 300 * DT, rel=0.03)  # speed lost: 1.18 m/s
    np.testing.assert_allclose(vel, vel_one, atol=1e-3)
    np.testing.assert_allclose(q, q_one, atol=1e-5)
