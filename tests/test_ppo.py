"""GentePPO's sync-free update computes what rsl-rl's PPO.update computes."""

import copy
from types import SimpleNamespace

import pytest
import torch
from rsl_rl.algorithms import PPO
from tensordict import TensorDict

from legged_gente.envs.base.legged_robot_config import LeggedRobotCfgPPO, rsl_rl_train_cfg
from legged_gente.utils.ppo import GentePPO, mixed_precision_on_cuda_only

NUM_ENVS, NUM_ACTIONS, STEPS = 32, 3, 8


def observations(generator):
    return TensorDict({"policy": torch.randn(NUM_ENVS, 5, generator=generator),
                       "critic": torch.randn(NUM_ENVS, 7, generator=generator)}, batch_size=[NUM_ENVS])


def algorithm(alg_class, learning_rate, generator, mini_batches=2, epochs=3):
    """The algorithm built from the default train config as a CPU runner builds it (fp32), seeded."""
    cfg = rsl_rl_train_cfg(LeggedRobotCfgPPO())
    mixed_precision_on_cuda_only(cfg, "cpu")
    cfg["num_steps_per_env"] = STEPS
    cfg["multi_gpu"] = None
    cfg["algorithm"].update(class_name=alg_class, num_mini_batches=mini_batches, num_learning_epochs=epochs,
                            learning_rate=learning_rate)
    torch.manual_seed(0)
    return PPO.construct_algorithm(observations(generator), SimpleNamespace(num_envs=NUM_ENVS, num_actions=NUM_ACTIONS),
                                   cfg, "cpu")


def rollout_and_update(alg, generator):
    """Fill one rollout with seeded data and update once; the losses."""
    obs = observations(generator)
    for _ in range(STEPS):
        alg.act(obs)
        obs = observations(generator)
        dones = torch.rand(NUM_ENVS, generator=generator) < 0.1
        alg.process_env_step(obs, torch.randn(NUM_ENVS, generator=generator), dones,
                             {"time_outs": dones & (torch.rand(NUM_ENVS, generator=generator) < 0.5)})
    alg.compute_returns(obs)
    return alg.update()


def updated(alg_class, learning_rate):
    """Build the algorithm, fill one rollout with seeded data, update once."""
    generator = torch.Generator().manual_seed(0)
    alg = algorithm(alg_class, learning_rate, generator)
    return alg, rollout_and_update(alg, generator)


@pytest.mark.parametrize("learning_rate", [1e-3, 5e-2])  # 5e-2: large steps, the adaptive rate must come down
def test_device_side_update_matches_rsl_rl(learning_rate):
    reference, reference_losses = updated(PPO, learning_rate)
    ours, losses = updated(GentePPO, learning_rate)
    assert ours.device_side_update
    assert isinstance(ours.optimizer.param_groups[0]["lr"], torch.Tensor)
    assert ours.learning_rate == pytest.approx(reference.learning_rate, rel=1e-6)
    assert losses == pytest.approx(reference_losses, rel=1e-4, abs=1e-6)
    for theirs, mine in zip(reference.actor.parameters(), ours.actor.parameters()):
        assert torch.allclose(theirs, mine, atol=1e-5)
    for theirs, mine in zip(reference.critic.parameters(), ours.critic.parameters()):
        assert torch.allclose(theirs, mine, atol=1e-5)
    if learning_rate == 5e-2:
        assert ours.learning_rate < learning_rate


def test_a_checkpoint_with_a_float_learning_rate_still_adapts():
    ours, _ = updated(GentePPO, 1e-3)
    state = copy.deepcopy(ours.optimizer.state_dict())
    state["param_groups"][0]["lr"] = 2e-3  # as saved by rsl-rl's PPO
    ours.optimizer.load_state_dict(state)
    assert isinstance(ours._learning_rate_tensor(), torch.Tensor)
    assert float(ours._learning_rate_tensor()) == pytest.approx(2e-3)


@pytest.mark.parametrize("saved_by", [PPO, GentePPO])
def test_a_loaded_checkpoint_keeps_the_optimizer_as_gente_ppo_builds_it(saved_by):
    """torch's load_state_dict takes every Adam setting from the checkpoint: one saved by rsl-rl's PPO (fused
    off, a float rate) or on the CPU (capturable False) could not be captured in a CUDA graph. After GentePPO's
    load its Adam has the settings it was built with, its rate is a device tensor with the saved value, its step
    counts are float tensors on the parameters' device, and the update still runs and adapts the rate."""
    saved, _ = updated(saved_by, 1e-3)
    checkpoint = saved.save()
    alg = algorithm(GentePPO, 5e-3, torch.Generator().manual_seed(1))
    built = {key: alg.optimizer.param_groups[0][key] for key in ("fused", "foreach", "capturable")}
    alg.load(copy.deepcopy(checkpoint), None, True)
    group = alg.optimizer.param_groups[0]
    assert {key: group[key] for key in built} == built == {"fused": True, "foreach": None, "capturable": False}
    assert isinstance(group["lr"], torch.Tensor) and float(group["lr"]) == pytest.approx(saved.learning_rate)
    steps = [alg.optimizer.state[p]["step"] for p in group["params"]]
    assert all(step.dtype == torch.float32 and step.device == p.device for step, p in zip(steps, group["params"]))
    before = float(group["lr"])
    rollout_and_update(alg, torch.Generator().manual_seed(2))
    assert alg.learning_rate != pytest.approx(before)  # the adaptive schedule moved it on the device


def test_sync_free_gaussian_samples_the_same_distribution():
    from rsl_rl.modules.distribution import GaussianDistribution

    from legged_gente.utils.ppo import SyncFreeGaussianDistribution

    ours, theirs = SyncFreeGaussianDistribution(2, init_std=0.5), GaussianDistribution(2, init_std=0.5)
    assert ours.state_dict().keys() == theirs.state_dict().keys()  # checkpoints load either way
    mean = torch.tensor([[1.0, -2.0]]).expand(200_000, 2)
    ours.update(mean)
    samples = ours.sample()
    assert torch.allclose(samples.mean(0), torch.tensor([1.0, -2.0]), atol=0.01)
    assert torch.allclose(samples.std(0), torch.tensor([0.5, 0.5]), atol=0.01)
    assert not samples.requires_grad


def test_two_rank_update_matches_rsl_rl_over_gloo():
    """GentePPO's one all-reduce of the gradient buffer (with the KL) against rsl-rl's bucketed gradient
    all-reduce, KL all-reduce and learning-rate broadcast: two CPU ranks, each with its own rollouts."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    repo = Path(__file__).resolve().parents[1]
    env = {k: v for k, v in os.environ.items() if k not in ("RANK", "LOCAL_RANK", "WORLD_SIZE")}
    env.update(OMP_NUM_THREADS="1", PYTHONUNBUFFERED="1")
    cmd = [sys.executable, "-m", "torch.distributed.run", "--standalone", "--nproc_per_node=2",
           "tools/check_cuda_graphs.py", "--ppo_only", "--device", "cpu", "--ppo_envs", "64"]
    out = subprocess.run(cmd, cwd=repo, env=env, capture_output=True, text=True, timeout=300)
    log = out.stdout + out.stderr
    assert out.returncode == 0, log[-4000:]
    assert log.count("GentePPO agrees with rsl-rl's PPO") == 2, log[-4000:]
    assert "rank 1: update 3:" in log, log[-4000:]


def test_a_non_finite_update_stops_training():
    """learning_rate=1e999 (inf, as --set algorithm.learning_rate=1e999 gives) makes Adam's step inf/NaN: the
    update must raise instead of returning NaN weights for the runner to save."""
    with pytest.raises(FloatingPointError, match="non-finite.*learning_rate"):
        updated(GentePPO, float("1e999"))


def test_a_non_finite_update_stops_rsl_rl_fallback_path(monkeypatch):
    """The fallback to rsl-rl's update (recurrent models, RND, ...) is checked too."""
    original = GentePPO.__init__

    def init(self, *args, **kwargs):
        original(self, *args, **kwargs)
        self.device_side_update = False

    monkeypatch.setattr(GentePPO, "__init__", init)
    with pytest.raises(FloatingPointError, match="non-finite"):
        updated(GentePPO, float("1e999"))


def test_the_same_mini_batches_give_rsl_rls_losses_gradients_and_learning_rate(monkeypatch):
    """The same mini-batch (the whole rollout, two epochs: the second sees a KL below half the desired one)
    through rsl-rl's PPO.update and GentePPO's device-side steps: the losses, the clipped gradients Adam is
    given at each step and the adapted learning rate agree. rsl-rl 5.5 computes its loss, KL rule and
    learning-rate rule inline in PPO.update with host reads, so GentePPO computes them itself; this pins the two
    together (an rsl-rl upgrade that changes them fails here)."""

    def one_batch(alg_class):
        generator = torch.Generator().manual_seed(0)
        alg = algorithm(alg_class, 1e-3, generator, mini_batches=1, epochs=2)
        obs = observations(generator)
        for _ in range(STEPS):
            alg.act(obs)
            obs = observations(generator)
            dones = torch.rand(NUM_ENVS, generator=generator) < 0.1
            alg.process_env_step(obs, torch.randn(NUM_ENVS, generator=generator), dones, {"time_outs": dones})
        alg.compute_returns(obs)
        gradients = []
        monkeypatch.setattr(alg.optimizer, "step", lambda: gradients.append(
            torch.cat([p.grad.flatten() for p in chain(alg.actor.parameters(), alg.critic.parameters())])))
        losses = alg.update()
        return losses, gradients, alg.learning_rate

    from itertools import chain

    reference_losses, reference_gradients, reference_lr = one_batch(PPO)
    losses, gradients, lr = one_batch(GentePPO)
    assert len(gradients) == len(reference_gradients) == 2
    assert losses == pytest.approx(reference_losses, rel=1e-5, abs=1e-7)
    for mine, theirs in zip(gradients, reference_gradients):
        assert torch.allclose(mine, theirs, rtol=1e-4, atol=1e-7)
    assert lr == pytest.approx(reference_lr, rel=1e-6) and lr > 1e-3  # adapted


@pytest.mark.parametrize("schedule", ["adaptive", "fixed"])
def test_a_critic_warmup_holds_the_actor_fixed_then_releases_it(monkeypatch, schedule):
    """freeze_actor(2): two updates change the critic and leave the actor (weights, action noise, observation
    normaliser) and the learning rate as they were, even when rounding makes the held actor's KL positive (TF32 on
    a GPU); the next update trains both, and its first Adam step on the actor is a fresh Adam's (every element
    moves by at most the learning rate, the largest by about that much), not one scaled by the frozen steps.
    With the adaptive schedule that rate is the floor, 1e-5 (a fresh Adam moves every weight by about the rate),
    and it climbs 1.5x per mini-batch while the KL stays below half the target; a fixed rate stays as set."""
    generator = torch.Generator().manual_seed(0)
    learning_rate = 1e-3
    alg = algorithm(GentePPO, learning_rate, generator)
    alg.schedule = schedule

    def state(model):
        return {k: v.clone() for k, v in model.state_dict().items()}

    alg.freeze_actor(2)
    actor_before = state(alg.actor)
    assert any("std" in k for k in actor_before) and any("normalizer" in k for k in actor_before)

    def small_kl(old, new):  # below half the desired KL
        return torch.full((NUM_ENVS,), 1e-4)

    with monkeypatch.context() as patch:  # an adapting rate would grow 1.5x per mini-batch
        patch.setattr(alg.actor, "get_kl_divergence", small_kl)
        for _ in range(2):
            critic_before = state(alg.critic)
            rollout_and_update(alg, generator)
            assert all(torch.equal(actor_before[k], v) for k, v in alg.actor.state_dict().items())
            assert not all(torch.equal(critic_before[k], v) for k, v in alg.critic.state_dict().items())
            assert alg.learning_rate == pytest.approx(learning_rate, rel=1e-6)  # the rate these updates used
    released_rate = 1e-5 if schedule == "adaptive" else learning_rate
    alg.num_learning_epochs = alg.num_mini_batches = 1  # one Adam step
    rollout_and_update(alg, generator)  # on the CPU the first mini-batch's KL is exactly 0: the rate stays
    changed = [k for k, v in alg.actor.state_dict().items() if not torch.equal(actor_before[k], v)]
    assert any("normalizer" in k for k in changed) and any(k.startswith("mlp") for k in changed)
    steps = torch.cat([(v - actor_before[k]).abs().flatten() for k, v in alg.actor.state_dict().items()
                       if k.startswith("mlp")])
    assert float(steps.max()) == pytest.approx(released_rate, rel=0.02)  # Adam's first step: lr * g / |g|
    with monkeypatch.context() as patch:
        patch.setattr(alg.actor, "get_kl_divergence", small_kl)
        rollout_and_update(alg, generator)
    assert alg.learning_rate == pytest.approx(released_rate * (1.5 if schedule == "adaptive" else 1.0), rel=1e-6)
    with pytest.raises(ValueError, match="critic_warmup_iterations=-1"):
        alg.freeze_actor(-1)


def test_freeze_actor_0_on_an_actor_that_is_not_held_changes_nothing():
    """Only a release restarts the actor's Adam: freeze_actor(0) in the middle of training keeps its step count
    and the learning rate."""
    alg, _ = updated(GentePPO, 1e-3)
    steps = [alg.optimizer.state[p]["step"].clone() for p in alg.actor.parameters()]
    rate = alg.learning_rate
    alg.freeze_actor(0)
    assert all(torch.equal(s, alg.optimizer.state[p]["step"]) for s, p in zip(steps, alg.actor.parameters()))
    assert float(alg._learning_rate_tensor()) == pytest.approx(rate, rel=1e-6)


def test_a_run_saved_during_its_critic_warmup_resumes_it():
    """A checkpoint written during the warm-up records the updates left; loading it (with the optimizer, as
    --resume does) holds the actor for those, so the actor's Adam bias correction still restarts at the release.
    A checkpoint written after it holds nothing."""
    held, _ = updated(GentePPO, 1e-3)
    held.freeze_actor(3)
    saved = held.save()
    assert saved["frozen_actor_updates"] == 3
    resumed, _ = updated(GentePPO, 1e-3)
    resumed.load(saved, None, True)
    assert resumed._frozen_actor_updates == 3 and float(resumed._actor_gradient_scale) == 0.0
    released, _ = updated(GentePPO, 1e-3)
    assert "frozen_actor_updates" not in released.save()
    released.load(released.save(), None, True)
    assert released._frozen_actor_updates == 0 and float(released._actor_gradient_scale) == 1.0


def test_mixed_precision_is_a_setting_that_reaches_both_updates():
    """``algorithm.use_mixed_precision`` (on by default; ``--set algorithm.use_mixed_precision=False`` turns it off)
    turns on bf16 autocast in GentePPO's update as in rsl-rl's: both give the same losses, and they differ from the
    fp32 update's by bf16's rounding."""
    from legged_gente.utils.args import apply_overrides

    fp32_cfg = LeggedRobotCfgPPO()
    apply_overrides(["algorithm.use_mixed_precision=False"], SimpleNamespace(), fp32_cfg)
    assert rsl_rl_train_cfg(LeggedRobotCfgPPO())["algorithm"]["use_mixed_precision"] is True
    assert rsl_rl_train_cfg(fp32_cfg)["algorithm"]["use_mixed_precision"] is False

    def losses(alg_class, mixed):
        generator = torch.Generator().manual_seed(0)
        cfg = rsl_rl_train_cfg(LeggedRobotCfgPPO() if mixed else fp32_cfg)
        cfg["num_steps_per_env"] = STEPS
        cfg["multi_gpu"] = None
        cfg["algorithm"].update(class_name=alg_class, num_mini_batches=2, num_learning_epochs=3)
        torch.manual_seed(0)
        alg = PPO.construct_algorithm(observations(generator),
                                      SimpleNamespace(num_envs=NUM_ENVS, num_actions=NUM_ACTIONS), cfg, "cpu")
        assert alg.use_mixed_precision is mixed
        return rollout_and_update(alg, generator)

    ours, theirs, fp32 = losses(GentePPO, True), losses(PPO, True), losses(GentePPO, False)
    assert ours == pytest.approx(theirs, rel=1e-3, abs=1e-5)
    assert ours["value"] != pytest.approx(fp32["value"], rel=1e-5)


@pytest.mark.parametrize("device, configured, mixed", [
    ("cuda:0", True, True), (torch.device("cuda", 1), True, True), ("cuda:0", False, False), ("cpu", True, False),
    ("cpu", False, False)])
def test_mixed_precision_applies_on_cuda_only(device, configured, mixed):
    """algorithm.use_mixed_precision, as the runner and the CUDA-graph check apply it: bf16 on CUDA devices only."""
    cfg = {"algorithm": {"use_mixed_precision": configured}}
    mixed_precision_on_cuda_only(cfg, device)
    assert cfg["algorithm"]["use_mixed_precision"] is mixed


def test_compile_update_runs_the_update_through_compiled_mlps_and_leaves_the_models_as_they_were(monkeypatch):
    """GentePPO.compile_update (on by default on CUDA, runner.compile_update): the update's mini-batch steps call
    the MLPs compiled by TorchInductor, which compute what the plain ones compute; afterwards the models hold
    their plain MLPs again, so state dicts (checkpoints) and exports keep their keys."""
    generator = torch.Generator().manual_seed(0)
    plain, plain_losses = updated(GentePPO, 1e-3)
    alg = algorithm(GentePPO, 1e-3, generator)
    keys = list(alg.actor.state_dict()) + list(alg.critic.state_dict())
    alg.compile_update()
    seen = []
    gradients = alg._minibatch_gradients

    def spying():
        seen.append((type(alg.actor.mlp).__name__, type(alg.critic.mlp).__name__))
        gradients()

    monkeypatch.setattr(alg, "_minibatch_gradients", spying)
    alg._minibatch_stages = (alg._minibatch_step,)
    losses = rollout_and_update(alg, generator)
    assert seen and all(names == ("OptimizedModule", "OptimizedModule") for names in seen)
    assert type(alg.actor.mlp).__name__ == type(alg.critic.mlp).__name__ == "MLP"
    assert list(alg.actor.state_dict()) + list(alg.critic.state_dict()) == keys
    assert losses == pytest.approx(plain_losses, rel=1e-4, abs=1e-6)
    for theirs, mine in zip(plain.actor.parameters(), alg.actor.parameters()):
        assert torch.allclose(theirs, mine, atol=1e-5)



@pytest.mark.parametrize("device, own_update, configured, compiled", [
    ("cuda:0", True, True, True), ("cpu", True, True, False), ("cuda:0", False, True, False),
    ("cuda:0", True, False, False)])
def test_compile_update_applies_to_gentes_own_update_on_cuda_only(device, own_update, configured, compiled):
    """runner.compile_update, as the runner and the CUDA-graph check apply it: GentePPO's own update on CUDA."""
    from legged_gente.utils.ppo import compile_update_if_configured

    calls = []
    alg = SimpleNamespace(device=device, device_side_update=own_update, compile_update=lambda: calls.append(1))
    compile_update_if_configured(alg, {"compile_update": configured})
    assert calls == ([1] if compiled else [])
