"""Timing of text -> spec -> heightfield with the planner (target: < 0.2 s for a 20 m x 20 m tile on a CPU).

Run ``python -m legged_gente.generation.benchmark``; it prints the median of a few repeats per scene.
"""

from __future__ import annotations

import statistics
import time

from legged_gente.generation.pipeline import generate_spec
from legged_gente.generation.validation import MAX_STRING_CHARS

SCENES = (
    "a forest trail along a knee-deep stream",
    "a city street with steep stairs",
    "a beach with waves",
    "rubble of a ruined building, slippery",
)
LONGEST = ("a deep river " * (MAX_STRING_CHARS // 13 + 1))[:MAX_STRING_CHARS]
"""The longest text gente-generate accepts, a modifier and a cue in every 13 characters: timed apart."""


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
    (seconds,) = benchmark((LONGEST,)).values()
    print(f"{seconds * 1000:7.1f} ms  the longest text accepted ({len(LONGEST)} characters: {LONGEST[:26]!r}...)")


if __name__ == "__main__":
    main()
