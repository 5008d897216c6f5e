"""Command-line overrides: --set SECTION.FIELD=VALUE reaches the env or the train config, typed and checked."""

import pytest

from legged_gente.envs.task_registry import apply_args, task_registry
from legged_gente.utils.args import build_parser, parse_args


def parsed(*flags):
    return parse_args(build_parser("test"), ["--device", "cpu", *flags])


def test_set_overrides_env_and_train_fields_with_their_types():
    args = parsed("--set", "terrain.solved_top_level=stay", "--set", "algorithm.learning_rate=3e-4",
                  "--set", "terrain.num_rows=4", "--set", "env.episode_length_s=10",
                  "--set", "commands.ranges.lin_vel_x=[-0.5, 1.5]", "--set", "runner.save_interval=7")
    env_cfg, train_cfg = task_registry.get_cfgs("gente_biped")
    apply_args(args, env_cfg, train_cfg)
    assert env_cfg.terrain.solved_top_level == "stay"
    assert env_cfg.terrain.num_rows == 4
    assert env_cfg.env.episode_length_s == 10.0 and isinstance(env_cfg.env.episode_length_s, float)
    assert env_cfg.commands.ranges.lin_vel_x == [-0.5, 1.5]
    assert train_cfg.algorithm.learning_rate == 3e-4 and train_cfg.runner.save_interval == 7
    # the classes themselves are untouched
    fresh, _ = task_registry.get_cfgs("gente_biped")
    assert fresh.terrain.solved_top_level == "random"


@pytest.mark.parametrize("flag, message", [
    ("terrain.num_rows=many", "of type int"),
    ("terrain.num_rowz=4", "terrain has no field 'num_rowz'"),
    ("terrian.num_rows=4", "terrian is not a config section"),
    ("terrain.curriculum=1", "of type bool"),
    ("env.num_envs=1.5", "of type int"),
    ("actor.hidden_dims=[256,128", r"the field is a list; give a list literal .* e.g. actor.hidden_dims=\[512, 256\]"),
    ("terrain.terrain_types=[a,b]", "give a list literal of numbers or quoted strings"),
    # entries of another type crashed later in torch ("too many dimensions 'str'", "could not convert string")
    ("commands.ranges.lin_vel_x=['a','b']",
     r"entries are numbers \(float\), e.g. commands.ranges.lin_vel_x=\[-1.0, 1.0\]"),
    ("terrain.terrain_types=['flat', 2]", r"entries are str"),
    ("control.stiffness={'hip': 'x'}", r"values are numbers \(float\)"),
    # a section given a value, a field used as a section: what the field is and how to set it
    ("rewards.scales=3", r"rewards.scales is a config section, not a field; set one of its fields, e.g. "
                         r"--set rewards.scales.\w+=\.\.\."),
    ("control.stiffness.knee=150", r"control.stiffness is a field \(dict\), not a config section; set it whole: "
                                   r"--set control.stiffness=\{'hip': 150.0"),
    ("terrain.curriculum=true", "of type bool; give True or False"),
])
def test_set_rejects_unknown_fields_and_wrong_types(flag, message):
    env_cfg, train_cfg = task_registry.get_cfgs("gente_biped")
    with pytest.raises(ValueError, match=message):
        apply_args(parsed("--set", flag), env_cfg, train_cfg)


def test_set_without_section_or_value_is_a_usage_error(capsys):
    for flag in ("num_rows=4", "terrain.num_rows"):
        with pytest.raises(SystemExit):
            parsed("--set", flag)
        assert "SECTION.FIELD=VALUE" in capsys.readouterr().err


def test_set_reaches_the_env_built_by_the_registry():
    args = parsed("--task", "gente_biped_flat", "--num_envs", "2", "--set", "rewards.base_height_target=0.8")
    env, env_cfg = task_registry.make_env("gente_biped_flat", args)
    assert env.cfg.rewards.base_height_target == 0.8


def test_set_entries_of_a_number_list_or_dict_become_floats_as_a_number_field_does():
    env_cfg, train_cfg = task_registry.get_cfgs("gente_biped")
    apply_args(parsed("--set", "commands.ranges.lin_vel_x=[0, 1]",
                      "--set", "observations.policy.commands.scale=[2, 2, 1]",
                      "--set", "control.stiffness={'hip': 150, 'knee': 200.5, 'ankle': 80}"), env_cfg, train_cfg)
    assert env_cfg.commands.ranges.lin_vel_x == [0.0, 1.0]
    assert all(isinstance(v, float) for v in env_cfg.commands.ranges.lin_vel_x)
    assert env_cfg.observations.policy.commands.scale == (2.0, 2.0, 1.0)
    assert all(isinstance(v, float) for v in env_cfg.observations.policy.commands.scale)
    assert env_cfg.control.stiffness == {"hip": 150.0, "knee": 200.5, "ankle": 80.0}
    assert all(isinstance(v, float) for v in env_cfg.control.stiffness.values())
