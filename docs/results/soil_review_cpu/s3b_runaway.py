"""A constant push of 0.95 T (below Mohr-Coulomb, T = c A + W tan(phi)) applied at once to a 41.5 kg foot
resting 2 s in clay_loam (preset means, bulldozing zeroed) and, as a control, on rigid ground whose map friction
is T / W. Expected: Janosi-Hanamoto mobilises T(j) = 0.95 T at j = 3K = 3 cm; as a dynamic friction limit the
foot stops where the work of T(j) equals the push's: 0.05 j = K (1 - exp(-j/K)), j ~ 20 K = 0.2 m.
Velocity every 0.5 s, slip resets (lift-offs) counted."""
import os
os.environ.setdefault("HX", "10")
from common import *
M = 41.5; L, B = 0.22, 0.096; A = L * B
p = SOIL_PRESETS["clay_loam"]
mjm = foot_model(M); W = sum(mjm.body_mass) * G
T = p.c[0] * A + W * p.mu[0]
for label, soil, fric in (("clay_loam", mean_soil("clay_loam", bulldoze_c=0.0, bulldoze_g=0.0), 1.0), ("rigid mu=T/W", None, T / W)):
    m, d, f = make(mjm, soil, friction=fric, **eval(os.environ.get("CFG", "{}")))
    q = d.qpos.numpy(); q[:, 0] = -9.0; d.qpos.assign(q)
    for _ in range(400): step(m, d, f)
    x0 = d.qpos.numpy()[0, 0]; prev = f.foot_slip.numpy()[0, 0]; resets = 0; out = []
    for k in range(800):
        step(m, d, f, [[0.95 * T, 0.0]])
        s = f.foot_slip.numpy()[0, 0]; resets += s < prev; prev = s
        if (k + 1) % 100 == 0:
            out.append(f"t={(k+1)*DT:.1f}s x={d.qpos.numpy()[0,0]-x0:.3f} m v={d.qvel.numpy()[0,0]:.3f}")
    print(f"{label}: T={T:.0f} N push={0.95*T:.0f} N, resets {resets}: " + "; ".join(out))
