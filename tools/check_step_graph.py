"""GPU check: the whole-step CUDA graph (cfg.sim.cuda_graph = "env_step") computes what plain launches do.

    python tools/check_step_graph.py [--task gente_biped] [--num_envs 512] [--steps 300]

Two envs of the task with the same seed, one stepping through the step graph and one with only the substeps
captured ("physics"), get the same random actions. The first steps are compared value by value (the
physics' float atomics and the order of random draws may differ slightly), the whole run by its statistics:
rewards, resets, terrain levels, episode length.
"""

from __future__ import annotations

import argparse

import torch

from legged_gente.envs.task_registry import task_registry


def run(task: str, num_envs: int, steps: int, mode: str, seed: int) -> dict:
    env_cfg, _ = task_registry.get_cfgs(task)
    env_cfg.env.num_envs = num_envs
    env_cfg.sim.cuda_graph = mode
    torch.manual_seed(seed)
    env, _ = task_registry.make_env(task, env_cfg=env_cfg, args=argparse.Namespace(device="cuda"))
    actions = torch.Generator().manual_seed(seed)
    first, rewards, resets, levels = [], [], [], []
    with torch.inference_mode():
        for step in range(steps):
            a = (torch.rand(num_envs, env.num_actions, generator=actions) * 2 - 1).cuda()
            obs, rew, done, _ = env.step(a)
            if step < 3:
                first.append((obs["policy"].clone(), obs["critic"].clone(), rew.clone()))
            rewards.append(rew.mean())
            resets.append(done.float().sum())
            levels.append(env.terrain_levels.float().mean())
    return {"first": first, "reward": torch.stack(rewards).cpu(), "resets": torch.stack(resets).cpu(),
            "level": torch.stack(levels).cpu(), "episode_length": env.episode_length_buf.float().mean().item(),
            "time": env.sim.time.mean().item()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="gente_biped")
    parser.add_argument("--num_envs", type=int, default=512)
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    graph = run(args.task, args.num_envs, args.steps, "env_step", args.seed)
    plain = run(args.task, args.num_envs, args.steps, "physics", args.seed)
    for i, ((gp, gc, gr), (pp, pc, pr)) in enumerate(zip(graph["first"], plain["first"])):
        print(f"step {i + 1}: max |diff| policy obs {(gp - pp).abs().max():.2e}, critic obs {(gc - pc).abs().max():.2e}, "
              f"reward {(gr - pr).abs().max():.2e}")
    print(f"{'':>22} {'env_step graph':>15} {'physics graph':>15}")
    for name, key, reduce in (("mean reward", "reward", torch.mean), ("resets (all steps)", "resets", torch.sum),
                              ("final terrain level", "level", lambda x: x[-1])):
        print(f"{name:>22} {float(reduce(graph[key])):>15.4f} {float(reduce(plain[key])):>15.4f}")
    for name in ("episode_length", "time"):
        print(f"{name:>22} {graph[name]:>15.4f} {plain[name]:>15.4f}")


if __name__ == "__main__":
    main()
