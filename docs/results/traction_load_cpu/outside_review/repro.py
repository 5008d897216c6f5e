"""Repro: 41.5 kg foot, 0.22 x 0.096 sole, no bulldozing. Worlds: driven 1 m/s, driven 2 m/s (servo on x),
constant push 0.95 T, 1.05 T. T by hand = c A + W tan(phi). 2 s settle, 4 s run."""
import sys; from rig import *
name = sys.argv[1]
tag, v = soil_nobull(name)
H = np.zeros((221, 21)); org = (-11.0, -1.0)
mjm, m, d, f, W = build(41.5, H, org, tag, 4, z0=0.02)
A = 0.22 * 0.096; T = v["c"] * A + W * v["mu"]
print(f"{name}: sole area model {f.sole_area if hasattr(f,'sole_area') else '?'} hand {A:.5f}; c={v['c']} tanphi={v['mu']:.4f} K={v['K']} W={W:.1f} T_hand={T:.1f} N")
q = d.qpos.numpy(); q[:, 0] = -10.0; d.qpos.assign(q)
Z = np.zeros((4, 3))
for _ in range(400): step(m, d, f, Z)
x0 = d.qpos.numpy()[:, 0].copy(); sp = np.array([1.0, 2.0]); KP, KV = 2e4, 2e3
Fs = []; N = 800
for k in range(N):
    t = (k + 1) * DT; x = d.qpos.numpy()[:, 0]; vx = d.qvel.numpy()[:, 0]
    Q = np.zeros((4, 3)); Q[:2, 0] = KP * (x0[:2] + sp * t - x[:2]) + KV * (sp - vx[:2]); Q[2, 0] = 0.95 * T; Q[3, 0] = 1.05 * T
    step(m, d, f, Q)
    if k >= N // 2: Fs.append(Q[:2, 0].copy())
    if (k + 1) % 100 == 0:
        xx = d.qpos.numpy()[:, 0] - x0; vv = d.qvel.numpy()[:, 0]
        print(f" t={t:.1f}s push0.95: x={xx[2]:.3f} v={vv[2]:.3f} | push1.05: x={xx[3]:.3f} v={vv[3]:.3f} | slip {f.foot_slip.numpy()[2:,0].round(3)}")
Fs = np.array(Fs).mean(0)
print(f"{name}: driven 1 m/s {Fs[0]:.1f} N = {Fs[0]/T:.3f} T; 2 m/s {Fs[1]:.1f} N = {Fs[1]/T:.3f} T")
K = v["K"]; from scipy.optimize import brentq
j = brentq(lambda j: 0.05 * j - K * (1 - math.exp(-j / K)), 2 * K, 100 * K); print(f" hand stop distance 0.95 T: j = {j:.4f} m = {j/K:.1f} K")
