"""Quasi-static loading: a 41.5 kg foot whose weight is cancelled by an upward force fading linearly to 0 over
T_ramp s (2, 4, 8 s), then held 2 s. Rut vs Bekker by hand for the final weight, and for the low-passed load
at each instant (does the rut track z(load)?)."""
from common import *
M = 41.5; L, B = 0.22, 0.096; A = L * B
for name in ["mud", "snow", "poppy_seeds_rft", "dry_sand"]:
    p = SOIL_PRESETS[name]
    mjm = foot_model(M); W = sum(mjm.body_mass) * G
    ramps = [2.0, 4.0, 8.0]
    m, d, f = make(mjm, mean_soil(name), nworld=3)
    zb = bekker(W / A, p.kc[0], p.kphi[0], p.n[0], B)
    n = int((8.0 + 2.0) / DT)
    maxratio = np.zeros(3); fnmax = np.zeros(3); fnmin = np.full(3, 1e9)
    for k in range(n):
        t = k * DT
        up = [W * max(1 - t / r, 0.0) for r in ramps]
        step(m, d, f, [[0, u] for u in up])
        load = f.foot_load.numpy()[:, 0]; rut = f.foot_sinkage.numpy()[:, 0]
        target = np.array([bekker(max(W - u, 1e-9) / A, p.kc[0], p.kphi[0], p.n[0], B) for u in up])  # z of the applied net load
        if t > 0.5:
            maxratio = np.maximum(maxratio, rut / target)
            fn = f.foot_fn.numpy()[:, 0] if hasattr(f, "foot_fn") else load
            fnmax = np.maximum(fnmax, fn / (W - np.array(up))); fnmin = np.minimum(fnmin, fn / (W - np.array(up)))
    rut = f.foot_sinkage.numpy()[:, 0]
    print(f"{name}: Bekker by hand {100*zb:.2f} cm; final rut after ramps 2/4/8 s: " +
          " / ".join(f"{100*r:.2f} cm ({r/zb:.2f}x)" for r in rut) +
          "; max over the ramp of rut / z(applied load): " + " / ".join(f"{x:.2f}" for x in maxratio) +
          "; instantaneous F_N / applied load range: " + " / ".join(f"{a:.2f}-{b:.2f}" for a, b in zip(fnmin, fnmax)))
