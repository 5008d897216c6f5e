"""Train a registered task with rsl-rl PPO:  python legged_gente/scripts/train.py --task=gente_biped"""

from __future__ import annotations

import dataclasses
import json
import os
import signal
import sys
import threading
import time
import warnings
from pathlib import Path

from legged_gente.utils.args import (
    build_parser, check_log_root, flag, import_mujoco, override_of, parse_args, run_command)

import_mujoco("gente-train")  # before the imports below load it (a MUJOCO_GL it cannot use: one line)

from legged_gente.envs.base.base_config import class_to_dict
from legged_gente.envs.task_registry import (
    apply_args, check_run_folder_names, is_one_folder_name, log_root_of, task_registry)
from legged_gente.terrain.soil import SOIL_PRESETS
from legged_gente.utils.episode_logger import StopRequested, TimeLimitReached
from legged_gente.utils.provenance import code_version, command_line, platform_record


def resolved_terrain(env) -> dict:
    """What the robots actually walk on: the tile grid's terrain names, for generated terrains the specs themselves
    (a spec file may change after the run), and the parameters of every soil on it (a custom soil is registered
    by the user's code, which may change after the run too)."""
    terrain = env.terrain
    if terrain is None:
        return {"mode": "plane"}
    specs = {}
    for path in getattr(env.cfg.terrain, "generated_specs", None) or []:
        try:
            specs[str(path)] = json.loads(Path(path).read_text())
        except (OSError, ValueError):
            specs[str(path)] = None
    soils = {name: dataclasses.asdict(SOIL_PRESETS[name]) for name in terrain.material.soil_presets}
    return {"mode": terrain.mode, "tile_size_m": list(terrain.tile_size), "resolution_m": terrain.resolution,
            "tiles": terrain.tile_names.tolist(), "generated_specs": specs, "soils": soils}


TERRAIN_KEYS = ("mode", "tile_size_m", "resolution_m", "tiles", "generated_specs")
"""What says which terrain a run's robots got (``resolved_terrain``; its soils are said by the tiles)."""


def terrain_change(before: dict | None, now: dict) -> str | None:
    """How the terrain ``now`` differs from a resumed run's (its config.json's ``terrain``), or None: a --resume
    builds the terrain of its own flags, not the resumed run's."""
    if not before:
        return None
    changed = [key for key in TERRAIN_KEYS if key in before and before.get(key) != now.get(key)]
    if not changed:
        return None
    then, here = (f"{r.get('mode')} ({len(r.get('tiles') or [])} rows of tiles)" for r in (before, now))
    return (f"--resume: the resumed run trained on {then} terrain; this run builds {here}, its {', '.join(changed)} "
            f"other than the resumed run's (a --terrain or --set is not carried over): give the same ones to continue "
            f"on its terrain")


def run_record(task: str, env, env_cfg, train_cfg, resumed_from: Path | None = None) -> dict:
    """config.json of a run: enough to reproduce it. ``world_size``: the processes of a torchrun launch (each with
    ``env.num_envs`` robots and its own seed, ``seed + rank``); ``resumed_from``: the checkpoint a --resume loaded."""
    return {"task": task, "command": command_line(), "world_size": int(os.environ.get("WORLD_SIZE", "1")),
            "resumed_from": str(resumed_from) if resumed_from is not None else None, "code": code_version(),
            "platform": platform_record(env.device), "terrain": resolved_terrain(env), "env": class_to_dict(env_cfg),
            "train": class_to_dict(train_cfg)}


class Terminated(KeyboardInterrupt):
    """A second SIGTERM: stop at once like a second Ctrl-C, keeping the last finished iteration."""


def _stop_after_the_iteration(logger):
    """A handler for SIGINT and SIGTERM (what `timeout` and job schedulers send): the first asks the logger to stop
    training when the running iteration has finished, so that no exception cuts through the step, the CUDA graphs
    or the update; a second stops at once."""

    def handler(signum, frame):
        if logger.stop_signal is not None:
            raise Terminated() if signum == signal.SIGTERM else KeyboardInterrupt()
        logger.stop_signal = signum
        # os.write, not print: a handler that prints while the interrupted code prints raises a reentrant-call error
        os.write(2, f"\n{signal.Signals(signum).name}: stopping when this iteration finishes (again: now)\n".encode())

    return handler


def train(args) -> Path | None:
    started = time.monotonic()  # --max_minutes counts the env's build too, as a job's time limit does
    log_root = log_root_of(args)
    check_log_root(args.log_root, log_root)
    _, named = task_registry.get_cfgs(args.task)  # the run's folder names, checked before the env is built
    apply_args(args, None, named)
    check_run_folder_names(named.runner)
    env, env_cfg = task_registry.make_env(args.task, args)
    runner, train_cfg, log_dir = task_registry.make_alg_runner(env, args.task, args, log_root=log_root)
    if train_cfg.runner.resume:
        resumed = Path(runner.loaded_checkpoint).parent / "config.json"
        try:
            before = json.loads(resumed.read_text()).get("terrain")
        except (OSError, ValueError, AttributeError):
            before = None  # a run folder without its config.json: nothing to compare
        change = terrain_change(before, resolved_terrain(env))
        if change:
            warnings.warn(change, stacklevel=1)
    if log_dir is not None:
        Path(log_dir).parent.mkdir(parents=True, exist_ok=True)
        try:  # exclusive: a run that took this name since make_alg_runner chose it is never written into
            Path(log_dir).mkdir()
        except FileExistsError:
            raise ValueError(f"run folder {log_dir} was created by another run starting at the same moment; start this "
                             f"one again, or give it a --run_name") from None
        resumed_from = Path(runner.loaded_checkpoint).resolve() if train_cfg.runner.resume else None
        record = run_record(args.task, env, env_cfg, train_cfg, resumed_from)
        (Path(log_dir) / "config.json").write_text(json.dumps(record, indent=1, default=str))
        print(f"Logging to {log_dir}")
    main_thread = threading.current_thread() is threading.main_thread()  # only it may set signal handlers
    stop_signals = (signal.SIGINT, signal.SIGTERM) if main_thread else ()
    previous = {s: signal.signal(s, _stop_after_the_iteration(runner.logger)) for s in stop_signals}
    if args.max_minutes is not None:
        runner.logger.deadline = started + 60.0 * args.max_minutes
    signalled = None
    try:
        runner.learn(train_cfg.runner.max_iterations, init_at_random_ep_len=True)
    except (KeyboardInterrupt, StopRequested, TimeLimitReached) as stop:  # Ctrl-C, SIGTERM, --max_minutes: keep
        if isinstance(stop, StopRequested):                                # what was learned
            signalled = stop.signum
        elif not isinstance(stop, TimeLimitReached):
            signalled = signal.SIGTERM if isinstance(stop, Terminated) else signal.SIGINT
        if main_thread:
            signal.signal(signal.SIGTERM, signal.SIG_IGN)  # a further SIGTERM must not cut the save short
        what = (f"Time limit of {args.max_minutes} min reached" if isinstance(stop, TimeLimitReached)
                else "Terminated (SIGTERM)" if signalled == signal.SIGTERM else "Interrupted")
        finished = runner.logger.last_iteration
        if log_dir is not None and finished is None:  # a checkpoint would claim an iteration that did not finish
            print(f"\n{what} before the first iteration finished: nothing to save", flush=True)
        elif log_dir is not None:
            runner.current_learning_iteration = finished
            path = Path(log_dir) / f"model_{finished}.pt"
            runner.save(str(path))
            print(f"\n{what}: saved {path}; continue with --resume", flush=True)
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
    if signalled is not None:  # a stopped run is no success: `gente-train ... && next` must not go on
        sys.exit(128 + signalled)
    return Path(log_dir) if log_dir else None


def build_train_parser():
    parser = build_parser("Train a legged robot with PPO (rsl-rl) on MuJoCo-Warp.", prog="gente-train")
    parser.add_argument(*flag("--max_minutes"), type=float,
                        help="stop after the iteration that passes this much wall-clock time since the env's "
                             "build began (kernel compilation included), saving a checkpoint to continue with "
                             "--resume (for time-limited jobs; no signal needed)")
    parser.add_argument(*flag("--log_root"), default=None,
                        help="where runs are written and --resume finds them (default: $GENTE_LOG_ROOT, else ./logs)")
    parser.add_argument("--pretrained", action="store_true",
                        help="start from the policy shipped for --task, or for the task it was registered with "
                             "pretrained_from (its actor; the critic, optimiser and curriculum start afresh, and the "
                             "critic trains alone for the first runner.critic_warmup_iterations, 800 by default): "
                             "fine-tune it on changed physics, terrain or rewards")
    return parser


def main(argv=None) -> None:
    parser = build_train_parser()
    args = parse_args(parser, argv)
    if args.max_minutes is not None and not args.max_minutes > 0:
        parser.error(f"--max_minutes must be > 0, got {args.max_minutes}")
    # --resume sets runner.resume after the --set (task_registry.apply_args): a --set of it too would be ignored
    resume_set = override_of(args.overrides, "runner.resume")
    resumes = args.resume or (resume_set is not None and resume_set.partition("=")[2].strip() == "True")
    picked = (args.load_run is not None or args.checkpoint is not None
              or override_of(args.overrides, "runner.load_run", "runner.checkpoint") is not None)
    if not resumes and picked:
        parser.error("--load_run/--checkpoint pick the checkpoint to resume from: add --resume (without it "
                     "training starts from scratch)")
    if args.run_name and not is_one_folder_name(args.run_name):
        parser.error(f"--run_name {args.run_name!r}: a run is one folder under logs/<experiment>/ (--resume looks "
                     f"for it there); give a name without '/' that is not '.' or '..'")
    if args.pretrained and args.resume:
        parser.error("--pretrained starts a new run from the shipped policy; --resume continues a run of your own: "
                     "pick one")
    if resume_set is not None and args.resume:
        parser.error(f"--resume and --set {resume_set} both set runner.resume; give one")
    if resume_set is not None and args.pretrained:  # a resumed run never loads the shipped policy
        parser.error(f"--pretrained starts a new run from the shipped policy; leave out --set {resume_set}")
    run_command("gente-train", train, args)


if __name__ == "__main__":
    main()
