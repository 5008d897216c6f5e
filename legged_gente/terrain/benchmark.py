"""Terrain build benchmark: a curriculum grid of every terrain type, water and sand included.

``python -m legged_gente.terrain.benchmark`` prints the wall-clock build time of the issue's reference grid
(10 rows of 8 m tiles at 0.1 m, a column per entry of ``BENCHMARK_TYPES``); ``gente-benchmark`` calls
:func:`benchmark_grid`.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

from .registry import ATOMIC_TERRAINS
from .terrain import Terrain, parse_tile_type

BENCHMARK_TYPES = [
    "flat", "pyramid_slope", "pyramid_slope:direction=down", "random_uniform", "natural_ground", "hills",
    "waves", "stairs", "stairs:direction=down", "pyramid_stairs", "pyramid_stairs:direction=down",
    "discrete_obstacles", "stepping_stones", "gap", "pit", "pillars", "rocks", "river+water", "basin+water",
    "hills+soil:preset=dry_sand", "low_friction", "basin+ice:depth=0.05",
]
"""Twenty-two columns: every geometric atomic, both directions where they have one, water in a river and in a
basin, sand, slippery ground and a frozen pond (its ice 5 cm above the basin's floor, below the rim as it deepens)."""


def curriculum_config(types: list[str], num_rows: int, num_cols: int, tile_size: float = 8.0,
                      resolution: float = 0.1, border_size: float = 5.0) -> type:
    """A terrain config of a curriculum grid: a column per entry of ``types`` (in equal shares of ``num_cols``),
    difficulty 0 to 1 over ``num_rows`` rows of ``tile_size`` m tiles."""

    class Cfg:
        mesh_type, mode = "heightfield", "curriculum"
        terrain_length = terrain_width = tile_size
        terrain_types, terrain_proportions = types, [1.0 / len(types)] * len(types)
        selected_terrain, selected_params, generated_specs = "flat", {}, []
        max_difficulty, max_init_terrain_level, curriculum, static_friction, seed = 1.0, 0, True, 1.0, 0

    Cfg.resolution, Cfg.border_size, Cfg.num_rows, Cfg.num_cols = resolution, border_size, num_rows, num_cols
    return Cfg


def benchmark_grid(
    num_rows: int = 10, num_cols: int = len(BENCHMARK_TYPES), tile_size: float = 8.0, resolution: float = 0.1, repeats: int = 3
) -> dict[str, Any]:
    """Build the curriculum grid ``repeats`` times; return the best and mean build seconds and the grid facts."""
    covered = {name for entry in BENCHMARK_TYPES for ops in parse_tile_type(entry) for name, _ in ops}
    missing = sorted(set(ATOMIC_TERRAINS) - covered)
    if missing:
        raise RuntimeError(f"benchmark types miss the atomic terrains {missing}; add them to BENCHMARK_TYPES.")

    Cfg = curriculum_config(BENCHMARK_TYPES, num_rows, num_cols, tile_size, resolution)
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        terrain = Terrain(Cfg, num_robots=num_rows * num_cols)
        times.append(time.perf_counter() - start)
    return {
        "best_s": min(times),
        "mean_s": sum(times) / len(times),
        "repeats": repeats,
        "grid": f"{num_rows} x {num_cols} tiles of {tile_size} m at {resolution} m",
        "cells": int(terrain.height_field.size),
        "types": terrain.tile_type_names,
    }


def describe(result: dict[str, Any]) -> str:
    """One line for :func:`benchmark_grid`'s result."""
    return (f"terrain build: {result['grid']} ({result['cells']} cells incl. border): "
            f"best {result['best_s']:.3f} s, mean {result['mean_s']:.3f} s over {result['repeats']} builds")


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=10)
    parser.add_argument("--cols", type=int, default=len(BENCHMARK_TYPES))
    parser.add_argument("--tile-size", type=float, default=8.0)
    parser.add_argument("--resolution", type=float, default=0.1)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    result = benchmark_grid(args.rows, args.cols, args.tile_size, args.resolution, args.repeats)
    print(describe(result))
    return result


if __name__ == "__main__":
    main()
