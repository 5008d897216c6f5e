"""One CUDA graph for a whole step: the env step (torch operations and Warp launches recorded together) or
a PPO mini-batch update (forward, backward, optimizer step).

Such a step is a few hundred small kernels; launched one by one from Python, the host takes longer to issue
them than the GPU takes to run them. ``StepGraph`` runs the step body once normally (this loads every Warp
module, warms up torch and creates lazily built state such as the optimizer's), records it into one
``torch.cuda.CUDAGraph`` on the second call (Warp, if the body launches Warp kernels, joins torch's capture
with ``wp.capture_begin(external=True)``), and from then on each call is a single graph launch.

What a graph replays is fixed at capture: the body must not branch on host values that change between steps
nor wait for the device, and state kept from one step to the next must be updated in place (``x[:] = ...``),
because a replay reads and writes the tensors that existed at capture. Tensors the body recomputes from
scratch each step may be rebound; they are named in ``outputs`` and rebound to the graph's tensors after
every replay. Any other tensor attribute that the body rebinds is an error at capture.
"""

from __future__ import annotations

from typing import Callable

import torch
import warp as wp
from tensordict import TensorDict


def rebound_attributes(owner, before: dict) -> dict:
    """``owner``'s attributes that are not the objects they were in ``before`` (a copy of ``vars(owner)``)."""
    return {name: value for name, value in vars(owner).items() if before.get(name) is not value}


def carried_state_rebound(rebound: dict, outputs) -> list[str]:
    """The rebound tensor attributes that are not step outputs: state a graph replay would lose."""
    return sorted(name for name, value in rebound.items()
                  if isinstance(value, (torch.Tensor, TensorDict)) and name not in outputs)


class StepGraph:
    """``body()`` (a method of ``owner``) run through one CUDA graph from its second call on; ``warp``: the
    body launches Warp kernels too."""

    def __init__(self, owner, body: Callable[[], None], outputs: tuple[str, ...], device: str, warp: bool = True):
        self.owner, self.body, self.outputs, self.device = owner, body, frozenset(outputs), torch.device(device)
        self.warp = warp
        self.graph: torch.cuda.CUDAGraph | None = None
        self.stream: torch.cuda.Stream | None = None  # warm-up and capture run here (torch's recipe)
        self.warmed_up = False
        self.bindings: dict = {}

    def __call__(self) -> None:
        if self.graph is None:
            current = torch.cuda.current_stream(self.device)
            if self.stream is None:
                self.stream = torch.cuda.Stream(self.device)
            self.stream.wait_stream(current)
            if not self.warmed_up:
                # on the capture stream: autograd's gradient accumulators created here keep running there
                with torch.cuda.stream(self.stream):
                    self._run_body()
                current.wait_stream(self.stream)
                self.warmed_up = True
                return
            self._capture()
        self.graph.replay()
        vars(self.owner).update(self.bindings)

    def _run_body(self) -> None:
        """The body with Warp launching on torch's current stream."""
        if self.warp:
            with wp.ScopedStream(wp.stream_from_torch(torch.cuda.current_stream(self.device)), sync_enter=False):
                self.body()
        else:
            self.body()

    def _capture(self) -> None:
        before = dict(vars(self.owner))
        graph = torch.cuda.CUDAGraph()
        with torch.cuda.graph(graph, stream=self.stream, capture_error_mode="thread_local"):
            if self.warp:
                warp_stream = wp.stream_from_torch(self.stream)
                with wp.ScopedStream(warp_stream, sync_enter=False):
                    wp.capture_begin(stream=warp_stream, force_module_load=False, external=True)
                    try:
                        self.body()
                    finally:
                        wp.capture_end(stream=warp_stream)
            else:
                self.body()
        rebound = rebound_attributes(self.owner, before)
        carried = carried_state_rebound(rebound, self.outputs)
        if carried:
            raise RuntimeError(
                f"{type(self.owner).__name__}'s step rebinds {carried} while being captured as a CUDA graph. State "
                f"kept from one step to the next must be updated in place (self.x[:] = ..., self.x.copy_(...)); a "
                f"tensor recomputed from scratch every step goes in the graph's outputs (an env's step_outputs). "
                f"Or turn the graph off (an env's cfg.sim.cuda_graph).")
        self.bindings = rebound
        self.graph = graph
