"""Soil and ground-friction formulas against textbook values computed here, and the contact friction a soil or a
low-friction cell gives (``kernels.ground_friction``): the soil and the map only ever lower a contact's grip."""

import math

import numpy as np
import pytest
import warp as wp

from legged_gente.external_forces import kernels as K
from legged_gente.external_forces import models

wp.config.quiet = True
DEV = "cpu"


# --------------------------------------------------------------------------------------------------------
# Bekker, Mohr-Coulomb, Janosi-Hanamoto by hand


def test_bekker_sinkage_inverts_the_pressure_sinkage_law():
    # Wong Table 2.3 dry sand: n 1.1, kc 0.99 kN/m^2.1, kphi 1528.43 kN/m^3.1; a 0.096 m wide sole at 19.3 kPa.
    # p = (kc/b + kphi) z^n -> z = (19.3e3 / (0.99e3/0.096 + 1528.43e3))^(1/1.1) = (0.0125428)^0.90909 = 0.018675 m
    z = models.bekker_sinkage(19.3e3, 0.99e3, 1528.43e3, 1.1, 0.096)
    assert z == pytest.approx(0.0125428 ** (1 / 1.1), rel=1e-4)
    assert z == pytest.approx(0.018675, rel=1e-3)
    # and the forward law gives the pressure back, for the table's other exponents too (snow 1.6, mud 0.5)
    for kc, kphi, n in ((0.99e3, 1528.43e3, 1.1), (4.37e3, 196.72e3, 1.6), (0.77e3, 51.91e3, 0.5)):
        z = models.bekker_sinkage(19.3e3, kc, kphi, n, 0.096)
        assert (kc / 0.096 + kphi) * z**n == pytest.approx(19.3e3, rel=1e-12)
    # no load, a pull (negative pressure): no sinkage
    assert models.bekker_sinkage(0.0, 0.99e3, 1528.43e3, 1.1, 0.096) == 0.0
    assert models.bekker_sinkage(-1e3, 0.99e3, 1528.43e3, 1.1, 0.096) == 0.0


def test_janosi_hanamoto_slip_that_mobilises_a_load():
    # Mohr-Coulomb under a 0.22 x 0.096 m sole carrying 407 N on dry sand (c 1.04 kPa, phi 28 deg, K 2.5 cm):
    # T_max = 1.04e3 * 0.02112 + 407 tan 28 = 21.96 + 216.41 = 238.37 N; half of it after j = K ln 2 = 1.733 cm
    a, fn, tan_phi, k = 0.22 * 0.096, 407.0, math.tan(math.radians(28.0)), 0.025
    t_max = 1.04e3 * a + fn * tan_phi
    assert t_max == pytest.approx(238.37, abs=0.01)
    assert models.soil_traction(1.04e3, tan_phi, a, fn, k * math.log(2.0), k) == pytest.approx(t_max / 2, rel=1e-12)
    # any push P below T_max is held after j = -K ln(1 - P / T_max); the traction never exceeds T_max
    for frac in (0.1, 0.5, 0.9, 0.999):
        j = -k * math.log(1.0 - frac)
        assert models.soil_traction(1.04e3, tan_phi, a, fn, j, k) == pytest.approx(frac * t_max, rel=1e-9)
    assert models.soil_traction(1.04e3, tan_phi, a, fn, 1e3, k) == pytest.approx(t_max, rel=1e-12)
    # a negative slip (no such thing: a path length) mobilises nothing
    assert models.soil_traction(1.04e3, tan_phi, a, fn, -0.01, k) == 0.0


def test_level_sole_rft_resistance_never_pushes_along_the_motion():
    # Li et al.'s fit for a level plate (beta = 0): alpha_x = (C11 + C01 + C-11) cos(gamma) = 0.136 cos(gamma),
    # >= 0 for every motion (gamma in [-pi/2, pi/2]): the plate's and the leading face's horizontal force
    # (alpha_x(pi/2, gamma) = 0.370 cos(gamma)) never have positive power
    gamma = np.linspace(-np.pi / 2, np.pi / 2, 181)
    ax, _ = models.rft_alpha(0.0, gamma, 1.0)
    np.testing.assert_allclose(ax, 0.136 * np.cos(gamma), atol=1e-12)
    ax, _ = models.rft_alpha(np.pi / 2, gamma, 1.0)
    np.testing.assert_allclose(ax, 0.370 * np.cos(gamma), atol=1e-12)
    rng = np.random.default_rng(0)
    for v in rng.normal(0.0, 0.3, (200, 3)):
        assert models.rft_element_force([0.0, 0.0, 1.0], v, 0.02, 1e-3, 4.64e5, 0.05) @ v <= 1e-12
        assert models.rft_face_force(v, 0.02, 0.09, 4.64e5, 0.05) @ v <= 1e-12


# --------------------------------------------------------------------------------------------------------
# The contact friction of a ground cell (kernels.ground_friction)


@wp.kernel
def _ground_friction_eval(fr_in: wp.array[K.vec5], foot: int, soilmap: K.SoilMap, feet: K.FootSoil,
                          fr_out: wp.array[K.vec5]):
    fr_out[0] = K.ground_friction(fr_in[0], wp.vec2i(0, 0), foot, 0, soilmap, feet)


def _ground_friction(fr, cell_friction=1.0, soil=None, foot=0, load=400.0, slip=1.0, area=0.22 * 0.096,
                     stance_load=None):
    """The friction ground_friction gives a contact (MuJoCo's friction ``fr``) on a one-cell map of friction
    ``cell_friction`` and soil ``soil`` = (c, tan phi, K) (None: rigid ground), under foot ``foot`` (-1: another
    body) of load ``load`` (N; its mean over the stance ``stance_load``, None: the same) that has slid ``slip``
    (m)."""
    soilmap = K.SoilMap()
    soilmap.origin, soilmap.resolution = wp.vec2(0.0, 0.0), 0.1
    soilmap.soil = wp.array(np.full((1, 1), -1 if soil is None else 0, np.int32), dtype=int, device=DEV)
    soilmap.friction = wp.array(np.full((1, 1), cell_friction, np.float32), dtype=float, device=DEV)
    params = np.zeros((1, 1, K.NSOILPARAM), np.float32)
    if soil is not None:
        params[0, 0, K.COH], params[0, 0, K.MU], params[0, 0, K.K] = soil
    feet = K.FootSoil()
    feet.friction_reference, feet.use_friction, feet.use_soil = 1.0, 1, 1
    feet.sole_area, feet.bekker_width, feet.friction_cap, feet.min_friction, feet.sink_step = area, 0.096, 2.0, 0.01, 0.0
    feet.bulldozing_face = 0.096
    feet.soil_params = wp.array(params, dtype=float, device=DEV)
    one = lambda v: wp.array(np.full((1, 1), v, np.float32), dtype=float, device=DEV)  # noqa: E731
    feet.load, feet.traction_load = one(load), one(load if stance_load is None else stance_load)
    feet.support, feet.slip, feet.sinkage = one(1.0), one(slip), one(0.0)
    feet.soil = wp.array(np.full((1, 1), -1 if soil is None else 0, np.int32), dtype=int, device=DEV)
    out = wp.zeros(1, dtype=K.vec5, device=DEV)
    wp.launch(_ground_friction_eval, dim=1, device=DEV,
              inputs=[wp.array(np.array([fr], np.float32), dtype=K.vec5, device=DEV), foot, soilmap, feet, out])
    return out.numpy()[0].astype(float)


def test_soil_and_map_only_lower_the_sliding_friction():
    rigid = [1.0, 1.0, 0.005, 1e-4, 1e-4]  # the biped's sole friction (sliding, torsional, rolling x2)
    sand = (1.04e3, math.tan(math.radians(28.0)), 0.025)
    # dry sand, fully mobilised (slip 1 m >> K): (c A + F_N tan phi) / F_N = (21.96 + 400 tan 28) / 400 = 0.5866
    fr = _ground_friction(rigid, soil=sand)
    assert fr[0] == pytest.approx((1.04e3 * 0.22 * 0.096 + 400.0 * math.tan(math.radians(28.0))) / 400.0, rel=1e-5)
    assert fr[0] == fr[1]
    # just touched down (slip 0): the soil has mobilised nothing
    assert _ground_friction(rigid, soil=sand, slip=0.0)[0] == 0.0
    # a soil stronger than the rigid ground (clay loam c 6.1 kPa over 40 N: 3.2 + 0.5) is capped by the ground
    assert _ground_friction(rigid, soil=(6.1e3, 0.5, 0.01), load=40.0)[0] == pytest.approx(1.0)
    # an ice cell (0.05) under that sand: the smaller of the two
    assert _ground_friction(rigid, cell_friction=0.05, soil=sand)[0] == pytest.approx(0.05)
    # another body than a foot on the sand: tan(phi) = 0.5317
    assert _ground_friction(rigid, soil=sand, foot=-1)[0] == pytest.approx(math.tan(math.radians(28.0)), rel=1e-6)
    # the cohesion share divides by the larger of the load and its mean over the stance: a sliding contact's load
    # sags in each hop, its stance mean does not (21.96 / 400 + tan 28 either way; 21.96 / 100 + tan 28 unsagged)
    held = (1.04e3 * 0.22 * 0.096 + 400.0 * math.tan(math.radians(28.0))) / 400.0
    assert _ground_friction(rigid, soil=sand, load=100.0, stance_load=400.0)[0] == pytest.approx(held, rel=1e-5)
    assert _ground_friction(rigid, soil=sand, load=400.0, stance_load=100.0)[0] == pytest.approx(held, rel=1e-5)
    # random loads, slips and cell frictions: never above the rigid ground's scaled by the cell, nor Mohr-Coulomb
    rng = np.random.default_rng(3)
    for load, slip, cell in zip(rng.uniform(1.0, 800.0, 20), rng.uniform(0.0, 0.1, 20), rng.uniform(0.0, 1.5, 20)):
        mu = _ground_friction(rigid, cell_friction=cell, soil=sand, load=load, slip=slip)[0]
        strength = (1.04e3 * 0.22 * 0.096 + load * math.tan(math.radians(28.0))) / load
        assert mu <= min(cell, strength) * (1 + 1e-5) + 1e-7


@pytest.mark.parametrize("case", ["ice", "sand", "sand_other_body"])
def test_torsional_friction_is_limited_with_the_sliding_friction(case):
    """A condim 4/6 contact's torsional friction is Coulomb friction of the contact patch: the spin torque a disc
    of radius a pressed uniformly by N holds is the integral of mu (N / pi a^2) r 2 pi r dr over 0..a = (2/3) mu N a,
    proportional to mu. A cell or a soil that lowers mu lowers it by the same factor; MuJoCo's torsional coefficient (a length,
    fr[2]) kept the rigid ground's, so a foot on ice or on sand resisted a twist as on concrete."""
    rigid = [1.0, 1.0, 0.02, 1e-4, 1e-4]
    tan28 = math.tan(math.radians(28.0))
    if case == "ice":  # a cell of friction 0.1: mu 1 -> 0.1, torsion 0.02 m -> 0.002 m
        fr, mu = _ground_friction(rigid, cell_friction=0.1), 0.1
    elif case == "sand":  # a cohesionless sand, fully mobilised: mu = tan 28 = 0.5317
        fr, mu = _ground_friction(rigid, soil=(0.0, tan28, 0.025)), tan28
    else:  # a knee on that sand: tan 28 too
        fr, mu = _ground_friction(rigid, soil=(0.0, tan28, 0.025), foot=-1), tan28
    assert fr[0] == pytest.approx(mu, rel=1e-6) and fr[1] == pytest.approx(mu, rel=1e-6)
    assert fr[2] == pytest.approx(0.02 * mu / 1.0, rel=1e-5)
    assert fr[3] == pytest.approx(1e-4) and fr[4] == pytest.approx(1e-4)  # rolling resistance is no grip: kept


# --------------------------------------------------------------------------------------------------------
# Device twins at the edges: no load, a pull, a negative rut or slip, a huge slip, an exponent near 0


@wp.kernel
def _soil_eval(x: wp.array2d[float], out: wp.array2d[float]):
    i = wp.tid()  # columns: p kc kphi n b | c mu A F_N j K | z
    out[i, 0] = K.bekker_sinkage_fn(x[i, 0], x[i, 1], x[i, 2], x[i, 3], x[i, 4])
    out[i, 1] = K.soil_traction_fn(x[i, 5], x[i, 6], x[i, 7], x[i, 8], x[i, 9], x[i, 10])
    out[i, 2] = K.soil_friction_fn(x[i, 5], x[i, 6], x[i, 7], x[i, 8], x[i, 9], x[i, 10], 1.0e30, 0.0, 2.0)
    out[i, 3] = K.bulldozing_force_fn(1.4e4, 2.6e5, 0.096, x[i, 11])


def test_soil_twins_agree_at_the_edges():
    sand = [0.99e3, 1528.43e3, 1.1, 0.096]
    rows = np.array([
        [0.0, *sand, 1.04e3, 0.53, 0.0211, 0.0, 0.0, 0.025, 0.0],  # no load, no slip, no rut
        [-5e3, *sand, 1.04e3, 0.53, 0.0211, -50.0, -0.01, 0.025, -0.02],  # a pull, a negative slip and rut
        [19.3e3, *sand, 1.04e3, 0.53, 0.0211, 407.0, 1e6, 0.025, 0.02],  # a huge slip: fully mobilised
        [19.3e3, 0.99e3, 1528.43e3, 0.05, 0.096, 0.0, 0.53, 0.0211, 1e-9, 0.05, 0.025, 0.3],  # n -> 0, F_N -> 0
    ], np.float32)
    out = wp.zeros((len(rows), 4), dtype=float, device=DEV)
    wp.launch(_soil_eval, dim=len(rows), device=DEV, inputs=[wp.array(rows, dtype=float, device=DEV), out])
    got, x = out.numpy(), rows.astype(float)
    ref = np.stack([models.bekker_sinkage(*x[:, 0:5].T), models.soil_traction(*x[:, 5:11].T),
                    models.soil_friction(*x[:, 5:11].T, 2.0), models.bulldozing_force(1.4e4, 2.6e5, 0.096, x[:, 11])], 1)
    np.testing.assert_allclose(got, ref, rtol=1e-5, atol=1e-9)
    # by hand: nothing without load, pull, slip or rut; T_max = 1.04e3 * 0.0211 + 407 * 0.53 = 237.65 N fully
    # mobilised; an exponent near 0 makes the soil rigid below kc/b + kphi (z = 0.0125^20 ~ 1e-38); with no load the
    # cohesionless coefficient is tan(phi) = 0.53 (1 - e^-2); bulldozing of a 0.3 m rut 0.096 (1.4e4 0.3 + 2.6e5 0.09)
    assert not got[0].any() and not got[1].any()
    assert got[2, 1] == pytest.approx(1.04e3 * 0.0211 + 407.0 * 0.53, rel=1e-5)
    assert got[3, 0] < 1e-30
    assert got[3, 2] == pytest.approx(0.53 * (1.0 - math.exp(-2.0)), rel=1e-5)
    assert got[3, 3] == pytest.approx(0.096 * (1.4e4 * 0.3 + 2.6e5 * 0.09), rel=1e-5)


def test_noise_factors_stay_positive_however_wide_their_spread():
    """The drag/buoyancy factor eps ~ N(1, noise_std) and the flow factor xi ~ N(1, noise_std) scale forces that
    must keep their sign (a negative eps makes drag push along the motion, a negative xi reverses the flow): with
    noise_std = 1, P(N(1, 1) < 0.1) = Phi(-0.9) = 0.184, so about 377 of 2048 draws would fall below 10 % of the
    mean; they are floored there, as the soil draws are, and the rest keep N(1, 1)'s spread."""
    n = 2048
    with wp.ScopedDevice(DEV):
        eps, xi = wp.zeros(n, dtype=float), wp.zeros(n, dtype=float)
        counter = wp.zeros(1, dtype=int)
        table = wp.zeros((1, K.NSOILPARAM, 2), dtype=float)
        params = wp.zeros((n, 1, K.NSOILPARAM), dtype=float)
        feet = [wp.zeros((n, 1), dtype=float) for _ in range(8)]
        mask = wp.array(np.ones(n, bool), dtype=bool)
        wp.launch(K.reset_kernel, dim=n, inputs=[mask, 3, counter, 1.0, table, eps, params, *feet])
        wp.launch(K.flow_noise_kernel, dim=n, inputs=[3, counter, 1.0, xi])
    for draws in (eps.numpy(), xi.numpy()):
        assert draws.min() == pytest.approx(0.1)
        floored = int(np.sum(draws == np.float32(0.1)))
        assert 300 < floored < 460  # binomial(2048, 0.184): 377 +- 3.5 sigma
        assert np.std(draws[draws > 0.1]) > 0.5


def test_the_stance_load_is_the_mean_since_touchdown_and_survives_hops_near_the_ground():
    """foot_state_kernel: a stance starts at the first substep with F_N above the threshold; its load is F_N's
    plain mean since then (hops' zeros included) until traction_load_tau, its slip grows by |v| dt in every one of
    its substeps (hops too); without load for liftoff_time it ends only if the sole is off the floor it stood on, the
    rut is forgotten if the sole is out of it, and the slip if both."""
    dt, tau, liftoff = 0.005, 0.3, 0.05
    arrays = {name: wp.zeros((1, 1), dtype=float, device=DEV)
              for name in ("fn", "slip", "air", "stance", "load", "sink_load", "traction_load", "sinkage")}
    vel = wp.array(np.array([[[0.5, 0.0, 0.0]]], np.float32), dtype=wp.vec3, device=DEV)
    near = wp.zeros((1, 1), dtype=int, device=DEV)

    def substep(fn):
        arrays["fn"].fill_(fn)
        wp.launch(K.foot_state_kernel, dim=(1, 1), device=DEV,
                  inputs=[dt, 1.0, dt / 0.05, dt / tau, arrays["fn"], vel, liftoff, near, arrays["slip"],
                          arrays["air"], arrays["stance"], arrays["load"], arrays["sink_load"],
                          arrays["traction_load"], arrays["sinkage"]])
        return {name: float(a.numpy()[0, 0]) for name, a in arrays.items()}

    substep(0.0)  # in the air before touchdown: no stance
    assert substep(0.0)["stance"] == 0.0 and arrays["slip"].numpy()[0, 0] == 0.0
    hops = [300.0, 0.0, 0.0, 0.0, 900.0, 0.0, 0.0, 0.0, 0.0, 0.0, 600.0, 0.0]  # 60 ms: 150 N on average
    for fn in hops:
        state = substep(fn)
    assert state["traction_load"] == pytest.approx(np.mean(hops), rel=1e-5)
    assert state["stance"] == pytest.approx(len(hops) * dt) and state["slip"] == pytest.approx(len(hops) * dt * 0.5)
    arrays["sinkage"].fill_(0.1)
    near.fill_(int(K.ON_FLOOR))  # a sliding sole hopping 1-2 cm above the floor it stood on, out of its rut
    for _ in range(20):
        state = substep(0.0)
    assert state["stance"] > len(hops) * dt and state["slip"] > len(hops) * dt * 0.5
    assert state["sinkage"] == 0.0  # out of its rut: left behind
    slip = state["slip"]
    arrays["sinkage"].fill_(0.1)
    near.fill_(int(K.IN_RUT))  # swinging inside its deep rut: the stance has ended, the rut and slip stay
    state = substep(0.0)
    assert state["stance"] == 0.0 and state["traction_load"] == 0.0 and state["sinkage"] == pytest.approx(0.1)
    assert state["slip"] == pytest.approx(slip + dt * 0.5)  # its last substep of stance counted
    near.fill_(0)  # clear of the ground and 100 ms without load: lifted off
    state = substep(0.0)
    assert state["slip"] == 0.0 and state["sinkage"] == 0.0


def test_the_rut_s_load_is_f_n_through_two_low_passes_in_series():
    """A foot whose rut deepens chatters (F_N 0 to 4 W, 25 Hz at 5 ms substeps); the rut keeps every peak of the
    load it deepens under, so that load is F_N through two first-order low-passes of sinkage_load_tau (50 ms) in
    series: x += a (F_N - x), y += a (x - y), a = dt / tau, worked out here step by step. A ripple of mean W
    peaks at 1.24 W through one and at 1.03 W through both."""
    dt, tau, weight = 0.005, 0.05, 400.0
    arrays = {name: wp.zeros((1, 1), dtype=float, device=DEV)
              for name in ("fn", "slip", "air", "stance", "load", "sink_load", "traction_load", "sinkage")}
    vel = wp.zeros((1, 1), dtype=wp.vec3, device=DEV)
    near = wp.zeros((1, 1), dtype=int, device=DEV)
    a = dt / tau
    x = y = 0.0
    peaks = [0.0, 0.0]
    ripple = [4.0, 2.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0]  # in W: 40 ms, mean W
    for k in range(400):
        fn = ripple[k % 8] * weight
        arrays["fn"].fill_(fn)
        wp.launch(K.foot_state_kernel, dim=(1, 1), device=DEV,
                  inputs=[dt, 1.0, a, dt / 0.3, arrays["fn"], vel, 0.05, near, arrays["slip"], arrays["air"],
                          arrays["stance"], arrays["load"], arrays["sink_load"], arrays["traction_load"],
                          arrays["sinkage"]])
        x += a * (fn - x)
        y += a * (x - y)
        assert arrays["load"].numpy()[0, 0] == pytest.approx(x, rel=1e-5)
        assert arrays["sink_load"].numpy()[0, 0] == pytest.approx(y, rel=1e-5)
        if k >= 200:
            peaks = [max(peaks[0], x), max(peaks[1], y)]
    assert peaks[0] > 1.2 * weight and peaks[1] < 1.03 * weight, peaks
