"""A/B of the quadruped's rut legs' after-substep kernels in a branch of their own beside the feet's (the working
tree, as 2ce4de2 first had it) against one after the other (75457ac), in one process: the benchmark's force-kernel
measure, then rounds alternating the two, then the feet's and the rut legs' state after one pass of each from the
same state."""
import argparse
import json
import time
import types

import warp as wp

from legged_gente.envs.task_registry import task_registry
from legged_gente.scripts import benchmark as B


def serial_after_substep(self):
    """75457ac's order: the feet's normal forces and state, then the rut legs'."""
    load_alpha = min(self.dt / float(self.cfg.sinkage_load_tau), 1.0)
    self._feet_state(load_alpha)
    self._legs_state(load_alpha)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--task", default="gente_quadruped")
    p.add_argument("--num_envs", type=int, default=8192)
    p.add_argument("--rounds", type=int, default=4)
    p.add_argument("--reps", type=int, default=2)
    p.add_argument("--device", default="cuda:0")
    a = p.parse_args()
    t0 = time.time()
    cfg, _ = task_registry.get_cfgs(a.task)
    cfg.env.num_envs = a.num_envs
    env, _ = task_registry.make_env(a.task, env_cfg=cfg, args=argparse.Namespace(device=a.device))
    B.settle(env)
    f, sim = env.forces, env.sim
    assert f.has_rut_legs, "this A/B needs rut legs"
    print(f"{a.task}: built and settled in {time.time() - t0:.0f} s; {f.nleg} rut legs", flush=True)
    substeps = 100 * env.cfg.control.decimation
    for r in range(a.reps):
        wf = B.raw_physics(env, substeps, with_forces=True)
        soles = wf / B.force_kernels_per_s(env, substeps, only_sole_contacts=True)
        forces = wf / B.force_kernels_per_s(env, substeps) - soles
        print(json.dumps(dict(label="beside", rep=r, with_forces=wf, forces_share=forces, soles_share=soles,
                              forces_us=forces * 1e6 * a.num_envs / wf)), flush=True)
    soles_per_s = B.force_kernels_per_s(env, substeps, only_sole_contacts=True)
    parallel = f.after_substep
    serial = types.MethodType(serial_after_substep, f)
    for r in range(a.rounds):
        for name, fn in (("one after the other (75457ac)", serial), ("beside (2ce4de2)", parallel)):
            f.after_substep = fn
            per_s = B.force_kernels_per_s(env, substeps)
            print(f"[round {r}] {name:30s} force pass minus soles "
                  f"{1e6 * env.num_envs * (1 / per_s - 1 / soles_per_s):6.2f} us per substep", flush=True)
    state = {}
    with wp.ScopedDevice(sim.wp_device), sim.substep_state_kept():
        kept = [wp.clone(x) for x in f.per_world_state()]
        for name, fn in (("serial", serial), ("parallel", parallel)):
            for x, k in zip(f.per_world_state(), kept):
                wp.copy(x, k)
            f.after_substep = fn
            B.force_pass(env)()
            wp.synchronize()
            state[name] = [wp.to_torch(x).clone().double() for x in f.per_world_state()]
        for x, k in zip(f.per_world_state(), kept):
            wp.copy(x, k)
    f.after_substep = parallel
    diff = max((x - y).abs().max().item() for x, y in zip(state["serial"], state["parallel"]))
    print(f"per-world force state after one force pass each way: max |serial - parallel| {diff:.3g} "
          f"over {len(kept)} arrays", flush=True)


if __name__ == "__main__":
    main()
