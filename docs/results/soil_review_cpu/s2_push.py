"""Horizontal resistance of a 41.5 kg foot (0.22 x 0.096 m footprint) resting 2 s in each soil at its preset
means, then pushed along x (its 0.096 m side leads). Worlds 0, 1: driven at 0.05 / 0.3 m/s by a PD servo on a
moving target (mean servo force over the last 2 of 4 s = mean resistance). Worlds 2, 3: a constant push of 0.95 /
1.05 (T + R_b) held 4 s (held: |v| < 0.01 m/s at the end). With the presets' bulldozing and with it zeroed.
Expected by hand: T = c A + W tan(phi), R_b = b (bulldoze_c z + bulldoze_g z^2) at the measured rut z."""
import math, sys
from common import *
M = 41.5; L, B = 0.22, 0.096; A = L * B; KP, KV = 2.0e4, 2.0e3
soils = sys.argv[1:] or ["dry_sand", "wet_sand", "snow", "mud", "clay_loam"]
for name in soils:
    for bull in (False, True):
        p = SOIL_PRESETS[name]
        ov = {} if bull else {"bulldoze_c": 0.0, "bulldoze_g": 0.0}
        mjm = foot_model(M); W = sum(mjm.body_mass) * G
        m, d, f = make(mjm, mean_soil(name, **ov), nworld=4)
        T = p.c[0] * A + W * p.mu[0]
        Rb = lambda z: B * (p.bulldoze_c[0] * z + p.bulldoze_g[0] * z * z) if bull else 0.0
        for _ in range(400): step(m, d, f)          # 2 s: settle
        z0 = f.foot_sinkage.numpy()[0, 0]; x0 = d.qpos.numpy()[:, 0].copy()
        lim0 = T + Rb(z0)
        vt = np.array([0.05, 0.3]); hold = np.array([0.95, 1.05]) * lim0
        fs, ruts = [], []
        for k in range(800):                          # 4 s
            t = (k + 1) * DT
            x, v = d.qpos.numpy()[:, 0], d.qvel.numpy()[:, 0]
            q = np.zeros((4, 2))
            q[:2, 0] = KP * (x0[:2] + vt * t - x[:2]) + KV * (vt - v[:2]); q[2:, 0] = hold
            step(m, d, f, q)
            if k >= 400: fs.append(q[:2, 0]); ruts.append(f.foot_sinkage.numpy()[:2, 0].copy())
        fs = np.array(fs).mean(0); zr = np.array(ruts).mean(0)
        x, v = d.qpos.numpy()[:, 0] - x0, d.qvel.numpy()[:, 0]
        print(f"{name:9s} bulldozing {'on ' if bull else 'off'}: T={T:.0f} N, rut at rest {100*z0:.2f} cm, R_b={Rb(z0):.0f} N, T+R_b={lim0:.0f} N | "
              f"push 0.95(T+R_b): slid {100*x[2]:.1f} cm, v_end {v[2]:.3f} | 1.05(T+R_b): slid {100*x[3]:.1f} cm, v_end {v[3]:.3f} | "
              + " | ".join(f"driven {vv} m/s (reached {100*xx/4:.1f} cm/s): mean resistance {F:.0f} N, rut {100*z:.2f} cm, T+R_b(z) {T+Rb(z):.0f} N, ratio {F/(T+Rb(z)):.2f}"
                           for vv, xx, F, z in zip(vt, x[:2], fs, zr)))
