"""task_registry.register checks what it is given (a user's own task module calls it), and an unknown task's error
says how a task kept outside the package gets registered."""

import pytest

from legged_gente.envs.base.legged_robot import LeggedRobot
from legged_gente.envs.gente_biped.gente_biped_config import (
    GenteBipedCfg, GenteBipedCfgPPO, GenteBipedFlatCfg, GenteBipedFlatCfgPPO)
from legged_gente.envs.task_registry import TaskRegistry, task_registry


@pytest.mark.parametrize("env_class, env_cfg, train_cfg, message", [
    (LeggedRobot, GenteBipedFlatCfg(), GenteBipedFlatCfgPPO,
     r"register\('x', \.\.\.\): env_cfg must be a class derived from LeggedRobotCfg, got an instance of GenteBipedFlatCfg"),
    (LeggedRobot, GenteBipedFlatCfgPPO, GenteBipedFlatCfg,
     r"env_cfg must be a class derived from LeggedRobotCfg, got GenteBipedFlatCfgPPO"),
    (LeggedRobot, GenteBipedFlatCfg, GenteBipedFlatCfg,
     r"train_cfg must be a class derived from LeggedRobotCfgPPO, got GenteBipedFlatCfg"),
    (GenteBipedFlatCfg, GenteBipedFlatCfg, GenteBipedFlatCfgPPO,
     r"env_class must be LeggedRobot or a class derived from it, got GenteBipedFlatCfg"),
])
def test_register_refuses_what_is_not_a_task(env_class, env_cfg, train_cfg, message):
    with pytest.raises(TypeError, match=message):
        TaskRegistry().register("x", env_class, env_cfg, train_cfg)


def test_a_task_name_is_taken_once():
    registry = TaskRegistry()
    registry.register("x", LeggedRobot, GenteBipedFlatCfg, GenteBipedFlatCfgPPO)
    registry.register("x", LeggedRobot, GenteBipedFlatCfg, GenteBipedFlatCfgPPO)  # the same again: a module imported twice
    with pytest.raises(ValueError, match=r"task 'x' is already registered \(LeggedRobot, GenteBipedFlatCfg, "
                                         r"GenteBipedFlatCfgPPO\); register GenteBipedCfg under another name"):
        registry.register("x", LeggedRobot, GenteBipedCfg, GenteBipedCfgPPO)
    with pytest.raises(ValueError, match="task 'gente_biped' is already registered"):
        task_registry.register("gente_biped", LeggedRobot, GenteBipedFlatCfg, GenteBipedFlatCfgPPO)


def test_an_unknown_task_says_how_an_outside_task_is_registered():
    with pytest.raises(KeyError, match=r"unknown task 'my_robot'; registered tasks: \[.*'gente_biped'.*\]; a task "
                                       r"kept outside the package is registered by its own module: run the command "
                                       r"from a script that imports it \(docs/new_robot.md\)"):
        task_registry.get_cfgs("my_robot")


def test_a_rollout_of_a_task_not_registered_here_says_how_to_replay_it():
    """The rollout file fixes its task: listing the registered tasks to pick from cannot help."""
    from legged_gente.viewer.rollout import robot_model

    with pytest.raises(ValueError, match=r"the rollout is of task 'my_robot', not registered here .*replay it from a "
                                         r"script that imports it \(docs/new_robot.md\)"):
        robot_model("my_robot")
