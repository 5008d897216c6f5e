"""GentePPO against PPO's formulas worked out by hand (numpy) on tiny rollouts: GAE (Schulman et al. 2016, "High-
Dimensional Continuous Control Using Generalized Advantage Estimation", eq. 16) with rsl-rl's time-out
bootstrap, the clipped surrogate, the clipped value loss and the entropy bonus (Schulman et al. 2017, eqs. 7 and
9), the adaptive learning rate, gradient clipping, the mini-batch partition, the observation normaliser, the
logger's episode means and resuming from a checkpoint."""

import math
from types import SimpleNamespace

import numpy as np
import pytest
import torch
from rsl_rl.algorithms import PPO
from tensordict import TensorDict
from torch import nn

from legged_gente.envs.base.legged_robot_config import LeggedRobotCfgPPO, rsl_rl_train_cfg
from legged_gente.utils.checkpoints import load_checkpoint
from legged_gente.utils.episode_logger import DeferredLogger
from legged_gente.utils.ppo import GentePPO, mixed_precision_on_cuda_only

NUM_ENVS, STEPS, NUM_ACTIONS = 2, 3, 2
GAMMA, LAM, CLIP, VALUE_COEF, ENTROPY_COEF, STD = 0.9, 0.8, 0.2, 0.5, 0.01, 0.7
CRITIC_BIAS = 0.25  # the critic's value of every state (its last layer's weights are zero)


def observations(generator) -> TensorDict:
    return TensorDict({"policy": torch.randn(NUM_ENVS, 3, generator=generator),
                       "critic": torch.randn(NUM_ENVS, 4, generator=generator)}, batch_size=[NUM_ENVS])


def last_linear(model: nn.Module) -> nn.Linear:
    return [m for m in model.mlp.modules() if isinstance(m, nn.Linear)][-1]


def algorithm(mini_batches=1, epochs=1, max_grad_norm=1e9, learning_rate=1e-3, steps=STEPS, num_envs=NUM_ENVS,
              **algorithm_cfg) -> GentePPO:
    """GentePPO on the CPU whose actor's mean is 0 and std STD, and whose critic's value is CRITIC_BIAS everywhere,
    so that log-probabilities, entropies and values follow from the formulas alone."""
    cfg = rsl_rl_train_cfg(LeggedRobotCfgPPO())
    mixed_precision_on_cuda_only(cfg, "cpu")
    cfg["num_steps_per_env"] = steps
    cfg["multi_gpu"] = None
    cfg["actor"]["hidden_dims"] = cfg["critic"]["hidden_dims"] = [8]
    cfg["actor"]["distribution_cfg"]["init_std"] = STD
    cfg["algorithm"].update(class_name=GentePPO, num_mini_batches=mini_batches, num_learning_epochs=epochs,
                            learning_rate=learning_rate, gamma=GAMMA, lam=LAM, clip_param=CLIP,
                            value_loss_coef=VALUE_COEF, entropy_coef=ENTROPY_COEF, max_grad_norm=max_grad_norm,
                            **algorithm_cfg)
    torch.manual_seed(0)
    obs = TensorDict({"policy": torch.zeros(num_envs, 3), "critic": torch.zeros(num_envs, 4)}, batch_size=[num_envs])
    alg = PPO.construct_algorithm(obs, SimpleNamespace(num_envs=num_envs, num_actions=NUM_ACTIONS), cfg, "cpu")
    assert isinstance(alg, GentePPO) and alg.device_side_update
    with torch.no_grad():
        for model in (alg.actor, alg.critic):
            last_linear(model).weight.zero_()
            last_linear(model).bias.zero_()
        last_linear(alg.critic).bias.fill_(CRITIC_BIAS)
    return alg


# a 3-step rollout of 2 robots: env 0 times out after step 1 (bootstrapped), env 1 terminates after step 0
REWARDS = np.array([[1.0, -0.5], [2.0, 0.3], [0.5, 1.5]])  # [step, env]
DONES = np.array([[0, 1], [1, 0], [0, 0]])
TIME_OUTS = np.array([[0, 0], [1, 0], [0, 0]])
VALUES = np.array([[0.4, -0.2], [1.1, 0.6], [-0.3, 0.9]])  # V(s_t) as the critic gave them in the rollout


def rollout(alg: GentePPO, generator, values=VALUES, rewards=REWARDS, dones=DONES, time_outs=TIME_OUTS):
    """Fill the storage with the given rewards, dones, time-outs and values; the rollout's observations."""
    obs = observations(generator)
    seen = []
    for step in range(len(rewards)):
        seen.append(obs)
        alg.act(obs)
        alg.transition.values = torch.tensor(values[step], dtype=torch.float32).unsqueeze(1)
        obs = observations(generator)
        alg.process_env_step(obs, torch.tensor(rewards[step], dtype=torch.float32),
                             torch.tensor(dones[step], dtype=torch.bool),
                             {"time_outs": torch.tensor(time_outs[step], dtype=torch.bool)})
    alg.compute_returns(obs)
    return seen


def gae_by_hand(rewards, values, dones, time_outs, last_value):
    """GAE(gamma, lambda) (Schulman et al. 2016, eq. 16) cut at each episode end, with a time-out's reward raised by
    gamma * V(s_t) (rsl-rl's bootstrap: the episode went on, so its value is not 0); returns R_t = A_t + V(s_t)."""
    rewards = rewards + GAMMA * values * time_outs
    advantages = np.zeros_like(rewards)
    following = np.zeros(rewards.shape[1])
    for t in reversed(range(len(rewards))):
        next_value = last_value if t == len(rewards) - 1 else values[t + 1]
        going_on = 1.0 - dones[t]
        delta = rewards[t] + GAMMA * next_value * going_on - values[t]
        following = delta + GAMMA * LAM * going_on * following
        advantages[t] = following
    return advantages, advantages + values


def test_gae_returns_and_advantages_by_hand():
    alg = algorithm()
    rollout(alg, torch.Generator().manual_seed(1))
    advantages, returns = gae_by_hand(REWARDS, VALUES, DONES, TIME_OUTS, CRITIC_BIAS)
    # spelled out for env 0 at its time-out (step 1): r + gamma V(s_1), no V(s_2) (another episode)
    assert advantages[1, 0] == pytest.approx(2.0 + GAMMA * 1.1 - 1.1)
    # env 1 terminated at step 0: its advantage there is r - V(s_0) alone
    assert advantages[0, 1] == pytest.approx(-0.5 - (-0.2))
    np.testing.assert_allclose(alg.storage.returns.squeeze(-1).numpy(), returns, rtol=1e-6, atol=1e-6)
    # normalised over the whole batch (rsl-rl 5.5 without per-mini-batch normalisation), with the sample std
    normalised = (advantages - advantages.mean()) / (advantages.std(ddof=1) + 1e-8)
    np.testing.assert_allclose(alg.storage.advantages.squeeze(-1).numpy(), normalised, rtol=1e-5, atol=1e-6)


def gaussian_log_prob(actions, mean, std):
    return np.sum(-(actions - mean) ** 2 / (2 * std ** 2) - np.log(std) - 0.5 * np.log(2 * np.pi), axis=-1)


def test_losses_and_their_gradients_by_hand():
    """One mini-batch, one epoch: the update's losses are those of the rollout's policy. The stored log-probs and
    values are moved so that some ratios and values fall outside the clip range, where the clipped terms rule."""
    alg = algorithm(normalize_advantage_per_mini_batch=True)
    rollout(alg, torch.Generator().manual_seed(2))
    st = alg.storage
    rows = NUM_ENVS * STEPS
    ratio_shift = np.array([0.5, -0.4, 0.1, -0.05, 0.3, -0.6])  # log(ratio) = new - old log-prob
    value_shift = np.array([0.5, -0.1, -0.4, 0.05, 0.3, 0.0])  # V_new - V_old
    with torch.no_grad():
        st.actions_log_prob -= torch.tensor(ratio_shift, dtype=torch.float32).view(STEPS, NUM_ENVS, 1)
        st.values.fill_(CRITIC_BIAS)
        st.values -= torch.tensor(value_shift, dtype=torch.float32).view(STEPS, NUM_ENVS, 1)
    actions = st.actions.flatten(0, 1).numpy().astype(np.float64)
    old_log_prob = st.actions_log_prob.flatten().numpy().astype(np.float64)
    old_values = st.values.flatten().numpy().astype(np.float64)
    returns = st.returns.flatten().numpy().astype(np.float64)
    advantages = st.advantages.flatten().numpy().astype(np.float64)  # raw: normalised per mini-batch
    advantages = (advantages - advantages.mean()) / (advantages.std(ddof=1) + 1e-8)

    log_prob = gaussian_log_prob(actions, 0.0, STD)
    ratio = np.exp(log_prob - old_log_prob)
    np.testing.assert_allclose(ratio, np.exp(ratio_shift), rtol=1e-5)
    clipped_ratio = np.clip(ratio, 1 - CLIP, 1 + CLIP)
    surrogate = np.mean(np.maximum(-advantages * ratio, -advantages * clipped_ratio))
    values = np.full(rows, CRITIC_BIAS)
    clipped_values = old_values + np.clip(values - old_values, -CLIP, CLIP)
    value_loss = np.mean(np.maximum((values - returns) ** 2, (clipped_values - returns) ** 2))
    entropy = NUM_ACTIONS * (0.5 + 0.5 * np.log(2 * np.pi) + np.log(STD))

    losses = alg.update()
    assert losses["surrogate"] == pytest.approx(surrogate, rel=1e-5, abs=1e-7)
    assert losses["value"] == pytest.approx(value_loss, rel=1e-5)
    assert losses["entropy"] == pytest.approx(entropy, rel=1e-6)

    # d loss / d std_i: the surrogate's gradient flows where the unclipped term is the larger (or the ratio is
    # inside the range); the entropy bonus enters with a minus sign, so it pushes the std up
    unclipped = (-advantages * ratio >= -advantages * clipped_ratio) | ((ratio > 1 - CLIP) & (ratio < 1 + CLIP))
    d_log_prob = (actions ** 2) / STD ** 3 - 1.0 / STD  # [row, action]
    d_std = np.mean((-advantages * ratio * unclipped)[:, None] * d_log_prob, axis=0) - ENTROPY_COEF / STD
    # d loss / d critic bias: 2 (V - R) where the unclipped error is the larger or the value is inside the range
    error, clipped_error = (values - returns) ** 2, (clipped_values - returns) ** 2
    active = (error >= clipped_error) | (np.abs(values - old_values) < CLIP)
    d_bias = VALUE_COEF * np.mean(2 * (values - returns) * active)
    gradients = dict(zip([n for n, _ in alg.actor.named_parameters()] + [f"critic.{n}" for n, _ in
                                                                          alg.critic.named_parameters()],
                         alg._gradient_views))
    np.testing.assert_allclose(gradients["distribution.std_param"].numpy(), d_std, rtol=1e-4, atol=1e-7)
    critic_bias = [name for name in gradients if name.startswith("critic.") and name.endswith(".bias")][-1]
    assert float(gradients[critic_bias]) == pytest.approx(d_bias, rel=1e-4)


def kl_gaussian(old_mean, old_std, new_mean, new_std):
    """KL(old || new) of diagonal Gaussians, summed over actions."""
    return np.sum(np.log(new_std / old_std) + (old_std ** 2 + (old_mean - new_mean) ** 2) / (2 * new_std ** 2) - 0.5,
                  axis=-1)


@pytest.mark.parametrize("kl_ratio, learning_rate, expected", [
    (3.0, 1e-3, 1e-3 / 1.5),  # above 2 x desired: / 1.5
    (2.5, 1.2e-5, 1e-5),  # ... but not below the floor
    (0.3, 1e-3, 1.5e-3),  # below half the desired: x 1.5
    (0.3, 8e-3, 1e-2),  # ... but not above the ceiling
    (1.0, 1e-3, 1e-3),  # in between: kept
    (1.9, 1e-3, 1e-3),
    (0.6, 1e-3, 1e-3),
])
def test_adaptive_learning_rate_from_the_kl(kl_ratio, learning_rate, expected):
    desired = 0.01
    alg = algorithm(learning_rate=learning_rate, desired_kl=desired, schedule="adaptive")
    rollout(alg, torch.Generator().manual_seed(3))
    # the old policy's mean moved by m in every action: KL = NUM_ACTIONS m^2 / (2 std^2)
    shift = math.sqrt(kl_ratio * desired * 2 * STD ** 2 / NUM_ACTIONS)
    assert kl_gaussian(np.full(NUM_ACTIONS, shift), STD, 0.0, STD) == pytest.approx(kl_ratio * desired)
    mean, std = alg.storage.distribution_params
    mean += shift
    alg.update()
    assert alg.learning_rate == pytest.approx(expected, rel=1e-5)
    assert float(alg.optimizer.param_groups[0]["lr"]) == pytest.approx(expected, rel=1e-5)


def test_gradients_are_clipped_to_max_norm_for_actor_and_critic_apart():
    max_norm = 1e-3
    unclipped = algorithm(max_grad_norm=1e9)
    clipped = algorithm(max_grad_norm=max_norm)
    for alg in (unclipped, clipped):
        torch.manual_seed(4)  # the same actions sampled
        rollout(alg, torch.Generator().manual_seed(4))
        alg.update()
    sizes = [unclipped._actor_size, unclipped._gradients.numel() - 1 - unclipped._actor_size]
    for raw, cut in zip(unclipped._gradients[:-1].split(sizes), clipped._gradients[:-1].split(sizes)):
        raw, cut = raw.double().numpy(), cut.double().numpy()
        norm = np.linalg.norm(raw)
        assert norm > max_norm  # clipping acts
        np.testing.assert_allclose(cut, raw * max_norm / (norm + 1e-6), rtol=1e-4, atol=1e-9)


@pytest.mark.parametrize("mini_batches, epochs", [(1, 1), (2, 3), (3, 2), (6, 2)])
def test_each_epoch_uses_every_sample_exactly_once(monkeypatch, mini_batches, epochs):
    alg = algorithm(mini_batches=mini_batches, epochs=epochs)
    rollout(alg, torch.Generator().manual_seed(5))
    seen = []
    step = alg._minibatch_stages[0]
    alg._minibatch_stages = (lambda: (seen.append(alg._batch_indices.clone()), step()),)
    alg.update()
    assert len(seen) == mini_batches * epochs
    for epoch in range(epochs):
        rows = torch.cat(seen[epoch * mini_batches:(epoch + 1) * mini_batches]).sort().values
        assert rows.tolist() == list(range(NUM_ENVS * STEPS))
    assert all(len(rows) == NUM_ENVS * STEPS // mini_batches for rows in seen)


def test_the_normaliser_learns_the_rollouts_observations_after_the_update_not_during_it(monkeypatch):
    alg = algorithm(mini_batches=2, epochs=2)
    seen = rollout(alg, torch.Generator().manual_seed(6))
    means_during = []
    step = alg._minibatch_stages[0]
    alg._minibatch_stages = (lambda: (means_during.append(alg.actor.obs_normalizer.mean.clone()), step()),)
    alg.update()
    assert all(torch.equal(mean, torch.zeros(3)) for mean in means_during)  # still the rollout's statistics
    for model, group in ((alg.actor, "policy"), (alg.critic, "critic")):
        # the observations the actions were taken on (s_0 .. s_{T-1}), not the last one
        x = np.concatenate([obs[group].numpy() for obs in seen]).astype(np.float64)
        np.testing.assert_allclose(model.obs_normalizer.mean.numpy(), x.mean(axis=0), rtol=1e-5, atol=1e-6)
        np.testing.assert_allclose(model.obs_normalizer.std.numpy(), x.std(axis=0), rtol=1e-5, atol=1e-6)
        assert int(model.obs_normalizer.count) == NUM_ENVS * STEPS


def test_resuming_from_a_save_continues_as_if_never_stopped(tmp_path):
    """Learning rate, Adam's moments and step count, normaliser statistics: a copy loaded from the saved file
    updates next as the original does."""
    generator = torch.Generator().manual_seed(7)
    original = algorithm(mini_batches=2, epochs=2, learning_rate=5e-2)
    rollout(original, generator)
    original.update()
    assert original.learning_rate != pytest.approx(5e-2)  # the adaptive rule moved it: the saved one is not the
    torch.save(original.save(), tmp_path / "model.pt")     # configured one
    resumed = algorithm(mini_batches=2, epochs=2, learning_rate=5e-2)
    resumed.load(load_checkpoint(tmp_path / "model.pt"), None, True)
    for model in (resumed.actor, resumed.critic):
        assert int(model.obs_normalizer.count) == NUM_ENVS * STEPS
    assert float(resumed.optimizer.param_groups[0]["lr"]) == pytest.approx(original.learning_rate)
    state = generator.get_state()
    for alg in (original, resumed):
        generator.set_state(state)
        torch.manual_seed(8)
        rollout(alg, generator)
        torch.manual_seed(9)
        alg.update()
    assert resumed.learning_rate == pytest.approx(original.learning_rate)
    for a, b in zip(original.save()["actor_state_dict"].values(), resumed.save()["actor_state_dict"].values()):
        assert torch.equal(a, b)
    for a, b in zip(original.save()["critic_state_dict"].values(), resumed.save()["critic_state_dict"].values()):
        assert torch.equal(a, b)


def test_the_loggers_episode_means_by_hand(tmp_path):
    logger = DeferredLogger(log_dir=str(tmp_path), cfg={"algorithm": {}, "logger": "tensorboard"}, env_cfg={}, num_envs=NUM_ENVS,
                            is_distributed=False, gpu_world_size=1, gpu_global_rank=0, device="cpu")
    logger.init_logging_writer()
    for step in range(STEPS):
        logger.process_env_step(torch.tensor(REWARDS[step], dtype=torch.float32),
                                torch.tensor(DONES[step]), {})
    logger.flush()
    # env 1 ends after step 0 (return -0.5, 1 step), env 0 after step 1 (1 + 2 = 3, 2 steps)
    assert list(logger.rewbuffer) == pytest.approx([-0.5, 3.0])
    assert list(logger.lenbuffer) == [1.0, 2.0]
    assert np.mean(logger.rewbuffer) == pytest.approx(1.25)
    # the unfinished episodes go on: env 0 has 0.5 over 1 step, env 1 has 0.3 + 1.5 over 2
    assert logger.cur_reward_sum.tolist() == pytest.approx([0.5, 1.8])
    assert logger.cur_episode_length.tolist() == [1.0, 2.0]
    logger.stop_logging_writer()
