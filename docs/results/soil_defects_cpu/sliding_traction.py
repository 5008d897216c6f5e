"""A 20 kg foot on four 2 cm sole spheres (the soil tests' foot world, tests/test_forces_soil.py), on a cohesionless soil, a sand
and a mud without bulldozing, pushed sideways with a constant force of 1.0 / 1.1 / 1.2 / 1.5 x its Mohr-Coulomb limit
T = c A + W tan(phi) (A the 0.22 m x 0.09 m sole): its travel and the mean resistance over the last 0.75 s of 1.5 s,
push - m a (a from the velocity change); a foot that slid past the soil map's edge, 2 m away, is not scored. The record of the sliding-traction numbers in docs/forces.md:

    python sliding_traction.py      (from the checkout's root or anywhere: it imports the tests' helpers)
"""
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "tests"))
import test_forces_soil as soil_world  # noqa: E402

from legged_gente.terrain.soil import register_custom_soil  # noqa: E402

G, MASS, AREA, DT = 9.81, 20.0, 0.22 * 0.09, 0.005
total = MASS + 4 * 1000 * 4 / 3 * math.pi * 0.02**3  # the foot world's sole spheres weigh too (density 1000)
factors = np.array([1.0, 1.1, 1.2, 1.5])
for name, c, phi in (("cohesionless_no_bulldozing", 0.0, 28.0), ("sand_no_bulldozing", 1.04e3, 28.0),
                     ("mud_no_bulldozing", 5.17e3, 11.0)):
    register_custom_soil(name, kc=0.99e3, kphi=1528.43e3, n=1.1, c=c, mu=math.tan(math.radians(phi)), K=0.025,
                         bulldoze_c=0.0, bulldoze_g=0.0)
    limit = c * AREA + total * G * math.tan(math.radians(phi))
    m, d, f = soil_world.make(soil_world.foot_world(MASS), soil_world.soil_map(name), nworld=len(factors))
    soil_world.run(m, d, f, 60)  # settle into the rut
    x0 = d.qpos.numpy()[:, 0].copy()
    push = factors * limit
    v = []
    for _ in range(300):
        soil_world.run(m, d, f, 1, push=push)
        v.append(d.qvel.numpy()[:, 0].copy())
    v = np.array(v)
    acceleration = (v[-1] - v[150]) / (149 * DT)
    for i, factor in enumerate(factors):
        resistance = push[i] - total * acceleration[i]
        travel = d.qpos.numpy()[i, 0] - x0[i]
        if travel > 1.9:
            print(f"{name}: push {factor:.1f} T ({push[i]:.0f} N): travel {travel:.2f} m, past the map's edge")
            continue
        print(f"{name}: push {factor:.1f} T ({push[i]:.0f} N): travel {travel:.2f} m in 1.5 s, "
              f"mean resistance over the last 0.75 s {resistance:.0f} N = {resistance / limit:.2f} T")
