"""The raw ceiling in env steps/s is raw substeps/s over the task's decimation: gente-benchmark writes the
decimation into its CSV (the last column) and tools/plot_throughput.py divides by it (4 for a CSV written before
the column existed)."""

import csv

from legged_gente.envs.task_registry import task_registry
from legged_gente.scripts import benchmark


def test_benchmark_rows_carry_the_decimation_their_ratios_use(monkeypatch):
    get_cfgs = task_registry.get_cfgs

    def decimation_2(name):
        env_cfg, train_cfg = get_cfgs(name)
        env_cfg.control.decimation = 2
        return env_cfg, train_cfg

    monkeypatch.setattr(task_registry, "get_cfgs", decimation_2)
    row, = benchmark.run("gente_biped_flat", [2], "cpu", steps=1, iterations=0)
    assert list(row)[-1] == "decimation" and row["decimation"] == 2
    assert row["env_over_raw"] == row["env_steps_per_s"] / (row["raw_substeps_per_s"] / 2)


def test_plot_divides_raw_substeps_by_the_csvs_decimation(load_file, tmp_path, monkeypatch):
    tool = load_file("tools/plot_throughput.py")
    plotted, plot = [], tool.plt.Axes.plot

    def recording_plot(ax, x, y, *args, **kwargs):
        plotted.append((kwargs["label"], y))
        return plot(ax, x, y, *args, **kwargs)

    monkeypatch.setattr(tool.plt.Axes, "plot", recording_plot)
    columns, row = ["num_envs", "raw_substeps_per_s", "env_steps_per_s", "ppo_steps_per_s"], [1024, 1200.0, 100.0, 50.0]
    for name, table in (("old", [columns, row]), ("new", [columns + ["decimation"], row + [2]])):
        with open(tmp_path / f"{name}.csv", "w", newline="") as f:
            csv.writer(f).writerows(table)
    tool.main([str(tmp_path / "out.png"), f"old={tmp_path / 'old.csv'}", f"new={tmp_path / 'new.csv'}"])
    raw = dict((label, y) for label, y in plotted if "raw" in label)
    assert raw == {"old: raw / decimation": [1200.0 / 4], "new: raw / decimation": [1200.0 / 2]}
