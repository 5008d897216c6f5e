"""Task registry: a name -> (env class, env cfg, train cfg); builds envs and rsl-rl runners from args."""

from __future__ import annotations

import argparse
import os
from datetime import datetime
from pathlib import Path

import torch

from legged_gente.envs.base.legged_robot_config import LeggedRobotCfg, LeggedRobotCfgPPO, rsl_rl_train_cfg
from legged_gente.envs.terrain_arg import apply_terrain_arg
from legged_gente.utils.args import apply_overrides

LOG_ROOT = Path(os.environ.get("GENTE_LOG_ROOT", Path(__file__).resolve().parents[2] / "logs"))


def apply_args(args: argparse.Namespace, env_cfg, train_cfg) -> None:
    """Override config instances with the flags that were given (None means 'keep the config's value')."""
    apply_overrides(getattr(args, "overrides", None) or [], env_cfg, train_cfg)
    if env_cfg is not None:
        if getattr(args, "num_envs", None) is not None:
            env_cfg.env.num_envs = args.num_envs
        if getattr(args, "terrain", None):
            apply_terrain_arg(args.terrain, env_cfg)
    if train_cfg is not None:
        if getattr(args, "seed", None) is not None:
            train_cfg.seed = args.seed
        for flag in ("max_iterations", "experiment_name", "run_name", "load_run", "checkpoint"):
            value = getattr(args, flag, None)
            if value is not None:
                setattr(train_cfg.runner, flag, value)
        if getattr(args, "resume", False):
            train_cfg.runner.resume = True


class TaskRegistry:
    def __init__(self) -> None:
        self.tasks: dict[str, tuple[type, type, type]] = {}

    def register(self, name: str, env_class: type, env_cfg: type[LeggedRobotCfg], train_cfg: type[LeggedRobotCfgPPO]):
        self.tasks[name] = (env_class, env_cfg, train_cfg)

    def get_cfgs(self, name: str) -> tuple[LeggedRobotCfg, LeggedRobotCfgPPO]:
        if name not in self.tasks:
            raise KeyError(f"unknown task {name!r}; registered tasks: {sorted(self.tasks)}")
        _, env_cfg, train_cfg = self.tasks[name]
        return env_cfg(), train_cfg()

    def make_env(self, name: str, args=None, env_cfg: LeggedRobotCfg | None = None):
        """The task's env with ``args`` (argparse namespace from utils.args) applied to its config."""
        default_env_cfg, train_cfg = self.get_cfgs(name)
        env_class = self.tasks[name][0]
        env_cfg = env_cfg or default_env_cfg
        if args is not None:
            apply_args(args, env_cfg, train_cfg)
        device = getattr(args, "device", None) or "cpu"
        # seed before the env draws anything (spawn yaw, commands, domain randomisation); one seed per rank
        torch.manual_seed(int(train_cfg.seed) + int(os.environ.get("RANK", "0")))
        env = env_class(env_cfg, device=device, train_cfg_steps_per_env=train_cfg.runner.num_steps_per_env)
        return env, env_cfg

    def make_alg_runner(self, env, name: str, args=None, train_cfg: LeggedRobotCfgPPO | None = None,
                        log_root: Path | str | None = LOG_ROOT):
        """An rsl-rl OnPolicyRunner for ``env``; loads a checkpoint when resuming (latest run by default)."""
        from legged_gente.utils.checkpoints import find_checkpoint
        from legged_gente.utils.distributed import GenteOnPolicyRunner

        if train_cfg is None:
            _, train_cfg = self.get_cfgs(name)
            if args is not None:
                apply_args(args, None, train_cfg)
        runner_cfg = train_cfg.runner
        experiment_root = Path(log_root) / runner_cfg.experiment_name if log_root is not None else None
        log_dir = None
        if experiment_root is not None:
            stamp = datetime.now().strftime("%Y-%m-%d_%H-%M-%S")
            log_dir = str(experiment_root / (stamp + (f"_{runner_cfg.run_name}" if runner_cfg.run_name else "")))
        runner = GenteOnPolicyRunner(env, rsl_rl_train_cfg(train_cfg), log_dir=log_dir, device=env.device)
        if runner.gpu_global_rank != 0:
            log_dir = None  # under torchrun only rank 0 writes the run folder (rsl-rl logs from rank 0 only)
        if runner_cfg.resume:
            path = find_checkpoint(experiment_root, runner_cfg.load_run, runner_cfg.checkpoint)
            print(f"Loading model from {path}")
            runner.load(str(path))
            print(runner.curriculum_message)
            # a checkpoint stores the last *finished* iteration; continue with the next one
            runner.current_learning_iteration += 1
        return runner, train_cfg, log_dir


task_registry = TaskRegistry()


def _register_builtin_tasks() -> None:
    from legged_gente.envs.base.legged_robot import LeggedRobot
    from legged_gente.envs.gente_biped.gente_biped import GenteBiped
    from legged_gente.envs.gente_biped.gente_biped_config import (
        GenteBipedCfg, GenteBipedCfgPPO, GenteBipedFlatCfg, GenteBipedFlatCfgPPO)
    from legged_gente.envs.gente_quadruped.gente_quadruped_config import (
        GenteQuadrupedCfg, GenteQuadrupedCfgPPO, GenteQuadrupedFlatCfg, GenteQuadrupedFlatCfgPPO)

    task_registry.register("gente_biped", GenteBiped, GenteBipedCfg, GenteBipedCfgPPO)
    task_registry.register("gente_biped_flat", GenteBiped, GenteBipedFlatCfg, GenteBipedFlatCfgPPO)
    task_registry.register("gente_quadruped", LeggedRobot, GenteQuadrupedCfg, GenteQuadrupedCfgPPO)
    task_registry.register("gente_quadruped_flat", LeggedRobot, GenteQuadrupedFlatCfg, GenteQuadrupedFlatCfgPPO)


_register_builtin_tasks()
