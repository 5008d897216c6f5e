"""Minimal foot world (after tests/test_forces_soil.py / tools/plot_forces_soil.py): one foot body on slide
joints, four 2 cm sole spheres, analytic sole contacts on a flat heightfield, whole map one soil."""
import math, numpy as np, mujoco, mujoco_warp as mjw, warp as wp
from legged_gente.external_forces.field import ForcesConfig, TerrainForces
from legged_gente.terrain.materials import MaterialMap
from legged_gente.terrain.soil import PARAM_NAMES, SOIL_PRESETS, register_custom_soil
wp.config.quiet = True; wp.set_device("cpu")
G, DT = 9.81, 0.005
import os
HX = float(os.environ.get("HX", "2"))  # half length of the map along x (m)
SHAPE, RES, ORIGIN = (int(round(2 * HX / 0.1)) + 1, 41), 0.1, (-HX, -2.0)
SOLE_XY = [(0.09, 0.028), (0.09, -0.028), (-0.09, 0.028), (-0.09, -0.028)]   # footprint 0.22 x 0.096 m

class Cfg(ForcesConfig):
    noise_std = 0.0; wading = False; foot_geom_names = [f"sole{k}" for k in range(4)]

def foot_model(mass, joints="xz", sole_xy=SOLE_XY, z0=0.02):
    axes = {"x": "1 0 0", "y": "0 1 0", "z": "0 0 1"}
    js = "".join(f'<joint name="{a}" type="slide" axis="{axes[a]}"/>' for a in joints)
    soles = "".join(f'<geom name="sole{k}" type="sphere" size="0.02" pos="{x} {y} 0" mass="0.001" contype="0" conaffinity="0"/>'
                    for k, (x, y) in enumerate(sole_xy))
    return mujoco.MjModel.from_xml_string(f"""<mujoco><option timestep="{DT}" {os.environ.get("OPT", "")}/>
      <asset><hfield name="hf" nrow="{SHAPE[1]}" ncol="{SHAPE[0]}" size="{HX} 2 1 0.1"/></asset>
      <worldbody><geom name="terrain" type="hfield" hfield="hf"/>
        <body name="foot" pos="0 0 {z0}">{js}
          <geom type="box" size="0.1 0.04 0.01" pos="0 0 0.03" mass="{mass}" contype="0" conaffinity="0"/>{soles}
        </body></worldbody></mujoco>""")

def mean_soil(name, **override):
    """preset `name` at its means, std 0 (optionally parameters overridden)."""
    p = SOIL_PRESETS[name]
    vals = {q: getattr(p, q)[0] for q in PARAM_NAMES}; vals.update(override)
    tag = f"mine_{name}_" + "_".join(f"{k}{v:g}" for k, v in override.items())
    register_custom_soil(tag, **vals, model=p.model)
    return tag

def make(mjm, soil=None, nworld=1, friction=1.0, seed=1, **cfg):
    mat = MaterialMap.rigid(SHAPE, friction=friction)
    if soil is not None:
        mat.soil[:] = 0; mat.soil_presets = [soil]
    m = mjw.put_model(mjm)
    d = mjw.make_data(mjm, nworld=nworld, nconmax=16 * nworld, njmax=64 * nworld)
    f = TerrainForces(mjm, m, d, np.zeros(SHAPE, np.float32), ORIGIN, RES, mat, type("C", (Cfg,), cfg)(), seed=seed)
    f.install()
    return m, d, f

def step(m, d, f, qfrc=None):
    if qfrc is not None:
        d.qfrc_applied.assign(np.asarray(qfrc, np.float32))
    mjw.step(m, d); f.after_substep()

def bekker(p, kc, kphi, n, b):
    return (p / (kc / b + kphi)) ** (1.0 / n)
