"""gente-benchmark end to end on the CPU with tiny sizes: a well-formed table and CSV."""

import csv
import functools

import pytest
import torch

from legged_gente.scripts import benchmark


def test_benchmark_prints_and_writes_a_table(tmp_path, capsys):
    out = tmp_path / "new" / "bench.csv"  # its folder is made
    benchmark.main(["--task", "gente_biped_flat", "--num_envs", "2", "3", "--steps", "2", "--iterations", "1",
                    "--device", "cpu", "--csv", str(out)])
    printed = capsys.readouterr().out
    assert "device: CPU" in printed and "raw substeps/s" in printed
    rows = list(csv.DictReader(open(out)))
    assert [int(r["num_envs"]) for r in rows] == [2, 3]
    for r in rows:
        for key in ("raw_substeps_per_s", "env_steps_per_s", "ppo_steps_per_s"):
            assert float(r[key]) > 0.0
        assert float(r["env_over_raw"]) == float(r["env_steps_per_s"]) / (float(r["raw_substeps_per_s"]) / 4)
        assert 0.0 < float(r["ppo_update_share"]) < 1.0


def test_terrain_build_prints_its_time(monkeypatch, capsys):
    """--terrain_build prints the grid build's time (the env benchmark itself is skipped here)."""
    from legged_gente.terrain import benchmark as terrain_benchmark

    cols = len(terrain_benchmark.BENCHMARK_TYPES)  # every type gets a column: none is left unbuilt
    small = functools.partial(terrain_benchmark.benchmark_grid, num_rows=2, num_cols=cols, tile_size=2.0, repeats=1)
    monkeypatch.setattr(terrain_benchmark, "benchmark_grid", small)
    monkeypatch.setattr(benchmark, "run", lambda *args: [{}])
    monkeypatch.setattr(benchmark, "print_table", lambda rows, device: None)
    benchmark.main(["--num_envs", "2", "--device", "cpu", "--terrain_build"])
    assert f"terrain build: 2 x {cols} tiles of 2.0 m at 0.1 m" in capsys.readouterr().out


def test_force_kernels_are_timed_on_a_terrain_with_materials(capsys):
    rows = benchmark.run("gente_biped", [3], "cpu", steps=2, iterations=0)
    assert 0.0 < rows[0]["forces_share"] < 1.0
    assert -1.0 < rows[0]["forces_slowdown"] < 1.0  # a difference of two noisy timings: not clamped at 0
    assert 0.0 < rows[0]["reset_forward_share"] < 1.0  # one forward costs less than a step of 4 substeps


def test_the_reset_forward_timing_leaves_the_integrated_force_state_as_it_was():
    import argparse

    from legged_gente.envs.task_registry import task_registry

    cfg, _ = task_registry.get_cfgs("gente_biped")
    cfg.env.num_envs = 3
    env, _ = task_registry.make_env("gente_biped", env_cfg=cfg, args=argparse.Namespace(device="cpu"))
    benchmark.settle(env, 0.1)
    assert env.sim.substep_state, "the curriculum's force fields integrate state (ruts, slip)"
    before = [t.clone() for t in env.sim.substep_state]
    assert benchmark.reset_forward_per_s(env, 2) > 0.0
    assert all(torch.equal(t, old) for t, old in zip(env.sim.substep_state, before))


def test_raw_physics_measures_from_and_returns_to_the_settled_state():
    import argparse

    from legged_gente.envs.task_registry import task_registry

    cfg, _ = task_registry.get_cfgs("gente_biped_flat")
    cfg.env.num_envs = 2
    env, _ = task_registry.make_env("gente_biped_flat", env_cfg=cfg, args=argparse.Namespace(device="cpu"))
    benchmark.settle(env)
    qpos, qvel = env.sim.qpos.clone(), env.sim.qvel.clone()
    assert (qpos[:, 2] > 0.8).all()  # landed and standing, not lying on the ground
    assert benchmark.raw_physics(env, benchmark.RESTORE_EVERY * env.cfg.control.decimation, with_forces=True) > 0.0
    assert torch.equal(env.sim.qpos, qpos) and torch.equal(env.sim.qvel, qvel)


def test_profile_prints_the_costliest_operations_and_writes_a_trace(tmp_path, capsys):
    import json

    trace = tmp_path / "trace.json"
    benchmark.main(["--task", "gente_biped_flat", "--num_envs", "2", "--steps", "1", "--iterations", "0",
                    "--device", "cpu", "--profile", str(trace)])
    printed = capsys.readouterr().out
    assert "Self CPU" in printed and "aten::" in printed
    assert json.load(open(trace))["traceEvents"]
    assert json.load(open(tmp_path / "trace_ppo.json"))["traceEvents"]  # the PPO iteration's
    assert "profile: 10 env steps at 2 envs" in printed and "profile: 1 PPO iteration at 2 envs" in printed


def test_cuda_graph_override_reaches_the_env_config(monkeypatch):
    """--cuda_graph sets cfg.sim.cuda_graph of the env it builds (on the CPU the graphs are off anyway)."""

    from legged_gente.envs.task_registry import task_registry

    seen = []
    make_env = task_registry.make_env

    def recording_make_env(name, env_cfg=None, args=None):
        seen.append(env_cfg.sim.cuda_graph)
        return make_env(name, env_cfg=env_cfg, args=args)

    monkeypatch.setattr(task_registry, "make_env", recording_make_env)
    benchmark.run("gente_biped_flat", [2], "cpu", steps=1, iterations=0, cuda_graph="physics")
    assert seen == ["physics"]
    with pytest.raises(SystemExit):
        benchmark.main(["--num_envs", "2", "--device", "cpu", "--cuda_graph", "always"])


def test_gpu_time_split_sorts_kernels_into_warp_and_torch():
    from types import SimpleNamespace

    cuda, cpu = torch.autograd.DeviceType.CUDA, torch.autograd.DeviceType.CPU
    events = [SimpleNamespace(name="ccd_hfield_kernel_builder__locals__ccd_hfield_kernel_3a0a_cuda_kernel_forward",
                              device_type=cuda, device_time_total=400.0),
              SimpleNamespace(name="_kinematics_branch_95f8028e_cuda_kernel_forward", device_type=cuda,
                              device_time_total=100.0),
              SimpleNamespace(name="void at::native::index_elementwise_kernel<128, 4>", device_type=cuda,
                              device_time_total=50.0),
              SimpleNamespace(name="aten::index", device_type=cpu, device_time_total=50.0)]  # its kernel's time
    split = benchmark.gpu_time_split(SimpleNamespace(events=lambda: events))
    assert split == {"total": 0.55, "warp": 0.5, "hfield": 0.4, "torch": pytest.approx(0.05)}


def test_the_sole_contacts_are_timed_apart_and_the_force_timing_leaves_the_state_as_it_was():
    """The sole contacts alone append one contact per touching sole point, each pass from the same count; the
    force timing leaves the contact count and the integrated force state as they were."""
    import argparse

    import numpy as np
    import warp as wp

    from legged_gente.envs.task_registry import task_registry

    cfg, _ = task_registry.get_cfgs("gente_biped")
    cfg.env.num_envs = 3
    env, _ = task_registry.make_env("gente_biped", env_cfg=cfg, args=argparse.Namespace(device="cpu"))
    benchmark.settle(env, 0.3)
    sim, forces = env.sim, env.forces
    sim.recompute(torch.ones(3, dtype=torch.bool))  # the contacts of the current state
    nacon = int(sim.d.nacon.numpy()[0])
    state = [t.clone() for t in sim.substep_state]
    before = sim.d.contact.geom.numpy()[:nacon].copy()
    soles = before[np.isin(before[:, 1], forces.pt_geom.numpy())]
    assert len(soles) > 0  # the robots stand on their soles
    forces.sole_contacts(sim.m, sim.d)
    added = sim.d.contact.geom.numpy()[nacon:int(sim.d.nacon.numpy()[0])]
    # the same sole contacts again, and nothing else
    assert sorted(map(tuple, added)) == sorted(map(tuple, soles))
    assert set(added[:, 0]) <= set(env.layout.terrain_geoms)
    wp.copy(sim.d.nacon, wp.array([nacon], dtype=int))
    assert benchmark.force_kernels_per_s(env, 3, only_sole_contacts=True) > 0.0
    assert benchmark.force_kernels_per_s(env, 3) > 0.0
    assert int(sim.d.nacon.numpy()[0]) == nacon
    assert (sim.d.contact.geom.numpy()[:nacon] == before).all()
    assert all(torch.equal(t, old) for t, old in zip(sim.substep_state, state))
