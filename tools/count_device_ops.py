"""Warp kernel launches, device copies and memsets in one env step and in one post-reset forward, counted on any
device: each is a node of the step's CUDA graph on a GPU, where a few thousand robots make most of them
latency-bound, so their number is a cost the CPU can count. (On the CPU the solver's iterations are a Python loop,
so its launches vary with the state; compare counts of the same state.)

    PYTHONPATH=$PWD python tools/count_device_ops.py --tasks gente_biped gente_quadruped
"""

from __future__ import annotations

import argparse
import collections
import contextlib
from typing import Iterator

import torch
import warp as wp


@contextlib.contextmanager
def counting() -> Iterator[collections.Counter]:
    """Counts wp.launch / wp.launch_tiled / replayed recorded launches ("launch"), wp.copy ("copy") and
    array.zero_ / array.fill_ ("memset") while the block runs."""
    counts = collections.Counter()
    originals = {(wp, "launch"): wp.launch, (wp, "launch_tiled"): wp.launch_tiled, (wp, "copy"): wp.copy,
                 (wp.array, "zero_"): wp.array.zero_, (wp.array, "fill_"): wp.array.fill_,
                 (wp.Launch, "launch"): wp.Launch.launch}
    kinds = {"launch": "launch", "launch_tiled": "launch", "copy": "copy", "zero_": "memset", "fill_": "memset"}

    def counted(fn, kind):
        def call(*args, **kwargs):
            counts[kind] += 1
            return fn(*args, **kwargs)
        return call

    for (owner, name), fn in originals.items():
        setattr(owner, name, counted(fn, kinds[name]))
    try:
        yield counts
    finally:
        for (owner, name), fn in originals.items():
            setattr(owner, name, fn)


def count_step(env) -> tuple[dict, dict]:
    """(the post-reset forward with one world reset, the env step after it): counts of each kind. The forward is
    counted apart: a GPU runs it every step, the CPU only when a world resets."""
    reset = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    reset[0] = True
    with counting() as forward:
        env.sim.forward(reset)
    with counting() as step:
        env.step(torch.zeros(env.num_envs, env.num_actions, device=env.device))
    return dict(forward), dict(step)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", nargs="+", default=["gente_biped", "gente_quadruped"])
    ap.add_argument("--num_envs", type=int, default=4)
    ap.add_argument("--device", default="cpu")
    args = ap.parse_args(argv)
    from legged_gente.envs.task_registry import task_registry

    for task in args.tasks:
        cfg, _ = task_registry.get_cfgs(task)
        cfg.env.num_envs = args.num_envs
        torch.manual_seed(0)
        env, _ = task_registry.make_env(task, env_cfg=cfg, args=argparse.Namespace(device=args.device))
        for _ in range(3):  # past the first steps' one-time work (kernel loads, the stage's first computation)
            env.step(torch.zeros(env.num_envs, env.num_actions, device=env.device))
        forward, step = count_step(env)
        print(f"{task}: env step {step}, post-reset forward {forward}")


if __name__ == "__main__":
    main()
