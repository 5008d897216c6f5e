"""Item 1: reproduce docs/results/sinkage_cpu/slow_load.txt for mud and snow (same world/loads as slow_load.py).
Hand reference (Bekker, Wong eq. 2.41): z = (p / (kc/b + kphi))**(1/n), p = W / (L*B), b = B = 0.096 m (smaller side)."""
import os, sys, time
sys.path.insert(0, os.path.join(os.environ.get("PYTHONPATH", "."), "docs/results/soil_review_cpu"))
from common import DT, G, SOIL_PRESETS, foot_model, make, mean_soil, step
M, L, B = 41.5, 0.22, 0.096
RAMPS = [0.0, 2.0, 8.0]
for name in sys.argv[1:] or ["mud", "snow"]:
    p = SOIL_PRESETS[name]
    kc, kphi, n = p.kc[0], p.kphi[0], p.n[0]
    mjm = foot_model(M, joints="z")
    weight = sum(mjm.body_mass) * G
    pres = weight / (L * B)
    z_hand = (pres / (kc / B + kphi)) ** (1.0 / n)   # Bekker by hand
    m, d, f = make(mjm, mean_soil(name), nworld=len(RAMPS))
    t0 = time.time(); t90 = None
    for k in range(int(10.0 / DT)):
        t = k * DT
        step(m, d, f, [[weight * max(1.0 - t / r, 0.0) if r > 0 else 0.0] for r in RAMPS])
        rut = f.foot_sinkage.numpy()[:, 0]
        if t90 is None and rut[0] >= 0.9 * z_hand:
            t90 = t
    print(f"{name:8s} p={pres:.0f} Pa Bekker(hand) {100*z_hand:.2f} cm; rut step/2s/8s: "
          + " / ".join(f"{100*r:.2f} cm ({r/z_hand:.2f}x)" for r in rut) + f"; step reaches 0.9x at {t90:.2f} s [{time.time()-t0:.0f} s wall]", flush=True)
