"""Reviewer's own foot rig: a level foot body on x/y/z slide joints, four r=2 cm sole spheres (analytic sole
contacts), whole map one soil, terrain heights given."""
import os, math, numpy as np, mujoco, mujoco_warp as mjw, warp as wp
from legged_gente.external_forces.field import ForcesConfig, TerrainForces
from legged_gente.terrain.materials import MaterialMap
from legged_gente.terrain.soil import PARAM_NAMES, SOIL_PRESETS, register_custom_soil
wp.config.quiet = True; wp.set_device("cpu")
G, DT, RES = 9.81, 0.005, 0.1
SOLES = [(0.09, 0.028), (0.09, -0.028), (-0.09, 0.028), (-0.09, -0.028)]

class Cfg(ForcesConfig):
    noise_std = 0.0; wading = False; foot_geom_names = [f"s{k}" for k in range(4)]

def soil_nobull(name, **ov):
    p = SOIL_PRESETS[name]; v = {q: getattr(p, q)[0] for q in PARAM_NAMES}
    v.update(bulldoze_c=0.0, bulldoze_g=0.0); v.update(ov)
    tag = "rev_" + name + "".join(f"_{k}{x:g}" for k, x in ov.items())
    register_custom_soil(tag, **v, model=p.model); return tag, v

def build(mass, heights, origin, soil, nworld, z0=0.02, **cfg):
    nx, ny = heights.shape
    xml = f"""<mujoco><option timestep="{DT}"/>
     <asset><hfield name="hf" nrow="{ny}" ncol="{nx}" size="{(nx-1)*RES/2} {(ny-1)*RES/2} 1 0.1"/></asset>
     <worldbody><geom name="ground" type="hfield" hfield="hf" pos="{origin[0]+(nx-1)*RES/2} {origin[1]+(ny-1)*RES/2} 0"/>
      <body name="foot" pos="0 0 {z0}"><joint name="jx" type="slide" axis="1 0 0"/><joint name="jy" type="slide" axis="0 1 0"/>
       <joint name="jz" type="slide" axis="0 0 1"/>
       <geom type="box" size="0.1 0.04 0.01" pos="0 0 0.03" mass="{mass}" contype="0" conaffinity="0"/>
       {''.join(f'<geom name="s{k}" type="sphere" size="0.02" pos="{x} {y} 0" mass="0.001" contype="0" conaffinity="0"/>' for k,(x,y) in enumerate(SOLES))}
      </body></worldbody></mujoco>"""
    mjm = mujoco.MjModel.from_xml_string(xml)
    mat = MaterialMap.rigid(heights.shape)
    mat.soil[:] = 0; mat.soil_presets = [soil]
    m = mjw.put_model(mjm); d = mjw.make_data(mjm, nworld=nworld, nconmax=16*nworld, njmax=64*nworld)
    f = TerrainForces(mjm, m, d, heights.astype(np.float32), origin, RES, mat, type("C", (Cfg,), cfg)(), seed=0)
    f.install()
    return mjm, m, d, f, sum(mjm.body_mass) * G

def step(m, d, f, q):
    d.qfrc_applied.assign(np.asarray(q, np.float32)); mjw.step(m, d); f.after_substep()

def limit(d, f, w=0):
    """sum over world w's contacts of mu * (that contact's share): mu_mean * F_N of the foot."""
    n = int(d.nacon.numpy()[0]); wid = d.contact.worldid.numpy()[:n]; mu = d.contact.friction.numpy()[:n, 0]
    sel = wid == w
    return float(mu[sel].mean()) if sel.any() else 0.0
