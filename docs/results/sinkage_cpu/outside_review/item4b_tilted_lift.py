"""Item 4b: a 20 kg foot (0.22 x 0.096 m sole) tilted by TILT about y (sole normal (sin t, 0, cos t)) rests 1 s on
the RFT seeds (poppy_seeds_rft at its means), then a servo lifts it at 0.3 m/s, world 0 along its own normal (the
sole's face leaves the grains), world 1 straight up (world z); 0.2 s. 240 substeps. Reported: the kernel's
foot_support during the lift against models.rft_support of the foot's velocity, the rut target p/(s zeta) from the
rut's load, and the rut before/after the lift. Hand reference: a sole leaving the grains carries nothing, so its
plastic rut should keep the rest depth z0 = m g / (zeta A) (= 1 at rest, level sole lifted)."""
import math, os, sys
import numpy as np
sys.path.insert(0, os.path.join(os.environ["PYTHONPATH"], "docs/results/soil_review_cpu"))
import common as C
from common import DT, G, SOIL_PRESETS, make, mean_soil, step
import mujoco
from legged_gente.external_forces import models
TILT = float(sys.argv[1]) if len(sys.argv) > 1 else 20.0
M, L, B = 20.0, 0.22, 0.096
soles = "".join(f'<geom name="sole{k}" type="sphere" size="0.02" pos="{x} {y} 0" mass="0.001" contype="0" conaffinity="0"/>'
                for k, (x, y) in enumerate(C.SOLE_XY))
h0 = 0.02 + 0.09 * math.sin(math.radians(TILT)) + 0.002
mjm = mujoco.MjModel.from_xml_string(f"""<mujoco><option timestep="{DT}"/>
  <asset><hfield name="hf" nrow="{C.SHAPE[1]}" ncol="{C.SHAPE[0]}" size="{C.HX} 2 1 0.1"/></asset>
  <worldbody><geom name="terrain" type="hfield" hfield="hf"/>
    <body name="carrier" pos="0 0 {h0}"><joint name="x" type="slide" axis="1 0 0"/><joint name="z" type="slide" axis="0 0 1"/>
      <geom type="sphere" size="0.005" mass="0.001" contype="0" conaffinity="0"/>
      <body name="foot" euler="0 {TILT} 0">
        <geom type="box" size="0.1 0.04 0.01" pos="0 0 0.03" mass="{M}" contype="0" conaffinity="0"/>{soles}
      </body></body></worldbody></mujoco>""")
W = sum(mjm.body_mass) * G
name = "poppy_seeds_rft"; zeta = SOIL_PRESETS[name].zeta[0]
m, d, f = make(mjm, mean_soil(name), nworld=2)
t = math.radians(TILT); nrm = np.array([math.sin(t), 0, math.cos(t)])
dirs = [nrm, np.array([0, 0, 1.0])]
KD = M * 2 * 2 * math.pi * 8
z_rest = W / (L * B) / zeta
for k in range(int(1.2 / DT)):
    tt = k * DT
    v = d.qvel.numpy()
    if tt < 1.0:
        frc = [[0.0, 0.0]] * 2
    else:
        frc = [list(W * np.array([0, 1.0]) + KD * (0.3 * np.array([dirs[w][0], dirs[w][2]]) - v[w])) for w in range(2)]
    step(m, d, f, frc)
    sup = f.foot_support.numpy()[:, 0]; rut = f.foot_sinkage.numpy()[:, 0]
    sl = getattr(f, "foot_sink_load", f.foot_load).numpy()[:, 0]; fn = f.foot_fn.numpy()[:, 0]
    if abs(tt - 0.995) < 1e-6:
        rut0 = rut.copy(); print(f"tilt {TILT:.0f} deg: rest depth by hand m g/(zeta A) = {100*z_rest:.2f} cm; rut after 1 s rest {100*rut[0]:.2f} / {100*rut[1]:.2f} cm")
    if tt >= 1.0 and (k - 200) % 4 == 0 and tt < 1.1:
        vv = d.qvel.numpy()
        ref = [models.rft_support(nrm, [vv[w, 0], 0, vv[w, 1]], 0.05) for w in range(2)]
        print(f" t={tt-1.0:.3f}: " + "; ".join(
            f"{['along normal', 'straight up'][w]}: v=({vv[w,0]:+.2f},{vv[w,1]:+.2f}) F_N {fn[w]:6.1f} N support kernel {sup[w]:.3f} numpy {ref[w]:.3f} "
            f"rut load {sl[w]/W:.2f} W, target {100*sl[w]/(L*B)/zeta/max(sup[w],1e-6):.2f} cm, rut {100*rut[w]:.2f} cm" for w in range(2)))
rut = f.foot_sinkage.numpy()[:, 0]
print(f" rut gained during the lift: along normal {100*(rut[0]-rut0[0]):+.2f} cm, straight up {100*(rut[1]-rut0[1]):+.2f} cm")
