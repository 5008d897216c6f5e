"""Where robots fail the velocity benchmark: the tallest step on the line they were told to walk.

The velocity task commands a fixed (vx, vy) in a fixed heading; success needs 70 % of the commanded distance along
that direction. For every moving robot this tool takes the commanded straight line in the world: from where the
robot stands once it has turned (``--turn_s``, 2 s) along its commanded direction (the heading command turned by
the angle of (vx, vy)), as long as the success rule asks it to walk (70 % of speed x the rest of the episode) plus
0.5 m. The line's *step* is the largest rise of the ground over ``run`` (0.3 m, about one stride of the biped)
along it. Every moving robot that did not diverge is binned by that step (a robot that fell before ``--turn_s``
from where it respawned), with its bin's success and fall rates; of the robots that stayed up and failed, the
share that had stalled (moved less than 30 % of the commanded speed over the last 3 s). The last bin, a rise of
0.7 m or more, is taller than the biped's knees (about 0.5 m above the ground) and the quadruped's hips (0.3 m):
for the robots that succeed on such a line the tool says how they passed it (the rise past the distance the rule
asks for, or the robot past the rise's distance along the line, with its largest sideways offset). A second table
bins the same robots by the line's *drop* (the largest fall of the ground over ``run``: a bank down into a channel
or a trench), a pair of lines splits them by whether the line holds a step or a drop of 0.45 m or more, and a last
table bins them by the deepest water on the line (the biped's pelvis stands about 1 m above its soles, the
quadruped's trunk 0.3 m).

    python tools/trace_failures.py --task gente_biped --pretrained --benchmark gente_original \
        --report docs/results/heading_tracking/gente_original_eval_biped_29219.csv

``--report`` picks the terrains where robots stay up and fail (fall rate < 0.2, success < 0.5 in that report);
``--items`` names them instead; without either, every item of the benchmark. The rollout is ``gente-evaluate``'s (same robots, commands and success rule for
the same item list), so run it where the items' evaluation fits (16 robots on 37 items: about 3 min on a CPU).
"""

from __future__ import annotations

import argparse
import csv
import math

import numpy as np

STEP_BINS = (0.0, 0.1, 0.2, 0.3, 0.45, 0.7, math.inf)  # m
WATER_BINS = (0.0, 0.01, 0.2, 0.4, 0.6, math.inf)  # m of water on the line: the first bin is dry
WALL = STEP_BINS[-2]  # m: the last bin's rise
REACH = STEP_BINS[-3]  # m: taller steps (up or down) than the curriculum's 0.30 m and the lone-step benchmark's reach
LINE_MARGIN = 0.5  # m: how far the line runs past the distance the success rule asks for


def commanded_direction(command: np.ndarray) -> np.ndarray:
    """(n, 2) world unit vectors of (vx, vy, yaw rate, heading) commands: (vx, vy) turned by the heading."""
    angle = np.arctan2(command[:, 1], command[:, 0]) + command[:, 3]
    return np.stack([np.cos(angle), np.sin(angle)], axis=1)


def line_step(height, start_xy: np.ndarray, direction: np.ndarray, length: float, run: float = 0.3,
              spacing: float = 0.1) -> tuple[float, float]:
    """The largest rise of ``height(x, y)`` over ``run`` metres along the line from ``start_xy`` in
    ``direction`` (a unit vector) for ``length`` metres, sampled every ``spacing`` metres, and the distance along
    the line of its top (0 m where the line does not rise)."""
    r = np.arange(0.0, length + spacing / 2, spacing)
    z = height(start_xy[0] + r * direction[0], start_xy[1] + r * direction[1])
    lag = max(1, int(round(run / spacing)))
    if len(z) <= lag:
        return 0.0, 0.0
    rise = z[lag:] - z[:-lag]
    k = int(rise.argmax())
    return (float(rise[k]), float(r[k + lag])) if rise[k] > 0.0 else (0.0, 0.0)


def water_depth(terrain):
    """``depth(x, y)``: the water's depth (m) over the ground at world points, 0 where dry: the nearest cell's
    surface, as the force kernels read it (``kernels.cell_of``), above the ground's height."""
    from legged_gente.terrain.materials import NO_WATER

    surface = terrain.material.water_surface
    nx, ny = surface.shape

    def nearest(u, n):  # halves away from zero, as wp.round
        return np.clip(np.sign(u) * np.floor(np.abs(u) + 0.5), 0, n - 1).astype(int)

    def depth(x, y):
        i = nearest((np.asarray(x) - terrain.origin_xy[0]) / terrain.resolution, nx)
        j = nearest((np.asarray(y) - terrain.origin_xy[1]) / terrain.resolution, ny)
        top = surface[i, j]
        return np.where(top > NO_WATER / 2, np.maximum(top - terrain.height_at(x, y), 0.0), 0.0)

    return depth


def line_depth(depth, start_xy: np.ndarray, direction: np.ndarray, length: float, spacing: float = 0.1) -> float:
    """The deepest water (``depth(x, y)``, m) on the line from ``start_xy`` in ``direction`` for ``length`` metres,
    sampled every ``spacing`` metres."""
    r = np.arange(0.0, length + spacing / 2, spacing)
    return float(depth(start_xy[0] + r * direction[0], start_xy[1] + r * direction[1]).max())


def print_bins(steps: np.ndarray, success: np.ndarray, fell: np.ndarray, stalled: np.ndarray,
               what: str = "step", bins: tuple = STEP_BINS) -> None:
    """Per bin of the line's step (or drop, or water, ``what``, in ``bins``): robots, success and fall rates, and
    the stalled share of those that stayed up and failed (``stalled`` is read only there)."""
    print(f"{what} on the line (m)".ljust(21) + "  robots  success     fell  up, failed: stalled")
    for lo, hi in zip(bins[:-1], bins[1:]):
        in_bin = (steps >= lo) & (steps < hi)
        up_failed = in_bin & ~success & ~fell
        label = f"[{lo:.2f}, {hi:.2f})" if math.isfinite(hi) else f">= {lo:.2f}"
        ok, down = (f"{success[in_bin].mean():.1%}", f"{fell[in_bin].mean():.1%}") if in_bin.any() else ("-", "-")
        stall = f"{stalled[up_failed].mean():.1%}" if up_failed.any() else "-"
        print(f"{label:20s} {in_bin.sum():7d}  {ok:>7s}  {down:>7s}  {stall:>19s}")


def print_walls(success: np.ndarray, beyond: np.ndarray, passed: np.ndarray, sideways: np.ndarray) -> None:
    """How the robots that succeed on a line with a wall pass it. ``success``: per robot, succeeded on such a line;
    ``beyond``: the rise's top lies past the distance the rule asks for; ``passed``: the robot got past the rise's
    distance along the line; ``sideways``: its largest distance from the line (m)."""
    n, went_past = int(success.sum()), success & passed
    offset = f", their median largest sideways offset {np.median(sideways[went_past]):.1f} m" if went_past.any() else ""
    print(f"succeed on a line rising {WALL} m or more: {n}; the rise past the asked distance: "
          f"{int((success & beyond).sum())}; past the rise's distance along the line: {int(went_past.sum())}{offset}")


def print_reach(steps: np.ndarray, drops: np.ndarray, success: np.ndarray, fell: np.ndarray) -> None:
    """Success and falls on the lines with neither a step nor a drop of ``REACH`` or more, and on the others."""
    within = (steps < REACH) & (drops < REACH)
    for label, mask in ((f"no step or drop of {REACH} m or more", within), ("a step or a drop beyond", ~within)):
        rates = f"success {success[mask].mean():.1%}, fell {fell[mask].mean():.1%}" if mask.any() else "-"
        print(f"lines with {label}: {int(mask.sum())} robots, {rates}")


def failing_terrains(report: str, max_fall_rate: float = 0.2, max_success: float = 0.5) -> list[str]:
    """The terrains of a gente-evaluate report.csv where robots stay up (fall rate below ``max_fall_rate``) and
    still fail (success below ``max_success``)."""
    names = []
    with open(report, newline="") as f:
        reader = csv.DictReader(f)
        missing = [c for c in ("row", "name", "success_rate", "fall_rate") if c not in (reader.fieldnames or [])]
        if missing:
            raise SystemExit(f"{report}: no column {', '.join(missing)}; give gente-evaluate's report.csv")
        for row in reader:
            if row["row"] == "terrain" and row["success_rate"] and row["fall_rate"]:
                if float(row["fall_rate"]) < max_fall_rate and float(row["success_rate"]) < max_success:
                    names.append(row["name"])
    if not names:
        raise SystemExit(f"{report}: no terrain with fall rate < {max_fall_rate} and success < {max_success}.")
    return names


def main() -> None:
    import torch

    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import Evaluation, load_policy
    from legged_gente.evaluation.report import MIN_PROGRESS, success as robot_success
    from legged_gente.utils.args import resolve_device, run_command

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--task", required=True)
    policy = parser.add_mutually_exclusive_group(required=True)
    policy.add_argument("--checkpoint", help="rsl-rl model_N.pt (config.json beside it) or a shipped model.pt")
    policy.add_argument("--pretrained", action="store_true", help="the policy shipped for --task")
    policy.add_argument("--baseline", choices=("zero", "random"))
    parser.add_argument("--benchmark", default="gente_original")
    which = parser.add_mutually_exclusive_group()
    which.add_argument("--report", help="gente-evaluate report.csv: its terrains with fall rate < 0.2, success < 0.5")
    which.add_argument("--items", nargs="+", help="these item ids (default, without --report: every item)")
    parser.add_argument("--robots_per_terrain", type=int, default=16)
    parser.add_argument("--episode_s", type=float, default=10.0)
    parser.add_argument("--turn_s", type=float, default=2.0, help="s after which the line starts (the turn is done)")
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--no_progress", action="store_true", help="no progress bar")
    args = parser.parse_args()
    try:
        args.device = resolve_device(args.device)  # a GPU that is not there: one line, before the env is built
    except ValueError as error:
        parser.error(str(error))
    if not 0.0 <= args.turn_s < args.episode_s - 3.0:
        raise SystemExit(f"--turn_s {args.turn_s}: give a value in [0, episode_s - 3) (episode_s {args.episode_s}).")

    def build(args):
        """The evaluation and the policy; a wrong report, benchmark, item, task or checkpoint is one line."""
        ids = failing_terrains(args.report) if args.report else args.items  # None: all
        items = load_benchmark(args.benchmark, ids)
        evaluation = Evaluation(args.task, items, args.robots_per_terrain, args.device, args.episode_s, "velocity")
        return items, evaluation, load_policy(evaluation, checkpoint=args.checkpoint, baseline=args.baseline,
                                              pretrained=args.pretrained)

    items, evaluation, act = run_command(parser.prog, build, args)
    env = evaluation.env
    if not env.heading_command:
        raise SystemExit(f"{args.task} commands a yaw rate, not a heading: its commanded path is no straight line; "
                         "this tool needs commands.heading_command = True.")
    positions = []

    def policy(obs):
        positions.append(env.base_pos[:, :2].clone())  # where each robot stands before the step
        return act(obs)

    task = evaluation.make_task()
    result = evaluation.run(policy, task, progress=not args.no_progress)
    m = result.metrics
    xy = torch.stack(positions, 1).cpu().numpy()  # (robots, steps, 2)
    command = task.commands(env.base_pos[:, :2], env.commands).cpu().numpy()
    moving = ~m["standing"]
    counted = moving & ~m["diverged"]
    success = counted & robot_success(m, "velocity")

    start = int(round(args.turn_s / evaluation.dt))
    last = int(round(3.0 / evaluation.dt))
    speed = np.linalg.norm(command[:, :2], axis=1)
    direction = commanded_direction(command)
    asked = MIN_PROGRESS * speed * (args.episode_s - args.turn_s)  # m: the distance the success rule asks for
    length = asked + LINE_MARGIN
    robots = np.flatnonzero(counted)
    lines = np.array([line_step(env.terrain.height_at, xy[i, start], direction[i], length[i]) for i in robots])
    steps, rise_at = lines[:, 0], lines[:, 1]
    path = xy[robots, start:] - xy[robots, start, None]  # (robots, steps, 2) from the line's start
    normal = np.stack([-direction[robots, 1], direction[robots, 0]], axis=1)
    along = np.einsum("ntk,nk->nt", path, direction[robots]).max(axis=1)
    sideways = np.abs(np.einsum("ntk,nk->nt", path, normal)).max(axis=1)
    moved = np.linalg.norm(xy[robots, -1] - xy[robots, -1 - last], axis=1) / (last * evaluation.dt)  # over last steps
    stalled = moved < 0.3 * speed[robots]
    fell = m["fell"][robots]
    print(f"{len(items)} terrains, {int(moving.sum())} moving robots: {int(success.sum())} succeed, "
          f"{int((moving & m['fell']).sum())} fall, {int((counted & ~m['fell'] & ~success).sum())} stay up and fail")
    print_bins(steps, success[robots], fell, stalled)
    print_walls(success[robots] & (steps >= WALL), rise_at > asked[robots], along > rise_at, sideways)
    drops = np.array([line_step(lambda x, y: -env.terrain.height_at(x, y), xy[i, start], direction[i], length[i])[0]
                      for i in robots])
    print_bins(drops, success[robots], fell, stalled, what="drop")
    print_reach(steps, drops, success[robots], fell)
    depth = water_depth(env.terrain)
    waters = np.array([line_depth(depth, xy[i, start], direction[i], length[i], spacing=env.terrain.resolution / 2)
                       for i in robots])  # half a cell apart: a line crossing a stream one cell wide samples it
    print_bins(waters, success[robots], fell, stalled, what="water", bins=WATER_BINS)


if __name__ == "__main__":
    main()
