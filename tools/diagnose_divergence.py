"""Why do robots diverge in an evaluation? Rolls the evaluation of ``gente-evaluate`` step by step and, for every
robot the first time its world breaks down, records what the env saw: the reason (non-finite state, a joint or
base faster than ``sim.max_qvel``, constraint rows over ``njmax``, a base faster than the evaluator's
``MAX_BASE_SPEED``), MuJoCo-Warp's per-world overflow bits (``d.overflow``, sticky until the world resets), the
step, the base height above the terrain and its tile. It also tracks the shared buffers over the run: the
contacts of all worlds (``nacon``) against ``naconmax``, the broadphase pairs (``ncollision``), the largest
``nefc``, and how many worlds ever raised each overflow bit (diverged or not).

    python tools/diagnose_divergence.py --task gente_quadruped --pretrained --benchmark gente_original \
        --robots_per_terrain 16 --device cuda --csv diverged.csv

``--items``/``--limit`` choose the terrains, as in gente-evaluate (running the worst terrains alone and within the
whole benchmark tells a per-world cause from one of the buffers all worlds share).
"""

from __future__ import annotations

import argparse
import csv

import mujoco_warp as mjw
import torch
import warp as wp

REASONS = {1: "non-finite", 2: "qvel>max_qvel", 4: "nefc>njmax"}


def main() -> None:
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import MAX_BASE_SPEED, Evaluation, load_policy

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--task", default="gente_quadruped")
    p.add_argument("--pretrained", action="store_true")
    p.add_argument("--checkpoint")
    p.add_argument("--benchmark", default="gente_original")
    p.add_argument("--items", nargs="+")
    p.add_argument("--limit", type=int)
    p.add_argument("--robots_per_terrain", type=int, default=16)
    p.add_argument("--episode_s", type=float, default=10.0)
    p.add_argument("--device", default="cpu")
    p.add_argument("--set", nargs="*", default=[], metavar="PATH=VALUE",
                   help="env config overrides before the env is built, e.g. sim.nconmax=64")
    p.add_argument("--csv", help="one row per diverged robot")
    args = p.parse_args()

    items = load_benchmark(args.benchmark, args.items)[: args.limit]
    if args.set:
        from legged_gente.envs.task_registry import task_registry
        from legged_gente.utils.args import apply_overrides

        env_cfg, train_cfg = task_registry.get_cfgs(args.task)
        apply_overrides(args.set, env_cfg, None)
        original = task_registry.get_cfgs
        task_registry.get_cfgs = lambda name: (env_cfg, train_cfg) if name == args.task else original(name)
    ev = Evaluation(args.task, items, args.robots_per_terrain, args.device, args.episode_s, "velocity", 0)
    env, sim = ev.env, ev.env.sim
    policy = load_policy(ev, checkpoint=args.checkpoint, pretrained=args.pretrained,
                         baseline=None if (args.checkpoint or args.pretrained) else "zero")
    task = ev.make_task()
    overflow = wp.to_torch(sim.d.overflow)
    nacon, ncollision = wp.to_torch(sim.d.nacon), wp.to_torch(sim.d.ncollision)
    n = env.num_envs
    dev = env.device
    # the env's own test, seen from inside the step (before the step resets the world): which part fired, which
    # dof was fastest, and the overflow bits the world had raised; in-place writes, so the step's graph keeps them
    reason = torch.zeros(n, dtype=torch.int32, device=dev)
    fastest_dof = torch.zeros(n, dtype=torch.int64, device=dev)
    bits_in_step = torch.zeros(n, dtype=torch.int32, device=dev)
    env_diverged = env._diverged

    def diverged_with_reasons():
        nonfinite = ~torch.isfinite(sim.qpos).all(1)
        fast = ~(sim.qvel.abs().amax(1) <= env.max_qvel)
        rows_over = sim.nefc > env.njmax
        reason.copy_(nonfinite.int() | (fast.int() << 1) | (rows_over.int() << 2))
        fastest_dof.copy_(sim.qvel.abs().argmax(1))
        bits_in_step.copy_(overflow.to(torch.int32))
        return env_diverged()

    env._diverged = diverged_with_reasons
    active = torch.ones(n, dtype=torch.bool, device=dev)
    ever_bits = torch.zeros(n, dtype=torch.int32, device=dev)
    max_nacon = torch.zeros((), dtype=torch.int32, device=dev)
    max_ncoll = torch.zeros((), dtype=torch.int32, device=dev)
    max_nefc = torch.zeros((), dtype=torch.int32, device=dev)
    rows = []
    names = {int(b): b.name for b in mjw.OverflowType if b.name not in ("NONE", "ALL")}
    with torch.inference_mode():
        env.reset()
        obs = env.set_commands(task.commands(env.base_pos[:, :2], env.commands), task.still())
        for step in range(ev.num_steps):
            _, _, dones, _ = env.step(policy(obs))
            # the reasons, as _diverged and the evaluator test them (on the state the step left, before a reset
            # of the diverged world: the env resets it inside the step, so the flag is all that survives)
            speed = torch.linalg.norm(sim.qvel[:, 0:3], dim=1)
            launched = ~dones & ~(speed <= MAX_BASE_SPEED)
            flagged = env.diverged_buf
            new = active & (flagged | launched)
            bits = overflow.to(torch.int32)
            ever_bits |= bits
            max_nacon = torch.maximum(max_nacon, nacon[0])
            max_ncoll = torch.maximum(max_ncoll, ncollision[0])
            max_nefc = torch.maximum(max_nefc, sim.nefc.amax())
            if bool(new.any()):
                for w in torch.nonzero(new).flatten().tolist():
                    rows.append({"world": w, "tile": int(ev.tile[w]), "item": items[int(ev.tile[w])].id,
                                 "step": step + 1, "flagged_by_env": bool(flagged[w]), "launched": bool(launched[w]),
                                 "reason": "|".join(v for k, v in REASONS.items() if int(reason[w]) & k),
                                 "fastest_dof": int(fastest_dof[w]), "base_speed": float(speed[w]),
                                 "overflow_bits_before": "|".join(v for k, v in names.items()
                                                                  if int(ever_bits[w] | bits_in_step[w]) & k),
                                 "nacon_all_worlds": int(nacon[0])})
            active &= ~dones & ~new
            task.update(env.base_pos[:, :2], active)
            obs = env.set_commands(task.commands(env.base_pos[:, :2], env.commands), task.still())
    naconmax, njmax = int(sim.d.naconmax), int(sim.d.njmax)
    print(f"{len(items)} terrains x {args.robots_per_terrain} robots = {n} worlds, {ev.num_steps} steps")
    print(f"diverged robots: {len(rows)} (env flag {sum(r['flagged_by_env'] for r in rows)}, "
          f"launched only {sum(r['launched'] and not r['flagged_by_env'] for r in rows)})")
    for v in REASONS.values():
        print(f"  env reason {v}: {sum(v in r['reason'].split('|') for r in rows)}")
    dofs: dict[int, int] = {}
    for r in rows:
        if "qvel" in r["reason"]:
            dofs[r["fastest_dof"]] = dofs.get(r["fastest_dof"], 0) + 1
    print("  fastest dof of the qvel cases:", sorted(dofs.items(), key=lambda kv: -kv[1]))
    print(f"max nacon {int(max_nacon)} of naconmax {naconmax}; max ncollision {int(max_ncoll)}; "
          f"max nefc {int(max_nefc)} of njmax {njmax}")
    for k, v in names.items():
        ever = int(((ever_bits & k) != 0).sum())
        among = sum(v in r["overflow_bits_before"].split("|") for r in rows)
        if ever or among:
            print(f"  overflow {v:14s}: worlds that raised it {ever} (a diverged robot's world before it diverged: {among})")
    by_item: dict[str, int] = {}
    for r in rows:
        by_item[r["item"]] = by_item.get(r["item"], 0) + 1
    print("worst terrains:", sorted(by_item.items(), key=lambda kv: -kv[1])[:10])
    if args.csv and rows:
        with open(args.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)


if __name__ == "__main__":
    main()
