"""Low swing keeps slip: 10 kg foot on mud (no bulldozing; K = 5 cm, rut ~0.65 cm) rests 1 s, is lifted by a z servo
until its sole is h above the unlowered ground (worlds h = 1, 2, 3, 6 cm), carried 0.5 m along x at 1 m/s, lowered
by the servo onto the fresh soil there (x held by a servo), then released with a constant push of 0.9 T along x.
JH: a sole on fresh soil starts from j = 0 and (by hand, 0.1 j = K (1 - exp(-j/K))) slides ~10 K = 0.5 m."""
import sys; from rig import *
tag, v = soil_nobull(sys.argv[1] if len(sys.argv) > 1 else "mud")
H = np.zeros((61, 21)); org = (-3.0, -1.0)
mjm, m, d, f, W = build(10.0, H, org, tag, 4)
A = 0.22 * 0.096; T = v["c"] * A + W * v["mu"]; hs = np.array([0.01, 0.02, 0.03, 0.06])
q = d.qpos.numpy(); q[:, 0] = -1.0; d.qpos.assign(q)   # qpos z = sole bottom height (body at 0.02, spheres r 0.02)
for _ in range(200): step(m, d, f, np.zeros((4, 3)))
x0 = d.qpos.numpy()[:, 0].copy()
print(f"T={T:.1f} N, rut {f.foot_sinkage.numpy()[0,0]:.4f}, slip at rest {f.foot_slip.numpy()[0,0]:.4f}")
for k in range(200):
    t = k * DT; qp = d.qpos.numpy(); qv = d.qvel.numpy(); Q = np.zeros((4, 3))
    zt = hs if t < 0.8 else np.full(4, -0.02); xt = x0 + np.clip(t - 0.15, 0, 0.5) * 1.0
    Q[:, 2] = 3e3 * (zt - qp[:, 2]) - 150 * qv[:, 2] + W; Q[:, 0] = 3e3 * (xt - qp[:, 0]) - 150 * qv[:, 0]
    Q[:, 2] = np.maximum(Q[:, 2], -W) if t >= 0.8 else Q[:, 2]
    step(m, d, f, Q)
    if k == 155: print(f"carried: sole height {np.round(d.qpos.numpy()[:,2]*100,2)} cm, x moved {np.round(d.qpos.numpy()[:,0]-x0,3)}, slip {f.foot_slip.numpy()[:,0].round(3)}, rut {f.foot_sinkage.numpy()[:,0].round(4)}, near {f.foot_near.numpy()[:,0]}")
print(f"landed: fn {f.foot_fn.numpy()[:,0].round(0)}, slip {f.foot_slip.numpy()[:,0].round(3)}, rut {f.foot_sinkage.numpy()[:,0].round(4)}")
x1 = d.qpos.numpy()[:, 0].copy()
for k in range(300):
    Q = np.zeros((4, 3)); Q[:, 0] = 0.9 * T; step(m, d, f, Q)
    if (k + 1) % 100 == 0:
        print(f" {0.005*(k+1):.1f} s after release: slid {np.round((d.qpos.numpy()[:,0]-x1)*100,1)} cm, v {d.qvel.numpy()[:,0].round(3)}")
