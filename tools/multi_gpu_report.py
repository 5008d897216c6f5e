"""Throughput ratio and learning of a 1-GPU and an N-GPU training run, from rsl-rl's console logs (rank 0).

    python tools/multi_gpu_report.py 1gpu.log 2gpu.log [--gpus 2] [--skip 3] [--csv multi_gpu.csv]

Mean "Steps per second" of each run (rsl-rl counts all ranks' steps: num_steps_per_env * num_envs * world_size /
rank 0's iteration time) after the first --skip iterations (kernel loading, CUDA-graph capture), their ratio,
and the mean reward / episode length at each run's last iteration and at the last iteration both reached.
"""

from __future__ import annotations

import argparse
import csv
import re
import statistics
from pathlib import Path

FIELDS = ("Steps per second", "Mean reward", "Mean episode length")


def parse(path: str) -> dict[int, dict[str, float]]:
    """Per logged iteration: the FIELDS rsl-rl printed for it."""
    rows, row = {}, None
    for line in open(path, errors="replace"):
        if m := re.search(r"Learning iteration (\d+)/", line):
            row = rows.setdefault(int(m.group(1)), {})
        elif row is not None and (m := re.match(r"\s*(" + "|".join(FIELDS) + r"):\s*(\S+)", line)):
            row[m.group(1)] = float(m.group(2))
    return rows


def learning(rows: dict, iteration: int) -> str:
    r = rows[iteration]
    return (f"iteration {iteration}: mean reward {r.get('Mean reward', float('nan')):.2f}, "
            f"mean episode length {r.get('Mean episode length', float('nan')):.1f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("one_gpu_log")
    parser.add_argument("multi_gpu_log")
    parser.add_argument("--gpus", type=int, default=2, help="how many GPUs the second run trained on")
    parser.add_argument("--skip", type=int, default=3, help="first iterations left out of the mean steps/s")
    parser.add_argument("--csv", help="write every iteration of both runs here")
    parser.add_argument("--plot", help="save the mean reward of both runs per iteration here (PNG)")
    args = parser.parse_args()
    if args.gpus < 2:
        parser.error(f"--gpus {args.gpus}: the second run trains on 2 or more GPUs; give how many it used")
    if args.skip < 0:
        parser.error(f"--skip {args.skip}: give how many first iterations to leave out, 0 or more")
    multi = f"{args.gpus}gpu"
    for path in (args.one_gpu_log, args.multi_gpu_log):
        if not Path(path).is_file():
            parser.error(f"{path}: no such file; give the console log of a training run (rank 0)")
    runs = {"1gpu": parse(args.one_gpu_log), multi: parse(args.multi_gpu_log)}
    for name, rows in runs.items():
        if len(rows) <= args.skip:
            raise SystemExit(f"{name}: only {len(rows)} iterations logged (need > --skip {args.skip}); train "
                             f"longer or see its log")
        unmeasured = sorted(i for i, r in rows.items() if "Steps per second" not in r)
        if unmeasured:
            raise SystemExit(f"{name}: iteration {unmeasured[0]} logs no 'Steps per second' (an rsl-rl log of "
                             f"another format, or cut short); give a console log of this rsl-rl-lib's runner")
    sps = {name: statistics.mean(r["Steps per second"] for i, r in rows.items() if i >= min(rows) + args.skip)
           for name, rows in runs.items()}
    both = set(runs["1gpu"]) & set(runs[multi])
    if not both:
        spans = ", ".join(f"{name}: {min(rows)}-{max(rows)}" for name, rows in runs.items())
        raise SystemExit(f"the logs share no iteration ({spans}); give logs of the same iterations")
    common = max(both)  # the last iteration both logged
    for name, rows in runs.items():
        print(f"{name}: {len(rows)} iterations, mean steps/s {sps[name]:.0f} (iterations after the first "
              f"{args.skip})")
        print(f"      last   {learning(rows, max(rows))}")
        print(f"      common {learning(rows, common)}")
    print(f"throughput ratio {multi}/1gpu: {sps[multi] / sps['1gpu']:.3f}")
    if args.csv:
        Path(args.csv).parent.mkdir(parents=True, exist_ok=True)
        with open(args.csv, "w", newline="") as f:
            writer = csv.writer(f)
            writer.writerow(["run", "iteration", "steps_per_second", "mean_reward", "mean_episode_length"])
            for name, rows in runs.items():
                for iteration, r in sorted(rows.items()):
                    writer.writerow([name, iteration, *(r.get(field, "") for field in FIELDS)])
    if args.plot:
        plot(runs, sps, args.plot)


def plot(runs: dict, sps: dict, path: str) -> None:
    """Mean reward per iteration of both runs (an N-GPU iteration learns from N times the samples)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.5))
    for name, rows in runs.items():
        iterations = sorted(i for i, r in rows.items() if "Mean reward" in r)
        ax.plot(iterations, [rows[i]["Mean reward"] for i in iterations],
                label=f"{name[:-3]} GPU{'s' if name != '1gpu' else ''}: {sps[name] / 1e6:.2f} M env-steps/s")
    ax.set_xlabel("PPO iteration")
    ax.set_ylabel("mean episode reward")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)


if __name__ == "__main__":
    main()
