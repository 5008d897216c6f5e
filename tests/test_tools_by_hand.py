"""The CPU tools of tools/ on tiny inputs: their numbers against values worked out by hand, and a user's wrong
input (a missing file, a CSV or log of another kind, a checkpoint of another task) as one line naming the fix."""

import csv
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from legged_gente.utils import checkpoints

ROOT = Path(__file__).resolve().parents[1]


def run_main(tool, monkeypatch, *argv):
    """``tool.main()`` with ``argv`` as its command line; the exit code (None when it returned)."""
    monkeypatch.setattr(sys, "argv", [tool.__name__, *argv])
    try:
        tool.main()
    except SystemExit as stop:
        return stop.code
    return None


def last_error_line(capsys) -> str:
    """The error the tool printed: its last line on stderr, with no traceback before it."""
    err = capsys.readouterr().err
    assert "Traceback" not in err, err
    return err.strip().splitlines()[-1]


def recorded_plots(tool, monkeypatch) -> list:
    """(label, x, y) of every line the tool draws with matplotlib's Axes.plot."""
    plotted, plot = [], tool.plt.Axes.plot

    def recording_plot(ax, x, y, *args, **kwargs):
        plotted.append((kwargs.get("label"), list(x), list(y)))
        return plot(ax, x, y, *args, **kwargs)

    monkeypatch.setattr(tool.plt.Axes, "plot", recording_plot)
    return plotted


# --- tools/plot_learning_curve.py ---------------------------------------------------------------------------------

def test_learning_curve_leaves_a_gap_before_the_first_finished_episode(load_file, tmp_path, monkeypatch):
    """tools/scalars_to_results.py writes the iterations before the first finished episode with empty episode
    cells: those are gaps in the curve (NaN), the rest is each column over its maximum against minutes.
    wall_s 60, 120, 180, 240 s -> 1, 2, 3, 4 min; episode length 500, 800 of 1000 steps -> 0.5, 0.8; terrain
    level 1, 2, 3 of 10 levels -> 0.1, 0.2, 0.3."""
    tool = load_file("tools/plot_learning_curve.py")
    path = tmp_path / "run.csv"
    path.write_text("iteration,wall_s,mean_episode_length,rew_tracking_lin_vel,mean_reward,terrain_level\n"
                    "0,60,,0.1,,\n1,120,,0.2,,1\n2,180,500,0.5,3,2\n3,240,800,0.6,4,3\n")
    plotted = recorded_plots(tool, monkeypatch)
    tool.main([str(path), str(tmp_path / "run.png"), "--levels", "10"])
    lines = {label: (x, y) for label, x, y in plotted}
    nan = math.nan
    for label, expected in (("episode length / max", [nan, nan, 0.5, 0.8]),
                            ("tracking_lin_vel / max", [0.1, 0.2, 0.5, 0.6]),
                            ("mean terrain level / 10", [nan, 0.1, 0.2, 0.3])):
        x, y = lines[label]
        np.testing.assert_allclose(x, [1.0, 2.0, 3.0, 4.0])
        np.testing.assert_allclose(y, expected, equal_nan=True)
    assert (tmp_path / "run.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_learning_curve_of_a_missing_csv_is_a_usage_error(load_file, tmp_path, capsys):
    tool = load_file("tools/plot_learning_curve.py")
    with pytest.raises(SystemExit) as stop:
        tool.main([str(tmp_path / "none.csv"), str(tmp_path / "out.png")])
    assert stop.value.code == 2
    assert last_error_line(capsys).endswith(f"{tmp_path / 'none.csv'}: no such file; give a training CSV of "
                                            "docs/results (tools/scalars_to_results.py)")


# --- tools/plot_throughput.py -------------------------------------------------------------------------------------

@pytest.mark.parametrize("text, what", [
    ("iteration,wall_s,mean_episode_length\n0,1.0,20\n",
     "no column num_envs, raw_substeps_per_s, env_steps_per_s, ppo_steps_per_s"),
    ("num_envs,raw_substeps_per_s,env_steps_per_s,ppo_steps_per_s\n", "no rows"),
])
def test_throughput_of_a_csv_of_another_kind_is_a_usage_error(load_file, tmp_path, capsys, text, what):
    """A training CSV given for a benchmark CSV (a KeyError traceback before), or a benchmark CSV without rows
    (matplotlib's 'Data cannot be log-scaled')."""
    tool = load_file("tools/plot_throughput.py")
    (tmp_path / "a.csv").write_text(text)
    with pytest.raises(SystemExit) as stop:
        tool.main([str(tmp_path / "out.png"), f"a={tmp_path / 'a.csv'}"])
    assert stop.value.code == 2
    assert last_error_line(capsys).endswith(f"'a={tmp_path / 'a.csv'}': {what}; give a CSV of gente-benchmark --csv")
    assert not (tmp_path / "out.png").exists()


def test_throughput_draws_each_rate_per_num_envs(load_file, tmp_path, monkeypatch):
    """raw / decimation = 160000 / 4 = 40000 and 560000 / 4 = 140000 env steps/s; env and PPO rates as written."""
    tool = load_file("tools/plot_throughput.py")
    (tmp_path / "a.csv").write_text("num_envs,raw_substeps_per_s,env_steps_per_s,ppo_steps_per_s,decimation\n"
                                    "1024,160000,30000,20000,4\n4096,560000,100000,70000,4\n")
    plotted = recorded_plots(tool, monkeypatch)
    tool.main([str(tmp_path / "out.png"), f"H={tmp_path / 'a.csv'}"])
    assert {label: (x, y) for label, x, y in plotted} == {
        "H: raw / decimation": ([1024, 4096], [40000.0, 140000.0]),
        "H: env": ([1024, 4096], [30000.0, 100000.0]), "H: PPO": ([1024, 4096], [20000.0, 70000.0])}


# --- tools/scalars_to_results.py ----------------------------------------------------------------------------------

SCALARS = ["step", "Train/mean_episode_length", "Episode/rew_tracking_lin_vel", "Train/mean_reward", "Perf/total_fps",
           "Episode/terrain_level", "Episode/diverged_resets", "Perf/collection_time", "Perf/learning_time"]


def scalars_to_results(*argv):
    return subprocess.run([sys.executable, str(ROOT / "tools" / "scalars_to_results.py"), *map(str, argv)],
                          capture_output=True, text=True)


def test_results_sum_each_iterations_own_time_and_divergences(tmp_path):
    """Iterations of 1.0 + 0.5, 2.0 + 0.3 and 0.7 + 0.2 s: wall_s 1.5, 3.8, 4.7; diverged resets 0, 1, 2 per
    iteration: cumulative 0, 1, 3."""
    with open(tmp_path / "a.csv", "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(SCALARS)
        for step, (collect, learn, diverged) in enumerate([(1.0, 0.5, 0), (2.0, 0.3, 1), (0.7, 0.2, 2)]):
            writer.writerow([step, 100 * step, 0.5, 1.0, 4000, 0.0, diverged, collect, learn])
    result = scalars_to_results(tmp_path / "out.csv", tmp_path / "a.csv")
    assert result.returncode == 0, result.stderr
    rows = list(csv.DictReader(open(tmp_path / "out.csv")))
    assert [float(r["wall_s"]) for r in rows] == [1.5, 3.8, 4.7]
    assert [int(r["diverged_resets_cumulative"]) for r in rows] == [0, 1, 3]


@pytest.mark.parametrize("case", ["missing", "no learning time"])
def test_results_of_a_missing_or_foreign_csv_is_one_line(tmp_path, case):
    chunk = tmp_path / "a.csv"
    if case == "no learning time":
        chunk.write_text("step,Perf/collection_time\n0,1.0\n")
    result = scalars_to_results(tmp_path / "out.csv", chunk)
    assert result.returncode == 1 and "Traceback" not in result.stderr and result.stderr.count("\n") == 1
    expected = {"missing": f"{chunk}: No such file or directory; give a scalars CSV of python -m "
                           "legged_gente.utils.tb_export",
                "no learning time": f"{chunk}: no training iterations (is it a tb_export CSV of a run?)"}[case]
    assert result.stderr.strip() == expected
    assert not (tmp_path / "out.csv").exists()


# --- tools/multi_gpu_report.py ------------------------------------------------------------------------------------

def rsl_rl_log(path, steps_per_second, rewards, first=0):
    """A console log as rsl-rl-lib 5.5's Logger prints it (labels right-aligned to 40 characters; the iteration
    header in bold); ``None`` reward: no episode has ended yet (rsl-rl prints no reward)."""
    pad = 40
    with open(path, "w") as f:
        for k, (sps, reward) in enumerate(zip(steps_per_second, rewards)):
            it = first + k
            f.write("#" * 80 + "\n")
            f.write(f"\033[1m{f' Learning iteration {it}/{first + 1000} '.center(80)}\033[0m \n\n")
            f.write(f"{'Total steps:':>{pad}} {1000 * (k + 1)} \n")
            if sps is not None:
                f.write(f"{'Steps per second:':>{pad}} {sps:.0f} \n")
            f.write(f"{'Collection time:':>{pad}} 1.000s \n")
            if reward is not None:
                f.write(f"{'Mean reward:':>{pad}} {reward:.2f}\n{'Mean episode length:':>{pad}} {10 * reward:.2f}\n")
            f.write(f"{'Mean episode rew_tracking_lin_vel:':>{pad}} 0.5000\n")
    return path


def test_multi_gpu_ratio_is_the_mean_rate_after_the_skipped_iterations(load_file, tmp_path, monkeypatch, capsys):
    """1 GPU, iterations 0-5: after the first 3, (1000 + 1100 + 900) / 3 = 1000 steps/s; 2 GPUs, iterations 0-4:
    (1900 + 2100) / 2 = 2000; ratio 2000 / 1000 = 2.000. The last iteration both reached is 4: rewards 4.00 and
    8.00."""
    tool = load_file("tools/multi_gpu_report.py")
    one = rsl_rl_log(tmp_path / "1.log", [10, 100, 1000, 1000, 1100, 900], [None, 1, 2, 3, 4, 5])
    two = rsl_rl_log(tmp_path / "2.log", [5, 50, 2000, 1900, 2100], [None, 2, 4, 6, 8])
    assert run_main(tool, monkeypatch, str(one), str(two), "--csv", str(tmp_path / "mg.csv")) is None
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "1gpu: 6 iterations, mean steps/s 1000 (iterations after the first 3)"
    assert out[2] == "      common iteration 4: mean reward 4.00, mean episode length 40.0"
    assert out[3] == "2gpu: 5 iterations, mean steps/s 2000 (iterations after the first 3)"
    assert out[5] == "      common iteration 4: mean reward 8.00, mean episode length 80.0"
    assert out[-1] == "throughput ratio 2gpu/1gpu: 2.000"
    rows = list(csv.DictReader(open(tmp_path / "mg.csv")))
    assert len(rows) == 11 and rows[0] == {"run": "1gpu", "iteration": "0", "steps_per_second": "10.0",
                                           "mean_reward": "", "mean_episode_length": ""}


def test_multi_gpu_report_of_a_missing_or_foreign_log_is_one_line(load_file, tmp_path, monkeypatch, capsys):
    tool = load_file("tools/multi_gpu_report.py")
    one = rsl_rl_log(tmp_path / "1.log", [1000] * 5, [1] * 5)
    assert run_main(tool, monkeypatch, str(one), str(tmp_path / "none.log")) == 2
    assert last_error_line(capsys).endswith(f"{tmp_path / 'none.log'}: no such file; give the console log of a "
                                            "training run (rank 0)")
    # a log whose iterations print no "Steps per second" (another rsl-rl's format): a KeyError traceback before
    other = rsl_rl_log(tmp_path / "2.log", [None] * 5, [1] * 5)
    assert run_main(tool, monkeypatch, str(one), str(other)) == ("2gpu: iteration 0 logs no 'Steps per second' (an "
                                                                 "rsl-rl log of another format, or cut short); give "
                                                                 "a console log of this rsl-rl-lib's runner")


# --- tools/ship_policy.py -----------------------------------------------------------------------------------------

def test_a_checkpoint_whose_run_trained_another_task_is_not_shipped(load_file, tmp_path, monkeypatch, capsys):
    """A checkpoint that names no task (saved before the runner recorded it) from a gente_quadruped run (its
    config.json says so; 12 actions) was shipped as gente_biped_flat's policy (10 actions)."""
    monkeypatch.setattr(checkpoints, "policies_root", lambda: tmp_path / "policies")  # never the package's
    tool = load_file("tools/ship_policy.py")
    (tmp_path / "run").mkdir()
    actor = {"mlp.0.weight": torch.zeros(4, 3), "mlp.2.weight": torch.zeros(12, 4),
             "distribution.std_param": torch.ones(12)}
    torch.save({"actor_state_dict": actor, "iter": 7}, tmp_path / "run" / "model_7.pt")
    (tmp_path / "run" / "config.json").write_text(json.dumps({"task": "gente_quadruped"}))
    with pytest.raises(SystemExit) as stop:
        tool.main([str(tmp_path / "run" / "model_7.pt"), "--task", "gente_biped_flat", "--note", "x"])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1, err
    assert err.strip() == (f"ship_policy: error: checkpoint {tmp_path / 'run' / 'model_7.pt'} is for gente_quadruped, "
                           f"not gente_biped_flat: ship it as --task gente_quadruped, or pick a checkpoint of a "
                           f"gente_biped_flat run")
    assert not (tmp_path / "policies").exists()


@pytest.mark.parametrize("task, num_actions", [("gente_biped", 10), ("gente_biped_flat", 10), ("gente_quadruped", 12)])
def test_the_shipped_policies_are_the_actor_alone_and_load_on_the_cpu(task, num_actions):
    """Each shipped model.pt loads with weights_only on the CPU, holds the actor only (no critic, no optimizer),
    names its task and the robot's action count (the biped's 10 joints, the quadruped's 12), and weighs about 4
    bytes per float32 parameter."""
    path, config = checkpoints.pretrained_policy(task)
    loaded = torch.load(path, map_location="cpu", weights_only=True)
    assert set(loaded) == {"actor_state_dict", "iter", "infos"} and config["task"] == task
    assert loaded["infos"] == {"task": task, "num_actions": num_actions}
    actor = loaded["actor_state_dict"]
    last = max((k for k in actor if k.startswith("mlp.") and k.endswith(".weight")), key=lambda k: int(k.split(".")[1]))
    assert actor[last].shape[0] == num_actions and actor["distribution.std_param"].shape == (num_actions,)
    assert all(v.device.type == "cpu" for v in actor.values())
    floats = sum(v.numel() for v in actor.values())
    assert 4 * floats < path.stat().st_size < 4 * floats + 16_000  # the zip's headers: a few kB


# --- the evaluation tools: a wrong benchmark, item, report, task or checkpoint is one line --------------------

def test_diagnose_divergence_of_an_unknown_item_is_one_line(load_file, capsys):
    tool = load_file("tools/diagnose_divergence.py")
    with pytest.raises(SystemExit) as stop:
        tool.main(["--task", "gente_biped", "--benchmark", "flat", "--items", "nope"])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert f"items ['nope'] are not in {ROOT / 'legged_gente' / 'benchmarks' / 'flat' / 'manifest.json'}" in err


def test_diagnose_divergence_with_a_checkpoint_of_another_robot_is_one_line(load_file, tmp_path, capsys):
    tool = load_file("tools/diagnose_divergence.py")
    actor = {"mlp.0.weight": torch.zeros(4, 3), "mlp.2.weight": torch.zeros(12, 4),
             "distribution.std_param": torch.ones(12)}
    torch.save({"actor_state_dict": actor, "iter": 7, "infos": {"task": "gente_quadruped"}}, tmp_path / "model_7.pt")
    with pytest.raises(SystemExit) as stop:
        tool.main(["--task", "gente_biped", "--benchmark", "flat", "--robots_per_terrain", "1", "--episode_s", "0.1",
                   "--no_progress", "--checkpoint", str(tmp_path / "model_7.pt")])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert "is for gente_quadruped (12 actions); this task is gente_biped (10 actions)" in err


@pytest.mark.parametrize("case", ["missing report", "report of another kind", "unknown item"])
def test_trace_failures_wrong_input_is_one_line(load_file, tmp_path, monkeypatch, capsys, case):
    tool = load_file("tools/trace_failures.py")
    report = tmp_path / "report.csv"
    argv = ["--task", "gente_biped", "--pretrained", "--benchmark", "flat"]
    if case == "unknown item":
        argv += ["--items", "nope"]
    else:
        argv += ["--report", str(report)]
    if case == "report of another kind":
        report.write_text("iteration,wall_s\n0,1.0\n")  # a training CSV: a KeyError 'row' traceback before
    code = run_main(tool, monkeypatch, *argv)
    if case == "report of another kind":  # SystemExit's message: Python prints it, one line
        assert code == f"{report}: no column row, name, success_rate, fall_rate; give gente-evaluate's report.csv"
        return
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    expected = {"missing report": f"{report}: No such file or directory", "unknown item": "items ['nope'] are not in"}
    assert expected[case] in err


def test_tile_edge_paths_of_an_unknown_benchmark_is_one_line(load_file, tmp_path, monkeypatch, capsys):
    tool = load_file("tools/tile_edge_paths.py")
    assert run_main(tool, monkeypatch, "--benchmark", str(tmp_path / "none")) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert f"{tmp_path / 'none' / 'manifest.json'} not found; pass a benchmark folder" in err


@pytest.mark.parametrize("argv, expected", [
    (("--benchmark", "flat", "--report", "{tmp}/report.csv"),
     "{tmp}/report.csv: no column row, name, success_rate, fall_rate, tracking_error; give gente-evaluate's "
     "report.csv"),
    (("--benchmark", "flat", "--report", "{tmp}/none.csv"), "{tmp}/none.csv: No such file or directory"),
    (("--curriculum", "gente_bipd"), "unknown task 'gente_bipd'; registered tasks:"),
    (("--curriculum", "gente_biped", "--set", "terrain.num_rowz=2"), "terrain has no field 'num_rowz'"),
])
def test_terrain_roughness_wrong_input_is_one_line(load_file, tmp_path, monkeypatch, capsys, argv, expected):
    tool = load_file("tools/terrain_roughness.py")
    (tmp_path / "report.csv").write_text("iteration,wall_s\n0,1.0\n")  # a training CSV, not a report
    assert run_main(tool, monkeypatch, *(a.format(tmp=tmp_path) for a in argv)) == 2
    assert expected.format(tmp=tmp_path) in last_error_line(capsys)
