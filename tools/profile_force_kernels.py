"""GPU time of each terrain force kernel, of a policy step's substeps and of the post-reset forward (torch
profiler over eager launches, after the robots have landed): where ``gente-benchmark``'s "forces" and "soles" shares
go.

    python tools/profile_force_kernels.py --task gente_biped --num_envs 8192

Eager launches: each kernel is timed on the device as launched one by one (no CUDA graph), so the sum of a
substep's kernels is its GPU time without the launch gaps a graph removes.
"""

from __future__ import annotations

import argparse
from collections import Counter

import torch


def kernel_times(fn, calls: int) -> tuple[Counter, Counter]:
    """Mean GPU time (µs) and count per call of each kernel ``fn`` launches, by name (Warp's hash suffix cut)."""
    import warp as wp
    from torch.profiler import ProfilerActivity, profile

    for _ in range(3):
        fn()
    wp.synchronize()
    with profile(activities=[ProfilerActivity.CUDA]) as prof:
        for _ in range(calls):
            fn()
        wp.synchronize()
    time_us, count = Counter(), Counter()
    for event in prof.events():
        if event.device_type == torch.autograd.DeviceType.CUDA:
            name = event.name.split("_cuda_kernel")[0]
            time_us[name] += event.device_time_total / calls
            count[name] += 1 / calls
    return time_us, count


def show(title: str, time_us: Counter, count: Counter, top: int) -> float:
    total = sum(time_us.values())
    print(f"== {title}: {total:.1f} µs of GPU time per call, {sum(count.values()):.0f} kernels")
    for name, us in time_us.most_common(top):
        print(f"  {us:8.2f} µs  x{count[name]:.0f}  {name[:90]}")
    return total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--task", default="gente_biped")
    parser.add_argument("--num_envs", type=int, default=8192)
    parser.add_argument("--calls", type=int, default=40, help="calls profiled per measurement")
    args = parser.parse_args()
    if not torch.cuda.is_available():
        parser.error("the kernels' GPU times need a CUDA device (on the CPU, gente-benchmark times the shares)")

    import mujoco_warp as mjw
    import warp as wp

    from legged_gente.envs.task_registry import task_registry
    from legged_gente.scripts.benchmark import RESET_SHARE, force_pass, settle, typical_resets

    env_cfg, _ = task_registry.get_cfgs(args.task)
    env_cfg.env.num_envs = args.num_envs
    env, _ = task_registry.make_env(args.task, env_cfg=env_cfg, args=argparse.Namespace(device="cuda"))
    if env.forces is None:
        parser.error(f"task {args.task} has no terrain force fields; pick one with forces (e.g. gente_biped)")
    settle(env)
    sim, forces = env.sim, env.forces
    nacon = wp.clone(sim.d.nacon)

    def policy_step():
        for _ in range(env.cfg.control.decimation):
            mjw.step(sim.m, sim.d)
            forces.after_substep()
        forces.observe()

    with wp.ScopedDevice(sim.wp_device), sim.substep_state_kept():
        force_total = show("force kernels (a policy step's passes)", *kernel_times(force_pass(env), args.calls),
                           top=20)
        wp.copy(sim.d.nacon, nacon)
        substep_total = show("policy step's substeps with forces", *kernel_times(policy_step, args.calls), top=30)
        reset = typical_resets(env)
        show(f"post-reset forward (Simulation.recompute, {RESET_SHARE:.0%} of the worlds reset)",
             *kernel_times(lambda: sim.recompute(reset), args.calls), top=25)
    print(f"force kernels: {force_total / substep_total:.1%} of the substeps' kernel time ({args.num_envs} robots, "
          f"{torch.cuda.get_device_name()})")


if __name__ == "__main__":
    main()
