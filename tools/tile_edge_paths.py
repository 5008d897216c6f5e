"""How many of a benchmark evaluation's commanded paths run off their terrain's tile, and what they meet there.

``gente-evaluate`` lays the benchmark's terrains out side by side as tiles (a 5 m flat border at height 0 around
the grid), spawns each tile's robots at its spawn point and gives each a fixed command (seeded as ``--seed``). A
robot that tracks its command perfectly walks a straight line at the commanded velocity in the world (heading
mode: the command's direction turned by its heading). This tool draws the same commands, without simulating,
and reports the moving robots whose line leaves the tile within the episode (10 s) and within the time the
success rule needs (1 s settle, then 70 % of the commanded distance over the remaining 9 s: 7.3 s), and the
height step at the tile's edge where they cross it (the neighbouring tile, or the border). Such steps are the
layout's, not the terrain's: GenTe's terrains lie at any height, so an edge can be a cliff of metres.

    python tools/tile_edge_paths.py --benchmark gente_original [--robots_per_terrain 64] [--seed 0]
"""

from __future__ import annotations

import argparse

import numpy as np
import torch

from legged_gente.evaluation.report import MIN_PROGRESS
from legged_gente.utils.args import run_command

EPISODE_S = 10.0
SETTLE_S = 1.0  # gente-evaluate's --settle_s
SUCCESS_S = SETTLE_S + MIN_PROGRESS * (EPISODE_S - SETTLE_S)  # settle, then the success rule's share of the distance


def exit_times(start: np.ndarray, velocity: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Per robot: when a point moving from ``start`` at ``velocity`` (n, 2) first leaves the box [lo, hi] (inf if
    it stands still)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        wall = np.where(velocity > 0, hi, lo)
        to_wall = np.where(velocity != 0, (wall - start) / velocity, np.inf)
    return to_wall.min(axis=1)


def edge_paths(benchmark: str, task: str = "gente_biped", robots_per_terrain: int = 64, seed: int = 0) -> dict:
    """Per moving robot of the evaluation: when its perfectly tracked path leaves its tile (``leave``, s; inf if
    never) and the height step it meets there (``step``, m, outside minus inside, 0.25 m either side of the edge)."""
    from legged_gente.envs.task_registry import task_registry
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import lay_out_items
    from legged_gente.evaluation.tasks import VelocityTask
    from legged_gente.terrain.terrain import Terrain

    items = load_benchmark(benchmark)
    env_cfg, _ = task_registry.get_cfgs(task)
    _, cols = lay_out_items(env_cfg.terrain, items)
    n = len(items) * robots_per_terrain
    terrain = Terrain(env_cfg.terrain, n)
    tile = np.arange(n) // robots_per_terrain
    row, col = tile // cols, tile % cols
    start = terrain.terrain_origins[row, col][:, :2]
    bounds = terrain.tile_bounds(row, col)
    lo, hi = bounds[:, :2], bounds[:, 2:]

    commands = env_cfg.commands
    draw = VelocityTask(n, commands.ranges, commands.heading_command, "cpu", seed=seed)
    c = draw.commands(torch.zeros(n, 2), torch.zeros(n, 4)).numpy()
    moving = ~draw.still().numpy()
    yaw = c[:, 3] if commands.heading_command else np.zeros(n)
    velocity = np.stack([c[:, 0] * np.cos(yaw) - c[:, 1] * np.sin(yaw),
                         c[:, 0] * np.sin(yaw) + c[:, 1] * np.cos(yaw)], 1)[moving]
    start = start[moving]
    leave = exit_times(start, velocity, lo[moving], hi[moving])

    direction = velocity / np.linalg.norm(velocity, axis=1, keepdims=True)
    edge = start + velocity * np.where(np.isfinite(leave), leave, 0.0)[:, None]
    outside, inside = edge + 0.25 * direction, edge - 0.25 * direction
    step = terrain.height_at(*outside.T) - terrain.height_at(*inside.T)
    return {"terrains": len(items), "leave": leave, "step": step}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--benchmark", default="gente_original", help="a benchmark name or folder")
    parser.add_argument("--task", default="gente_biped", help="its command ranges are drawn from")
    parser.add_argument("--robots_per_terrain", type=int, default=64)
    parser.add_argument("--seed", type=int, default=0, help="as gente-evaluate's --seed")
    args = parser.parse_args()
    # a wrong benchmark, task or robot count: one line (run_command)
    r = run_command(parser.prog, lambda a: edge_paths(a.benchmark, a.task, a.robots_per_terrain, a.seed), args)
    total = len(r["leave"])
    print(f"{args.benchmark}: {r['terrains']} terrains, {total} moving robots ({args.task}'s commands, "
          f"seed {args.seed})")
    for seconds, what in ((EPISODE_S, "within the episode"), (SUCCESS_S, "before the success rule's distance")):
        off = r["leave"] < seconds
        s = np.abs(r["step"][off])
        if not s.size:
            print(f"  paths leaving their tile {what} ({seconds:g} s): none")
            continue
        print(f"  paths leaving their tile {what} ({seconds:g} s): {off.sum()} ({off.sum() / total:.1%}); the height "
              f"step at the edge: median {np.median(s):.2f} m, over 0.3 m for {(s > 0.3).mean():.0%}, over 1 m for "
              f"{(s > 1.0).mean():.0%}")


if __name__ == "__main__":
    main()
