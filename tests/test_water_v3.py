"""Water forces, third audit: a partly wet sphere foot's drag area is its wetted frontal area (the wet cap projected
along the relative flow), and a leg whose middle alone is over water (a stream narrower than the leg) gets its
strip-theory loads. Expected values from the geometry by hand."""

import math

import mujoco_warp as mjw
import numpy as np
import pytest
from test_forces_water import DIAGONAL_M, RHO, Cfg, G, assign, make, model, water

from legged_gente.external_forces import water_models as WM

R_BALL, CD_SPHERE = 0.05, 0.47


def segment_area(r, h):
    """Circle of radius r below a chord h above its centre: r^2 acos(-h/r) + h sqrt(r^2 - h^2) (circular segment)."""
    return r * r * math.acos(-h / r) + h * math.sqrt(r * r - h * h)


def brute_frontal_area(r, depth, v, n=1201):
    """The wet cap (the sphere below the surface ``depth`` above its lowest point) projected on the plane normal to v,
    by counting grid points of that plane: the line along v through a point meets the cap iff the lowest point of
    its chord through the sphere lies below the surface."""
    v = np.asarray(v, float) / np.linalg.norm(v)
    e1 = np.cross(v, [0.0, 0.0, 1.0]) if abs(v[2]) < 0.9 else np.cross(v, [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(v, e1)
    g = (np.arange(n) + 0.5) / n * 2 * r - r
    u, w = np.meshgrid(g, g, indexing="ij")
    half_chord = np.sqrt(np.maximum(r * r - u * u - w * w, 0.0))
    lowest = u * e1[2] + w * e2[2] - abs(v[2]) * half_chord
    covered = (u * u + w * w <= r * r) & (lowest <= depth - r)
    return covered.sum() * (2 * r / n) ** 2


def test_sphere_frontal_area_by_hand():
    r = R_BALL
    d = 0.25 * r  # wet 1/4 of its radius: the surface h = -0.75 r from the centre
    # horizontal flow: the circle of the vertical mid-plane below the waterline (a circular segment)
    horizontal = segment_area(r, -0.75 * r)
    assert WM.sphere_wet_frontal_area(r, d, [1.0, 0.0, 0.0]) == pytest.approx(horizontal, rel=1e-9)
    assert WM.sphere_wet_frontal_area(r, d, [0.3, -0.4, 0.0]) == pytest.approx(horizontal, rel=1e-9)
    # which is not the wet volume share of pi r^2 that the drag used: d^2 (3r - d) / (4 r^3) = 0.043 against 0.072
    volume_share = d * d * (3 * r - d) / (4 * r**3)
    assert horizontal / (math.pi * r * r) == pytest.approx(0.0721, abs=1e-4)
    assert volume_share == pytest.approx(0.0430, abs=1e-4)
    # vertical flow: the disk of the waterline circle, pi (r^2 - (r - d)^2)
    assert WM.sphere_wet_frontal_area(r, d, [0.0, 0.0, -2.0]) == pytest.approx(math.pi * (r * r - (r - d) ** 2))
    # wet to the centre, flow at 60 deg from the vertical: the lower half of the silhouette disk, pi r^2 / 2, and
    # beyond it the lower half of the waterline disk seen at that angle, an ellipse of axes r cos(60), r
    v60 = [math.sin(math.pi / 3), 0.0, math.cos(math.pi / 3)]
    assert WM.sphere_wet_frontal_area(r, r, v60) == pytest.approx(math.pi * r * r / 2 * (1 + 0.5))
    # dry and wholly wet
    assert WM.sphere_wet_frontal_area(r, 0.0, [1.0, 0.0, 0.0]) == 0.0
    assert WM.sphere_wet_frontal_area(r, 2.5 * r, [0.2, 0.3, 0.9]) == pytest.approx(math.pi * r * r)
    # any direction and depth against the projection counted point by point
    rng = np.random.default_rng(5)
    for _ in range(8):
        v, depth = rng.normal(size=3), rng.uniform(0.0, 2 * r)
        assert WM.sphere_wet_frontal_area(r, depth, v) == pytest.approx(brute_frontal_area(r, depth, v), rel=2e-3,
                                                                        abs=2e-3 * r * r)


@pytest.mark.filterwarnings(DIAGONAL_M)
def test_partly_wet_sphere_foot_drag_uses_its_wetted_frontal_area():
    # A sphere foot (r = 5 cm) on three slides, gravity off (no buoyancy), still water (no flow inertia), wet to a
    # quarter of its radius (or 1.5 r), moving at v: the standard drag equation with the projected frontal area,
    # F = -0.5 rho cd A |v| v (Hoerner, Fluid-Dynamic Drag, ch. 3; cd 0.47). Its added-mass force is 0 at zero
    # acceleration on slides.
    r, z0 = R_BALL, 1.0
    slides = "".join(f'<joint type="slide" axis="{a}"/>' for a in ("1 0 0", "0 1 0", "0 0 1"))
    mjm = model(f'<body pos="0 0 {z0}">{slides}<geom name="ball" type="sphere" size="{r}" density="3000"/></body>')
    cfg = type("C", (Cfg,), {"leg_geom_names": [], "foot_geom_names": ["ball"]})
    cases = [  # (depth of the lowest point, velocity, frontal area by hand)
        (0.25 * r, [1.0, 0.0, 0.0], segment_area(r, -0.75 * r)),
        (0.25 * r, [0.0, 0.0, 0.8], math.pi * (r * r - (0.75 * r) ** 2)),
        (0.25 * r, [0.6, 0.3, -0.74], brute_frontal_area(r, 0.25 * r, [0.6, 0.3, -0.74])),
        (1.5 * r, [0.0, -0.7, 0.0], segment_area(r, 0.5 * r)),
        (1.5 * r, [-0.5, 0.2, 0.6], brute_frontal_area(r, 1.5 * r, [-0.5, 0.2, 0.6])),
    ]
    surface = z0 - r + 0.25 * r
    m, d, f = make(mjm, water(surface=surface), cfg, nworld=len(cases))
    assign(d.qpos, [[0.0, 0.0, 0.25 * r - depth] for depth, _, _ in cases])
    assign(d.qvel, [v for _, v, _ in cases])
    mjw.step(m, d)
    got = f.foot_water_force.numpy()[:, 0]
    for w, (_, v, area) in enumerate(cases):
        v = np.asarray(v)
        expect = -0.5 * RHO * CD_SPHERE * area * np.linalg.norm(v) * v
        np.testing.assert_allclose(got[w], expect, rtol=3e-3, atol=1e-4)


# ----------------------------------------------------------------------- a leg over a stream narrower than itself

HALF, R_LEG = 0.1125, 0.03  # the middle Gauss slice spans s = +-(4/9) HALF = +-0.05 m: one 0.1 m cell


def strip_of_water(level):
    """Dry everywhere (surface 1 m under the ground) but the cells of x index 20, the samples at x = 0: the water
    reaches over x in [-0.05, 0.05) (a stream one cell wide along y)."""
    mat = water(surface=-1.0)
    mat.water_surface[20, :] = level
    return mat


def test_reference_leg_across_a_one_cell_stream_by_hand():
    # A horizontal cylinder along x centred over the stream, its ends (x = +-0.1125) over dry cells, all under the
    # stream's surface: the slice over the stream (the middle one, 0.1 m long) is wholly wet, V = pi r^2 0.1.
    res, origin = 0.1, -2.0

    def surface_at(p):
        return 2.0 if round((p[0] - origin) / res) == 20 else -1.0

    slices = WM.segment_slices([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], R_LEG, HALF, surface_at)
    assert sum(v for _, _, v in slices) == pytest.approx(math.pi * R_LEG**2 * 0.1, rel=1e-6)


@pytest.mark.filterwarnings(DIAGONAL_M)
def test_leg_across_a_one_cell_stream_gets_buoyancy_of_its_wet_part():
    # The same leg at rest in the simulation (gravity on, on a vertical slide): Archimedes on the 0.1 m over the
    # stream, rho g pi r^2 0.1 (12 cm of leg over dry cells on each side feel nothing), not 0.
    mjm = model(f'<body pos="0 0 1"><joint type="slide" axis="0 0 1"/><geom name="leg" type="cylinder" '
                f'size="{R_LEG} {HALF}" euler="0 90 0" density="3000"/></body>', gravity=True)
    m, d, f = make(mjm, strip_of_water(2.0))
    mjw.step(m, d)
    fz = f.seg_force.numpy()[0, 0]
    np.testing.assert_allclose(fz, [0.0, 0.0, RHO * G * math.pi * R_LEG**2 * 0.1], rtol=1e-4, atol=1e-6)
    # its added mass across the axis, ca rho pi r^2 0.1 (ca = 1), enters M: the slide's diagonal grows by it
    m.callback.passive = None
    mjw.forward(m, d)
    m0 = d.M.numpy()[0, 0]
    f.passive(m, d)
    assert d.M.numpy()[0, 0] - m0 == pytest.approx(RHO * math.pi * R_LEG**2 * 0.1, rel=1e-4)


@pytest.mark.filterwarnings(DIAGONAL_M)
@pytest.mark.parametrize("leg_type", ["cylinder", "capsule"])
def test_foot_ball_inside_a_legs_straight_part_adds_no_second_added_mass(leg_type):
    # A ball (r 3 cm) wholly inside the straight part of a welded leg (R 4 cm, half-length 15 cm), all under water,
    # on an x slide: the leg's strips already hold that volume, so the added mass along x is the leg's alone,
    # C_a rho pi R^2 L with C_a = 1 for a circular cylinder across its axis (Newman, Marine Hydrodynamics, sec. 4.13);
    # counting the ball again would add its 0.5 rho V (a sphere's added mass).
    big, half, r = 0.04, 0.15, 0.03
    mjm = model(f'<body pos="0 0 1"><joint type="slide" axis="1 0 0"/>'
                f'<geom name="leg" type="{leg_type}" size="{big} {half}" density="3000"/>'
                f'<geom name="ball" type="sphere" pos="0 0 0.05" size="{r}" density="3000"/></body>')
    cfg = type("C", (Cfg,), {"leg_geom_names": ["leg"], "foot_geom_names": ["ball"]})
    m, d, f = make(mjm, water(surface=3.0), cfg)
    m.callback.passive = None
    mjw.forward(m, d)
    m_body = d.M.numpy()[0, 0].copy()
    f.passive(m, d)
    added = d.M.numpy()[0, 0] - m_body
    assert added == pytest.approx(RHO * math.pi * big * big * 2 * half, rel=1e-4)
