"""Checks of the shipped robot models (legged_gente/resources/robots): names, masses, geometry, limits, keyframe, and a
PD-held stand on flat ground. Plain CPU MuJoCo, no Warp."""

from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
import pytest

ROBOTS_DIR = Path(__file__).resolve().parents[1] / "legged_gente" / "resources" / "robots"
GRAVITY = 9.81


@dataclass(frozen=True)
class RobotExpectation:
    name: str
    base: str
    mass_range: tuple[float, float]
    base_height_range: tuple[float, float]
    joints: tuple[str, ...]
    feet: tuple[str, ...]
    foot_colliders: tuple[str, ...]  # the only geoms that collide
    segment_geoms: tuple[str, ...]
    segment_radius_range: tuple[float, float]


SIDES = ("left", "right")
LEGS = ("FL", "FR", "RL", "RR")
BIPED = RobotExpectation(
    name="gente_biped",
    base="pelvis",
    mass_range=(30.0, 50.0),
    base_height_range=(0.9, 1.0),
    joints=tuple(f"{s}_{j}" for s in SIDES for j in ("hip_yaw", "hip_roll", "hip_pitch", "knee", "ankle")),
    feet=tuple(f"{s}_foot" for s in SIDES),
    foot_colliders=tuple(f"{s}_sole_{c}" for s in SIDES for c in ("toe_l", "toe_r", "heel_l", "heel_r")),
    segment_geoms=tuple(f"{s}_{seg}_geom" for s in SIDES for seg in ("thigh", "shank")),
    segment_radius_range=(0.05, 0.05),  # the water model assumes exactly 0.05 m
)
QUADRUPED = RobotExpectation(
    name="gente_quadruped",
    base="trunk",
    mass_range=(12.0, 15.0),
    base_height_range=(0.27, 0.33),
    joints=tuple(f"{leg}_{j}" for leg in LEGS for j in ("hip", "thigh", "calf")),
    feet=tuple(f"{leg}_foot" for leg in LEGS),
    foot_colliders=tuple(f"{leg}_foot_geom" for leg in LEGS),
    segment_geoms=tuple(f"{leg}_{seg}_geom" for leg in LEGS for seg in ("thigh", "calf")),
    segment_radius_range=(0.02, 0.025),
)
ROBOTS = (BIPED, QUADRUPED)


def _path(robot: RobotExpectation) -> Path:
    return ROBOTS_DIR / robot.name / f"{robot.name}.xml"


def _model(robot: RobotExpectation) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(str(_path(robot)))


def _model_on_ground(robot: RobotExpectation) -> mujoco.MjModel:
    spec = mujoco.MjSpec.from_file(str(_path(robot)))
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[5.0, 5.0, 0.1])
    return spec.compile()


def _keyframe_data(model: mujoco.MjModel) -> mujoco.MjData:
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("stand").id)
    mujoco.mj_forward(model, data)
    return data


def _lowest_point_z(model: mujoco.MjModel, data: mujoco.MjData, geom_id: int) -> float:
    """Lowest world z of a box or sphere geom."""
    size = model.geom_size[geom_id]
    z = data.geom_xpos[geom_id, 2]
    if model.geom_type[geom_id] == mujoco.mjtGeom.mjGEOM_SPHERE:
        return z - size[0]
    if model.geom_type[geom_id] == mujoco.mjtGeom.mjGEOM_BOX:
        rot = data.geom_xmat[geom_id].reshape(3, 3)
        return z - np.abs(rot[2, :]) @ size
    raise AssertionError(f"foot geom {model.geom(geom_id).name} must be a box or a sphere")


def _tilt_deg(data: mujoco.MjData, body: str) -> float:
    return float(np.degrees(np.arccos(np.clip(data.body(body).xmat[8], -1.0, 1.0))))


@pytest.mark.parametrize("robot", ROBOTS, ids=lambda r: r.name)
def test_loads_with_expected_mass_joints_and_options(robot):
    model = _model(robot)
    assert robot.mass_range[0] <= mujoco.mj_getTotalmass(model) <= robot.mass_range[1]
    assert model.opt.timestep == pytest.approx(0.005)
    assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    names = [model.joint(j).name for j in range(model.njnt)]
    assert names == ["root", *robot.joints]
    assert model.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE
    assert model.body(model.jnt_bodyid[0]).name == robot.base
    assert model.nu == len(robot.joints)
    assert model.key("stand").id >= 0
    for site in ("imu", *(f"{foot}_site" for foot in robot.feet)):
        assert model.site(site).id >= 0


@pytest.mark.parametrize("robot", ROBOTS, ids=lambda r: r.name)
def test_joints_are_limited_damped_and_have_armature(robot):
    model = _model(robot)
    for name in robot.joints:
        j = model.joint(name)
        assert model.jnt_limited[j.id] and model.jnt_range[j.id, 0] < model.jnt_range[j.id, 1]
        assert model.jnt_actfrclimited[j.id] and model.jnt_actfrcrange[j.id, 1] > 0
        dof = model.jnt_dofadr[j.id]
        assert 0.01 <= model.dof_armature[dof] <= 0.1
        assert 0.3 <= model.dof_damping[dof] <= 1.0


@pytest.mark.parametrize("robot", ROBOTS, ids=lambda r: r.name)
def test_one_position_actuator_per_joint_with_joint_limits(robot):
    model = _model(robot)
    for name in robot.joints:
        act, joint = model.actuator(name), model.joint(name)
        assert model.actuator_trntype[act.id] == mujoco.mjtTrn.mjTRN_JOINT
        assert model.actuator_trnid[act.id, 0] == joint.id
        # position servo: force = kp * (ctrl - q) - kv * qdot
        kp = model.actuator_gainprm[act.id, 0]
        assert kp > 0 and model.actuator_biasprm[act.id, 1] == -kp and model.actuator_biasprm[act.id, 2] < 0
        assert model.actuator_forcelimited[act.id]
        np.testing.assert_array_equal(model.actuator_forcerange[act.id], model.jnt_actfrcrange[joint.id])
        np.testing.assert_allclose(model.actuator_ctrlrange[act.id], model.jnt_range[joint.id], atol=1e-12)


@pytest.mark.parametrize("robot", ROBOTS, ids=lambda r: r.name)
def test_leg_segments_are_capsules_of_the_specified_radius(robot):
    model = _model(robot)
    lo, hi = robot.segment_radius_range
    for name in robot.segment_geoms:
        g = model.geom(name)
        assert model.geom_type[g.id] == mujoco.mjtGeom.mjGEOM_CAPSULE
        assert lo - 1e-12 <= model.geom_size[g.id, 0] <= hi + 1e-12


def test_biped_foot_sole_size():
    model = _model(BIPED)
    for side in SIDES:
        g = model.geom(f"{side}_foot_geom")
        assert model.geom_type[g.id] == mujoco.mjtGeom.mjGEOM_BOX
        half = model.geom_size[g.id]
        assert 2 * half[0] == pytest.approx(0.22, abs=0.01)
        assert 2 * half[1] == pytest.approx(0.09, abs=0.01)
        assert 0.015 <= half[2] <= 0.04


def test_biped_sole_spheres_sit_at_the_corners_of_the_sole_box():
    """The foot touches the ground through 4 spheres (heightfield-safe, docs/robots.md); together they span
    the visual sole box, and their bottoms are the sole."""
    model = _model(BIPED)
    for side in SIDES:
        box = model.geom(f"{side}_foot_geom").id
        spheres = [model.geom(f"{side}_sole_{c}").id for c in ("toe_l", "toe_r", "heel_l", "heel_r")]
        assert all(model.geom_type[g] == mujoco.mjtGeom.mjGEOM_SPHERE for g in spheres)
        r = model.geom_size[spheres, 0]
        pos = model.geom_pos[spheres]
        box_lo = model.geom_pos[box] - model.geom_size[box]
        box_hi = model.geom_pos[box] + model.geom_size[box]
        np.testing.assert_allclose(pos[:, 2] - r, box_lo[2], atol=1e-9)  # sphere bottoms on the sole plane
        np.testing.assert_allclose([(pos[:, 0] + r).max(), (pos[:, 0] - r).min()], [box_hi[0], box_lo[0]],
                                   atol=1e-9)
        assert (pos[:, 1].max() - pos[:, 1].min()) >= 0.5 * (box_hi[1] - box_lo[1])  # resists rolling


def test_quadruped_feet_are_welded_spheres():
    model = _model(QUADRUPED)
    for leg in LEGS:
        foot = model.body(f"{leg}_foot")
        assert model.body_jntnum[foot.id] == 0
        assert model.body(model.body_parentid[foot.id]).name == f"{leg}_calf"
        g = model.geom(f"{leg}_foot_geom")
        assert model.geom_type[g.id] == mujoco.mjtGeom.mjGEOM_SPHERE
        assert 0.015 <= model.geom_size[g.id, 0] <= 0.025


@pytest.mark.parametrize("robot", ROBOTS, ids=lambda r: r.name)
def test_only_feet_collide_and_no_ground_inside(robot):
    model = _model(robot)
    foot_geoms = set(robot.foot_colliders)
    for g in range(model.ngeom):
        name = model.geom(g).name
        assert model.geom_type[g] not in (mujoco.mjtGeom.mjGEOM_PLANE, mujoco.mjtGeom.mjGEOM_HFIELD)
        collides = model.geom_contype[g] != 0 or model.geom_conaffinity[g] != 0
        assert collides == (name in foot_geoms), name
    for name in foot_geoms:
        assert model.geom_friction[model.geom(name).id, 0] == pytest.approx(1.0)


@pytest.mark.parametrize("robot", ROBOTS, ids=lambda r: r.name)
def test_keyframe_stands_flat_on_the_ground(robot):
    model = _model(robot)
    data = _keyframe_data(model)
    key = model.key("stand")
    np.testing.assert_array_equal(key.qpos[3:7], [1.0, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(key.ctrl, key.qpos[7:])
    lo, hi = robot.base_height_range
    assert lo <= data.body(robot.base).xpos[2] <= hi
    for geom in robot.foot_colliders:
        assert abs(_lowest_point_z(model, data, model.geom(geom).id)) < 0.005
    for foot in robot.feet:
        assert abs(_lowest_point_z(model, data, model.geom(f"{foot}_geom").id)) < 0.005
        assert abs(data.site(f"{foot}_site").xpos[2]) < 0.005
    for name in robot.joints:  # the stand must be inside the joint limits
        j = model.joint(name)
        q = data.qpos[model.jnt_qposadr[j.id]]
        assert model.jnt_range[j.id, 0] <= q <= model.jnt_range[j.id, 1]


def test_biped_knee_bends_backwards():
    """H1 convention: a positive knee angle moves the foot behind the knee (-x)."""
    model = _model(BIPED)
    data = mujoco.MjData(model)
    data.qpos[2] = 1.0
    data.qpos[3] = 1.0
    data.qpos[model.jnt_qposadr[model.joint("left_knee").id]] = 0.5
    mujoco.mj_kinematics(model, data)
    assert data.body("left_foot").xpos[0] < data.body("left_shank").xpos[0] - 0.1


def test_biped_ankle_gain_exceeds_toppling_stiffness():
    """With the feet fixed, tipping the whole body about the ankle axis is resisted by the two ankle
    servos alone; gravity's negative stiffness for it is m g h (inverted pendulum, small angles), so the
    placeholder gains can only hold a PD stand if 2 kp_ankle > m g h."""
    model = _model(BIPED)
    data = _keyframe_data(model)
    ankle_z = data.xanchor[model.joint("left_ankle").id, 2]
    above = [b for b in range(1, model.nbody) if not model.body(b).name.endswith("_foot")]
    mass = model.body_mass[above].sum()
    com_z = (model.body_mass[above] @ data.xipos[above, 2]) / mass
    kp_ankle = model.actuator_gainprm[model.actuator("left_ankle").id, 0]
    assert 2 * kp_ankle > mass * GRAVITY * (com_z - ankle_z)


@pytest.mark.parametrize("robot", ROBOTS, ids=lambda r: r.name)
def test_pd_holds_the_stand_for_two_seconds(robot):
    model = _model_on_ground(robot)
    data = _keyframe_data(model)
    z0 = data.body(robot.base).xpos[2]
    for _ in range(round(2.0 / model.opt.timestep)):
        mujoco.mj_step(model, data)
        assert np.all(np.isfinite(data.qpos))
        assert abs(data.body(robot.base).xpos[2] - z0) < 0.10
        assert _tilt_deg(data, robot.base) < 10.0
