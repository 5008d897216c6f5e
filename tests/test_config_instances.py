"""A config instance is the run's own: editing its lists and dicts in place leaves the class, and so every later
config of the task, as it was."""

from legged_gente.envs.task_registry import task_registry


def test_editing_a_config_s_dict_or_list_in_place_does_not_reach_the_next_config():
    env_cfg, train_cfg = task_registry.get_cfgs("gente_biped")
    knee = next(key for key in env_cfg.control.stiffness if "knee" in key)
    before = env_cfg.control.stiffness[knee]
    env_cfg.control.stiffness[knee] = before + 1.0
    env_cfg.asset.foot_bodies.append("no_such_foot")
    train_cfg.runner.obs_groups["rnd_state"] = ["policy"]  # what rsl-rl's resolve_obs_groups may add
    fresh_env, fresh_train = task_registry.get_cfgs("gente_biped")
    assert fresh_env.control.stiffness[knee] == before
    assert "no_such_foot" not in fresh_env.asset.foot_bodies
    assert "rnd_state" not in fresh_train.runner.obs_groups
