"""tools/check_cuda_graphs.py --device: every check runs on the device given. The env and evaluation checks ran on
"cuda" whatever --device said, so `--device cpu` without --ppo_only ended in Warp's traceback after the PPO checks
(on the CPU nothing is captured or compiled: the runs agree, which checks the check itself)."""

import sys

import pytest


@pytest.fixture(scope="module")
def tool(load_file):
    return load_file("tools/check_cuda_graphs.py")


def test_the_env_and_evaluation_checks_run_on_the_device_given(tool, monkeypatch, capsys):
    monkeypatch.setattr(tool, "check_ppo", lambda *args, **kwargs: True)
    monkeypatch.setattr(tool, "check_critic_warmup", lambda *args, **kwargs: True)
    devices = []
    monkeypatch.setattr(tool, "evaluation_agrees", lambda task, **kwargs: devices.append(kwargs.get("device")) or True)
    monkeypatch.setattr(sys, "argv", ["check_cuda_graphs.py", "--device", "cpu", "--num_envs", "2", "--steps", "2"])
    tool.main()
    out = capsys.readouterr().out
    assert devices == ["cpu"]
    assert "the env step agrees across graph and compile modes" in out and "all checks agree" in out
