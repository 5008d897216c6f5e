"""Throughput versus num_envs from gente-benchmark CSVs (one line style per file). The raw line is the raw ceiling
in env steps/s: raw substeps/s over the CSV's decimation column (a CSV without it, written before gente-benchmark
recorded it, is read as decimation 4: every task's then)."""

import argparse
import csv
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

OLD_CSV_DECIMATION = 4
COLUMNS = ("num_envs", "raw_substeps_per_s", "env_steps_per_s", "ppo_steps_per_s")  # of gente-benchmark --csv


def raw_ceiling(row: dict) -> float:
    """Env steps/s the raw physics would allow: raw substeps/s / the row's decimation (OLD_CSV_DECIMATION where the
    CSV has no such column)."""
    return float(row["raw_substeps_per_s"]) / int(row.get("decimation", OLD_CSV_DECIMATION))


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("png")
    parser.add_argument("csvs", nargs="+", help="LABEL=PATH")
    parser.add_argument("--skip_raw", nargs="*", default=[], help="labels whose raw column is not plotted")
    args = parser.parse_args(argv)
    styles = ("-", "--", ":")  # one line style per CSV
    if len(args.csvs) > len(styles):
        parser.error(f"{len(args.csvs)} CSVs given; at most {len(styles)} (one line style each) fit one plot")
    for item in args.csvs:
        if "=" not in item:
            parser.error(f"{item!r}: give each CSV as LABEL=PATH, e.g. \"H100=benchmark.csv\"")
        path = Path(item.split("=", 1)[1])
        if not path.is_file():
            parser.error(f"{item!r}: no such file; give a CSV of gente-benchmark --csv")
        with open(path, newline="") as f:
            reader = csv.DictReader(f)
            rows = list(reader)
        missing = [c for c in COLUMNS if c not in (reader.fieldnames or [])]
        if missing or not rows:
            what = f"no column {', '.join(missing)}" if missing else "no rows"
            parser.error(f"{item!r}: {what}; give a CSV of gente-benchmark --csv")
    unknown = sorted(set(args.skip_raw) - {item.split("=", 1)[0] for item in args.csvs})
    if unknown:
        parser.error(f"--skip_raw {unknown}: no CSV has that label; the labels are those before '=' in LABEL=PATH")
    fig, ax = plt.subplots(figsize=(10, 4))
    for style, item in zip(styles, args.csvs):
        label, path = item.split("=", 1)
        rows = list(csv.DictReader(open(Path(path))))
        n = [int(r["num_envs"]) for r in rows]
        for key, colour, name in (("raw_substeps_per_s", "k", "raw / decimation"), ("env_steps_per_s", "tab:blue", "env"),
                                  ("ppo_steps_per_s", "tab:orange", "PPO")):
            if key == "raw_substeps_per_s" and label in args.skip_raw:
                continue
            values = [raw_ceiling(r) if key == "raw_substeps_per_s" else float(r[key]) for r in rows]
            ax.plot(n, values, style, color=colour, marker="o", label=f"{label}: {name}")
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("num_envs")
    ax.set_ylabel("env steps / s")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))  # beside the axes: no line hidden
    fig.tight_layout()
    fig.savefig(args.png, dpi=90)


if __name__ == "__main__":
    main()
