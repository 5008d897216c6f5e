"""Why do robots diverge in an evaluation? Rolls the evaluation of ``gente-evaluate`` step by step and, for every
robot the first time its world breaks down, records what the env saw: the reason (non-finite state, a joint or
base faster than ``sim.max_qvel``, constraint rows over ``njmax``; or only a base faster than the evaluator's
``MAX_BASE_SPEED``), the fastest dof, MuJoCo-Warp's per-world overflow bits (``d.overflow``, sticky until the world
resets), the step and the terrain. It also tracks the buffers all worlds share: the contacts (``nacon``) against
``naconmax``, the broadphase pairs (``ncollision``), the largest ``nefc``, and how many worlds ever raised each
overflow bit (diverged or not).

    python tools/diagnose_divergence.py --task gente_quadruped --pretrained --benchmark gente_original \\
        --robots_per_terrain 16 --device cuda --csv diverged.csv

``--items``/``--limit`` choose the terrains, as in gente-evaluate: a cause that shows with the whole benchmark but
not with its worst terrains alone lies in what the worlds share (buffers, or the terrain's size: that is how the
heightfield precision loss of docs/terrain.md was found). ``--plain_launches`` steps the env without its CUDA graph
and compiled torch logic, to tell a graph or compiler effect from the physics.

``--contacts`` prints each diverged robot's terrain contacts (the geom, its penetration, height and normal) as the
step before left them and, for a launched robot (its world is not reset), as its step left them: that is how a
biped shank given a tree's top face 2.45 m above it was found (docs/forces.md). The penetration is the one the
solver saw, after the force fields' contact filter, so since that find at most ``forces.terrain_contact_max_depth``
(``sole_contact_max_depth`` for an analytic sole): a contact at the cap whose height lies far from its geom is such
a face. ``--launch_speed`` counts a base faster than it as launched (default the evaluator's ``MAX_BASE_SPEED``):
lower, it finds the launches that stay under the evaluator's threshold, which the same cause makes far more often.
"""

from __future__ import annotations

import argparse
import csv
from collections import Counter
from pathlib import Path

import mujoco
import mujoco_warp as mjw
import torch
import warp as wp

REASONS = {1: "non-finite", 2: "qvel>max_qvel", 4: "nefc>njmax"}
OVERFLOWS = {int(b): b.name for b in mjw.OverflowType if b.name not in ("NONE", "ALL")}
COLUMNS = ("world", "tile", "item", "step", "flagged_by_env", "launched", "reason", "fastest_dof", "base_speed",
           "overflow_bits")
"""The keys of a row of ``diagnose`` (one per diverged robot): the CSV's header."""


def _names(bits: int, table: dict[int, str]) -> str:
    return "|".join(name for bit, name in table.items() if bits & bit)


def terrain_contacts(sim) -> dict:
    """The contacts of robot geoms with the terrain (geoms of the world body) now in ``sim.d``, on the device."""
    c, k = sim.d.contact, int(wp.to_torch(sim.d.nacon)[0])
    geom = wp.to_torch(c.geom)[:k].long()
    ground = wp.to_torch(sim.m.geom_bodyid).long()[geom] == 0
    keep = ground[:, 0] ^ ground[:, 1]
    robot = torch.where(ground[:, 0], geom[:, 1], geom[:, 0])[keep]
    # frame row 0 is the normal from geom[0] to geom[1]: turned to point from the terrain to the robot geom
    sign = torch.where(ground[:, 0], 1.0, -1.0)[keep].unsqueeze(1)
    return {"world": wp.to_torch(c.worldid)[:k][keep], "geom": robot, "dist": wp.to_torch(c.dist)[:k][keep],
            "pos": wp.to_torch(c.pos)[:k][keep], "normal": sign * wp.to_torch(c.frame)[:k, 0][keep]}


def describe_contacts(contacts: dict, world: int, mjm) -> list[str]:
    """One line per terrain contact of ``world``: the robot geom, its penetration as the solver saw it (the contact
    filter's cap and rut applied), the contact point's height and the normal from the terrain to the geom."""
    mine = contacts["world"] == world
    lines = []
    for g, d, p, n in zip(contacts["geom"][mine].tolist(), contacts["dist"][mine].tolist(),
                          contacts["pos"][mine].tolist(), contacts["normal"][mine].tolist()):
        name = mujoco.mj_id2name(mjm, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom {g}"
        lines.append(f"{name}: dist {d:+.3f} m at z {p[2]:.2f} m, normal ({n[0]:+.2f}, {n[1]:+.2f}, {n[2]:+.2f})")
    return lines or ["no terrain contact"]


def diagnose(evaluation, policy, progress: bool = False, launch_speed: float | None = None,
             contacts: bool = False) -> tuple[list[dict], dict]:
    """Roll ``policy`` through ``evaluation`` (an ``Evaluation``); one row per robot whose world diverged (at its
    first divergence) or whose base moved faster than ``launch_speed`` (default the evaluator's
    ``MAX_BASE_SPEED``), and a summary of the shared buffers; with ``contacts``, the summary's "contacts" holds
    each such robot's terrain contacts before and after its step (``describe_contacts``)."""
    from tqdm import tqdm

    from legged_gente.evaluation.evaluator import MAX_BASE_SPEED

    launch_speed = MAX_BASE_SPEED if launch_speed is None else launch_speed
    env, sim = evaluation.env, evaluation.env.sim
    n, dev = env.num_envs, env.device
    overflow, nacon, ncollision = wp.to_torch(sim.d.overflow), wp.to_torch(sim.d.nacon), wp.to_torch(sim.d.ncollision)
    # the env's own test, seen from inside the step (before the step resets the world): which part fired, the
    # fastest dof, the overflow bits; written in place, so the step's CUDA graph keeps writing them
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
    task = evaluation.make_task()
    items = evaluation.items
    active = torch.ones(n, dtype=torch.bool, device=dev)
    ever_bits = torch.zeros(n, dtype=torch.int32, device=dev)
    peak = {"nacon": 0, "ncollision": 0, "nefc": 0}
    rows, described = [], []
    try:
        with torch.inference_mode():
            env.reset()
            obs = env.set_commands(task.commands(env.base_pos[:, :2], env.commands), task.still())
            for step in tqdm(range(1, evaluation.num_steps + 1), disable=not progress, unit="step"):
                before = terrain_contacts(sim) if contacts else None
                _, _, dones, _ = env.step(policy(obs))
                speed = torch.linalg.norm(sim.qvel[:, 0:3], dim=1)
                launched = ~dones & ~(speed <= launch_speed)
                new = active & (env.diverged_buf | launched)
                ever_bits |= overflow.to(torch.int32) | torch.where(new, bits_in_step, 0)
                peak = {"nacon": max(peak["nacon"], int(nacon[0])),
                        "ncollision": max(peak["ncollision"], int(ncollision[0])),
                        "nefc": max(peak["nefc"], int(sim.nefc.amax()))}
                for w in torch.nonzero(new).flatten().tolist():
                    tile = int(evaluation.tile[w])
                    rows.append({"world": w, "tile": tile, "item": items[tile].id, "step": step,
                                 "flagged_by_env": bool(env.diverged_buf[w]), "launched": bool(launched[w]),
                                 "reason": _names(int(reason[w]), REASONS) if env.diverged_buf[w] else "",
                                 "fastest_dof": int(fastest_dof[w]), "base_speed": float(speed[w]),
                                 "overflow_bits": _names(int(ever_bits[w]), OVERFLOWS)})
                    if contacts:
                        lines = [f"world {w} ({items[tile].id}), step {step}, base {float(speed[w]):.1f} m/s; "
                                 f"terrain contacts after step {step - 1}:"]
                        lines += ["  " + line for line in describe_contacts(before, w, sim.mjm)]
                        if env.diverged_buf[w]:
                            lines.append(f"  after step {step}: its world was reset in the step")
                        else:
                            lines.append(f"  after step {step}:")
                            lines += ["  " + line for line in describe_contacts(terrain_contacts(sim), w, sim.mjm)]
                        described.append("\n".join(lines))
                active &= ~dones & ~new
                task.update(env.base_pos[:, :2], active)
                obs = env.set_commands(task.commands(env.base_pos[:, :2], env.commands), task.still())
    finally:
        env._diverged = env_diverged
    summary = {"worlds": n, "steps": evaluation.num_steps, "naconmax": int(sim.d.naconmax), "njmax": int(sim.d.njmax),
               **{f"max_{k}": v for k, v in peak.items()},
               "worlds_raising": {name: int(((ever_bits & bit) != 0).sum()) for bit, name in OVERFLOWS.items()},
               "launch_speed": launch_speed}
    if contacts:
        summary["contacts"] = described
    return rows, summary


def report(rows: list[dict], summary: dict) -> str:
    lines = [f"{summary['worlds']} worlds, {summary['steps']} steps; diverged robots: {len(rows)} "
             f"(env flag {sum(r['flagged_by_env'] for r in rows)}, launched only "
             f"{sum(r['launched'] and not r['flagged_by_env'] for r in rows)}, base over "
             f"{summary['launch_speed']:g} m/s)"]
    for name in REASONS.values():
        lines.append(f"  env reason {name}: {sum(name in r['reason'].split('|') for r in rows)}")
    dofs = Counter(r["fastest_dof"] for r in rows if "qvel" in r["reason"])
    lines.append(f"  fastest dof of the qvel cases: {dofs.most_common()}")
    lines.append(f"max nacon {summary['max_nacon']} of naconmax {summary['naconmax']}; max ncollision "
                 f"{summary['max_ncollision']}; max nefc {summary['max_nefc']} of njmax {summary['njmax']}")
    for name, count in summary["worlds_raising"].items():
        among = sum(name in r["overflow_bits"].split("|") for r in rows)
        if count or among:
            lines.append(f"  overflow {name:14s}: worlds that raised it {count} (diverged robots' worlds: {among})")
    lines.append(f"worst terrains: {Counter(r['item'] for r in rows).most_common(10)}")
    lines += summary.get("contacts", [])
    return "\n".join(lines)


def write_csv(path: str, rows: list[dict]) -> str:
    """The rows under ``COLUMNS``' header (the header alone when no robot diverged); what was written, in words."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    return f"{path}: {len(rows)} diverged robots" if rows else f"{path}: header only, no robot diverged"


def main(argv=None) -> None:
    from legged_gente.envs.base.step_runner import StepRunner
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import Evaluation, load_policy
    from legged_gente.utils.args import resolve_device, run_command

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--task", default="gente_quadruped")
    src = p.add_mutually_exclusive_group()
    src.add_argument("--pretrained", action="store_true", help="the policy shipped for --task")
    src.add_argument("--checkpoint", help="rsl-rl checkpoint or run folder (neither: zero actions)")
    p.add_argument("--benchmark", default="gente_original")
    p.add_argument("--items", nargs="+")
    p.add_argument("--limit", type=int)
    p.add_argument("--robots_per_terrain", type=int, default=16)
    p.add_argument("--episode_s", type=float, default=10.0)
    p.add_argument("--seed", type=int, default=0, help="as gente-evaluate's --seed (commands, spawn points)")
    p.add_argument("--device", default="cpu")
    p.add_argument("--plain_launches", action="store_true", help="no CUDA graph, no torch.compile in the env step")
    p.add_argument("--no_progress", action="store_true", help="no progress bar")
    p.add_argument("--launch_speed", type=float, help="base speed (m/s) counted as launched (default: the "
                                                         "evaluator's MAX_BASE_SPEED)")
    p.add_argument("--contacts", action="store_true", help="print each such robot's terrain contacts")
    p.add_argument("--csv", help="one row per diverged robot (the header alone when none diverged)")
    args = p.parse_args(argv)
    if args.launch_speed is not None and not (0.0 < args.launch_speed < float("inf")):
        p.error(f"--launch_speed {args.launch_speed} must be a finite speed > 0 m/s (or left out: the evaluator's "
                f"MAX_BASE_SPEED).")
    try:
        args.device = resolve_device(args.device)  # a GPU that is not there: one line, before the env is built
    except ValueError as error:
        p.error(str(error))

    def build(args):
        """The evaluation and the policy; a wrong benchmark, item, task or checkpoint is one line (run_command)."""
        items = load_benchmark(args.benchmark, args.items)[: args.limit]
        evaluation = Evaluation(args.task, items, args.robots_per_terrain, args.device, args.episode_s, "velocity",
                                args.seed)
        if args.plain_launches:
            evaluation.env._runner = StepRunner(evaluation.env, compile=False, graph=False)
        policy = load_policy(evaluation, checkpoint=args.checkpoint, pretrained=args.pretrained,
                             baseline=None if (args.checkpoint or args.pretrained) else "zero")
        return evaluation, policy

    evaluation, policy = run_command(p.prog, build, args)
    rows, summary = diagnose(evaluation, policy, progress=not args.no_progress, launch_speed=args.launch_speed,
                             contacts=args.contacts)
    print(report(rows, summary))
    if args.csv:
        print(write_csv(args.csv, rows))


if __name__ == "__main__":
    main()
