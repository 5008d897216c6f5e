"""Export a run's TensorBoard scalars to one CSV (step, then one column per tag)."""

from __future__ import annotations

import argparse
import csv
from pathlib import Path


def export_scalars(run_dir: Path, out_csv: Path) -> Path:
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    acc = EventAccumulator(str(run_dir), size_guidance={"scalars": 0})
    acc.Reload()
    tags = sorted(acc.Tags()["scalars"])
    if not tags:
        raise FileNotFoundError(f"no TensorBoard scalars in {run_dir}; is it a training run folder?")
    table: dict[int, dict[str, float]] = {}
    for tag in tags:
        for event in acc.Scalars(tag):
            table.setdefault(event.step, {})[tag] = event.value
    with open(out_csv, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["step"] + tags)
        for step in sorted(table):
            writer.writerow([step] + [table[step].get(tag, "") for tag in tags])
    return out_csv


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("run_dir", type=Path)
    parser.add_argument("out_csv", type=Path)
    args = parser.parse_args(argv)
    print(export_scalars(args.run_dir, args.out_csv))


if __name__ == "__main__":
    main()
