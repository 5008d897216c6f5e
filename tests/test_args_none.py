"""--set FIELD=None: accepted where None is one of the field's documented settings, a one-line error elsewhere."""

import pytest

from legged_gente.envs.task_registry import apply_args, task_registry, validate_cfgs
from legged_gente.utils.args import apply_overrides, build_parser, parse_args


def parsed(*flags):
    return parse_args(build_parser("test"), ["--device", "cpu", *flags])


def test_none_is_set_where_it_is_a_documented_setting():
    env_cfg, train_cfg = task_registry.get_cfgs("gente_biped")
    assert env_cfg.forces.foot_water_geom_names  # the biped names its feet's water geoms
    apply_args(parsed("--set", "algorithm.desired_kl=None",  # rsl-rl: no KL target, a fixed learning rate
                      "--set", "observations.policy.height_scan.clip=None",  # ObsTerm: not clamped
                      "--set", "observations.policy.height_scan.when=None",  # ObsTerm: always
                      "--set", "observations.critic.friction=None",  # terms.obs_terms: the term dropped
                      "--set", "forces.foot_water_geom_names=None",  # ForcesConfig: the foot_geom_names
                      "--set", "forces.sole_length=0.2", "--set", "forces.sole_length=None"), env_cfg, train_cfg)
    assert train_cfg.algorithm.desired_kl is None
    assert env_cfg.observations.policy.height_scan.clip is None
    assert env_cfg.observations.policy.height_scan.when is None
    assert env_cfg.observations.critic.friction is None
    assert env_cfg.forces.foot_water_geom_names is None and env_cfg.forces.sole_length is None
    validate_cfgs(env_cfg, train_cfg)


def test_a_dropped_term_and_an_unclamped_term_reach_the_env():
    args = parsed("--task", "gente_biped_flat", "--num_envs", "1", "--set", "observations.critic.friction=None",
                  "--set", "observations.policy.base_lin_vel.clip=(-1, 1)",
                  "--set", "observations.policy.base_lin_vel.clip=None")
    env, _ = task_registry.make_env("gente_biped_flat", args)
    assert "friction" not in env.observation_names["critic"]
    assert all(clip is None for name, _, _, clip, _ in env._obs_groups["policy"] if name == "base_lin_vel")


@pytest.mark.parametrize("flag, message", [
    ("algorithm.learning_rate=None", r"algorithm.learning_rate=None: the field's value is 0.001 of type float; None "
                                     r"is not one of its settings .*algorithm.desired_kl"),
    ("terrain.num_rows=None", "None is not one of its settings"),
    ("commands.ranges.lin_vel_x=None", "None is not one of its settings"),
    # a string field: None is not the word 'None'
    ("terrain.solved_top_level=None", r"of type str; None is not one of its settings .*quote"),
    ("rewards.scales=None", "rewards.scales is a config section, not a field"),
])
def test_none_is_refused_elsewhere_in_one_line(flag, message):
    env_cfg, train_cfg = task_registry.get_cfgs("gente_biped")
    with pytest.raises(ValueError, match=message) as error:
        apply_args(parsed("--set", flag), env_cfg, train_cfg)
    assert "\n" not in str(error.value)


@pytest.mark.parametrize("flag, message", [
    # a field whose value is None took any literal: a word for a length failed deep in the force fields' build
    ("forces.sole_length=abc", r"forces.sole_length=abc: the field is None now; give a value of its type, "
                               r"float \| None"),
    ("forces.sole_width=[0.1]", r"float \| None"),
    ("forces.foot_water_geom_names=None forces.foot_water_geom_names=5", r"list\[str\] \| None"),
    ("forces.foot_water_geom_names=None forces.foot_water_geom_names=['sole',3]", r"list\[str\] \| None"),
    ("observations.policy.base_lin_vel.clip=5", r"tuple\[float, float\] \| None"),
    ("observations.policy.base_lin_vel.clip=(1,2,3)", r"tuple\[float, float\] \| None"),
    ("observations.policy.base_lin_vel.when=3", r"str \| None"),
    ("terrain.selected_terrain=[1]", r"str \| None"),
    ("observations.critic.friction=None observations.critic.friction=ObsTerm", "an observation term can only be dropped"),
])
def test_a_field_that_is_none_takes_only_values_of_its_declared_type(flag, message):
    env_cfg, train_cfg = task_registry.get_cfgs("gente_biped")
    with pytest.raises(ValueError, match=message) as error:
        apply_args(parsed(*[f for setting in flag.split() for f in ("--set", setting)]), env_cfg, train_cfg)
    assert "\n" not in str(error.value)


def test_a_field_that_is_none_takes_its_declared_type():
    env_cfg, train_cfg = task_registry.get_cfgs("gente_biped")
    apply_args(parsed("--set", "forces.sole_length=1", "--set", "observations.policy.base_lin_vel.clip=[-1, 2]",
                      "--set", "terrain.selected_terrain=stairs"), env_cfg, train_cfg)
    assert env_cfg.forces.sole_length == 1.0 and type(env_cfg.forces.sole_length) is float
    assert env_cfg.observations.policy.base_lin_vel.clip == (-1.0, 2.0)
    assert env_cfg.terrain.selected_terrain == "stairs"


def test_a_field_that_is_none_and_declares_no_type_is_refused():
    class Custom:
        class section:
            untyped = None

    with pytest.raises(ValueError, match=r"section.untyped=1: the field is None and declares no type; declare it "
                                         r"in its config class, e.g. untyped: float \| None = None"):
        apply_overrides(["section.untyped=1"], Custom(), None)


def test_a_declared_type_lets_a_field_take_each_of_its_forms():
    """An observation term's scale is a number or one per column (terms.ObsTerm): --set refused the per-column
    form of a term whose scale was a number, since it checked against the value's type only."""
    env_cfg, train_cfg = task_registry.get_cfgs("gente_biped")
    apply_args(parsed("--set", "observations.policy.base_lin_vel.scale=[1,2,3]"), env_cfg, train_cfg)
    assert env_cfg.observations.policy.base_lin_vel.scale == (1.0, 2.0, 3.0)
    apply_args(parsed("--set", "observations.policy.base_lin_vel.scale=0.5"), env_cfg, train_cfg)
    assert env_cfg.observations.policy.base_lin_vel.scale == 0.5
    with pytest.raises(ValueError, match=r"give a value of its type, float \| tuple\[float, \.\.\.\]"):
        apply_args(parsed("--set", "observations.policy.base_lin_vel.scale=['a']"), env_cfg, train_cfg)
