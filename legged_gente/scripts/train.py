"""Train a registered task with rsl-rl PPO:  python legged_gente/scripts/train.py --task=gente_biped"""

from __future__ import annotations

import json
from pathlib import Path

from legged_gente.envs.base.base_config import class_to_dict
from legged_gente.envs.task_registry import task_registry
from legged_gente.utils.args import build_parser, parse_args


def train(args) -> Path | None:
    env, env_cfg = task_registry.make_env(args.task, args)
    runner, train_cfg, log_dir = task_registry.make_alg_runner(env, args.task, args)
    if log_dir is not None:
        Path(log_dir).mkdir(parents=True, exist_ok=True)
        (Path(log_dir) / "config.json").write_text(json.dumps(
            {"task": args.task, "env": class_to_dict(env_cfg), "train": class_to_dict(train_cfg)}, indent=1,
            default=str))
        print(f"Logging to {log_dir}")
    try:
        runner.learn(train_cfg.runner.max_iterations, init_at_random_ep_len=True)
    except KeyboardInterrupt:  # Ctrl-C (or `timeout -s INT`): keep what was learned
        if log_dir is not None:
            path = Path(log_dir) / f"model_{runner.current_learning_iteration}.pt"
            runner.save(str(path))
            print(f"\nInterrupted: saved {path}; continue with --resume")
    return Path(log_dir) if log_dir else None


def main(argv=None) -> None:
    train(parse_args(build_parser("Train a legged robot with PPO (rsl-rl) on MuJoCo-Warp."), argv))


if __name__ == "__main__":
    main()
