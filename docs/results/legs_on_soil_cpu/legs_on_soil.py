"""How much a shipped policy's robot stands on bodies other than its feet on soil (the soil sinks under the feet and,
since b6e845c, the rut legs, the quadruped's calves; any other body meets the soil as rigid ground, docs/forces.md): ROBOTS robots per tile walking straight ahead
at 0.5 m/s (their spawn heading held) on flat ground and on the whole-tile soils mud, snow and dry sand, in the
evaluation's env (observation noise, pushes, friction and mass randomisation); from 0.5 s to 3 s, per robot-step,
whether such a body has a contact force over 1 N, and their vertical contact force as a fraction of the robot's
weight. The record of how docs/robots.md's numbers were made:

    python legs_on_soil.py TASK ROBOTS OUT_FOLDER
"""
import json
import sys
from pathlib import Path

import torch

from legged_gente.evaluation.benchmark import Item
from legged_gente.evaluation.evaluator import Evaluation, load_policy, settle_steps
from legged_gente.utils.torch_math import yaw_of

task, robots, out = sys.argv[1], int(sys.argv[2]), Path(sys.argv[3])
out.mkdir(parents=True, exist_ok=True)
items = []
for soil in ("flat", "mud", "snow", "dry_sand"):
    calls = [{"tool": "flat", "region": "full", "params": {}, "mode": "set"}]
    if soil != "flat":
        calls.append({"tool": "soil", "region": "full", "params": {"preset": soil}})
    spec = {"version": 1, "name": soil, "size_x": 20.0, "size_y": 20.0, "resolution": 0.1, "seed": 0,
            "source": {"text": soil}, "backend": "hand-written", "model": None, "calls": calls}
    (out / f"{soil}.json").write_text(json.dumps(spec, indent=1))
    items.append(Item(soil, "text", out / f"{soil}.json"))

evaluation = Evaluation(task, items, robots, "cpu", 3.0, "velocity")
env = evaluation.env
policy = load_policy(evaluation, pretrained=True)
feet = set(env.feet.tolist())
legs = torch.tensor([i for i in range(1, env.mjm.nbody) if i not in feet])  # every body but the world and the feet
weight = float(env.mjm.body_subtreemass[env.base]) * 9.81
start = settle_steps(0.5, env.dt)  # the first 0.5 s left out, as the evaluation's settling
touching = torch.zeros(env.num_envs)
load = torch.zeros(env.num_envs)
fell = torch.zeros(env.num_envs, dtype=torch.bool)
torch.manual_seed(0)
with torch.inference_mode():
    env.reset()
    heading = yaw_of(env.base_quat)
    commands = torch.stack([torch.full_like(heading, 0.5), torch.zeros_like(heading), torch.zeros_like(heading),
                            heading], 1)
    still = torch.zeros(env.num_envs, dtype=torch.bool)
    obs = env.set_commands(commands, still)
    for step in range(evaluation.num_steps):  # the 3 s episode
        _, _, dones, _ = env.step(policy(obs))
        fell |= dones.bool()
        obs = env.set_commands(commands, still)
        if step >= start:
            force = env.contact_forces[:, legs]
            touching += (torch.norm(force, dim=-1) > 1.0).any(1).float()
            load += force[..., 2].clamp(min=0).sum(1) / weight
steps = evaluation.num_steps - start
tile = torch.as_tensor(evaluation.tile)
lines = [f"{task}, the shipped policy, bodies other than the feet, {robots} robots per tile, 0.5 m/s ahead, "
         f"{steps} steps from 0.5 s to 3 s"]
for t, item in enumerate(items):
    on = tile == t
    lines.append(f"{item.id:9s} touching in {100 * touching[on].sum() / (steps * on.sum()):5.1f} % of robot-steps; "
                 f"their vertical load {100 * load[on].sum() / (steps * on.sum()):5.1f} % of the weight on average, "
                 f"{100 * load[on].sum() / max(touching[on].sum(), 1):5.1f} % while touching; "
                 f"reset {int(fell[on].sum())}")
print("\n".join(lines))
(out / f"{task}_{robots}.txt").write_text("\n".join(lines) + "\n")
