"""Mean horizontal resistance of a 41.5 kg foot (0.22 x 0.096 m footprint) driven along x at constant speed
(PD servo on a moving target), started at x = -9 m on a 20 m soil strip after 2 s at rest; bulldozing zeroed so
the expected resistance is Mohr-Coulomb alone, T = c A + W tan(phi). Resistance = mean servo force over the
second half of the run; also the share of substeps with the foot's slip reset (a lift-off)."""
import os, sys
os.environ.setdefault("HX", "10")
from common import *
M = 41.5; L, B = 0.22, 0.096; A = L * B; KP, KV = 2.0e4, 2.0e3
speeds = np.array([0.3, 1.0, 2.0, 4.0])
for name in (sys.argv[1:] or ["dry_sand", "clay_loam", "mud"]):
    p = SOIL_PRESETS[name]
    mjm = foot_model(M); W = sum(mjm.body_mass) * G
    m, d, f = make(mjm, mean_soil(name, bulldoze_c=0.0, bulldoze_g=0.0), nworld=len(speeds), **eval(os.environ.get("CFG", "{}")))
    q = d.qpos.numpy(); q[:, 0] = -9.0; d.qpos.assign(q)
    T = p.c[0] * A + W * p.mu[0]
    for _ in range(400): step(m, d, f)
    x0 = d.qpos.numpy()[:, 0].copy()
    n = 800; fs, resets, fn = [], [], []
    prev = f.foot_slip.numpy()[:, 0].copy()
    for k in range(n):
        t = (k + 1) * DT
        tgt = x0 + np.minimum(speeds * t, 18.0)
        x, v = d.qpos.numpy()[:, 0], d.qvel.numpy()[:, 0]
        F = KP * (tgt - x) + KV * (np.where(speeds * t < 18.0, speeds, 0) - v)
        step(m, d, f, np.stack([F, np.zeros_like(F)], 1))
        s = f.foot_slip.numpy()[:, 0]
        if k >= n // 2:
            fs.append(F); resets.append(s < prev); fn.append(f.foot_fn.numpy()[:, 0].copy())
        prev = s.copy()
    fs = np.array(fs).mean(0); resets = np.array(resets).mean(0); fn = np.array(fn)
    for i, sp in enumerate(speeds):
        print(f"{name}: {sp} m/s: mean resistance {fs[i]:.0f} N = {fs[i]/T:.2f} T (T = {T:.0f} N); slip resets in "
              f"{100*resets[i]:.1f} % of substeps; F_N mean {fn[:, i].mean():.0f} N (W {W:.0f}), zero in {100*(fn[:, i] < 1).mean():.0f} % of substeps")
