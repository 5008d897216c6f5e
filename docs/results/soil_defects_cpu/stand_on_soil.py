"""The shipped policy told to stand still (or, with ``--zero-actions``, the robot holding its default pose: zero
actions) on whole-tile soils (mud, snow, dry sand) and on flat rigid ground, ROBOTS robots per tile, in the
evaluation's env: from 0.5 s to 3 s, the mean and largest horizontal speed of the sole points
of the feet in soil contact, the bulldozing force on them and the base's horizontal speed, sampled after each
policy step's last substep. With ``--no-bulldozing`` the soil presets' bulldozing coefficients are zeroed first.
The record of the bulldozing chatter in docs/forces.md:

    python stand_on_soil.py TASK ROBOTS OUT_FOLDER [--no-bulldozing] [--zero-actions]
"""
import dataclasses
import json
import sys
from pathlib import Path

import torch
import warp as wp

from legged_gente.evaluation.benchmark import Item
from legged_gente.evaluation.evaluator import Evaluation, load_policy, settle_steps
from legged_gente.terrain import soil

task, robots, out = sys.argv[1], int(sys.argv[2]), Path(sys.argv[3])
no_bulldozing = "--no-bulldozing" in sys.argv[4:]
zero_actions = "--zero-actions" in sys.argv[4:]
out.mkdir(parents=True, exist_ok=True)
soils = ("flat", "mud", "snow", "dry_sand")
if no_bulldozing:
    for name in soils[1:]:
        soil.SOIL_PRESETS[name] = dataclasses.replace(soil.SOIL_PRESETS[name], bulldoze_c=(0.0, 0.0),
                                                      bulldoze_g=(0.0, 0.0))
items = []
for name in soils:
    calls = [{"tool": "flat", "region": "full", "params": {}, "mode": "set"}]
    if name != "flat":
        calls.append({"tool": "soil", "region": "full", "params": {"preset": name}})
    spec = {"version": 1, "name": name, "size_x": 20.0, "size_y": 20.0, "resolution": 0.1, "seed": 0,
            "source": {"text": name}, "backend": "hand-written", "model": None, "calls": calls}
    (out / f"{name}.json").write_text(json.dumps(spec, indent=1))
    items.append(Item(name, "text", out / f"{name}.json"))

evaluation = Evaluation(task, items, robots, "cpu", 3.0, "velocity")
env, forces = evaluation.env, evaluation.env.forces
policy = load_policy(evaluation, pretrained=True)
start = settle_steps(0.5, env.dt)
n = env.num_envs
speed_sum, speed_max, count = torch.zeros(n), torch.zeros(n), torch.zeros(n)
force_sum, force_max, base_sum = torch.zeros(n), torch.zeros(n), torch.zeros(n)
torch.manual_seed(0)
with torch.inference_mode():
    env.reset()
    commands, still = torch.zeros(n, 4), torch.ones(n, dtype=torch.bool)
    obs = env.set_commands(commands, still)
    for step in range(evaluation.num_steps):
        _, _, dones, _ = env.step(torch.zeros(n, env.num_actions) if zero_actions else policy(obs))
        obs = env.set_commands(commands, still)
        if step >= start:
            touch = wp.to_torch(forces.foot_fn) > 0.0
            speed = torch.linalg.norm(wp.to_torch(forces.foot_vel), dim=-1) * touch
            force = torch.linalg.norm(wp.to_torch(forces.foot_force), dim=-1) * touch
            speed_sum += speed.sum(1)
            count += touch.sum(1)
            speed_max = torch.maximum(speed_max, speed.max(1).values)
            force_sum += force.sum(1)
            force_max = torch.maximum(force_max, force.max(1).values)
            base_sum += torch.linalg.norm(env.base_lin_vel[:, :2], dim=-1)
steps = evaluation.num_steps - start
tile = torch.as_tensor(evaluation.tile)
who = "zero actions (the default pose held)" if zero_actions else "the shipped policy standing still"
lines = [f"{task}, {who}, {robots} robots per tile, {steps} policy steps from 0.5 s to 3 s"
         + (", the presets' bulldozing zeroed" if no_bulldozing else "")]
for t, item in enumerate(items):
    on = tile == t
    c = max(float(count[on].sum()), 1.0)
    lines.append(f"{item.id:9s} feet in contact: horizontal speed mean {float(speed_sum[on].sum()) / c:.3f} max "
                 f"{float(speed_max[on].max()):.3f} m/s; bulldozing mean {float(force_sum[on].sum()) / c:6.1f} max "
                 f"{float(force_max[on].max()):6.1f} N; base horizontal speed mean "
                 f"{float(base_sum[on].sum()) / (steps * int(on.sum())):.3f} m/s")
print("\n".join(lines))
(out / f"{task}_{robots}{'_zero_actions' if zero_actions else ''}{'_no_bulldozing' if no_bulldozing else ''}.txt").write_text("\n".join(lines) + "\n")
