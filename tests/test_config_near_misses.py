"""A misspelt setting in a config subclass is a new attribute to Python, which nothing reads, while the parent's
value stays in force: it is named in a one-line warning with the setting meant. A user's own new setting, a slip or
two from none, is left alone."""

import argparse
import warnings

import pytest

from legged_gente.envs.base.base_config import near_misses, typing_slips
from legged_gente.envs.task_registry import task_registry, validate_cfgs

OPEN = ("observations",)


@pytest.mark.parametrize("a, b, slips", [
    ("kitten", "sitting", 3),  # k -> s, e -> i, + g
    ("forcse", "forces", 1),  # s and e swapped
    ("push_robot", "push_robots", 1),
    ("stifness", "stiffness", 1),
    ("", "abc", 3),
    ("swing_height_target", "base_height_target", 5),  # swin -> base: four changed, one dropped
])
def test_typing_slips_count_letters_missing_added_changed_or_swapped(a, b, slips):
    assert typing_slips(a, b) == slips == typing_slips(b, a)


@pytest.mark.parametrize("task", ["gente_biped", "gente_quadruped", "gente_biped_flat", "gente_quadruped_flat"])
def test_the_shipped_tasks_have_none(task):
    env_cfg, train_cfg = task_registry.get_cfgs(task)
    assert near_misses(type(env_cfg), "cfg", OPEN) == [] and near_misses(type(train_cfg), "train_cfg") == []


def user_cfg():
    base = type(task_registry.get_cfgs("gente_biped_flat")[0])

    class Mine(base):
        class forces(base.forces):
            paper_drag_aera = True
        class rewards(base.rewards):
            swing_height_targt = 0.12
            my_own_setting = 3.0  # read by the user's own reward
            class scales(base.rewards.scales):
                feet_air_tme = 0.0  # meant: feet_air_time, which stays 1.0
                my_term = 0.0  # the user's own term
        class forcse(base.forces):
            pass
        class domain_rand(base.domain_rand):
            push_robot = False

    return Mine


def test_a_subclass_s_slips_are_named_with_the_setting_meant():
    found = near_misses(user_cfg(), "cfg", OPEN)
    meant = {line.split(" ")[0]: line.rsplit(" ", 1)[-1] for line in found}
    assert meant == {"cfg.forces.paper_drag_aera": "cfg.forces.paper_drag_area?",
                     "cfg.rewards.swing_height_targt": "cfg.rewards.swing_height_target?",
                     "cfg.forcse": "cfg.forces?", "cfg.domain_rand.push_robot": "cfg.domain_rand.push_robots?",
                     "cfg.rewards.scales.feet_air_tme": "cfg.rewards.scales.feet_air_time?"}


def test_building_the_env_warns_once_per_slip(recwarn):
    cfg = user_cfg()()
    cfg.env.num_envs = 1
    task_registry.make_env("gente_biped_flat", env_cfg=cfg, args=argparse.Namespace(device="cpu"))
    slips = [str(w.message) for w in recwarn if "nothing reads it" in str(w.message)]
    assert len(slips) == 5 and all("\n" not in s for s in slips)


def test_a_train_config_slip_is_named_too():
    base = type(task_registry.get_cfgs("gente_biped")[1])

    class Mine(base):
        class algorithm(base.algorithm):
            lerning_rate = 1e-4

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        validate_cfgs(None, Mine())
    assert [str(w.message).rsplit(" ", 1)[-1] for w in caught] == ["train_cfg.algorithm.learning_rate?"]


def test_a_slip_set_on_a_config_instance_in_a_script_is_named_too(recwarn):
    """``cfg.domain_rand.push_robot = False`` on the instance ``get_cfgs`` returns is as silent as one in a subclass."""
    cfg, train_cfg = task_registry.get_cfgs("gente_biped_flat")
    cfg.env.num_envs = 1
    cfg.domain_rand.push_robot = False  # meant: push_robots, which stays True
    cfg.rewards.my_own_setting = 3.0  # far from every setting: the user's own
    train_cfg.algorithm.lerning_rate = 1e-4
    assert near_misses(cfg, "cfg", OPEN) == [
        "cfg.domain_rand.push_robot was set on the config instance but is not a setting of its class, so nothing "
        "reads it; did you mean cfg.domain_rand.push_robots?"]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        validate_cfgs(None, train_cfg)
    assert [str(w.message).rsplit(" ", 1)[-1] for w in caught] == ["train_cfg.algorithm.learning_rate?"]
    env, _ = task_registry.make_env("gente_biped_flat", env_cfg=cfg, args=argparse.Namespace(device="cpu"))
    slips = [str(w.message) for w in recwarn if "nothing reads it" in str(w.message)]
    assert slips == ["cfg.domain_rand.push_robot was set on the config instance but is not a setting of its class, so "
                     "nothing reads it; did you mean cfg.domain_rand.push_robots?"]
