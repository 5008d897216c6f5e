"""docs/new_robot.md's rough robot on the tutorial's own mud: its feet carry it and sink as Bekker says, and its
shins (whose contacts the tutorial penalises) stay out of the ground."""

import math

import pytest
import torch

from legged_gente.envs.task_registry import task_registry
from test_new_robot_tutorial import tutorial  # noqa: F401  (the fixture: the doc's files, tasks registered)

GRAVITY = 9.81
MASS = 3.0 + 4 * (0.3 + 0.1 + 0.02)  # kg: base, 4 x (thigh, shin, foot) of the tutorial's MJCF
FOOT_RADIUS = 0.02  # m


def mud_sinkage(load: float) -> float:
    """Bekker's static sinkage z = (p / (kc/b + kphi))^(1/n) (Wong, Theory of Ground Vehicles, ch. 2) of one ball
    foot, a disc of area pi r^2 and width b = r, in mud (sandy loam at 32 % moisture, Wong Table 2.3:
    kc = 0.77 kN/m^1.5, kphi = 51.91 kN/m^2.5, n = 0.5)."""
    pressure = load / (math.pi * FOOT_RADIUS**2)
    return (pressure / (0.77e3 / FOOT_RADIUS + 51.91e3)) ** (1 / 0.5)


def test_rough_robot_stands_on_its_feet_in_mud(tutorial):  # noqa: F811
    cfg, _ = task_registry.get_cfgs("my_robot_rough")
    cfg.env.num_envs = 2
    cfg.terrain.terrain_types, cfg.terrain.terrain_proportions = ["soil:preset=mud"], [1.0]
    cfg.terrain.num_rows, cfg.terrain.num_cols = 1, 2
    cfg.terrain.terrain_length = cfg.terrain.terrain_width = 3.0
    cfg.terrain.border_size = 1.0
    cfg.domain_rand.push_robots = False
    env, _ = task_registry.make_env("my_robot_rough", env_cfg=cfg)
    shins = [env.mjm.body(f"{leg}_shin").id for leg in ("FL", "FR", "RL", "RR")]
    feet_fz, shins_fz = [], []
    for step in range(75):  # 1.5 s with zero actions: the drop, the sinking, the stand
        env.step(torch.zeros(2, env.num_actions))
        if step >= 50:
            feet_fz.append(env.contact_forces[:, env.feet, 2].sum(1))
            shins_fz.append(env.contact_forces[:, shins, 2].abs().sum(1))
    assert torch.stack(shins_fz).max() == 0.0  # the shins never touch
    # the feet carry the robot's weight (averaged over the last 0.5 s: the contacts chatter as a foot sinks)
    assert torch.stack(feet_fz).mean(0).tolist() == [pytest.approx(MASS * GRAVITY, rel=0.2)] * 2
    # and sink about as deep as Bekker says for a quarter of it each: 1.0 cm (the rear feet carry more, and the
    # landing digs deeper than the static sinkage)
    z = mud_sinkage(MASS * GRAVITY / 4)
    sinkage = torch.as_tensor(env.forces.foot_sinkage.numpy())
    assert 0.7 * z < sinkage.mean() < 3.0 * z

