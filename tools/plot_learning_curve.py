"""Plot a training CSV from docs/results (iteration, wall_s, mean_episode_length, rew_tracking_lin_vel, ...)."""

import argparse
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("csv")
    parser.add_argument("png")
    parser.add_argument("--max_episode_length", type=float, default=1000.0)
    args = parser.parse_args()
    rows = list(csv.DictReader(open(args.csv)))
    t = [float(r["wall_s"]) / 60 for r in rows]
    fig, ax = plt.subplots(figsize=(7, 3.6))
    ax.plot(t, [float(r["mean_episode_length"]) / args.max_episode_length for r in rows], label="episode length / max")
    ax.plot(t, [float(r["rew_tracking_lin_vel"]) for r in rows], label="tracking_lin_vel / max")
    ax.axhline(0.9, color="tab:blue", ls=":", lw=1)
    ax.axhline(0.8, color="tab:orange", ls=":", lw=1)
    ax.set_xlabel("training wall time (min)")
    ax.set_ylim(0, 1.05)
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(args.png, dpi=90)


if __name__ == "__main__":
    main()
