"""GenteBiped's sole clearance (the swing-height reward's input) for the sole shapes a biped may have, and a clear
error for sole geoms that are not on a foot."""

import math
import re

import pytest

from legged_gente.envs.gente_biped.gente_biped import GenteBiped
from legged_gente.envs.gente_biped.gente_biped_config import GenteBipedFlatCfg
from legged_gente.sim.assembly import resolve_path

# gente_biped.xml: pelvis -> hip pitch axis 0.07 + 0.05 + 0.04 m, thigh 0.4 m, shank 0.4 m, ankle -> sole centres
# 0.05 m, sole radius 0.02 m (and the sole box's bottom at 0.05 + 0.02 m)
PELVIS_TO_HIP, THIGH, SHANK, ANKLE_TO_SOLE = 0.16, 0.4, 0.4, 0.07
HIP_PITCH, KNEE = -0.25, 0.55  # the task's default angles; ankle -0.3 keeps the foot level (-0.25 + 0.55 - 0.3 = 0)


def biped(tmp_path, sole_geoms, xml_edit=None):
    cfg = GenteBipedFlatCfg()
    cfg.env.num_envs = 2
    cfg.init_state.joint_pos_noise = 0.0  # the default pose exactly: a level foot at a known height
    cfg.asset.sole_geoms = sole_geoms
    if xml_edit is not None:
        path = tmp_path / "biped.xml"
        path.write_text(xml_edit(resolve_path(cfg.asset.file).read_text()))
        cfg.asset.file = str(path)
    return GenteBiped(cfg, device="cpu")


def capsule_soles(text: str) -> str:
    """Each foot's four sole spheres -> two capsules of the same radius lying across the sole (toe and heel)."""
    for side in ("left", "right"):
        text = re.sub(rf'\s*<geom name="{side}_sole_\w+" class="sole" pos="[^"]*"/>', "", text)
        capsules = "".join(f'<geom name="{side}_sole_{end}" class="sole" type="capsule" '
                           f'fromto="{x} 0.028 -0.05 {x} -0.028 -0.05"/>' for end, x in (("toe", 0.14), ("heel", -0.04)))
        text = text.replace(f'<site name="{side}_foot_site"', capsules + f'<site name="{side}_foot_site"')
    return text


@pytest.mark.parametrize("sole_geoms, xml_edit", [(["*_sole_*"], None), (["*_foot_geom"], None),
                                                 (["*_sole_*"], capsule_soles)], ids=["spheres", "box", "capsules"])
def test_clearance_of_a_level_foot_is_its_height_above_the_ground(tmp_path, sole_geoms, xml_edit):
    env = biped(tmp_path, sole_geoms, xml_edit)
    standing = PELVIS_TO_HIP + THIGH * math.cos(HIP_PITCH) + SHANK * math.cos(HIP_PITCH + KNEE) + ANKLE_TO_SOLE
    expected = env.cfg.init_state.pos[2] - standing  # the reset puts the pelvis at init_state.pos over flat ground
    assert env.sole_clearance().flatten().tolist() == pytest.approx([expected] * 4, abs=1e-5)


def test_sole_geoms_off_the_feet_are_named(tmp_path):
    with pytest.raises(ValueError, match=r"pelvis_geom.*not on a foot"):
        biped(tmp_path, ["*_sole_*", "pelvis_geom"])


def test_an_unsupported_sole_shape_is_named(tmp_path):
    ellipsoid = lambda text: text.replace('<geom type="sphere" size="0.02" mass="0"',  # noqa: E731
                                          '<geom type="ellipsoid" size="0.02 0.02 0.02" mass="0"')
    with pytest.raises(ValueError, match=r"left_sole_toe_l is of type ellipsoid.*sphere, capsule or box"):
        biped(tmp_path, ["*_sole_*"], ellipsoid)
