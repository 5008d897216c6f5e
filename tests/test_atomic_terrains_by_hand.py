"""Atomic terrains' declared height bounds and parameter docs, and the soil helpers, against values worked out by hand.

Complements tests/test_terrain.py (bounds at the curriculum's difficulties) and tests/test_terrain_by_hand.py
(each terrain's geometry): here the bounds hold for any parameters inside their declared ranges.
"""

import math
import re
import warnings

import numpy as np
import pytest

from legged_gente.terrain.registry import ATOMIC_TERRAINS
from legged_gente.terrain.soil import SoilPreset, bulldozing_coefficients

GEOMETRIC = sorted(n for n, a in ATOMIC_TERRAINS.items() if a.kind == "geometric")


def _random_params(a, rng):
    """Every numeric parameter uniform in its declared range, its ends one draw in five; choices uniform."""
    params = {}
    for name, p in a.params.items():
        if p.choices is not None:
            params[name] = p.choices[rng.integers(len(p.choices))]
        elif p.integer:
            params[name] = int(rng.integers(p.low, p.high + 1))
        else:
            r = rng.random()
            params[name] = p.low if r < 0.1 else p.high if r < 0.2 else float(rng.uniform(p.low, p.high))
    return params


# ------------------------------------------------------------------------------------------------- bounds
@pytest.mark.parametrize("name", GEOMETRIC)
def test_declared_bounds_hold_every_height_for_random_parameters_in_range(name):
    """``height_bounds(params, nx * res, ny * res)`` promises the range of every height the terrain makes; the
    generation validator and the benchmark checker rely on it. 60 random parameter sets within the declared
    ranges (cross-field rules respected), on odd and even regions of 0.05-0.2 m cells."""
    a = ATOMIC_TERRAINS[name]
    rng = np.random.default_rng(11)
    built = 0
    for trial in range(60):
        raw = _random_params(a, rng)
        if name == "river":
            raw["offset"] = float(rng.uniform(-1.0, 1.0))  # keep the channel in the region
        try:
            params = a.check_params(raw)
        except ValueError:
            continue
        res = float(rng.choice([0.05, 0.1, 0.13, 0.2]))
        shape = (int(rng.integers(5, 70)), int(rng.integers(5, 70)))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            h = a.fn(shape, res, np.random.default_rng(trial), **params)
        lo, hi = a.height_bounds(params, shape[0] * res, shape[1] * res)
        assert lo - 1e-6 <= h.min() and h.max() <= hi + 1e-6, (params, shape, res, h.min(), h.max(), lo, hi)
        built += 1
    assert built >= 30


def test_stepping_stone_tops_below_a_shallow_floor_stay_in_the_declared_bounds():
    """depth 0.05 m, height_noise 0.1 m: the floor is at -0.05 m and a stone's top is drawn in [-0.1, 0.1] m, so a
    top can lie below the floor, down to -0.1 m. The declared range must reach -max(depth, height_noise) = -0.1 m;
    it said -depth = -0.05 m. Stones 0.5 m with 0.5 m gaps on 10 m x 10 m: 100 stones, and with seed 0 some
    top is below -0.05 m."""
    a = ATOMIC_TERRAINS["stepping_stones"]
    params = a.check_params({"stone_size": 0.5, "stone_distance": 0.5, "depth": 0.05, "height_noise": 0.1,
                             "platform": 0.0})
    h = a.fn((100, 100), 0.1, np.random.default_rng(0), **params)
    assert h.min() < -0.05 - 1e-3  # a stone top below the floor
    assert a.height_bounds(params, 10.0, 10.0) == pytest.approx((-0.1, 0.1))
    deep = a.check_params({**params, "depth": 0.5})
    assert a.height_bounds(deep, 10.0, 10.0) == pytest.approx((-0.5, 0.1))  # the usual case: the floor is lowest


# ---------------------------------------------------------------------------------------- parameter docs
@pytest.mark.parametrize("name", ["natural_ground", "hills"])
def test_the_amplitude_of_noise_relief_is_documented_as_the_bound_its_peaks_stay_under(name):
    """Perlin relief is scaled so that |height| <= amplitude (2-D Perlin noise with unit gradients is bounded by
    sqrt(2)/2, hence the factor sqrt(2)); its peaks come nowhere near that bound: on an 8 m region with the default
    wavelength and octaves the largest |height| of 20 seeds is 0.3-0.7 times the amplitude. The doc must not
    promise the amplitude as the largest height (a user asking for 0.3 m of relief got 0.15 m) and must give the
    fraction the peaks do reach."""
    a = ATOMIC_TERRAINS[name]
    params = a.check_params({"amplitude": 0.2, "platform": 0.0})
    peaks = [float(np.abs(a.fn((80, 80), 0.1, np.random.default_rng(s), **params)).max()) / 0.2 for s in range(20)]
    assert 0.3 <= min(peaks) and max(peaks) <= 0.75, peaks
    doc = a.params["amplitude"].doc
    assert not doc.startswith("largest |height|"), doc
    fraction = re.search(r"peaks reach about (0\.\d+)-(0\.\d+) of it", doc)
    assert fraction, doc
    lo, hi = float(fraction.group(1)), float(fraction.group(2))
    assert lo <= float(np.median(peaks)) <= hi, (np.median(peaks), doc)


# ----------------------------------------------------------------------------------------------------- soil
def test_bulldozing_coefficients_of_a_frictionless_clay_are_prandtls_limits():
    """phi = 0 (a saturated clay, undrained): N_q = e^0 tan^2(45 deg) = 1, and (N_q - 1) / tan(phi) tends to
    pi + 2 = 5.14 (Prandtl's N_c); N_gamma = (N_q - 1) tan(1.4 phi) vanishes as phi^2, so 2 N_gamma / tan(phi) -> 0.
    K_pc = (5.14 - 0) cos^2 0 = pi + 2 and K_pgamma = (0 + 1) cos^2 0 = 1: with c = 20 kPa and gamma = 17 kN/m^3
    the coefficients are 0.67 * 20e3 * (pi + 2) = 68.9 kN/m^2 and 0.5 * 17e3 = 8.5 kN/m^3. A division by
    tan(0) raised ZeroDivisionError; 0.001 deg gives nearly the same values."""
    bc, bg = bulldozing_coefficients(20e3, 0.0, 17e3)
    assert bc == pytest.approx(0.67 * 20e3 * (math.pi + 2.0), rel=1e-9)
    assert bg == pytest.approx(0.5 * 17e3, rel=1e-9)
    near = bulldozing_coefficients(20e3, 1e-3, 17e3)
    assert near[0] == pytest.approx(bc, rel=1e-3) and near[1] == pytest.approx(bg, rel=1e-3)


@pytest.mark.parametrize("phi", [-5.0, 64.5, 90.0, float("nan")])
def test_bulldozing_coefficients_refuse_a_friction_angle_outside_the_formulas_range(phi):
    """Meyerhof's N_gamma = (N_q - 1) tan(1.4 phi) turns infinite at 1.4 phi = 90 deg (phi = 64.3 deg) and negative
    beyond; a negative phi is no soil. Such an angle gave negative or non-finite coefficients silently (or an error
    naming bulldoze_g, not phi)."""
    with pytest.raises(ValueError, match=r"^bulldozing_coefficients: phi_deg=.* is outside \[0, 64\) degrees"):
        bulldozing_coefficients(1e3, phi, 15e3)


def test_an_rft_soil_with_a_bare_number_for_zeta_is_refused_in_one_line():
    """Every parameter of a SoilPreset is a (mean, std) pair; a bare number is refused naming the field. For zeta
    of an 'rft' soil the model check read zeta[0] first and raised TypeError ('float' object is not
    subscriptable)."""
    pairs = {k: (1.0, 0.0) for k in ("kc", "kphi", "n", "c", "mu", "K", "bulldoze_c", "bulldoze_g")}
    with pytest.raises(ValueError, match=r"SoilPreset\.zeta must be a \(mean, std\) tuple, got 464000\.0"):
        SoilPreset(**pairs, zeta=4.64e5, model="rft")


def test_meanders_steeper_than_45_degrees_to_the_axis_are_refused():
    """The channel's width is measured across its mean axis; where a meander y = A sin(2 pi x / L) runs at
    slope k = 2 pi A / L to it, the width perpendicular to the course is width / sqrt(1 + k^2). k > 1 (a course
    steeper than 45 degrees, over 29 % narrower) is refused; the steepest of the shipped specs, k = 0.39 (7 %),
    is not."""
    river = ATOMIC_TERRAINS["river"]
    with pytest.raises(ValueError, match=r"river: meanders of 1 m every 4 m .* meander_amplitude <= meander_wavelength / \(2 pi\) = 0.637 m"):
        river.check_params({"meander_amplitude": 1.0, "meander_wavelength": 4.0})
    k = 2 * math.pi * 0.5 / 8.0
    assert k == pytest.approx(0.3927, abs=1e-4) and 1 / math.sqrt(1 + k * k) == pytest.approx(0.931, abs=1e-3)
    river.check_params({"meander_amplitude": 0.5, "meander_wavelength": 8.0})
    river.check_params({"meander_amplitude": 4.0 / (2 * math.pi), "meander_wavelength": 4.0})  # k = 1 exactly
