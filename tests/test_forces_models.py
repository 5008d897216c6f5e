"""Warp device formulas against the numpy references, and the references against textbook values."""

import re

import numpy as np
import pytest
import warp as wp

from legged_gente.external_forces import kernels as K
from legged_gente.external_forces import models
from legged_gente.terrain.soil import SOIL_PRESETS, preset_table, register_custom_soil

wp.config.quiet = True


@wp.kernel
def _eval(
    x: wp.array2d[float],  # columns: rho cd r L v | g | ca | kind t amp omega phase | p kc kphi n width | bc bg z |
    #                        c mu fn j K (A = x[:, 16] ** 2 * 2, cap 2)
    paper: int,
    out: wp.array2d[float],
):
    i = wp.tid()
    out[i, 0] = K.cylinder_drag_fn(x[i, 0], x[i, 1], x[i, 2], x[i, 3], x[i, 4], paper)
    out[i, 1] = K.flow_force_fn(int(x[i, 7]), x[i, 8], x[i, 9], x[i, 10], x[i, 11])
    out[i, 2] = K.bekker_sinkage_fn(x[i, 12], x[i, 13], x[i, 14], x[i, 15], x[i, 16])
    out[i, 3] = K.bulldozing_force_fn(x[i, 17], x[i, 18], x[i, 16], x[i, 19])
    area = x[i, 16] * x[i, 16] * 2.0
    out[i, 4] = K.shear_strength_fn(x[i, 24], x[i, 20], area, x[i, 21])
    out[i, 5] = K.soil_traction_fn(x[i, 24], x[i, 20], area, x[i, 21], x[i, 22], x[i, 23])
    out[i, 6] = K.soil_friction_fn(x[i, 24], x[i, 20], area, x[i, 21], x[i, 22], x[i, 23], x[i, 6], out[i, 3],
                                   2.0)  # ca's column as the surface's friction


@pytest.mark.parametrize("paper", [0, 1])
def test_kernels_match_references(paper):
    rng = np.random.default_rng(paper)
    n = 256
    u = lambda lo, hi: rng.uniform(lo, hi, n)  # noqa: E731
    cols = [u(900, 1100), u(0.8, 1.3), u(0.01, 0.1), u(0, 0.5), u(-2, 2), u(9, 10), u(0.5, 1.5),
            rng.integers(0, 3, n).astype(float), u(0, 20), u(-1, 1), u(0, 3), u(-3, 3),
            u(-1e3, 5e4), u(0.5e3, 5e4), u(1e5, 3e6), u(0.4, 1.7), u(0.03, 0.2),
            u(0, 8e4), u(0, 3e5), u(0, 0.1), u(0.1, 0.8), u(0, 500), u(0, 0.2), u(0.005, 0.05), u(0, 1.5e4)]
    x = np.stack(cols, 1).astype(np.float32)
    out = wp.zeros((n, 7), dtype=float, device="cpu")
    wp.launch(_eval, dim=n, inputs=[wp.array(x, dtype=float, device="cpu"), paper, out], device="cpu")
    got = out.numpy()
    x = x.astype(np.float64)
    kinds = np.array(models.FLOW_NAMES)[x[:, 7].astype(int)]
    ref = np.stack([
        models.cylinder_drag(x[:, 0], x[:, 1], x[:, 2], x[:, 3], x[:, 4], area="paper" if paper else "projected"),
        np.array([models.flow_force(k, t, a, o, p) for k, t, a, o, p in zip(kinds, *x[:, 8:12].T)]),
        models.bekker_sinkage(x[:, 12], x[:, 13], x[:, 14], x[:, 15], x[:, 16]),
        models.bulldozing_force(x[:, 17], x[:, 18], x[:, 16], x[:, 19]),
        models.shear_strength(x[:, 24], x[:, 20], 2 * x[:, 16] ** 2, x[:, 21]),
        models.soil_traction(x[:, 24], x[:, 20], 2 * x[:, 16] ** 2, x[:, 21], x[:, 22], x[:, 23]),
        models.soil_friction(x[:, 24], x[:, 20], 2 * x[:, 16] ** 2, x[:, 21], x[:, 22], x[:, 23], 2.0,
                             models.bulldozing_force(x[:, 17], x[:, 18], x[:, 16], x[:, 19]), surface_mu=x[:, 6]),
    ], 1)
    scale = np.maximum(np.abs(ref), 1e-6 * np.abs(ref).max(0))
    # a tide near its zero crossing: float32 rounding of omega*t is relative to the amplitude, not the value
    scale[:, 1] = np.maximum(scale[:, 1], np.abs(x[:, 9]))
    rel = (np.abs(got - ref) / scale).max(0)
    assert np.all(rel <= 1e-5), rel


def test_references_textbook_values():
    # 1 m/s across a 0.1 m x 1 m cylinder in water, cd 1.2: 0.5*1.2*1000*0.1*1 = 60 N.
    assert models.cylinder_drag(1000, 1.2, 0.05, 1.0, 1.0) == pytest.approx(60.0)
    assert models.cylinder_drag(1000, 1.2, 0.05, 1.0, 1.0, area="paper") == pytest.approx(60.0 * np.pi)
    # Archimedes: 1 litre displaced weighs 9.81 N; the added mass of a cylinder equals its displaced mass.
    r = np.sqrt(1e-3 / np.pi)
    assert models.buoyancy(1000, 9.81, r, 1.0) == pytest.approx(9.81)
    assert models.added_mass(1000, 1.0, r, 1.0) == pytest.approx(1.0)
    assert models.flow_force("still", 3.0, 2.0) == 0.0
    assert models.flow_force("current", 3.0, 2.0) == 2.0
    assert models.flow_force("tide", 1.0, 2.0, omega=np.pi / 2, phase=0.0) == pytest.approx(0.0, abs=1e-12)
    # Bekker: linear soil (n=1), p = (kc/b + kphi) z -> 10 kPa on kc/b + kphi = 1 MN/m^3 gives 1 cm.
    assert models.bekker_sinkage(1e4, 1e5, 0.5e6, 1.0, 0.2) == pytest.approx(0.01)
    assert models.bekker_sinkage(-5.0, 1e5, 0.5e6, 1.0, 0.2) == 0.0
    # Mohr-Coulomb on dry sand (c = 1.04 kPa, phi = 28 deg, Wong) under a 0.22 x 0.09 m sole loaded by 196.2 N
    t_max = 1.04e3 * 0.0198 + 196.2 * np.tan(np.radians(28.0))
    assert models.shear_strength(1.04e3, np.tan(np.radians(28.0)), 0.0198, 196.2) == pytest.approx(t_max)
    # Janosi-Hanamoto: after a slip of K the traction is (1 - 1/e) of the strength; fully mobilised far beyond
    assert models.soil_traction(1.04e3, 0.53, 0.0198, 196.2, 0.025, 0.025) == pytest.approx(
        (1.04e3 * 0.0198 + 196.2 * 0.53) * (1 - np.exp(-1)))
    assert models.soil_traction(0.0, 0.5, 0.02, 100.0, 1e9, 0.01) == pytest.approx(50.0)
    assert models.soil_friction(1.04e3, 0.53, 0.0198, 196.2, 1e9, 0.025, 2.0) == pytest.approx(
        0.53 + 1.04e3 * 0.0198 / 196.2)
    assert models.soil_friction(1.04e3, 0.53, 0.0198, 1.0, 1e9, 0.025, 2.0) == 2.0  # capped as F_N -> 0
    # on ice under the sand (surface 0.2) the shear is the ice's; 30 N of bulldozing on the leading face adds to it
    assert models.soil_friction(1.04e3, 0.53, 0.0198, 196.2, 1e9, 0.025, 2.0, bulldozing=30.0,
                                surface_mu=0.2) == pytest.approx(0.2 + 30.0 / 196.2)
    # Bekker bulldozing: b (0.67 c K_pc z + 0.5 gamma K_pgamma z^2) with the two coefficients given
    assert models.bulldozing_force(1e4, 2e5, 0.1, 0.02) == pytest.approx(0.1 * (1e4 * 0.02 + 2e5 * 4e-4))
    with pytest.raises(ValueError, match="area"):
        models.cylinder_drag(1, 1, 1, 1, 1, area="lateral")
    with pytest.raises(ValueError, match="kind"):
        models.flow_force("river", 0, 1)


def test_sinkage_grows_with_load_as_bekker():
    s = SOIL_PRESETS["dry_sand"]
    p = np.linspace(1e3, 1e5, 20)
    z = models.bekker_sinkage(p, s.kc[0], s.kphi[0], s.n[0], 0.1)
    assert np.all(np.diff(z) > 0)
    # doubling the load scales sinkage by 2^(1/n)
    z1, z2 = models.bekker_sinkage(np.array([2e4, 4e4]), s.kc[0], s.kphi[0], s.n[0], 0.1)
    assert z2 / z1 == pytest.approx(2 ** (1 / s.n[0]))


def test_soil_presets_and_custom():
    for name in ("dry_sand", "wet_sand", "snow", "mud", "clay_loam"):
        assert name in SOIL_PRESETS and SOIL_PRESETS[name].source
    assert preset_table(["mud", "snow"]).shape == (2, 10, 2)  # 9 parameters and the model
    with pytest.raises(KeyError, match="register_custom_soil"):
        preset_table(["lava"])
    with pytest.raises(ValueError, match="built-in"):
        register_custom_soil("mud", kc=1, kphi=1, n=1, c=0, mu=1, K=1, bulldoze_c=1, bulldoze_g=1)
    with pytest.raises(ValueError, match="missing"):
        register_custom_soil("peat_t", kc=(1e3, 1e2))
    p = register_custom_soil("peat_t", kc=(1e3, 1e2), kphi=2e5, n=(1.0, 0.1), c=(2e3, 2e2), mu=(0.3, 0.03),
                             K=(0.05, 0.01), bulldoze_c=(1e4, 1e3), bulldoze_g=(0.0, 0.0))
    assert p.kphi == (2e5, 0.0) and SOIL_PRESETS.pop("peat_t") is p


def test_bulldozing_coefficients_by_hand():
    from legged_gente.terrain.soil import bulldozing_coefficients

    # dry sand, c = 1.04 kPa, phi = 28 deg, gamma = 15.7 kN/m^3: N_q = e^(pi tan 28) tan^2(59 deg) = 14.72,
    # N_c = (N_q - 1) / tan 28 = 25.80, N_gamma = (N_q - 1) tan(39.2 deg) = 11.19 (Meyerhof),
    # K_pc = (25.80 - 0.532) cos^2 28 = 19.70, K_pgamma = (2 * 11.19 / 0.532 + 1) cos^2 28 = 33.6
    bc, bg = bulldozing_coefficients(1.04e3, 28.0, 15.7e3)
    assert bc == pytest.approx(0.67 * 1.04e3 * 19.70, rel=0.01)
    assert bg == pytest.approx(0.5 * 15.7e3 * 33.6, rel=0.01)


# --------------------------------------------------------------------------------------------------------
# Resistive force theory (Li, Zhang & Goldman, Science 2013)


def test_rft_plate_pushed_straight_down_by_hand():
    # Li et al.'s generic fit at beta = 0 (horizontal plate), gamma = pi/2 (moving straight down): every sine term
    # is sin(pi/2) = 1 and cos(2 beta) = 1, every C term a cosine of pi/2 = 0 and D10 sin(0) = 0:
    # alpha_z = A00 + A10 + B11 + B01 + B-11 = 0.206 + 0.169 + 0.212 + 0.358 + 0.055 = 1.000 zeta, alpha_x = 0
    zeta = 4.64e5
    ax, az = models.rft_alpha(0.0, np.pi / 2, zeta)
    assert az == pytest.approx(1.000 * zeta, rel=1e-9) and ax == pytest.approx(0.0, abs=1e-9 * zeta)


def test_rft_other_orientations_by_hand():
    zeta = 1.0
    # a vertical plate (beta = pi/2) moved horizontally (gamma = 0): cos(2 beta) = -1, sin(2 beta) = 0
    # alpha_x = C11 cos(pi) + C01 cos(0) + C-11 cos(-pi) + D10 sin(pi) = 0.124 + 0.253 - 0.007 + 0 = 0.370
    # alpha_z = A00 - A10 + B11 sin(pi) + B01 sin(0) + B-11 sin(-pi) = 0.206 - 0.169 = 0.037
    np.testing.assert_allclose(models.rft_alpha(np.pi / 2, 0.0, zeta), (0.370, 0.037), atol=1e-12)
    # a plate tilted 45 deg (beta = pi/4) pushed straight down (gamma = pi/2): 2 beta + gamma = pi, -2 beta + gamma = 0
    # alpha_x = C11 cos(pi) + C01 cos(pi/2) + C-11 cos(0) + D10 sin(pi/2) = 0.124 + 0 + 0.007 + 0.088 = 0.219
    # alpha_z = A00 + A10 cos(pi/2) + B11 sin(pi) + B01 sin(pi/2) + B-11 sin(0) = 0.206 + 0.358 = 0.564
    np.testing.assert_allclose(models.rft_alpha(np.pi / 4, np.pi / 2, zeta), (0.219, 0.564), atol=1e-12)
    # a horizontal plate dragged horizontally: alpha_x = C11 + C01 + C-11 = 0.136, alpha_z = A00 + A10 = 0.375
    np.testing.assert_allclose(models.rft_alpha(0.0, 0.0, zeta), (0.136, 0.375), atol=1e-12)


def test_rft_element_force_directions_by_hand():
    zeta, depth, area, reg = 4.64e5, 0.02, 1e-3, 0.05
    # the tilted sole's face, normal (sin 45, 0, -cos 45) (down and towards +x), pushed straight down: beta = 45 deg,
    # the medium pushes it back towards -x with alpha_x = 0.219 zeta
    n = np.array([np.sqrt(0.5), 0.0, -np.sqrt(0.5)])
    f = models.rft_element_force(n, [0.0, 0.0, -0.2], depth, area, zeta, reg)
    np.testing.assert_allclose(f, [-0.219 * zeta * depth * area, 0.0, 0.0], rtol=1e-9, atol=1e-12)
    # either face of the plate gives the same force (the fit is pi-periodic in beta)
    np.testing.assert_allclose(models.rft_element_force(-n, [0.0, 0.0, -0.2], depth, area, zeta, reg), f, atol=1e-12)
    # a flat sole dragged along -y at 0.3 m/s: 0.136 zeta |z| A along +y; slower than reg, faded linearly
    f = models.rft_element_force([0, 0, -1.0], [0.0, -0.3, 0.0], depth, area, zeta, reg)
    np.testing.assert_allclose(f, [0.0, 0.136 * zeta * depth * area, 0.0], rtol=1e-9, atol=1e-12)
    f = models.rft_element_force([0, 0, -1.0], [0.0, -0.01, 0.0], depth, area, zeta, reg)
    np.testing.assert_allclose(f, [0.0, 0.136 * zeta * depth * area * 0.01 / reg, 0.0], rtol=1e-9, atol=1e-12)
    assert not models.rft_element_force([0, 0, -1.0], [0.3, 0.0, 0.0], -0.01, area, zeta, reg).any()  # in the air


def test_rft_face_force_by_hand():
    """The leading face of a sole sunk 2.14 cm, 0.09 m across the motion: strips of vertical plate (beta = pi/2)
    whose stress alpha_x(pi/2, gamma) |s| = (C01 - C11 - C-11) cos(gamma) zeta |s| = 0.370 cos(gamma) zeta |s|
    integrates over the depth to 0.370 cos(gamma) zeta z^2 / 2 * b (the vertical-plate value of
    test_rft_other_orientations_by_hand)."""
    zeta, z, b, reg = 4.64e5, 0.0214, 0.09, 0.05
    level = 0.370 * zeta * z * z / 2 * b  # 3.54 N
    np.testing.assert_allclose(models.rft_face_force([0.3, 0.0, 0.0], z, b, zeta, reg), [-level, 0.0, 0.0],
                               rtol=1e-9)
    # dragged along -y while sinking at 45 deg: gamma = pi/4, cos(gamma) = sqrt(1/2), pushed back along +y
    np.testing.assert_allclose(models.rft_face_force([0.0, -0.2, -0.2], z, b, zeta, reg),
                               [0.0, level * np.sqrt(0.5), 0.0], rtol=1e-9, atol=1e-12)
    # slower than the fade speed: scaled by |v| / reg; straight down (the face slides along itself): none
    np.testing.assert_allclose(models.rft_face_force([0.01, 0.0, 0.0], z, b, zeta, reg),
                               [-level * 0.01 / reg, 0.0, 0.0], rtol=1e-9)
    assert not models.rft_face_force([0.0, 0.0, -0.3], z, b, zeta, reg).any()
    assert not models.rft_face_force([0.3, 0.0, 0.0], -0.01, b, zeta, reg).any()  # above the surface


def test_rft_support_by_hand():
    """The vertical stress under a sole in units of zeta, alpha_z(beta, gamma) / zeta, from the Fourier series by
    hand (beta = 0 for a level sole: cos(2 beta) = 1, the B terms sum to (0.212 + 0.358 + 0.055) sin(gamma))."""
    up, reg = [0.0, 0.0, 1.0], 0.05
    assert models.rft_support(up, [0.0, 0.0, -0.3], reg) == pytest.approx(1.000, abs=1e-12)  # pushed straight down
    assert models.rft_support(up, [0.0, 0.0, 0.0], reg) == pytest.approx(1.000, abs=1e-12)  # at rest
    # dragged level sideways: gamma = 0, A00 + A10 = 0.206 + 0.169 = 0.375
    assert models.rft_support(up, [0.3, 0.0, 0.0], reg) == pytest.approx(0.375, abs=1e-12)
    assert models.rft_support(up, [0.0, -0.3, 0.0], reg) == pytest.approx(0.375, abs=1e-12)
    # dragged at half the fade speed: 1 + 0.5 (0.375 - 1) = 0.6875
    assert models.rft_support(up, [0.025, 0.0, 0.0], reg) == pytest.approx(0.6875, abs=1e-12)
    # sinking at 45 deg while dragged: 0.375 + 0.625 sin(pi/4) = 0.8169
    assert models.rft_support(up, [0.2, 0.0, -0.2], reg) == pytest.approx(0.375 + 0.625 * np.sqrt(0.5), abs=1e-12)
    # rising while dragged: the upward part is left out (the sole's open rut has no grains above it): level
    assert models.rft_support(up, [0.2, 0.0, 0.2], reg) == pytest.approx(0.375, abs=1e-12)
    # rising straight up: unloading, supported as at rest (not as dragged sideways, 0.375)
    assert models.rft_support(up, [0.0, 0.0, 0.3], reg) == pytest.approx(1.000, abs=1e-12)
    # rising at 0.025 m/s while dragged at 0.025 m/s: faded by the drag's speed alone, 0.6875 as above
    assert models.rft_support(up, [0.025, 0.0, 0.025], reg) == pytest.approx(0.6875, abs=1e-12)
    # a sole tilted 30 deg, dragged level along +x: leading edge up (a ski; normal tilted against the motion)
    # beta = +30 deg, leading edge down (normal tilted along the motion) beta = -30 deg; cos(2 beta) = 0.5,
    # sin(2 beta) = +-sqrt(3)/2: A00 + A10 0.5 +- (B11 - B-11) sqrt(3)/2 = 0.2905 +- 0.157 * 0.8660
    s30, c30 = np.sin(np.radians(30.0)), np.cos(np.radians(30.0))
    for sign in (1.0, -1.0):
        n = [-sign * s30, 0.0, c30]
        assert models.rft_support(n, [0.3, 0.0, 0.0], reg) == pytest.approx(0.2905 + sign * 0.157 * c30, abs=1e-12)
    # the sinkage whose stress carries the load: z = p / (support zeta); 9909 Pa on zeta = 4.64e5 N/m^3
    assert models.rft_sinkage(9909.0, 4.64e5, 1.0) == pytest.approx(9909.0 / 4.64e5, rel=1e-12)  # 2.14 cm
    assert models.rft_sinkage(9909.0, 4.64e5, 0.375) == pytest.approx(9909.0 / (0.375 * 4.64e5), rel=1e-12)
    assert models.rft_sinkage(0.0, 4.64e5, 0.375) == 0.0
    assert models.rft_sinkage(9909.0, 4.64e5, -0.02) == pytest.approx(9909.0 / (1e-6 * 4.64e5), rel=1e-12)


def test_rft_support_and_sinkage_kernels_match_references():
    from legged_gente.external_forces import rft as R

    @wp.kernel
    def support_eval(normals: wp.array[wp.vec3], vels: wp.array[wp.vec3], loads: wp.array[wp.vec2],
                     out: wp.array[wp.vec2]):
        i = wp.tid()
        out[i] = wp.vec2(R.rft_support_fn(normals[i], vels[i], 0.05),
                         K.rft_sinkage_fn(loads[i][0], 4.64e5, loads[i][1]))

    rng = np.random.default_rng(2)
    k = 300
    normals = rng.normal(size=(k, 3))
    normals[:100] = [0.0, 0.0, 1.0]  # level soles
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    vels = rng.normal(0, 0.1, (k, 3))
    vels[:20, :2] = 0.0  # straight up or down
    vels[20:40] *= 0.1  # below the fade speed
    loads = np.stack([rng.uniform(-2e3, 2e4, k), rng.uniform(-0.1, 1.0, k)], axis=1)
    arrays = [wp.array(a.astype(np.float32), dtype=t, device="cpu")
              for a, t in ((normals, wp.vec3), (vels, wp.vec3), (loads, wp.vec2))]
    out = wp.zeros(k, dtype=wp.vec2, device="cpu")
    wp.launch(support_eval, dim=k, device="cpu", inputs=[*arrays, out])
    got = out.numpy()
    for i in range(k):
        assert got[i, 0] == pytest.approx(models.rft_support(normals[i], vels[i], 0.05), abs=1e-5)
        assert got[i, 1] == pytest.approx(float(models.rft_sinkage(loads[i, 0], 4.64e5, loads[i, 1])), rel=1e-5)


def test_rft_kernel_matches_reference():
    from legged_gente.external_forces import rft as R

    @wp.kernel
    def rft_eval(normals: wp.array[wp.vec3], vels: wp.array[wp.vec3], depths: wp.array[float],
                 angles: wp.array[wp.vec2], out: wp.array[wp.vec3], alphas: wp.array[wp.vec2],
                 faces: wp.array[wp.vec3]):
        i = wp.tid()
        out[i] = R.rft_element_force_fn(normals[i], vels[i], depths[i], 1.0e-3, 4.64e5, 0.05)
        alphas[i] = R.rft_alpha_fn(angles[i][0], angles[i][1], 4.64e5)
        faces[i] = R.rft_face_force_fn(vels[i], depths[i], 0.09, 4.64e5, 0.05)

    rng = np.random.default_rng(1)
    k = 300
    normals = rng.normal(size=(k, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    vels = rng.normal(0, 0.2, (k, 3))
    vels[:20, :2] = 0.0  # straight up or down
    depths = rng.uniform(-0.01, 0.05, k)
    angles = rng.uniform(-np.pi / 2, np.pi / 2, (k, 2))
    arrays = [wp.array(a.astype(np.float32), dtype=t, device="cpu")
              for a, t in ((normals, wp.vec3), (vels, wp.vec3), (depths, float), (angles, wp.vec2))]
    out, alphas = wp.zeros(k, dtype=wp.vec3, device="cpu"), wp.zeros(k, dtype=wp.vec2, device="cpu")
    faces = wp.zeros(k, dtype=wp.vec3, device="cpu")
    wp.launch(rft_eval, dim=k, device="cpu", inputs=[*arrays, out, alphas, faces])
    for i in range(k):
        ref = models.rft_element_force(normals[i], vels[i], depths[i], 1e-3, 4.64e5, 0.05)
        np.testing.assert_allclose(out.numpy()[i], ref, rtol=1e-4, atol=1e-3)
        np.testing.assert_allclose(alphas.numpy()[i], models.rft_alpha(*angles[i], 4.64e5), rtol=1e-5, atol=0.5)
        face = models.rft_face_force(vels[i], depths[i], 0.09, 4.64e5, 0.05)
        np.testing.assert_allclose(faces.numpy()[i], face, rtol=1e-4, atol=1e-4)
    assert np.count_nonzero(np.abs(faces.numpy()).max(1) > 1.0) > 100  # most of the random faces are sunk and moving


@pytest.mark.parametrize("value", ["abc", (1.0, "x"), None, [1.0, 2.0, 3.0]])
def test_a_custom_soil_value_that_is_no_number_or_pair_names_its_parameter(value):
    """numpy's 'could not convert string to float' named neither the parameter nor the fix."""
    params = dict(kc=1e3, kphi=2e5, n=1.0, c=2e3, mu=0.3, K=0.01, bulldoze_c=1.0, bulldoze_g=1.0)
    with pytest.raises(ValueError, match=r"register_custom_soil\('peat_v'\): kc=.* is not a number or a \(mean, std\) "
                                         r"pair; give e.g. kc=\(1000.0, 100.0\) or kc=1000.0"):
        register_custom_soil("peat_v", **{**params, "kc": value})


@pytest.mark.parametrize("field, value, named", [
    ("mu", 28.0, "math.tan(math.radians(phi))"),  # phi in degrees, not tan(phi)
    ("K", 2.5, "2.5 cm is 0.025"),  # centimetres, not metres
])
def test_a_soil_value_in_the_wrong_unit_is_refused_naming_the_unit(field, value, named):
    """No soil has tan(phi) above 2 (phi 63 deg) or a shear deformation modulus above 0.5 m (the presets: 0.01-0.05
    m): 28 for mu is degrees, 2.5 for K centimetres."""
    params = dict(kc=1.0e3, kphi=2.0e5, n=1.0, c=2.0e3, mu=0.4, K=0.03, bulldoze_c=0.0, bulldoze_g=0.0)
    params[field] = value
    with pytest.raises(ValueError, match=re.escape(named)):
        register_custom_soil("peat", **params)
    assert "peat" not in SOIL_PRESETS
