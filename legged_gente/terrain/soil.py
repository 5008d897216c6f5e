"""Deformable-soil presets: Bekker pressure-sinkage, Mohr-Coulomb shear strength, Janosi-Hanamoto shear
deformation and Bekker bulldozing parameters.

Every parameter is a ``(mean, std)`` pair: the force field draws one value per env per episode from this
Gaussian (the GenTe paper's per-episode domain randomisation). Means come from the terramechanics literature
named next to each preset; the standard deviations are ours (about 10-20 % of the mean), reflecting the
scatter of repeated bevameter tests that Wong reports for one soil, since the tables give means only.

Units (SI):
    kc:   cohesive modulus of deformation, N/m^(n+1)          (Bekker 1969; Wong, *Theory of Ground Vehicles*)
    kphi: frictional modulus of deformation, N/m^(n+2)        (same)
    n:    exponent of deformation, 1                           (same)
    c:    cohesion, Pa                                         (same table)
    mu:   tan(phi), phi the soil's angle of internal shearing resistance, 1 (same table)
    K:    Janosi-Hanamoto shear deformation modulus, m
    bulldoze_c: Bekker bulldozing coefficient of z, N/m^2 per metre of foot width (0.67 c K_pc)
    bulldoze_g: Bekker bulldozing coefficient of z^2, N/m^3 per metre of foot width (0.5 gamma K_pgamma)
    zeta: resistive force theory's medium constant, N/m^3: the vertical stress per unit depth on a horizontal
          plate pushed straight down (Li, Zhang & Goldman, Science 2013); 0 for Bekker soils

Each preset names its granular ``model``: "bekker" (Bekker sinkage and bulldozing, the default of every
natural soil here; the shipped policies were trained with it) or "rft" (resistive force theory: a sole sinks
until RFT's vertical stress under its motion, alpha_z(beta, gamma) |z|, carries its load: zeta |z| at rest or
pushed down, Bekker's law with n = 1, kc = 0, kphi = zeta; its resistance to moving through the medium is the
RFT stresses on its sole plate's elements and on its leading face in place of bulldozing; see
:func:`rft_preset`).

The traction a foot can get from a soil is its shear strength (Mohr-Coulomb: c A + F_N tan phi, A the sole
area), mobilised with the foot's slip j as Janosi and Hanamoto measured: (c A + F_N tan phi)(1 - exp(-j/K)).
Bulldozing is Bekker's resistance per unit width (Bekker 1960/1969, Wong ch. 2) with both its terms:
R_b/b = 0.67 c z K_pc + 0.5 z^2 gamma K_pgamma, K_pc = (N_c - tan phi) cos^2 phi and
K_pgamma = (2 N_gamma / tan phi + 1) cos^2 phi; :func:`bulldozing_coefficients` computes both from (c, phi,
gamma). Which term dominates depends on the soil and the sinkage: for the cohesive soils (mud, clay loam)
the cohesion term, for dry sand at a few centimetres the gamma term.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

PARAM_NAMES = ("kc", "kphi", "n", "c", "mu", "K", "bulldoze_c", "bulldoze_g", "zeta")
"""Order of the parameters in :func:`preset_table` (the force kernels index columns by this order); the table
has one more column, the model (0 Bekker, 1 RFT)."""
MODELS = ("bekker", "rft")


def bulldozing_coefficients(c: float, phi_deg: float, gamma: float) -> tuple[float, float]:
    """Bekker's bulldozing coefficients (0.67 c K_pc, 0.5 gamma K_pgamma) of a soil (Wong, ch. 2).

    Bearing-capacity factors in closed form: N_q = exp(pi tan phi) tan^2(45 deg + phi/2) (Prandtl-Reissner),
    N_c = (N_q - 1) cot phi, N_gamma = (N_q - 1) tan(1.4 phi) (Meyerhof 1963). Wong tabulates Terzaghi's
    factors: these are 13-19 % lower at the presets' 11-29 deg (N_c 25.8 against Terzaghi's 31.6 at 28 deg). At phi = 0 (a clay, undrained) the limits: N_c = pi + 2
    (Prandtl) and 2 N_gamma / tan phi = 0. Meyerhof's tan(1.4 phi) diverges at phi = 64.3 deg: phi must be below 64.
    """
    if not 0.0 <= phi_deg < 64.0:
        raise ValueError(f"bulldozing_coefficients: phi_deg={phi_deg!r} is outside [0, 64) degrees, where the "
                         f"bearing-capacity factors hold (Meyerhof's tan(1.4 phi) diverges at 64.3); give the soil's "
                         f"friction angle in degrees.")
    if phi_deg == 0.0:
        return 0.67 * c * (math.pi + 2.0), 0.5 * gamma
    phi = math.radians(phi_deg)
    nq = math.exp(math.pi * math.tan(phi)) * math.tan(math.pi / 4 + phi / 2) ** 2
    nc = (nq - 1.0) / math.tan(phi)
    ngamma = (nq - 1.0) * math.tan(1.4 * phi)
    kpc = (nc - math.tan(phi)) * math.cos(phi) ** 2
    kpgamma = (2.0 * ngamma / math.tan(phi) + 1.0) * math.cos(phi) ** 2
    return 0.67 * c * kpc, 0.5 * gamma * kpgamma


MAX_MU = 2.0
"""The largest soil friction coefficient tan(phi) accepted: 63 deg, past the internal friction angle of the soils
Wong tabulates (Theory of Ground Vehicles, ch. 2; the presets below: 11-29 deg)."""
MAX_K = 0.5
"""The largest shear deformation modulus K (m) accepted: soils mobilise their shear strength over centimetres of
slip (the presets below: K = 0.01-0.05 m); half a metre would mobilise nothing under a foot."""


@dataclasses.dataclass(frozen=True)
class SoilPreset:
    """One deformable soil: each parameter a ``(mean, std)`` pair in the SI units of the module docstring."""

    kc: tuple[float, float]
    kphi: tuple[float, float]
    n: tuple[float, float]
    c: tuple[float, float]
    mu: tuple[float, float]
    K: tuple[float, float]
    bulldoze_c: tuple[float, float]
    bulldoze_g: tuple[float, float]
    zeta: tuple[float, float] = (0.0, 0.0)
    model: str = "bekker"
    source: str = ""

    def __post_init__(self):
        if self.model not in MODELS:
            raise ValueError(f"SoilPreset.model={self.model!r}: must be one of {MODELS}.")
        for name in PARAM_NAMES:
            value = getattr(self, name)
            if not (isinstance(value, tuple) and len(value) == 2):
                raise ValueError(f"SoilPreset.{name} must be a (mean, std) tuple, got {value!r}.")
            mean, std = value
            if not (math.isfinite(mean) and math.isfinite(std)) or std < 0:
                raise ValueError(f"SoilPreset.{name}=({mean}, {std}): mean must be finite and std >= 0.")
            if name in ("kphi", "n", "K") and mean <= 0:
                # kc may be ~0 (Grenville loam) or slightly negative in Wong's fits; c, bulldozing terms may be 0
                raise ValueError(f"SoilPreset.{name} mean must be > 0, got {mean}.")
            if name in ("c", "mu", "bulldoze_c", "bulldoze_g", "zeta") and mean < 0:
                raise ValueError(f"SoilPreset.{name} mean must be >= 0, got {mean}.")
        # bounds no soil reaches, which a value in the wrong unit crosses: tan(phi) of 28 deg given as 28, K in cm
        if self.mu[0] > MAX_MU:
            raise ValueError(f"SoilPreset.mu={self.mu}: mu is tan(phi), dimensionless, at most {MAX_MU} (phi "
                             f"{math.degrees(math.atan(MAX_MU)):.0f} deg); for phi in degrees give "
                             f"math.tan(math.radians(phi)) (28 deg: 0.53).")
        if self.K[0] > MAX_K:
            raise ValueError(f"SoilPreset.K={self.K}: K is Janosi-Hanamoto's shear deformation modulus in metres, "
                             f"at most {MAX_K} m (the presets: 0.01-0.05 m); 2.5 cm is 0.025.")
        if self.model == "rft" and not self.zeta[0] > 0:  # after the pair checks: zeta is a pair here
            raise ValueError(f"SoilPreset.zeta={self.zeta}: an 'rft' soil needs zeta > 0 N/m^3 (Li et al. 2013).")


def _pct(mean: float, frac: float) -> tuple[float, float]:
    return (mean, abs(mean) * frac)


def _bekker(kc, kphi, n, c, phi_deg, gamma, K, source) -> SoilPreset:
    """A Bekker soil from Wong's table values (kc, kphi in N/m^(n+1), N/m^(n+2); c in Pa; phi in degrees),
    its unit weight gamma (N/m^3) for bulldozing and its shear deformation modulus K (m)."""
    bc, bg = bulldozing_coefficients(c, phi_deg, gamma)
    return SoilPreset(kc=_pct(kc, 0.2), kphi=_pct(kphi, 0.15), n=_pct(n, 0.05), c=_pct(c, 0.15),
                      mu=_pct(math.tan(math.radians(phi_deg)), 0.1), K=_pct(K, 0.2), bulldoze_c=_pct(bc, 0.2),
                      bulldoze_g=_pct(bg, 0.2), source=source)


def rft_preset(zeta, c, phi_deg, K, source) -> SoilPreset:
    """A granular medium under resistive force theory: its constant zeta (N/m^3) and, for the contact's traction
    limit, its cohesion c (Pa), friction angle phi (degrees) and shear modulus K (m).

    RFT's stress on a horizontal sole pushed straight down is alpha_z(0, pi/2) |z| = zeta |z|: the sinkage law
    p = zeta z, which is Bekker's with kc = 0, kphi = zeta, n = 1 (the values given here, which the observations
    show). The rut itself uses zeta times the sole's current alpha_z / zeta (``kernels.rut_sinkage_fn``), so a
    moving sole sinks as RFT says. No bulldozing: the RFT stresses on the sole plate's elements and its leading face replace it."""
    return SoilPreset(kc=(0.0, 0.0), kphi=_pct(zeta, 0.15), n=(1.0, 0.0), c=_pct(c, 0.15),
                      mu=_pct(math.tan(math.radians(phi_deg)), 0.1), K=_pct(K, 0.2), bulldoze_c=(0.0, 0.0),
                      bulldoze_g=(0.0, 0.0), zeta=_pct(zeta, 0.15), model="rft", source=source)


SOIL_PRESETS: dict[str, SoilPreset] = {
    # Dry sand, Land Locomotion Lab. (LLL), Wong Table 2.3: n=1.1, kc=0.99 kN/m^(n+1), kphi=1528.43 kN/m^(n+2),
    # c=1.04 kPa, phi=28 deg. K = 2.5 cm for loose sand (Wong, Janosi-Hanamoto K values); gamma ~ 15.7 kN/m^3.
    "dry_sand": _bekker(0.99e3, 1528.43e3, 1.1, 1.04e3, 28.0, 15.7e3, 0.025,
                        "Wong, Theory of Ground Vehicles, Table 2.3 (dry sand, LLL); Bekker 1969"),
    # Wet sand: sandy loam at 15 % moisture, LLL, Wong Table 2.3: n=0.7, kc=5.27e3, kphi=1515.04e3,
    # c=1.72 kPa, phi=29 deg. K = 1 cm for firm sandy terrain (Wong); gamma ~ 18 kN/m^3.
    "wet_sand": _bekker(5.27e3, 1515.04e3, 0.7, 1.72e3, 29.0, 18.0e3, 0.010,
                        "Wong, Theory of Ground Vehicles, Table 2.3 (sandy loam 15% moisture, LLL)"),
    # Snow (U.S.), Wong Table 2.3: n=1.6, kc=4.37e3, kphi=196.72e3, c=1.03 kPa, phi=19.7 deg (the table's
    # "U.S., Harrison" row is another snow: n=1.6, kc=2.49e3, kphi=245.90e3, c=0.62 kPa, phi=23.2 deg).
    # K = 5 cm (2 in.) for undisturbed fresh snow (Wong, sec. 2.4.3, after Bekker); gamma ~ 3 kN/m^3 (settled snow).
    # A 41.5 kg biped on one 0.22 x 0.096 m sole (19.3 kPa) sinks ~21 cm.
    "snow": _bekker(4.37e3, 196.72e3, 1.6, 1.03e3, 19.7, 3.0e3, 0.050,
                    "Wong, Theory of Ground Vehicles, Table 2.3 (snow, U.S.)"),
    # Mud: sandy loam at 32 % moisture (Hanamoto), Wong Table 2.3: n=0.5, kc=0.77e3, kphi=51.91e3, c=5.17 kPa,
    # phi=11 deg: a saturated, soft soil. Checked against the table as reproduced in a public SCM terramechanics
    # parameter set (Wong 2008 rows; its lean clay at 32 % is n=0.15, kc=1.52e3, kphi=119.61e3, c=13.79 kPa,
    # phi=11 deg, which this preset once mixed up with the sandy loam's n and c). Sinks (19.3e3 / (0.77e3/0.096 +
    # 51.91e3))^2 = 10.3 cm under a 41.5 kg biped's single support (19.3 kPa); Wong's wet clays of the table
    # (n = 0.11-0.15) sink micrometres at that pressure, his firm clayey soil of Thailand 0.5 mm. K ~ 5 cm for
    # a saturated soft soil (Wong reports several cm for soft wet soils; not in Table 2.3); gamma ~ 17 kN/m^3.
    "mud": _bekker(0.77e3, 51.91e3, 0.5, 5.17e3, 11.0, 17.0e3, 0.050,
                   "Wong, Theory of Ground Vehicles, Table 2.3 (sandy loam 32% moisture, Hanamoto)"),
    # Clay loam: North Gower clayey loam at 46 % moisture, Wong Table 2.3: n=0.73, kc=41.6e3, kphi=2471e3,
    # c=6.1 kPa, phi=26.6 deg. K = 0.6 cm for clay at maximum compaction; ~1 cm here (Wong); gamma ~ 18 kN/m^3.
    "clay_loam": _bekker(41.6e3, 2471e3, 0.73, 6.1e3, 26.6, 18.0e3, 0.010,
                         "Wong, Theory of Ground Vehicles, Table 2.3 (North Gower clayey loam)"),
    # Poppy seeds, closely packed, under RFT: Li, Zhang & Goldman 2013 (Table S2) fit this medium with
    # A00 + A10 + B11 + B01 + B-11 = 0.094 + 0.092 + 0.092 + 0.151 + 0.035 = 0.464 N/cm^3: zeta = 4.64e5 N/m^3
    # (0.25 N/cm^3 loosely packed). A 20 kg load on a 0.22 m x 0.09 m sole (9.9 kPa) sinks 2.1 cm. Li et al. give
    # no Mohr-Coulomb values for the seeds: the traction limit borrows dry sand's (c = 0, phi = 28 deg, Wong
    # Table 2.3, cohesion dropped: dry grains) and its K = 2.5 cm.
    "poppy_seeds_rft": rft_preset(4.64e5, 0.0, 28.0, 0.025,
                                  "Li, Zhang & Goldman, Science 2013 (closely packed poppy seeds); traction: Wong "
                                  "Table 2.3 dry sand"),
}


def _mean_std(soil: str, param: str, value) -> tuple[float, float]:
    """A ``(mean, std)`` pair of floats from a pair or a bare number (std 0)."""
    try:
        pair = tuple(float(x) for x in value) if np.ndim(value) else (float(value), 0.0)
    except (TypeError, ValueError):
        pair = ()
    if len(pair) != 2:
        raise ValueError(f"register_custom_soil({soil!r}): {param}={value!r} is not a number or a (mean, std) pair; give "
                         f"e.g. {param}=(1000.0, 100.0) or {param}=1000.0.")
    return pair


def register_custom_soil(name: str, **params) -> SoilPreset:
    """Add a soil to :data:`SOIL_PRESETS` under ``name``.

    Each of ``PARAM_NAMES`` is a ``(mean, std)`` pair (a bare number means std 0; see
    :func:`bulldozing_coefficients` for the bulldozing pair); ``zeta`` (default 0), ``model`` ("bekker" or "rft",
    default "bekker"; an RFT soil is best made with :func:`rft_preset`'s values) and ``source`` (str) are
    optional. Re-registering a built-in name raises; re-registering a custom name replaces it.
    """
    if not isinstance(name, str) or not name.isidentifier():
        raise ValueError(f"Soil name must be a python identifier like 'peat', got {name!r}.")
    if name in _BUILTIN:
        raise ValueError(f"{name!r} is a built-in soil preset; register yours under another name.")
    missing = [p for p in PARAM_NAMES if p not in params and p != "zeta"]
    unknown = sorted(set(params) - set(PARAM_NAMES) - {"source", "model"})
    if missing or unknown:
        raise ValueError(
            f"register_custom_soil({name!r}): missing {missing}, unknown {unknown}; give exactly "
            f"{list(PARAM_NAMES[:-1])} as (mean, std) pairs (and optionally zeta=..., model=..., source=...)."
        )
    params = {"zeta": 0.0, **params}
    fields = {p: _mean_std(name, p, params[p]) for p in PARAM_NAMES}
    preset = SoilPreset(**fields, model=str(params.get("model", "bekker")), source=str(params.get("source", "custom")))
    SOIL_PRESETS[name] = preset
    return preset


def preset_table(names: list[str]) -> np.ndarray:
    """``(max(len(names), 1), len(PARAM_NAMES) + 1, 2)`` float32 (mean, std) of the named presets, in order; the
    last column is the model (1 for "rft", 0 for "bekker", std 0).

    This is what the force kernels read: ``MaterialMap.soil`` indexes its first axis. With no names one
    all-zero row is returned so device arrays are never empty (no cell indexes it).
    """
    unknown = [n for n in names if n not in SOIL_PRESETS]
    if unknown:
        raise KeyError(
            f"Unknown soil preset(s) {unknown}; known: {sorted(SOIL_PRESETS)}. Register custom soils with "
            f"register_custom_soil(name, ...)."
        )
    table = np.zeros((max(len(names), 1), len(PARAM_NAMES) + 1, 2), np.float32)
    for i, name in enumerate(names):
        preset = SOIL_PRESETS[name]
        table[i] = [getattr(preset, p) for p in PARAM_NAMES] + [(float(preset.model == "rft"), 0.0)]
    return table


_BUILTIN = frozenset(SOIL_PRESETS)
