"""The command-line layer, checked by hand against what the flags and --set are documented to do: a number --set
cannot give (inf), a flag and a --set that both set one field, a --run_name that is not one folder name. Parse
and config only: no env is built (the task's env class is replaced by a stand-in that stops the command)."""

import re
from pathlib import Path

import pytest

from legged_gente.envs.task_registry import apply_args, task_registry
from legged_gente.scripts import train as train_script
from legged_gente.utils.args import build_parser, parse_args

CPU = ["--task", "gente_biped_flat", "--device", "cpu", "--num_envs", "2", "--headless"]


class Built(Exception):
    """Raised by the stand-in make_env: the command got past its checks and would build an env."""


@pytest.fixture
def no_env(monkeypatch, tmp_path):
    monkeypatch.setenv("GENTE_LOG_ROOT", str(tmp_path))

    def env_class(*args, **kwargs):
        raise Built()

    _, env_cfg, train_cfg = task_registry.tasks["gente_biped_flat"]
    monkeypatch.setitem(task_registry.tasks, "gente_biped_flat", (env_class, env_cfg, train_cfg))


def one_line_error(capsys, argv) -> str:
    with pytest.raises(SystemExit) as exit_info:
        train_script.main(argv)
    err = capsys.readouterr().err
    assert exit_info.value.code == 2, err
    assert "Traceback" not in err
    return [line for line in err.splitlines() if line.strip()][-1]


def overridden(overrides):
    """The biped's configs after ``--set`` of ``overrides`` (what apply_args makes of them)."""
    env_cfg, train_cfg = task_registry.get_cfgs("gente_biped_flat")
    args = parse_args(build_parser("test"), ["--device", "cpu", *[a for o in overrides for a in ("--set", o)]])
    apply_args(args, env_cfg, train_cfg)
    return env_cfg, train_cfg


# 1e999 is past the largest double (about 1.8e308): Python's literal reads it as inf, which no field means.
# A number that large written as an integer (400 digits) cannot be a float at all: float() of it overflows.
@pytest.mark.parametrize("override", [
    "sim.dt=1e999",
    "algorithm.learning_rate=1e999",
    "env.episode_length_s=1e999",
    "rewards.scales.tracking_lin_vel=-1e999",
    "domain_rand.friction_range=[0.5, 1e999]",
    "sim.dt=1" + "0" * 400,
    "rewards.scales.tracking_lin_vel=nan",  # words to Python's literals: a numeric field takes them as none of its
    "sim.dt=-inf",  # values, and said so only by their type
    "sim.dt=Infinity",
])
def test_set_refuses_a_number_that_is_not_finite(override):
    with pytest.raises(ValueError, match="not a finite number"):
        overridden([override])


def test_set_refusing_inf_is_one_line_before_building(capsys, no_env):
    line = one_line_error(capsys, [*CPU, "--set", "algorithm.learning_rate=1e999"])
    assert line.startswith("gente-train: error: --set algorithm.learning_rate=1e999:") and "finite" in line


def test_set_takes_large_finite_numbers_and_strings_that_look_like_inf():
    env_cfg, train_cfg = overridden(["env.episode_length_s=1e300", "runner.run_name=1e999"])
    assert env_cfg.env.episode_length_s == 1e300
    assert train_cfg.runner.run_name == "1e999"  # a string field keeps the word as written


@pytest.mark.parametrize("flags, field", [
    (["--num_envs", "2", "--set", "env.num_envs=8"], "env.num_envs"),
    (["--max_iterations", "3", "--set", "runner.max_iterations=7"], "runner.max_iterations"),
    (["--experiment_name", "a", "--set", "runner.experiment_name=b"], "runner.experiment_name"),
    (["--run_name", "a", "--set", "runner.run_name=b"], "runner.run_name"),
])
def test_a_flag_and_a_set_of_the_same_field_are_refused(capsys, no_env, flags, field):
    """Without the check the flag silently wins over the --set (apply_args applies the flags last)."""
    argv = ["--task", "gente_biped_flat", "--device", "cpu", "--headless", *flags]
    line = one_line_error(capsys, argv)
    assert field in line and "give one" in line


def test_a_set_alone_still_sets_the_field(no_env):
    env_cfg, train_cfg = overridden(["env.num_envs=8", "runner.max_iterations=7"])
    assert env_cfg.env.num_envs == 8 and train_cfg.runner.max_iterations == 7


@pytest.mark.parametrize("name", ["a/b", "../escape"])
def test_run_name_is_one_folder_name(capsys, no_env, name):
    """A run named "a/b" lands in logs/<experiment>/<date>_a/b/, where --resume (which looks for model_*.pt one
    level under logs/<experiment>/) never finds it; "../escape" puts it in logs/<experiment>/<date>_../escape/."""
    line = one_line_error(capsys, [*CPU, "--run_name", name])
    assert f"--run_name {name!r}" in line


def test_a_plain_run_name_passes_the_checks(no_env):
    with pytest.raises(Built):
        train_script.main([*CPU, "--run_name", "stairs-v2_lr3e-4"])


FLAT_SPEC = Path(__file__).resolve().parents[1] / "legged_gente" / "benchmarks" / "flat" / "specs" / "flat.json"


def with_terrain(terrain, overrides):
    env_cfg, train_cfg = task_registry.get_cfgs("gente_biped_flat")
    argv = ["--device", "cpu", "--terrain", str(terrain), *[a for o in overrides for a in ("--set", o)]]
    apply_args(parse_args(build_parser("test"), argv), env_cfg, train_cfg)
    return env_cfg


def test_set_of_a_terrain_field_reaches_a_terrain_cfg_module(tmp_path):
    """A terrain_cfg.py replaces the terrain section; a --set terrain.* given with it was silently dropped."""
    module = tmp_path / "terrain_cfg.py"
    module.write_text("from legged_gente.envs.base.legged_robot_config import LeggedRobotCfg\n\n\n"
                      "class Emitted(LeggedRobotCfg.terrain):\n    num_rows = 3\n")
    env_cfg = with_terrain(module, ["terrain.solved_top_level=stay", "terrain.num_cols=2"])
    assert env_cfg.terrain.num_rows == 3  # the module's own value
    assert env_cfg.terrain.solved_top_level == "stay" and env_cfg.terrain.num_cols == 2  # the --set on top


@pytest.mark.parametrize("terrain, override, field", [
    ("plane", "terrain.mesh_type=heightfield", "terrain.mesh_type"),  # --terrain plane sets mesh_type "plane"
    (FLAT_SPEC, "terrain.num_rows=4", "terrain.num_rows"),  # a spec is one tile: num_rows = num_cols = 1
    (FLAT_SPEC, "terrain.resolution=0.05", "terrain.resolution"),  # the spec's cell is 0.1 m
])
def test_a_set_that_terrain_overrides_is_refused(terrain, override, field):
    with pytest.raises(ValueError, match=f"--terrain .* sets {field} .*leave out --set {override}"):
        with_terrain(terrain, [override])


def test_a_set_terrain_agrees_with_is_taken():
    env_cfg = with_terrain(FLAT_SPEC, ["terrain.resolution=0.1", "terrain.solved_top_level=stay"])
    assert env_cfg.terrain.resolution == 0.1 and env_cfg.terrain.solved_top_level == "stay"
    assert env_cfg.terrain.terrain_length == 20.0  # the spec's size_x, m


@pytest.mark.parametrize("flags, field", [
    (["--experiment_name", "../../escape"], "experiment_name"),
    (["--experiment_name", ""], "experiment_name"),
    (["--experiment_name", ".."], "experiment_name"),
    (["--set", "runner.run_name=x/../../y"], "run_name"),
    (["--set", "runner.experiment_name=a/b"], "experiment_name"),
])
def test_run_folder_names_are_one_folder_each(capsys, no_env, flags, field):
    """--experiment_name ../../escape logged a run two folders above the log root, an empty one made the log root
    itself the experiment (and --resume then took a run from it), and --set runner.run_name=x/../../y passed the
    --run_name flag's check; each is now refused before anything is built or written."""
    line = one_line_error(capsys, [*CPU, *flags])
    assert line.startswith(f"gente-train: error: runner.{field}=") and "give a name without '/'" in line


@pytest.mark.parametrize("override, listed", [
    ("foo.bar=1", "its sections: actor, algorithm, asset, commands"),
    ("terrain.foo.bar=1", "terrain has fields only: --set terrain.FIELD=..."),
])
def test_set_of_an_unknown_section_lists_the_sections(override, listed):
    with pytest.raises(ValueError, match=re.escape(listed)):
        overridden([override])


@pytest.mark.parametrize("argv, whose", [
    (["--num_envs", "100"], "100 robots on the CPU (no GPU in use): that many are sized for a GPU"),
    ([], "4096 robots on the CPU (no GPU in use): the task's default is sized for a GPU"),
])
def test_the_slow_cpu_notice_says_whose_count_it_is(capsys, no_env, argv, whose):
    """--num_envs 100 on the CPU was called 'the task's default'."""
    with pytest.raises(Built):
        train_script.main(["--task", "gente_biped_flat", "--device", "cpu", *argv])
    assert whose in capsys.readouterr().out


def test_a_checkpoint_file_given_to_checkpoint_or_load_run_is_answered_with_the_two_flags(capsys, tmp_path):
    """--checkpoint is an iteration in train, play and view (a file in gente-evaluate): a model_9.pt path given to
    it, or to --load_run, says which two flags load that file."""
    run = tmp_path / "myrun"
    run.mkdir()
    (run / "model_9.pt").write_bytes(b"")
    line = one_line_error(capsys, [*CPU, "--resume", "--checkpoint", str(run / "model_9.pt")])
    assert f"for this file give --load_run {run} --checkpoint 9" in line
    from legged_gente.utils.checkpoints import find_checkpoint

    with pytest.raises(FileNotFoundError, match=re.escape(f"--load_run {run} --checkpoint 9")):
        find_checkpoint(tmp_path / "logs", str(run / "model_9.pt"), None)
