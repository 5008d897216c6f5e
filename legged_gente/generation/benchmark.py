"""Timing of text -> spec -> heightfield with the planner (target: < 0.2 s for a 20 m x 20 m tile on a CPU).

Run ``python -m legged_gente.generation.benchmark``; it prints the median of a few repeats per scene.
"""

from __future__ import annotations

import statistics
import time

from legged_gente.generation.pipeline import generate_spec

SCENES = (
    "a forest trail along a knee-deep stream",
    "a city street with steep stairs",
    "a beach with waves",
    "rubble of a ruined building, slippery",
)


def benchmark(scenes=SCENES, repeats: int = 3, size: float = 20.0, resolution: float = 0.1) -> dict[str, float]:
    """Median seconds per scene for planner text -> validated TerrainSpec -> (heights, MaterialMap): one
    ``generate_spec``, which builds the tile to check its water (a second ``build`` would time it twice)."""
    generate_spec(scenes[0], size_x=size, size_y=size, resolution=resolution)  # warm imports and caches
    out = {}
    for text in scenes:
        times = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            generate_spec(text, size_x=size, size_y=size, resolution=resolution)
            times.append(time.perf_counter() - t0)
        out[text] = statistics.median(times)
    return out


def main() -> None:
    results = benchmark()
    for text, seconds in results.items():
        print(f"{seconds * 1000:7.1f} ms  {text!r}")
    print(f"worst {max(results.values()) * 1000:.1f} ms per 20 m x 20 m tile at 0.1 m (target < 200 ms)")


if __name__ == "__main__":
    main()
