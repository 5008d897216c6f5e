"""The env layer's settings and rules checked by hand: settings that divide or set a share are refused with the fix
(at construction and in set_param) instead of being run as something else; terminations against their thresholds;
the ground under the height scan and the base-height terms against MuJoCo's own heightfield."""

import math
import re

import mujoco
import numpy as np
import pytest
import torch
from test_env_inputs import N, cfg_of, env  # noqa: F401 (env is a fixture)

from legged_gente.envs.gente_biped.gente_biped import GenteBiped
from legged_gente.envs.gente_biped.gente_biped_config import GenteBipedCfg


class TwoRough(GenteBipedCfg):
    """Two 8 m tiles (levels 0, 1) of random_uniform ground."""

    class env(GenteBipedCfg.env):
        num_envs = N

    class terrain(GenteBipedCfg.terrain):
        num_rows = 2
        num_cols = 1
        border_size = 1.0
        terrain_types = ["random_uniform"]
        terrain_proportions = [1.0]

    class domain_rand(GenteBipedCfg.domain_rand):
        push_robots = False


# ---------------------------------------------------------------------------------------------------------------
# settings that divide or count: refused in one line, also when the env is built without the task registry
# ---------------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("section, field, value, rule", [
    ("control", "decimation", 0, r"use >= 1"),  # dt = sim.dt * 0: the episode length divided by zero
    ("sim", "dt", 0.0, r"use > 0"),
    ("sim", "dt", -0.005, r"use > 0"),
    ("env", "episode_length_s", 0.0, r"use > 0"),  # 0 s: every step was a time-out
    ("sim", "max_qvel", 0.0, r"use > 0"),  # every moving world was reset as diverged, every step
])
def test_a_step_length_or_limit_that_is_not_positive_is_refused(section, field, value, rule):
    cfg = cfg_of()
    setattr(getattr(cfg, section), field, value)
    with pytest.raises(ValueError, match=rf"cfg.{section}.{field}={value}; {rule}"):
        GenteBiped(cfg, device="cpu")


def test_a_negative_initial_terrain_level_is_refused_not_a_crash_in_randint():
    cfg = TwoRough()
    cfg.terrain.max_init_terrain_level = -1  # levels drawn from randint(0, 0): a RuntimeError deep in torch
    with pytest.raises(ValueError, match=r"cfg.terrain.max_init_terrain_level=-1; use >= 0"):
        GenteBiped(cfg, device="cpu")


@pytest.mark.parametrize("value", [0.0, -1.0, 4.0])
def test_the_termination_tilt_is_an_angle_in_0_to_pi(value):
    """The check compares cos(tilt): -1 rad ran as +1 rad, 4 rad as 2 pi - 4 = 2.28 rad, 0 ended every episode at
    the first tilt. pi (cos = -1) is the largest angle, and never ends one."""
    cfg = cfg_of()
    cfg.asset.terminate_tilt = value
    with pytest.raises(ValueError, match=rf"cfg.asset.terminate_tilt={value}; use an angle in \(0, pi\]"):
        GenteBiped(cfg, device="cpu")


# ---------------------------------------------------------------------------------------------------------------
# settings the step reads from tensors: the same rule at construction and in set_param
# ---------------------------------------------------------------------------------------------------------------
RULES = [  # path, a bad value, the rule's words
    ("rewards.tracking_sigma", 0.0, r"a kernel width > 0"),
    ("rewards.tracking_sigma", -0.25, r"a kernel width > 0"),
    ("commands.still_fraction", 1.5, r"a fraction, in \[0, 1\]"),
    ("commands.still_fraction", -0.1, r"a fraction, in \[0, 1\]"),
    ("commands.heading_stiffness", -0.5, r">= 0"),
    ("rewards.gait_period", 0.0, r"a period > 0"),  # the biped's
    ("rewards.stance_fraction", 1.2, r"a fraction of the period, in \[0, 1\]"),
]


@pytest.mark.parametrize("path, value, rule", RULES)
def test_a_run_time_setting_outside_its_range_is_refused_in_the_config(path, value, rule):
    cfg = cfg_of()
    section, name = path.split(".")
    setattr(getattr(cfg, section), name, value)
    with pytest.raises(ValueError, match=rf"cfg.{path}={value}; use {rule}"):
        GenteBiped(cfg, device="cpu")


@pytest.mark.parametrize("path, value, rule", RULES)
def test_a_run_time_setting_outside_its_range_is_refused_by_set_param(env, path, value, rule):
    section, name = path.split(".")
    before = float(getattr(getattr(env.params, section), name))
    with pytest.raises(ValueError, match=rf"{path}={value}; use {rule}"):
        env.set_param(path, value)
    assert float(getattr(getattr(env.params, section), name)) == before  # unchanged


def test_tracking_with_a_zero_sigma_would_not_reward_perfect_tracking(env):
    """Why sigma must be > 0: exp(-err^2 / sigma) is 1 for a perfect tracker; with sigma = 0 it is exp(-0/0) = NaN,
    which the total drops as 0, and any error gives exp(-inf) = 0: the tracking terms paid nothing at all."""
    env.commands[:] = torch.tensor([0.5, -0.2, 0.3, 0.0])
    env.base_lin_vel = torch.tensor([[0.5, -0.2, 0.0]] * N)
    env.base_ang_vel = torch.tensor([[0.0, 0.0, 0.3]] * N)
    assert env._reward_tracking_lin_vel().tolist() == pytest.approx([1.0] * N)
    assert env._reward_tracking_ang_vel().tolist() == pytest.approx([1.0] * N)
    with pytest.raises(ValueError):
        env.set_param("rewards.tracking_sigma", 0.0)
    env.set_param("rewards.tracking_sigma", 0.1)  # a valid width is taken
    try:
        env.base_lin_vel = torch.tensor([[0.3, -0.2, 0.0]] * N)  # 0.2 m/s short: exp(-0.04 / 0.1)
        assert env._reward_tracking_lin_vel().tolist() == pytest.approx([math.exp(-0.04 / 0.1)] * N, rel=1e-5)
    finally:
        env.set_param("rewards.tracking_sigma", 0.25)
        env.reset()


# ---------------------------------------------------------------------------------------------------------------
# terminations against their thresholds (legged_gym: contact force > 1 N on a terminating body; ours adds tilt and
# base height); none of them is a time-out
# ---------------------------------------------------------------------------------------------------------------
def test_terminations_by_contact_tilt_and_height_are_falls_not_time_outs():
    cases = [  # (contact force on the pelvis N, base tilt rad, base height m, ends the episode)
        ((0.0, 0.0, 0.0), 0.0, 0.98, False),
        ((0.0, 0.6, 0.79), 0.0, 0.98, False),  # |f| = 0.99 N: not over 1 N
        ((0.0, 0.0, 1.2), 0.0, 0.98, True),  # 1.2 N
        ((0.0, 0.0, 0.0), 0.95, 0.98, False),  # under 1 rad of tilt
        ((0.0, 0.0, 0.0), 1.05, 0.98, True),  # over 1 rad
        ((0.0, 0.0, 0.0), 0.0, 0.51, False),  # 0.51 m above the flat ground (z = 0)
        ((0.0, 0.0, 0.0), 0.0, 0.49, True),  # under 0.5 m
    ]
    cfg = cfg_of()
    cfg.env.num_envs = n = len(cases)
    env = GenteBiped(cfg, device="cpu")
    assert cfg.asset.terminate_tilt == 1.0 and cfg.asset.terminate_height == 0.5  # the biped's: rad, m
    pelvis = env.mjm.body("pelvis").id
    assert pelvis in env.terminate_bodies.tolist()
    env.contact_forces = torch.zeros(n, env.mjm.nbody, 3)
    env.contact_forces[:, pelvis] = torch.tensor([c[0] for c in cases])
    tilt = torch.tensor([c[1] for c in cases])  # a pitch: gravity in the base frame (sin, 0, -cos)
    env.projected_gravity = torch.stack([torch.sin(tilt), torch.zeros(n), -torch.cos(tilt)], dim=1)
    env.base_pos = torch.zeros(n, 3)
    env.base_pos[:, 2] = torch.tensor([c[2] for c in cases])
    env.episode_length_buf = torch.ones(n, dtype=torch.long)
    env._check_termination(torch.zeros(n, dtype=torch.bool))
    assert env.reset_buf.tolist() == [c[3] for c in cases]
    assert not env.time_out_buf.any()  # falls: PPO does not bootstrap them
    assert env._reward_termination().tolist() == [float(c[3]) for c in cases]


# ---------------------------------------------------------------------------------------------------------------
# the ground the height scan, base_height and terminate_height measure from is MuJoCo's heightfield
# ---------------------------------------------------------------------------------------------------------------
def test_the_ground_height_is_where_a_ray_meets_mujocos_heightfield():
    """At heightfield vertices and along the cell edges in x MuJoCo's surface (two triangles a cell) and the
    env's bilinear interpolation are both linear, so they must agree there: a ray cast straight down by MuJoCo
    (on the CPU model, robot excluded) against env._ground_height, on rough ground."""
    env = GenteBiped(TwoRough(), device="cpu")
    model = env.mjm
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    res, (ox, oy) = env.terrain.resolution, env.terrain.origin_xy
    nx, ny = env.height_samples.shape
    terrain_geoms = {g for g in range(model.ngeom) if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_HFIELD}
    rng = np.random.default_rng(0)
    points, hits = [], []
    while len(points) < 40:
        i, j = int(rng.integers(20, nx - 20)), int(rng.integers(20, ny - 20))
        # a vertex, or a point along its cell's x edge (1 mm off the edge line: a ray exactly on a triangle
        # edge may slip through)
        x = ox + res * (i + (float(rng.random()) if len(points) % 2 else 0.0))
        y = oy + res * j + 1e-3
        geom = np.array([-1], dtype=np.int32)
        dist = mujoco.mj_ray(model, data, np.array([x, y, 10.0]), np.array([0.0, 0.0, -1.0]), None, 1, -1, geom)
        if int(geom[0]) not in terrain_geoms:
            continue  # the robot's body in the way
        points.append((x, y))
        hits.append(10.0 - dist)
    ground = env._ground_height(torch.tensor(points, dtype=torch.float32))
    heights = torch.tensor(hits, dtype=torch.float32)
    assert heights.std() > 0.005  # rough ground: a shifted or transposed grid would not match
    # 1 mm off the edge line with slopes of at most ~0.3 (random_uniform of the lowest levels): under 0.5 mm
    assert torch.allclose(ground, heights, atol=5e-4)


# ---------------------------------------------------------------------------------------------------------------
# commands from outside
# ---------------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("still", [torch.ones(N, 1, dtype=torch.bool), torch.ones(N + 1, dtype=torch.bool),
                                   torch.tensor([0.0, 0.5])])
def test_set_commands_takes_one_stand_still_flag_per_robot(env, still):
    """A (num_envs, 1) mask failed inside torch's copy_ (a broadcast error), and float flags were cast, 0.5 to
    True: refused in one line instead."""
    with pytest.raises(ValueError, match=re.escape(f"still of shape {tuple(still.shape)} and dtype {still.dtype}; "
                                                   f"this env takes (num_envs,) = ({N},) booleans")):
        env.set_commands(torch.zeros(N, 4), still)
    env.set_commands(torch.zeros(N, 4), torch.tensor([True, False]))  # one flag per robot is taken
    assert env.standing_still.tolist() == [True, False]
    env.reset()
