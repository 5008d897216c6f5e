"""tools/check_cuda_graphs.py's verdicts, on the CPU: any mismatch of the env, the evaluation or PPO (a NaN
difference included) is a mismatch, and a mismatch exits with 1."""

import math
import sys

import numpy as np
import pytest
import torch


@pytest.fixture(scope="module")
def tool(load_file):
    return load_file("tools/check_cuda_graphs.py")


def env_run(reward=1.0, critic_nan=False):
    first = []
    for step in range(3):
        critic = torch.zeros(4, 6)
        if critic_nan and step == 2:
            critic[1, 5] = math.nan  # the last element: Python's max() over [0, 0, nan] would skip it
        first.append((torch.zeros(4, 5), critic, torch.zeros(4)))
    return {"first": first, "reward": torch.full((10,), reward), "resets": torch.zeros(10),
            "level": torch.zeros(10), "episode_length": 10.0, "time": 0.2}


def test_env_runs_agree_only_when_equal(tool):
    assert tool.compare_env_runs({"env_step": env_run(), "physics": env_run()})
    assert not tool.compare_env_runs({"env_step": env_run(critic_nan=True), "physics": env_run()})
    assert not tool.compare_env_runs({"env_step": env_run(reward=1.2), "physics": env_run()})  # 20 % > 10 %
    assert not tool.compare_env_runs({"env_step": env_run(reward=math.nan), "physics": env_run()})
    short = env_run()
    short["first"] = short["first"][:1]
    assert not tool.compare_env_runs({"env_step": short, "physics": env_run()})


def test_largest_counts_nan_as_infinite(tool):
    assert max([0.0, math.nan]) == 0.0  # why the tool does not use max()
    assert tool.largest([0.0, math.nan]) == math.inf and tool.largest([1e-4, 2e-4]) == 2e-4


def evaluation_metrics(diverged=(False, False, False, True), tracking=0.2, distance=1.0, falls=0):
    n = len(diverged)
    return {"diverged": np.array(diverged), "fell": np.arange(n) < falls,
            "tracking_error": np.full(n, tracking), "distance": np.full(n, distance)}


def test_evaluations_agree_only_with_the_same_diverged_robots_and_close_means(tool):
    ref = evaluation_metrics()
    assert tool.compare_evaluations({"graph": evaluation_metrics(tracking=0.21), "plain": ref}, "plain")
    assert not tool.compare_evaluations({"graph": evaluation_metrics(diverged=(True, False, False, False)),
                                         "plain": ref}, "plain")
    assert not tool.compare_evaluations({"graph": evaluation_metrics(distance=1.5), "plain": ref}, "plain")
    assert not tool.compare_evaluations({"graph": evaluation_metrics(tracking=math.nan), "plain": ref}, "plain")


def test_evaluations_agree_on_falls_within_one_robot(tool):
    """Two runs of the same launches on a GPU may part on one robot at the edge of falling (the contacts' order
    differs between runs); two robots are a difference of the launches."""
    ref = evaluation_metrics(falls=1)
    assert tool.compare_evaluations({"graph": evaluation_metrics(falls=0), "plain": ref}, "plain")
    assert tool.compare_evaluations({"graph": evaluation_metrics(falls=2), "plain": ref}, "plain")
    assert not tool.compare_evaluations({"graph": evaluation_metrics(falls=3), "plain": ref}, "plain")
    assert not tool.compare_evaluations({"graph": evaluation_metrics(falls=2), "plain": evaluation_metrics()}, "plain")


@pytest.mark.parametrize("failing", ["check_ppo", "check_critic_warmup", "env_steps", "evaluation_agrees"])
def test_any_mismatch_exits_with_1(tool, monkeypatch, failing):
    for name in ("check_ppo", "check_critic_warmup", "env_steps", "evaluation_agrees"):
        monkeypatch.setattr(tool, name, lambda *args, verdict=(name != failing), **kwargs: verdict)
    monkeypatch.setattr(sys, "argv", ["check_cuda_graphs.py", "--device", "cpu"])
    with pytest.raises(SystemExit) as exit_info:
        tool.main()
    assert exit_info.value.code == 1


def test_all_agreeing_exits_with_0(tool, monkeypatch, capsys):
    for name in ("check_ppo", "check_critic_warmup", "env_steps", "evaluation_agrees"):
        monkeypatch.setattr(tool, name, lambda *args, **kwargs: True)
    monkeypatch.setattr(sys, "argv", ["check_cuda_graphs.py", "--device", "cpu"])
    tool.main()
    assert "all checks agree" in capsys.readouterr().out


def test_the_evaluation_check_runs(tool):
    """The GPU check's evaluation part end to end on the CPU (where every run steps plainly, so they agree)."""
    assert tool.evaluation_agrees("gente_biped", robots_per_terrain=2, episode_s=0.2, device="cpu")


def test_the_critic_warmup_check_runs(tool):
    """The GPU check's critic warm-up part on the CPU: two held updates leave the actor and the learning rate
    alone, the third moves the actor."""
    assert tool.check_critic_warmup("cpu", 64)


@pytest.mark.parametrize("flag, runs, skipped", [
    ("--env_only", {"env_steps", "evaluation_agrees"}, {"check_ppo", "check_critic_warmup"}),
    ("--ppo_only", {"check_ppo", "check_critic_warmup"}, {"env_steps", "evaluation_agrees"}),
])
def test_only_flags_run_their_checks_alone(tool, monkeypatch, capsys, flag, runs, skipped):
    called = set()
    for name in runs | skipped:
        monkeypatch.setattr(tool, name, lambda *args, name=name, **kwargs: called.add(name) or True)
    monkeypatch.setattr(sys, "argv", ["check_cuda_graphs.py", "--device", "cpu", flag])
    tool.main()
    assert called == runs and "all checks agree" in capsys.readouterr().out


def test_only_flags_exclude_each_other(tool, monkeypatch):
    monkeypatch.setattr(sys, "argv", ["check_cuda_graphs.py", "--env_only", "--ppo_only"])
    with pytest.raises(SystemExit) as exit_info:
        tool.main()
    assert exit_info.value.code == 2
