"""The rut of a 41.5 kg foot (0.22 x 0.096 m sole: the biped's) at the default sinkage settings, against Bekker's
depth by hand for its weight: the weight put on at once (a step load), or over 2 s or 8 s (an upward force fading
linearly), then held to 10 s; and how long the step load's rut takes to reach 0.9 of Bekker's depth.
Run from the project root: python docs/results/sinkage_cpu/slow_load.py (the review's foot world, common.py)."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "soil_review_cpu"))
from common import DT, G, SOIL_PRESETS, bekker, foot_model, make, mean_soil, step  # noqa: E402

M, L, B = 41.5, 0.22, 0.096
RAMPS = [0.0, 2.0, 8.0]
for name in ["mud", "poppy_seeds_rft", "snow", "dry_sand", "clay_loam"]:
    p = SOIL_PRESETS[name]
    mjm = foot_model(M, joints="z")
    weight = sum(mjm.body_mass) * G
    m, d, f = make(mjm, mean_soil(name), nworld=len(RAMPS))
    z_bekker = bekker(weight / (L * B), p.kc[0], p.kphi[0], p.n[0], B)
    t90 = None
    for k in range(int(10.0 / DT)):
        t = k * DT
        step(m, d, f, [[weight * max(1.0 - t / r, 0.0) if r > 0 else 0.0] for r in RAMPS])
        rut = f.foot_sinkage.numpy()[:, 0]
        if t90 is None and rut[0] >= 0.9 * z_bekker:
            t90 = t
    print(f"{name:16s} Bekker {100 * z_bekker:5.2f} cm; rut after a step load / a 2 s / an 8 s ramp: "
          + " / ".join(f"{r / z_bekker:.2f}" for r in rut) + f" x; the step load's reaches 0.9 x at {t90:.2f} s")
