"""Throughput benchmark: raw mjw.step, LeggedRobot.step and full PPO, at several num_envs, in one run.

    gente-benchmark --task gente_biped_flat --num_envs 1024 4096 8192 [--device cuda]

Raw physics is ``mjw.step`` of the very model the env compiles (captured in a CUDA graph on GPU), from the
robots standing after landing (restored every RESTORE_EVERY policy steps, so they never lie fallen), reported as
substeps/s summed over worlds; env steps/s is policy steps/s summed over worlds; PPO is rsl-rl's
collection + learning. ``env/raw`` compares env steps against the raw ceiling (raw substeps / decimation); the
CSV's last column is the task's decimation.
"""

from __future__ import annotations

import argparse
import time
import warnings
from collections import Counter

import torch
import warp as wp

from legged_gente.utils.args import (
    Parser, add_verbose, check_output, flag, import_mujoco, quiet_third_party, resolve_device, run_command)

import_mujoco("gente-benchmark")  # before the imports below load it (a MUJOCO_GL it cannot use: one line)

from legged_gente.envs.base.legged_robot import CUDA_GRAPH_MODES
from legged_gente.envs.task_registry import task_registry
from legged_gente.utils.tables import write_rows


def _sync(device: str) -> None:
    if device.startswith("cuda"):
        torch.cuda.synchronize(device)
        wp.synchronize()


WARMUP_CALLS = 5  # untimed calls first: the first replays after a capture or a kernel load run slow


def _timed_calls(env, fn, steps: int) -> float:
    """Calls/s of ``fn``: captured once into a CUDA graph and replayed on GPU, called directly on the CPU."""
    sim = env.sim
    with wp.ScopedDevice(sim.wp_device):
        fn()  # loads every kernel module before capture or timing
        graph = None
        if sim.wp_device.is_cuda:
            with wp.ScopedCapture() as capture:
                fn()
            graph = capture.graph
        run = (lambda: wp.capture_launch(graph)) if graph is not None else fn
        for _ in range(WARMUP_CALLS):
            run()
        _sync(env.device)
        start = time.perf_counter()
        for _ in range(steps):
            run()
        _sync(env.device)
    return steps / (time.perf_counter() - start)


def settle(env, seconds: float = 0.5) -> None:
    """Zero-action env steps until the spawned robots have landed and stand: the raw ceiling is measured from
    this state (a landing impact takes the solver more iterations than standing or walking does)."""
    actions = torch.zeros(env.num_envs, env.num_actions, device=env.device)
    for _ in range(round(seconds / env.dt)):
        env.step(actions)


RESTORE_EVERY = 3  # policy steps between returns to the start state (12 substeps, 0.06 s, for the biped)


def raw_physics(env, substeps: int, with_forces: bool = False) -> float:
    """Substeps/s (all worlds) of mjw.step on the env's model and data; no env logic. ``with_forces`` keeps the
    terrain force callbacks and their after-substep kernels in the loop (and their observation once per policy
    step); without, the contact filter stays where it makes the soles' terrain contacts (``forces.sole_contact``).

    Every RESTORE_EVERY policy steps the worlds go back to the state the measurement began in (two device
    copies; ``settle`` makes that a standing state), and the env gets that state back at the end: without it
    the unactuated robots fall over within a second, and a fallen robot's many contacts make the "ceiling"
    slower than the env, which resets them.
    """
    import mujoco_warp as mjw

    sim = env.sim
    start_qpos, start_qvel = wp.clone(sim.d.qpos), wp.clone(sim.d.qvel)
    callbacks = (sim.m.callback.passive, sim.m.callback.contactfilter)
    if not with_forces:
        sim.m.callback.passive = None
        if env.forces is None or not env.forces.npt:  # analytic sole contacts are the feet's collision: kept
            sim.m.callback.contactfilter = None
    hooks, step_hooks = (sim.after_substep, sim.after_step) if with_forces else ([], [])
    decimation = env.cfg.control.decimation

    def restore():
        wp.copy(sim.d.qpos, start_qpos)
        wp.copy(sim.d.qvel, start_qvel)

    def substeps_from_start():
        restore()
        for _ in range(RESTORE_EVERY):
            for _ in range(decimation):
                mjw.step(sim.m, sim.d)
                for hook in hooks:
                    hook()
            for hook in step_hooks:
                hook()

    try:
        block = RESTORE_EVERY * decimation
        return _timed_calls(env, substeps_from_start, max(1, substeps // block)) * block * env.num_envs
    finally:
        sim.m.callback.passive, sim.m.callback.contactfilter = callbacks
        restore()
        sim.drop_stage()


def force_pass(env, only_sole_contacts: bool = False):
    """A callable launching a policy step's force kernels with no physics around them: ``decimation`` passes of
    the callbacks' and the after-substep kernels on the current contacts and state (the analytic sole contacts
    included), then the observation once; or ``decimation`` passes of the sole contacts alone (the feet's terrain
    collision, which the raw physics has too). Each pass starts from the contact count of now: the sole contacts
    append theirs."""
    forces, sim = env.forces, env.sim
    nacon = wp.clone(sim.d.nacon)

    def kernels():
        for _ in range(env.cfg.control.decimation):
            wp.copy(sim.d.nacon, nacon)
            if only_sole_contacts:
                forces.sole_contacts(sim.m, sim.d)
                continue
            forces.contact_filter(sim.m, sim.d)
            forces.passive(sim.m, sim.d)
            forces.after_substep()
        if not only_sole_contacts:
            forces.observe()

    return kernels


def force_kernels_per_s(env, substeps: int, only_sole_contacts: bool = False) -> float:
    """Substep passes/s (all worlds) of ``force_pass``, timed over ``substeps`` of them (whole policy steps); the
    contact count and what the kernels integrate are put back afterwards."""
    sim, decimation = env.sim, env.cfg.control.decimation
    nacon = wp.clone(sim.d.nacon)
    with sim.substep_state_kept():
        try:
            steps = max(1, substeps // decimation)
            return _timed_calls(env, force_pass(env, only_sole_contacts), steps) * decimation * env.num_envs
        finally:
            wp.copy(sim.d.nacon, nacon)
            sim.drop_stage()


# the worlds a step resets, for the forward's timing: about what a training step resets (20 s episodes are
# 1000 steps; early in training falls end them sooner)
RESET_SHARE = 0.01


def typical_resets(env) -> torch.Tensor:
    """A reset mask of every ``1 / RESET_SHARE``-th world, to time the post-reset forward with."""
    reset = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    reset[::round(1 / RESET_SHARE)] = True
    return reset


def reset_forward_per_s(env, calls: int) -> float:
    """Calls/s of the Warp work of the forward a step runs after its resets (``Simulation.recompute``: MuJoCo's
    forward with the force fields' callbacks, their after-substep hooks and the per-body contact forces), on the
    current state, with every ``1 / RESET_SHARE``-th world reset. On a GPU the step runs it every time, whether a
    world reset or not (deciding would wait for the device); its first half is the next substep's, computed ahead,
    which that substep does not repeat, and the constraints are solved in the reset worlds only."""
    reset = typical_resets(env)
    return _timed_calls(env, lambda: env.sim.recompute(reset), calls)


def env_steps(env, steps: int, check_sync: bool = False) -> float:
    """Policy steps/s (all worlds) of LeggedRobot.step with random actions. ``check_sync`` (CUDA only): torch
    raises on any operation that waits for the device inside the timed steps (the env must have none)."""
    actions = torch.zeros(env.num_envs, env.num_actions, device=env.device)
    env.step(actions)
    _sync(env.device)
    if check_sync:
        torch.cuda.set_sync_debug_mode("error")
    try:
        start = time.perf_counter()
        for _ in range(steps):
            actions.uniform_(-1.0, 1.0)
            env.step(actions)
    finally:
        if check_sync:
            torch.cuda.set_sync_debug_mode("default")
    _sync(env.device)
    return steps * env.num_envs / (time.perf_counter() - start)


def _runner(env, task: str):
    """The task's PPO runner on ``env``, logging nowhere, after one warm-up iteration (kernel loads, graph
    captures). One runner per env serves the sync check, the timing and the profile."""
    _, train_cfg = task_registry.get_cfgs(task)
    runner, train_cfg, _ = task_registry.make_alg_runner(env, task, train_cfg=train_cfg, log_root=None)
    runner.learn(1)
    return runner, train_cfg


def ppo_sync_points(runner) -> Counter:
    """Where one PPO iteration (rsl-rl collection + update) makes the host wait for the device: torch's sync
    debug mode warns at each such operation; counted per source line (CUDA only)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        torch.cuda.set_sync_debug_mode("warn")
        try:
            runner.learn(1)
        finally:
            torch.cuda.set_sync_debug_mode("default")
    return Counter(f"{w.filename}:{w.lineno}" for w in caught if "synchroniz" in str(w.message))


def ppo_steps(runner, train_cfg, iterations: int) -> tuple[float, float]:
    """PPO env-steps/s (collection + learning) and the share of the time spent in the policy update."""
    env = runner.env
    update, update_seconds = runner.alg.update, 0.0

    def timed_update():
        nonlocal update_seconds
        _sync(env.device)
        start = time.perf_counter()
        losses = update()
        _sync(env.device)
        update_seconds += time.perf_counter() - start
        return losses

    runner.alg.update = timed_update
    try:
        _sync(env.device)
        start = time.perf_counter()
        runner.learn(iterations)
        _sync(env.device)
        seconds = time.perf_counter() - start
    finally:
        runner.alg.update = update
    return iterations * train_cfg.runner.num_steps_per_env * env.num_envs / seconds, update_seconds / seconds


def gpu_time_split(prof) -> dict[str, float]:
    """Device time (ms) of the kernels a profile recorded: all, Warp's (MuJoCo-Warp's physics and the force
    kernels; Warp names its kernels ``<name>_<hash>_cuda_kernel_forward``), of those the heightfield
    collision, and the rest (torch: env logic, policy, update). The profiler does not record the kernels of a CUDA
    graph's conditional nodes, where MuJoCo-Warp runs the constraint solver's iterations: a lower bound."""
    kernels = [e for e in prof.events() if e.device_type == torch.autograd.DeviceType.CUDA]
    total = sum(e.device_time_total for e in kernels) / 1e3
    warp_kernels = [e for e in kernels if "_cuda_kernel_" in e.name]
    warp_ms = sum(e.device_time_total for e in warp_kernels) / 1e3
    hfield = sum(e.device_time_total for e in warp_kernels if "hfield" in e.name) / 1e3
    return {"total": total, "warp": warp_ms, "hfield": hfield, "torch": total - warp_ms}


def profile(runner, steps: int, out: str, raw_substeps_per_s: float) -> None:
    """torch.profiler over ``steps`` env steps, then over one PPO iteration: prints the operations that take
    the most device (or CPU) time and, on GPU, how the device time splits between Warp and torch; writes a
    Chrome trace of each (chrome://tracing, ui.perfetto.dev): ``out`` and ``out`` with ``_ppo`` added."""
    from pathlib import Path

    from torch.profiler import ProfilerActivity, profile as torch_profile

    env = runner.env
    actions = torch.zeros(env.num_envs, env.num_actions, device=env.device)
    cuda = env.device.startswith("cuda")
    activities = [ProfilerActivity.CPU] + ([ProfilerActivity.CUDA] if cuda else [])
    _sync(env.device)
    with torch_profile(activities=activities) as env_prof:
        with torch.inference_mode():  # as in rsl-rl's rollouts (learn() left the env's buffers inference tensors)
            for _ in range(steps):
                actions.uniform_(-1.0, 1.0)
                env.step(actions)
        _sync(env.device)
    with torch_profile(activities=activities) as ppo_prof:
        runner.learn(1)
        _sync(env.device)
    ppo_out = Path(out).with_name(Path(out).stem + "_ppo" + Path(out).suffix)
    for prof, what, trace in ((env_prof, f"{steps} env steps", out), (ppo_prof, "1 PPO iteration", ppo_out)):
        for sort_by in (["self_cuda_time_total"] if cuda else []) + ["self_cpu_time_total"]:
            print(prof.key_averages().table(sort_by=sort_by, row_limit=15, max_name_column_width=60))
        prof.export_chrome_trace(str(trace))
        print(f"profile: {what} at {env.num_envs} envs -> {trace}")
    if cuda:
        step = {key: value / steps for key, value in gpu_time_split(env_prof).items()}
        iteration = gpu_time_split(ppo_prof)
        print(f"GPU time per env step at {env.num_envs} envs: {step['total']:.2f} ms = Warp (physics, force "
              f"kernels) {step['warp']:.2f} ms, of which heightfield collision {step['hfield']:.2f} ms, + torch "
              f"{step['torch']:.2f} ms; the raw ceiling's physics (standing robots, graph-timed): "
              f"{1e3 * env.num_envs * env.cfg.control.decimation / raw_substeps_per_s:.2f} ms (wall clock)")
        print(f"GPU time per PPO iteration ({runner.cfg['num_steps_per_env']} env steps + update): "
              f"{iteration['total']:.1f} ms = Warp {iteration['warp']:.1f} ms + torch (env logic, policy, update) "
              f"{iteration['torch']:.1f} ms")
        print("GPU times are lower bounds: the profiler does not record the kernels of CUDA-graph conditional nodes, "
              "where MuJoCo-Warp runs the constraint solver's iterations")


def run(task: str, sizes: list[int], device: str, steps: int, iterations: int, check_sync: bool = False,
        profile_out: str | None = None, profile_envs: int | None = None, cuda_graph: str | None = None) -> list[dict]:
    rows = []
    for index, num_envs in enumerate(sizes):
        # GPU memory of the first size only: a later one reuses memory the sizes before it left in the pools
        # (Warp's, the CUDA graphs'), so it would seem to take less than it does alone
        measure_memory = device.startswith("cuda") and index == 0
        env_cfg, _ = task_registry.get_cfgs(task)
        env_cfg.env.num_envs = num_envs
        if cuda_graph is not None:
            env_cfg.sim.cuda_graph = cuda_graph
        free_before = torch.cuda.mem_get_info(device)[0] if measure_memory else 0
        env, _ = task_registry.make_env(task, env_cfg=env_cfg, args=argparse.Namespace(device=device))
        settle(env)
        raw = raw_physics(env, steps * env.cfg.control.decimation)
        forces_share = forces_slowdown = soles_share = float("nan")
        if env.forces is not None:
            substeps = steps * env.cfg.control.decimation
            with_forces = raw_physics(env, substeps, with_forces=True)
            forces_slowdown = 1.0 - with_forces / raw  # negative when noise makes the run with forces faster
            soles_share = with_forces / force_kernels_per_s(env, substeps, only_sole_contacts=True) \
                if env.forces.npt else 0.0
            forces_share = with_forces / force_kernels_per_s(env, substeps) - soles_share
        forward_s = 1.0 / reset_forward_per_s(env, steps)
        stepped = env_steps(env, steps, check_sync)
        profiled = profile_out and num_envs == (profile_envs or sizes[-1])
        ppo = update_share = float("nan")
        runner = None
        if iterations > 0 or profiled:
            runner, train_cfg = _runner(env, task)
            if check_sync and iterations > 0:
                points = ppo_sync_points(runner)
                print(f"PPO iteration at {num_envs} envs: {sum(points.values())} host-device syncs"
                      + "".join(f"\n  {count:4d} x {where}" for where, count in points.most_common()))
            if iterations > 0:
                ppo, update_share = ppo_steps(runner, train_cfg, iterations)
            if profiled:
                profile(runner, 10, profile_out, raw)
        ceiling = raw / env.cfg.control.decimation
        memory = (free_before - torch.cuda.mem_get_info(device)[0]) / 2**30 if measure_memory else float("nan")
        rows.append({"num_envs": num_envs, "raw_substeps_per_s": raw, "env_steps_per_s": stepped,
                     "ppo_steps_per_s": ppo, "env_over_raw": stepped / ceiling, "ppo_over_raw": ppo / ceiling,
                     "ppo_update_share": update_share, "forces_share": forces_share, "soles_share": soles_share,
                     "forces_slowdown": forces_slowdown, "reset_forward_share": forward_s * stepped / num_envs,
                     "gpu_memory_gib": memory, "decimation": env.cfg.control.decimation})
        del env, runner  # the runner holds the env: free both before the next size is built
        if device.startswith("cuda"):
            torch.cuda.empty_cache()
    return rows


def print_table(rows: list[dict], device: str) -> None:
    name = torch.cuda.get_device_name(device) if device.startswith("cuda") else "CPU"
    print(f"\ndevice: {name}")
    header = (f"{'num_envs':>9} {'raw substeps/s':>15} {'env steps/s':>12} {'PPO steps/s':>12} {'env/raw':>8} "
              f"{'PPO/raw':>8} {'update':>7} {'forces':>7} {'soles':>7} {'forces Δ':>8} {'forward':>8} {'GPU GiB':>8}")
    print(header)
    print("-" * len(header))
    for r in rows:
        print(f"{r['num_envs']:>9d} {r['raw_substeps_per_s']:>15,.0f} {r['env_steps_per_s']:>12,.0f} "
              f"{r['ppo_steps_per_s']:>12,.0f} {r['env_over_raw']:>8.2f} {r['ppo_over_raw']:>8.2f} "
              f"{r['ppo_update_share']:>7.1%} "
              f"{r['forces_share']:>7.1%} {r['soles_share']:>7.1%} {r['forces_slowdown']:>8.1%} {r['reset_forward_share']:>8.1%} "
              f"{r['gpu_memory_gib']:>8.2f}")
    print("raw: mjw.step substeps/s; raw ceiling in env steps/s = raw / decimation (the ratios' denominator);\n"
          "update: the PPO update's share of the PPO time (the rest is collection: policy + env steps);\n"
          "forces: the terrain force kernels' time (soil, water, ground friction, ruts) as a share of a substep\n"
          "  with them (nan: terrain has none); soles: the analytic sole contacts' (the feet's terrain collision,\n"
          "  in raw too), apart from forces;\n"
          "forces Δ: how much slower the physics substep is with the force fields on (kernels + changed contacts);\n"
          f"forward: the post-reset forward's share of an env step (it runs every step on a GPU), {RESET_SHARE:.0%} of\n"
          "  the worlds reset;\n"
          "GPU GiB: device memory the first size took (later sizes reuse pooled memory: run each alone to measure it)")


def main(argv=None) -> None:
    parser = Parser(prog="gente-benchmark", description="legged_gente throughput benchmark")
    parser.add_argument("--task", default="gente_biped_flat")
    parser.add_argument(*flag("--num_envs"), type=int, nargs="+", default=[1024, 4096, 8192])
    parser.add_argument("--device", default=None)
    parser.add_argument("--steps", type=int, default=100, help="policy steps timed per measurement")
    parser.add_argument("--iterations", type=int, default=3, help="PPO iterations timed (0 skips PPO)")
    parser.add_argument(*flag("--terrain_build"), action="store_true", help="also time the terrain grid build")
    parser.add_argument("--csv", help="also write the table to this CSV file")
    parser.add_argument(*flag("--check_sync"), action="store_true",
                        help="CUDA: fail if LeggedRobot.step waits for the device anywhere (torch sync debug mode); "
                             "list where a PPO iteration does")
    parser.add_argument("--profile", metavar="TRACE_JSON",
                        help="also profile 10 env steps, then 1 PPO iteration (torch.profiler): print the costliest "
                             "operations and, on GPU, the Warp / torch split of the device time; write the env "
                             "steps' Chrome trace here, the PPO iteration's beside it (name + _ppo)")
    parser.add_argument(*flag("--cuda_graph"), choices=CUDA_GRAPH_MODES,
                        help="override the task's cfg.sim.cuda_graph (what one CUDA graph records on GPU)")
    parser.add_argument(*flag("--profile_envs"), type=int, help="the num_envs to profile at (default: the last of --num_envs)")
    add_verbose(parser)
    args = parser.parse_args(argv)
    quiet_third_party(args.verbose)
    try:
        args.device = resolve_device(args.device)
    except ValueError as error:
        parser.error(str(error))
    if any(n < 1 for n in args.num_envs):
        parser.error("--num_envs values must be >= 1")
    if args.steps < 1 or args.iterations < 0:
        parser.error(f"--steps {args.steps} must be >= 1 and --iterations {args.iterations} >= 0 (0 skips PPO)")
    if args.profile_envs is not None and not args.profile:
        parser.error("--profile_envs picks the num_envs that --profile profiles; add --profile TRACE_JSON or leave it "
                     "out")
    if args.profile_envs is not None and args.profile_envs not in args.num_envs:
        parser.error(f"--profile_envs {args.profile_envs} is not one of --num_envs {args.num_envs}")
    if args.check_sync and not args.device.startswith("cuda"):
        parser.error("--check_sync needs a CUDA device (--device cuda)")
    if args.terrain_build:
        from legged_gente.terrain.benchmark import benchmark_grid, describe

        print(describe(benchmark_grid()), flush=True)
    run_command("gente-benchmark", measure, args)


def measure(args: argparse.Namespace) -> None:
    """Run the benchmark the flags ask for; print its table and write its CSV."""
    for name, path in (("--csv", args.csv), ("--profile", args.profile)):
        if path:
            check_output(path, name, folder=False)
    rows = run(args.task, args.num_envs, args.device, args.steps, args.iterations, args.check_sync, args.profile,
               args.profile_envs, args.cuda_graph)
    if args.check_sync:
        print("check_sync: no host-device synchronisation in LeggedRobot.step")
    print_table(rows, args.device)
    if args.csv:
        write_rows(args.csv, rows)


if __name__ == "__main__":
    main()
