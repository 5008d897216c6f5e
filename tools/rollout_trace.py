"""Record a seeded rollout's observations and state, or compare two records bitwise: the check that a change meant
to leave the numbers alone (a refactor, a kernel moved or split) does.

Each task runs ``--steps`` env steps of random actions (seeded) with short episodes, so the post-reset forward
runs too; the record holds, per step, the observations (every group), the force fields' observation and qpos.

    PYTHONPATH=$PWD python tools/rollout_trace.py record /tmp/before.npz      # on the commit before
    PYTHONPATH=$PWD python tools/rollout_trace.py record /tmp/after.npz       # on the change
    python tools/rollout_trace.py compare /tmp/before.npz /tmp/after.npz
"""

from __future__ import annotations

import argparse
import sys

import numpy as np


def record(path: str, tasks: list[str], num_envs: int, steps: int, episode_s: float, device: str) -> None:
    import torch

    from legged_gente.envs.task_registry import task_registry

    out = {}
    for task in tasks:
        cfg, _ = task_registry.get_cfgs(task)
        cfg.env.num_envs = num_envs
        cfg.env.episode_length_s = episode_s  # time-outs: the post-reset forward runs
        torch.manual_seed(0)
        env, _ = task_registry.make_env(task, env_cfg=cfg, args=argparse.Namespace(device=device))
        actions = torch.Generator().manual_seed(0)
        obs_steps, field_steps, qpos_steps, resets = [], [], [], 0
        for _ in range(steps):
            a = torch.randn(env.num_envs, env.num_actions, generator=actions).to(env.device) * 0.5
            obs, _, done, _ = env.step(a)
            resets += int(done.sum())
            obs_steps.append(np.concatenate([obs[k].cpu().numpy() for k in sorted(obs.keys())], -1))
            qpos_steps.append(env.sim.qpos.cpu().numpy().copy())
            if env.forces is not None:
                field_steps.append(env.forces.privileged_obs().cpu().numpy().copy())
        out[f"{task}/obs"], out[f"{task}/qpos"] = np.stack(obs_steps), np.stack(qpos_steps)
        if field_steps:
            out[f"{task}/field_obs"] = np.stack(field_steps)
        print(f"{task}: {steps} steps of {num_envs} robots, {resets} resets")
    np.savez(path, **out)


def compare(path_a: str, path_b: str) -> bool:
    a, b = np.load(path_a), np.load(path_b)
    same = sorted(a.files) == sorted(b.files)
    if not same:
        print(f"different contents: {sorted(a.files)} against {sorted(b.files)}")
    for key in sorted(set(a.files) & set(b.files)):
        equal = a[key].shape == b[key].shape and np.array_equal(a[key], b[key], equal_nan=True)
        diff = "" if equal or a[key].shape != b[key].shape else \
            f", max |difference| {np.nanmax(np.abs(a[key] - b[key])):.3g}"
        print(f"{key}: {'bitwise equal' if equal else 'DIFFERENT'}{diff}")
        same &= equal
    return same


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    rec = sub.add_parser("record", help="run the rollouts and save them")
    rec.add_argument("path")
    rec.add_argument("--tasks", nargs="+", default=["gente_biped", "gente_quadruped"])
    rec.add_argument("--num_envs", type=int, default=6)
    rec.add_argument("--steps", type=int, default=60)
    rec.add_argument("--episode_s", type=float, default=0.3, help="episode length (s): short, so robots reset")
    rec.add_argument("--device", default="cpu")
    cmp = sub.add_parser("compare", help="compare two records bitwise (exit 1 if they differ)")
    cmp.add_argument("a")
    cmp.add_argument("b")
    args = ap.parse_args(argv)
    if args.command == "record":
        record(args.path, args.tasks, args.num_envs, args.steps, args.episode_s, args.device)
    elif not compare(args.a, args.b):
        sys.exit(1)


if __name__ == "__main__":
    main()
