"""Item 4a: RFT support of a sole, numpy reference (models.rft_support) vs the Warp twin (rft.rft_support_fn),
on soles dragged sideways while rising/sinking, level and tilted; then a tilted sole lifted straight out of its rut
along its own normal. Hand reference (Li et al. 2013 generic fit, docs/forces.md):
  alpha_z/zeta = A00 + A10 cos 2b + B11 sin(2b+g) + B01 sin g + B-11 sin(-2b+g)
  A00 .206, A10 .169, B11 .212, B01 .358, B-11 .055
A sole tilted by theta (normal (sin th, 0, cos th)) lifted along its normal at speed u: after the upward part is
dropped the velocity left is (u sin th, 0, 0): b = -theta (pi-periodic), g = 0:
  s = 0.206 + 0.169 cos 2th - 0.157 sin 2th   (full fade once u sin th >= 0.05 m/s),
whereas a level sole lifted straight up gets s = 1 (the commit's point: a rising sole is supported as at rest)."""
import math
import numpy as np, warp as wp
wp.config.quiet = True; wp.set_device("cpu")
from legged_gente.external_forces import models
from legged_gente.external_forces import rft as R

@wp.kernel
def ev(n: wp.array[wp.vec3], v: wp.array[wp.vec3], out: wp.array[float]):
    i = wp.tid(); out[i] = R.rft_support_fn(n[i], v[i], 0.05)

def warp_support(ns, vs):
    ns, vs = np.asarray(ns, np.float32), np.asarray(vs, np.float32)
    out = wp.zeros(len(ns), dtype=float)
    wp.launch(ev, dim=len(ns), inputs=[wp.array(ns, dtype=wp.vec3), wp.array(vs, dtype=wp.vec3), out])
    return out.numpy()

rng = np.random.default_rng(0)
k = 2000
ns = rng.normal(size=(k, 3)); ns[:, 2] = np.abs(ns[:, 2]) + 0.3; ns[:500] = [0, 0, 1]
ns /= np.linalg.norm(ns, axis=1, keepdims=True)
vs = rng.normal(0, 0.3, (k, 3)); vs[:, 2] = np.abs(vs[:, 2]) * np.where(np.arange(k) % 2, 1, -1)  # half rising
ref = np.array([models.rft_support(n, v, 0.05) for n, v in zip(ns, vs)])
got = warp_support(ns, vs)
print(f"random soles (500 level, 1500 tilted), half rising: max |warp - numpy| = {np.abs(got - ref).max():.2e}")

# a level sole dragged at 0.3 m/s along x while rising / sinking at vz
A00, A10, B11, B01, BM11 = .206, .169, .212, .358, .055
print("level sole dragged 0.3 m/s, vz: numpy / warp / hand")
for vz in (0.3, 0.1, 0.0, -0.1, -0.3):
    g = max(math.atan2(-vz, 0.3), 0.0)
    hand = A00 + A10 + B11 * math.sin(g) + B01 * math.sin(g) + BM11 * math.sin(g)
    n, v = [0, 0, 1], [0.3, 0, vz]
    print(f"  vz {vz:+.1f}: {models.rft_support(n, v, 0.05):.4f} / {warp_support([n], [v])[0]:.4f} / {hand:.4f}")
print("tilted sole lifted along its normal at 0.3 m/s (numpy / warp / hand); level sole lifted: 1")
for th in (0, 5, 10, 20, 30, 45, 60):
    t = math.radians(th); n = [math.sin(t), 0, math.cos(t)]; v = [0.3 * x for x in n]
    fade = min(0.3 * math.sin(t) / 0.05, 1.0)
    hand = 1 + fade * (0.206 + 0.169 * math.cos(2 * t) - 0.157 * math.sin(2 * t) - 1)
    sn, sw = models.rft_support(n, v, 0.05), warp_support([n], [v])[0]
    tgt = f"rut target {1/sn:.2f} x rest depth" if sn > 0 else "no depth carries the load (rut deepens at sinkage_rate)"
    print(f"  tilt {th:2d} deg: {sn:.4f} / {sw:.4f} / {hand:.4f}  -> {tgt}")
print("tilted 30 deg, lifted straight up (world z) 0.3 m/s:", round(models.rft_support([0.5, 0, 0.866], [0, 0, 0.3], 0.05), 4))
print("tilted 30 deg, pressed along -normal 0.3 m/s:", round(models.rft_support([0.5, 0, 0.866], [-0.15, 0, -0.26], 0.05), 4))
# a sole tilted 20 deg 'leading edge up' (ski) moving forward 1 m/s and climbing 0.2 m/s: its face still presses (v.n<0)
t = math.radians(20); n = [-math.sin(t), 0, math.cos(t)]; v = [1.0, 0, 0.2]
b = math.atan2(n[2], n[0]) + math.pi / 2; g = math.atan2(-0.2, 1.0)
full = A00 + A10 * math.cos(2 * b) + B11 * math.sin(2 * b + g) + B01 * math.sin(g) + BM11 * math.sin(-2 * b + g)
print(f"ski-like sole (tilt 20 deg, leading edge up) 1 m/s forward, climbing 0.2 m/s, v.n = {np.dot(n, v):+.2f} (face pressing): "
      f"support {models.rft_support(n, v, 0.05):.3f}; RFT with its real gamma {math.degrees(g):.1f} deg by hand {full:.3f}")
