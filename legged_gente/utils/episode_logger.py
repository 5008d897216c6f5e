"""rsl-rl's training logger without its host sync in every rollout step.

rsl-rl 5.5's ``Logger.process_env_step`` finds the finished episodes with ``nonzero()`` and copies their
returns to the host at every env step: the CPU waits for the GPU to finish the step before it can launch the
next one, so the two never overlap. ``DeferredLogger`` keeps the per-step (done, return, length) tensors on
the device and moves them to the host once per iteration, in ``log``. The numbers it logs are the same.

It also ends training at a wall-clock deadline (``gente-train --max_minutes``) or when a stop was asked for
(``gente-train``'s Ctrl-C or SIGTERM sets ``stop_signal``): ``log`` runs once per iteration, after the policy
update, so stopping there leaves a whole iteration to save.
"""

from __future__ import annotations

import time

import torch
import torch.distributed as dist
from rsl_rl.utils.logger import Logger

from legged_gente.utils.signals import take_back


class TimeLimitReached(Exception):
    """Training reached its wall-clock deadline after a whole iteration (raised by ``DeferredLogger.log``)."""


class StopRequested(Exception):
    """A signal asked training to stop, and the iteration it arrived in has finished (raised by
    ``DeferredLogger.log``)."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


class DeferredLogger(Logger):
    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._finished: list[tuple[torch.Tensor, torch.Tensor, torch.Tensor]] = []
        self.deadline: float | None = None
        """``time.monotonic()`` after which training stops at the end of the iteration (None: never)."""
        self.last_iteration: int | None = None
        """The last iteration logged, so finished, in this process (None: none yet): what a stopped run saves."""
        self.stop_signal: int | None = None
        """The signal that asked training to stop at the end of the iteration (None: none)."""

    def process_env_step(self, rewards: torch.Tensor, dones: torch.Tensor, extras: dict,
                         intrinsic_rewards: torch.Tensor | None = None) -> None:
        if self.writer is None or intrinsic_rewards is not None:  # nothing to log, or RND's extra buffers
            return super().process_env_step(rewards, dones, extras, intrinsic_rewards)
        if "episode" in extras:
            self.ep_extras.append(extras["episode"])
        elif "log" in extras:
            self.ep_extras.append(extras["log"])
        self.cur_reward_sum += rewards
        self.cur_episode_length += 1
        done = dones > 0
        self._finished.append((done, self.cur_reward_sum.clone(), self.cur_episode_length.clone()))
        self.cur_reward_sum.masked_fill_(done, 0.0)
        self.cur_episode_length.masked_fill_(done, 0.0)

    def _store_code_state(self) -> list[str]:
        """Nothing: the run's config.json records the code version (commit or package version) instead of
        rsl-rl's git/ folder, which stays empty outside a checkout of rsl-rl itself."""
        return []

    def flush(self) -> None:
        """Move the episodes that finished since the last flush into the host-side buffers (one sync)."""
        if not self._finished:
            return
        done, returns, lengths = (torch.stack(parts) for parts in zip(*self._finished))
        self._finished.clear()
        self.rewbuffer.extend(returns[done].tolist())
        self.lenbuffer.extend(lengths[done].tolist())

    def log(self, it: int, *args, **kwargs) -> None:
        self.last_iteration = it
        take_back()  # a signal must reach the stop handlers, not Triton's (utils/signals.py)
        self.flush()
        self._drop_undefined_means()
        super().log(it, *args, **kwargs)
        late, signum = self._stop_reason()
        if signum:
            raise StopRequested(signum)
        if late:
            raise TimeLimitReached()

    def _drop_undefined_means(self) -> None:
        """Leave out the episode values that are NaN (the env's mean of a reward term when no episode ended): rsl-rl
        skips a key an env did not send, where it would log the NaN as a point. One host read per iteration."""
        scalars = [(extras, key) for extras in self.ep_extras for key, value in extras.items()
                   if isinstance(value, torch.Tensor) and value.numel() == 1]
        if not scalars:
            return
        undefined = torch.stack([extras[key].reshape(()).float() for extras, key in scalars]).isnan().tolist()
        for (extras, key), drop in zip(scalars, undefined):
            if drop:
                del extras[key]

    def _stop_reason(self) -> tuple[bool, int]:
        """(past the deadline, the signal that asked to stop or 0) on any rank: every rank must stop at the same
        iteration, or the ones that go on would wait forever in the next gradient all-reduce (a signal reaches
        the ranks at different points of an iteration). On several ranks, one small all-reduce per iteration."""
        late = self.deadline is not None and time.monotonic() >= self.deadline
        signum = self.stop_signal or 0
        if not (dist.is_available() and dist.is_initialized()):
            return late, signum
        flags = torch.tensor([float(late), float(signum)], device=self.device)
        dist.all_reduce(flags, op=dist.ReduceOp.MAX)
        late, signum = flags.tolist()
        return bool(late), int(signum)
