"""A user's mistake on the command line is one line on stderr and exit status 2, never a traceback; flags take
both spellings (--num_envs, --num-envs) in every command; the CPU default of 4096 robots is called out."""

import json
from pathlib import Path

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
])
def test_nonsense_evaluation_flags(capsys, tmp_path, flags, message):
    (tmp_path / "FILE").write_text("")
    flags = [str(tmp_path / f) if f == "FILE" else f for f in flags]
    out = [] if "--out" in flags else ["--out", str(tmp_path / "out")]
    line = one_line_error(capsys, evaluate_script.main, ["--task", "gente_biped_flat", "--baseline", "zero",
                                                         "--benchmark", "flat", "--robots_per_terrain", "2",
                                                         "--device", "cpu", "--no_progress", *out, *flags])
    assert message in line


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
    ({"size_x": -5.0}, "size_x -5, size_y 20 and resolution 0.1 must be > 0 m"),
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
    assert generate_script.main(["--image", str(image), "--out", str(tmp_path / "o")]) == 1
    err = capsys.readouterr().err.strip()
    assert f"{image} could not be read as an image" in err and "BytesIO" not in err, err


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


def test_checkpoint_of_another_task(capsys, tmp_path):
    """A quadruped checkpoint played as the biped: the tasks and action counts, not torch's size mismatch."""
    args = parse_args(build_parser("test"), ["--task", "gente_quadruped_flat", *CPU])
    env, _ = task_registry.make_env(args.task, args)
    _, train_cfg = task_registry.get_cfgs(args.task)
    train_cfg.actor.hidden_dims = train_cfg.critic.hidden_dims = [8]
    runner, _, _ = task_registry.make_alg_runner(env, args.task, train_cfg=train_cfg, log_root=None)
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
