"""``LeggedRobot.foot_terrain()``: what lies under each foot, for a reward, in SI units (docs: README "Rewards and
observations"), read from the force fields' observation whose columns docs/forces.md lists (water depth m, flow
m/s, on-soil flag, sinkage m, normal force / 100 N, ...); zeros on a plane."""

import argparse

import torch

from legged_gente.envs.task_registry import task_registry

G = 9.81


def make(task, **terrain):
    cfg, _ = task_registry.get_cfgs(task)
    cfg.env.num_envs = 2
    for key, value in terrain.items():
        setattr(cfg.terrain, key, value)
    cfg.domain_rand.push_robots = cfg.domain_rand.randomize_base_mass = False
    env, _ = task_registry.make_env(task, env_cfg=cfg, args=argparse.Namespace(device="cpu"))
    return env


def test_standing_on_sand_the_feet_carry_the_robot_in_newtons():
    """20 steps (0.4 s) after spawning on dry sand with zero actions, both bipeds stand: every foot is on soil in a
    rut, and their normal forces carry the robot's weight M g (41.5 kg: 407 N) give or take its sway; a force read
    in the observation's units (hundreds of newtons) would be 100 times too small."""
    env = make("gente_biped", terrain_types=["soil:preset=dry_sand"], terrain_proportions=[1.0], num_rows=1,
               num_cols=1, curriculum=False, mode="random")
    for _ in range(20):
        env.step(torch.zeros(env.num_envs, env.num_actions))
    feet = env.foot_terrain()
    weight = float(env.mjm.body_mass[1:].sum()) * G
    assert feet["on_soil"].all() and (feet["sinkage"] > 0).all()
    assert ((0.5 * weight < feet["normal_force"].sum(1)) & (feet["normal_force"].sum(1) < 2.0 * weight)).all()
    assert (feet["water_depth"] == 0).all() and feet["flow"].shape == (2, 2, 2)
    obs = env.forces.privileged_obs().view(2, 2, -1)
    assert torch.equal(feet["normal_force"], 100.0 * obs[..., 5]) and torch.equal(feet["sinkage"], obs[..., 4])


def test_on_a_plane_every_foot_reads_zero():
    env = make("gente_biped_flat")
    feet = env.foot_terrain()
    assert feet["normal_force"].shape == (2, 2) and not feet["on_soil"].any()
    assert all(not value.any() for value in feet.values())


def test_the_force_field_observation_names_each_foot_and_value():
    """env.observation_names["critic"]: force_fields' columns as <foot body>.<value>, in the kernel's order."""
    env_cfg, _ = task_registry.get_cfgs("gente_biped")
    env_cfg.env.num_envs = 1
    env_cfg.terrain.num_rows, env_cfg.terrain.num_cols = 2, 2
    env, _ = task_registry.make_env("gente_biped", env_cfg=env_cfg, device="cpu")
    names = [n for n in env.observation_names["critic"] if n.startswith("force_fields")]
    feet = env.forces.foot_names
    assert len(feet) == 2 and len(names) == 2 * 12
    assert names[:6] == [f"force_fields.{feet[0]}.{v}" for v in
                         ("water_depth", "flow_x", "flow_y", "on_soil", "sinkage", "normal_force_100N")]
    assert names[12] == f"force_fields.{feet[1]}.water_depth" and names[-1] == f"force_fields.{feet[1]}.K_cm"
    # the names follow the values: a foot's sinkage column is the foot_terrain() sinkage
    column = env.observation_names["critic"].index(f"force_fields.{feet[1]}.sinkage")
    critic = env.get_observations()["critic"]
    assert critic.shape[1] == len(env.observation_names["critic"])
    assert torch.allclose(critic[0, column], env.foot_terrain()["sinkage"][0, 1])
