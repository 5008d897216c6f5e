"""rsl-rl's PPO with an update that never waits for the GPU.

rsl-rl 5.5's ``PPO.update`` reads four numbers back to the host in every mini-batch: the KL divergence (to adapt
the learning rate in Python) and the three losses (``.item()``). Each read makes the CPU wait until the GPU has
finished the mini-batch before it launches the next one, so the few hundred small kernels of a mini-batch are
issued and executed one after the other instead of overlapping. ``GentePPO`` keeps the learning rate in a device
tensor that the optimizer reads (adapted in place by the same rule), sums the losses on the device, and reads
everything once per update. On a GPU each mini-batch step (the gather of its rows from the rollout, forward, loss,
backward, gradient clipping, Adam) then runs as CUDA graphs (``StepGraph``) that read the rows from a tensor the
host refills: one graph on a single GPU; under torchrun two, the gradients and the optimizer step, with one NCCL
all-reduce launched between them. All gradients live in one flat buffer (``param.grad`` are views into it, which
backward accumulates into in place) with one more element for the KL divergence, so that all-reduce averages the
gradients and the KL at once, where rsl-rl issues one per gradient bucket plus one for the KL and a broadcast of
the learning rate. The rollout's ``act`` (policy and value forward passes, sampling) is one more graph. The loss
is PPO's clipped surrogate with the clipped value loss and entropy bonus (Schulman et al. 2017), as in rsl-rl;
``update`` falls back to rsl-rl's for what it does not cover (recurrent models, RND, symmetry, optimizers other
than Adam).

What rsl-rl factors out is shared: the models' log-probabilities, entropy and KL divergence
(``get_output_log_prob``, ``output_entropy``, ``get_kl_divergence``), the rollout storage, ``act`` and the
fallback update. The mini-batches are the storage generator's (the same random permutation, cut in order),
gathered inside the graph instead of by the generator on the host. rsl-rl-lib 5.5 computes the loss terms, the KL
test and the learning-rate rule inline in ``PPO.update``, between host reads (``kl_mean > ...`` in Python,
``.item()``), so there is no smaller piece of it to subclass; those few lines are written here on device tensors,
and ``tests/test_ppo.py`` pins them to rsl-rl's: the same mini-batches give the same losses, clipped gradients and
learning rate.

``SyncFreeGaussianDistribution`` is rsl-rl's Gaussian policy distribution sampled as mean + std * N(0, 1):
``torch.normal(mean, std)``, which rsl-rl's ``sample`` calls, checks ``std >= 0`` on the host, a sync at
every action sampled in the rollout and in every mini-batch.
"""

from __future__ import annotations

import contextlib
import math
from itertools import chain

import torch
from rsl_rl.algorithms import PPO
from rsl_rl.modules.distribution import GaussianDistribution
from rsl_rl.storage import RolloutStorage
from tensordict import TensorDict
from torch import nn

from legged_gente.utils.cuda_graph import StepGraph


class SyncFreeGaussianDistribution(GaussianDistribution):
    def sample(self) -> torch.Tensor:
        """A draw from the same Gaussian, without torch.normal's host-side check of the std."""
        with torch.no_grad():
            return self._distribution.rsample()


def mixed_precision_on_cuda_only(train_cfg: dict, device: str | torch.device) -> None:
    """``algorithm.use_mixed_precision`` (bf16 autocast of the update's forward pass) applies on CUDA devices only,
    as ``runner.matmul_precision`` does: on the CPU bf16 autocast made the update slower, so the update stays
    fp32 there. Rewrites the setting in the runner's config before the algorithm is built (the task registry
    copies the outcome into the run's config.json); the runner and the CUDA-graph check both apply it here."""
    algorithm = train_cfg["algorithm"]
    algorithm["use_mixed_precision"] = (bool(algorithm.get("use_mixed_precision"))
                                        and torch.device(device).type == "cuda")


def compile_update_if_configured(alg: PPO, train_cfg: dict) -> None:
    """``runner.compile_update``: GentePPO's own update on a CUDA device runs compiled MLPs; rsl-rl's update, and
    any update on the CPU, run as they are. The runner and the CUDA-graph check both apply it here."""
    if (train_cfg.get("compile_update") and torch.device(alg.device).type == "cuda"
            and getattr(alg, "device_side_update", False)):
        alg.compile_update()


class GentePPO(PPO):
    MIN_LEARNING_RATE, MAX_LEARNING_RATE = 1e-5, 1e-2
    """The adaptive schedule's bounds (rsl-rl's)."""

    def __init__(self, actor, critic, storage, *args, optimizer: str = "adam", **kwargs):
        super().__init__(actor, critic, storage, *args, optimizer=optimizer, **kwargs)
        # rsl-rl reads the optimizer's name in any case ("Adam" is its Adam)
        self.device_side_update = (optimizer.lower() == "adam" and self.rnd is None and self.symmetry is None
                                   and not (actor.is_recurrent or critic.is_recurrent))
        self._act_graph = None
        self._frozen_actor_updates = 0  # the critic warm-up's updates left (freeze_actor)
        if self.device_side_update:
            # Adam reading its learning rate from a tensor: the adaptive schedule changes it on the device
            cuda = torch.device(self.device).type == "cuda"
            self._parameters = list(chain(self.actor.parameters(), self.critic.parameters()))
            lr = torch.tensor(float(self.learning_rate), device=self.device)
            self.optimizer = torch.optim.Adam(self._parameters, lr=lr, fused=True, capturable=cuda)
            sizes = [parameter.numel() for parameter in self._parameters]
            self._gradients = torch.zeros(sum(sizes) + 1, device=self.device)  # all gradients, then the KL
            self._gradient_views = [view.view_as(parameter) for parameter, view in
                                    zip(self._parameters, self._gradients[:-1].split(sizes))]
            self._loss_sums = torch.zeros(3, device=self.device)  # value, surrogate, entropy
            self._actor_size = sum(parameter.numel() for parameter in self.actor.parameters())
            self._actor_gradient_scale = torch.ones((), device=self.device)  # 0 while the actor is held fixed
            self._batch_indices: torch.Tensor | None = None  # the rollout rows of the next mini-batch
            self._advantages: torch.Tensor | None = None  # the rollout's advantages, in one tensor (see update)
            self._compiled_mlps: list[tuple[nn.Module, nn.Module]] = []  # (model, its compiled MLP): compile_update
            self._graphed = cuda
            if not cuda:
                self._minibatch_stages = (self._minibatch_step,)
            elif not self.is_multi_gpu:
                self._minibatch_stages = (StepGraph(self, self._minibatch_step, self.device, warp=False),)
            else:  # NCCL's all-reduce runs between the two graphs
                self._minibatch_stages = (StepGraph(self, self._minibatch_gradients, self.device, warp=False),
                                          self._all_reduce_gradients,
                                          StepGraph(self, self._apply_gradients, self.device, warp=False))
            if cuda:
                self._act_graph = StepGraph(self, self._act_step, self.device, warp=False)
                self._act_observations: TensorDict | None = None  # what the act graph reads

    def act(self, obs: TensorDict) -> torch.Tensor:
        """rsl-rl's act (actions, values, log-probabilities, distribution parameters into ``self.transition``),
        on a GPU replayed from a CUDA graph that reads a static copy of ``obs``."""
        if self._act_graph is None:
            return super().act(obs)
        if self._act_observations is None:
            self._act_observations = obs.clone()
        else:
            self._act_observations.copy_(obs)
        self._act_graph()
        vars(self.transition).update(self._act_transition)
        return self.transition.actions

    def compile_update(self) -> None:
        """Let the update run the actor's and critic's MLPs compiled by TorchInductor (``torch.compile``), which
        fuses their elementwise work (the ELUs, their gradients, the bias gradients): that work, not the matrix
        products, bounds the update (docs/performance_log.md). Only the update uses the compiled MLPs; the models,
        their state dict, ``act`` and exports stay as they are. They compile in the first update (seconds),
        before its graphs are captured."""
        self._compiled_mlps = [(model, torch.compile(model.mlp, dynamic=False)) for model in (self.actor, self.critic)
                               if isinstance(getattr(model, "mlp", None), nn.Module)]

    @contextlib.contextmanager
    def _update_models(self):
        """The models with their compiled MLPs in place (``compile_update``) for the block's duration."""
        kept = [(model, model.mlp) for model, _ in self._compiled_mlps]
        for model, compiled in self._compiled_mlps:
            model.mlp = compiled
        try:
            yield
        finally:
            for model, mlp in kept:
                model.mlp = mlp

    def freeze_actor(self, updates: int) -> None:
        """Train the critic alone for the next ``updates`` updates: the actor's gradients are zeroed, so Adam
        (whose moments start at zero) leaves the actor and its action noise exactly as they are. For fine-tuning
        a trained actor with a fresh critic: an untrained critic's advantages would otherwise pull the actor off
        its gait in the first updates.

        At the release (``updates`` reaching 0) the actor's Adam starts afresh: its bias correction restarts, and
        with the adaptive schedule the learning rate restarts at its floor. A fresh Adam's first steps move every
        weight by about the learning rate whatever its gradient (m / sqrt(v) = sign(g)), which at the rate the
        critic trained with threw the trained actor far off (KL above twice the target at once: the rate fell
        to its floor within the first iteration); from the floor the KL rule raises it 1.5x per mini-batch while
        the policy changes little (Liu et al. 2020, "On the Variance of the Adaptive Learning Rate and
        Beyond": Adam's early steps want a warm-up)."""
        if updates < 0:
            raise ValueError(f"runner.critic_warmup_iterations={updates}: the number of critic-only updates "
                             f"must be >= 0")
        if not self.device_side_update:
            if updates:
                raise ValueError("a critic warm-up needs GentePPO's own update (Adam, feed-forward models, no RND "
                                 "or symmetry); set runner.critic_warmup_iterations = 0")
            return
        released = self._frozen_actor_updates > 0 and not updates
        self._frozen_actor_updates = updates
        self._actor_gradient_scale.fill_(0.0 if updates else 1.0)  # device writes, no host wait
        if released:  # the actor's Adam moments are still zero; restart its bias correction too, or its first
            for parameter in self.actor.parameters():  # steps would be scaled by the frozen steps' count
                state = self.optimizer.state.get(parameter)
                if state:
                    state["step"].zero_()
            if self._adaptive_learning_rate:
                self._learning_rate_tensor().fill_(self.MIN_LEARNING_RATE)

    def save(self) -> dict:
        """rsl-rl's checkpoint, plus the critic warm-up's remaining updates when it is still running."""
        saved = super().save()
        if self._frozen_actor_updates:
            saved["frozen_actor_updates"] = self._frozen_actor_updates
        return saved

    def load(self, loaded_dict: dict, load_cfg: dict | None, strict: bool) -> bool:
        """rsl-rl's load; a run saved during its critic warm-up (with its optimizer state) resumes the warm-up.
        Without a KL target the learning rate is the config's, not the one the checkpoint's optimizer state holds
        (rsl-rl's load restores that one, so a changed algorithm.learning_rate was ignored on --resume)."""
        configured = float(self.learning_rate)
        iteration = super().load(loaded_dict, load_cfg, strict)
        if self.device_side_update:
            self._keep_optimizer_settings()
        if (load_cfg is None or load_cfg.get("optimizer")) and not self._adaptive_learning_rate:
            for group in self.optimizer.param_groups:
                if isinstance(group["lr"], torch.Tensor):
                    group["lr"].fill_(configured)
                else:
                    group["lr"] = configured
            self.learning_rate = configured
        if (load_cfg is None or load_cfg.get("optimizer")) and loaded_dict.get("frozen_actor_updates", 0):
            self.freeze_actor(int(loaded_dict["frozen_actor_updates"]))
        return iteration

    def _keep_optimizer_settings(self) -> None:
        """Adam as built here after a checkpoint's optimizer state is loaded: torch takes every setting of a param
        group from the checkpoint, and one saved on the CPU or by rsl-rl's PPO (capturable False, fused off, a float
        rate) cannot be captured in the CUDA graph. Its step counts go to the parameters' device, as fused and
        capturable Adam keep them."""
        built = {key: self.optimizer.defaults[key] for key in ("fused", "foreach", "capturable")}  # load keeps these
        for group in self.optimizer.param_groups:
            group.update(built)
            for parameter in group["params"]:
                state = self.optimizer.state.get(parameter, {})
                if "step" in state:
                    state["step"] = state["step"].to(parameter.device, torch.float32)
        self._learning_rate_tensor()

    def _act_step(self) -> None:
        super().act(self._act_observations)
        self._act_transition = dict(vars(self.transition))

    def _learning_rate_tensor(self) -> torch.Tensor:
        """The optimizer's learning rate as a device tensor (a checkpoint of rsl-rl's PPO restores a float)."""
        group = self.optimizer.param_groups[0]
        if not isinstance(group["lr"], torch.Tensor):
            group["lr"] = torch.tensor(float(group["lr"]), device=self.device)
        return group["lr"]

    def _adapt_learning_rate(self, lr: torch.Tensor, kl: torch.Tensor) -> None:
        """rsl-rl's adaptive rule, in place on the device: /1.5 above 2 x desired KL, x1.5 below half of it."""
        lower = torch.clamp(lr / 1.5, min=self.MIN_LEARNING_RATE)
        higher = torch.clamp(lr * 1.5, max=self.MAX_LEARNING_RATE)
        lr.copy_(torch.where(kl > 2.0 * self.desired_kl, lower,
                             torch.where((kl < 0.5 * self.desired_kl) & (kl > 0.0), higher, lr)))

    def _minibatch(self) -> RolloutStorage.Batch:
        """The mini-batch of rollout rows ``self._batch_indices``, gathered from the storage (as rsl-rl's
        generator does). Under graphs the gather is part of the mini-batch graph, which reads the index tensor the
        host refills, so nothing is copied into a static batch and the host issues no gathers."""
        storage, rows = self.storage, self._batch_indices

        def gathered(tensor: torch.Tensor) -> torch.Tensor:
            return tensor.flatten(0, 1)[rows]

        return RolloutStorage.Batch(
            observations=storage.observations.flatten(0, 1)[rows], actions=gathered(storage.actions),
            values=gathered(storage.values), advantages=self._advantages.flatten(0, 1)[rows],
            returns=gathered(storage.returns), old_actions_log_prob=gathered(storage.actions_log_prob),
            old_distribution_params=tuple(gathered(p) for p in storage.distribution_params))

    def _minibatch_step(self) -> None:
        """One PPO mini-batch step on the rows ``self._batch_indices``: gradients, their average over the ranks,
        Adam."""
        self._minibatch_gradients()
        if self.is_multi_gpu:
            self._all_reduce_gradients()
        self._apply_gradients()

    def _minibatch_gradients(self) -> None:
        """PPO's loss on the rows ``self._batch_indices``, its gradients (and the KL divergence) into
        ``self._gradients``, the losses added to ``self._loss_sums``."""
        batch = self._minibatch()
        advantages = batch.advantages.squeeze(-1)
        if self.normalize_advantage_per_mini_batch:
            advantages = (advantages - advantages.mean()) / (advantages.std() + 1e-8)
        device_type = torch.device(self.device).type
        # (autocast's cast cache cannot be used under CUDA graph capture)
        with torch.amp.autocast(device_type=device_type, enabled=self.use_mixed_precision, dtype=torch.bfloat16,
                                cache_enabled=False):
            self.actor(batch.observations, stochastic_output=True)
            log_prob = self.actor.get_output_log_prob(batch.actions)
            entropy = self.actor.output_entropy.mean()
            values = self.critic(batch.observations)
            ratio = torch.exp(log_prob - batch.old_actions_log_prob.squeeze(-1))
            clipped_ratio = ratio.clamp(1.0 - self.clip_param, 1.0 + self.clip_param)
            surrogate_loss = torch.max(-advantages * ratio, -advantages * clipped_ratio).mean()
            if self.use_clipped_value_loss:
                clipped_values = batch.values + (values - batch.values).clamp(-self.clip_param, self.clip_param)
                value_loss = torch.max((values - batch.returns).square(),
                                       (clipped_values - batch.returns).square()).mean()
            else:
                value_loss = (values - batch.returns).square().mean()
            loss = surrogate_loss + self.value_loss_coef * value_loss - self.entropy_coef * entropy
        self._gradients.zero_()
        for parameter, view in zip(self._parameters, self._gradient_views):
            parameter.grad = view  # backward accumulates into the shared buffer (no kernel: Python only)
        if self._adaptive_learning_rate:
            with torch.no_grad():
                self._gradients[-1] = self.actor.get_kl_divergence(batch.old_distribution_params,
                                                                   self.actor.output_distribution_params).mean()
        loss.backward()
        self._loss_sums += torch.stack([value_loss, surrogate_loss, entropy]).detach()

    def _all_reduce_gradients(self) -> None:
        """Sum the gradients and KL of all ranks: one NCCL all-reduce (gloo on the CPU), no host wait."""
        torch.distributed.all_reduce(self._gradients, op=torch.distributed.ReduceOp.SUM)

    def _apply_gradients(self) -> None:
        """The rank-averaged gradients: adapt the learning rate to the KL, clip, one Adam step."""
        if self.is_multi_gpu:
            self._gradients /= self.gpu_world_size
        if self._adaptive_learning_rate:  # every rank has the same mean KL, so the same learning rate
            # a held actor's KL is rounding noise (TF32), not a policy change: the rate must not adapt to it
            self._adapt_learning_rate(self._learning_rate_tensor(), self._gradients[-1] * self._actor_gradient_scale)
        self._gradients[:self._actor_size] *= self._actor_gradient_scale
        nn.utils.clip_grad_norm_(self.actor.parameters(), self.max_grad_norm)
        nn.utils.clip_grad_norm_(self.critic.parameters(), self.max_grad_norm)
        self.optimizer.step()

    @property
    def _adaptive_learning_rate(self) -> bool:
        return self.desired_kl is not None and self.schedule == "adaptive"

    def _update_normalization(self) -> None:
        """The models' observation statistics from this rollout (the critic's only while the actor is held
        fixed). rsl-rl's normaliser assigns a new std tensor; it is copied back into the one the mini-batch graph
        reads."""
        observations = self.storage.observations.flatten(0, 1)
        for model in (self.critic,) if self._frozen_actor_updates else (self.actor, self.critic):
            before = dict(model.named_buffers())
            model.update_normalization(observations)
            for name, buffer in list(model.named_buffers()):
                if name in before and buffer is not before[name]:
                    before[name].copy_(buffer)
                    owner, _, leaf = name.rpartition(".")
                    setattr(model.get_submodule(owner), leaf, before[name])

    def _parameters_finite(self) -> torch.Tensor:
        return torch.stack([torch.isfinite(p).all() for p in chain(self.actor.parameters(),
                                                                      self.critic.parameters())]).all()

    def _check_finite(self, losses: dict[str, float], parameters_finite: bool) -> None:
        """Stop at the first non-finite loss or parameter: a NaN policy must not train on and be saved."""
        if parameters_finite and all(math.isfinite(v) for v in losses.values()):
            return
        shown = ", ".join(f"{k} {v:.3g}" for k, v in losses.items())
        raise FloatingPointError(
            f"PPO update gave a non-finite {'loss' if parameters_finite else 'parameter'} (losses: {shown}; learning "
            f"rate {self.learning_rate:.3g}); training stops here. Lower algorithm.learning_rate or look for "
            f"infinite rewards or observations.")

    def update(self) -> dict[str, float]:
        if not self.device_side_update:
            losses = super().update()
            self._check_finite(losses, bool(self._parameters_finite()))
            return losses
        self._loss_sums.zero_()
        # rsl-rl's compute_returns binds the storage's advantages to a new tensor; the graphs read this one
        if self._advantages is None:
            self._advantages = self.storage.advantages.clone()
        else:
            self._advantages.copy_(self.storage.advantages)
        # the mini-batches of rsl-rl's mini_batch_generator: the same random permutation, cut in order
        size = self.storage.num_envs * self.storage.num_transitions_per_env // self.num_mini_batches
        permutation = torch.randperm(self.num_mini_batches * size, device=self.device)
        with self._update_models():
            for _ in range(self.num_learning_epochs):
                for rows in permutation.split(size):
                    if self._graphed and self._batch_indices is not None:
                        self._batch_indices.copy_(rows)  # the tensor the graphs read
                    else:
                        self._batch_indices = rows.clone() if self._graphed else rows
                    for stage in self._minibatch_stages:
                        stage()
        self._update_normalization()
        self.storage.clear()
        num_updates = self.num_learning_epochs * self.num_mini_batches
        means = self._loss_sums / num_updates
        finite = self._parameters_finite().float().reshape(1)
        value, surrogate, entropy, learning_rate, finite = torch.cat(
            [means, self._learning_rate_tensor().reshape(1), finite]).tolist()  # the update's one host read
        self.learning_rate = learning_rate  # a float for the logger: the rate this update ended with
        if self._frozen_actor_updates:
            self.freeze_actor(self._frozen_actor_updates - 1)
        losses = {"value": value, "surrogate": surrogate, "entropy": entropy}
        self._check_finite(losses, finite == 1.0)
        return losses
