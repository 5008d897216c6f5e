"""Light foot on a cohesive soil, T/W > 1: M kg foot (default 10) at rest 1 s on mud (no bulldozing), then a constant
push along x at once. Worlds: 0.7 T fresh (j=0), 0.9 T fresh, 0.9 T with j preset to 1 m (fully mobilised),
0.7 T with j preset. Mohr-Coulomb/JH: all stop (fresh 0.9 T after ~10 K = 0.5 m, 0.7 T after ~3.2 K; preset: ~0)."""
import sys; from rig import *
tag, v = soil_nobull(sys.argv[1] if len(sys.argv) > 1 else "mud"); M = float(sys.argv[2]) if len(sys.argv) > 2 else 10.0
H = np.zeros((61, 21)); org = (-3.0, -1.0)
mjm, m, d, f, W = build(M, H, org, tag, 4)
A = 0.22 * 0.096; T = v["c"] * A + W * v["mu"]; fr = np.array([0.7, 0.9, 0.9, 0.7])
q = d.qpos.numpy(); q[:, 0] = -2.0; d.qpos.assign(q)
for _ in range(200): step(m, d, f, np.zeros((4, 3)))
s = f.foot_slip.numpy(); s[2:, :] = 1.0; f.foot_slip.assign(s)
print(f"M={M} W={W:.0f} N T={T:.1f} N T/W={T/W:.2f}")
x0 = d.qpos.numpy()[:, 0].copy(); fz = []
for k in range(300):
    Q = np.zeros((4, 3)); Q[:, 0] = fr * T; step(m, d, f, Q); fz.append(f.foot_fn.numpy()[:, 0].copy())
    if (k + 1) % 100 == 0:
        fzz = np.array(fz[-100:])
        print(f" {0.005*(k+1):.1f} s: slid {np.round((d.qpos.numpy()[:,0]-x0)*100,1)} cm, v {d.qvel.numpy()[:,0].round(3)}, F_N=0 in {np.round((fzz<1).mean(0)*100)} %")
