"""Item 3: weight shifting. A 41.5 kg foot (0.22 x 0.096 m sole, z slide) set down at rest; its load on the soil
W - F_up is held at W (world 0), or swings as a raised cosine between 0.1 W and W at 1 Hz (world 1) and 2 Hz
(world 2), starting at W; 3.0 s = 600 substeps. The foot never leaves its rut (plastic rut kept).
Hand reference: plastic sinkage follows the peak sustained load, Bekker (Wong eq. 2.41)
    z_B(W) = (W/(L B) / (kc/B + kphi))**(1/n)     (Wong: reloading below the previous peak adds little)
And by hand what the filters pass of a sinusoidal load F = 0.55 W + 0.45 W cos(wt): each first-order low-pass of
tau = 50 ms has gain 1/sqrt(1 + (w tau)^2); filtered peak = 0.55 W + 0.45 W g^k, k = 1 (before) or 2 (after);
a filter-limited rut = z_B(filtered peak) = z_B(W) (peak/W)**(1/n)."""
import math, os, sys
import numpy as np
sys.path.insert(0, os.path.join(os.environ["PYTHONPATH"], "docs/results/soil_review_cpu"))
from common import DT, G, SOIL_PRESETS, foot_model, make, mean_soil, step
M, L, B, TAU = 41.5, 0.22, 0.096, 0.05
FREQ = [0.0, 1.0, 2.0]
T_END = float(os.environ.get("T_END", "3.0"))
tree = os.environ["PYTHONPATH"].rstrip("/").split("/")[-1]
for name in sys.argv[1:]:
    p = SOIL_PRESETS[name]; kc, kphi, n = p.kc[0], p.kphi[0], p.n[0]
    mjm = foot_model(M, joints="z")
    W = sum(mjm.body_mass) * G
    zB = (W / (L * B) / (kc / B + kphi)) ** (1.0 / n) if p.model == "bekker" else W / (L * B) / p.zeta[0]
    m, d, f = make(mjm, mean_soil(name), nworld=len(FREQ))
    mx = np.zeros(len(FREQ)); peak_sl = np.zeros(len(FREQ))
    for k in range(int(T_END / DT)):
        t = k * DT
        load = [W if fr == 0 else W * (0.55 + 0.45 * math.cos(2 * math.pi * fr * t)) for fr in FREQ]
        step(m, d, f, [[W - l] for l in load])
        sl = getattr(f, "foot_sink_load", f.foot_load).numpy()[:, 0]
        if t > 1.0: peak_sl = np.maximum(peak_sl, sl)
    rut = f.foot_sinkage.numpy()[:, 0]
    print(f"[{tree}] {name}: z_B(W) by hand {100*zB:.2f} cm")
    for i, fr in enumerate(FREQ):
        w = 2 * math.pi * fr; g = 1 / math.sqrt(1 + (w * TAU) ** 2)
        h1 = (0.55 + 0.45 * g) ** (1 / n) if fr else 1.0; h2 = (0.55 + 0.45 * g * g) ** (1 / n) if fr else 1.0
        print(f"  {'hold W' if fr == 0 else f'{fr:.0f} Hz 0.1-1 W'}: rut {100*rut[i]:.2f} cm = {rut[i]/zB:.2f} x z_B(W); "
              f"rut's filtered load peak (t>1 s) {peak_sl[i]/W:.2f} W; by hand a filter-limited rut: 1 pass {h1:.2f}, 2 passes {h2:.2f} x z_B(W)", flush=True)
