"""Walking-like load cycle: 2 kg foot, down force 0 -> 400 N over 0.1 s, hold 0.2 s, 400 -> 0 over 0.1 s, 0.05 s
at its weight, lift 5 cm (z servo) for 0.3 s and back down. While loaded (0-0.45 s of each 0.75 s cycle) a push along
y of frac * (c A + L tan phi), L = applied load (weight + down force); in the swing y is servo-held. Worlds: frac
0.8 / 0.6 / 0.4 / 0.0. y slid per phase: ramp-up+hold (0-0.3 s), unloading (0.3-0.45 s)."""
import sys, os; from rig import *
name = sys.argv[1]; cfg = eval(os.environ.get("CFG", "{}"))
tag, v = soil_nobull(name)
H = np.zeros((41, 41)); org = (-2.0, -2.0)
mjm, m, d, f, W = build(2.0, H, org, tag, 4, **cfg)
A = 0.22 * 0.096; fr = np.array([0.8, 0.6, 0.4, 0.0]); FD = 400.0
for _ in range(200): step(m, d, f, np.zeros((4, 3)))
zrest = d.qpos.numpy()[:, 2].copy()
print(f"{name} cfg={cfg} cA={v['c']*A:.0f} N tanphi={v['mu']:.3f} K={v['K']} rut={f.foot_sinkage.numpy()[0,0]*100:.2f} cm")
res = []
for cyc in range(4):
    y0 = d.qpos.numpy()[:, 1].copy(); marks = {}
    for k in range(150):
        t = k * DT; Q = np.zeros((4, 3)); qp = d.qpos.numpy(); qv = d.qvel.numpy()
        if t < 0.45:
            Fd = FD * min(t / 0.1, 1.0) if t < 0.3 else FD * max(1 - (t - 0.3) / 0.1, 0.0)
            Q[:, 2] = -Fd; Q[:, 1] = fr * (v["c"] * A + (W + Fd) * v["mu"])
        else:
            if k == 90: yh = qp[:, 1].copy()
            zt = zrest + (0.05 if t < 0.7 else 0.0)
            Q[:, 2] = 3e3 * (zt - qp[:, 2]) - 100 * qv[:, 2] + W; Q[:, 1] = 3e3 * (yh - qp[:, 1]) - 100 * qv[:, 1]
        step(m, d, f, Q)
        if k in (59, 89, 149): marks[k] = d.qpos.numpy()[:, 1] - y0
        if k == 89: sl = f.foot_slip.numpy()[:, 0].copy()
    print(f" cycle {cyc}: y slid in load+hold {np.round(marks[59]*100,2)} cm, in unloading {np.round((marks[89]-marks[59])*100,2)} cm; slip at lift {np.round(sl,3)}")
