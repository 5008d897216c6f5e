"""Diverged worlds over several steps: a full reset (MuJoCo's whole Data, not only qpos), no re-divergence, no
curriculum move, no episode statistics, and a per-interval count. A masked reset restores every reset buffer."""

import math

import pytest
import torch
import warp as wp

from legged_gente.envs.gente_biped.gente_biped import GenteBiped
from legged_gente.envs.gente_biped.gente_biped_config import GenteBipedCfg

STEPS_AFTER = 8  # steps a reset world is watched for a new divergence


class Curriculum(GenteBipedCfg):
    """Five robots on a small flat curriculum grid (3 levels), no pushes, every robot starting on level 1."""

    class env(GenteBipedCfg.env):
        num_envs = 5

    class domain_rand(GenteBipedCfg.domain_rand):
        randomize_friction = False
        push_robots = False

    class terrain(GenteBipedCfg.terrain):
        num_rows = 3
        num_cols = 5
        border_size = 2.0
        terrain_types = ["flat"]
        terrain_proportions = [1.0]
        max_init_terrain_level = 1


@pytest.fixture
def env():
    torch.manual_seed(0)
    env = GenteBiped(Curriculum(), device="cpu")
    env._log_every = 1  # every step reports its statistics
    env.terrain_levels[:] = 1
    env.env_origins[:] = env.terrain_origins[env.terrain_levels, env.terrain_columns]
    env.reset()
    return env


def zero_step(env):
    return env.step(torch.zeros(env.num_envs, env.num_actions))


@pytest.mark.parametrize("blow_up", ["nan", "fast"])
def test_diverged_world_resets_fully_keeps_its_level_and_stays_out_of_the_statistics(env, blow_up):
    for _ in range(2):
        zero_step(env)
    w = 2
    # the world's solver warm start and applied forces as a blown-up world leaves them
    wp.to_torch(env.sim.d.qacc_warmstart)[w] = 1.0e6
    wp.to_torch(env.sim.d.qfrc_applied)[w] = 1.0e3
    if blow_up == "nan":
        env.sim.qpos[w, 7] = math.nan
    else:
        env.sim.qvel[w, 0] = 1.0e4  # m/s, far above sim.max_qvel = 1000 (and 50 m from the origin after a step)
    _, reward, done, extras = zero_step(env)
    stats = extras["episode"]
    assert done[w] and extras["time_outs"][w]  # a truncation: PPO bootstraps it, no termination penalty
    assert reward[w] == 0.0
    assert stats["diverged_resets"].item() == 1.0
    assert env.terrain_levels[w] == 1  # a 50 m "walk" (or NaN) must not promote it
    assert stats["terrain_level"].item() == pytest.approx(1.0)
    assert stats["rew_alive"].isnan()  # no episode that counts has ended: no mean
    # the reset restored MuJoCo's Data, not only qpos/qvel
    assert (wp.to_torch(env.sim.d.qacc_warmstart)[w] == 0).all()
    assert (wp.to_torch(env.sim.d.qfrc_applied)[w] == 0).all()
    assert env.sim.time[w] == 0.0 and env.episode_length_buf[w] == 0
    spawn = env.env_origins[w] + env.init_base_state[:3]
    assert torch.allclose(env.sim.qpos[w, :3], spawn)
    # fresh kinematics at the first step of the episode: the base body sits where qpos puts it
    assert torch.allclose(env.sim.xpos[w, env.base], spawn, atol=1e-5)
    for _ in range(STEPS_AFTER):
        _, _, done, extras = zero_step(env)
        assert extras["episode"]["diverged_resets"].item() == 0.0  # per interval, not a running total
        assert not done[w]  # and the world does not diverge again
        assert torch.isfinite(env.sim.qpos[w]).all()
    assert env.terrain_levels[w] == 1


def test_finished_episodes_still_move_levels_and_count(env):
    """The exclusion is for diverged worlds only: a robot that times out after walking a tile moves up."""
    env.sim.qpos[0, 0] += 0.6 * env.cfg.terrain.terrain_length  # m, more than half a tile from its origin
    env.episode_length_buf[0] = env.max_episode_length - 1
    _, _, done, extras = zero_step(env)
    assert done[0] and env.terrain_levels[0] == 2
    assert extras["episode"]["diverged_resets"].item() == 0.0
    assert extras["episode"]["rew_alive"].item() > 0.0


def test_overflowing_constraint_rows_count_as_diverged_but_exactly_full_does_not(env):
    nefc = env.sim.nefc
    nefc[:] = 0
    nefc[1] = env.cfg.sim.njmax  # every row fits
    nefc[3] = env.cfg.sim.njmax + 1  # MuJoCo-Warp counts the rows it wanted: one was dropped
    assert env._diverged().tolist() == [False, False, False, True, False]


def test_masked_reset_restores_every_reset_buffer(env):
    for _ in range(3):
        zero_step(env)
    mask = torch.tensor([True, False, True, False, False])
    d = env.sim.d
    env.sim.qpos[:, 7:] += 0.3
    env.sim.qvel[:] = 0.5
    env.sim.ctrl[:] = 0.7
    data_fields = {name: wp.to_torch(getattr(d, name)) for name in ("qacc_warmstart", "qfrc_applied", "xfrc_applied")}
    for field in data_fields.values():
        field.fill_(2.0)
    env.sim.time[:] = 1.5
    env.actions[:] = 1.0
    env.last_actions[:] = 1.0
    env.last_dof_vel[:] = 1.0
    env.feet_air_time.air_time[:] = 0.4
    env.feet_air_time.last_contact[:] = True
    env.episode_sums[:] = 3.0
    env.episode_length_buf[:] = 17
    before_q, before_v = env.sim.qpos.clone(), env.sim.qvel.clone()
    env._reset_envs(mask)
    m, k = mask, ~mask
    for name, field in data_fields.items():
        assert (field[m] == 0).all(), name
        assert (field[k] == 2.0).all(), name
    assert (env.sim.time[m] == 0).all() and (env.sim.time[k] == 1.5).all()
    assert torch.allclose(env.sim.ctrl[m], env.default_dof_pos.expand(2, -1))  # a zero action's PD targets
    assert (env.sim.ctrl[k] == 0.7).all()
    for buf in (env.actions, env.last_actions, env.last_dof_vel, env.feet_air_time.air_time, env.episode_sums):
        assert (buf[m] == 0).all() and (buf[k] != 0).all()
    assert not env.feet_air_time.last_contact[m].any() and env.feet_air_time.last_contact[k].all()
    assert (env.episode_length_buf[m] == 0).all() and (env.episode_length_buf[k] == 17).all()
    assert torch.equal(env.sim.qpos[k], before_q[k]) and torch.equal(env.sim.qvel[k], before_v[k])
    assert not torch.equal(env.sim.qpos[m], before_q[m])


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_a_world_given_non_finite_actions_is_diverged_and_the_others_are_not_touched(env, bad):
    """A NaN or inf action must not drive the joints (a NaN position target once gave every joint its negative
    torque limit, with nothing flagged): the world holds its default pose for the step and is reset as diverged."""
    for _ in range(2):
        zero_step(env)
    actions = torch.zeros(env.num_envs, env.num_actions)
    actions[1, 0] = bad
    _, reward, done, extras = env.step(actions)
    assert done.tolist() == [False, True, False, False, False]
    assert extras["time_outs"][1] and reward[1] == 0.0
    assert extras["episode"]["diverged_resets"].item() == 1.0
    assert torch.isfinite(env.torques).all() and torch.isfinite(env.actions).all()
    assert (env.actions[1] == 0).all()
    assert env.terrain_levels[1] == 1
    _, _, done, extras = zero_step(env)
    assert not done.any() and extras["episode"]["diverged_resets"].item() == 0.0
