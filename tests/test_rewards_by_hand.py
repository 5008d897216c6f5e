"""Each reward term's value against a hand computation from its definition (legged_gym's formulas,
leggedrobotics/legged_gym legged_gym/envs/base/legged_robot.py, and the biped's docstrings): the state a term reads
is set to chosen numbers, the expected value is worked out here from the formula."""

import math

import pytest
import torch

from legged_gente.envs.task_registry import task_registry
from legged_gente.utils.args import build_parser, parse_args

N = 2
# gente_biped.xml: joint ranges (rad) and actuator force ranges (N*m) per joint kind
RANGE = {"hip_yaw": (-0.43, 0.43), "hip_roll": (-0.43, 0.43), "hip_pitch": (-1.57, 1.0), "knee": (0.0, 2.0),
         "ankle": (-0.87, 0.87)}
FORCE_LIMIT = {"hip_yaw": 120.0, "hip_roll": 150.0, "hip_pitch": 150.0, "knee": 250.0, "ankle": 50.0}
# gente_biped.xml, all joints at 0: foot body origin from the pelvis, y 0.09 + 0.02, z -(0.07 + 0.05 + 0.04 + 0.4 + 0.4)
FOOT_FROM_PELVIS = {"left_foot": (0.0, 0.11, -0.96), "right_foot": (0.0, -0.11, -0.96)}


@pytest.fixture(scope="module")
def env():
    args = parse_args(build_parser("test"), ["--task", "gente_biped_flat", "--device", "cpu", "--num_envs", str(N),
                                             "--set", "domain_rand.push_robots=False"])
    env, _ = task_registry.make_env("gente_biped_flat", args)
    return env


def joint(env, name):
    return env.layout.joint_names.index(name)


def kind(name):
    return name.split("_", 1)[1]  # "left_hip_pitch" -> "hip_pitch"


def body(env, name):
    return env.mjm.body(name).id


def feet_forces(env, per_foot):
    """Contact forces with ``per_foot`` (N, num_feet, 3) on the feet (in the order of env.feet), zero elsewhere."""
    forces = torch.zeros(N, env.mjm.nbody, 3)
    forces[:, env.feet] = torch.tensor(per_foot, dtype=torch.float32)
    return forces


def close(value, expected):
    assert value.tolist() == pytest.approx(expected, rel=1e-5, abs=1e-6)


# ---------------------------------------------------------------------------------------------------------------
# base motion
# ---------------------------------------------------------------------------------------------------------------
def test_lin_vel_z_is_the_squared_vertical_body_velocity(env):
    env.base_lin_vel = torch.tensor([[0.5, 0.1, -0.3], [0.0, 0.0, 0.7]])
    close(env._reward_lin_vel_z(), [0.09, 0.49])


def test_ang_vel_xy_is_the_squared_roll_and_pitch_rates(env):
    env.base_ang_vel = torch.tensor([[0.3, -0.4, 2.0], [1.0, 0.0, -5.0]])
    close(env._reward_ang_vel_xy(), [0.3**2 + 0.4**2, 1.0])


def test_orientation_is_the_squared_horizontal_gravity_in_the_base_frame(env):
    env.projected_gravity = torch.tensor([[0.1, -0.2, -0.97], [0.0, 0.0, -1.0]])
    close(env._reward_orientation(), [0.01 + 0.04, 0.0])


def test_a_pitched_base_moving_up_gives_orientation_and_lin_vel_z_in_its_own_frame(env):
    # base pitched by theta about y, moving straight up at 0.8 m/s (world): in the base frame gravity is
    # R^T (0, 0, -1) = (sin theta, 0, -cos theta) and the velocity R^T (0, 0, v) = (-v sin theta, 0, v cos theta)
    theta, v = 0.3, 0.8
    env.sim.qpos[:, 3:7] = torch.tensor([math.cos(theta / 2), 0.0, math.sin(theta / 2), 0.0])
    env.sim.qvel[:] = 0.0
    env.sim.qvel[:, 0:3] = torch.tensor([0.0, 0.0, v])
    env.sim.qvel[:, 3:6] = torch.tensor([0.2, -0.1, 0.4])  # body-frame rates (MuJoCo's free joint)
    env._update_state()
    close(env._reward_orientation(), [math.sin(theta) ** 2] * N)
    close(env._reward_lin_vel_z(), [(v * math.cos(theta)) ** 2] * N)
    close(env._reward_ang_vel_xy(), [0.2**2 + 0.1**2] * N)


def test_base_height_is_the_squared_error_from_the_target_over_flat_ground(env):
    target = env.cfg.rewards.base_height_target  # 0.98 m; the plane is at z = 0
    env.base_pos = torch.tensor([[1.0, 2.0, 0.90], [-3.0, 0.5, 1.10]])
    close(env._reward_base_height(), [(0.90 - target) ** 2, (1.10 - target) ** 2])


# ---------------------------------------------------------------------------------------------------------------
# velocity tracking
# ---------------------------------------------------------------------------------------------------------------
def test_tracking_lin_vel_is_a_gaussian_kernel_of_the_xy_error(env):
    sigma = env.cfg.rewards.tracking_sigma  # 0.25 (m/s)^2
    env.commands = torch.tensor([[1.0, 0.2, 0.5, 0.0], [0.0, 0.0, 0.0, 0.0]])
    env.base_lin_vel = torch.tensor([[0.7, 0.6, 3.0], [0.0, 0.0, -1.0]])  # z plays no part
    close(env._reward_tracking_lin_vel(), [math.exp(-(0.3**2 + 0.4**2) / sigma), 1.0])


def test_tracking_ang_vel_is_a_gaussian_kernel_of_the_yaw_rate_error(env):
    sigma = env.cfg.rewards.tracking_sigma
    env.commands = torch.tensor([[1.0, 0.2, 0.5, 0.0], [0.0, 0.0, -1.0, 0.0]])
    env.base_ang_vel = torch.tensor([[3.0, -2.0, 0.1], [0.0, 0.0, -1.0]])  # roll, pitch play no part
    close(env._reward_tracking_ang_vel(), [math.exp(-0.4**2 / sigma), 1.0])


def test_tracking_sigma_set_at_run_time_is_the_one_used(env):
    env.commands = torch.tensor([[1.0, 0.0, 0.0, 0.0]] * N)
    env.base_lin_vel = torch.zeros(N, 3)
    env.set_param("rewards.tracking_sigma", 0.5)
    try:
        close(env._reward_tracking_lin_vel(), [math.exp(-1.0 / 0.5)] * N)
    finally:
        env.set_param("rewards.tracking_sigma", 0.25)


# ---------------------------------------------------------------------------------------------------------------
# joints and actions
# ---------------------------------------------------------------------------------------------------------------
def test_torques_is_the_sum_of_squared_joint_torques(env):
    torques = torch.zeros(N, env.num_actions)
    torques[0, :3] = torch.tensor([10.0, -20.0, 5.0])
    torques[1, -1] = -40.0
    env.torques = torques
    close(env._reward_torques(), [100.0 + 400.0 + 25.0, 1600.0])


def test_dof_vel_is_the_sum_of_squared_joint_velocities(env):
    vel = torch.zeros(N, env.num_actions)
    vel[0, 1], vel[0, 7] = 2.0, -3.0
    env.dof_vel = vel
    close(env._reward_dof_vel(), [13.0, 0.0])


def test_dof_acc_is_the_squared_finite_difference_over_the_policy_step(env):
    dt = env.cfg.sim.dt * env.cfg.control.decimation  # 0.005 s * 4 = 0.02 s
    assert dt == pytest.approx(0.02)
    env.last_dof_vel = torch.zeros(N, env.num_actions)
    env.dof_vel = torch.zeros(N, env.num_actions)
    env.last_dof_vel[0, 0], env.dof_vel[0, 0] = 1.0, 1.2  # 10 rad/s^2
    env.dof_vel[1, 4] = -0.1  # -5 rad/s^2
    close(env._reward_dof_acc(), [(0.2 / 0.02) ** 2, (0.1 / 0.02) ** 2])


def test_action_rate_is_the_squared_change_of_the_actions(env):
    env.last_actions = torch.zeros(N, env.num_actions)
    env.actions = torch.zeros(N, env.num_actions)
    env.last_actions[0, :2] = torch.tensor([0.5, -0.5])
    env.actions[0, :2] = torch.tensor([0.2, 0.5])
    env.actions[1, 9] = 2.0
    close(env._reward_action_rate(), [0.3**2 + 1.0**2, 4.0])


def test_torque_limits_penalises_torque_above_the_soft_fraction_of_each_actuators_limit(env):
    torques = torch.zeros(N, env.num_actions)
    torques[0, joint(env, "left_knee")] = -260.0  # limit 250: 10 over
    torques[0, joint(env, "right_ankle")] = 55.0  # limit 50: 5 over
    torques[0, joint(env, "left_hip_yaw")] = 119.0  # limit 120: under
    torques[1, joint(env, "right_hip_pitch")] = 140.0
    env.torques = torques
    close(env._reward_torque_limits(), [15.0, 0.0])
    env.set_param("rewards.soft_torque_limit", 0.9)  # right hip pitch: 140 - 0.9 * 150 = 5 over
    try:
        left_knee = 260.0 - 0.9 * FORCE_LIMIT["knee"]
        right_ankle = 55.0 - 0.9 * FORCE_LIMIT["ankle"]
        left_hip_yaw = 119.0 - 0.9 * FORCE_LIMIT["hip_yaw"]
        close(env._reward_torque_limits(), [left_knee + right_ankle + left_hip_yaw, 140.0 - 0.9 * 150.0])
    finally:
        env.set_param("rewards.soft_torque_limit", 1.0)


def test_dof_pos_limits_penalises_the_distance_past_the_soft_joint_range(env):
    soft = env.cfg.rewards.soft_dof_pos_limit  # 0.9: the range shrunk about its middle (legged_gym)

    def soft_range(name):
        low, high = RANGE[kind(name)]
        mid, half = (low + high) / 2, soft * (high - low) / 2
        return mid - half, mid + half

    pos = torch.zeros(N, env.num_actions)
    for i, name in enumerate(env.layout.joint_names):
        pos[:, i] = sum(soft_range(name)) / 2  # every joint mid-range: no penalty
    knee_low = soft_range("left_knee")[0]  # 1.0 - 0.9 = 0.1
    pitch_high = soft_range("right_hip_pitch")[1]  # -0.285 + 0.9 * 1.285 = 0.8715
    pos[0, joint(env, "left_knee")] = 0.05
    pos[0, joint(env, "right_hip_pitch")] = 0.95
    env.dof_pos = pos
    assert knee_low == pytest.approx(0.1) and pitch_high == pytest.approx(0.8715)
    close(env._reward_dof_pos_limits(), [(knee_low - 0.05) + (0.95 - pitch_high), 0.0])


def test_stand_still_penalises_joint_offsets_only_under_a_stand_still_command(env):
    pos = env.default_dof_pos.repeat(N, 1)
    pos[:, joint(env, "left_knee")] += 0.2
    pos[:, joint(env, "right_hip_roll")] -= 0.1
    env.dof_pos = pos
    env.commands = torch.tensor([[0.05, 0.05, 0.8, 0.0], [0.3, 0.0, 0.0, 0.0]])  # |v_xy| 0.07 < 0.1; 0.3 > 0.1
    close(env._reward_stand_still(), [0.3, 0.0])


def test_hip_deviation_is_the_squared_offset_of_the_hip_yaw_and_roll_joints(env):
    pos = env.default_dof_pos.repeat(N, 1)
    for name, offset in (("left_hip_yaw", 0.1), ("left_hip_roll", -0.2), ("right_hip_yaw", 0.3),
                         ("right_hip_roll", 0.05)):
        pos[0, joint(env, name)] += offset
    pos[1, joint(env, "left_hip_pitch")] += 0.5  # hip pitch, knee and ankle are not hip deviation
    pos[1, joint(env, "right_knee")] += 0.5
    env.dof_pos = pos
    close(env._reward_hip_deviation(), [0.01 + 0.04 + 0.09 + 0.0025, 0.0])


# ---------------------------------------------------------------------------------------------------------------
# contacts
# ---------------------------------------------------------------------------------------------------------------
def test_collision_counts_penalised_bodies_with_a_contact_force_over_0_1_newton(env):
    forces = torch.zeros(N, env.mjm.nbody, 3)
    forces[0, body(env, "left_thigh")] = torch.tensor([0.0, 0.08, 0.08])  # |f| = 0.113 > 0.1
    forces[0, body(env, "right_shank")] = torch.tensor([0.0, 0.0, 20.0])
    forces[0, body(env, "left_foot")] = torch.tensor([0.0, 0.0, 300.0])  # a foot is not penalised
    forces[1, body(env, "left_shank")] = torch.tensor([0.05, 0.05, 0.05])  # |f| = 0.087 < 0.1
    forces[1, body(env, "pelvis")] = torch.tensor([0.0, 0.0, 50.0])  # the pelvis terminates, is not penalised
    env.contact_forces = forces
    close(env._reward_collision(), [2.0, 0.0])


def test_feet_stumble_is_a_foot_pushed_sideways_more_than_five_times_its_vertical_force(env):
    env.contact_forces = feet_forces(env, [[[30.0, 40.0, 9.0], [0.0, 0.0, 100.0]],  # 50 > 5 * 9
                                           [[30.0, 40.0, 11.0], [5.0, 0.0, -2.0]]])  # 50 < 55; 5 < 10
    close(env._reward_feet_stumble(), [1.0, 0.0])


def test_feet_contact_forces_penalises_force_above_the_maximum(env):
    fmax = env.cfg.rewards.max_contact_force  # 500 N
    env.contact_forces = feet_forces(env, [[[300.0, 0.0, 400.0], [0.0, 0.0, 480.0]],  # 500 N: none over
                                           [[0.0, 360.0, 480.0], [0.0, 0.0, 700.0]]])  # 600 N and 700 N
    close(env._reward_feet_contact_forces(), [0.0, (600.0 - fmax) + (700.0 - fmax)])


def test_no_fly_is_one_while_a_foot_bears_more_than_one_newton(env):
    env.contact_forces = feet_forces(env, [[[0.0, 0.0, 1.5], [0.0, 0.0, 0.0]],
                                           [[50.0, 0.0, 0.9], [0.0, 0.0, 1.0]]])  # contact is f_z > 1 N
    close(env._reward_no_fly(), [1.0, 0.0])


def test_termination_is_a_reset_that_is_not_a_time_out(env):
    env.reset_buf = torch.tensor([True, True])
    env.time_out_buf = torch.tensor([False, True])
    close(env._reward_termination(), [1.0, 0.0])
    env.reset_buf = torch.tensor([False, False])
    env.time_out_buf = torch.tensor([False, False])
    close(env._reward_termination(), [0.0, 0.0])


def test_alive_is_one_per_step(env):
    close(env._reward_alive(), [1.0, 1.0])


def test_feet_air_time_pays_the_swing_beyond_the_target_at_touchdown(env):
    # legged_gym: the foot leaves the ground from a reset, 29 steps in the air, touches down on the 30th: the
    # counter holds 30 policy steps at touchdown (it is incremented before being paid), 30 * 0.02 s = 0.6 s
    dt, target = env.dt, env.cfg.rewards.feet_air_time_target  # 0.02 s, 0.5 s
    env.feet_air_time.reset(torch.ones(N, dtype=torch.bool))
    env.commands = torch.tensor([[0.5, 0.0, 0.0, 0.0], [0.05, 0.05, 0.0, 0.0]])  # env 1: |v_xy| < 0.1, not paid
    stance = torch.tensor([[False, True]] * N)  # left foot swings, right stands
    for _ in range(29):
        env.feet_air_time.update(stance, dt)
        close(env._reward_feet_air_time(), [0.0, 0.0])
    env.feet_air_time.update(torch.ones(N, 2, dtype=torch.bool), dt)
    close(env._reward_feet_air_time(), [30 * dt - target, 0.0])
    env.feet_air_time.update(torch.ones(N, 2, dtype=torch.bool), dt)  # paid once
    close(env._reward_feet_air_time(), [0.0, 0.0])


def test_feet_air_time_counts_the_first_step_after_lift_off_as_contact(env):
    # legged_gym's two-step contact filter: lift-off after a contact, 10 steps in the air, touchdown: the first
    # air step is still filtered as contact, so the swing paid is 9 + 1 = 10 steps
    dt, target = env.dt, env.cfg.rewards.feet_air_time_target
    env.feet_air_time.reset(torch.ones(N, dtype=torch.bool))
    env.commands = torch.tensor([[0.5, 0.0, 0.0, 0.0]] * N)
    env.feet_air_time.update(torch.ones(N, 2, dtype=torch.bool), dt)
    for _ in range(10):
        env.feet_air_time.update(torch.tensor([[False, True]] * N), dt)
    env.feet_air_time.update(torch.ones(N, 2, dtype=torch.bool), dt)
    close(env._reward_feet_air_time(), [10 * dt - target] * N)


def test_gait_contact_counts_feet_whose_contact_matches_their_phase(env):
    # phase = (t / period) mod 1, the second foot half a period later; stance while phase < stance_fraction
    period, stance_fraction = env.cfg.rewards.gait_period, env.cfg.rewards.stance_fraction  # 0.8 s, 0.55
    env.episode_length_buf = torch.tensor([10, 30])  # t = 0.2 s, 0.6 s
    phases = [[(t / period) % 1.0, (t / period + 0.5) % 1.0] for t in (10 * env.dt, 30 * env.dt)]
    assert sum(phases, []) == pytest.approx([0.25, 0.75, 0.75, 0.25])
    stance = [[p < stance_fraction for p in env_phases] for env_phases in phases]  # [[T, F], [F, T]]
    contact = [[True, False], [True, True]]
    env.contact_forces = feet_forces(env, [[[0.0, 0.0, 200.0 if c else 0.0] for c in row] for row in contact])
    expected = [sum(s == c for s, c in zip(s_row, c_row)) for s_row, c_row in zip(stance, contact)]
    assert expected == [2, 1]
    close(env._reward_gait_contact(), [2.0, 1.0])


# ---------------------------------------------------------------------------------------------------------------
# feet kinematics (a forward pass of the simulator on a pose chosen here)
# ---------------------------------------------------------------------------------------------------------------
def pose(env, base_z, lin_vel, ang_vel):
    """Every joint at 0 and still, base upright at (0, 0, base_z) with world velocity ``lin_vel`` and body rates
    ``ang_vel``; bodies recomputed by a forward pass."""
    env.sim.qpos[:, 0:3] = torch.tensor([0.0, 0.0, base_z])
    env.sim.qpos[:, 3:7] = torch.tensor([1.0, 0.0, 0.0, 0.0])
    env.sim.qpos[:, env.qpos_adr] = 0.0
    env.sim.qvel[:] = 0.0
    env.sim.qvel[:, 0:3] = torch.tensor(lin_vel)
    env.sim.qvel[:, 3:6] = torch.tensor(ang_vel)
    env.sim.forward(torch.ones(N, dtype=torch.bool))
    env._update_state()


def test_feet_slip_is_the_squared_horizontal_speed_of_feet_on_the_ground(env):
    # rigid body: v_foot = v_base + w x r, r the foot's origin from the pelvis (all joints at 0, base upright)
    v, w = (0.3, -0.2, 0.1), (0.2, 0.0, 0.5)
    pose(env, 1.5, v, w)  # 1.5 m: the soles (0.96 + 0.07 m below the pelvis) clear the ground

    def speed2(foot):
        rx, ry, rz = FOOT_FROM_PELVIS[foot]
        cross = (w[1] * rz - w[2] * ry, w[2] * rx - w[0] * rz, w[0] * ry - w[1] * rx)
        return (v[0] + cross[0]) ** 2 + (v[1] + cross[1]) ** 2

    left, right = speed2("left_foot"), speed2("right_foot")
    assert [env.mjm.body(int(b)).name for b in env.feet] == ["left_foot", "right_foot"]
    env.contact_forces = feet_forces(env, [[[0.0, 0.0, 100.0], [0.0, 0.0, 0.0]],
                                           [[0.0, 0.0, 100.0], [0.0, 0.0, 100.0]]])
    close(env._reward_feet_slip(), [left, left + right])


def test_feet_swing_height_is_the_squared_clearance_error_of_feet_in_swing(env):
    # all joints at 0, base upright at 1.2 m: each foot's lowest sole point is 0.96 + 0.05 + 0.02 m below the pelvis
    target = env.cfg.rewards.swing_height_target  # 0.08 m
    pose(env, 1.2, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    clearance = 1.2 - (0.96 + 0.05 + 0.02)
    env.contact_forces = feet_forces(env, [[[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]],  # both in swing
                                           [[0.0, 0.0, 0.0], [0.0, 0.0, 100.0]]])  # the right foot stands
    close(env._reward_feet_swing_height(), [2 * (clearance - target) ** 2, (clearance - target) ** 2])


# ---------------------------------------------------------------------------------------------------------------
# the step's total (legged_gym's compute_reward)
# ---------------------------------------------------------------------------------------------------------------
def test_the_total_is_the_sum_of_terms_times_scale_times_dt_clipped_at_zero(env, monkeypatch):
    # every registered term made to return chosen values: env 0 a positive total, env 1 a negative one (clipped)
    scales = env.cfg.rewards.scales
    names = [name for name, _ in env.reward_functions]
    # env 0: the rewarded terms 1, the penalties 0.01; env 1: the rewarded terms 0, the penalties 1
    values = {name: torch.tensor([1.0, 0.0] if getattr(scales, name) > 0 else [0.01, 1.0]) for name in names}
    monkeypatch.setattr(env, "reward_functions", [(name, lambda name=name: values[name]) for name in names])
    monkeypatch.setattr(env, "diverged_buf", torch.zeros(N, dtype=torch.bool))
    expected = [sum(float(values[name][k]) * getattr(scales, name) * env.dt for name in names) for k in range(N)]
    assert expected[0] > 0 > expected[1]  # the chosen values make one total positive, one negative
    env._compute_reward()
    close(env.rew_buf, [expected[0], 0.0])  # only_positive_rewards: the negative total is clipped at zero
    monkeypatch.setattr(env, "diverged_buf", torch.tensor([True, False]))
    env._compute_reward()
    close(env.rew_buf, [0.0, 0.0])  # a diverged world earns nothing
