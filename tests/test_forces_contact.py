"""Analytic sole contacts (external_forces/contact.py): the kernel against its numpy reference, and the
triangulated heightfield's geometry against hand-computed planes (flat ground, a stair riser, a gap)."""

import math

import numpy as np
import pytest
import warp as wp

from legged_gente.external_forces import contact as C

wp.config.quiet = True
RES = 0.1
ORIGIN = (-1.0, -1.0)


def terrain():
    """21 x 21 cells: flat at 0 for x < 0, a 0.15 m stair step from x = 0 to 0.1, a 0.3 m wide, 1 m deep gap
    at y in [0.3, 0.5] (vertices j = 13..15), and a 0.5 m pillar vertex at (-0.5, -0.5)."""
    h = np.zeros((21, 21), np.float32)
    h[11:, :] = 0.15  # x = ORIGIN + i * RES >= 0.1
    h[:, 14:17] = -1.0
    h[5, 5] = 0.5
    return h


@wp.kernel
def _contacts(heights: wp.array2d[float], origin: wp.vec2, res: float, centres: wp.array[wp.vec3],
              radius: float, rut: float, out: wp.array[wp.vec4]):
    i = wp.tid()
    out[i] = C.sphere_contact_fn(heights, origin, res, centres[i], radius, rut, radius, 1.0e10)


def kernel_contacts(h, centres, radius, rut):
    out = wp.zeros(len(centres), dtype=wp.vec4, device="cpu")
    wp.launch(_contacts, dim=len(centres), device="cpu",
              inputs=[wp.array(h, dtype=float, device="cpu"), wp.vec2(*ORIGIN), RES,
                      wp.array(np.asarray(centres, np.float32), dtype=wp.vec3, device="cpu"), radius, rut, out])
    return out.numpy()


def test_kernel_matches_reference_on_steps_gaps_pillars():
    h = terrain()
    rng = np.random.default_rng(0)
    xy = rng.uniform(-0.95, 0.95, (400, 2))
    z = np.array([C.surface_height(h, ORIGIN, RES, x, y)[0] for x, y in xy]) + rng.uniform(-0.05, 0.05, 400)
    centres = np.column_stack([xy, z])
    for rut in (0.0, 0.03):
        got = kernel_contacts(h, centres, 0.02, rut)
        hits = 0
        for c, g in zip(centres, got):
            dist, normal, _ = C.sphere_contact(h, ORIGIN, RES, c, 0.02, rut)
            if np.isinf(dist):
                assert g[3] >= 1e9
                continue
            hits += 1
            assert g[3] == pytest.approx(dist, abs=2e-5)
            np.testing.assert_allclose(g[:3], normal, atol=2e-3)
        assert hits > 150


def test_flat_ground_vertical_normal_at_any_depth():
    h = terrain()
    # 2 cm sphere at x = -0.35 (flat, far from the pillar): 1 cm above (out of reach: no contact)
    assert np.isinf(C.sphere_contact(h, ORIGIN, RES, (-0.35, -0.8, 0.03), 0.02)[0])
    # touching, 1 mm in, 5 cm and 20 cm deep
    for cz in (0.02, 0.019, -0.03, -0.18):
        dist, normal, pos = C.sphere_contact(h, ORIGIN, RES, (-0.35, -0.8, cz), 0.02)
        g = kernel_contacts(h, [(-0.35, -0.8, cz)], 0.02, 0.0)[0]
        assert dist == pytest.approx(cz - 0.02, abs=1e-6) and g[3] == pytest.approx(cz - 0.02, abs=1e-6)
        np.testing.assert_array_equal(normal, [0.0, 0.0, 1.0])
        np.testing.assert_allclose(g[:3], [0.0, 0.0, 1.0], atol=1e-7)
        assert pos[2] == pytest.approx(cz - 0.02 - 0.5 * dist)
    # a 12 cm rut: the surface under the sphere lowered by 0.12 m, so a sphere resting in it is 10 cm down
    dist, normal, _ = C.sphere_contact(h, ORIGIN, RES, (-0.35, -0.8, -0.10), 0.02, rut=0.12)
    assert dist == pytest.approx(0.0, abs=1e-6)


def test_stair_riser_gives_the_riser_normal():
    h = terrain()
    # the riser is the triangulated ramp from x = 0 (h = 0) to x = 0.1 (h = 0.15): slope 1.5, normal (-0.15, 0, 0.1)/|.|
    n = np.array([-0.15, 0.0, 0.1]) / math.hypot(0.15, 0.1)
    on_ramp = np.array([0.05, -0.75, 0.075])
    centre = on_ramp + n * (0.02 - 0.004)  # 4 mm into the riser
    dist, normal, _ = C.sphere_contact(h, ORIGIN, RES, centre, 0.02)
    assert dist == pytest.approx(-0.004, abs=1e-6)
    np.testing.assert_allclose(normal, n, atol=1e-6)
    g = kernel_contacts(h, [centre], 0.02, 0.0)[0]
    np.testing.assert_allclose(g, [*n, -0.004], atol=2e-5)


def test_sphere_over_a_gap_falls_in_and_lands_on_its_floor():
    h = terrain()
    # gap vertices j = 14..16 (y = 0.4 .. 0.6) at -1 m; its walls are ramps over y = 0.3..0.4 and 0.6..0.7.
    # A sphere at y = 0.5, level with the ground, is 0.1 m (horizontally) from the walls' tops: no contact
    dist, _, _ = C.sphere_contact(h, ORIGIN, RES, (-0.35, 0.5, 0.0), 0.02)
    assert np.isinf(dist)
    dist, normal, _ = C.sphere_contact(h, ORIGIN, RES, (-0.35, 0.5, -0.985), 0.02)  # 5 mm into the gap's floor
    assert dist == pytest.approx(-0.005, abs=1e-6)
    np.testing.assert_allclose(normal, [0, 0, 1], atol=1e-9)


def test_pillar_side_pushes_sideways_and_up():
    h = terrain()
    # vertex (5, 5) at (-0.5, -0.5) raised 0.5 m; the face of the triangle (5,5)-(6,5)-(6,6)... a sphere just
    # beside the pillar's +x face at mid-height is pushed along that face's normal: up and towards +x
    a, b, c = np.array([-0.5, -0.5, 0.5]), np.array([-0.4, -0.4, 0.0]), np.array([-0.4, -0.5, 0.0])
    n = np.cross(b - a, c - a)
    n = n / np.linalg.norm(n) * np.sign(np.cross(b - a, c - a)[2])
    on_face = (a + b + c) / 3
    centre = on_face + n * 0.019
    dist, normal, _ = C.sphere_contact(h, ORIGIN, RES, centre, 0.02)
    assert dist == pytest.approx(-0.001, abs=1e-6)
    np.testing.assert_allclose(normal, n, atol=1e-6)
    assert normal[0] > 0.9 and normal[2] > 0


def test_matches_mujoco_heightfield_collision_where_it_is_right():
    """A sphere 5 mm into a bumpy heightfield, over a triangle's centroid (where MuJoCo's prism collision is
    right): the analytic contact has MuJoCo's depth and normal, so both use the same surface and split."""
    import mujoco
    import mujoco_warp as mjw

    rng = np.random.default_rng(3)
    n = 8
    h = (0.3 * np.linspace(0, 1, n)[:, None] + 0.2 * np.linspace(0, 1, n)[None, :]
         + rng.uniform(0, 0.03, (n, n))).astype(np.float32)  # heights[i, j] at x = i * RES, y = j * RES
    lo, span = float(h.min()), float(h.max() - h.min())
    half = (n - 1) * RES / 2
    spec = mujoco.MjSpec()  # as sim.assembly builds the terrain: MuJoCo's rows run along y, data in [0, 1]
    hfield = spec.add_hfield(name="hf", nrow=n, ncol=n, size=[half, half, span, 0.1])
    hfield.userdata = ((h.T - lo) / span).ravel().tolist()
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_HFIELD, hfieldname="hf", pos=[half, half, lo])
    body = spec.worldbody.add_body(name="b")
    body.add_freejoint()
    body.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.02, 0, 0])
    mjm = spec.compile()
    poses = []
    for i, j, upper in ((1, 2, True), (3, 1, False), (4, 4, True), (5, 2, False), (2, 5, False)):
        a, b, c = C.triangle_vertices(h, (0.0, 0.0), RES, i, j, upper)
        normal = np.cross(b - a, c - a)
        normal = normal / np.linalg.norm(normal) * np.sign(normal[2])
        poses.append(((a + b + c) / 3 + normal * (0.02 - 0.005), normal))
    m = mjw.put_model(mjm)
    d = mjw.make_data(mjm, nworld=len(poses), nconmax=16, njmax=64)
    qpos = np.zeros((len(poses), 7), np.float32)
    qpos[:, :3] = [p for p, _ in poses]
    qpos[:, 3] = 1.0
    d.qpos.assign(qpos)
    mjw.forward(m, d)
    k = int(d.nacon.numpy()[0])
    world, dist, frame = d.contact.worldid.numpy()[:k], d.contact.dist.numpy()[:k], d.contact.frame.numpy()[:k]
    for w, (centre, normal) in enumerate(poses):
        deepest = np.argmin(np.where(world == w, dist, np.inf))
        ours, our_normal, _ = C.sphere_contact(h, (0.0, 0.0), RES, centre, 0.02)
        assert ours == pytest.approx(-0.005, abs=1e-5) and dist[deepest] == pytest.approx(ours, abs=5e-4)
        np.testing.assert_allclose(our_normal, normal, atol=1e-6)
        np.testing.assert_allclose(frame[deepest, 0], normal, atol=2e-3)


# --------------------------------------------------------------------------------------------------------
# A sphere inside a tall step (a foot pushed into a pillar or a wall): the nearest surface, never the top far
# above it, and a bounded push out


def tall_step(height=1.0):
    """21 x 21 cells, flat at 0 for x < 0, a ``height`` m step from x = 0 to 0.1 (the riser is the triangulated
    ramp of one cell, as a 1.5 m pillar's side in a 0.1 m heightfield)."""
    h = np.zeros((21, 21), np.float32)
    h[11:, :] = height
    return h


def test_sphere_inside_a_tall_step_is_pushed_out_of_its_nearest_face():
    h = tall_step(1.0)
    # Centre at x = 0.13, z = 0.9: 3 cm past the riser's top edge, 10 cm below the top. The riser is the plane
    # z = 10 x (x in [0, 0.1]), outward normal (-10, 0, 1)/sqrt(101); the centre lies |10 * 0.13 - 0.9| /
    # sqrt(101) = 0.0398 m behind it, its foot (0.13 - 0.0396, 0.9 + 0.0040) = (0.0904, 0.904) on the riser. The
    # top (z = 1) is 0.1 m above it, the edge (0.1, 1) sqrt(0.03^2 + 0.1^2) = 0.104 m away: the riser is nearest.
    n = np.array([-10.0, 0.0, 1.0]) / math.sqrt(101.0)
    depth = abs(10 * 0.13 - 0.9) / math.sqrt(101.0)
    centre = (0.13, -0.75, 0.9)
    dist, normal, _ = C.sphere_contact(h, ORIGIN, RES, centre, 0.02)
    assert dist == pytest.approx(-depth - 0.02, abs=1e-6)
    np.testing.assert_allclose(normal, n, atol=1e-6)
    g = kernel_contacts(h, [centre], 0.02, 0.0)[0]
    np.testing.assert_allclose(g, [*n, -depth - 0.02], atol=2e-5)
    # 2 cm under the top, 5 cm past the edge: the top is nearest (the riser is (1.5 - 0.98)/sqrt(101) = 5.2 cm away)
    dist, normal, _ = C.sphere_contact(h, ORIGIN, RES, (0.15, -0.75, 0.98), 0.02)
    assert dist == pytest.approx(-0.02 - 0.02, abs=1e-6)
    np.testing.assert_array_equal(normal, [0.0, 0.0, 1.0])


def test_contact_depth_is_continuous_through_a_tall_step():
    """The signed distance to a surface is 1-Lipschitz: a sphere moved by dx changes its contact distance by at
    most dx. Measuring the depth vertically jumps by ~0.9 m where the centre passes under the step's top."""
    h = tall_step(1.0)
    xs = np.linspace(-0.05, 0.25, 301)  # 1 mm apart, through the riser and under the top at z = 0.9 and 0.5
    for z in (0.9, 0.5):
        dists = [C.sphere_contact(h, ORIGIN, RES, (x, -0.75, z), 0.02, reach=1.0)[0] for x in xs]
        assert np.all(np.isfinite(dists))
        assert np.max(np.abs(np.diff(dists))) <= 1e-3 + 1e-9
        got = kernel_contacts(h, [(x, -0.75, z) for x in xs], 0.02, 0.0)[:, 3]
        near = np.asarray(dists) < 0.0  # within the kernel's reach (the radius)
        np.testing.assert_allclose(got[near], np.asarray(dists)[near], atol=2e-5)


def energy_gained_on_slides(m, d, forces, steps, g, z0):
    """Step a body on an x and a z slide (qpos: x, z) released at rest at height z0; the largest gain of its energy
    per unit mass, v^2 / 2 + g z, over ``steps`` substeps, per world (J/kg)."""
    import mujoco_warp as mjw

    gained = np.full(d.qpos.shape[0], -np.inf)
    for _ in range(steps):
        mjw.step(m, d)
        forces.after_substep()
        energy = 0.5 * np.sum(d.qvel.numpy() ** 2, axis=1) + g * d.qpos.numpy()[:, 1]
        gained = np.maximum(gained, energy - g * z0)
    return gained


def test_sphere_released_inside_a_pillar_is_not_launched():
    """A sole sphere released at rest with its centre 0.5 m inside a 1.5 m step (where a quadruped's foot ends
    up when its body, which does not collide, walks into a pillar) must come out, not fly.

    The most a contact may push it out at: MuJoCo's soft contact is a damped spring on the penetration r,
    a_ref = -b v - k r with b = 2 / (dmax tc), k = 1 / (dmax^2 tc^2 dr^2) (MuJoCo docs, "Solver parameters";
    defaults tc = 0.02 s, dr = 1, dmax = 0.95), so pushed out from depth D it moves at most at the speed where
    the spring and the damper balance: v = k D / b = D / (2 dmax tc dr^2). The sole contact reports at most
    sole_contact_max_depth D = 3 cm (the test's setting): v <= 0.03 / (2 * 0.95 * 0.02) = 0.79 m/s. Over T = 0.5 s
    the contact can raise the body at most T v and leave it at most that speed: its energy per unit mass,
    v^2 / 2 + g z, grows by at most g T v + v^2 / 2 (once out of the step, it falls: gravity keeps it)."""
    import mujoco
    import mujoco_warp as mjw

    from legged_gente.external_forces.field import ForcesConfig, TerrainForces
    from legged_gente.terrain.materials import MaterialMap

    tc, dmax, depth_cap, g = 0.02, 0.95, 0.03, 9.81
    v_max = depth_cap / (2 * dmax * tc)  # 0.79 m/s
    h = tall_step(1.5)
    xml = """<mujoco><option timestep="0.005"/>
      <asset><hfield name="hf" nrow="21" ncol="21" size="1 1 1.5 0.1"/></asset>
      <worldbody><geom name="terrain" type="hfield" hfield="hf"/>
        <body name="foot"><joint type="slide" axis="1 0 0"/><joint type="slide" axis="0 0 1"/>
          <geom name="sole" type="sphere" size="0.02" mass="2" contype="0" conaffinity="0"/></body>
      </worldbody></mujoco>"""
    mjm = mujoco.MjModel.from_xml_string(xml)
    mjm.hfield_data[:] = (h.T / 1.5).ravel()

    class Cfg(ForcesConfig):
        noise_std, wading, foot_geom_names, sole_contact_max_depth = 0.0, False, ["sole"], depth_cap

    # centres 2, 10 and 30 cm past the riser's top edge, 0.5 m below the top
    starts = [(0.12, 1.0), (0.2, 1.0), (0.4, 1.0)]
    m = mjw.put_model(mjm)
    d = mjw.make_data(mjm, nworld=len(starts), nconmax=8, njmax=32)
    forces = TerrainForces(mjm, m, d, h, ORIGIN, RES, MaterialMap.rigid(h.shape), Cfg(), seed=0)
    forces.install()
    d.qpos.assign(np.asarray(starts, np.float32))
    steps, dt = 100, 0.005
    gained = energy_gained_on_slides(m, d, forces, steps, g, z0=1.0)
    bound = g * steps * dt * v_max + 0.5 * v_max**2  # 3.9 + 0.3 J/kg
    assert np.all(gained <= bound), (gained, bound)
    assert np.all(d.qpos.numpy()[:, 1] < 1.0 + steps * dt * v_max)  # not above the step's top (1.5 m)
