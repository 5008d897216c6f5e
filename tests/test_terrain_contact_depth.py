"""A leg, body or box-sole geom that MuJoCo collides with the heightfield (not an analytic sole) and that ends up
inside a tall column (a tree, a pillar) is given the column's top prism face, metres above it, as its contact: the
biped's shank was seen 2.45 m "deep" in a 3 m tree of a forest scene and left at 11-28 m/s. The contact filter
caps every terrain contact's penetration at ``terrain_contact_max_depth``."""

import mujoco
import mujoco_warp as mjw
import numpy as np
import pytest
from test_forces_contact import ORIGIN, RES, energy_gained_on_slides, tall_step

from legged_gente.external_forces.field import ForcesConfig, TerrainForces
from legged_gente.terrain.materials import MaterialMap

XML = """<mujoco><option timestep="0.005"/>
  <asset><hfield name="hf" nrow="21" ncol="21" size="1 1 1.5 0.1"/></asset>
  <worldbody><geom name="terrain" type="hfield" hfield="hf"/>
    <body name="shank"><joint type="slide" axis="1 0 0"/><joint type="slide" axis="0 0 1"/>
      <geom name="shank" type="capsule" fromto="0 -0.1 0 0 0.1 0" size="0.03" mass="2"/></body>
  </worldbody></mujoco>"""
STARTS = [(0.12, 1.0), (0.2, 1.0), (0.4, 1.0)]  # 2, 10 and 30 cm past the 1.5 m step's riser, 0.5 m below its top


class Cfg(ForcesConfig):
    noise_std, wading, soil, friction_from_map, sole_contact = 0.0, False, False, False, False
    foot_geom_names, leg_geom_names = [], []


def scene(cap):
    mjm = mujoco.MjModel.from_xml_string(XML)
    h = tall_step(1.5)
    mjm.hfield_data[:] = (h.T / 1.5).ravel()
    m = mjw.put_model(mjm)
    d = mjw.make_data(mjm, nworld=len(STARTS), nconmax=64, njmax=256)
    cfg = type("C", (Cfg,), {"terrain_contact_max_depth": cap})
    forces = TerrainForces(mjm, m, d, h, ORIGIN, RES, MaterialMap.rigid(h.shape), cfg(), seed=0)
    forces.install()
    d.qpos.assign(np.asarray(STARTS, np.float32))
    return m, d, forces


def test_a_capsule_inside_a_tall_step_gets_no_contact_deeper_than_the_cap():
    cap = 0.03
    m, d, _ = scene(cap)
    mjw.forward(m, d)
    n = int(d.nacon.numpy()[0])
    dist = d.contact.dist.numpy()[:n]
    assert n > 0
    assert dist.min() >= -cap - 1e-6, dist.min()  # MuJoCo gives the top face, 0.5 m above the capsule


def test_a_capsule_released_inside_a_tall_step_is_not_launched():
    """As test_forces_contact's sole sphere: pushed out from a depth of at most D = 3 cm, MuJoCo's soft contact
    (a_ref = -b v - k r, b = 2 / (dmax tc), k = 1 / (dmax^2 tc^2), tc 0.02 s, dmax 0.95) moves it at most at
    v = D / (2 dmax tc) = 0.79 m/s: over T = 0.5 s its energy per unit mass grows by at most g T v + v^2 / 2."""
    tc, dmax, cap, g = 0.02, 0.95, 0.03, 9.81
    v_max = cap / (2 * dmax * tc)
    m, d, forces = scene(cap)
    steps, dt = 100, 0.005
    gained = energy_gained_on_slides(m, d, forces, steps, g, z0=1.0)
    assert np.all(gained <= g * steps * dt * v_max + 0.5 * v_max**2), gained


@pytest.mark.parametrize("value", [0.0, -0.01, float("inf"), float("nan")])
def test_a_cap_that_is_not_a_finite_positive_depth_is_refused(value):
    with pytest.raises(ValueError, match=r"forces.terrain_contact_max_depth=.*must be a finite number > 0"):
        scene(value)
