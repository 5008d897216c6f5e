"""A user's mistake on the command line is one line on stderr and exit status 2, never a traceback; flags take
both spellings (--num_envs, --num-envs) in every command; the CPU default of 4096 robots is called out."""

import json
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from legged_gente.envs.task_registry import task_registry
from legged_gente.scripts import benchmark as benchmark_script
from legged_gente.scripts import evaluate as evaluate_script
from legged_gente.scripts import generate as generate_script
from legged_gente.scripts import play as play_script
from legged_gente.scripts import train as train_script
from legged_gente.scripts import view as view_script
from legged_gente.utils.args import build_parser, flag, parse_args


def one_line_error(capsys, main, argv) -> str:
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    err = capsys.readouterr().err
    assert exit_info.value.code == 2, err
    assert "Traceback" not in err
    lines = [line for line in err.splitlines() if line.strip()]
    return lines[-1]


BENCHMARKS = Path(__file__).resolve().parents[1] / "legged_gente" / "benchmarks"
CPU = ["--device", "cpu", "--num_envs", "1", "--headless"]


@pytest.mark.parametrize("override, message", [
    ("terrain.num_rows=-2", "num_rows=-2 and num_cols=20 must both be >= 1"),
    ("terrain.resolution=0", "resolution must be > 0 m"),
    ("terrain.terrain_length=8.05", "terrain_length=8.05 m is not a whole number of resolution=0.1 m cells"),
])
def test_an_invalid_grid_setting_is_refused_on_a_plane_task_too(capsys, tmp_path, monkeypatch, override, message):
    """A plane task builds no terrain grid, but a grid setting it ignores is still refused when invalid: silently
    accepted, it would surface only once the user moves to a task with a grid."""
    monkeypatch.setenv("GENTE_LOG_ROOT", str(tmp_path))
    line = one_line_error(capsys, train_script.main, ["--task", "gente_biped_flat", *CPU, "--max_iterations", "1",
                                                      "--set", override])
    assert message in line, line


def test_unknown_task(capsys):
    line = one_line_error(capsys, train_script.main, ["--task", "gente_bipd", *CPU])
    assert line.startswith("gente-train: error: unknown task 'gente_bipd'") and "gente_biped_flat" in line


def test_bad_set_field(capsys):
    line = one_line_error(capsys, train_script.main, ["--task", "gente_biped_flat", *CPU, "--set", "terrain.num_rowz=4"])
    assert "terrain has no field 'num_rowz'" in line and "num_rows" in line


@pytest.mark.parametrize("override, message", [
    ("runner.save_interval=0", "runner.save_interval=0: must be >= 1"),
    ("runner.num_steps_per_env=0", "runner.num_steps_per_env=0: must be >= 1"),
    ("sim.dt=0", "sim.dt=0.0: must be > 0"),
    ("algorithm.num_mini_batches=0", "algorithm.num_mini_batches=0: must be >= 1"),
    ("env.episode_length_s=0", "env.episode_length_s=0.0: must be > 0"),
    ("terrain.hfield_piece_size=0", "terrain.hfield_piece_size=0.0: must be > 0"),
    ("runner.num_steps_per_env=2", "= 1 * 2 = 2 samples cannot fill algorithm.num_mini_batches=4"),
])
def test_zero_divisors_are_rejected_before_anything_runs(capsys, override, message):
    line = one_line_error(capsys, train_script.main, ["--task", "gente_biped_flat", *CPU, "--set", override])
    assert message in line


@pytest.mark.parametrize("override, message", [
    ("algorithm.learning_rate=-1", "algorithm.learning_rate=-1.0: must be a number > 0"),
    ("algorithm.gamma=5", "algorithm.gamma=5.0: must be a number in (0, 1]"),
    ("algorithm.clip_param=-1", "algorithm.clip_param=-1.0: must be a number > 0"),
    ("algorithm.schedule=bogus", "algorithm.schedule='bogus': use 'adaptive'"),
    ("commands.ranges.lin_vel_x=[1.0,2.0,3.0]", "cfg.commands.ranges.lin_vel_x=[1.0, 2.0, 3.0]; use [low, high]"),
])
def test_nonsense_settings_are_rejected_before_anything_runs(capsys, override, message):
    """rsl-rl would train on with a negative learning rate or clip, a discount above 1 or an unknown schedule
    (it treats any schedule but 'adaptive' as fixed)."""
    line = one_line_error(capsys, train_script.main, ["--task", "gente_biped_flat", *CPU, "--set", override])
    assert message in line


@pytest.mark.parametrize("flags, message", [
    (["--episode_s", "0"], "episode_s must be > 0 s, got 0.0"),
    (["--episode_s", "-1"], "episode_s must be > 0 s, got -1.0"),
    (["--tracking_threshold", "-1"], "tracking_threshold must be > 0 m/s"),
    (["--min_progress", "5"], "min_progress is a share of the commanded distance, in (0, 1]; got 5.0"),
    (["--min_speed", "0"], "min_speed must be > 0 m/s"),
    (["--out", "FILE"], "is a file; give a folder"),
    (["--mode", "waypoints", "--speed", "0"], "speed must be > 0 m/s, got 0.0"),
    (["--tile_edge_margin", "near"], "'near' is not a distance in m; give a number such as 0.5, or 'off'"),
    (["--tile_edge_margin", "-0.1"], "tile_edge_margin -0.1 m must be in [0, "),
    (["--settle_s", "-1", "--episode_s", "2"], "settle_s must be >= 0 s, got -1.0"),
])
def test_nonsense_evaluation_flags(capsys, tmp_path, flags, message):
    (tmp_path / "FILE").write_text("")
    flags = [str(tmp_path / f) if f == "FILE" else f for f in flags]
    out = [] if "--out" in flags else ["--out", str(tmp_path / "out")]
    line = one_line_error(capsys, evaluate_script.main, ["--task", "gente_biped_flat", "--baseline", "zero",
                                                         "--benchmark", "flat", "--robots_per_terrain", "2",
                                                         "--device", "cpu", "--no_progress", *out, *flags])
    assert message in line


@pytest.mark.parametrize("flags, message", [
    (["--stand_fraction", "2"], "--stand_fraction must be in [0, 1], got 2.0"),
    (["--min_speed", "-1"], "--min_speed must be > 0 m/s, got -1.0"),
    (["--mode", "waypoints", "--reach_distance", "0"], "--reach_distance must be > 0 m, got 0.0"),
    (["--mode", "waypoints", "--speed", "inf"], "--speed must be a finite speed in m/s, got inf"),
])
def test_a_task_setting_is_refused_in_its_flags_name_before_the_env_is_built(capsys, tmp_path, monkeypatch, flags,
                                                                             message):
    from legged_gente.evaluation import evaluator

    monkeypatch.setattr(evaluator, "Evaluation", never)
    line = one_line_error(capsys, evaluate_script.main, ["--task", "gente_biped_flat", "--baseline", "zero",
                                                         "--benchmark", "flat", "--device", "cpu", "--out",
                                                         str(tmp_path / "out"), *flags])
    assert message in line, line


@pytest.mark.parametrize("flags, message", [
    (["--speed", "0.8"], "--speed is a flag of --mode waypoints; it does nothing with --mode velocity"),
    (["--reach_distance", "5"], "--reach_distance is a flag of --mode waypoints; it does nothing with --mode velocity"),
    (["--mode", "waypoints", "--min_speed", "0.5"], "--min_speed is a flag of --mode velocity; it does nothing with --mode waypoints"),
    (["--mode", "waypoints", "--stand_fraction", "0"], "--stand_fraction is a flag of --mode velocity; it does nothing"),
    (["--mode", "waypoints", "--tracking_threshold", "0.1"], "--tracking_threshold is a flag of --mode velocity"),
    (["--mode", "waypoints", "--min_progress", "0.5"], "--min_progress is a flag of --mode velocity"),
])
def test_a_flag_of_the_other_evaluation_mode_is_refused(capsys, tmp_path, flags, message):
    """--speed with the velocity task used to be ignored: the run scored something else than was asked."""
    line = one_line_error(capsys, evaluate_script.main, ["--task", "gente_biped_flat", "--baseline", "zero",
                                                         "--benchmark", "flat", "--device", "cpu", "--no_progress",
                                                         "--out", str(tmp_path / "out"), *flags])
    assert message in line


def test_the_mode_flags_keep_their_defaults():
    def parsed(*flags):
        return evaluate_script.mode_settings(evaluate_script.build_parser().parse_args(["--baseline", "zero",
                                                                                        "--out", "o", *flags]))

    assert parsed() == {"tracking_threshold": 0.25, "min_progress": 0.7, "min_speed": 0.3, "stand_fraction": 0.1}
    assert parsed("--mode", "waypoints", "--speed", "0.4") == {"reach_distance": 1.0, "speed": 0.4}


def test_the_tile_edge_margin_is_on_by_default_and_can_be_turned_off():
    def margin(*flags):
        return evaluate_script.build_parser().parse_args(["--baseline", "zero", "--out", "o", *flags]).tile_edge_margin

    assert margin() == 0.5 and margin("--tile_edge_margin", "0.8") == 0.8 and margin("--tile-edge-margin", "off") is None


@pytest.mark.parametrize("flags, message", [
    (["--task", "nope"], "unknown task 'nope'; registered tasks:"),
    (["--steps", "0"], "--steps 0 must be >= 1"),
    (["--steps", "-3"], "--steps -3 must be >= 1"),
    (["--iterations", "-1"], "--iterations -1 >= 0"),
])
def test_nonsense_benchmark_flags(capsys, flags, message):
    line = one_line_error(capsys, benchmark_script.main, ["--num_envs", "2", "--device", "cpu", *flags])
    assert message in line


@pytest.mark.parametrize("argv, message", [
    (["--port", "99999"], "port 99999 must be in 0..65535"),
    (["--host", "256.1.1.1"], "cannot serve on host '256.1.1.1'"),
    (["--play", "--policy", "zero", "--steps", "0"], "--steps 0: roll out at least 1 policy step"),
    (["TEXT.npz"], "TEXT.npz is not a readable NumPy .npz archive"),
    (["gente100", "--traces", "TEXT.npz"], "TEXT.npz is not a readable NumPy .npz archive"),
])
def test_nonsense_viewer_input(capsys, tmp_path, argv, message):
    """A port out of range or a host that is not this machine's kept the viewer waiting for a server that never
    came; a text file named .npz showed numpy's advice to unpickle it."""
    (tmp_path / "TEXT.npz").write_text("hello")
    argv = [str(tmp_path / a) if a == "TEXT.npz" else a for a in argv]
    line = one_line_error(capsys, view_script.main, ["--task", "gente_biped_flat", "--headless", "--seconds", "0",
                                                     *argv])
    assert message in line


def test_play_needs_a_step(capsys):
    line = one_line_error(capsys, play_script.main, ["--task", "gente_biped_flat", *CPU, "--steps", "-5"])
    assert "--steps -5: roll out at least 1 policy step" in line


def test_a_checkpoint_is_picked_only_to_resume(capsys):
    line = one_line_error(capsys, train_script.main, ["--task", "gente_biped_flat", *CPU, "--checkpoint", "5"])
    assert "add --resume" in line


FLAT_SPEC = BENCHMARKS / "flat" / "specs" / "flat.json"


@pytest.mark.parametrize("change, message", [
    ("{not json", "is not valid JSON (Expecting property name"),
    ({"version": 99}, "terrain spec format version 99; this code reads version 1"),
    ({"size_x": -5.0}, "not a terrain spec document: spec: field 'size_x': -5.0 is less than the minimum of 1.0."),
    ({"calls": [{"tool": "flat", "region": "upper_half_ish", "params": {}}]},
     "region 'upper_half_ish' is none of the named regions (full, "),
])
def test_a_bad_terrain_spec_names_the_problem(capsys, tmp_path, change, message):
    path = tmp_path / "spec.json"
    document = json.loads(FLAT_SPEC.read_text())
    path.write_text(change if isinstance(change, str) else json.dumps(document | change))
    line = one_line_error(capsys, train_script.main, ["--task", "gente_biped_flat", *CPU, "--terrain", str(path)])
    assert message in line


@pytest.mark.parametrize("manifest, message", [
    ('{"items": [', "manifest.json is not valid JSON"),
    ('{"name": "x"}', "is not a benchmark manifest (KeyError: 'items'): it needs"),
    ('{"items": [{"id": "a", "kind": "text"}]}', "is not a benchmark manifest (KeyError: 'spec')"),
])
def test_a_bad_manifest_names_its_file(capsys, tmp_path, manifest, message):
    (tmp_path / "manifest.json").write_text(manifest)
    line = one_line_error(capsys, evaluate_script.main, ["--baseline", "zero", "--benchmark", str(tmp_path),
                                                         "--out", str(tmp_path / "out"), "--device", "cpu"])
    assert message in line and str(tmp_path) in line


@pytest.mark.parametrize("argv, message", [
    (["--text", "   "], "--text is empty; describe the scene"),
    (["--text", "a hill", "--out", "FILE"], "is a file; give a folder"),
    (["--text", "a hill", "--backend", "openai", "--base-url", "http://127.0.0.1:9/v1", "--model", "m",
      "--max-retries", "-1"], "--max-retries must be between 0 and 10, got -1"),
    (["--text", "a hill", "--backend", "openai", "--base-url", "http://127.0.0.1:9/v1", "--model", "m",
      "--max-retries", "1000000"], "--max-retries must be between 0 and 10, got 1000000"),
])
def test_nonsense_generation_flags(capsys, tmp_path, argv, message):
    (tmp_path / "FILE").write_text("")
    argv = [str(tmp_path / a) if a == "FILE" else a for a in argv]
    line = one_line_error(capsys, generate_script.main, ["--out", str(tmp_path / "out"), *argv])
    assert message in line


def test_generation_errors_are_one_line_and_name_the_image(capsys, tmp_path):
    """A size the spec refuses by its flag, before generating; an unreadable image by its path, not by Pillow's buffer."""
    line = one_line_error(capsys, generate_script.main, ["--text", "a hill", "--size", "100000", "--out", str(tmp_path / "o")])
    assert line == "gente-generate: error: --size 100000: must be in [1, 200]."
    image = tmp_path / "photo.png"
    image.write_text("not an image")
    line = one_line_error(capsys, generate_script.main, ["--image", str(image), "--out", str(tmp_path / "o")])
    assert f"{image} could not be read as an image" in line and "BytesIO" not in line, line


def test_cuda_without_a_gpu_says_so(capsys, monkeypatch):
    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    monkeypatch.setattr(torch.cuda, "device_count", lambda: 0)
    for main in (train_script.main, play_script.main):
        line = one_line_error(capsys, main, ["--task", "gente_biped_flat", "--device", "cuda"])
        assert "no GPU visible, use --device cpu" in line
    line = one_line_error(capsys, evaluate_script.main, ["--baseline", "zero", "--out", "x", "--device", "cuda:1"])
    assert "no GPU visible, use --device cpu" in line


def test_missing_checkpoint(capsys, tmp_path):
    line = one_line_error(capsys, play_script.main, ["--task", "gente_biped_flat", *CPU, "--log_root", str(tmp_path)])
    assert line.startswith("gente-play: error: no runs under") and "train first" in line
    line = one_line_error(capsys, evaluate_script.main, ["--task", "gente_biped_flat", "--checkpoint",
                                                         str(tmp_path / "model_9.pt"), "--out", str(tmp_path),
                                                         "--device", "cpu", "--limit", "1"])
    assert "no such file or run folder" in line


def small_runner(task: str):
    """The task's runner on the CPU with 8-wide networks (quick to save and load)."""
    args = parse_args(build_parser("test"), ["--task", task, *CPU])
    env, _ = task_registry.make_env(args.task, args)
    _, train_cfg = task_registry.get_cfgs(args.task)
    train_cfg.actor.hidden_dims = train_cfg.critic.hidden_dims = [8]
    return task_registry.make_alg_runner(env, args.task, train_cfg=train_cfg, log_root=None)[0]


def test_checkpoint_of_another_task(capsys, tmp_path):
    """A quadruped checkpoint played as the biped: the tasks and action counts, not torch's size mismatch."""
    runner = small_runner("gente_quadruped_flat")
    run = tmp_path / "gente_biped_flat" / "2026-01-01_00-00-00"
    run.mkdir(parents=True)
    runner.save(str(run / "model_0.pt"))
    line = one_line_error(capsys, play_script.main, ["--task", "gente_biped_flat", *CPU, "--log_root", str(tmp_path),
                                                     "--steps", "1"])
    assert "is for gente_quadruped_flat (12 actions); this task is gente_biped_flat (10 actions)" in line


def test_every_command_takes_both_flag_spellings():
    for spelling in ("--num_envs", "--num-envs"):
        assert parse_args(build_parser("t"), ["--device", "cpu", spelling, "3"]).num_envs == 3
    for spelling in ("--max-retries", "--max_retries"):
        assert generate_script.build_parser().parse_args(["--out", "o", spelling, "2"]).max_retries == 2
    for spelling in ("--robots_per_terrain", "--robots-per-terrain"):
        args = evaluate_script.build_parser().parse_args(["--baseline", "zero", "--out", "o", spelling, "2"])
        assert args.robots_per_terrain == 2
    assert flag("--task") == ("--task",)


def test_many_robots_on_the_cpu_are_called_out(capsys, monkeypatch):
    """The task default (4096 robots) on the CPU prints a note with the fix before the (slow) env is built."""
    env_class, env_cfg, train_cfg = task_registry.tasks["gente_biped_flat"]

    class Built(Exception):
        pass

    def not_built(*args, **kwargs):
        raise Built

    monkeypatch.setitem(task_registry.tasks, "gente_biped_flat", (not_built, env_cfg, train_cfg))
    with pytest.raises(Built):
        task_registry.make_env("gente_biped_flat", parse_args(build_parser("t"), ["--task", "gente_biped_flat",
                                                                                 "--device", "cpu"]))
    out = capsys.readouterr().out
    assert "4096 robots on the CPU" in out and "--num_envs" in out


def test_third_party_noise_is_quiet_by_default():
    import warp as wp

    from legged_gente.utils.args import quiet_third_party

    level = wp.config.log_level
    try:
        quiet_third_party(verbose=False)
        assert wp.config.log_level == wp.LOG_WARNING  # no "Module ... loaded" lines, no banner
    finally:
        wp.config.log_level = level


def test_the_projects_own_warnings_are_one_line_unless_verbose(tmp_path):
    """A command's warning of the project's (no flat spawn patch, water no geom feels, ...) is one line saying
    what, not Python's file, line and source line; a third party's keeps Python's form; --verbose keeps both."""
    import subprocess
    import sys

    code = ("import sys, warnings\n"
            "from legged_gente.utils.args import quiet_third_party\n"
            "quiet_third_party(verbose=sys.argv[1] == 'verbose')\n"
            "import legged_gente.terrain.terrain as t\n"
            "warnings.warn_explicit('no flat 1.0 m spawn patch\\n on tile (0, 1)', UserWarning, t.__file__, 191)\n"
            "warnings.warn_explicit('a library speaks', UserWarning, '/elsewhere/lib.py', 7)\n")
    quiet = subprocess.run([sys.executable, "-c", code, "quiet"], capture_output=True, text=True, timeout=300)
    lines = [line for line in quiet.stderr.splitlines() if not line.startswith("Warp CUDA warning")]
    assert lines[0] == "warning: no flat 1.0 m spawn patch on tile (0, 1)", quiet.stderr
    assert lines[1].startswith("/elsewhere/lib.py:7: UserWarning: a library speaks"), quiet.stderr
    verbose = subprocess.run([sys.executable, "-c", code, "verbose"], capture_output=True, text=True, timeout=300)
    assert "terrain.py:191: UserWarning: no flat 1.0 m spawn patch" in verbose.stderr, verbose.stderr


def test_an_os_error_is_one_line_naming_its_path(capsys, tmp_path):
    """A folder that is a file, or one that may not be written, from wherever in a command it comes."""
    from legged_gente.utils.args import run_command

    def fail(args):
        raise NotADirectoryError(20, "Not a directory", str(tmp_path / "a.png" / "sub"))

    with pytest.raises(SystemExit) as exit_info:
        run_command("gente-x", fail, parse_args(build_parser("t"), ["--device", "cpu"]))
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and "Traceback" not in err
    assert err.strip() == f"gente-x: error: {tmp_path / 'a.png' / 'sub'}: Not a directory", err


class Started(Exception):
    """The command began its work (it should have refused its input before)."""


def never(*args, **kwargs):
    raise Started


@pytest.fixture
def blocked(tmp_path):
    """An output path under a file: no folder can be made there."""
    (tmp_path / "notimage.png").write_text("x")
    return tmp_path / "notimage.png" / "sub"


def test_evaluate_checks_its_out_folder_before_evaluating(capsys, monkeypatch, blocked):
    from legged_gente.evaluation import evaluator

    monkeypatch.setattr(evaluator, "Evaluation", never)
    line = one_line_error(capsys, evaluate_script.main, ["--baseline", "zero", "--benchmark", "flat", "--device",
                                                         "cpu", "--out", str(blocked)])
    assert line == f"gente-evaluate: error: --out {blocked}: {blocked.parent} is a file; give a folder to write to"


def test_benchmark_checks_its_csv_and_profile_before_measuring(capsys, monkeypatch, blocked):
    monkeypatch.setattr(benchmark_script, "run", never)
    for name in ("--csv", "--profile"):
        line = one_line_error(capsys, benchmark_script.main, ["--num_envs", "2", "--device", "cpu", name,
                                                              str(blocked / "x.csv")])
        assert line == f"gente-benchmark: error: {name} {blocked / 'x.csv'}: {blocked.parent} is a file; give a " \
                       f"folder to write to"


def test_train_and_play_check_the_log_root_before_building(capsys, monkeypatch, blocked):
    monkeypatch.setattr(task_registry, "make_env", never)
    monkeypatch.setenv("GENTE_LOG_ROOT", str(blocked))
    line = one_line_error(capsys, train_script.main, ["--task", "gente_biped_flat", *CPU])
    assert line == f"gente-train: error: GENTE_LOG_ROOT {blocked}: {blocked.parent} is a file; give a folder to " \
                   f"write to"
    line = one_line_error(capsys, play_script.main, ["--task", "gente_biped_flat", *CPU, "--pretrained"])
    assert line == f"gente-play: error: GENTE_LOG_ROOT {blocked}: {blocked.parent} is a file; give a folder to " \
                   f"write to"
    monkeypatch.delenv("GENTE_LOG_ROOT")
    line = one_line_error(capsys, play_script.main, ["--task", "gente_biped_flat", *CPU, "--pretrained",
                                                     "--log_root", str(blocked)])
    assert line == f"gente-play: error: --log_root {blocked}: {blocked.parent} is a file; give a folder to write to"


@pytest.mark.parametrize("override", ["actor.hidden_dims=[]", "actor.hidden_dims=[-4]", "actor.hidden_dims=[64,'a']",
                                      "critic.hidden_dims=[0]", "critic.hidden_dims=[64,2.5]"])
def test_network_sizes_are_positive_layer_widths(capsys, monkeypatch, override):
    """An empty list, a negative or zero width or a word crashed in torch, or trained a 0-wide layer."""
    _, env_cfg, train_cfg = task_registry.tasks["gente_biped_flat"]
    monkeypatch.setitem(task_registry.tasks, "gente_biped_flat", (never, env_cfg, train_cfg))
    line = one_line_error(capsys, train_script.main, ["--task", "gente_biped_flat", *CPU, "--set", override])
    section = override.split(".")[0]
    assert f"{section}.hidden_dims=" in line and "must be a non-empty list of layer widths >= 1" in line, line


def test_a_checkpoint_without_config_json_is_evaluated_with_the_sizes_of_its_weights(capsys, tmp_path):
    """A lone model.pt (no run's config.json beside it) of 8-wide layers, without observation normalisation: its
    actor's layer widths and normaliser are read off its weights, and said; a --set that agrees is fine too."""
    args = parse_args(build_parser("test"), ["--task", "gente_biped_flat", *CPU])
    env, _ = task_registry.make_env(args.task, args)
    _, train_cfg = task_registry.get_cfgs(args.task)
    train_cfg.actor.hidden_dims, train_cfg.critic.hidden_dims = [8, 6], [8]
    train_cfg.actor.obs_normalization = False
    task_registry.make_alg_runner(env, args.task, train_cfg=train_cfg, log_root=None)[0].save(
        str(tmp_path / "model_0.pt"))  # no config.json beside it
    flags = ["--task", "gente_biped_flat", "--checkpoint", str(tmp_path / "model_0.pt"), "--benchmark", "flat",
             "--robots_per_terrain", "1", "--episode_s", "0.1", "--settle_s", "0", "--device", "cpu",
             "--no_progress", "--out", str(tmp_path / "out")]
    evaluate_script.main(flags)
    assert (tmp_path / "out" / "report.json").is_file()
    assert ("no config.json beside it: the actor's settings are read off its weights: hidden_dims [8, 6], "
            "obs_normalization False") in capsys.readouterr().out
    for override in ("actor.hidden_dims=[8,6]", "actor.obs_normalization=True"):  # the weights say: no second say
        line = one_line_error(capsys, evaluate_script.main, [*flags, "--set", override])
        assert f"--set {override}: a checkpoint without config.json gets its actor's layer widths" in line, line


def test_evaluating_a_run_folder_skips_its_unreadable_newest_checkpoint_as_play_does(capsys, tmp_path):
    """A run folder's newest checkpoint cut short (a run killed while saving): the newest readable one is evaluated,
    the skip is said, and the report names the file evaluated; a checkpoint file named alone is still refused."""
    runner = small_runner("gente_biped_flat")
    run = tmp_path / "run"
    run.mkdir()
    for iteration in (3, 4):
        runner.current_learning_iteration = iteration
        runner.save(str(run / f"model_{iteration}.pt"))
    newest = run / "model_4.pt"
    newest.write_bytes(newest.read_bytes()[:1000])
    flags = ["--task", "gente_biped_flat", "--benchmark", "flat", "--robots_per_terrain", "1", "--episode_s", "0.1",
             "--settle_s", "0", "--device", "cpu", "--no_progress", "--out", str(tmp_path / "out")]
    report = evaluate_script.evaluate(evaluate_script.build_parser().parse_args([*flags, "--checkpoint", str(run)]))
    assert report["meta"]["policy_file"] == str((run / "model_3.pt").resolve())
    out = capsys.readouterr().out
    assert "model_4.pt is unreadable" in out and "skipped model_4.pt" in out
    line = one_line_error(capsys, evaluate_script.main, [*flags, "--checkpoint", str(newest)])
    assert "model_4.pt is unreadable" in line


@pytest.mark.parametrize("flags, message", [
    (["--baseline", "zero", "--set", "actor.hidden_dims=[8]"], "--set sets the network sizes of a --checkpoint"),
    (["--checkpoint", "CKPT", "--set", "terrain.num_rows=2"],
     "--set terrain.num_rows=2: gente-evaluate sets only the network sizes (actor.*, critic.*)"),
    (["--checkpoint", "CKPT", "--set", "actor.hidden_dims=[]"], "must be a non-empty list of layer widths"),
])
def test_evaluate_set_is_refused_where_it_would_do_nothing(capsys, tmp_path, monkeypatch, flags, message):
    from legged_gente.evaluation import evaluator

    monkeypatch.setattr(evaluator, "Evaluation", never)
    (tmp_path / "model_0.pt").write_text("")
    flags = [str(tmp_path / "model_0.pt") if f == "CKPT" else f for f in flags]
    line = one_line_error(capsys, evaluate_script.main, [*flags, "--benchmark", "flat", "--device", "cpu",
                                                         "--out", str(tmp_path / "out")])
    assert message in line


def test_evaluate_set_is_refused_beside_a_config_json(capsys, tmp_path, monkeypatch):
    from legged_gente.evaluation import evaluator

    monkeypatch.setattr(evaluator, "Evaluation", never)
    (tmp_path / "model_0.pt").write_text("")
    (tmp_path / "config.json").write_text("{}")
    line = one_line_error(capsys, evaluate_script.main, ["--checkpoint", str(tmp_path / "model_0.pt"), "--set",
                                                         "actor.hidden_dims=[8]", "--device", "cpu", "--out",
                                                         str(tmp_path / "out")])
    assert f"{tmp_path / 'config.json'} sets the network sizes; leave out --set" in line


@pytest.mark.parametrize("main, argv", [
    (train_script.main, ["--num_envs", "x"]),
    (play_script.main, ["--bogus"]),
    (evaluate_script.main, ["--baseline", "zero"]),
    (benchmark_script.main, ["--steps", "x"]),
    (view_script.main, ["--port", "x"]),
])
def test_a_usage_error_is_one_line_without_the_usage_block(capsys, main, argv):
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and len(err.strip().splitlines()) == 1, err
    assert err.startswith(f"gente-{main.__module__.rsplit('.', 1)[1]}: error: "), err


def test_flags_are_never_abbreviated():
    """--set in gente-evaluate was ambiguous with --settle_s; --max_it was taken for --max_iterations."""
    with pytest.raises(SystemExit):
        parse_args(build_parser("t"), ["--device", "cpu", "--max_it", "3"])
    with pytest.raises(SystemExit):
        evaluate_script.build_parser().parse_args(["--baseline", "zero", "--out", "o", "--settle", "1"])


def view_error(capsys, monkeypatch, tmp_path, argv) -> str:
    """gente-view's one-line error for ``argv``, given before its server starts."""
    import viser

    monkeypatch.setattr(viser, "ViserServer", never)
    names = {"TEXT.npz": "hello", "ROLLOUT.npz": None, "FILE": "x"}
    for name, text in names.items():
        if text is not None:
            (tmp_path / name).write_text(text)
    if "ROLLOUT.npz" in argv:
        from legged_gente.viewer.rollout import Rollout

        from test_viewer import GridCfg
        from legged_gente.terrain.terrain import Terrain

        terrain = Terrain(GridCfg, num_robots=1)
        steps = 5
        Rollout("gente_biped_flat", 0.02, np.zeros((steps, 1, 7 + 10), np.float32), np.zeros((steps, 1, 3)),
                np.zeros((steps, 1, 3)), np.zeros((steps, 1), bool), np.zeros((steps, 1), bool), [],
                np.zeros((steps, 1, 0, 3), np.float32), np.zeros((steps, 1, 0, 3), np.float32),
                terrain.height_field, terrain.origin_xy, terrain.resolution, terrain.material
                ).save(tmp_path / "ROLLOUT.npz")
    argv = [str(tmp_path / a) if a in names or a.startswith("FILE/") else a for a in argv]
    return one_line_error(capsys, view_script.main, ["--task", "gente_biped_flat", "--headless", *argv])


@pytest.mark.parametrize("argv, message", [
    (["nonexist.json"], "gente-view: error: nonexist.json: no such file or folder; pass a spec .json, a "
                        "terrain_cfg.py, a benchmark folder or a rollout .npz"),
    (["--task", "nope"], "gente-view: error: unknown task 'nope'; registered tasks: ["),
    (["--record", "r.npz"], "gente-view: error: --record writes the rollout of --play: add --play"),
    (["--traces", "TEXT.npz"], "gente-view: error: --traces replays gente-evaluate's robots on their benchmark: "
                               "give its folder, or the spec.json it evaluated, as the source (gente-view gente100 "
                               "--traces eval/traces.npz)"),
    (["--item", "x"], "gente-view: error: --item picks the item of --traces"),
    (["ROLLOUT.npz", "--step", "-5"], "gente-view: error: --step -5: the rollout has steps 0..4"),
    (["ROLLOUT.npz", "--step", "99999"], "gente-view: error: --step 99999: the rollout has steps 0..4"),
    (["--step", "3"], "gente-view: error: --step opens a rollout paused: give a rollout .npz, --traces or --play"),
    (["--seconds", "-1"], "gente-view: error: --seconds -1.0 must be >= 0"),
    (["--play", "--policy", "zero", "--robots", "0"], "gente-view: error: --robots 0 must be >= 1"),
    (["--steps", "10"], "gente-view: error: --steps sets how --play rolls out: add --play"),
    (["--robots", "2", "--policy", "zero"], "gente-view: error: --policy, --robots set how --play rolls out: add --play"),
    (["--num_envs", "8"], "gente-view: error: --num_envs sets how --play rolls out: add --play"),
    (["--load_run", "x"], "gente-view: error: --load_run sets how --play rolls out: add --play"),
    (["--checkpoint", "5"], "gente-view: error: --checkpoint sets how --play rolls out: add --play"),
    (["--play", "--policy", "zero", "--record", "FILE/r.npz"],
     "gente-view: error: --record FILE/r.npz: FILE is a file; give a folder to write to"),
    (["gente100", "--traces", "nonexist.npz"], "gente-view: error: nonexist.npz: no such file; give"),
])
def test_viewer_input_is_checked_before_the_server_starts(capsys, monkeypatch, tmp_path, argv, message):
    line = view_error(capsys, monkeypatch, tmp_path, argv)
    assert line.startswith(message.replace("FILE", str(tmp_path / "FILE"))), line


def test_a_bad_terrain_module_stops_the_viewer_before_its_server(capsys, monkeypatch, tmp_path):
    (tmp_path / "terrain_cfg.py").write_text("x = (\n")
    line = view_error(capsys, monkeypatch, tmp_path, ["--terrain", str(tmp_path / "terrain_cfg.py")])
    assert "terrain_cfg.py:1: SyntaxError" in line


@pytest.mark.parametrize("spelling", [["--device", "cuda:99"], ["--device=cuda:99"]])
def test_the_viewer_takes_the_device_given(capsys, spelling):
    """gente-view appended '--device cpu' to a command line without the word '--device', so '--device=cuda:99'
    was replaced by the CPU without a word; the CPU is its default, and a device given is the one used."""
    assert view_script.build_arg_parser().parse_args([]).device == "cpu"
    line = one_line_error(capsys, view_script.main, ["--task", "gente_biped_flat", "--headless", "--seconds", "0",
                                                    *spelling])
    assert "cuda:99" in line


def test_viewer_flags_take_both_spellings():
    parser = view_script.build_arg_parser()
    for spelling in ("--no_shadows", "--no-shadows"):
        assert parse_args(parser, ["--device", "cpu", spelling]).no_shadows
    for spelling in ("--log_root", "--log-root"):
        assert parse_args(parser, ["--device", "cpu", spelling, "x"]).log_root == "x"


@pytest.mark.parametrize("main, build", [(play_script.main, play_script.build_play_parser),
                                         (view_script.main, view_script.build_arg_parser)])
def test_training_flags_are_not_offered_where_nothing_trains(capsys, main, build):
    """gente-play and gente-view listed --max_iterations, --resume and --run_name and ignored them."""
    help_text = build().format_help()
    for name in ("--max_iterations", "--resume", "--run_name"):
        assert name not in help_text
        line = one_line_error(capsys, main, ["--task", "gente_biped_flat", *CPU, name, *(["3"] if name != "--resume" else [])])
        assert f"unrecognized arguments: {name}" in line


def test_mujoco_not_installed_says_so_not_opengl(capsys, monkeypatch):
    """Without the mujoco package the fix is to install it, not to change MUJOCO_GL (the error blamed OpenGL)."""
    from legged_gente.utils.args import import_mujoco

    monkeypatch.setitem(sys.modules, "mujoco", None)  # `import mujoco` raises ModuleNotFoundError(name="mujoco")
    monkeypatch.setenv("MUJOCO_GL", "egl")
    with pytest.raises(SystemExit) as stop:
        import_mujoco("gente-train")
    line = capsys.readouterr().err.strip()
    assert stop.value.code == 2 and len(line.splitlines()) == 1, line
    assert line.startswith("gente-train: error: MuJoCo is not installed") and "pip install" in line, line
    assert "OpenGL" not in line and "MUJOCO_GL" not in line, line


def test_gente_generate_takes_verbose_for_the_traceback(tmp_path, monkeypatch, capsys):
    """As the other gente-* commands: an error is one line, and --verbose shows its traceback before it, with the
    same exit status."""
    def fail(*args, **kwargs):
        raise ValueError("the output folder cannot be written")

    monkeypatch.setattr(generate_script, "generate_spec", fail)
    argv = ["--text", "a hill", "--out", str(tmp_path / "o")]
    assert generate_script.main(argv) == 2
    assert capsys.readouterr().err.strip() == "gente-generate: error: the output folder cannot be written"
    assert generate_script.main([*argv, "--verbose"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" in err and err.strip().endswith("gente-generate: error: the output folder cannot be written")


def test_verbose_keeps_a_usage_error_s_exit_status(capsys):
    """gente-train --task gente_bipd exits 2; with --verbose it exited 1 (the exception re-raised): the traceback
    now comes before the one line, and the status stays 2."""
    from legged_gente.scripts import train as train_script

    for extra in ([], ["--verbose"]):
        with pytest.raises(SystemExit) as stop:
            train_script.main(["--task", "gente_biped_flat", "--device", "cpu", "--set", "sim.dt=0", *extra])
        assert stop.value.code == 2
    err = capsys.readouterr().err
    assert "Traceback" in err and err.strip().splitlines()[-1].startswith("gente-train: error:")


@pytest.mark.parametrize("name", ["a/b", ".", ".."])
def test_a_run_name_that_is_not_one_folder_says_which_names_are_refused(name, capsys):
    """'..' was told to drop a '/' it did not have."""
    from legged_gente.scripts import train as train_script

    with pytest.raises(SystemExit) as stop:
        train_script.main(["--task", "gente_biped_flat", "--device", "cpu", "--run_name", name])
    assert stop.value.code == 2
    assert capsys.readouterr().err.strip().endswith("give a name without '/' that is not '.' or '..'")
