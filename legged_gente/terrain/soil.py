"""Deformable-soil presets: Bekker pressure-sinkage, bulldozing, friction and shear-deformation parameters.

Every parameter is a ``(mean, std)`` pair: the force field draws one value per env per episode from this
Gaussian (the GenTe paper's per-episode domain randomisation). Means come from the terramechanics literature
named next to each preset; the standard deviations are ours (about 10-20 % of the mean), reflecting the
scatter of repeated bevameter tests that Wong reports for one soil, since the tables give means only.

Units (SI):
    kc:   cohesive modulus of deformation, N/m^(n+1)          (Bekker 1969; Wong, *Theory of Ground Vehicles*)
    kphi: frictional modulus of deformation, N/m^(n+2)        (same)
    n:    exponent of deformation, 1                           (same)
    bulldoze_a: bulldozing coefficient per metre of foot width, N/m^(bulldoze_n+1); the force on a foot of
          width b sunk by z is ``b * bulldoze_a * z**bulldoze_n`` (the GenTe paper's a*z^n with a = b*bulldoze_a)
    bulldoze_n: bulldozing exponent, 1
    mu:   soil-foot friction coefficient, 1 (Mohr-Coulomb tan(phi) of the soil's internal friction angle)
    K:    Janosi-Hanamoto shear deformation modulus, m

Bulldozing coefficients follow Bekker's bulldozing resistance per unit width (Bekker 1960/1969, as given in
Wong ch. 2): R_b/b = 0.67 c z K_pc + 0.5 z^2 gamma K_pgamma. For frictional soils (sand, snow) the second
term dominates: a = 0.5 gamma K_pgamma, n = 2. For cohesive soils (mud, clay) the first dominates:
a = 0.67 c K_pc, n = 1. K_pc = (N_c - tan phi) cos^2 phi and K_pgamma = (2 N_gamma / tan phi + 1) cos^2 phi
use Terzaghi's bearing-capacity factors N_c, N_gamma at the soil's phi.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

PARAM_NAMES = ("kc", "kphi", "n", "bulldoze_a", "bulldoze_n", "mu", "K")
"""Order of the parameters in :func:`preset_table` (the force kernels index columns by this order)."""


@dataclasses.dataclass(frozen=True)
class SoilPreset:
    """One deformable soil: each field a ``(mean, std)`` pair in the SI units of the module docstring."""

    kc: tuple[float, float]
    kphi: tuple[float, float]
    n: tuple[float, float]
    bulldoze_a: tuple[float, float]
    bulldoze_n: tuple[float, float]
    mu: tuple[float, float]
    K: tuple[float, float]
    source: str = ""

    def __post_init__(self):
        for name in PARAM_NAMES:
            value = getattr(self, name)
            if not (isinstance(value, tuple) and len(value) == 2):
                raise ValueError(f"SoilPreset.{name} must be a (mean, std) tuple, got {value!r}.")
            mean, std = value
            if not (math.isfinite(mean) and math.isfinite(std)) or std < 0:
                raise ValueError(f"SoilPreset.{name}=({mean}, {std}): mean must be finite and std >= 0.")
            if name != "kc" and mean <= 0:
                # kc may be ~0 (Grenville loam) or slightly negative in Wong's fits; the others must be positive.
                raise ValueError(f"SoilPreset.{name} mean must be > 0, got {mean}.")


def _pct(mean: float, frac: float) -> tuple[float, float]:
    return (mean, abs(mean) * frac)


SOIL_PRESETS: dict[str, SoilPreset] = {
    # Dry sand, Land Locomotion Lab. (LLL), Wong Table 2.3: n=1.1, kc=0.99 kN/m^(n+1), kphi=1528.43 kN/m^(n+2),
    # phi=28 deg (mu = tan 28 = 0.53). K = 2.5 cm for loose sand (Wong, Janosi-Hanamoto K values).
    # Bulldozing: gamma ~ 15.7 kN/m^3, N_gamma(28 deg) ~ 13 -> K_pgamma ~ 39 -> a = 0.5*gamma*K_pgamma ~ 3.1e5.
    "dry_sand": SoilPreset(
        kc=_pct(0.99e3, 0.2), kphi=_pct(1528.43e3, 0.15), n=_pct(1.1, 0.05),
        bulldoze_a=_pct(3.1e5, 0.2), bulldoze_n=_pct(2.0, 0.05), mu=_pct(0.53, 0.1), K=_pct(0.025, 0.2),
        source="Wong, Theory of Ground Vehicles, Table 2.3 (dry sand, LLL); Bekker 1969",
    ),
    # Wet sand: sandy loam at 15 % moisture, LLL, Wong Table 2.3: n=0.7, kc=5.27e3, kphi=1515.04e3, phi=29 deg
    # (mu = 0.55). K = 1 cm for firm sandy terrain (Wong). Bulldozing with gamma ~ 18 kN/m^3 (wet),
    # N_gamma(29 deg) ~ 14 -> K_pgamma ~ 40 -> a ~ 3.6e5, n = 2.
    "wet_sand": SoilPreset(
        kc=_pct(5.27e3, 0.2), kphi=_pct(1515.04e3, 0.15), n=_pct(0.7, 0.05),
        bulldoze_a=_pct(3.6e5, 0.2), bulldoze_n=_pct(2.0, 0.05), mu=_pct(0.55, 0.1), K=_pct(0.010, 0.2),
        source="Wong, Theory of Ground Vehicles, Table 2.3 (sandy loam 15% moisture, LLL)",
    ),
    # Snow (U.S., Harrison), Wong Table 2.3: n=1.6, kc=4.37e3, kphi=196.72e3, phi=19.7 deg (mu = 0.36).
    # K = 4 cm for undisturbed fresh snow (Wong, snow shear tests). Bulldozing with gamma ~ 3 kN/m^3
    # (settled snow), N_gamma(20 deg) ~ 4 -> K_pgamma ~ 20 -> a ~ 3e4, n = 2.
    "snow": SoilPreset(
        kc=_pct(4.37e3, 0.2), kphi=_pct(196.72e3, 0.2), n=_pct(1.6, 0.05),
        bulldoze_a=_pct(3.0e4, 0.25), bulldoze_n=_pct(2.0, 0.05), mu=_pct(0.36, 0.1), K=_pct(0.040, 0.2),
        source="Wong, Theory of Ground Vehicles, Table 2.3 (snow, U.S., Harrison)",
    ),
    # Mud: clayey soil at 38 % moisture (Thailand), Wong Table 2.3: n=0.5, kc=13.19e3, kphi=692.15e3,
    # c=4.14 kPa, phi=13 deg (mu = 0.23). K ~ 5 cm for saturated, remoulded fine-grained soil (Wong reports
    # several cm for muskeg/soft wet soils). Bulldozing, cohesive term: N_c(13 deg) ~ 10 -> K_pc ~ 9.3 ->
    # a = 0.67*c*K_pc ~ 2.6e4 N/m^2 per unit width, n = 1.
    "mud": SoilPreset(
        kc=_pct(13.19e3, 0.2), kphi=_pct(692.15e3, 0.2), n=_pct(0.5, 0.05),
        bulldoze_a=_pct(2.6e4, 0.25), bulldoze_n=_pct(1.0, 0.05), mu=_pct(0.23, 0.15), K=_pct(0.050, 0.25),
        source="Wong, Theory of Ground Vehicles, Table 2.3 (clayey soil 38% moisture, Thailand)",
    ),
    # Clay loam: North Gower clayey loam at 46 % moisture, Wong Table 2.3: n=0.73, kc=41.6e3, kphi=2471e3,
    # c=6.1 kPa, phi=26.6 deg (mu = 0.50). K = 0.6 cm for clay at maximum compaction; ~1 cm here (Wong).
    # Bulldozing, cohesive term: N_c(26.6 deg) ~ 27 -> K_pc ~ 21 -> a = 0.67*c*K_pc ~ 8.6e4, n = 1.
    "clay_loam": SoilPreset(
        kc=_pct(41.6e3, 0.2), kphi=_pct(2471e3, 0.15), n=_pct(0.73, 0.05),
        bulldoze_a=_pct(8.6e4, 0.2), bulldoze_n=_pct(1.0, 0.05), mu=_pct(0.50, 0.1), K=_pct(0.010, 0.2),
        source="Wong, Theory of Ground Vehicles, Table 2.3 (North Gower clayey loam)",
    ),
}


def register_custom_soil(name: str, **params) -> SoilPreset:
    """Add a soil to :data:`SOIL_PRESETS` under ``name``.

    Each of ``kc, kphi, n, bulldoze_a, bulldoze_n, mu, K`` is a ``(mean, std)`` pair (a bare number means
    std 0); ``source`` (str) is optional. Re-registering a built-in name raises; re-registering a custom
    name replaces it.
    """
    if not isinstance(name, str) or not name.isidentifier():
        raise ValueError(f"Soil name must be a python identifier like 'peat', got {name!r}.")
    if name in _BUILTIN:
        raise ValueError(f"{name!r} is a built-in soil preset; register yours under another name.")
    missing = [p for p in PARAM_NAMES if p not in params]
    unknown = sorted(set(params) - set(PARAM_NAMES) - {"source"})
    if missing or unknown:
        raise ValueError(
            f"register_custom_soil({name!r}): missing {missing}, unknown {unknown}; give exactly "
            f"{list(PARAM_NAMES)} as (mean, std) pairs (and optionally source=...)."
        )
    fields = {
        p: tuple(float(x) for x in params[p]) if np.ndim(params[p]) else (float(params[p]), 0.0)
        for p in PARAM_NAMES
    }
    preset = SoilPreset(**fields, source=str(params.get("source", "custom")))
    SOIL_PRESETS[name] = preset
    return preset


def preset_table(names: list[str]) -> np.ndarray:
    """``(max(len(names), 1), len(PARAM_NAMES), 2)`` float32 (mean, std) of the named presets, in order.

    This is what the force kernels read: ``MaterialMap.soil`` indexes its first axis. With no names one
    all-zero row is returned so device arrays are never empty (no cell indexes it).
    """
    unknown = [n for n in names if n not in SOIL_PRESETS]
    if unknown:
        raise KeyError(
            f"Unknown soil preset(s) {unknown}; known: {sorted(SOIL_PRESETS)}. Register custom soils with "
            f"register_custom_soil(name, ...)."
        )
    table = np.zeros((max(len(names), 1), len(PARAM_NAMES), 2), np.float32)
    for i, name in enumerate(names):
        table[i] = [getattr(SOIL_PRESETS[name], p) for p in PARAM_NAMES]
    return table


_BUILTIN = frozenset(SOIL_PRESETS)
