"""LeggedRobot's step logic checked by hand on tiny CPU runs: episode length in steps, command resampling, pushes,
terminations against time-outs, the order of rewards, resets and observations, action scaling and PD torques,
observation noise, the height scan's frame and clip, and the terrain curriculum's thresholds. Every expected
value is computed here from the documented rule (legged_gym's where the env follows it), never read back."""

import math
from unittest.mock import patch

import pytest
import torch

from legged_gente.envs.gente_biped.gente_biped import GenteBiped
from legged_gente.envs.gente_biped.gente_biped_config import GenteBipedCfg, GenteBipedFlatCfg

DT = 0.005 * 4  # s: the biped's physics step times its decimation


def flat_cfg(num_envs: int = 4):
    cfg = GenteBipedFlatCfg()
    cfg.env.num_envs = num_envs
    cfg.domain_rand.push_robots = False
    return cfg


def zeros(env):
    return torch.zeros(env.num_envs, env.num_actions)


# ---------------------------------------------------------------------------------------------------------------
# episode length, command resampling, pushes
# ---------------------------------------------------------------------------------------------------------------
def test_an_episode_of_0_14_s_lasts_7_steps_not_8():
    # 0.14 s / 0.02 s is 7.000000000000001 in binary floating point: the episode is 7 policy steps (0.14 s), and
    # the 7th step is its time-out
    cfg = flat_cfg(2)
    cfg.env.episode_length_s = 0.14
    env = GenteBiped(cfg, device="cpu")
    assert env.max_episode_length == 7
    for _ in range(6):
        _, _, done, extras = env.step(zeros(env))
        assert not done.any()
    _, _, done, extras = env.step(zeros(env))
    assert done.all() and extras["time_outs"].all()


def test_a_resampling_time_of_half_a_policy_step_resamples_every_step():
    # the config check accepts half a step (less "would round to none"): it counts as one step, not zero
    cfg = flat_cfg(3)
    cfg.commands.resampling_time = DT / 2
    cfg.commands.heading_command = False
    cfg.commands.still_fraction = 0.0
    cfg.commands.ranges.lin_vel_x = [0.5, 1.0]  # never a small command: every draw is a new value
    env = GenteBiped(cfg, device="cpu")
    for _ in range(3):
        before = env.commands.clone()
        env.step(zeros(env))
        assert (env.commands[:, :3] != before[:, :3]).all(dim=1).all()


def test_commands_are_resampled_every_resampling_time_within_their_ranges():
    cfg = flat_cfg(4)
    cfg.commands.resampling_time = 3 * DT  # every 3rd step
    cfg.commands.heading_command = False  # the yaw rate is the drawn one
    cfg.commands.still_fraction = 0.0
    ranges = cfg.commands.ranges
    ranges.lin_vel_x, ranges.lin_vel_y, ranges.ang_vel_yaw = [0.5, 1.0], [-0.1, 0.1], [-0.3, 0.3]
    env = GenteBiped(cfg, device="cpu")
    changed_at = []
    for step in range(1, 8):
        before = env.commands.clone()
        _, _, done, _ = env.step(zeros(env))
        assert not done.any()
        changed = (env.commands[:, :3] != before[:, :3]).any(dim=1)
        assert changed.all() or not changed.any()  # every robot's episode started together
        if changed.all():
            changed_at.append(step)
        c = env.commands
        assert ((c[:, 0] >= 0.5) & (c[:, 0] <= 1.0)).all() and (c[:, 1].abs() <= 0.1).all()
        assert (c[:, 2].abs() <= 0.3).all()
    assert changed_at == [3, 6]
    # legged_gym: a command slower than 0.2 m/s is zeroed (the yaw rate is kept)
    env.set_param("commands.ranges.lin_vel_x", [0.0, 0.14])
    env.set_param("commands.ranges.lin_vel_y", [0.0, 0.14])  # |v| <= 0.14 * sqrt(2) = 0.198 < 0.2
    env._resample_commands(torch.ones(4, dtype=torch.bool))
    assert (env.commands[:, :2] == 0).all() and (env.commands[:, 2] != 0).all()


def test_pushes_come_every_push_interval():
    cfg = flat_cfg(2)
    cfg.domain_rand.push_robots = True
    cfg.domain_rand.push_interval_s = 2 * DT
    env = GenteBiped(cfg, device="cpu")
    with patch.object(env, "_push_robots", wraps=env._push_robots) as push:
        pushed_at = []
        for step in range(1, 6):
            calls = push.call_count
            env.step(zeros(env))
            if push.call_count > calls:
                pushed_at.append(step)
    assert pushed_at == [2, 4]


# ---------------------------------------------------------------------------------------------------------------
# terminations, time-outs and the order of rewards, resets and observations
# ---------------------------------------------------------------------------------------------------------------
def test_a_fall_is_a_termination_a_time_out_is_not_and_rewards_see_the_state_before_the_reset():
    cfg = flat_cfg(4)
    cfg.noise.add_noise = False
    env = GenteBiped(cfg, device="cpu")
    env._log_every = 1
    for _ in range(3):
        env.step(zeros(env))
    # robot 0 rolled 90 degrees in the air (tilt > terminate_tilt = 1 rad); robot 1 at its last step
    env.sim.qpos[0, 3:7] = torch.tensor([math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0])
    env.episode_length_buf[1] = env.max_episode_length - 1
    actions = torch.full((4, env.num_actions), 0.2)
    _, _, done, extras = env.step(actions)
    assert done.tolist() == [True, True, False, False]
    assert extras["time_outs"].tolist() == [False, True, False, False]  # PPO bootstraps robot 1 only
    # the orientation term of the step that ended robot 0's episode was computed from its rolled base:
    # |g_xy|^2 = 1, scaled by -1.0 * dt; robot 1 stands upright (|g_xy|^2 ~ 0). legged_gym's statistic: the
    # finished episodes' mean sum over the episode length in seconds
    expected = (cfg.rewards.scales.orientation * DT * 1.0 + 0.0) / 2 / cfg.env.episode_length_s
    assert extras["episode"]["rew_orientation"].item() == pytest.approx(expected, rel=0.03)
    # the observations are the new episodes' (after the reset): upright, no previous action
    names = env.observation_names["policy"]
    critic = env.get_observations()["critic"]
    gravity = critic[:, [names.index(f"projected_gravity[{i}]") for i in range(3)]]
    assert torch.allclose(gravity[:2], torch.tensor([0.0, 0.0, -1.0]).expand(2, 3), atol=1e-5)
    acts = critic[:, [names.index(f"actions[{i}]") for i in range(env.num_actions)]]
    assert (acts[:2] == 0).all() and torch.allclose(acts[2:], torch.full((2, env.num_actions), 0.2))
    assert env.episode_length_buf[:2].tolist() == [0, 0] and env.episode_length_buf[2:].tolist() == [4, 4]


# ---------------------------------------------------------------------------------------------------------------
# actions, PD torques, observation noise
# ---------------------------------------------------------------------------------------------------------------
# the biped's gains (gente_biped_config.py, by joint-name substring) and torque limits (its MJCF's actuatorfrcrange)
KP = {"hip_yaw": 150.0, "hip_roll": 150.0, "hip_pitch": 150.0, "knee": 200.0, "ankle": 80.0}
KD = {"hip_yaw": 5.0, "hip_roll": 5.0, "hip_pitch": 5.0, "knee": 5.0, "ankle": 3.0}
LIMIT = {"hip_yaw": 120.0, "hip_roll": 150.0, "hip_pitch": 150.0, "knee": 250.0, "ankle": 50.0}


def per_joint(env, table):
    return torch.tensor([table[name.split("_", 1)[1]] for name in env.layout.joint_names])


def test_actions_are_clipped_scaled_and_turned_into_limited_pd_torques():
    torch.manual_seed(0)
    cfg = flat_cfg(2)
    cfg.normalization.clip_actions = 10.0
    env = GenteBiped(cfg, device="cpu")
    actions = torch.tensor([[12.0, -12.0] * 5, [1.0, -2.0] * 5])  # robot 0 clipped at +-10, robot 1 not
    env.step(actions)
    target = env.sim.ctrl - env.default_dof_pos
    assert torch.allclose(target[0], torch.tensor([2.5, -2.5] * 5))  # 0.25 rad per unit action
    assert torch.allclose(target[1], torch.tensor([0.25, -0.5] * 5))
    # tau = kp (target - q) - kd qdot, clamped to the joint's torque limit, at the state the forward sees. Robot
    # 0's joints held still: 2.5 rad past the default is beyond every joint's range, so each of its torques
    # saturates (e.g. the knee, range [0, 2] rad: 200 N*m/rad * (2.5 - 0.55) rad > 250 N*m)
    env.sim.qvel[0, env.dof_adr] = 0.0
    env.sim.forward(torch.ones(2, dtype=torch.bool))
    q, qd = env.sim.qpos[:, env.qpos_adr], env.sim.qvel[:, env.dof_adr]
    kp, kd, limit = per_joint(env, KP), per_joint(env, KD), per_joint(env, LIMIT)
    tau = kp * (env.sim.ctrl - q) - kd * qd
    expected = torch.maximum(torch.minimum(tau, limit), -limit)
    assert (tau[0].abs() > limit).all() and (tau[1].abs() < limit).all()  # both cases are checked
    assert torch.allclose(env.sim.actuator_force, expected, atol=1e-2)


def test_observation_noise_is_uniform_in_plus_minus_noise_times_scale_times_level():
    cfg = flat_cfg(8)
    cfg.noise.noise_level = 2.0
    env = GenteBiped(cfg, device="cpu")
    env.step(zeros(env))
    names = env.observation_names["policy"]
    # legged_gym: noise_vec = noise * noise_level * obs_scale; obs += (2 U(0, 1) - 1) * noise_vec
    half_width = {"base_lin_vel": 0.1 * 2.0 * 2.0, "base_ang_vel": 0.2 * 2.0 * 0.25, "projected_gravity": 0.05 * 2.0,
                  "commands": 0.0, "dof_pos": 0.01 * 2.0, "dof_vel": 1.5 * 2.0 * 0.05, "actions": 0.0,
                  "gait_clock": 0.0}
    expected = torch.tensor([half_width[n.split("[")[0]] for n in names])
    width = len(names)
    noise = []
    for _ in range(50):
        env._compute_observations()
        noise.append(env.policy_obs - env.critic_obs[:, :width])  # the critic's copy is the noise-free one
    noise = torch.stack(noise).flatten(0, 1)
    assert (noise.abs() <= expected + 1e-6).all()
    assert torch.allclose(noise.abs().amax(0), expected, rtol=0.05, atol=1e-7)  # 400 draws reach the bounds
    assert torch.allclose(noise.mean(0), torch.zeros(width), atol=0.1 * expected.max())


def test_friction_and_base_mass_are_drawn_once_per_world_not_per_reset():
    # legged_gym draws them when the worlds are created; cfg.domain_rand says U(low, high) per world
    cfg = flat_cfg(4)
    cfg.domain_rand.friction_range = [0.5, 1.25]
    cfg.domain_rand.randomize_base_mass, cfg.domain_rand.added_mass_range = True, [-1.0, 3.0]
    env = GenteBiped(cfg, device="cpu")
    friction, mass = env.sim.geom_friction[:, :, 0].clone(), env.sim.body_mass[:, env.base].clone()
    assert ((friction >= 0.5) & (friction <= 1.25)).all() and len(set(friction[:, 0].tolist())) == 4
    mass0 = float(env.mjm.body_mass[env.base])
    assert (mass - mass0 >= -1.0 - 1e-4).all() and (mass - mass0 <= 3.0 + 1e-4).all()
    env.episode_length_buf[:] = env.max_episode_length - 1
    _, _, done, _ = env.step(zeros(env))
    assert done.all()  # every world reset...
    assert torch.equal(env.sim.geom_friction[:, :, 0], friction)  # ...and kept its draws
    assert torch.equal(env.sim.body_mass[:, env.base], mass)


# ---------------------------------------------------------------------------------------------------------------
# on a heightfield: the height scan and the terrain curriculum
# ---------------------------------------------------------------------------------------------------------------
class ThreeLevels(GenteBipedCfg):
    """Three 8 m tiles along x (levels 0, 1, 2) of flat ground."""

    class env(GenteBipedCfg.env):
        num_envs = 5

    class terrain(GenteBipedCfg.terrain):
        num_rows = 3
        num_cols = 1
        border_size = 1.0
        terrain_types = ["flat"]
        terrain_proportions = [1.0]
        solved_top_level = "stay"

    class domain_rand(GenteBipedCfg.domain_rand):
        push_robots = False


@pytest.fixture(scope="module")
def hf_env():
    return GenteBiped(ThreeLevels(), device="cpu")


def test_the_height_scan_samples_the_ground_in_the_bases_yaw_frame_then_clips_and_scales(hf_env):
    env = hf_env
    res, (ox, oy) = env.terrain.resolution, env.terrain.origin_xy
    nx, ny = env.height_samples.shape
    a, b, c = 1.5, -0.4, 0.1  # ground z = a x + b y + c (bilinear interpolation is exact on a plane)
    xs = ox + res * torch.arange(nx, dtype=torch.float32)
    ys = oy + res * torch.arange(ny, dtype=torch.float32)
    saved = env.height_samples.clone()
    env.height_samples.copy_(a * xs[:, None] + b * ys[None, :] + c)
    try:
        yaw, roll = 0.5, 0.3
        bx, by, bz = 4.0, 3.0, 5.9  # the scan spans about +-1.7 m around 0 here: some of it clipped
        # yaw about world z after a roll about the base x: the scan grid turns by the yaw only
        q_yaw = torch.tensor([math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])
        cr, sr = math.cos(roll / 2), math.sin(roll / 2)
        w, x, y, z = q_yaw.tolist()
        quat = torch.tensor([w * cr - x * sr, w * sr + x * cr, y * cr + z * sr, z * cr - y * sr])
        env.sim.qpos[0, 0:3] = torch.tensor([bx, by, bz])
        env.sim.qpos[0, 3:7] = quat
        env._update_state()
        target = ThreeLevels.rewards.base_height_target
        expected = []
        for dx in ThreeLevels.terrain.measured_points_x:  # x-major, as the observation's names are numbered
            for dy in ThreeLevels.terrain.measured_points_y:
                wx = bx + math.cos(yaw) * dx - math.sin(yaw) * dy
                wy = by + math.sin(yaw) * dx + math.cos(yaw) * dy
                expected.append(bz - target - (a * wx + b * wy + c))
        expected = torch.tensor(expected)
        assert torch.allclose(env._obs_height_scan()[0], expected, atol=1e-4)
        # the observation: clipped to [-1, 1] m, then scaled by 5
        env._compute_observations()
        names = env.observation_names["policy"]
        columns = [i for i, n in enumerate(names) if n.startswith("height_scan[")]
        assert (expected > 1).any() and (expected < -1).any() and (expected.abs() < 1).any()
        assert torch.allclose(env.critic_obs[0, columns], 5.0 * expected.clamp(-1.0, 1.0), atol=5e-4)
    finally:
        env.height_samples.copy_(saved)
        env.reset()


def test_the_curriculum_promotes_past_half_a_tile_demotes_under_half_the_commanded_distance(hf_env):
    env = hf_env
    # tiles of 8 m: up beyond 4 m from the level's origin. Commanded 0.3 m/s for the 20 s episode: 6 m, down
    # under 3 m. Robot 3 walked far but its world diverged; robot 4 solved the top level (solved_top_level stay)
    env.terrain_levels[:] = torch.tensor([1, 1, 1, 1, 2])
    env.env_origins[:] = env.terrain_origins[env.terrain_levels, env.terrain_columns]
    env.commands[:, :2] = torch.tensor([0.18, 0.24])  # |v| = 0.3 m/s, in any direction
    walked = torch.tensor([4.1, 3.9, 2.9, 4.1, 4.1])
    direction = torch.tensor([-0.8, 0.6])  # the distance is the norm in the plane, whatever the direction
    env.sim.qpos[:, 0:2] = env.env_origins[:, :2] + walked[:, None] * direction
    env._update_state()
    done = torch.ones(5, dtype=torch.bool)
    diverged = torch.tensor([False, False, False, True, False])
    count, diverged_before = env._stat_count.item(), env.diverged_resets.item()
    env._log_and_update_curriculum(done, diverged)
    assert env.terrain_levels.tolist() == [2, 1, 0, 1, 2]
    assert torch.equal(env.env_origins, env.terrain_origins[env.terrain_levels, env.terrain_columns])
    assert env._stat_count.item() - count == 4  # the diverged episode is not counted either
    assert env.diverged_resets.item() - diverged_before == 1
    # a robot whose episode has not ended keeps its level however far it walked
    env._log_and_update_curriculum(torch.zeros(5, dtype=torch.bool), torch.zeros(5, dtype=torch.bool))
    assert env.terrain_levels.tolist() == [2, 1, 0, 1, 2]
    env.reset()


def test_a_first_episode_shortened_by_a_random_start_is_held_to_the_distance_of_its_own_time(hf_env):
    """rsl-rl starts training (and a --resume) with random episode lengths, so each robot's first episode is cut
    short. Robots 0-2 start at step 900 of the 1000-step (20 s) episode: 2 s at 0.3 m/s is 0.6 m, down under
    0.3 m: robot 0 walked 0.4 m and keeps its level, robot 1 walked 0.2 m and goes down (legged_gym's rule held
    both to the whole episode's 6 m: both down). Robot 3 started at step 0: down under 3 m, as before. Once reset,
    robot 0's next episode is whole again: 0.4 m is then too little."""
    env = hf_env
    assert env.max_episode_length == 1000 and env.max_episode_length_s == pytest.approx(20.0)
    start = torch.tensor([900, 900, 900, 0, 0])
    env.episode_length_buf = start  # as rsl-rl's OnPolicyRunner.learn(init_at_random_ep_len=True) assigns it
    env.episode_length_buf[:] = torch.where(start > 0, 1000, 999)  # robots 0-2 time out now; 3 and 4 walked 999
    env.terrain_levels[:] = torch.tensor([1, 1, 1, 1, 1])
    env.env_origins[:] = env.terrain_origins[env.terrain_levels, env.terrain_columns]
    env.commands[:, :2] = torch.tensor([0.18, 0.24])  # |v| = 0.3 m/s
    walked = torch.tensor([0.4, 0.2, 3.1, 2.9, 3.1])
    env.sim.qpos[:, 0:2] = env.env_origins[:, :2] + walked[:, None] * torch.tensor([0.6, 0.8])
    env._update_state()
    env._log_and_update_curriculum(torch.ones(5, dtype=torch.bool), torch.zeros(5, dtype=torch.bool))
    assert env.terrain_levels.tolist() == [1, 0, 1, 0, 1]
    env._reset_envs(torch.tensor([True, False, False, False, False]))
    env.episode_length_buf[0] = 1000  # its whole next episode walked
    env.sim.qpos[0, 0:2] = env.env_origins[0, :2] + 0.4 * torch.tensor([0.6, 0.8])
    env._update_state()
    env._log_and_update_curriculum(torch.tensor([True, False, False, False, False]), torch.zeros(5, dtype=torch.bool))
    assert env.terrain_levels.tolist() == [0, 0, 1, 0, 1]
    env.reset()


# ---------------------------------------------------------------------------------------------------------------
# episode statistics, the curriculum restored
# ---------------------------------------------------------------------------------------------------------------
def test_reward_means_are_undefined_until_an_episode_ends_then_per_episode():
    """Until an episode ends there is no mean per episode to report: NaN, not 0 (which a plot reads as a value).
    Then robots 0 and 1 time out after 6 steps each: rew_alive = 2 x 6 x alive x dt / (2 episodes) / episode_s."""
    cfg = flat_cfg()
    env = GenteBiped(cfg, device="cpu")
    env._log_every = 1
    for _ in range(5):
        _, _, done, extras = env.step(zeros(env))
        assert not done.any() and math.isnan(extras["episode"]["rew_alive"].item())
        assert extras["episode"]["terrain_level"].item() == 0.0  # defined every time
    env.episode_length_buf[:2] = env.max_episode_length - 1
    _, _, done, extras = env.step(zeros(env))
    assert done[:2].all() and not done[2:].any()
    per_episode = 6 * cfg.rewards.scales.alive * DT
    assert extras["episode"]["rew_alive"].item() == pytest.approx(per_episode / env.max_episode_length_s)


def test_the_curriculum_restores_after_steps_taken_in_inference_mode(hf_env):
    """rsl-rl collects its rollouts under torch.inference_mode(); restoring a curriculum afterwards (outside it)
    resets every robot and so writes the env's buffers: none of them may have become an inference tensor."""
    env = hf_env
    with torch.inference_mode():
        env.step(zeros(env))
    state = {"terrain_levels": torch.full((env.num_envs,), 1, dtype=torch.long)}
    assert env.load_curriculum_state(state) == "terrain curriculum restored: mean level 1.00"
    assert env.terrain_levels.eq(1).all()
