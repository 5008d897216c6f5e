"""gente-view: terrains and rollouts in the browser (viser).

    gente-view terrains/beach/spec.json                  # a generated spec (or its terrain_cfg.py)
    gente-view --task gente_biped                        # the task's curriculum grid
    gente-view gente100                                # a benchmark folder: one item at a time
    gente-view --task gente_biped --play --num_envs 4    # play the latest checkpoint live on the CPU
    gente-view --task gente_biped --play --pretrained    # play the policy shipped with the package
    gente-view rollout.npz                               # replay a recorded rollout
    gente-view gente100 --traces eval/traces.npz --item text_00_sandy_beach_where_gentle

Open the printed address in a browser. ``--headless`` only serves (no browser is opened).
"""

from __future__ import annotations

import signal
import sys
import threading
import time
import traceback
import webbrowser
from pathlib import Path

import numpy as np

from legged_gente.utils.args import (
    DEFAULT_TASK, USER_ERRORS, build_parser, check_output, error_text, flag, import_mujoco, one_line, parse_args)
from legged_gente.utils.signals import take_back

import_mujoco("gente-view")  # before the imports below load it (a MUJOCO_GL it cannot use: one line)

from legged_gente.envs.task_registry import apply_args, log_root_of

DEFAULT_ROBOTS = 4
"""Robots drawn by ``--play`` when ``--robots`` is not given (fewer if ``--num_envs`` is smaller)."""
DEFAULT_STEPS = 500
"""Policy steps of ``--play`` when ``--steps`` is not given."""
TRACE_KEYS = ("ids", "dt", "qpos", "cmd", "vel", "active")
"""What ``--traces`` replays from gente-evaluate's traces.npz."""


def build_arg_parser():
    p = build_parser("See terrains and rollouts in the browser.", prog="gente-view", training=False,
                     headless="only serve: open no browser", device="cpu")  # the viewer's robots are few
    p.add_argument("source", nargs="?", help="spec.json, terrain_cfg.py, benchmark folder or rollout .npz "
                                             "(default: the task's terrain grid)")
    p.add_argument("--port", type=int, default=8080, help="port of the web page (default 8080)")
    p.add_argument("--host", default="127.0.0.1", help="address to serve on (0.0.0.0: every interface)")
    p.add_argument(*flag("--no_shadows"), action="store_true", help="no shadows (faster in software WebGL)")
    p.add_argument("--seconds", type=float, default=None, help="stop serving after this many seconds")
    p.add_argument("--play", action="store_true", help="roll the task's policy out live (CPU by default)")
    p.add_argument("--policy", choices=("checkpoint", "zero"), default=None,
                   help="--play: the run's checkpoint (--load_run/--checkpoint, default the latest) or zero actions")
    p.add_argument("--pretrained", action="store_true",
                   help="--play: the policy shipped with the package for --task (resources/policies/<task>/)")
    p.add_argument("--steps", type=int, default=None, help=f"--play: policy steps (default {DEFAULT_STEPS})")
    p.add_argument("--robots", type=int, default=None,
                   help=f"--play: robots drawn and recorded (default {DEFAULT_ROBOTS}, at most --num_envs)")
    p.add_argument("--record", help="--play: also write the rollout to this .npz")
    p.add_argument("--traces", help="gente-evaluate's traces.npz (with the benchmark folder as source)")
    p.add_argument("--item", help="--traces: the item id to replay (default: the first)")
    p.add_argument("--step", type=int, help="open the rollout paused at this policy step")
    p.add_argument(*flag("--log_root"), default=None, help="where runs are (default: $GENTE_LOG_ROOT, else ./logs)")
    p.set_defaults(task=None)  # given or not: a rollout .npz names its own (main); else DEFAULT_TASK
    return p


def _task_terrain(args, terrain_arg=None):
    """Builder of the task's terrain, with ``terrain_arg`` (a spec or terrain_cfg.py) applied if given, as
    ``--terrain`` is: the --set terrain.* on top of a terrain_cfg.py, refused where a spec sets the field."""
    from legged_gente.envs.task_registry import apply_terrain_with_overrides, task_registry
    from legged_gente.terrain.terrain import Terrain

    def build():
        env_cfg, _ = task_registry.get_cfgs(args.task)
        apply_args(args, env_cfg, None)
        if terrain_arg:
            apply_terrain_with_overrides(str(terrain_arg), env_cfg, args.overrides, given_as="the source")
        return Terrain(env_cfg.terrain, num_robots=1)

    return build


def _benchmark_items(root: Path, args):
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import grid_shape
    from legged_gente.viewer.server import TerrainItem

    items = load_benchmark(root)
    specs = {i.id: i for i in items}
    if args.traces is None:
        return [TerrainItem(i.id, _task_terrain(args, i.spec_path)) for i in items], None
    from legged_gente.utils.tables import open_npz

    with open_npz(args.traces) as f:
        if "version" in f.files:
            raise ValueError(f"{args.traces} is a rollout recorded by gente-view, not gente-evaluate's traces; open "
                             f"it as the source: gente-view {args.traces}")
        if "qpos" not in f.files:
            raise ValueError(f"{args.traces} has no qpos (written by an older gente-evaluate); evaluate again to "
                             f"replay the robots.")
        missing = [key for key in TRACE_KEYS if key not in f.files]
        if missing:
            raise ValueError(f"{args.traces} has no {', '.join(missing)}: it is not a traces.npz of gente-evaluate; "
                             f"give the one it wrote for this benchmark.")
        ids = [str(i) for i in f["ids"]]
        item = args.item or ids[0]
        if item not in ids:
            raise ValueError(f"--item {item!r} is not in {args.traces}; it has {ids[:5]}...")
        k = ids.index(item)
        trace = {key: f[key][k] for key in ("qpos", "cmd", "vel", "active")} | {"dt": float(f["dt"])}
        if "fell" in f.files:  # traces.npz of an older gente-evaluate do not say why an episode ended
            trace["fell"] = f["fell"][k]
    if item not in specs:
        raise ValueError(f"{args.traces} item {item!r} is not in the benchmark {root}; pass the folder it was "
                         f"evaluated on.")
    size_x, size_y = specs[item].spec().size_x, specs[item].spec().size_y
    _, cols = grid_shape(len(ids))
    offset = ((k // cols) * size_x, (k % cols) * size_y)  # the tile the evaluation put the item on
    return [TerrainItem(item, _task_terrain(args, specs[item].spec_path), offset)], trace


def _trace_rollout(trace: dict, task: str, terrain):
    """One robot of gente-evaluate's traces as a Rollout (no force arrows: evaluation does not keep them)."""
    from legged_gente.viewer.rollout import Rollout

    active = trace["active"].astype(bool)
    fell_at_all = bool(trace.get("fell", False))
    # the robot's first episode; a fall to the step that ended it, whose pose the evaluator keeps (the fall's)
    steps = min(max(int(active.sum()), 1) + int(fell_at_all), len(active))
    ended = np.zeros((steps, 1), bool)
    ended[-1] = int(active.sum()) < len(active)  # a fall, or its tile's edge (the measured episode ends there too)
    fell = ended & fell_at_all
    return Rollout(task, trace["dt"], trace["qpos"][:steps, None], trace["cmd"][:steps, None],
                   trace["vel"][:steps, None], ended, fell, [], np.zeros((steps, 1, 0, 3), np.float32),
                   np.zeros((steps, 1, 0, 3), np.float32), terrain.height_field, terrain.origin_xy,
                   terrain.resolution, terrain.material)


def _make_play(args):
    """The env, the policy and a recorder for ``--play`` (gente-play's settings: no noise, no pushes)."""
    import torch

    from legged_gente.envs.task_registry import task_registry
    from legged_gente.viewer.rollout import Recorder

    robots = args.robots or min(DEFAULT_ROBOTS, args.num_envs or DEFAULT_ROBOTS)
    env_cfg, train_cfg = task_registry.get_play_cfgs(args.task, args.num_envs or robots)
    env_cfg.env.num_envs = args.num_envs or robots
    apply_args(args, env_cfg, train_cfg)
    env, _ = task_registry.make_env(args.task, args, env_cfg=env_cfg)
    if args.policy == "zero":
        policy = lambda obs: torch.zeros(env.num_envs, env.num_actions, device=env.device)  # noqa: E731
    elif args.pretrained:
        runner, checkpoint = task_registry.make_pretrained_runner(env, args.task, train_cfg)
        print(f"gente-view: playing the policy shipped for {args.task}: {checkpoint}", flush=True)
        policy = runner.get_inference_policy(device=env.device)
    else:
        train_cfg.runner.resume = True
        log_root = log_root_of(args)
        runner, _, _ = task_registry.make_alg_runner(env, args.task, args, train_cfg=train_cfg, log_root=log_root,
                                                     policy_only=True)
        policy = runner.get_inference_policy(device=env.device)
    return env, policy, Recorder(env, args.task, robots)


def _run_play(env, policy, recorder, steps: int, record: str | None, stop: threading.Event | None = None) -> None:
    """``steps`` policy steps recorded by ``recorder`` (fewer once ``stop`` is set), then the file if ``record``."""
    import torch

    obs = env.get_observations()
    with torch.inference_mode():
        for _ in range(steps):
            if stop is not None and stop.is_set():
                break
            obs, _, _, _ = env.step(policy(obs))
            recorder.add()
    if record:
        print(f"wrote {recorder.rollout().save(record)}", flush=True)  # from the play thread: in order when piped


def main(argv=None) -> None:
    parser = build_arg_parser()
    args = parse_args(parser, sys.argv[1:] if argv is None else argv)
    from legged_gente.viewer.rollout import Rollout, robot_model
    from legged_gente.viewer.scene import BareTerrain, plane_terrain
    from legged_gente.viewer.server import TerrainItem, Viewer

    from legged_gente.evaluation.benchmark import benchmark_root

    source = Path(args.source) if args.source else None
    if source is not None and not source.suffix:
        source = benchmark_root(source)  # a folder, or a shipped benchmark by name (gente100)
    if args.pretrained and not args.play:
        parser.error("--pretrained plays the shipped policy: add --play")
    if args.pretrained and (args.policy == "zero" or args.load_run or args.checkpoint is not None):
        parser.error("--pretrained plays the shipped policy; leave out --policy zero, --load_run and --checkpoint")
    check_flags(parser, args, source)
    given_task, args.task = args.task, args.task or DEFAULT_TASK  # a rollout .npz names its own
    play_steps = args.steps or DEFAULT_STEPS
    rollout, mjm, play, stop_play = None, None, None, threading.Event()
    try:
        if args.pretrained:
            from legged_gente.envs.task_registry import task_registry

            task_registry.shipped_policy(args.task)  # a task without a shipped policy: say so before building anything
        if args.play:
            if args.record:
                check_output(args.record, "--record", folder=False)
            env, policy, recorder = _make_play(args)
            items = [TerrainItem(f"{args.task} (play)", lambda: env.terrain or plane_terrain())]
            rollout, mjm = recorder, env.mjm
            play = threading.Thread(target=_run_play, args=(env, policy, recorder, play_steps, args.record, stop_play),
                                    daemon=True)
        elif source is None:
            items = [TerrainItem(args.task, _task_terrain(args))]
        elif source.is_dir() or args.traces:  # a benchmark folder, or the one spec.json an evaluation scored
            items, trace = _benchmark_items(source, args)
            if trace is not None:
                terrain = items[0].build()
                items[0].build = lambda: terrain
                rollout, mjm = _trace_rollout(trace, args.task, terrain), robot_model(args.task)
                if rollout.qpos.shape[-1] != mjm.nq:  # traces.npz does not name its task
                    raise ValueError(f"{args.traces} holds robots of {rollout.qpos.shape[-1]} qpos values, the "
                                     f"--task {args.task} robot {mjm.nq}; pass the --task it was evaluated with.")
        elif source.suffix.lower() == ".npz":
            rollout = Rollout.load(source)
            if given_task not in (None, rollout.task):
                raise ValueError(f"--task {given_task}: the rollout {source} was recorded with task {rollout.task}, "
                                 f"whose robot it replays; leave out --task")
            items = [TerrainItem(source.stem, lambda: BareTerrain(rollout.heights, rollout.material,
                                                                  rollout.resolution, rollout.origin))]
            mjm = robot_model(rollout.task)
            if rollout.qpos.shape[-1] != mjm.nq:
                raise ValueError(f"{source} holds robots of {rollout.qpos.shape[-1]} qpos values, the robot of its "
                                 f"task {rollout.task} {mjm.nq}: it was recorded with another robot model; record it "
                                 f"again.")
        elif source.suffix.lower() in (".json", ".py"):
            items = [TerrainItem(source.parent.name or source.stem,
                                 _task_terrain(args, source))]
        else:
            parser.error(f"{source}: pass a spec .json, a terrain_cfg.py, a benchmark folder or a rollout .npz")
        if args.step is not None:
            steps = play_steps if play is not None else len(rollout.qpos)
            if not 0 <= args.step < steps:
                raise ValueError(f"--step {args.step}: the rollout has steps 0..{steps - 1}")
        viewer = Viewer(items, host=args.host, port=args.port, shadows=not args.no_shadows)
    except USER_ERRORS as error:
        if args.verbose:
            traceback.print_exc()
        parser.exit(2, f"gente-view: error: {one_line(error_text(error))}\n")
    if rollout is not None:
        player = viewer.attach_rollout(rollout, mjm, play=args.step is None)
        if args.step is not None:
            player.step_gui.value = args.step
            player.draw(args.step)
            player.focus(args.step)
        elif isinstance(rollout, Rollout):
            player.focus(0)
    if play is not None:
        play.start()
    print(f"gente-view: serving {viewer.url}  (Ctrl-C stops)", flush=True)
    if not args.headless:
        webbrowser.open(viewer.url)
    deadline = None if args.seconds is None else time.monotonic() + args.seconds
    try:
        while deadline is None or time.monotonic() < deadline:
            time.sleep(0.2)
            take_back((signal.SIGINT,))  # from Triton, if the play thread's step is compiled (sim.torch_compile)
    except KeyboardInterrupt:
        pass
    if play is not None:
        if args.record:
            if play.is_alive():  # else it has finished, and said so
                print("gente-view: finishing the rollout to record it", flush=True)
        else:
            stop_play.set()  # only watched: the policy stops with the viewer
        play.join()
    viewer.stop()


def check_flags(parser, args, source: Path | None) -> None:
    """The flags that need another flag or a source of a kind, and the ranges: refused before anything is built."""
    if source is not None and not source.exists():
        parser.error(f"{args.source}: no such file or folder; pass a spec .json, a terrain_cfg.py, a benchmark "
                     f"folder or a rollout .npz")
    if args.play and source is not None:
        parser.error("--play rolls out on the task's terrain: give --terrain, not a source file")
    if args.terrain and source is not None:
        parser.error(f"--terrain {args.terrain} and the source {args.source} both give the terrain; give one (a "
                     f"rollout .npz brings its own)")
    if args.overrides and source is not None and source.suffix.lower() == ".npz":
        parser.error(f"--set {args.overrides[0]}: the rollout {args.source} is replayed as recorded; leave out --set")
    if args.record and not args.play:
        parser.error("--record writes the rollout of --play: add --play")
    if args.record and not args.record.endswith(".npz"):  # numpy would add it, and a rollout is opened by it
        parser.error(f"--record {args.record}: name the rollout file *.npz (gente-view opens rollouts by that suffix)")
    play_only = [name for name, value in (("--policy", args.policy), ("--robots", args.robots),
                                          ("--num_envs", args.num_envs), ("--steps", args.steps),
                                          ("--load_run", args.load_run), ("--checkpoint", args.checkpoint))
                 if value is not None]
    if play_only and not args.play:
        parser.error(f"{', '.join(play_only)} set{'s' if len(play_only) == 1 else ''} how --play rolls out: add --play")
    if args.traces and (source is None or not (source.is_dir() or source.suffix.lower() == ".json")):
        parser.error("--traces replays gente-evaluate's robots on their benchmark: give its folder, or the spec.json "
                     "it evaluated, as the source (gente-view gente100 --traces eval/traces.npz)")
    if args.item and not args.traces:
        parser.error("--item picks the item of --traces to replay: add --traces")
    replay = source is not None and source.suffix.lower() == ".npz"
    if args.step is not None and not (args.play or args.traces or replay):
        parser.error("--step opens a rollout paused: give a rollout .npz, --traces or --play")
    if args.seconds is not None and not args.seconds >= 0:  # NaN too
        parser.error(f"--seconds {args.seconds} must be >= 0")
    if args.robots is not None and args.robots < 1:
        parser.error(f"--robots {args.robots} must be >= 1")
    if args.robots is not None and args.num_envs is not None and args.robots > args.num_envs:
        parser.error(f"--robots {args.robots} exceeds --num_envs {args.num_envs}: only simulated worlds can be "
                     f"drawn; raise --num_envs or lower --robots")


if __name__ == "__main__":
    main()
