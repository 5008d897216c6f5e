"""How rough a benchmark's terrains are, next to how a policy did on them; and how rough a task's training
curriculum is, for comparison.

A cell is *rough* when the terrain within ``window`` (0.3 m, about one stride of the biped) around it spans more
than ``step`` (0.15 m) in height: the robot has to step up or down that much within one stride there. A
terrain's rough share is the share of rough cells within ``centre`` (8 m) square around the tile's centre, where
the evaluated robots spawn and walk (0.3-1.1 m/s for 9 s).

    python tools/terrain_roughness.py --benchmark gente_original --report docs/results/gente_original_eval_biped_040b769.csv
    python tools/terrain_roughness.py --curriculum gente_biped [--set terrain.max_difficulty=1.5 --set terrain.num_rows=14]
"""

from __future__ import annotations

import argparse
import csv

import numpy as np
from scipy.ndimage import maximum_filter, minimum_filter

from legged_gente.utils.args import USER_ERRORS, error_text

BINS = (0.0, 0.02, 0.1, 0.3, 1.0)


def rough_cells(heights: np.ndarray, resolution: float, window: float = 0.3, step: float = 0.15) -> np.ndarray:
    """Per cell: the height span within a ``window`` square around it exceeds ``step``."""
    size = max(1, int(round(window / resolution)))
    return (maximum_filter(heights, size=size) - minimum_filter(heights, size=size)) > step


def rough_share(heights: np.ndarray, resolution: float, centre: float = 8.0, **kwargs) -> float:
    """The rough share of the ``centre`` square (m) around the middle of ``heights``."""
    rough = rough_cells(heights, resolution, **kwargs)
    half = int(round(centre / 2 / resolution))
    cx, cy = heights.shape[0] // 2, heights.shape[1] // 2
    return float(rough[max(cx - half, 0):cx + half, max(cy - half, 0):cy + half].mean())


REPORT_COLUMNS = ("success_rate", "fall_rate", "tracking_error")  # per terrain, from gente-evaluate's report.csv


def read_report(path: str) -> dict[str, dict[str, float]]:
    """Per terrain of a report.csv: its ``REPORT_COLUMNS`` (NaN where empty: no moving robot there)."""
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        missing = [c for c in ("row", "name", *REPORT_COLUMNS) if c not in (reader.fieldnames or [])]
        if missing:
            raise ValueError(f"{path}: no column {', '.join(missing)}; give gente-evaluate's report.csv")
        return {r["name"]: {k: float(r[k] or "nan") for k in REPORT_COLUMNS} for r in reader if r["row"] == "terrain"}


def benchmark_table(benchmark: str, report: str | None) -> tuple[list[tuple[str, float, dict[str, float]]], int]:
    """(item id, rough share, the report's ``REPORT_COLUMNS`` for it, NaN without a report) per item of
    ``benchmark`` that the report scores (each item without a report), and the benchmark's item count; a report
    with none of its terrains is a ValueError."""
    from legged_gente.evaluation.benchmark import load_benchmark

    items = load_benchmark(benchmark)
    metrics = read_report(report) if report else {}
    if report and not metrics.keys() & {item.id for item in items}:
        raise ValueError(f"{report} has none of the terrains of benchmark {benchmark}; give gente-evaluate's "
                         f"report.csv of an evaluation on {benchmark}")
    missing = dict.fromkeys(REPORT_COLUMNS, float("nan"))
    rows = []
    for item in items:
        if report and item.id not in metrics:  # an evaluation of some items (--items): the bins count those
            continue
        spec = item.spec()
        heights, _ = spec.build()
        rows.append((item.id, rough_share(heights, spec.resolution), metrics.get(item.id, missing)))
    return rows, len(items)


def print_bins(rows: list[tuple[str, float, dict[str, float]]]) -> None:
    """Per bin of rough share: the terrains' count and the means of their success rate, fall rate and tracking
    error (m/s), which tell falling from being too slow."""
    shares = np.array([r[1] for r in rows])
    print("rough share      terrains   success  fall rate  tracking error (means over the terrains)")
    for lo, hi in zip(BINS[:-1], BINS[1:]):
        inside = (shares >= lo) & ((shares < hi) if hi < 1.0 else (shares <= hi))
        means = []
        for column, fmt in zip(REPORT_COLUMNS, ("{:.1%}", "{:.1%}", "{:.3f}")):
            values = np.array([r[2][column] for r, keep in zip(rows, inside) if keep])
            means.append(fmt.format(np.nanmean(values)) if np.isfinite(values).any() else "-")
        print(f"[{lo:.2f}, {hi:.2f}{']' if hi == 1.0 else ')'}   {int(inside.sum()):8d}  {means[0]:>8}  {means[1]:>9}  "
              f"{means[2]:>14}")


def curriculum_table(task: str, overrides: list[str] = ()) -> None:
    """Per curriculum level: the mean and largest rough share of its tiles (each whole tile); ``overrides`` are
    gente-train's ``--set`` values."""
    from legged_gente.envs.task_registry import task_registry
    from legged_gente.terrain.terrain import Terrain
    from legged_gente.utils.args import apply_overrides

    env_cfg, train_cfg = task_registry.get_cfgs(task)
    apply_overrides(list(overrides), env_cfg, train_cfg)
    terrain = Terrain(env_cfg.terrain, env_cfg.env.num_envs)
    rough = rough_cells(terrain.height_field, terrain.resolution)
    rows, cols = terrain.tile_cells
    print("level  mean rough share  largest (tile)")
    for r in range(terrain.num_rows):
        shares = [rough[terrain.border + r * rows:terrain.border + (r + 1) * rows,
                        terrain.border + c * cols:terrain.border + (c + 1) * cols].mean() for c in range(terrain.num_cols)]
        worst = int(np.argmax(shares))
        print(f"{r:5d}  {np.mean(shares):16.3f}  {shares[worst]:.3f} ({terrain.tile_names[r, worst]})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--benchmark", help="a benchmark name (gente100, gente_original) or folder")
    source.add_argument("--curriculum", metavar="TASK", help="a task whose training curriculum to measure")
    parser.add_argument("--report", help="gente-evaluate's report.csv of that benchmark: success, fall rate and "
                        "tracking error per terrain")
    parser.add_argument("--set", action="append", default=[], dest="overrides", metavar="SECTION.FIELD=VALUE",
                        help="with --curriculum: a config override, as gente-train's --set")
    args = parser.parse_args()
    if args.curriculum and args.report:
        parser.error("--report goes with --benchmark (a report scores a benchmark's terrains, not a curriculum)")
    if args.benchmark and args.overrides:
        parser.error("--set goes with --curriculum (it changes the task's terrain config; a benchmark's terrains are "
                     "its specs)")
    try:  # a wrong benchmark, report, task or --set: one line
        if args.curriculum:
            curriculum_table(args.curriculum, args.overrides)
            return
        rows, count = benchmark_table(args.benchmark, args.report)
    except USER_ERRORS as error:
        parser.error(error_text(error))
    if len(rows) < count:
        print(f"{args.report} scores {len(rows)} of the {count} terrains of {args.benchmark}: the bins hold those")
    print_bins(rows)


if __name__ == "__main__":
    main()
