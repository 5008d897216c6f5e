"""GentePPO's own update against rsl-rl's PPO.update for the algorithm options GentePPO computes itself (the
advantage normalisation per mini-batch, the unclipped value loss, the fixed schedule, a fixed or log-space action
noise, a rollout that the mini-batches do not divide), and the optimizer name as rsl-rl reads it."""

from types import SimpleNamespace

import pytest
import torch
from rsl_rl.algorithms import PPO

from legged_gente.envs.base.legged_robot_config import LeggedRobotCfgPPO, rsl_rl_train_cfg
from legged_gente.utils.ppo import GentePPO, mixed_precision_on_cuda_only
from test_ppo import NUM_ACTIONS, NUM_ENVS, STEPS, observations, rollout_and_update


def algorithm(alg_class, generator, algorithm_cfg: dict, distribution_cfg: dict, mini_batches: int):
    cfg = rsl_rl_train_cfg(LeggedRobotCfgPPO())
    mixed_precision_on_cuda_only(cfg, "cpu")
    cfg["num_steps_per_env"] = STEPS
    cfg["multi_gpu"] = None
    cfg["algorithm"].update(class_name=alg_class, num_mini_batches=mini_batches, num_learning_epochs=2,
                            **algorithm_cfg)
    cfg["actor"]["distribution_cfg"].update(distribution_cfg)
    torch.manual_seed(0)
    return PPO.construct_algorithm(observations(generator), SimpleNamespace(num_envs=NUM_ENVS, num_actions=NUM_ACTIONS),
                                   cfg, "cpu")


def two_updates(alg_class, algorithm_cfg=None, distribution_cfg=None, mini_batches=3):
    generator = torch.Generator().manual_seed(0)
    alg = algorithm(alg_class, generator, algorithm_cfg or {}, distribution_cfg or {}, mini_batches)
    losses = [rollout_and_update(alg, generator) for _ in range(2)]
    return alg, losses


@pytest.mark.parametrize("algorithm_cfg, distribution_cfg, mini_batches", [
    ({"normalize_advantage_per_mini_batch": True}, {}, 3),
    ({"use_clipped_value_loss": False}, {}, 3),
    ({"schedule": "fixed"}, {}, 3),
    ({}, {"learn_std": False}, 3),
    ({}, {"std_type": "log"}, 3),
    ({}, {}, 5),  # 256 rollout rows in 5 mini-batches of 51: one row left out, as rsl-rl leaves it
])
def test_options_give_rsl_rls_update(algorithm_cfg, distribution_cfg, mini_batches):
    reference, reference_losses = two_updates(PPO, algorithm_cfg, distribution_cfg, mini_batches)
    ours, losses = two_updates(GentePPO, algorithm_cfg, distribution_cfg, mini_batches)
    assert ours.device_side_update
    assert ours.learning_rate == pytest.approx(reference.learning_rate, rel=1e-6)
    for mine, theirs in zip(losses, reference_losses):
        assert mine == pytest.approx(theirs, rel=1e-4, abs=1e-6)
    for model, reference_model in ((ours.actor, reference.actor), (ours.critic, reference.critic)):
        for (name, mine), theirs in zip(model.state_dict().items(), reference_model.state_dict().values()):
            assert torch.allclose(mine.float(), theirs.float(), atol=1e-5), name


def test_the_optimizer_name_is_read_as_rsl_rl_reads_it():
    """rsl-rl takes ``algorithm.optimizer`` in any case ("Adam" is its Adam): GentePPO runs its own update for it
    too, so the critic warm-up works, instead of falling back to rsl-rl's update."""
    alg, _ = two_updates(GentePPO, {"optimizer": "Adam"})
    assert alg.device_side_update
    alg.freeze_actor(2)
    assert alg._frozen_actor_updates == 2
