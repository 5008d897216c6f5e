"""LeggedRobot on the CPU: shapes, masked resets, reward terms, config subclassing."""

import pytest
import torch

from legged_gente.envs.gente_biped.gente_biped import GenteBiped
from legged_gente.envs.gente_biped.gente_biped_config import GenteBipedFlatCfg
from legged_gente.envs.task_registry import task_registry

NUM_ENVS = 4


def small_cfg(cfg_class=GenteBipedFlatCfg):
    cfg = cfg_class()
    cfg.env.num_envs = NUM_ENVS
    return cfg


@pytest.fixture(scope="module")
def env():
    return GenteBiped(small_cfg(), device="cpu")


def test_shapes(env):
    obs = env.get_observations()
    assert env.num_actions == 10
    # 3 + 3 + 3 + 3 commands + 3 * 10 joints/actions + 2 gait clock
    assert obs["policy"].shape == (NUM_ENVS, 44)
    assert obs["critic"].shape[0] == NUM_ENVS and obs["critic"].shape[1] > 44
    obs, rew, done, extras = env.step(torch.zeros(NUM_ENVS, env.num_actions))
    assert rew.shape == (NUM_ENVS,) and done.shape == (NUM_ENVS,) and done.dtype == torch.bool
    assert extras["time_outs"].shape == (NUM_ENVS,)
    assert torch.isfinite(obs["policy"]).all() and torch.isfinite(obs["critic"]).all()


def test_joint_order_from_names(env):
    names = env.layout.joint_names
    assert names[:5] == ["left_hip_yaw", "left_hip_roll", "left_hip_pitch", "left_knee", "left_ankle"]
    knee = names.index("left_knee")
    assert env.default_dof_pos[0, knee].item() == pytest.approx(0.55)
    assert [env.mjm.body(int(b)).name for b in env.feet] == ["left_foot", "right_foot"]


def test_masked_reset_only_touches_masked_worlds(env):
    for _ in range(3):
        env.step(0.3 * torch.randn(NUM_ENVS, env.num_actions))
    before_q = env.sim.qpos.clone()
    mask = torch.tensor([True, False, True, False])
    env._reset_envs(mask)
    after_q = env.sim.qpos
    assert torch.equal(after_q[~mask], before_q[~mask])
    assert not torch.equal(after_q[mask], before_q[mask])
    assert (env.episode_length_buf[mask] == 0).all()
    spawn = env.env_origins[mask] + env.init_base_state[:3]
    assert torch.allclose(after_q[mask, :3], spawn)


def test_episode_timeout_sets_time_outs(env):
    env.episode_length_buf[:] = env.max_episode_length - 1
    _, _, done, extras = env.step(torch.zeros(NUM_ENVS, env.num_actions))
    assert done.all() and extras["time_outs"].all()
    assert (env.episode_length_buf == 0).all()


def test_every_reward_term_is_finite():
    cfg = small_cfg()
    names = [n[len("_reward_"):] for n in dir(GenteBiped) if n.startswith("_reward_")]
    for name in names:
        setattr(cfg.rewards.scales, name, 1.0)
    env = GenteBiped(cfg, device="cpu")
    assert set(env.reward_scales) == set(names)
    for _ in range(3):
        env.step(torch.randn(NUM_ENVS, env.num_actions))
        for name, fn in env.reward_functions:
            value = fn()
            assert value.shape == (NUM_ENVS,), name
            assert torch.isfinite(value).all(), name


def test_unknown_reward_term_is_a_clear_error():
    cfg = small_cfg()
    cfg.rewards.scales.dance = 1.0
    with pytest.raises(ValueError, match="_reward_dance"):
        GenteBiped(cfg, device="cpu")


def test_config_subclass_changes_the_robot():
    class HeavyHeadBiped(GenteBipedFlatCfg):
        class init_state(GenteBipedFlatCfg.init_state):
            pos = [0.0, 0.0, 1.1]

        class control(GenteBipedFlatCfg.control):
            stiffness = {"hip": 100.0, "knee": 120.0, "ankle": 30.0}

    env = GenteBiped(small_cfg(HeavyHeadBiped), device="cpu")
    knee = env.mjm.actuator("left_knee").id
    assert env.mjm.actuator_gainprm[knee, 0] == pytest.approx(120.0)
    assert env.mjm.actuator_biasprm[knee, 1] == pytest.approx(-120.0)
    assert env.sim.qpos[0, 2].item() == pytest.approx(1.1, abs=1e-5)


def test_bad_names_give_clear_errors():
    cfg = small_cfg()
    cfg.asset.foot_bodies = ["*_flipper"]
    with pytest.raises(ValueError, match="_flipper.*matches nothing"):
        GenteBiped(cfg, device="cpu")
    cfg = small_cfg()
    cfg.control.stiffness = {"hip": 100.0}
    with pytest.raises(ValueError, match=r"no stiffness .* given for joint 'left_knee'"):
        GenteBiped(cfg, device="cpu")


def test_task_registry_knows_the_biped():
    env_cfg, train_cfg = task_registry.get_cfgs("gente_biped")
    assert env_cfg.asset.file.endswith("gente_biped.xml")
    with pytest.raises(KeyError, match="registered tasks"):
        task_registry.get_cfgs("no_such_task")


def test_episode_statistics_are_per_finished_episode_means():
    cfg = small_cfg()
    cfg.domain_rand.push_robots = False
    env = GenteBiped(cfg, device="cpu")
    env._log_every = 1
    for _ in range(5):
        _, _, done, extras = env.step(torch.zeros(NUM_ENVS, env.num_actions))
        assert not done.any()
        assert extras["episode"]["rew_alive"].isnan()  # no episode ended yet: no mean
    env.episode_length_buf[:2] = env.max_episode_length - 1  # robots 0 and 1 time out on the next step
    _, _, done, extras = env.step(torch.zeros(NUM_ENVS, env.num_actions))
    assert done[:2].all() and not done[2:].any()
    alive_per_step = cfg.rewards.scales.alive * env.dt
    assert extras["episode"]["rew_alive"].item() == pytest.approx(6 * alive_per_step / env.max_episode_length_s)
    assert extras["episode"]["terrain_level"].item() == 0.0


def test_domain_randomisation_writes_per_world_model_fields():
    cfg = small_cfg()
    cfg.domain_rand.randomize_friction = True
    cfg.domain_rand.friction_range = [0.3, 0.4]
    cfg.domain_rand.randomize_base_mass = True
    cfg.domain_rand.added_mass_range = [1.0, 2.0]
    env = GenteBiped(cfg, device="cpu")
    friction = env.sim.geom_friction[:, :, 0]
    assert ((friction >= 0.3) & (friction <= 0.4)).all()
    assert torch.equal(friction[:, 0:1].expand_as(friction), friction)  # one coefficient per world
    assert len(set(friction[:, 0].tolist())) == NUM_ENVS
    mass0 = float(env.mjm.body_mass[env.base])
    added = env.sim.body_mass[:, env.base] - mass0
    assert torch.allclose(added, env.added_base_mass[:, 0], atol=1e-5)
    assert ((added >= 1.0) & (added <= 2.0)).all()
    ratio = env.sim.body_inertia[:, env.base] / torch.as_tensor(env.mjm.body_inertia[env.base], dtype=torch.float32)
    assert torch.allclose(ratio, (env.sim.body_mass[:, env.base] / mass0)[:, None].expand_as(ratio), rtol=1e-5)
    # the critic sees the randomised values
    critic = env.get_observations()["critic"]
    assert torch.allclose(critic[:, 44:46], torch.cat([env.friction_coeffs, env.added_base_mass], dim=1))


def test_heading_commands_turn_towards_the_heading(env):
    from legged_gente.utils.torch_math import yaw_of

    yaw = yaw_of(env.base_quat)
    env.commands[:, 3] = yaw + torch.tensor([0.5, -0.5, 3.0, 0.0])
    env.standing_still[:] = False
    env._update_heading_commands()
    stiffness, (low, high) = env.cfg.commands.heading_stiffness, env.cfg.commands.ranges.ang_vel_yaw
    expected = torch.tensor([0.5, -0.5, 3.0, 0.0]) * stiffness
    assert torch.allclose(env.commands[:, 2], expected.clamp(low, high), atol=1e-5)


def test_reset_turns_headings_into_yaw_rates(env):
    """The first observation after reset() (the one rsl-rl's runner starts from) carries the heading controller's
    yaw rate, as every step's does, not the raw yaw-rate sample."""
    from legged_gente.utils.torch_math import wrap_to_pi, yaw_of

    torch.manual_seed(3)
    env.reset()
    stiffness, (low, high) = env.cfg.commands.heading_stiffness, env.cfg.commands.ranges.ang_vel_yaw
    expected = (stiffness * wrap_to_pi(env.commands[:, 3] - yaw_of(env.base_quat))).clamp(low, high)
    expected = torch.where(env.standing_still, 0.0, expected)
    assert torch.allclose(env.commands[:, 2], expected, atol=1e-5)


def test_pushes_change_base_velocity_only_in_the_plane(env):
    before = env.sim.qvel.clone()
    env._push_robots()
    delta = env.sim.qvel - before
    assert (delta[:, :2].abs() > 0).any(dim=1).all()
    assert delta[:, :2].abs().max() <= env.cfg.domain_rand.max_push_vel_xy
    assert torch.equal(delta[:, 2:], torch.zeros_like(delta[:, 2:]))
