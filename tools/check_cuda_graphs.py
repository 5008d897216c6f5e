"""GPU check: the CUDA graphs compute what plain launches compute.

    python tools/check_cuda_graphs.py [--task gente_biped] [--num_envs 512] [--steps 300]

Env step: two envs of the task with the same seed, one stepping through the whole-step graph
(cfg.sim.cuda_graph = "env_step") and one with only the substeps captured ("physics"), get the same random
actions. The first steps are compared value by value (the order of random draws differs, so resets and
commands do), the whole run by its statistics: rewards, resets, terrain levels, episode length.

PPO update: GentePPO with its mini-batch graph and rsl-rl's PPO update the same networks on the same
synthetic rollouts (one mini-batch per epoch, so the shuffling draws do not matter); parameters, losses and
the adaptive learning rate are compared after each update.
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


def ppo_updates(alg_class, updates: int = 3, num_envs: int = 4096, steps: int = 24):
    """``updates`` PPO updates on seeded synthetic rollouts; the actor's parameters and losses after each."""
    from types import SimpleNamespace

    from rsl_rl.algorithms import PPO
    from tensordict import TensorDict

    from legged_gente.envs.base.legged_robot_config import LeggedRobotCfgPPO, rsl_rl_train_cfg

    generator = torch.Generator(device="cuda").manual_seed(0)

    def observations():
        return TensorDict({"policy": torch.randn(num_envs, 48, generator=generator, device="cuda"),
                           "critic": torch.randn(num_envs, 64, generator=generator, device="cuda")},
                          batch_size=[num_envs], device="cuda")

    cfg = rsl_rl_train_cfg(LeggedRobotCfgPPO())
    cfg["num_steps_per_env"], cfg["multi_gpu"] = steps, None
    cfg["algorithm"].update(class_name=alg_class, num_mini_batches=1, num_learning_epochs=4, learning_rate=3e-3)
    torch.manual_seed(0)
    alg = PPO.construct_algorithm(observations(), SimpleNamespace(num_envs=num_envs, num_actions=12), cfg, "cuda")
    history = []
    for update in range(updates):
        torch.manual_seed(100 + update)  # the same sampled actions whatever the update drew before
        with torch.inference_mode():  # as rsl-rl's runner collects
            obs = observations()
            for _ in range(steps):
                alg.act(obs)
                obs = observations()
                dones = torch.rand(num_envs, generator=generator, device="cuda") < 0.02
                alg.process_env_step(obs, torch.randn(num_envs, generator=generator, device="cuda"), dones,
                                     {"time_outs": dones})
            alg.compute_returns(obs)
        losses = alg.update()
        history.append((torch.cat([p.detach().flatten() for p in alg.actor.parameters()]), losses,
                        alg.learning_rate))
    return alg, history


def check_ppo() -> None:
    from rsl_rl.algorithms import PPO

    from legged_gente.utils.ppo import GentePPO

    ours, mine = ppo_updates(GentePPO)
    _, theirs = ppo_updates(PPO)
    print(f"PPO update: GentePPO's mini-batch graph captured: {ours._minibatch_graph.graph is not None}")
    for i, ((p, losses, lr), (q, ref_losses, ref_lr)) in enumerate(zip(mine, theirs)):
        print(f"update {i + 1}: max |diff| actor parameters {(p - q).abs().max():.2e} (largest {q.abs().max():.2f}), "
              f"losses {losses} vs {ref_losses}, learning rate {lr:.3e} vs {ref_lr:.3e}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="gente_biped")
    parser.add_argument("--num_envs", type=int, default=512)
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    check_ppo()
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
