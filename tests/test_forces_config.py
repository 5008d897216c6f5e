"""ForcesConfig values that would crash a substep or silently give NaN forces are refused when the fields are built,
in one line naming the field and a valid value."""

import mujoco
import mujoco_warp as mjw
import numpy as np
import pytest
import warp as wp

from legged_gente.external_forces.field import ForcesConfig, TerrainForces
from legged_gente.terrain.materials import MaterialMap

wp.config.quiet = True
SHAPE = (5, 5)


class Cfg(ForcesConfig):
    noise_std = 0.0
    leg_geom_names = ["shin"]
    foot_geom_names = ["foot"]
    sole_contact = False


def build(**values):
    mjm = mujoco.MjModel.from_xml_string(
        '<mujoco><worldbody><geom type="plane" size="1 1 .1"/><body pos="0 0 0.3"><freejoint/>'
        '<geom name="shin" type="capsule" size="0.03 0.1"/><geom name="foot" type="box" size=".05 .04 .02" '
        'pos="0 0 -0.15"/></body></worldbody></mujoco>')
    wp.set_device("cpu")
    m = mjw.put_model(mjm)
    d = mjw.make_data(mjm, nworld=1, nconmax=8, njmax=32)
    cfg = type("C", (Cfg,), values)()
    return TerrainForces(mjm, m, d, np.zeros(SHAPE, np.float32), (-1.0, -1.0), 0.5, MaterialMap.rigid(SHAPE), cfg)


@pytest.mark.filterwarnings("ignore:forces. water geoms")
@pytest.mark.parametrize("name, value", [
    ("sinkage_load_tau", 0.0),  # after_substep divided by it: ZeroDivisionError
    ("traction_load_tau", 0.0),  # the same
    ("liftoff_clearance", -0.01),  # a foot on the ground counted as lifted off: its slip forgotten at every hop
    ("bulldozing_speed_reg", 0.0),  # a foot at rest on soil: 0 / 0 -> NaN bulldozing force
    ("water_density", -1000.0),  # buoyancy pulling down
    ("drag_coefficient", -1.1),  # drag pushing along the motion: adds energy
    ("friction_reference", 0.0),  # the map friction is divided by it
    ("noise_std", float("nan")),
])
def test_bad_values_are_refused_with_the_field_named(name, value):
    with pytest.raises(ValueError, match=f"forces.{name}="):
        build(**{name: value})


@pytest.mark.filterwarnings("ignore:forces. water geoms")
def test_defaults_are_accepted():
    assert build().nfoot == 1
