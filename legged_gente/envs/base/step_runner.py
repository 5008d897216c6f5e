"""How a LeggedRobot's step is run: eagerly, with its torch logic compiled (torch.compile), and/or as one CUDA graph.

This is the machinery a subclass author never sees. The env's ``_step_body`` is plain torch and Warp; the
runner wraps it from outside:

* ``cfg.sim.torch_compile`` (CUDA): ``_post_physics_step`` (rewards, terminations, resets, curriculum,
  observations) is compiled; the Warp calls in it (``Simulation`` methods) are left out by the backend.
* ``cfg.sim.cuda_graph = "env_step"`` (CUDA): the whole step is recorded into one CUDA graph and replayed
  (``utils.cuda_graph.StepGraph``, which also keeps state carried between steps in one tensor whatever the body
  rebinds).

Both replay what they saw once: a Python value read inside the step is frozen into the compiled code or the
graph. So the step must not read ``cfg``: fixed settings are read at construction, settings a run may change
live in device tensors (``env.params``, ``env.reward_scale_vec``, changed with ``env.set_param``). The runner
checks this rule on every device at the first step, which runs eagerly with ``env.cfg`` watched
(:func:`config_reads`), and raises if the step read any config value.
"""

from __future__ import annotations

import contextlib

import torch

from legged_gente.utils.cuda_graph import StepGraph


class _Watched:
    """A config (sub)object whose attribute reads are recorded in ``reads`` as dotted paths."""

    def __init__(self, target, path: str, reads: list[str]):
        object.__setattr__(self, "_target", target)
        object.__setattr__(self, "_path", path)
        object.__setattr__(self, "_reads", reads)

    def __getattr__(self, name: str):
        value = getattr(self._target, name)
        path = f"{self._path}.{name}"
        if hasattr(value, "__dict__") and not callable(value) and not isinstance(value, type):
            return _Watched(value, path, self._reads)
        self._reads.append(path)
        return value

    def __setattr__(self, name: str, value) -> None:
        setattr(self._target, name, value)


@contextlib.contextmanager
def config_reads(env):
    """Within the block, ``env.cfg`` records every value read from it; yields the list of dotted paths."""
    reads: list[str] = []
    cfg = env.cfg
    env.cfg = _Watched(cfg, "cfg", reads)
    try:
        yield reads
    finally:
        env.cfg = cfg


def check_no_config_reads(env, reads: list[str]) -> None:
    if reads:
        names = sorted(set(reads))
        raise ValueError(  # the user's env code, reported as a user error (one line, exit status 2)
            f"{type(env).__name__}'s step reads {names}: under CUDA graphs and torch.compile such a value is frozen "
            f"at the first steps. Read a fixed setting once in __init__ (self.x = cfg...), or keep a setting that "
            f"changes during training in a tensor (env.params.rewards.<name> for numbers in cfg.rewards, "
            f"env.params.commands.<name>; change them with env.set_param).")


class StepRunner:
    """Calls ``env._step_body()``; see the module docstring. ``compile``/``graph`` default to the env's config
    (both only on CUDA); tests turn ``compile`` on on the CPU."""

    def __init__(self, env, compile: bool | None = None, graph: bool | None = None):
        cuda = env.sim.wp_device.is_cuda
        self.env = env
        self.compile = (cuda and env.cfg.sim.torch_compile) if compile is None else compile
        use_graph = (cuda and env.cfg.sim.cuda_graph == "env_step") if graph is None else graph
        self.graph = StepGraph(env, env._step_body, env.device) if use_graph else None
        self.checked = False
        if self.compile:
            print("[legged_gente] the step's torch logic is compiled (torch.compile) at the second step: about 20 s "
                  "once per num_envs, cached afterwards; --set sim.torch_compile=False turns it off", flush=True)

    def __call__(self) -> None:
        env = self.env
        if not self.checked:
            with config_reads(env) as reads:
                env._step_body()  # eager: the config check, and the graph's first warm-up
            check_no_config_reads(env, reads)
            self.checked = True
            if self.compile:
                # the step's torch logic (a few hundred small operations) fused by TorchInductor into a few
                # dozen kernels; compiled at its next call (the graph's warm-up, before any capture)
                env._post_physics_step = torch.compile(env._post_physics_step, fullgraph=False, dynamic=False)
            return
        if self.graph is not None:
            self.graph()
        else:
            env._step_body()
