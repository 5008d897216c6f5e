"""GPU check: the CUDA graphs compute what plain launches compute.

    python tools/check_cuda_graphs.py [--task gente_biped] [--num_envs 512] [--steps 300] [--env_only]
    NCCL_NVLS_ENABLE=0 torchrun --standalone --nproc_per_node=2 tools/check_cuda_graphs.py --ppo_only
    torchrun --standalone --nproc_per_node=2 tools/check_cuda_graphs.py --ppo_only --device cpu --ppo_envs 64

Env step: four envs of the task with the same seed get the same random actions: one stepping through the
whole-step graph with its torch logic compiled (the default: cfg.sim.cuda_graph = "env_step",
cfg.sim.torch_compile = True), the same with the force fields' kernels launched one after another
(cfg.forces.parallel_kernels = False) instead of as parallel branches, one through the whole-step graph uncompiled,
and one with only the substeps captured ("physics"), without observation noise and pushes. The first steps (before
any reset, so before any random draw) must agree value by value within 1e-3, the run's mean reward within 10% (after
resets the order of random draws differs, so resets and commands do); resets, terrain levels and episode lengths
are printed. Any mismatch, of the env, the evaluation or PPO (a NaN difference included), exits with 1.

Evaluation: ``gente-evaluate``'s rollout (the shipped policy of the task on two benchmark terrains) through the
env's default step (whole-step graph, compiled) twice, the second run after a reset that follows the capture,
and once with plain launches: the diverged robots must be the same, the number of falls within one robot
(FALLS_TOLERANCE), the mean tracking error and distance agree within STATISTICS_TOLERANCE.

PPO update: GentePPO with its mini-batch graphs and rsl-rl's PPO update the same networks on the same
synthetic rollouts (one mini-batch per epoch, so the shuffling draws do not matter); parameters, losses and
the adaptive learning rate are compared after each update (a mismatch: more than --tolerance). On CUDA it runs
twice: in fp32, and with the bf16 autocast the runner uses there (``algorithm.use_mixed_precision``), where the
compiled MLPs' fused kernels and rsl-rl's eager ones round differently (bf16 keeps 8 significant bits, 2^-8 = 3.9e-3),
so --bf16_tolerance applies. Under torchrun every rank gets its own rollouts, so the gradient and KL all-reduce
between GentePPO's two graphs is compared with rsl-rl's (with --device cpu: the same update without graphs, over
gloo, in fp32; the CPU tests run it that way).

Critic warm-up: GentePPO with its actor held for two updates (``freeze_actor``, what ``gente-train --pretrained``
does first), through the same graphs: the actor and the learning rate must stay exactly as they were (TF32 rounding
makes the held actor's KL nonzero), and the update after the release must move the actor.

PPO act: GentePPO's act graph against rsl-rl's act on the same observations: values and distribution
parameters equal, the graph's sampled actions standard normal around the mean.
"""

from __future__ import annotations

import argparse
import math

import torch

from legged_gente.envs.task_registry import task_registry
from legged_gente.utils.distributed import init_process_group, rank_device, torchrun_launch


def run(task: str, num_envs: int, steps: int, mode: str, seed: int, torch_compile: bool, device: str,
        parallel_kernels: bool = True) -> dict:
    env_cfg, _ = task_registry.get_cfgs(task)
    env_cfg.env.num_envs = num_envs
    env_cfg.sim.cuda_graph = mode
    env_cfg.sim.torch_compile = torch_compile
    env_cfg.forces.parallel_kernels = parallel_kernels
    env_cfg.noise.add_noise = False  # no random draws in the first steps: they must agree value by value
    env_cfg.domain_rand.push_robots = False
    torch.manual_seed(seed)
    env, _ = task_registry.make_env(task, env_cfg=env_cfg, args=argparse.Namespace(device=device))
    actions = torch.Generator().manual_seed(seed)
    first, rewards, resets, levels = [], [], [], []
    with torch.inference_mode():
        for step in range(steps):
            a = (torch.rand(num_envs, env.num_actions, generator=actions) * 2 - 1).to(env.device)
            obs, rew, done, _ = env.step(a)
            if step < 3:
                first.append((obs["policy"].clone(), obs["critic"].clone(), rew.clone()))
            rewards.append(rew.mean())
            resets.append(done.float().sum())
            levels.append(env.terrain_levels.float().mean())
    return {"first": first, "reward": torch.stack(rewards).cpu(), "resets": torch.stack(resets).cpu(),
            "level": torch.stack(levels).cpu(), "episode_length": env.episode_length_buf.float().mean().item(),
            "time": env.sim.time.mean().item()}


def synthetic_observations(num_envs: int, device: str, generator: torch.Generator | None = None):
    """Random policy (48) and critic (64) observations, as rsl-rl's runner passes them."""
    from tensordict import TensorDict

    return TensorDict({"policy": torch.randn(num_envs, 48, generator=generator, device=device),
                       "critic": torch.randn(num_envs, 64, generator=generator, device=device)},
                      batch_size=[num_envs], device=device)


def ppo_algorithm(alg_class, device: str, num_envs: int, steps: int, observations, mixed_precision: bool):
    from types import SimpleNamespace

    from rsl_rl.algorithms import PPO

    from legged_gente.envs.base.legged_robot_config import LeggedRobotCfgPPO, rsl_rl_train_cfg
    from legged_gente.utils.ppo import compile_update_if_configured, mixed_precision_on_cuda_only

    cfg = rsl_rl_train_cfg(LeggedRobotCfgPPO())
    launch = torchrun_launch()
    cfg["num_steps_per_env"], cfg["multi_gpu"] = steps, launch.rsl_rl_multi_gpu() if launch else None
    cfg["algorithm"].update(class_name=alg_class, num_mini_batches=1, num_learning_epochs=4, learning_rate=3e-3)
    cfg["algorithm"]["use_mixed_precision"] = mixed_precision
    mixed_precision_on_cuda_only(cfg, device)  # as GenteOnPolicyRunner does: bf16 on CUDA only
    torch.manual_seed(0)  # the same initial networks on every rank (rsl-rl's runner broadcasts rank 0's)
    alg = PPO.construct_algorithm(observations(), SimpleNamespace(num_envs=num_envs, num_actions=12), cfg, device)
    compile_update_if_configured(alg, cfg)  # as GenteOnPolicyRunner does
    return alg


def ppo_updates(alg_class, device: str, num_envs: int, updates: int = 3, steps: int = 24, frozen_actor: int = 0,
                mixed_precision: bool = True):
    """``updates`` PPO updates on seeded synthetic rollouts (each rank its own), the first ``frozen_actor`` of them
    with the actor held (GentePPO only), in bf16 on CUDA as the runner updates unless ``mixed_precision`` is False;
    the actor's parameters, losses and learning rate before the first and after each."""
    rank = torch.distributed.get_rank() if torch.distributed.is_initialized() else 0
    generator = torch.Generator(device=device).manual_seed(rank)

    def observations():
        return synthetic_observations(num_envs, device, generator)

    alg = ppo_algorithm(alg_class, device, num_envs, steps, observations, mixed_precision)
    if hasattr(alg, "_act_graph"):
        alg._act_graph = None  # the same sampled actions as rsl-rl's act; the act graph is checked apart
    if frozen_actor:
        alg.freeze_actor(frozen_actor)
    history = [(torch.cat([p.detach().flatten() for p in alg.actor.parameters()]), {}, alg.learning_rate)]
    for update in range(updates):
        torch.manual_seed(100 + 10 * rank + update)  # the same sampled actions whatever the update drew before
        with torch.inference_mode():  # as rsl-rl's runner collects
            obs = observations()
            for _ in range(steps):
                alg.act(obs)
                obs = observations()
                dones = torch.rand(num_envs, generator=generator, device=device) < 0.02
                alg.process_env_step(obs, torch.randn(num_envs, generator=generator, device=device), dones,
                                     {"time_outs": dones})
            alg.compute_returns(obs)
        losses = alg.update()
        history.append((torch.cat([p.detach().flatten() for p in alg.actor.parameters()]), losses,
                        alg.learning_rate))
    return alg, history


def check_ppo(device: str, num_envs: int, tolerance: float, mixed_precision: bool = False) -> bool:
    """GentePPO's update against rsl-rl's; True when parameters, losses and learning rates agree."""
    from rsl_rl.algorithms import PPO

    from legged_gente.utils.ppo import GentePPO

    ours, mine = ppo_updates(GentePPO, device, num_envs, mixed_precision=mixed_precision)
    _, theirs = ppo_updates(PPO, device, num_envs, mixed_precision=mixed_precision)
    rank = f"rank {torch.distributed.get_rank()}: " if torch.distributed.is_initialized() else ""
    graphs = [stage.graph is not None for stage in ours._minibatch_stages if hasattr(stage, "graph")]
    print(f"{rank}PPO update ({'bf16' if ours.use_mixed_precision else 'fp32'}): GentePPO's mini-batch stages "
          f"{len(ours._minibatch_stages)}, graphs captured {graphs}, MLPs compiled {bool(ours._compiled_mlps)}")
    agree = True
    for i, ((p, losses, lr), (q, ref_losses, ref_lr)) in enumerate(zip(mine[1:], theirs[1:])):
        difference = float((p - q).abs().max())
        loss_difference = largest([abs(losses[k] - ref_losses[k]) / max(abs(ref_losses[k]), 1e-3) for k in ref_losses
                                    if k in losses])
        agree &= difference <= tolerance and loss_difference <= tolerance and abs(lr - ref_lr) <= 1e-6 * ref_lr
        print(f"{rank}update {i + 1}: max |diff| actor parameters {difference:.2e} (largest {q.abs().max():.2f}), "
              f"largest relative loss difference {loss_difference:.1e}, learning rate {lr:.3e} vs {ref_lr:.3e}")
    return agree


def check_critic_warmup(device: str, num_envs: int) -> bool:
    """GentePPO's update with the actor held for two updates, then released; True when the held updates left
    the actor and the learning rate exactly as they were and the third moved the actor (finite)."""
    from legged_gente.utils.ppo import GentePPO

    _, history = ppo_updates(GentePPO, device, num_envs, frozen_actor=2)
    (start, _, rate), held, released = history[0], history[1:3], history[3]
    held_still = all(torch.equal(actor, start) and abs(lr - rate) <= 1e-6 * rate for actor, _, lr in held)  # float32
    moved = float((released[0] - start).abs().max())
    agree = held_still and 0.0 < moved < math.inf
    print(f"critic warm-up: actor and learning rate unchanged over the 2 held updates: {held_still} (rate "
          f"{rate:.3e} -> {held[-1][2]:.3e}); after the release the actor moved by up to {moved:.2e}")
    return agree


def check_act(device: str, num_envs: int) -> bool:
    """GentePPO's act graph against rsl-rl's act on the same observations, three calls (warm-up, capture,
    replay); True when values and distribution parameters agree and the sampled actions are plausible."""
    from rsl_rl.algorithms import PPO

    from legged_gente.utils.ppo import GentePPO

    def observations():
        return synthetic_observations(num_envs, device)

    alg = ppo_algorithm(GentePPO, device, num_envs, 24, observations, mixed_precision=True)
    agree = True
    with torch.inference_mode():
        for call in range(3):
            obs = observations()
            actions = alg.act(obs).clone()
            ours = {name: getattr(alg.transition, name).clone() for name in ("values", "actions_log_prob")}
            mean, std = (p.clone() for p in alg.transition.distribution_params)
            PPO.act(alg, obs)
            reference_mean, reference_std = alg.transition.distribution_params
            z = (actions - mean) / std
            log_prob = alg.actor.get_output_log_prob(actions)  # the eager pass above left the same distribution
            differences = [float((ours["values"] - alg.transition.values).abs().max()),
                           float((mean - reference_mean).abs().max()), float((std - reference_std).abs().max()),
                           float((ours["actions_log_prob"] - log_prob).abs().max())]
            agree &= max(differences) < 1e-4 and abs(float(z.mean())) < 0.05 and abs(float(z.std()) - 1) < 0.05
            print(f"act call {call + 1}: max |diff| values / mean / std / log-prob {differences}, sampled "
                  f"(action - mean) / std: mean {float(z.mean()):.3f}, std {float(z.std()):.3f}")
    print(f"PPO act: GentePPO's act graph captured: {alg._act_graph.graph is not None}")
    return agree


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="gente_biped")
    parser.add_argument("--num_envs", type=int, default=512)
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--device", default="cuda", help="cuda, cuda:N, or cpu (every check without graphs: the "
                        "PPO update against rsl-rl's; the env and evaluation runs then agree trivially)")
    parser.add_argument("--ppo_envs", type=int, default=4096, help="envs of the synthetic PPO rollouts")
    parser.add_argument("--tolerance", type=float, default=1e-3,
                        help="largest accepted parameter and relative loss difference of the PPO updates")
    parser.add_argument("--bf16_tolerance", type=float, default=1e-2,
                        help="the same, for the updates in bf16 (on CUDA)")
    only = parser.add_mutually_exclusive_group()
    only.add_argument("--ppo_only", action="store_true", help="check the PPO update only (what torchrun runs)")
    only.add_argument("--env_only", action="store_true", help="check the env step and the evaluation only")
    args = parser.parse_args()
    launch = torchrun_launch()
    device = args.device
    if launch is not None:
        device = rank_device(args.device, launch)
        init_process_group(launch, device)
    agree = True
    if not args.env_only:
        agree = check_ppo(device, args.ppo_envs, args.tolerance)
        if device.startswith("cuda"):
            agree &= check_ppo(device, args.ppo_envs, args.bf16_tolerance, mixed_precision=True)
        agree &= check_critic_warmup(device, args.ppo_envs)
        if device.startswith("cuda") and launch is None:
            agree &= check_act(device, args.ppo_envs)
        if agree:
            print("GentePPO agrees with rsl-rl's PPO")
        else:
            print(f"MISMATCH: GentePPO differs from rsl-rl's PPO by more than --tolerance {args.tolerance} (fp32) or "
                  f"--bf16_tolerance {args.bf16_tolerance} (bf16), or its critic warm-up did not hold the actor")
    if not args.ppo_only:
        if env_steps(args.task, args.num_envs, args.steps, args.seed, device):
            print("the env step agrees across graph and compile modes")
        else:
            print(f"MISMATCH: the env step differs across graph and compile modes (first steps by more than "
                  f"{ENV_TOLERANCE}, or mean rewards by more than {STATISTICS_TOLERANCE:.0%})")
            agree = False
        if evaluation_agrees(args.task, device=device):
            print("the evaluation agrees through the whole-step graph and with plain launches")
        else:
            print("MISMATCH: the evaluation differs between the whole-step graph and plain launches")
            agree = False
    if not agree:
        raise SystemExit(1)
    print("all checks agree")


ENV_TOLERANCE = 1e-3  # largest accepted difference of the first steps' observations and rewards
STATISTICS_TOLERANCE = 0.1  # largest accepted relative difference of the run's mean reward
# falls may differ by one robot: two runs of the same launches on a GPU order the contacts differently (atomics), so
# a robot at the edge of falling may fall in one and not the other (seen once between two runs through the graph)
FALLS_TOLERANCE = 1


def largest(differences: list[float]) -> float:
    """The largest difference, NaN counting as infinite (Python's max skips a NaN that is not first)."""
    return max((d if not math.isnan(d) else math.inf for d in differences), default=0.0)


def env_steps(task: str, num_envs: int, steps: int, seed: int, device: str = "cuda") -> bool:
    """The env-step graph with the torch logic compiled (the default), the same with the force fields' kernels one
    after another instead of in parallel branches, without compiling, and the physics-only graph without (see
    :func:`compare_env_runs`); on the CPU, where nothing is captured, compiled or branched, four plain runs."""
    runs = {"env_step+compile": run(task, num_envs, steps, "env_step", seed, True, device),
            "forces in order": run(task, num_envs, steps, "env_step", seed, True, device, parallel_kernels=False),
            "env_step": run(task, num_envs, steps, "env_step", seed, False, device),
            "physics": run(task, num_envs, steps, "physics", seed, False, device)}
    return compare_env_runs(runs)


def compare_env_runs(runs: dict[str, dict], reference: str = "physics") -> bool:
    """True when every run's first steps agree with the reference run's value by value (no noise, no resets
    yet) and their mean rewards over the run within STATISTICS_TOLERANCE (after the first resets their random
    draws differ)."""
    ref_run = runs[reference]
    agree = True
    for name in (n for n in runs if n != reference):
        if len(runs[name]["first"]) != len(ref_run["first"]):
            print(f"{name}: {len(runs[name]['first'])} first steps, {reference}: {len(ref_run['first'])}")
            agree = False
        for i, ((gp, gc, gr), (pp, pc, pr)) in enumerate(zip(runs[name]["first"], ref_run["first"])):
            differences = [float((gp - pp).abs().max()), float((gc - pc).abs().max()), float((gr - pr).abs().max())]
            agree &= largest(differences) <= ENV_TOLERANCE
            print(f"{name} vs {reference}, step {i + 1}: max |diff| policy obs {differences[0]:.2e}, critic obs "
                  f"{differences[1]:.2e}, reward {differences[2]:.2e}")
        mean, ref = float(runs[name]["reward"].mean()), float(ref_run["reward"].mean())
        agree &= abs(mean - ref) <= STATISTICS_TOLERANCE * abs(ref) + 1e-4  # False for a NaN
    print(f"{'':>22}" + "".join(f"{name:>18}" for name in runs))
    for label, key, reduce in (("mean reward", "reward", torch.mean), ("resets (all steps)", "resets", torch.sum),
                               ("final terrain level", "level", lambda x: x[-1])):
        print(f"{label:>22}" + "".join(f"{float(reduce(r[key])):>18.4f}" for r in runs.values()))
    for key in ("episode_length", "time"):
        print(f"{key:>22}" + "".join(f"{r[key]:>18.4f}" for r in runs.values()))
    return bool(agree)


EVALUATION_ITEMS = ["image_05_sketch_blocks", "text_15_concrete_staircase_between_two"]  # gente100: no water, no soil


def evaluation_agrees(task: str, robots_per_terrain: int = 32, episode_s: float = 2.0, device: str = "cuda") -> bool:
    """gente-evaluate's rollout through the env's default step (twice) and with plain launches (see the module
    docstring; on the CPU, where the default step is plain too, this checks only that the check runs)."""
    from legged_gente.envs.base.step_runner import StepRunner
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import Evaluation, load_policy

    evaluation = Evaluation(task, load_benchmark("gente100", EVALUATION_ITEMS), robots_per_terrain, device, episode_s)
    policy = load_policy(evaluation, pretrained=True)
    settle_s = episode_s / 4

    def rollout():
        return evaluation.run(policy, settle_s=settle_s, progress=False)

    runs = {"graph": rollout(), "graph, again": rollout()}
    evaluation.env._runner = StepRunner(evaluation.env, compile=False, graph=False)
    runs["plain launches"] = rollout()
    return compare_evaluations({name: result.metrics for name, result in runs.items()}, "plain launches")


def compare_evaluations(runs: dict[str, dict], reference: str) -> bool:
    """True when every run has the reference run's diverged robots, its number of falls within
    ``FALLS_TOLERANCE``, and its mean tracking error and distance over the robots that did not diverge within
    STATISTICS_TOLERANCE (+ 0.02)."""
    def summary(m):
        kept = ~m["diverged"]
        return {"diverged": int(m["diverged"].sum()), "falls": int(m["fell"].sum()),
                "tracking_error": float(m["tracking_error"][kept].mean()),
                "distance": float(m["distance"][kept].mean())}

    ref = summary(runs[reference])
    agree = True
    for name, metrics in runs.items():
        got = summary(metrics)
        print(f"evaluation, {name:>15}: " + ", ".join(f"{k} {v:.4g}" for k, v in got.items()))
        agree &= (got["diverged"] == ref["diverged"] and abs(got["falls"] - ref["falls"]) <= FALLS_TOLERANCE
                  and all(abs(got[k] - ref[k]) <= STATISTICS_TOLERANCE * abs(ref[k]) + 0.02
                          for k in ("tracking_error", "distance")))
        agree &= bool((metrics["diverged"] == runs[reference]["diverged"]).all())
    return bool(agree)


if __name__ == "__main__":
    main()
