"""README's "From Python": its code block runs as written (from a folder of its own), and a script trains as the
paragraph after it says."""

import re
import subprocess
import sys
from pathlib import Path

import torch

from legged_gente.envs.task_registry import task_registry

README = Path(__file__).resolve().parents[1] / "README.md"


def from_python_block() -> str:
    section = README.read_text().split("### From Python", 1)[1].split("\n## ", 1)[0]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_the_readme_block_runs_as_written(tmp_path):
    script = from_python_block() + (
        "\nassert actions.shape == (4, env.num_actions) and torch.isfinite(actions).all()"
        "\nassert rewards.shape == dones.shape == (4,) and path.is_file()"
        "\nprint('walked', float(env.base_lin_vel[:, 0].mean()))\n")
    (tmp_path / "mine.py").write_text(script)
    done = subprocess.run([sys.executable, "mine.py"], cwd=tmp_path, capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "walked" in done.stdout and "load on device" not in done.stdout + done.stderr  # quiet_third_party


def test_a_script_trains_as_the_readme_says(tmp_path):
    env_cfg, train_cfg = task_registry.get_cfgs("gente_biped_flat")
    env_cfg.env.num_envs = 2
    train_cfg.runner.num_steps_per_env = 4
    env, env_cfg = task_registry.make_env("gente_biped_flat", env_cfg=env_cfg, device="cpu")
    runner, train_cfg, log_dir = task_registry.make_alg_runner(env, "gente_biped_flat", train_cfg=train_cfg,
                                                              log_root=tmp_path)
    runner.learn(1, init_at_random_ep_len=True)
    assert Path(log_dir).parent.parent == tmp_path and list(Path(log_dir).glob("model_*.pt"))
    assert env.device == "cpu" and torch.isfinite(env.obs_buf["policy"]).all()
