"""Every built-in task's config against its robot's MJCF (plain CPU MuJoCo kinematics, no simulation): the default
pose inside the joint limits, the spawn above the ground, the base height target at the default pose's height."""

import mujoco
import numpy as np
import pytest

from legged_gente.envs.task_registry import task_registry
from legged_gente.sim.assembly import resolve_path, value_for

BUILTIN = ("gente_biped", "gente_biped_flat", "gente_quadruped", "gente_quadruped_flat")


def default_pose(task: str):
    """(cfg, model, data): the robot as every reset starts it without noise, the base at init_state.pos and the
    joints at the config's default angles."""
    cfg, _ = task_registry.get_cfgs(task)
    model = mujoco.MjModel.from_xml_path(str(resolve_path(cfg.asset.file)))
    data = mujoco.MjData(model)
    data.qpos[0:3], data.qpos[3:7] = cfg.init_state.pos, cfg.init_state.rot
    for j in range(1, model.njnt):
        data.qpos[model.jnt_qposadr[j]] = value_for(model.joint(j).name, cfg.init_state.default_joint_angles, "angle")
    mujoco.mj_kinematics(model, data)
    return cfg, model, data


def lowest_collider_z(model, data) -> float:
    """Lowest point of the geoms that touch the ground (the shipped robots collide through spheres only)."""
    colliding = [g for g in range(model.ngeom) if model.geom_contype[g] or model.geom_conaffinity[g]]
    assert all(model.geom_type[g] == mujoco.mjtGeom.mjGEOM_SPHERE for g in colliding)
    return min(data.geom_xpos[g, 2] - model.geom_size[g, 0] for g in colliding)


@pytest.mark.parametrize("task", BUILTIN)
def test_default_angles_are_inside_the_joint_limits(task):
    _, model, data = default_pose(task)
    for j in range(1, model.njnt):
        low, high = model.jnt_range[j]
        assert low <= data.qpos[model.jnt_qposadr[j]] <= high, model.joint(j).name


@pytest.mark.parametrize("task", BUILTIN)
def test_spawn_is_above_the_ground_and_the_height_target_near_the_stand(task):
    cfg, model, data = default_pose(task)
    clearance = lowest_collider_z(model, data)
    assert 0.0 <= clearance <= 0.05  # dropped from at most 5 cm, never started inside the ground
    standing = cfg.init_state.pos[2] - clearance  # the base's height with the feet on flat ground
    assert abs(cfg.rewards.base_height_target - standing) <= 0.03 * standing



@pytest.mark.parametrize("task", BUILTIN)
def test_a_reset_s_joint_noise_never_starts_a_collider_inside_the_ground(task):
    """Resets add uniform noise of +-init_state.joint_pos_noise to every default angle (before any joint limit):
    at the worst of 2000 draws the robot still starts above flat ground, so no reset launches it out of it."""
    cfg, model, data = default_pose(task)
    noise = cfg.init_state.joint_pos_noise
    rng = np.random.default_rng(0)
    default = data.qpos.copy()
    worst = np.inf
    for _ in range(2000):
        data.qpos[:] = default
        data.qpos[7:] += rng.uniform(-noise, noise, model.nq - 7)
        mujoco.mj_kinematics(model, data)
        worst = min(worst, lowest_collider_z(model, data))
    assert worst >= 0.0, f"{task}: a collider starts {-worst * 100:.1f} cm inside the ground"
