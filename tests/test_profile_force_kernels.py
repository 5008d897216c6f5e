"""tools/profile_force_kernels.py needs a GPU: without one it says so in one line."""

import os
import subprocess
import sys
from pathlib import Path

TOOL = Path(__file__).resolve().parents[1] / "tools" / "profile_force_kernels.py"


def test_without_a_gpu_it_says_what_it_needs():
    env = dict(os.environ, CUDA_VISIBLE_DEVICES="")  # no GPU visible, whatever the machine has
    out = subprocess.run([sys.executable, str(TOOL), "--num_envs", "2"], capture_output=True, text=True, env=env)
    assert out.returncode == 2
    assert "need a CUDA device" in out.stderr and "Traceback" not in out.stderr
