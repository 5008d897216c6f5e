"""gente_quadruped on the CPU: builds from its config, shapes, finite rewards, stable steps, terrain forces."""

import warnings

import numpy as np
import pytest
import torch

from legged_gente.envs.base.legged_robot import LeggedRobot
from legged_gente.envs.gente_quadruped.gente_quadruped_config import GenteQuadrupedCfg, GenteQuadrupedFlatCfg
from legged_gente.envs.task_registry import task_registry
from legged_gente.terrain.terrain import Terrain

NUM_ENVS = 4
LEGS = ("FL", "FR", "RL", "RR")


@pytest.fixture(scope="module")
def env():
    """The flat task with every reward term switched on, so each one is computed."""
    cfg = GenteQuadrupedFlatCfg()
    cfg.env.num_envs = NUM_ENVS
    cfg.domain_rand.push_robots = False
    for name in dir(LeggedRobot):
        if name.startswith("_reward_"):
            setattr(cfg.rewards.scales, name[len("_reward_"):], 1.0)
    return LeggedRobot(cfg, device="cpu")


def test_registered_tasks():
    for name, plane in (("gente_quadruped", False), ("gente_quadruped_flat", True)):
        env_cfg, train_cfg = task_registry.get_cfgs(name)
        assert env_cfg.asset.file.endswith("gente_quadruped.xml")
        assert (env_cfg.terrain.mesh_type == "plane") == plane
        assert train_cfg.runner.experiment_name == name


def test_shapes_and_names(env):
    assert env.num_actions == 12
    assert env.layout.joint_names[:3] == ["FL_hip", "FL_thigh", "FL_calf"]
    assert env.default_dof_pos[0, :3].tolist() == pytest.approx([0.0, 0.8, -1.6])
    assert [env.mjm.body(int(b)).name for b in env.feet] == [f"{leg}_foot" for leg in LEGS]
    assert sorted(env.mjm.body(int(b)).name for b in env.penalized_bodies) == sorted(
        f"{leg}_{part}" for leg in LEGS for part in ("thigh", "calf"))
    assert [env.mjm.body(int(b)).name for b in env.terminate_bodies] == ["trunk"]
    # the config's gains replace the file's kp 40 / kv 1 placeholders
    calf = env.mjm.actuator("RR_calf").id
    assert env.mjm.actuator_gainprm[calf, 0] == pytest.approx(30.0)
    assert env.mjm.actuator_biasprm[calf, 2] == pytest.approx(-0.8)
    assert env.torque_limits.tolist() == [25.0, 25.0, 35.0] * 4
    obs = env.get_observations()
    # lin vel, ang vel, gravity, commands (3 each) + 3 * 12 joints/actions; no height scan on a plane
    assert obs["policy"].shape == (NUM_ENVS, 48)
    assert obs["critic"].shape[0] == NUM_ENVS and obs["critic"].shape[1] > 48


def test_every_reward_is_finite_and_steps_stay_bounded(env):
    assert set(env.reward_scales) == {n[len("_reward_"):] for n in dir(LeggedRobot) if n.startswith("_reward_")}
    for _ in range(10):
        obs, rew, done, _ = env.step(0.5 * torch.randn(NUM_ENVS, env.num_actions))
        for name, fn in env.reward_functions:
            value = fn()
            assert value.shape == (NUM_ENVS,) and torch.isfinite(value).all(), name
        assert torch.isfinite(rew).all() and torch.isfinite(obs["policy"]).all()
    assert env.diverged_resets.item() == 0
    # standing on its feet at about the stand height, not flung away or through the floor
    assert ((env.base_pos[:, 2] > 0.15) & (env.base_pos[:, 2] < 0.45)).all()
    assert env.sim.qvel.abs().max().item() < 50.0


def test_standing_feet_carry_the_robot_and_no_calf_touches():
    """The calves' contacts are watched (penalize_contacts_on) but only their upper part collides: a robot
    standing still on flat ground stands on its feet, and the collision penalty stays 0 (the calf capsule's end cap
    holds the foot ball, so a whole colliding calf touched the ground with every standing foot). Seeded: the reset
    draws (joint noise, spawn) decide when a robot held in its default pose starts to sit back on its calves, which
    some draws reach soon after step 25; unseeded, the outcome hung on the tests run before it."""
    torch.manual_seed(0)
    cfg = GenteQuadrupedFlatCfg()
    cfg.env.num_envs = NUM_ENVS
    cfg.domain_rand.push_robots = False
    cfg.domain_rand.init_lin_vel_xy_noise = 0.0
    env = LeggedRobot(cfg, device="cpu")
    for _ in range(25):
        env.step(torch.zeros(NUM_ENVS, env.num_actions))
    calves = [env.mjm.body(f"{leg}_calf").id for leg in LEGS]
    assert torch.norm(env.contact_forces[:, calves], dim=-1).max() == 0.0
    assert (env._reward_collision() == 0).all()
    # the feet carry the whole weight, m g with m the robot's mass
    weight = float(env.mjm.body_subtreemass[env.base]) * 9.81
    feet_z = env.contact_forces[:, env.feet, 2].sum(1)
    assert torch.allclose(feet_z, torch.full_like(feet_z, weight), rtol=0.15)


def test_curriculum_water_is_wading_depth():
    """Every water cell of the full quadruped curriculum is shallower than the trunk height."""
    terrain = Terrain(GenteQuadrupedCfg().terrain, NUM_ENVS)
    wet = terrain.material.has_water()
    assert wet.any() and terrain.material.has_soil().any()
    depth = (terrain.material.water_surface - terrain.height_field)[wet]
    assert depth.max() <= 0.15 + 1e-4 < GenteQuadrupedCfg.rewards.base_height_target


def test_forces_resolve_against_the_quadruped_geoms():
    """Wading acts on the leg capsules and soil on the foot spheres, in water and on mud."""
    cfg = GenteQuadrupedCfg()
    cfg.env.num_envs = NUM_ENVS
    types = [t for t in GenteQuadrupedCfg.terrain.terrain_types if "water" in t or "soil" in t]
    assert len(types) == NUM_ENVS  # a robot on each
    cfg.terrain.num_rows, cfg.terrain.num_cols = 2, len(types)
    cfg.terrain.terrain_length = cfg.terrain.terrain_width = 4.0
    cfg.terrain.border_size = 1.0
    cfg.terrain.terrain_types = types
    cfg.terrain.terrain_proportions = [1.0 / len(types)] * len(types)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        env = LeggedRobot(cfg, device="cpu")
    # the light calves' and feet's added mass is implicit and their mass matrix full: nothing to warn about
    assert not [str(w.message) for w in caught if str(w.message).startswith("forces:")]
    # every robot on the hardest row (then a reset): the start levels are random, and the easiest row's water and
    # soil are the shallowest and firmest
    hardest = torch.full_like(env.terrain_levels, env.max_terrain_level - 1)
    assert env.load_curriculum_state({"terrain_levels": hardest}).startswith("terrain curriculum restored")
    forces = env.forces
    assert forces is not None
    mjm = env.mjm
    seg = forces.seg_geom.numpy()
    assert [mjm.geom(int(g)).name for g in seg] == cfg.forces.leg_geom_names
    assert forces.seg_radius.numpy() == pytest.approx([0.025, 0.02] * 4)
    assert [mjm.body(int(b)).name for b in forces.foot_body.numpy()] == [f"{leg}_foot" for leg in ("FL", "FR", "RL", "RR")]
    assert (forces.sole_length, forces.sole_width, forces.sole_disc) == (pytest.approx(0.04), pytest.approx(0.04), True)
    assert (forces.sole_area, forces.bekker_width) == pytest.approx((3.14159265 * 0.02 ** 2, 0.02))  # Bekker: b = r
    for _ in range(10):
        obs, rew, _, _ = env.step(0.5 * torch.randn(NUM_ENVS, env.num_actions))
    assert torch.isfinite(obs["critic"]).all() and torch.isfinite(rew).all()
    assert env.diverged_resets.item() == 0
    # the water pushes on the wading robots' legs (buoyancy, whatever they do); on soil a foot at rest may feel none
    xfrc = env.sim.d.xfrc_applied.numpy()
    bodies = np.unique(np.concatenate([forces.seg_body.numpy(), forces.foot_body.numpy()]))
    wading = [w for w in range(NUM_ENVS) if "water" in types[int(env.terrain_columns[w])]]
    assert len(wading) == 2 and all(np.abs(xfrc[w, bodies]).max() > 0.0 for w in wading)
