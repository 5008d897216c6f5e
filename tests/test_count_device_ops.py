"""tools/count_device_ops.py on the CPU: the post-reset forward copies the force fields' state as one array."""

import argparse

import pytest
import torch
import warp as wp


@pytest.fixture(scope="module")
def tool(load_file):
    return load_file("tools/count_device_ops.py")


def test_counting_counts_each_kind_and_restores_warp(tool):
    a, ones = wp.zeros(4, dtype=float, device="cpu"), wp.ones(4, dtype=float, device="cpu")
    launch, zero = wp.launch, wp.array.zero_
    with tool.counting() as counts:
        a.zero_()
        a.fill_(1.0)
        wp.copy(a, ones)
    assert dict(counts) == {"memset": 2, "copy": 1}
    assert (wp.launch, wp.array.zero_) == (launch, zero)


def test_the_forward_copies_the_fields_state_once_per_phase(tool):
    """Per forward: the stage keeps the force fields' state before it and as it leaves it (2 copies), the forward
    puts it back (1) and restores the constraint row counts (1): 4, however many arrays the fields carry (18)."""
    from legged_gente.envs.task_registry import task_registry

    cfg, _ = task_registry.get_cfgs("gente_biped")
    cfg.env.num_envs = 2
    torch.manual_seed(0)
    env, _ = task_registry.make_env("gente_biped", env_cfg=cfg, args=argparse.Namespace(device="cpu"))
    env.step(torch.zeros(2, env.num_actions))
    forward, step = tool.count_step(env)
    assert forward["copy"] == 4
    assert step["launch"] > 100 and forward["launch"] > 50  # the physics is counted too
