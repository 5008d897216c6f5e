"""Plot a training CSV from docs/results (iteration, wall_s, mean_episode_length, rew_tracking_lin_vel, ...
and, on a curriculum, terrain_level) against training wall time. An empty cell (the iterations before the first
finished episode log no episode length) is a gap in its line."""

import argparse
import csv
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("csv")
    parser.add_argument("png")
    parser.add_argument("--max_episode_length", type=float, default=1000.0)
    parser.add_argument("--levels", type=int, help="number of curriculum levels: also plot terrain_level / levels")
    parser.add_argument("--level_target", type=float, default=6.0, help="terrain level drawn as a dotted line")
    parser.add_argument("--mark", type=float, nargs="*", default=[], help="minutes to mark (e.g. resumes)")
    parser.add_argument("--title", default="")
    args = parser.parse_args(argv)
    if args.max_episode_length <= 0:
        parser.error(f"--max_episode_length {args.max_episode_length}: give the task's episode length in steps, > 0")
    if args.levels is not None and args.levels < 1:
        parser.error(f"--levels {args.levels}: give the number of curriculum levels, 1 or more (or leave it out)")
    if not Path(args.csv).is_file():
        parser.error(f"{args.csv}: no such file; give a training CSV of docs/results (tools/scalars_to_results.py)")
    try:
        with open(args.csv, newline="") as f:
            reader = csv.DictReader(f)
            rows = list(reader)
    except UnicodeDecodeError:  # e.g. the PNG, the two arguments swapped
        parser.error(f"{args.csv}: not a text file; give a training CSV of docs/results (tools/scalars_to_results.py)")
    needed = ["wall_s", "mean_episode_length", "rew_tracking_lin_vel"] + (["terrain_level"] if args.levels else [])
    missing = [c for c in needed if c not in (reader.fieldnames or [])]
    if missing or not rows:
        what = f"no column {', '.join(missing)}" if missing else "no rows"
        parser.error(f"{args.csv}: {what}; give a training CSV of docs/results (tools/scalars_to_results.py)")
    t = [float(r["wall_s"]) / 60 for r in rows]

    def column(name: str, scale: float = 1.0) -> list[float]:
        return [float(r[name]) / scale if r[name] else math.nan for r in rows]  # NaN: a gap in the line

    fig, ax = plt.subplots(figsize=(7, 3.6))
    ax.plot(t, column("mean_episode_length", args.max_episode_length), label="episode length / max")
    ax.plot(t, column("rew_tracking_lin_vel"), label="tracking_lin_vel / max")
    ax.axhline(0.9, color="tab:blue", ls=":", lw=1)
    ax.axhline(0.8, color="tab:orange", ls=":", lw=1)
    if args.levels:
        ax.plot(t, column("terrain_level", args.levels), color="tab:green",
                label=f"mean terrain level / {args.levels}")
        ax.axhline(args.level_target / args.levels, color="tab:green", ls=":", lw=1)
    for minute in args.mark:
        ax.axvline(minute, color="grey", ls="--", lw=1)
    ax.set_xlabel("training wall time (min)")
    ax.set_ylim(0, 1.05)
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right", fontsize=8)
    if args.title:
        ax.set_title(args.title, fontsize=9)
    fig.tight_layout()
    Path(args.png).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.png, dpi=90)


if __name__ == "__main__":
    main()
