"""Warp device formulas against the numpy references, and the references against textbook values."""

import numpy as np
import pytest
import warp as wp

from legged_gente.external_forces import kernels as K
from legged_gente.external_forces import models
from legged_gente.terrain.soil import SOIL_PRESETS, preset_table, register_custom_soil

wp.config.quiet = True


@wp.kernel
def _eval(
    x: wp.array2d[float],  # columns: rho cd r L v | g | cm | kind t amp omega phase | p kc kphi n width | a bn z | mu fn j K
    paper: int,
    out: wp.array2d[float],
):
    i = wp.tid()
    out[i, 0] = K.cylinder_drag_fn(x[i, 0], x[i, 1], x[i, 2], x[i, 3], x[i, 4], paper)
    out[i, 1] = K.buoyancy_fn(x[i, 0], x[i, 5], x[i, 2], x[i, 3])
    out[i, 2] = K.added_mass_fn(x[i, 0], x[i, 6], x[i, 2], x[i, 3])
    out[i, 3] = K.flow_force_fn(int(x[i, 7]), x[i, 8], x[i, 9], x[i, 10], x[i, 11])
    out[i, 4] = K.bekker_sinkage_fn(x[i, 12], x[i, 13], x[i, 14], x[i, 15], x[i, 16])
    out[i, 5] = K.bulldozing_force_fn(x[i, 17], x[i, 18], x[i, 19])
    out[i, 6] = K.presliding_friction_fn(x[i, 20], x[i, 21], x[i, 22], x[i, 23])


@pytest.mark.parametrize("paper", [0, 1])
def test_kernels_match_references(paper):
    rng = np.random.default_rng(paper)
    n = 256
    u = lambda lo, hi: rng.uniform(lo, hi, n)  # noqa: E731
    cols = [u(900, 1100), u(0.8, 1.3), u(0.01, 0.1), u(0, 0.5), u(-2, 2), u(9, 10), u(0.5, 1.5),
            rng.integers(0, 3, n).astype(float), u(0, 20), u(-1, 1), u(0, 3), u(-3, 3),
            u(-1e3, 5e4), u(0.5e3, 5e4), u(1e5, 3e6), u(0.4, 1.7), u(0.03, 0.2),
            u(1e3, 5e5), u(0.8, 2.2), u(0, 0.1), u(0.1, 0.8), u(0, 500), u(0, 0.2), u(0.005, 0.05)]
    x = np.stack(cols, 1).astype(np.float32)
    out = wp.zeros((n, 7), dtype=float, device="cpu")
    wp.launch(_eval, dim=n, inputs=[wp.array(x, dtype=float, device="cpu"), paper, out], device="cpu")
    got = out.numpy()
    x = x.astype(np.float64)
    kinds = np.array(models.FLOW_NAMES)[x[:, 7].astype(int)]
    ref = np.stack([
        models.cylinder_drag(x[:, 0], x[:, 1], x[:, 2], x[:, 3], x[:, 4], area="paper" if paper else "projected"),
        models.buoyancy(x[:, 0], x[:, 5], x[:, 2], x[:, 3]),
        models.added_mass(x[:, 0], x[:, 6], x[:, 2], x[:, 3]),
        np.array([models.flow_force(k, t, a, o, p) for k, t, a, o, p in zip(kinds, *x[:, 8:12].T)]),
        models.bekker_sinkage(x[:, 12], x[:, 13], x[:, 14], x[:, 15], x[:, 16]),
        models.bulldozing_force(x[:, 17], x[:, 18], x[:, 19]),
        models.presliding_friction(x[:, 20], x[:, 21], x[:, 22], x[:, 23]),
    ], 1)
    scale = np.maximum(np.abs(ref), 1e-6 * np.abs(ref).max(0))
    # a tide near its zero crossing: float32 rounding of omega*t is relative to the amplitude, not the value
    scale[:, 3] = np.maximum(scale[:, 3], np.abs(x[:, 9]))
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
    assert models.presliding_friction(0.5, 100.0, 1e9, 0.01) == pytest.approx(50.0)
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
    assert preset_table(["mud", "snow"]).shape == (2, 7, 2)
    with pytest.raises(KeyError, match="register_custom_soil"):
        preset_table(["lava"])
    with pytest.raises(ValueError, match="built-in"):
        register_custom_soil("mud", kc=1, kphi=1, n=1, bulldoze_a=1, bulldoze_n=1, mu=1, K=1)
    with pytest.raises(ValueError, match="missing"):
        register_custom_soil("peat_t", kc=(1e3, 1e2))
    p = register_custom_soil("peat_t", kc=(1e3, 1e2), kphi=2e5, n=(1.0, 0.1), bulldoze_a=(1e4, 1e3),
                             bulldoze_n=(1.0, 0.0), mu=(0.3, 0.03), K=(0.05, 0.01))
    assert p.kphi == (2e5, 0.0) and SOIL_PRESETS.pop("peat_t") is p
