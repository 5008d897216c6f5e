"""Hand reference for item 2: Newton + Bekker for the 41.5 kg foot (0.22 x 0.096 m sole) landing at 0.3 m/s with its
whole weight (plastic soil, no rebound): m z'' = m g - A (kc/b + kphi) z^n, z(0) = 0, z'(0) = 0.3 m/s.
Time to reach 0.5 / 0.9 / 1.0 x z_B and the depth where it stops (z' = 0)."""
import math
from legged_gente.terrain.soil import SOIL_PRESETS
M, L, B, G, dt = 41.504, 0.22, 0.096, 9.81, 1e-5
for name in ("mud", "dry_sand", "snow"):
    p = SOIL_PRESETS[name]; k = p.kc[0] / B + p.kphi[0]; n = p.n[0]
    zB = (M * G / (L * B) / k) ** (1 / n)
    z, v, t, hits = 0.0, 0.3, 0.0, {}
    while v > 0:
        a = G - L * B * k * z ** n / M; v += a * dt; z += v * dt; t += dt
        for q in (0.5, 0.9, 1.0):
            if q not in hits and z >= q * zB: hits[q] = t
    print(f"{name:8s} z_B {100*zB:.2f} cm: reaches 0.5/0.9/1.0 z_B at {hits[0.5]:.3f}/{hits[0.9]:.3f}/{hits[1.0]:.3f} s, stops at {z/zB:.2f} z_B ({t:.3f} s)")
