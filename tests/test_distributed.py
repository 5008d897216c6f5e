"""Distributed PPO under torchrun on the CPU (gloo, world size 1), and the rank/device/backend rules."""

import os
import subprocess
import sys
from pathlib import Path

import pytest
import torch

from legged_gente.utils import distributed
from legged_gente.utils.args import build_parser, parse_args
from legged_gente.utils.distributed import (GenteOnPolicyRunner, Launch, backend_for, rank_device,
                                            torchrun_launch)

REPO = Path(__file__).resolve().parents[1]


def torchrun_env(monkeypatch, rank, local_rank, world_size):
    for name, value in (("RANK", rank), ("LOCAL_RANK", local_rank), ("WORLD_SIZE", world_size)):
        monkeypatch.setenv(name, str(value))


def test_train_py_under_torchrun_is_distributed_and_saves(tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("RANK", "LOCAL_RANK", "WORLD_SIZE")}
    env.update(GENTE_LOG_ROOT=str(tmp_path), PYTHONUNBUFFERED="1", OMP_NUM_THREADS="1")
    cmd = [sys.executable, "-m", "torch.distributed.run", "--standalone", "--nproc_per_node=1",
           "legged_gente/scripts/train.py", "--task", "gente_biped_flat", "--num_envs", "4",
           "--max_iterations", "1", "--device", "cpu", "--headless", "--seed", "7"]
    out = subprocess.run(cmd, cwd=REPO, env=env, capture_output=True, text=True, timeout=300)
    log = out.stdout + out.stderr
    assert out.returncode == 0, log[-4000:]
    # our runner joined a gloo group as rank 0 of 1, and rsl-rl's learn() took its distributed branch
    assert "[distributed] rank 0/1 (node 0, local 0) on cpu, backend gloo, seed 7\n" in log, log[-4000:]
    assert "Synchronizing parameters for rank 0" in log, log[-4000:]
    checkpoints = list((tmp_path / "gente_biped_flat").glob("*/model_0.pt"))
    assert len(checkpoints) == 1, log[-4000:]
    assert set(torch.load(checkpoints[0], weights_only=False)) >= {"actor_state_dict", "iter"}


def test_torchrun_launch_from_environment():
    assert torchrun_launch({}) is None
    assert torchrun_launch({"RANK": "3", "LOCAL_RANK": "1", "WORLD_SIZE": "4"}) == Launch(3, 1, 4)
    with pytest.raises(ValueError, match=r"\['WORLD_SIZE'\] missing"):
        torchrun_launch({"RANK": "0", "LOCAL_RANK": "0"})
    with pytest.raises(ValueError, match="must be integers"):
        torchrun_launch({"RANK": "a", "LOCAL_RANK": "0", "WORLD_SIZE": "1"})
    with pytest.raises(ValueError, match="need 0 <= RANK < WORLD_SIZE"):
        torchrun_launch({"RANK": "2", "LOCAL_RANK": "0", "WORLD_SIZE": "2"})
    # two hosts of two GPUs: the second host's first process is global rank 2, device index (local rank) 0
    second_host = {"RANK": "2", "LOCAL_RANK": "0", "WORLD_SIZE": "4", "LOCAL_WORLD_SIZE": "2", "GROUP_RANK": "1"}
    assert torchrun_launch(second_host) == Launch(rank=2, local_rank=0, world_size=4, node=1)
    with pytest.raises(ValueError, match="LOCAL_RANK < LOCAL_WORLD_SIZE"):
        torchrun_launch({**second_host, "LOCAL_RANK": "2"})


def test_rank_device_and_backend(monkeypatch):
    launch = Launch(rank=1, local_rank=1, world_size=2)
    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    assert rank_device(None, launch) == "cuda:1"
    assert rank_device("cuda", launch) == "cuda:1"
    assert rank_device("cuda:1", launch) == "cuda:1"
    assert rank_device("cpu", launch) == "cpu"
    with pytest.raises(ValueError, match="'cuda:0' does not belong to torchrun LOCAL_RANK 1"):
        rank_device("cuda:0", launch)
    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    assert rank_device(None, launch) == "cpu"
    assert backend_for("cuda:1") == "nccl"
    assert backend_for("cpu") == "gloo"
    with pytest.raises(ValueError, match="no distributed backend for device 'mps'"):
        backend_for("mps")


def test_parse_args_under_torchrun(monkeypatch):
    torchrun_env(monkeypatch, 1, 1, 2)
    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    monkeypatch.setattr(torch.cuda, "device_count", lambda: 2)  # parse_args checks the device is there
    assert parse_args(build_parser("t"), ["--device", "cuda"]).device == "cuda:1"
    assert parse_args(build_parser("t"), []).device == "cuda:1"
    assert parse_args(build_parser("t"), ["--device", "cpu"]).device == "cpu"
    with pytest.raises(SystemExit):
        parse_args(build_parser("t"), ["--device", "cuda:0"])


def test_runner_rejects_a_device_of_another_rank(monkeypatch):
    torchrun_env(monkeypatch, 1, 1, 2)
    with pytest.raises(ValueError, match="'cuda:0' does not belong to torchrun LOCAL_RANK 1"):
        GenteOnPolicyRunner(None, {"seed": 1, "algorithm": {}}, device="cuda:0")  # fails before the env or a process group
    assert not torch.distributed.is_initialized()


def test_runner_multi_gpu_cfg_and_rank_seed(monkeypatch):
    """Rank 1 of 2 on the CPU: rsl-rl's multi_gpu keys, gloo, seed + rank (the group itself is faked)."""
    torchrun_env(monkeypatch, 1, 1, 2)
    calls = []
    monkeypatch.setattr(distributed, "init_process_group", lambda launch, device: calls.append((launch, device))
                        or backend_for(device))
    runner = GenteOnPolicyRunner.__new__(GenteOnPolicyRunner)
    runner.cfg, runner.device = {"seed": 5}, "cpu"
    with torch.random.fork_rng():
        runner._configure_multi_gpu()
        assert torch.initial_seed() == 6
    assert runner.is_distributed and calls == [(Launch(1, 1, 2), "cpu")]
    assert runner.cfg["multi_gpu"] == {"global_rank": 1, "local_rank": 1, "world_size": 2}
    assert runner.cfg["seed"] == 6


def test_nccl_group_keeps_nvlink_multicast_off(monkeypatch):
    """The NCCL path sets NCCL_NVLS_ENABLE=0 before it initialises the group (NCCL itself is faked)."""
    for name in ("NCCL_NVLS_ENABLE", "TORCH_SYMM_MEM_DISABLE_MULTICAST"):
        monkeypatch.setenv(name, "")  # recorded, so the teardown removes what the code under test sets
        monkeypatch.delenv(name)
    seen = {}

    def fake_init(backend, rank, world_size, device_id=None):
        seen.update(backend=backend, rank=rank, world_size=world_size, device_id=device_id,
                    nvls=os.environ.get("NCCL_NVLS_ENABLE"))

    monkeypatch.setattr(torch.distributed, "is_initialized", lambda: False)
    monkeypatch.setattr(torch.distributed, "init_process_group", fake_init)
    monkeypatch.setattr(torch.cuda, "set_device", lambda device: None)
    monkeypatch.setattr(distributed.atexit, "register", lambda fn: None)
    assert distributed.init_process_group(Launch(0, 0, 2), "cuda:0") == "nccl"
    assert seen == {"backend": "nccl", "rank": 0, "world_size": 2, "device_id": torch.device("cuda:0"), "nvls": "0"}
    assert os.environ["TORCH_SYMM_MEM_DISABLE_MULTICAST"] == "1"


def test_multi_gpu_report_reads_rsl_rl_logs(tmp_path):
    """tools/multi_gpu_report.py: mean steps/s after the skipped iterations, their ratio, the CSV."""
    def log(path, steps_per_second, rewards):
        lines = []
        for i, (sps, reward) in enumerate(zip(steps_per_second, rewards)):
            lines += [f"\x1b[1m   Learning iteration {i}/1000 \x1b[0m", f"   Steps per second: {sps}",
                      f"   Mean reward: {reward}", "   Mean episode length: 100.0"]
        path.write_text("\n".join(lines) + "\n")

    log(tmp_path / "1.log", [10, 100, 100, 100], [0.1, 1.0, 2.0, 3.0])
    log(tmp_path / "2.log", [10, 180, 200, 190], [0.2, 1.5, 2.5, 3.5])
    out = subprocess.run([sys.executable, "tools/multi_gpu_report.py", str(tmp_path / "1.log"), str(tmp_path / "2.log"),
                          "--skip", "1", "--csv", str(tmp_path / "runs.csv"), "--plot", str(tmp_path / "runs.png")],
                         cwd=REPO, capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert "throughput ratio 2gpu/1gpu: 1.900" in out.stdout
    assert "common iteration 3: mean reward 3.50" in out.stdout
    rows = (tmp_path / "runs.csv").read_text().splitlines()
    assert rows[0] == "run,iteration,steps_per_second,mean_reward,mean_episode_length" and len(rows) == 9
    assert (tmp_path / "runs.png").stat().st_size > 0
    four = subprocess.run([sys.executable, "tools/multi_gpu_report.py", str(tmp_path / "1.log"), str(tmp_path / "2.log"),
                           "--gpus", "4", "--skip", "1"], cwd=REPO, capture_output=True, text=True, timeout=60)
    assert "throughput ratio 4gpu/1gpu: 1.900" in four.stdout and "4gpu: 4 iterations" in four.stdout
    one = subprocess.run([sys.executable, "tools/multi_gpu_report.py", str(tmp_path / "1.log"), str(tmp_path / "2.log"),
                          "--gpus", "1"], cwd=REPO, capture_output=True, text=True, timeout=60)
    assert one.returncode != 0 and "--gpus 1: the second run trains on 2 or more GPUs" in one.stderr
    short = subprocess.run([sys.executable, "tools/multi_gpu_report.py", str(tmp_path / "1.log"),
                            str(tmp_path / "2.log"), "--skip", "4"], cwd=REPO, capture_output=True, text=True)
    assert short.returncode != 0 and "only 4 iterations logged" in short.stderr


def _stop_vote(rank: int, port: int, results) -> None:
    import signal
    import time
    from types import SimpleNamespace

    import torch.distributed as dist

    from legged_gente.utils.episode_logger import DeferredLogger

    dist.init_process_group("gloo", init_method=f"tcp://127.0.0.1:{port}", rank=rank, world_size=2)
    try:
        # only rank 0 is past its deadline (rank 1 has an hour left); only rank 1 got SIGTERM so far
        logger = SimpleNamespace(deadline=time.monotonic() + (-1.0 if rank == 0 else 3600.0), device="cpu",
                                 stop_signal=None if rank == 0 else signal.SIGTERM)
        results[rank] = DeferredLogger._stop_reason(logger)
    finally:
        dist.destroy_process_group()


def test_a_deadline_or_a_signal_on_one_rank_stops_every_rank_at_the_same_iteration():
    """One rank past --max_minutes' deadline, or signalled, stops them all: a rank that went on would hang in the
    all-reduce."""
    import signal
    import socket

    import torch.multiprocessing as mp

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    results = mp.Manager().dict()
    mp.spawn(_stop_vote, args=(port, results), nprocs=2, join=True)
    assert dict(results) == {0: (True, signal.SIGTERM), 1: (True, signal.SIGTERM)}
