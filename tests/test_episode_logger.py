"""DeferredLogger gathers finished episodes on the device and logs exactly what rsl-rl's Logger logs."""

import pytest
import torch
from rsl_rl.utils.logger import Logger

from legged_gente.envs.base.legged_robot_config import LeggedRobotCfgPPO, rsl_rl_train_cfg
from legged_gente.utils.distributed import GenteOnPolicyRunner
from legged_gente.utils.episode_logger import DeferredLogger

NUM_ENVS = 6


def make(logger_class):
    logger = logger_class(log_dir=None, cfg=rsl_rl_train_cfg(LeggedRobotCfgPPO()), env_cfg={}, num_envs=NUM_ENVS,
                          is_distributed=False, gpu_world_size=1, gpu_global_rank=0, device="cpu")
    logger.writer = object()  # as if init_logging_writer had opened one: process_env_step records
    return logger


def test_deferred_logger_matches_rsl_rl_logger():
    reference, deferred = make(Logger), make(DeferredLogger)
    generator = torch.Generator().manual_seed(3)
    for step in range(40):
        rewards = torch.randn(NUM_ENVS, generator=generator)
        dones = torch.rand(NUM_ENVS, generator=generator) < 0.15
        extras = {"episode": {"terrain_level": torch.tensor(float(step))}} if step % 10 == 0 else {}
        reference.process_env_step(rewards, dones, extras)
        deferred.process_env_step(rewards, dones, extras)
    assert len(deferred.rewbuffer) == 0  # nothing moved to the host during the rollout
    deferred.flush()
    assert len(reference.rewbuffer) > 5
    assert list(deferred.rewbuffer) == pytest.approx(list(reference.rewbuffer))
    assert list(deferred.lenbuffer) == list(reference.lenbuffer)
    assert torch.equal(deferred.cur_reward_sum, reference.cur_reward_sum)
    assert torch.equal(deferred.cur_episode_length, reference.cur_episode_length)
    assert len(deferred.ep_extras) == len(reference.ep_extras) == 4


def test_unknown_matmul_precision_is_rejected():
    cfg = rsl_rl_train_cfg(LeggedRobotCfgPPO())
    cfg["matmul_precision"] = "tf32"
    with pytest.raises(ValueError, match="matmul_precision"):
        GenteOnPolicyRunner(None, cfg)
