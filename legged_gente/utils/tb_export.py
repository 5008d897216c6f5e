"""Export a run's TensorBoard scalars to one CSV (step, then one column per tag)."""

from __future__ import annotations

import csv
from pathlib import Path

from legged_gente.utils.args import Parser, run_command


def export_scalars(run_dir: Path, out_csv: Path) -> Path:
    """Every scalar of the run folder ``run_dir`` (or one event file) into ``out_csv`` (its folder made)."""
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    if not Path(run_dir).exists():  # TensorBoard would say it "has been permanently deleted"
        raise FileNotFoundError(f"{run_dir}: no such run folder; give a training run's folder "
                                f"(logs/<experiment>/<run>)")
    acc = EventAccumulator(str(run_dir), size_guidance={"scalars": 0})
    acc.Reload()
    tags = sorted(acc.Tags()["scalars"])
    if not tags:
        raise FileNotFoundError(f"no TensorBoard scalars in {run_dir}; is it a training run folder?")
    table: dict[int, dict[str, float]] = {}
    for tag in tags:
        for event in acc.Scalars(tag):
            table.setdefault(event.step, {})[tag] = event.value
    Path(out_csv).parent.mkdir(parents=True, exist_ok=True)
    with open(out_csv, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["step"] + tags)
        for step in sorted(table):
            writer.writerow([step] + [table[step].get(tag, "") for tag in tags])
    return out_csv


def main(argv=None) -> None:
    parser = Parser(prog="tb_export", description=__doc__)
    parser.add_argument("run_dir", type=Path)
    parser.add_argument("out_csv", type=Path)
    args = parser.parse_args(argv)
    print(run_command(parser.prog, lambda a: export_scalars(a.run_dir, a.out_csv), args))


if __name__ == "__main__":
    main()
