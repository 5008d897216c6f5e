"""MuJoCo's contact adhesion as a load-independent shear capacity (docs/forces.md, "A sliding sole's traction on a
cohesive soil"): a 10 kg box on a plane (four contacts, friction 0.2, pyramidal cone) with each contact's adhesion
a = 0 or 100 N, pushed sideways or pulled up from rest for 2.5 s, in MuJoCo and in MuJoCo-Warp (CPU).

By hand: without adhesion it slides above 0.2 x 98.1 = 19.6 N; with it, above 0.2 x (98.1 + 4 x 100) = 99.6 N
(Coulomb's cone on the contacts' normal force plus their adhesion, which MuJoCo applies back as a passive pull, so
the net normal force stays the weight); a pull above the weight lifts it either way (the adhesion acts while the
contacts penetrate, here without margin).

    python adhesion_friction_limit.py
"""
import mujoco
import mujoco_warp as mjw
import numpy as np
import warp as wp

XML = """
<mujoco>
  <option timestep="0.002" cone="pyramidal"/>
  <worldbody>
    <geom type="plane" size="100 5 0.1" friction="0.2 0 0"/>
    <body pos="0 0 0.05">
      <joint type="slide" axis="1 0 0"/>
      <joint type="slide" axis="0 0 1"/>
      <geom type="box" size="0.1 0.1 0.05" mass="10" friction="0.2 0 0" adhesion="{a}"/>
    </body>
  </worldbody>
</mujoco>
"""
STEPS, START = 1250, 250
CASES = [(0.0, "push", f) for f in (15.0, 19.0, 25.0)] + [(100.0, "push", f) for f in (25.0, 90.0, 97.0, 102.0)] \
    + [(100.0, "pull", f) for f in (50.0, 150.0)]

wp.config.quiet = True
for adhesion, kind, force in CASES:
    mjm = mujoco.MjModel.from_xml_string(XML.format(a=adhesion))
    dof = 0 if kind == "push" else 1
    d = mujoco.MjData(mjm)
    for i in range(STEPS):
        d.qfrc_applied[dof] = force if i >= START else 0.0
        mujoco.mj_step(mjm, d)
    with wp.ScopedDevice("cpu"):
        m_w = mjw.put_model(mjm)
        d_w = mjw.make_data(mjm, nworld=1, nconmax=8, njmax=32)
        for i in range(STEPS):
            d_w.qfrc_applied.assign(np.array([[force if (i >= START and j == dof) else 0.0 for j in range(2)]],
                                             np.float32))
            mjw.step(m_w, d_w)
    print(f"adhesion {adhesion:5.0f} N per contact, {kind} {force:5.1f} N: MuJoCo moved {d.qpos[dof]:8.4f} m "
          f"({d.qvel[dof]:6.3f} m/s), MuJoCo-Warp {d_w.qpos.numpy()[0, dof]:8.4f} m "
          f"({d_w.qvel.numpy()[0, dof]:6.3f} m/s)")
