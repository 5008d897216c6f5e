"""gente-evaluate: a policy on the benchmark's terrains -> per-terrain, per-category and overall metrics.

    gente-evaluate --task gente_biped --checkpoint logs/gente_biped/RUN/model_1500.pt \\
        --benchmark gente100 --robots_per_terrain 16 --out eval/ [--device cuda]

Writes ``report.json``, ``report.csv`` and ``traces.npz`` (the first robot of every terrain: commands,
velocities, positions, falls, waypoints) to ``--out``. See docs/evaluation.md for the metrics' definitions.
"""

from __future__ import annotations

import argparse
import math
import warnings
from pathlib import Path

import numpy as np

from legged_gente.utils.args import (
    Parser, add_verbose, apply_overrides, check_output, flag, import_mujoco, override_of, quiet_third_party,
    resolve_device, run_command, seed)

import_mujoco("gente-evaluate")  # before the imports below load it (a MUJOCO_GL it cannot use: one line)

from legged_gente.evaluation.benchmark import TILE_EDGE_MARGIN, shipped_benchmarks


def edge_margin(text: str) -> float | None:
    """--tile_edge_margin's value: metres, or 'off' (None: no margin)."""
    if text == "off":
        return None
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a distance in m; give a number such as 0.5, or 'off'")


MODE_FLAGS = {
    "velocity": ("tracking_threshold", "min_progress", "min_speed", "stand_fraction"),
    "waypoints": ("reach_distance", "speed"),
}
"""Each evaluation mode's own flags: a flag of the other mode would be ignored, so it is refused."""


def mode_settings(args) -> dict:
    """The flags of ``args.mode``, defaults (the evaluation's own) filled in; a flag of the other mode given is an
    error."""
    from legged_gente.evaluation.report import MIN_PROGRESS, TRACKING_THRESHOLD  # imported here: --help needs no torch
    from legged_gente.evaluation.tasks import MIN_SPEED, REACH_DISTANCE, STAND_FRACTION, WAYPOINT_SPEED

    defaults = {"tracking_threshold": TRACKING_THRESHOLD, "min_progress": MIN_PROGRESS, "min_speed": MIN_SPEED,
                "stand_fraction": STAND_FRACTION, "reach_distance": REACH_DISTANCE, "speed": WAYPOINT_SPEED}
    for mode, flags in MODE_FLAGS.items():
        for name in flags:
            if mode != args.mode and getattr(args, name) is not None:
                raise ValueError(f"--{name} is a flag of --mode {mode}; it does nothing with --mode {args.mode}: "
                                 f"leave it out, or add --mode {mode}.")
    given = {name: getattr(args, name) for name in MODE_FLAGS[args.mode]}
    return {name: defaults[name] if value is None else value for name, value in given.items()}


def build_parser() -> argparse.ArgumentParser:
    p = Parser(prog="gente-evaluate", description="Evaluate a locomotion policy on a terrain benchmark.")
    p.add_argument("--task", default="gente_biped", help="registered task name")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--checkpoint", help="rsl-rl checkpoint model_N.pt, a run folder (its latest checkpoint) or a "
                                          "shipped policy's model.pt; network sizes from the config.json beside it")
    src.add_argument("--exported", help="policy.onnx exported by gente-play (run with onnxruntime on the CPU)")
    src.add_argument("--pretrained", action="store_true", help="the policy shipped with the package for --task")
    src.add_argument("--baseline", choices=("zero", "random"), help="no policy: zero or random actions")
    p.add_argument("--benchmark", default="gente100", help=f"a shipped benchmark ({', '.join(shipped_benchmarks())}; gente_val is for choosing "
                                                   "between candidates), a folder with a manifest.json, or one "
                                                   "generated terrain's spec.json")
    p.add_argument("--items", nargs="+", help="only these item ids")
    p.add_argument("--limit", type=int, help="only the first N items")
    p.add_argument(*flag("--robots_per_terrain"), type=int, default=16)
    p.add_argument("--mode", choices=("velocity", "waypoints"), default="velocity", help="evaluation task")
    p.add_argument(*flag("--episode_s"), type=float, default=None,
                   help="episode length in s (default: 10 for velocity; for waypoints 1.5 times the zigzag's "
                        "length over --speed: 32.1 s at 0.6 m/s)")
    p.add_argument(*flag("--tracking_threshold"), type=float, default=None,
                   help="m/s; velocity-task success needs a mean tracking error below it (default 0.25)")
    p.add_argument(*flag("--min_progress"), type=float, default=None,
                   help="velocity-task success needs this share of the commanded distance covered along the command "
                        "(default 0.7)")
    p.add_argument(*flag("--min_speed"), type=float, default=None,
                   help="m/s; the slowest moving command of the velocity task (default 0.3)")
    p.add_argument(*flag("--stand_fraction"), type=float, default=None,
                   help="share of robots commanded to stand still, scored as the group stand_still (velocity task; "
                        "default 0.1)")
    p.add_argument(*flag("--settle_s"), type=float, default=1.0, help="s at the start not counted in the tracking error")
    p.add_argument(*flag("--reach_distance"), type=float, default=None,
                   help="m; waypoint reached within this distance, d (waypoint task; default 1.0)")
    p.add_argument("--speed", type=float, default=None,
                   help="m/s; forward command of the waypoint task (default 0.6)")
    p.add_argument(*flag("--tile_edge_margin"), type=edge_margin, default=TILE_EDGE_MARGIN,
                   help=f"m; end a robot's measured episode when its base comes this close to its tile's edge, where "
                        f"its terrain ends (default {TILE_EDGE_MARGIN}); 'off' measures on past the edge, on the next "
                        f"tile or the border")
    p.add_argument("--seed", type=seed, default=0, help="random seed, in [0, 2**32) (default 0)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--device", default=None, help="cpu | cuda | cuda:N (default: cuda if available)")
    p.add_argument(*flag("--no_progress"), action="store_true", help="no progress bar")
    p.add_argument("--set", action="append", default=[], metavar="SECTION.FIELD=VALUE", dest="overrides",
                   help="the network settings of a --checkpoint without a config.json beside it that its weights "
                        "do not give (repeatable), e.g. --set actor.activation=relu (actor.*, critic.*; the layer "
                        "widths and normaliser are read off the weights)")
    add_verbose(p)
    return p


WEIGHTS_SETTINGS = ("actor.hidden_dims", "actor.obs_normalization")
"""What a checkpoint's weights say of its actor (read off them when no config.json lies beside it)."""


def check_network_overrides(args) -> None:
    """``--set`` gives only the network sizes (actor.*, critic.*) of a --checkpoint without a config.json beside
    it (one with it takes them from there): checked on a fresh config before anything is built."""
    from legged_gente.envs.task_registry import sets_a_network, task_registry

    if not args.checkpoint:
        raise ValueError("--set sets the network sizes of a --checkpoint; leave it out with --exported, "
                         "--pretrained or --baseline.")
    checkpoint = Path(args.checkpoint)
    config = (checkpoint if checkpoint.is_dir() else checkpoint.parent) / "config.json"
    if config.is_file():
        raise ValueError(f"{config} sets the network sizes; leave out --set.")
    env_cfg, train_cfg = task_registry.get_cfgs(args.task)
    apply_overrides(args.overrides, env_cfg, train_cfg)  # the names, types and layer widths
    for text in args.overrides:
        if not sets_a_network(text):
            raise ValueError(f"--set {text}: gente-evaluate sets only the network sizes (actor.*, critic.*) of a "
                             f"--checkpoint without config.json; the evaluation's settings are its flags.")
    given = override_of(args.overrides, *WEIGHTS_SETTINGS)
    if given:
        raise ValueError(f"--set {given}: a checkpoint without config.json gets its actor's layer widths and "
                         f"observation normaliser from its weights; leave it out (--set gives the rest, e.g. "
                         f"actor.activation)")


def evaluate(args) -> dict:
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.envs.task_registry import task_registry
    from legged_gente.evaluation.evaluator import Evaluation, check_settle, episode_steps, load_policy_and_file
    from legged_gente.evaluation.report import build_report, check_success_rule, short_measure_note, write_reports
    from legged_gente.evaluation.tasks import check_task_settings, waypoint_episode_s
    from legged_gente.utils.provenance import code_version, command_line, file_sha256, platform_record

    for name, given in (("--checkpoint", args.checkpoint), ("--exported", args.exported)):
        if given and not Path(given).exists():  # before the (slow) evaluation envs are built
            raise FileNotFoundError(f"{name} {given}: no such file" + (" or run folder." if name == "--checkpoint"
                                                                          else "; give the policy.onnx gente-play wrote."))
    check_output(args.out, "--out")
    if args.overrides:
        check_network_overrides(args)
    settings = mode_settings(args)
    # the velocity task's success rule (the waypoint task's, the last waypoint reached, has no setting)
    rule = {name: settings.pop(name) for name in ("tracking_threshold", "min_progress") if name in settings}
    try:  # the task's own settings, before the (slow) evaluation envs are built, in the flags' names
        check_task_settings(**settings)
    except ValueError as error:
        raise ValueError(f"--{error}") from None
    if rule:
        check_success_rule(**rule)  # before the rollout, not after it
    items = load_benchmark(args.benchmark, args.items)
    if args.limit is not None:
        if args.limit < 1:
            raise ValueError(f"--limit must be >= 1, got {args.limit}.")
        items = items[: args.limit]
    device = resolve_device(args.device)
    episode_s = args.episode_s if args.episode_s is not None else (
        waypoint_episode_s(settings["speed"]) if args.mode == "waypoints" else 10.0)
    env_cfg, _ = task_registry.get_cfgs(args.task)
    dt = env_cfg.sim.dt * env_cfg.control.decimation
    if math.isfinite(episode_s) and episode_s > 0:  # a bad episode_s: the evaluation says so
        try:  # before the (slow) evaluation envs are built, in the flag's name
            check_settle(args.settle_s, episode_steps(episode_s, dt), dt)
        except ValueError as error:
            raise ValueError(f"--{error}") from None
    evaluation = Evaluation(args.task, items, args.robots_per_terrain, device, episode_s, args.mode, args.seed)
    apply_overrides(args.overrides, None, evaluation.train_cfg)
    policy, policy_file = load_policy_and_file(evaluation, args.checkpoint, args.exported, args.baseline,
                                               args.pretrained)
    task = evaluation.make_task(**settings, tile_edge_margin=args.tile_edge_margin)
    result = evaluation.run(policy, task, settle_s=args.settle_s, progress=not args.no_progress,
                            tile_edge_margin=args.tile_edge_margin)
    meta = {"task": args.task, "benchmark": str(args.benchmark),
            "policy": args.checkpoint or args.exported or args.baseline or "pretrained",
            "policy_file": str(policy_file) if policy_file else None,
            "robots_per_terrain": args.robots_per_terrain, "device": device, "seed": args.seed,
            "tile_edge_margin": args.tile_edge_margin, "items": [item.id for item in items],
            "terrain_digests": {item.id: item.spec().terrain_digest() for item in items},
            # what reproduces it: the policy's bytes (a later export may overwrite its path), the code, the platform
            "policy_sha256": file_sha256(policy_file) if policy_file else None, "command": command_line(),
            "code": code_version(), "platform": platform_record(device)}
    report = build_report(result, items, meta=meta, **rule)
    json_path, csv_path = write_reports(report, args.out)
    np.savez_compressed(Path(args.out) / "traces.npz", ids=np.array([i.id for i in items]), **result.traces)
    o = report["overall"]
    if o["robots"] == 0 and args.mode == "velocity":
        fix = ("lower --stand_fraction below 1" if settings["stand_fraction"] >= 1
               else "raise --robots_per_terrain")
        print(f"no robot had a moving command (all were told to stand still, --stand_fraction "
              f"{settings['stand_fraction']}); {fix} to score moving ones.")
    heading = o.get("heading_error")
    heading = f"heading error {heading:.1f} deg; " if heading is not None and math.isfinite(heading) else ""
    rate = lambda value: "-" if math.isnan(value) else f"{100 * value:.1f}%"  # noqa: E731  (nan: no robot scored)
    print(f"success {rate(o['success_rate'])} over {o['robots']} robots on {o['terrains']} terrains; "
          f"tracking error {'-' if math.isnan(o['tracking_error']) else format(o['tracking_error'], '.3f')} m/s; {heading}falls {o['falls']}; diverged {o['diverged']}; "
          f"stopped at their tile's edge {o['left_tile']}")
    for name, g in report["groups"].items():
        print(f"  {name:18s} success {rate(g['success_rate']):>6s}  ({g['terrains']} terrains)")
    note = short_measure_note(result.metrics, report["meta"]["episode_length_s"])
    if note:
        warnings.warn(note, stacklevel=1)
    print(f"wrote {json_path}, {csv_path}, {Path(args.out) / 'traces.npz'}")
    return report


def main(argv=None) -> None:
    parser = build_parser()
    args = parser.parse_args(argv)
    quiet_third_party(args.verbose)
    run_command("gente-evaluate", evaluate, args)


if __name__ == "__main__":
    main()
