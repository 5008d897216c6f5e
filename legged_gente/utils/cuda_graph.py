"""One CUDA graph for a whole step: the env step (torch operations and Warp launches recorded together) or
a PPO mini-batch update (forward, backward, optimizer step).

Such a step is a few hundred small kernels; launched one by one from Python, the host takes longer to issue
them than the GPU takes to run them. ``StepGraph`` runs the step body once normally (this loads every Warp
module, warms up torch and creates lazily built state such as the optimizer's), records it into one
``torch.cuda.CUDAGraph`` on the second call (Warp, if the body launches Warp kernels, joins torch's capture
with ``wp.capture_begin(external=True)``), and from then on each call is a single graph launch.

What a graph replays is fixed at capture: the body must not branch on host values that change between steps
nor wait for the device (its owner's wrapper checks what it can, e.g. the env's step runner rejects config reads).
The body may rebind its owner's tensor attributes freely (``self.x = self.x + 1``): a replay reads and writes
the tensors that existed at capture, so at the end of the capture ``StepGraph`` records a copy of every rebound
tensor into the tensor the attribute held before, and binds the attribute back to it. State carried from one
step to the next thus stays in one tensor whatever the body does, at the cost of one device copy per rebound
tensor (none where the body works in place; two where it rebinds one attribute to another's tensor, which is
cloned first so that the copies cannot overwrite each other's sources). Rebound non-tensor attributes (e.g. a dict
of tensors) are bound to the objects the capture made after every replay. Every attribute the capture rebound is
bound back after each replay, so code run eagerly between replays (a reset, refreshed observations) may rebind
them too: the next replay's results are where the attributes point afterwards.
"""

from __future__ import annotations

from typing import Callable

import torch
import warp as wp


def rebound_attributes(owner, before: dict) -> dict:
    """``owner``'s attributes that are not the objects they were in ``before`` (a copy of ``vars(owner)``)."""
    return {name: value for name, value in vars(owner).items() if before.get(name) is not value}


def _same_memory(a: torch.Tensor, b: torch.Tensor) -> bool:
    return a.data_ptr() == b.data_ptr() and a.shape == b.shape and a.stride() == b.stride()


class StepGraph:
    """``body()`` (a method of ``owner``) run through one CUDA graph after ``warmup`` plain calls; ``warp``: the
    body launches Warp kernels too."""

    def __init__(self, owner, body: Callable[[], None], device: str, warp: bool = True, warmup: int = 1):
        self.owner, self.body, self.device = owner, body, torch.device(device)
        self.warp = warp
        self.graph: torch.cuda.CUDAGraph | None = None
        self.stream: torch.cuda.Stream | None = None  # warm-up and capture run here (torch's recipe)
        self.warmup = warmup
        self.bindings: dict = {}

    def __call__(self) -> None:
        if self.graph is None:
            current = torch.cuda.current_stream(self.device)
            if self.stream is None:
                self.stream = torch.cuda.Stream(self.device)
            self.stream.wait_stream(current)
            if self.warmup > 0:
                # on the capture stream: autograd's gradient accumulators created here keep running there
                with torch.cuda.stream(self.stream):
                    self._run_body()
                current.wait_stream(self.stream)
                self.warmup -= 1
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
            kept = self._copy_back(rebound, before)
        self._bind(rebound, kept)
        self.graph = graph

    def _bind(self, rebound: dict, kept: dict) -> None:
        """The owner's attributes as every replay leaves them: the rebound tensors' old tensors (``kept``), the
        other rebound objects as the capture made them."""
        self.bindings = rebound | kept
        vars(self.owner).update(self.bindings)

    def _copy_back(self, rebound: dict, before: dict) -> dict:
        """Record (into the graph) a copy of each rebound tensor into the one its attribute held before the
        capture; those attributes point at their old tensors again. A new value that shares memory with a tensor
        some copy writes (``self.last = self.now; self.now = ...``, or a swap) is cloned before any copy is made,
        so each attribute gets the value the step gave it whatever the order of the copies."""
        kept, copies = {}, []
        for name, new in rebound.items():
            old = before.get(name)
            if not (isinstance(new, torch.Tensor) and isinstance(old, torch.Tensor)):
                continue
            if old.shape != new.shape or old.dtype != new.dtype or old.device != new.device:
                raise RuntimeError(
                    f"{type(self.owner).__name__}.{name} changes from {tuple(old.shape)} {old.dtype} to "
                    f"{tuple(new.shape)} {new.dtype} in a step captured as a CUDA graph; keep its shape and dtype.")
            if not _same_memory(old, new):
                copies.append((old, new))
            kept[name] = old
        written = {old.untyped_storage().data_ptr() for old, _ in copies}
        sources = [new.clone() if new.untyped_storage().data_ptr() in written else new for _, new in copies]
        for (old, _), source in zip(copies, sources):
            old.copy_(source)
        return kept
