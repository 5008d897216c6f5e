"""The force kernels' time per substep at one size, as gente-benchmark measures it, three times; with --variants the
two candidate changes of candidates.patch alone and together (each against the kernels as they were, in one
process: the kernels as they were are read from base/, a copy of the package at 01d963f); with --added_mass the
added-mass kernel against a one-thread-per-point version. Run from a folder holding base/legged_gente."""
import argparse
import json
import sys
import time

import torch
import warp as wp

from legged_gente.scripts import benchmark as B
from legged_gente.envs.task_registry import task_registry
from legged_gente.external_forces import water as W
from legged_gente.external_forces.water import dof_jac


@wp.kernel
def added_mass_point_kernel(
    point_dofs: wp.array2d[int],
    point_geom: wp.array[int],
    point_axes: wp.array[wp.vec3],
    M_rownnz: wp.array[int],
    M_rowadr: wp.array[int],
    geom_xmat: wp.array2d[wp.mat33],
    cdof: wp.array2d[wp.spatial_vector],
    point_mass: wp.array2d[float],
    point_offset: wp.array2d[wp.vec3],
    M: wp.array2d[float],
):
    w, pt = wp.tid()
    scale = point_mass[pt, w]
    if scale <= 0.0:
        return
    rot = geom_xmat[w, point_geom[pt]]
    added = scale * (rot * wp.diag(point_axes[pt]) * wp.transpose(rot))
    rp = point_offset[pt, w]
    nchain = point_dofs.shape[1]
    for n in range(nchain):
        i = point_dofs[pt, n]
        if i < 0:
            break
        aji = added * dof_jac(cdof, w, i, rp)
        rowadr = M_rowadr[i]
        adr = rowadr + M_rownnz[i] - 1
        for k in range(n, nchain):
            j = point_dofs[pt, k]
            if j < 0 or adr < rowadr:
                break
            wp.atomic_add(M, w, adr, wp.dot(aji, dof_jac(cdof, w, j, rp)))
            adr = adr - 1


def graph_us(fn, reps=200):
    fn()
    if not wp.get_device().is_cuda:
        t = time.perf_counter()
        for _ in range(5):
            fn()
        return 1e6 * (time.perf_counter() - t) / 5
    with wp.ScopedCapture() as cap:
        fn()
    for _ in range(5):
        wp.capture_launch(cap.graph)
    wp.synchronize()
    t = time.perf_counter()
    for _ in range(reps):
        wp.capture_launch(cap.graph)
    wp.synchronize()
    return 1e6 * (time.perf_counter() - t) / reps


def variants(env, substeps):
    import importlib.util
    from legged_gente.external_forces import field as F
    spec = importlib.util.spec_from_file_location("water_base", "base/legged_gente/external_forces/water.py")
    old_water = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(old_water)
    new_water = F.W
    f, sim = env.forces, env.sim
    m, d = sim.m, sim.d
    dummy = wp.zeros((f.nworld, 0), dtype=wp.spatial_vector, device=sim.wp_device)
    new_passive = F.TerrainForces.passive

    def zeroing_passive(self, m, d):
        d.xfrc_applied.zero_()
        new_passive(self, m, d)

    def use(water_new, fold_zero):
        F.W = new_water if water_new else old_water
        F.TerrainForces.passive = new_passive if fold_zero else zeroing_passive
        launch = f._recorded_filter(m, d)[0]
        assert launch.kernel is F.K.foot_cell_kernel
        launch.set_param_at_index(13, d.xfrc_applied if fold_zero else dummy)

    soles_per_s = B.force_kernels_per_s(env, substeps, only_sole_contacts=True)
    names = {(False, False): "base-like", (True, False): "A foot water", (False, True): "B xfrc in foot_cell",
             (True, True): "A+B"}
    for r in range(3):
        for key, name in names.items():
            use(*key)
            per_s = B.force_kernels_per_s(env, substeps)
            us = 1e6 * env.num_envs * (1 / per_s - 1 / soles_per_s)
            print(f"[variants] round {r} {name:22s} force pass minus soles {us:6.2f} us per substep", flush=True)
    use(True, True)
    # the two kernels alone
    with wp.ScopedDevice(sim.wp_device), sim.substep_state_kept():
        B.force_pass(env)()
        for block in (64, 128, 256, 512):
            am = lambda: wp.launch(W.added_mass_kernel, dim=(f.nworld, *f.point_dofs.shape), block_dim=block,
                                   inputs=[f.point_dofs, f.point_geom, f.point_axes, m.dof_parentid, m.M_rownnz,
                                           m.M_rowadr, d.geom_xmat, d.cdof, f.point_mass, f.point_offset, d.M])
            print(f"[variants] added mass block_dim {block}: {graph_us(am):.2f} us", flush=True)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("label")
    p.add_argument("--num_envs", type=int, default=8192)
    p.add_argument("--reps", type=int, default=3)
    p.add_argument("--added_mass", action="store_true")
    p.add_argument("--device", default="cuda:0")
    p.add_argument("--variants", action="store_true")
    a = p.parse_args()
    t0 = time.time()
    cfg, _ = task_registry.get_cfgs("gente_biped")
    cfg.env.num_envs = a.num_envs
    env, _ = task_registry.make_env("gente_biped", env_cfg=cfg, args=argparse.Namespace(device=a.device))
    B.settle(env)
    print(f"[{a.label}] built and settled in {time.time() - t0:.0f} s", flush=True)
    substeps = 100 * env.cfg.control.decimation
    for r in range(a.reps):
        raw = B.raw_physics(env, substeps)
        wf = B.raw_physics(env, substeps, with_forces=True)
        soles = wf / B.force_kernels_per_s(env, substeps, only_sole_contacts=True)
        forces = wf / B.force_kernels_per_s(env, substeps) - soles
        print(json.dumps(dict(label=a.label, rep=r, raw=raw, with_forces=wf, forces=forces, soles=soles,
                              forces_us=forces * 1e6 * a.num_envs / wf)), flush=True)
    if a.variants:
        variants(env, substeps)
    if a.added_mass:
        f, sim = env.forces, env.sim
        m, d = sim.m, sim.d
        with wp.ScopedDevice(sim.wp_device), sim.substep_state_kept():
            B.force_pass(env)()  # fills point_mass / point_offset from the current state
            wet = (wp.to_torch(f.point_mass) > 0).sum().item()
            M0 = wp.clone(d.M)
            cur = lambda: wp.launch(W.added_mass_kernel, dim=(f.nworld, *f.point_dofs.shape), inputs=[
                f.point_dofs, f.point_geom, f.point_axes, m.dof_parentid, m.M_rownnz, m.M_rowadr,
                d.geom_xmat, d.cdof, f.point_mass, f.point_offset, d.M])
            alt = lambda: wp.launch(added_mass_point_kernel, dim=(f.nworld, f.point_dofs.shape[0]), inputs=[
                f.point_dofs, f.point_geom, f.point_axes, m.M_rownnz, m.M_rowadr,
                d.geom_xmat, d.cdof, f.point_mass, f.point_offset, d.M])
            wp.copy(d.M, M0); cur(); Ma = wp.to_torch(d.M).clone()
            wp.copy(d.M, M0); alt(); Mb = wp.to_torch(d.M).clone()
            print(f"[{a.label}] wet points {wet} of {f.point_mass.shape}, chain {f.point_dofs.shape}; "
                  f"|M_cur - M_alt| max {(Ma - Mb).abs().max().item():.3g}, |dM| max "
                  f"{(Ma - wp.to_torch(M0)).abs().max().item():.3g}", flush=True)
            for r in range(3):
                print(f"[{a.label}] added mass per launch: current {graph_us(cur):.2f} us, per point "
                      f"{graph_us(alt):.2f} us", flush=True)
            wp.copy(d.M, M0)


if __name__ == "__main__":
    main()
