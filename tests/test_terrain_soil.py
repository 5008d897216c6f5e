"""The soil presets are Wong's table rows converted to SI by hand (kN -> N, kPa -> Pa, degrees -> tan phi)."""

import math

import pytest

from legged_gente.terrain.soil import SOIL_PRESETS

# Wong, Theory of Ground Vehicles, Table 2.3, in the table's units:
# n (1), kc (kN/m^(n+1)), kphi (kN/m^(n+2)), c (kPa), phi (deg)
WONG_TABLE_2_3 = {
    "dry_sand": (1.1, 0.99, 1528.43, 1.04, 28.0),  # dry sand, LLL
    "wet_sand": (0.7, 5.27, 1515.04, 1.72, 29.0),  # sandy loam 15 % moisture, LLL
    "snow": (1.6, 4.37, 196.72, 1.03, 19.7),  # snow, U.S.
    "mud": (0.5, 0.77, 51.91, 5.17, 11.0),  # sandy loam 32 % moisture, Hanamoto
    "clay_loam": (0.73, 41.6, 2471.0, 6.1, 26.6),  # North Gower clayey loam 46 % moisture
}


@pytest.mark.parametrize("name", sorted(WONG_TABLE_2_3))
def test_bekker_preset_is_its_table_row_in_si_units(name):
    n, kc, kphi, c, phi = WONG_TABLE_2_3[name]
    p = SOIL_PRESETS[name]
    assert p.model == "bekker" and "Table 2.3" in p.source
    assert p.n[0] == pytest.approx(n)
    assert p.kc[0] == pytest.approx(kc * 1e3)  # 1 kN/m^(n+1) = 1e3 N/m^(n+1)
    assert p.kphi[0] == pytest.approx(kphi * 1e3)  # 1 kN/m^(n+2) = 1e3 N/m^(n+2)
    assert p.c[0] == pytest.approx(c * 1e3)  # 1 kPa = 1e3 Pa
    assert p.mu[0] == pytest.approx(math.tan(math.radians(phi)))



# Wong, Theory of Ground Vehicles, sec. 2.4.3 (after Bekker): Janosi-Hanamoto K in inches -> m
WONG_K_INCHES = {"dry_sand": 1.0, "wet_sand": 0.4, "snow": 2.0}  # loose sand, firm sandy terrain, fresh snow


@pytest.mark.parametrize("name", sorted(WONG_K_INCHES))
def test_shear_deformation_modulus_is_wongs_in_si_units(name):
    assert SOIL_PRESETS[name].K[0] == pytest.approx(WONG_K_INCHES[name] * 0.0254, rel=0.02)  # 1 in. = 0.0254 m
