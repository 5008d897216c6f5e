"""A/B of the feet's cells found beside the contact filter (parallel branches; the working tree) against one after
the other (`75d30b2`), in one process at 8192 robots: the benchmark's force-kernel measure three times, then rounds
alternating the two, then the contacts and the feet's state from one pass of each on the same state."""
import argparse
import json
import time

import torch
import warp as wp

from legged_gente.scripts import benchmark as B
from legged_gente.envs.task_registry import task_registry


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--task", default="gente_biped")
    p.add_argument("--num_envs", type=int, default=8192)
    p.add_argument("--rounds", type=int, default=4)
    p.add_argument("--device", default="cuda:0")
    p.add_argument("--reps", type=int, default=3)
    a = p.parse_args()
    t0 = time.time()
    cfg, _ = task_registry.get_cfgs(a.task)
    cfg.env.num_envs = a.num_envs
    env, _ = task_registry.make_env(a.task, env_cfg=cfg, args=argparse.Namespace(device=a.device))
    B.settle(env)
    f, sim = env.forces, env.sim
    print(f"{a.task}: built and settled in {time.time() - t0:.0f} s; feet_apart_from_filter {f.feet_apart_from_filter}",
          flush=True)
    substeps = 100 * env.cfg.control.decimation
    for r in range(a.reps):
        raw = B.raw_physics(env, substeps)
        wf = B.raw_physics(env, substeps, with_forces=True)
        soles = wf / B.force_kernels_per_s(env, substeps, only_sole_contacts=True)
        forces = wf / B.force_kernels_per_s(env, substeps) - soles
        print(json.dumps(dict(label="beside", rep=r, raw=raw, with_forces=wf, forces=forces, soles=soles,
                              forces_us=forces * 1e6 * a.num_envs / wf)), flush=True)
    soles_per_s = B.force_kernels_per_s(env, substeps, only_sole_contacts=True)
    for r in range(a.rounds):
        for name, beside in (("one after the other (before)", False), ("beside (after)", True)):
            f.feet_apart_from_filter = beside
            per_s = B.force_kernels_per_s(env, substeps)
            us = 1e6 * env.num_envs * (1 / per_s - 1 / soles_per_s)
            print(f"[round {r}] {name:30s} force pass minus soles {us:6.2f} us per substep", flush=True)
    out = {}
    import mujoco_warp as mjw
    with wp.ScopedDevice(sim.wp_device), sim.substep_state_kept():
        for beside in (False, True):  # MuJoCo-Warp's collision with the filter and the sole contacts, on one state
            f.feet_apart_from_filter = beside
            mjw.collision(sim.m, sim.d)
            wp.synchronize()
            n = int(sim.d.nacon.numpy()[0])
            c = sim.d.contact
            out[beside] = [wp.to_torch(x)[:n].clone() for x in (c.dist, c.friction, c.dim, c.geom)] + [
                wp.to_torch(x).clone() for x in (f.foot_touch, f.foot_cand, f.foot_inrut, f.foot_soil)]
            print(f"feet_apart_from_filter {beside}: {n} contacts", flush=True)
    f.feet_apart_from_filter = True
    # the contacts' order may differ (atomic slots): compare sorted values
    diffs = [(torch.sort(x.flatten().double())[0] - torch.sort(y.flatten().double())[0]).abs().max().item()
             for x, y in zip(out[False], out[True])]
    print("contacts (dist, friction, dim, geom) and feet (touch, cand, inrut, soil): max |before - after| "
          + ", ".join(f"{d:.3g}" for d in diffs), flush=True)


if __name__ == "__main__":
    main()
