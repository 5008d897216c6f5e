"""A/B of the added mass launched per water branch (the working tree) against one launch after both branches (the
code before), in one process at 8192 bipeds: the benchmark's force-kernel measure three times, then rounds alternating
the two, then M from one pass of each on the same state."""
import argparse
import json
import time

import warp as wp

from legged_gente.scripts import benchmark as B
from legged_gente.envs.task_registry import task_registry
from legged_gente.external_forces import field as F


def one_launch_passive(self, m, d):
    """The passive callback as it was: the three branches, then one added-mass launch over all the points."""
    d.xfrc_applied.zero_()
    self._added_mass = lambda *a: None
    try:
        self._in_parallel(lambda: self._feet_water(m, d), lambda: self._legs_water(m, d), lambda: self._soil(m, d))
    finally:
        del self._added_mass
    F.TerrainForces._added_mass(self, m, d, 0, self.point_dofs.shape[0])


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--num_envs", type=int, default=8192)
    p.add_argument("--rounds", type=int, default=4)
    p.add_argument("--device", default="cuda:0")
    a = p.parse_args()
    t0 = time.time()
    cfg, _ = task_registry.get_cfgs("gente_biped")
    cfg.env.num_envs = a.num_envs
    env, _ = task_registry.make_env("gente_biped", env_cfg=cfg, args=argparse.Namespace(device=a.device))
    B.settle(env)
    print(f"built and settled in {time.time() - t0:.0f} s", flush=True)
    substeps = 100 * env.cfg.control.decimation
    for r in range(3):
        raw = B.raw_physics(env, substeps)
        wf = B.raw_physics(env, substeps, with_forces=True)
        soles = wf / B.force_kernels_per_s(env, substeps, only_sole_contacts=True)
        forces = wf / B.force_kernels_per_s(env, substeps) - soles
        print(json.dumps(dict(label="split", rep=r, raw=raw, with_forces=wf, forces=forces, soles=soles,
                              forces_us=forces * 1e6 * a.num_envs / wf)), flush=True)
    new_passive = F.TerrainForces.passive
    soles_per_s = B.force_kernels_per_s(env, substeps, only_sole_contacts=True)
    for r in range(a.rounds):
        for name, passive in (("one launch (before)", one_launch_passive), ("split (after)", new_passive)):
            F.TerrainForces.passive = passive
            per_s = B.force_kernels_per_s(env, substeps)
            us = 1e6 * env.num_envs * (1 / per_s - 1 / soles_per_s)
            print(f"[round {r}] {name:20s} force pass minus soles {us:6.2f} us per substep", flush=True)
    f, sim = env.forces, env.sim
    Ms = {}
    with wp.ScopedDevice(sim.wp_device), sim.substep_state_kept():
        M0 = wp.clone(sim.d.M)
        for name, passive in (("before", one_launch_passive), ("after", new_passive)):
            wp.copy(sim.d.M, M0)
            passive(f, sim.m, sim.d)
            Ms[name] = wp.to_torch(sim.d.M).clone()
        wp.copy(sim.d.M, M0)
    dm = (Ms["before"] - wp.to_torch(M0)).abs().max().item()
    wet = (wp.to_torch(f.point_mass) > 0).sum().item()
    print(f"M: |before - after| max {(Ms['before'] - Ms['after']).abs().max().item():.3g}, added mass max {dm:.3g}, "
          f"wet points {wet} of {tuple(f.point_mass.shape)}", flush=True)
    F.TerrainForces.passive = new_passive


if __name__ == "__main__":
    main()
