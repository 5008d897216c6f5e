"""A two-node torchrun launch on one CPU host: two torchrun invocations (--nnodes=2, one process each) meet at a
c10d rendezvous on 127.0.0.1 and train one PPO iteration together over gloo, as two hosts would (the c10d
rendezvous numbers the hosts itself: torchrun ignores --node_rank with it, so none is given)."""

import os
import re
import signal
import socket
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
TIMEOUT_S = 300  # both nodes together; one iteration of 2 envs each takes well under a minute on 2 cores


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_two_nodes_train_together_and_only_global_rank_0_logs(tmp_path):
    port = free_port()
    env = {k: v for k, v in os.environ.items() if k not in ("RANK", "LOCAL_RANK", "WORLD_SIZE", "LOCAL_WORLD_SIZE",
                                                            "GROUP_RANK", "MASTER_ADDR", "MASTER_PORT")}
    env.update(PYTHONUNBUFFERED="1", OMP_NUM_THREADS="1", GLOO_SOCKET_IFNAME="lo")
    nodes = []
    for host in (0, 1):
        # each "host" has its own log folder, as two machines without a shared filesystem would
        log_root = tmp_path / f"host{host}"
        cmd = [sys.executable, "-m", "torch.distributed.run", "--nnodes=2", "--nproc_per_node=1", "--rdzv_backend=c10d", f"--rdzv_endpoint=127.0.0.1:{port}",
               "--rdzv_id=gente_two_nodes", "--max_restarts=0", "-m", "legged_gente.scripts.train",
               "--task=gente_biped_flat", "--device=cpu", "--num_envs=2", "--max_iterations=1", "--headless",
               "--seed=7"]
        out = open(tmp_path / f"host{host}.log", "w")
        nodes.append((subprocess.Popen(cmd, cwd=REPO, env={**env, "GENTE_LOG_ROOT": str(log_root)}, stdout=out,
                                       stderr=subprocess.STDOUT, start_new_session=True), log_root, out))
    try:
        codes = [process.wait(timeout=TIMEOUT_S) for process, _, _ in nodes]
    finally:
        for process, _, out in nodes:
            if process.poll() is None:
                os.killpg(process.pid, signal.SIGKILL)
            out.close()
    logs = [(tmp_path / f"host{n}.log").read_text() for n in (0, 1)]
    assert codes == [0, 0], "\n\n".join(log[-3000:] for log in logs)

    # the rendezvous numbers the hosts (GROUP_RANK) in its own order; find which host got global rank 0
    ranks = [re.search(r"\[distributed\] rank (\d)/2 \(node (\d), local 0\) on cpu, backend gloo, seed (\d+)", log)
             for log in logs]
    assert all(ranks), "\n\n".join(log[-3000:] for log in logs)
    by_rank = sorted((int(m[1]), int(m[2]), int(m[3]), host) for host, m in enumerate(ranks))
    assert [(rank, node, seed) for rank, node, seed, _ in by_rank] == [(0, 0, 7), (1, 1, 8)]  # seed + global rank
    first, second = by_rank[0][3], by_rank[1][3]
    assert "Synchronizing parameters for rank 1" in logs[second]  # rsl-rl broadcast rank 0's networks
    assert "logs on rank 0" in logs[second] and "Logging to" not in logs[second]
    # only global rank 0 writes a run folder: config, TensorBoard events, the checkpoint
    run = list((tmp_path / f"host{first}" / "gente_biped_flat").glob("*/model_0.pt"))
    assert len(run) == 1 and (run[0].parent / "config.json").is_file()
    assert not (tmp_path / f"host{second}").exists()
