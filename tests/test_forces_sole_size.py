"""The sole a foot presses on the soil with, derived from its geoms (forces.sole_length / sole_width None): the
footprint of each geom as it is turned in the foot body, by hand."""

import math

import mujoco
import mujoco_warp as mjw
import numpy as np
import pytest
import warp as wp

from legged_gente.external_forces.field import ForcesConfig, TerrainForces
from legged_gente.terrain.materials import MaterialMap

wp.config.quiet = True
SHAPE = (5, 5)


def sole(geom: str):
    """TerrainForces of a foot body whose one geom named "sole" is ``geom``."""
    mjm = mujoco.MjModel.from_xml_string(
        f'<mujoco><worldbody><geom type="plane" size="1 1 .1"/><body name="foot" pos="0 0 0.3"><freejoint/>'
        f'<geom name="sole" {geom} mass="1" contype="0" conaffinity="0"/></body></worldbody></mujoco>')

    class Cfg(ForcesConfig):
        noise_std, wading, sole_contact, foot_geom_names = 0.0, False, False, ["sole"]

    wp.set_device("cpu")
    m = mjw.put_model(mjm)
    d = mjw.make_data(mjm, nworld=1, nconmax=8, njmax=32)
    return TerrainForces(mjm, m, d, np.zeros(SHAPE, np.float32), (-1.0, -1.0), 0.5, MaterialMap.rigid(SHAPE), Cfg())


def test_capsule_lying_along_the_foot_is_a_rectangle():
    # r 2 cm, its axis 0.1 m along the foot's x: footprint (0.1 + 2 r) x 2 r = 0.14 m x 0.04 m, Bekker's b the
    # smaller side; it rests on its side, r below its axis
    f = sole('type="capsule" fromto="-0.05 0 0 0.05 0 0" size="0.02"')
    assert (f.sole_length, f.sole_width, f.sole_disc) == (pytest.approx(0.14), pytest.approx(0.04), False)
    assert f.sole_area == pytest.approx(0.14 * 0.04) and f.bekker_width == pytest.approx(0.04)
    assert f.foot_drop.numpy()[0] == pytest.approx(0.02)


def test_upright_capsule_and_sphere_are_discs():
    # an upright capsule (r 2 cm, half-length 5 cm) stands on its end cap: a disc of radius r, 7 cm below its centre
    f = sole('type="capsule" size="0.02 0.05"')
    assert f.sole_disc and f.sole_area == pytest.approx(math.pi * 0.02**2) and f.bekker_width == pytest.approx(0.02)
    assert f.foot_drop.numpy()[0] == pytest.approx(0.07)
    f = sole('type="sphere" size="0.03"')
    assert f.sole_disc and f.sole_area == pytest.approx(math.pi * 0.03**2)
    assert f.foot_drop.numpy()[0] == pytest.approx(0.03)


def test_turned_box_sole_takes_its_turned_extent():
    # a 0.2 x 0.08 x 0.02 m box turned 90 deg about z lies 0.08 m along the foot's x and 0.2 m along its y
    f = sole('type="box" size="0.1 0.04 0.01" euler="0 0 90"')
    assert (f.sole_length, f.sole_width) == (pytest.approx(0.08), pytest.approx(0.2)) and not f.sole_disc
    # on its edge (turned 90 deg about x) it is 0.2 m x 0.02 m and stands 0.04 m below its centre
    f = sole('type="box" size="0.1 0.04 0.01" euler="90 0 0"')
    assert (f.sole_length, f.sole_width) == (pytest.approx(0.2), pytest.approx(0.02))
    assert f.foot_drop.numpy()[0] == pytest.approx(0.04)


def test_turning_a_round_geom_about_its_axis_changes_nothing():
    # a sphere or an upright cylinder turned 45 deg about z keeps its footprint: a disc of its radius
    for geom, r in (('type="sphere" size="0.03" euler="0 0 45"', 0.03),
                    ('type="cylinder" size="0.02 0.05" euler="0 0 45"', 0.02)):
        f = sole(geom)
        assert f.sole_disc and f.sole_area == pytest.approx(math.pi * r * r) and f.bekker_width == pytest.approx(r)
