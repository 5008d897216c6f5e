"""A foot set down at rest on the soil (its sole spheres touching the surface) with its whole weight at once, at
the default sinkage settings, the tests' foot world (tests/test_forces_soil.py: 0.22 x 0.09 m sole): its rut
after 2 s against Bekker's depth by hand. Run from the project root: python docs/results/sinkage_cpu/landing.py"""
import sys

sys.path.insert(0, "tests")
import warp as wp  # noqa: E402

import test_forces_soil as T  # noqa: E402
from legged_gente.terrain.soil import SOIL_PRESETS  # noqa: E402

soils = T.registered_test_soils.__wrapped__()  # the tests' soils (Wong's Table 2.3, Li et al.'s seeds)
next(soils)
wp.set_device("cpu")
for soil, mass in (("t_snow", 20.0), ("t_mud", 41.5), ("t_rft", 20.0)):
    p = SOIL_PRESETS[soil]
    m, d, f = T.make(T.foot_world(mass, z0=0.02), T.soil_map(soil))
    T.run(m, d, f, 400)
    z_bekker = (mass * T.G / T.SOLE_AREA / (p.kc[0] / 0.09 + p.kphi[0])) ** (1 / p.n[0])
    print(f"{soil} {mass} kg: rut {f.foot_sinkage.numpy()[0, 0] / z_bekker:.2f} x Bekker's {100 * z_bekker:.2f} cm")
