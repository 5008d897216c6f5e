"""Turn the scalars CSVs of one training run (``python -m legged_gente.utils.tb_export``; several when it was
resumed, in order) into the results format of docs/results: iteration, wall_s, mean_episode_length,
rew_tracking_lin_vel, mean_reward, env_steps_per_s, terrain_level, diverged_resets_cumulative.

Episode/diverged_resets is the count per logging interval (one iteration); the results column sums it over
the run. (Runs before the divergence fix logged a running total per chunk; their results files were made so.)

wall_s is the training time rsl-rl measures (collection + learning, summed over iterations, also those before the
first finished episode, whose episode columns are empty): process start-up
and the pause between resumed chunks are not in it. When a chunk was resumed from a checkpoint older than the
previous chunk's last iteration, the iterations it redid are counted once, from the later chunk.

    python tools/scalars_to_results.py OUT.csv chunk1.csv [chunk2.csv ...]
"""

import argparse
import csv

from legged_gente.utils.tables import write_rows

COLUMNS = {  # results column: TensorBoard tag
    "mean_episode_length": "Train/mean_episode_length",
    "rew_tracking_lin_vel": "Episode/rew_tracking_lin_vel",
    "mean_reward": "Train/mean_reward",
    "env_steps_per_s": "Perf/total_fps",
    "terrain_level": "Episode/terrain_level",
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out")
    parser.add_argument("chunks", nargs="+")
    args = parser.parse_args()
    iterations = []  # (iteration, seconds, diverged resets, results values), in training order
    for path in args.chunks:
        try:
            with open(path, newline="") as f:
                reader = csv.DictReader(f)
                rows = [r for r in reader if r.get("Perf/collection_time")]  # every iteration logs it
        except OSError as error:
            raise SystemExit(f"{path}: {error.strerror}; give a scalars CSV of python -m "
                             f"legged_gente.utils.tb_export")
        except UnicodeDecodeError:  # e.g. the run's TensorBoard event file itself
            raise SystemExit(f"{path}: not a text file; give a scalars CSV of python -m legged_gente.utils.tb_export")
        missing = [c for c in ("step", "Perf/learning_time") if c not in (reader.fieldnames or [])]
        if not rows or missing:
            raise SystemExit(f"{path}: no training iterations (is it a tb_export CSV of a run?)")
        # a chunk resumed from a checkpoint older than the previous chunk's last iteration redid those iterations
        iterations = [it for it in iterations if it[0] < int(rows[0]["step"])]
        for r in rows:
            iterations.append((int(r["step"]), float(r["Perf/collection_time"]) + float(r["Perf/learning_time"]),
                               float(r.get("Episode/diverged_resets") or 0.0),  # this iteration's count
                               {name: f"{float(r[tag]):.4g}" if r.get(tag) else "" for name, tag in COLUMNS.items()}))
    out_rows, wall, diverged = [], 0.0, 0.0
    for iteration, seconds, resets, values in iterations:
        wall += seconds
        diverged += resets
        out_rows.append({"iteration": iteration, "wall_s": round(wall, 1), **values,
                         "diverged_resets_cumulative": int(diverged)})
    write_rows(args.out, out_rows)
    print(f"wrote {args.out}: {len(out_rows)} iterations, {wall / 60:.1f} min of training")


if __name__ == "__main__":
    main()
