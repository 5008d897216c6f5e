"""The tools that turn runs into the numbers the docs report, on synthetic timings, logs and scalar CSVs: every
ratio, share and mean against values worked out by hand, and wrong flags as one-line usage errors."""

import csv
import math
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from test_tools_by_hand import last_error_line, run_main

from legged_gente.scripts import benchmark

ROOT = Path(__file__).resolve().parents[1]
# the first bytes of a TensorBoard event file (a record length, its CRC, then the serialized event): not text
EVENT_FILE = b"\x18\x00\x00\x00\x00\x00\x00\x00\xa3\x7fK\"\t\xc8\xf0\xff"



# --- legged_gente/scripts/benchmark.py ----------------------------------------------------------------------------

def fake_measurements(monkeypatch, calls):
    """Replace every timing of ``benchmark.run`` by a fixed rate, so its arithmetic can be checked by hand:
    decimation 4, 100 worlds; raw 400,000 substeps/s without the force fields, 320,000 with them; the force
    pass 1,600,000 passes/s (all worlds), the sole contacts alone 3,200,000; the post-reset forward 1,000
    calls/s; the env 50,000 steps/s; PPO 30,000 env-steps/s with the update 25 % of its time."""
    env = SimpleNamespace(num_envs=100, cfg=SimpleNamespace(control=SimpleNamespace(decimation=4)),
                          forces=SimpleNamespace(npt=2))

    def raw_physics(env, substeps, with_forces=False):
        calls.append(("raw", substeps, with_forces))
        return 320_000.0 if with_forces else 400_000.0

    def force_kernels_per_s(env, steps, only_sole_contacts=False):
        calls.append(("forces", steps, only_sole_contacts))
        return 3_200_000.0 if only_sole_contacts else 1_600_000.0

    monkeypatch.setattr(benchmark.task_registry, "make_env", lambda task, env_cfg, args: (env, None))
    monkeypatch.setattr(benchmark, "settle", lambda env: None)
    monkeypatch.setattr(benchmark, "raw_physics", raw_physics)
    monkeypatch.setattr(benchmark, "force_kernels_per_s", force_kernels_per_s)
    monkeypatch.setattr(benchmark, "reset_forward_per_s", lambda env, calls: 1_000.0)
    monkeypatch.setattr(benchmark, "env_steps", lambda env, steps, check_sync=False: 50_000.0)
    monkeypatch.setattr(benchmark, "_runner", lambda env, task: (None, None))
    monkeypatch.setattr(benchmark, "ppo_steps", lambda runner, cfg, iterations: (30_000.0, 0.25))


def test_benchmark_ratios_and_shares_by_hand(monkeypatch):
    """Raw ceiling 400,000 / 4 = 100,000 env steps/s: env/raw 50,000 / 100,000 = 0.5, PPO/raw 0.3. A substep with
    the forces takes 1 / 320,000 s (all worlds), the force pass 1 / 1,600,000 s: 0.2 of it, the sole contacts
    1 / 3,200,000 s: 0.1, so the force kernels without the soles 0.2 - 0.1 = 0.1; forces Δ 1 - 320,000 / 400,000
    = 0.2. An env step takes 100 / 50,000 = 2 ms, the forward 1 ms: 0.5. Every timing of 5 policy steps runs
    5 x 4 = 20 substeps (or force passes)."""
    calls = []
    fake_measurements(monkeypatch, calls)
    (row,) = benchmark.run("gente_biped", [100], "cpu", steps=5, iterations=2)
    expected = {"num_envs": 100, "raw_substeps_per_s": 400_000.0, "env_steps_per_s": 50_000.0,
                "ppo_steps_per_s": 30_000.0, "env_over_raw": 0.5, "ppo_over_raw": 0.3, "ppo_update_share": 0.25,
                "forces_share": 0.1, "soles_share": 0.1, "forces_slowdown": 0.2, "reset_forward_share": 0.5,
                "decimation": 4}
    assert math.isnan(row.pop("gpu_memory_gib"))  # measured on CUDA only
    assert row == pytest.approx(expected)
    assert sorted(calls) == [("forces", 20, False), ("forces", 20, True), ("raw", 20, False), ("raw", 20, True)]


def test_benchmark_csv_has_the_documented_columns_in_their_units(monkeypatch, tmp_path):
    """The CSV: rates in steps/s (not thousands), shares as fractions (the table prints them as %), one row per
    --num_envs, the task's decimation last."""
    fake_measurements(monkeypatch, [])
    out = tmp_path / "bench.csv"
    benchmark.main(["--task", "gente_biped", "--num_envs", "100", "--steps", "5", "--iterations", "2",
                    "--device", "cpu", "--csv", str(out)])
    with open(out, newline="") as f:
        reader = csv.DictReader(f)
        (row,) = list(reader)
    assert reader.fieldnames == ["num_envs", "raw_substeps_per_s", "env_steps_per_s", "ppo_steps_per_s",
                                 "env_over_raw", "ppo_over_raw", "ppo_update_share", "forces_share", "soles_share",
                                 "forces_slowdown", "reset_forward_share", "gpu_memory_gib", "decimation"]
    assert float(row["raw_substeps_per_s"]) == 400_000.0 and float(row["ppo_over_raw"]) == pytest.approx(0.3)
    assert float(row["forces_share"]) == pytest.approx(0.1) and row["decimation"] == "4"


# --- tools/multi_gpu_report.py ------------------------------------------------------------------------------------

def rsl_rl_log(path, iterations, steps_per_second, rewards):
    """A console log as rsl-rl-lib's Logger prints it: a bold header per iteration, labels right-aligned."""
    with open(path, "w") as f:
        for it, sps, reward in zip(iterations, steps_per_second, rewards):
            f.write("#" * 80 + "\n" + f"\033[1m{f' Learning iteration {it}/2000 '.center(80)}\033[0m \n\n")
            f.write(f"{'Steps per second:':>40} {sps:.0f} \n{'Collection time:':>40} 1.000s \n")
            f.write(f"{'Mean reward:':>40} {reward:.2f}\n{'Mean episode length:':>40} {100 * reward:.2f}\n")
    return str(path)


def test_multi_gpu_mean_after_skip_of_a_resumed_log(load_file, tmp_path, monkeypatch, capsys):
    """Logs that start at iteration 500 (a resumed run): --skip 2 leaves out 500 and 501. 1 GPU: (400 + 600) / 2
    = 500 steps/s; 4 GPUs: (1800 + 2200 + 2000) / 3 = 2000; ratio 4.000. The last iteration both reached: 503,
    where the 1-GPU run's reward is 4.00 (its fourth iteration) and the 4-GPU run's 8.00."""
    tool = load_file("tools/multi_gpu_report.py")
    one = rsl_rl_log(tmp_path / "1.log", range(500, 504), [1, 1, 400, 600], [1, 2, 3, 4])
    four = rsl_rl_log(tmp_path / "4.log", range(500, 505), [1, 1, 1800, 2200, 2000], [2, 4, 6, 8, 10])
    assert run_main(tool, monkeypatch, one, four, "--gpus", "4", "--skip", "2") is None
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "1gpu: 4 iterations, mean steps/s 500 (iterations after the first 2)"
    assert out[1] == "      last   iteration 503: mean reward 4.00, mean episode length 400.0"
    assert out[2] == "      common iteration 503: mean reward 4.00, mean episode length 400.0"
    assert out[3] == "4gpu: 5 iterations, mean steps/s 2000 (iterations after the first 2)"
    assert out[4] == "      last   iteration 504: mean reward 10.00, mean episode length 1000.0"
    assert out[5] == "      common iteration 503: mean reward 8.00, mean episode length 800.0"
    assert out[6] == "throughput ratio 4gpu/1gpu: 4.000"


def test_multi_gpu_negative_skip_is_a_usage_error(load_file, tmp_path, monkeypatch, capsys):
    """--skip -1 was taken: the mean then counted every iteration, the warm-up ones too, and the report said
    "iterations after the first -1"."""
    tool = load_file("tools/multi_gpu_report.py")
    one = rsl_rl_log(tmp_path / "1.log", range(4), [10, 100, 100, 100], [1, 2, 3, 4])
    two = rsl_rl_log(tmp_path / "2.log", range(4), [10, 200, 200, 200], [1, 2, 3, 4])
    assert run_main(tool, monkeypatch, one, two, "--skip", "-1") == 2
    assert last_error_line(capsys).endswith("--skip -1: give how many first iterations to leave out, 0 or more")


# --- tools/plot_learning_curve.py ---------------------------------------------------------------------------------

RESULTS = ("iteration,wall_s,mean_episode_length,rew_tracking_lin_vel,mean_reward,terrain_level\n"
           "0,30,,0.1,,0.5\n1,90,400,0.3,2,1.5\n")


def test_learning_curve_scales_by_hand(load_file, tmp_path, monkeypatch):
    """wall_s 30 and 90 s -> 0.5 and 1.5 min; episode length 400 of 800 steps -> 0.5; terrain level 0.5 and 1.5
    of 5 levels -> 0.1 and 0.3; the level target 4 of 5 levels is drawn at 0.8. The PNG goes into a new folder."""
    tool = load_file("tools/plot_learning_curve.py")
    (tmp_path / "run.csv").write_text(RESULTS)
    lines, hlines = {}, []
    plot, axhline = tool.plt.Axes.plot, tool.plt.Axes.axhline
    monkeypatch.setattr(tool.plt.Axes, "plot", lambda ax, x, y, *a, **k: (lines.__setitem__(k.get("label"), (x, y)),
                                                                           plot(ax, x, y, *a, **k))[1])
    monkeypatch.setattr(tool.plt.Axes, "axhline", lambda ax, y, *a, **k: (hlines.append(y), axhline(ax, y, *a, **k))[1])
    png = tmp_path / "img" / "run.png"  # a folder not made yet: a FileNotFoundError traceback before
    tool.main([str(tmp_path / "run.csv"), str(png), "--max_episode_length", "800", "--levels", "5",
               "--level_target", "4"])
    assert png.read_bytes()[:4] == b"\x89PNG"
    np.testing.assert_allclose(lines["episode length / max"][0], [0.5, 1.5])
    np.testing.assert_allclose(lines["episode length / max"][1], [math.nan, 0.5])
    np.testing.assert_allclose(lines["mean terrain level / 5"][1], [0.1, 0.3])
    assert hlines[-1] == pytest.approx(0.8)


@pytest.mark.parametrize("flags, message", [
    (["--max_episode_length", "0"], "--max_episode_length 0.0: give the task's episode length in steps, > 0"),
    (["--max_episode_length", "-1000"], "--max_episode_length -1000.0: give the task's episode length in steps, > 0"),
    (["--levels", "0"], "--levels 0: give the number of curriculum levels, 1 or more (or leave it out)"),
    (["--levels", "-10"], "--levels -10: give the number of curriculum levels, 1 or more (or leave it out)"),
])
def test_learning_curve_nonsense_scales_are_usage_errors(load_file, tmp_path, capsys, flags, message):
    """--max_episode_length 0 divided by zero (a ZeroDivisionError traceback); -1000 drew the episode lengths
    below the axis; --levels 0 was read as "no curriculum" and drew no level line, -10 drew it below the axis."""
    tool = load_file("tools/plot_learning_curve.py")
    (tmp_path / "run.csv").write_text(RESULTS)
    with pytest.raises(SystemExit) as stop:
        tool.main([str(tmp_path / "run.csv"), str(tmp_path / "run.png"), *flags])
    assert stop.value.code == 2
    assert last_error_line(capsys).endswith(message)
    assert not (tmp_path / "run.png").exists()


def test_multi_gpu_logs_without_a_common_iteration_are_one_line(load_file, tmp_path, monkeypatch, capsys):
    """The last iteration both reached was min(last iterations): a 1-GPU log of iterations 800-803 (the tail of a
    long run's console) and a 2-GPU log of 0-4 gave iteration 4, which the 1-GPU log does not hold (a KeyError
    traceback). With a gap in one log (iterations 0-2 and 5-6 against 0-5) it is 5, the last one in both."""
    tool = load_file("tools/multi_gpu_report.py")
    tail = rsl_rl_log(tmp_path / "1.log", range(800, 804), [100] * 4, [1, 2, 3, 4])
    two = rsl_rl_log(tmp_path / "2.log", range(5), [200] * 5, [1, 2, 3, 4, 5])
    assert run_main(tool, monkeypatch, tail, two, "--skip", "1") == ("the logs share no iteration (1gpu: 800-803, "
                                                                     "2gpu: 0-4); give logs of the same iterations")
    gap = rsl_rl_log(tmp_path / "gap.log", [0, 1, 2, 5, 6], [100] * 5, [1, 2, 3, 4, 5])
    six = rsl_rl_log(tmp_path / "6.log", range(6), [200] * 6, [1, 2, 3, 4, 5, 6])
    assert run_main(tool, monkeypatch, gap, six, "--skip", "1") is None
    out = capsys.readouterr().out.splitlines()
    assert out[2] == "      common iteration 5: mean reward 4.00, mean episode length 400.0"
    assert out[5] == "      common iteration 5: mean reward 6.00, mean episode length 600.0"


def test_learning_curve_of_a_binary_file_is_a_usage_error(load_file, tmp_path, capsys):
    """The PNG of an earlier plot given as the CSV (the two arguments swapped): a UnicodeDecodeError traceback."""
    tool = load_file("tools/plot_learning_curve.py")
    png = tmp_path / "run.png"
    png.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\xff\xd8")
    with pytest.raises(SystemExit) as stop:
        tool.main([str(png), str(tmp_path / "run.csv")])
    assert stop.value.code == 2
    assert last_error_line(capsys).endswith(f"{png}: not a text file; give a training CSV of docs/results "
                                        "(tools/scalars_to_results.py)")


# --- tools/scalars_to_results.py ----------------------------------------------------------------------------------

def test_results_of_a_tensorboard_event_file_is_one_line(tmp_path):
    """The run's event file given instead of its tb_export CSV: a UnicodeDecodeError traceback."""
    events = tmp_path / "events.out.tfevents.1.host"
    events.write_bytes(EVENT_FILE)
    result = subprocess.run([sys.executable, str(ROOT / "tools" / "scalars_to_results.py"), str(tmp_path / "out.csv"),
                             str(events)], capture_output=True, text=True)
    assert result.returncode == 1 and "Traceback" not in result.stderr, result.stderr
    assert result.stderr.strip() == (f"{events}: not a text file; give a scalars CSV of python -m "
                                     "legged_gente.utils.tb_export")
    assert not (tmp_path / "out.csv").exists()


def test_results_minutes_and_values_by_hand(tmp_path):
    """Two chunks: iterations 0-2 of 20 + 10 s each, then a resume from iteration 1's checkpoint that redid 1 and 2
    at 5 + 1 s each: wall_s 30, 36, 42 (iteration 0 of the first chunk, 1 and 2 of the second); 0.7 min printed.
    Rates stay in env steps/s (469,123 -> 4.691e+05, four significant digits), the level as logged."""
    header = ["step", "Perf/total_fps", "Episode/terrain_level", "Perf/collection_time", "Perf/learning_time"]
    for name, rows in (("a.csv", [(0, 469123, 0.5, 20, 10), (1, 1, 9, 20, 10), (2, 1, 9, 20, 10)]),
                       ("b.csv", [(1, 2000, 1.25, 5, 1), (2, 3000, 2.5, 5, 1)])):
        with open(tmp_path / name, "w", newline="") as f:
            csv.writer(f).writerows([header, *rows])
    result = subprocess.run([sys.executable, str(ROOT / "tools" / "scalars_to_results.py"), str(tmp_path / "out.csv"),
                             str(tmp_path / "a.csv"), str(tmp_path / "b.csv")], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == f"wrote {tmp_path / 'out.csv'}: 3 iterations, 0.7 min of training"
    rows = list(csv.DictReader(open(tmp_path / "out.csv")))
    assert [(r["iteration"], float(r["wall_s"]), r["terrain_level"]) for r in rows] == [
        ("0", 30.0, "0.5"), ("1", 36.0, "1.25"), ("2", 42.0, "2.5")]
    assert float(rows[0]["env_steps_per_s"]) == 469100.0 and rows[0]["diverged_resets_cumulative"] == "0"


def test_multi_gpu_csv_and_plot_go_into_a_new_folder(load_file, tmp_path, monkeypatch):
    """--csv and --plot into a folder not made yet (as gente-benchmark --csv and scalars_to_results make theirs):
    a FileNotFoundError traceback after the report was printed. The CSV: one row per iteration of each run."""
    tool = load_file("tools/multi_gpu_report.py")
    one = rsl_rl_log(tmp_path / "1.log", range(3), [100, 100, 100], [1, 2, 3])
    two = rsl_rl_log(tmp_path / "2.log", range(2), [200, 200], [1, 2])
    out = tmp_path / "new" / "mg.csv"
    assert run_main(tool, monkeypatch, one, two, "--skip", "1", "--csv", str(out), "--plot",
                    str(tmp_path / "img" / "mg.png")) is None
    rows = list(csv.DictReader(open(out)))
    assert [(r["run"], r["iteration"], float(r["steps_per_second"]), float(r["mean_reward"])) for r in rows] == [
        ("1gpu", "0", 100.0, 1.0), ("1gpu", "1", 100.0, 2.0), ("1gpu", "2", 100.0, 3.0),
        ("2gpu", "0", 200.0, 1.0), ("2gpu", "1", 200.0, 2.0)]
    assert (tmp_path / "img" / "mg.png").read_bytes()[:4] == b"\x89PNG"
