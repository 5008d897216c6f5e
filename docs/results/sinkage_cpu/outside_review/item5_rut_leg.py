"""Item 5: a rut leg (the quadruped's calves' mechanism): the tests' leg world (tests/test_forces_soil.py
leg_world: 8 kg on a vertical slide, a flat 2 cm capsule 0.14 m long, its foot ball 0.2 m above it) on mud (the
preset's means, default sinkage settings), the leg set on the surface at rest (world 0) or striking at 0.5 m/s
(world 1) and 1.0 m/s (world 2), then left lying; 1.5 s = 300 substeps.
Hand reference (Bekker, Wong eq. 2.41, the code's patch: 2r wide = b, 0.14 + 2r long):
  z_B = (m g / (0.04 * 0.18) / (kc / 0.04 + kphi))**(1/n)
and a plastic soil meeting the leg at v0 absorbs its energy while the leg sinks (Bekker pressure as resistance):
  m g z + m v0^2 / 2 = A (kc/b + kphi) z^(n+1) / (n+1)   -> z_dyn, the depth an impact reaches."""
import math, os, sys
import numpy as np
sys.path.insert(0, os.path.join(os.environ["PYTHONPATH"], "tests"))
sys.path.insert(0, os.path.join(os.environ["PYTHONPATH"], "docs/results/soil_review_cpu"))
import warp as wp
wp.config.quiet = True; wp.set_device("cpu")
import mujoco_warp as mjw
import test_forces_soil as T
from common import mean_soil, SOIL_PRESETS
from legged_gente.external_forces.field import TerrainForces
from scipy.optimize import brentq
M, V0 = 8.0, [0.0, 0.5, 1.0]
name = "mud"; p = SOIL_PRESETS[name]; kc, kphi, n = p.kc[0], p.kphi[0], p.n[0]
A, b = 0.04 * 0.18, 0.04; k = kc / b + kphi
zB = (M * T.G / A / k) ** (1 / n)
zdyn = [brentq(lambda z: A * k * z ** (n + 1) / (n + 1) - M * T.G * z - 0.5 * M * v * v, 1e-6, 1.0) for v in V0]
mjm = T.leg_world(M, 0, leg="-0.07 0 0 0.07 0 0", foot_z=-0.2)
m = mjw.put_model(mjm); d = mjw.make_data(mjm, nworld=3, nconmax=48, njmax=192)
cfg = type("C", (T.Cfg,), {"foot_geom_names": ["sole"], "rut_leg_geom_names": ["leg"]})()
f = TerrainForces(mjm, m, d, np.zeros(T.SHAPE, np.float32), T.ORIGIN, T.RES, T.soil_map(mean_soil(name)), cfg, seed=1)
f.install()
qpos, qvel = d.qpos.numpy(), d.qvel.numpy()
qpos[:, 0] = 0.0205 - 0.3; qvel[:, 0] = [-v for v in V0]
d.qpos.assign(qpos); d.qvel.assign(qvel)
marks = {5: "25ms", 10: "50ms", 20: "100ms", 40: "200ms", 299: "1.5s"}
rows = {w: [] for w in range(3)}; peak_fn = np.zeros(3); peak_depth = np.zeros(3)
for s in range(300):
    mjw.step(m, d); fn_now = None
    f.after_substep()
    rut = f.leg_sinkage.numpy()[:, 0]; h = 0.3 + d.qpos.numpy()[:, 0]
    peak_depth = np.maximum(peak_depth, 0.02 - h)
    if s in marks:
        for w in range(3):
            rows[w].append(f"{marks[s]} {100*rut[w]:.2f}")
tree = os.environ["PYTHONPATH"].rstrip("/").split("/")[-1]
print(f"[{tree}] {M} kg leg on {name}: z_B by hand {100*zB:.2f} cm")
for w in range(3):
    print(f"  v0 {V0[w]:.1f} m/s (z_dyn by hand {100*zdyn[w]:.2f} cm): leg rut (cm) at " + ", ".join(rows[w])
          + f"; deepest the leg's bottom went {100*peak_depth[w]:.2f} cm", flush=True)
