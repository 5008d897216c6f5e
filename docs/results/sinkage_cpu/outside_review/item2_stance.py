"""Item 2: repeated walking stances. A 41.5 kg foot (0.22 x 0.096 m sole, soil review's world, z slide) is lowered
by a PD servo at 0.3 m/s until it touches; from touchdown its supporting force fades from W to 0 over r
(world 0: r = 0, a step; world 1: r = 0.05 s; world 2: r = 0.1 s), full weight W held, at ts = 0.35 s the servo
lifts it 6 cm at 0.5 m/s; swing, then the next stance (cycle 0.9 s, 4 stances = 720 substeps).
Hand reference (Bekker, Wong eq. 2.41): z_B = (W/(L B) / (kc/B + kphi))**(1/n) for the peak load W; plastic
sinkage should reach it as soon as the load does (quasi-static soil), i.e. by ts ~ r.
Also by hand: the rut's load through k first-order low-passes of tau = 50 ms after a step: 1 pass 1-e^-x,
2 passes 1-(1+x)e^-x, x = t/tau; Bekker depth target ~ load^(1/n).
Usage: PYTHONPATH=<tree> python item2_stance.py soil [soil...]"""
import math, os, sys
import numpy as np
sys.path.insert(0, os.path.join(os.environ["PYTHONPATH"], "docs/results/soil_review_cpu"))
from common import DT, G, SOIL_PRESETS, foot_model, make, mean_soil, step

M, L, B = 41.5, 0.22, 0.096
RISE = [0.0, 0.05, 0.1]
CYCLE, STANCE, NCYC = 0.9, 0.35, 4
KP, KD = M * (2 * math.pi * 5) ** 2, 2 * M * 2 * math.pi * 5
TAU = 0.05
tree = os.environ["PYTHONPATH"].rstrip("/").split("/")[-1]
for name in sys.argv[1:]:
    p = SOIL_PRESETS[name]
    kc, kphi, n = p.kc[0], p.kphi[0], p.n[0]
    mjm = foot_model(M, joints="z", z0=0.08)   # starts 6 cm up; q below = sole sphere bottom height (qpos + 0.06)
    W = sum(mjm.body_mass) * G
    zB = (W / (L * B) / (kc / B + kphi)) ** (1.0 / n)
    nw = len(RISE)
    m, d, f = make(mjm, mean_soil(name), nworld=nw)
    phase = ["down"] * nw; t_td = [None] * nw; target = [0.06] * nw; wait = [0.0] * nw
    rec = [[] for _ in range(nw)]   # per stance: dict of rut at checkpoints
    cur = [None] * nw
    for k in range(int(NCYC * CYCLE / DT)):
        t = k * DT
        q = d.qpos.numpy()[:, 0] + 0.06; v = d.qvel.numpy()[:, 0]
        fn = f.foot_fn.numpy()[:, 0]; rut = f.foot_sinkage.numpy()[:, 0]
        sl = getattr(f, "foot_sink_load", f.foot_load).numpy()[:, 0]; ld = f.foot_load.numpy()[:, 0]
        frc = []
        for w in range(nw):
            tc = t % CYCLE
            if phase[w] == "swing" and tc < DT / 2:
                phase[w] = "down"; target[w] = 0.06
            if phase[w] == "down":
                target[w] = max(target[w] - 0.3 * DT, -0.03)
                if fn[w] > 1.0 or q[w] <= 0.0:
                    phase[w] = "stance"; t_td[w] = t; cur[w] = {"rut": [], "sl": [], "ld": [], "fn": [], "vtd": v[w]}
            if phase[w] == "stance":
                ts = t - t_td[w]
                cur[w]["rut"].append(rut[w]); cur[w]["sl"].append(sl[w]); cur[w]["ld"].append(ld[w]); cur[w]["fn"].append(fn[w])
                if ts >= STANCE:
                    phase[w] = "lift"; target[w] = q[w]; rec[w].append(cur[w])
                    cur[w]["q_end"] = q[w]
            if phase[w] == "lift":
                target[w] = min(target[w] + 0.5 * DT, 0.06)
                if target[w] >= 0.06: phase[w] = "swing"
            if phase[w] == "stance":
                ts = t - t_td[w]; r = RISE[w]
                frc.append([W * max(1.0 - ts / r, 0.0) if r > 0 else 0.0])
            else:
                frc.append([W + KP * (target[w] - q[w]) - KD * v[w]])
        step(m, d, f, frc)
    print(f"[{tree}] {name}: W = {W:.1f} N, Bekker z_B(W) by hand = {100*zB:.2f} cm")
    for w in range(nw):
        for i, s in enumerate(rec[w]):
            r = np.array(s["rut"]) / zB
            idx = lambda ts: min(int(round(ts / DT)), len(r) - 1)
            t50 = next((j * DT for j, x in enumerate(r) if x >= 0.5), float("nan"))
            t90 = next((j * DT for j, x in enumerate(r) if x >= 0.9), float("nan"))
            print(f"  rise {RISE[w]:.2f}s stance {i+1}: rut/z_B at ts=0.10/0.20/0.35 s: "
                  f"{r[idx(0.1)]:.2f}/{r[idx(0.2)]:.2f}/{r[-1]:.2f}; t50 {t50:.3f} s, t90 {t90:.3f} s; "
                  f"rut-load/W at 0.1/0.2 s {s['sl'][idx(0.1)]/W:.2f}/{s['sl'][idx(0.2)]/W:.2f}; "
                  f"rut at touchdown {100*s['rut'][0]:.2f} cm; sole bottom at end {100*s['q_end']:.2f} cm; touchdown speed {s['vtd']:.2f} m/s", flush=True)
