"""Physics time of a task with the terrain force fields on and off, and MuJoCo's heightfield collision's share
of it, on the device given (made for the CPU, where the torch profiler does not see Warp's kernels).

The env is built and settled as gente-benchmark does; then, from the same standing state each time (restored
before each block of substeps), the minimum over interleaved repetitions of:
  step, forces on:   mjw.step with the force callbacks and the after-substep kernels (and their observation
                     once per policy step: after every decimation-th substep)
  step, forces off:  mjw.step without them (the contact filter kept where it makes the soles' contacts)
  collision:         mjw.collision alone (broad- and narrow-phase and the contact filter)
  ... no terrain:    the same on a copy of the model whose terrain geom collides with nothing (contype =
                     conaffinity = 0 before mjw.put_model, which filters the geom pairs), the analytic sole
                     contacts still made by the contact filter
The heightfield collision (MuJoCo's, of every other geom) is the difference of the last two. Minima, not means:
the machine may be shared.

    PYTHONPATH=$PWD python tools/forces_cpu_timing.py --task gente_biped --num_envs 4
"""

from __future__ import annotations

import argparse
import copy
import itertools
import time

import mujoco_warp as mjw
import warp as wp

from legged_gente.envs.task_registry import task_registry
from legged_gente.scripts.benchmark import settle


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", default="gente_biped")
    ap.add_argument("--num_envs", type=int, default=4)
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--block", type=int, default=10, help="substeps per timed block")
    ap.add_argument("--repeats", type=int, default=30)
    args = ap.parse_args(argv)
    env_cfg, _ = task_registry.get_cfgs(args.task)
    env_cfg.env.num_envs = args.num_envs
    env, _ = task_registry.make_env(args.task, env_cfg=env_cfg, args=argparse.Namespace(device=args.device))
    settle(env)
    sim, forces = env.sim, env.forces
    m, d = sim.m, sim.d
    qpos, qvel = wp.clone(d.qpos), wp.clone(d.qvel)
    callbacks = (m.callback.passive, m.callback.contactfilter)
    mjm = copy.copy(env.mjm)
    terrain = [g for g in range(mjm.ngeom)
               if mjm.geom_bodyid[g] == 0 and (mjm.geom_contype[g] or mjm.geom_conaffinity[g])]
    mjm.geom_contype[terrain] = mjm.geom_conaffinity[terrain] = 0
    with wp.ScopedDevice(sim.wp_device):
        m_off = mjw.put_model(mjm)
    m_off.callback.contactfilter = callbacks[1]

    def block(fn):
        wp.copy(d.qpos, qpos)
        wp.copy(d.qvel, qvel)
        mjw.forward(m, d)
        wp.synchronize()
        start = time.perf_counter()
        for _ in range(args.block):
            fn()
        wp.synchronize()
        return (time.perf_counter() - start) / args.block

    substeps_on = itertools.count(1)

    def step_on():
        mjw.step(m, d)
        for hook in sim.after_substep:
            hook()
        if next(substeps_on) % env.cfg.control.decimation == 0:
            for hook in sim.after_step:
                hook()

    def set_filter(on):
        m.callback.passive = callbacks[0] if on else None
        m.callback.contactfilter = callbacks[1] if on or (forces is not None and forces.npt) else None

    times = {"step, forces on": [], "step, forces off": [], "collision": [], "collision, no terrain": []}
    for _ in range(args.repeats):
        set_filter(True)
        times["step, forces on"].append(block(step_on))
        set_filter(False)
        times["step, forces off"].append(block(lambda: mjw.step(m, d)))
        set_filter(True)
        times["collision"].append(block(lambda: mjw.collision(m, d)))
        times["collision, no terrain"].append(block(lambda: mjw.collision(m_off, d)))
    set_filter(True)
    best = {k: 1e3 * min(v) for k, v in times.items()}
    hfield = best["collision"] - best["collision, no terrain"]
    print(f"{args.task}, {args.num_envs} envs, {args.device}: minimum of {args.repeats} blocks of {args.block} "
          f"substeps (ms per substep, all worlds)")
    for k, v in best.items():
        print(f"  {k:24s} {v:7.2f}")
    print(f"  forces' cost: {best['step, forces on'] - best['step, forces off']:+.2f} ms "
          f"({best['step, forces on'] / best['step, forces off'] - 1:+.1%}); heightfield collision {hfield:.2f} ms "
          f"= {hfield / best['step, forces on']:.1%} of a substep with forces")


if __name__ == "__main__":
    main()
