"""The paper's evaluation figures (matplotlib, small PNGs).

    python -m legged_gente.evaluation.figures reward  RUN_OR_CSV [RUN_OR_CSV ...] --out reward.png
    python -m legged_gente.evaluation.figures tracking EVAL_DIR/traces.npz --out tracking.png [--ids ID ...]
    python -m legged_gente.evaluation.figures waypoints --task gente_biped --checkpoint CKPT --item ID --out wp.png
    python -m legged_gente.evaluation.figures training --run RUN_DIR [RESUMED_DIR ...] --items A B C --out succ.png

(a) mean training reward with a +-1 std band over seeds (TensorBoard run folders or CSVs with an
``iteration``/``step`` column); (b) commanded vs actual vx and vy on several terrains (from gente-evaluate's
traces.npz); (c) overhead trajectories on a grey heightmap with start, end and waypoints for several reach
distances d through one terrain; (d) success rate over training iterations on a few terrains (evaluates
several checkpoints of one run, over the folders of its --resume chunks).
"""

from __future__ import annotations

import argparse
import csv
import textwrap
from pathlib import Path

import numpy as np

from legged_gente.utils.args import Parser, add_verbose, quiet_third_party, run_command
from legged_gente.utils.tables import open_npz

DPI = 90
PROG = "python -m legged_gente.evaluation.figures"


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


# ------------------------------------------------------------------------------------- (a) reward band
def read_curve(source: str | Path, column: str = "mean_reward") -> tuple[np.ndarray, np.ndarray]:
    """(iterations, values) of one training run: a CSV (``iteration`` or ``step`` column) or a TensorBoard folder."""
    source = Path(source)
    if source.is_dir():
        from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

        acc = EventAccumulator(str(source), size_guidance={"scalars": 0})
        acc.Reload()
        tags = [t for t in acc.Tags()["scalars"] if t.split("/")[-1] == column]
        if not tags:
            raise KeyError(f"{source}: no TensorBoard scalar named */{column}; tags: {acc.Tags()['scalars'][:10]}")
        events = acc.Scalars(tags[0])
        return np.array([e.step for e in events], float), np.array([e.value for e in events], float)
    with open(source) as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise ValueError(f"{source} has no rows.")
    key = "iteration" if "iteration" in rows[0] else "step"
    if column not in rows[0] or key not in rows[0]:
        raise KeyError(f"{source}: needs columns '{key}' and '{column}'; has {list(rows[0])}.")
    rows = [r for r in rows if r[column] != ""]
    return np.array([float(r[key]) for r in rows]), np.array([float(r[column]) for r in rows])


def plot_reward_seeds(sources: list[str | Path], out: str | Path, column: str = "mean_reward", label: str = "") -> Path:
    """Mean over seeds with a +-1 std band, on the iterations all runs share."""
    curves = [read_curve(s, column) for s in sources]
    common = sorted(set.intersection(*(set(it.tolist()) for it, _ in curves)))
    if not common:
        raise ValueError("the runs share no iteration; pass runs of one configuration with different seeds.")
    values = np.stack([np.interp(common, it, v) for it, v in curves])
    mean, std = values.mean(0), values.std(0)
    plt = _plt()
    fig, ax = plt.subplots(figsize=(5, 3.2))
    ax.plot(common, mean, color="tab:blue", label=f"mean over {len(sources)} seed{'s' * (len(sources) > 1)}")
    ax.fill_between(common, mean - std, mean + std, color="tab:blue", alpha=0.25, label="+-1 std")
    ax.set_xlabel("iteration")
    ax.set_ylabel(column.replace("_", " "))
    ax.set_title(label or ("training reward" if column == "mean_reward" else f"{column.replace('_', ' ')} in training"))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return _save(fig, out)


# -------------------------------------------------------------------------------- (b) velocity tracking
def plot_tracking(traces: str | Path, out: str | Path, ids: list[str] | None = None, max_terrains: int = 4) -> Path:
    """Commanded vs actual vx (top) and vy (bottom) of each chosen terrain's first robot, while it was alive."""
    data = open_npz(traces)
    if not {"ids", "dt", "active"} <= set(data.files):
        raise ValueError(f"{traces} is not a traces.npz of gente-evaluate (it holds {sorted(data.files)[:6]}); give "
                         f"the traces.npz that gente-evaluate --out wrote.")
    all_ids = [str(i) for i in data["ids"]]
    chosen = ids or all_ids[:max_terrains]
    missing = [i for i in chosen if i not in all_ids]
    if missing:
        raise KeyError(f"{missing} not in {traces}; it has {all_ids[:5]}...")
    dt = float(data["dt"])
    plt = _plt()
    fig, axes = plt.subplots(2, len(chosen), figsize=(2.6 * len(chosen), 3.6), sharex=True, squeeze=False)
    for c, item in enumerate(chosen):
        k = all_ids.index(item)
        alive = data["active"][k].astype(bool)
        t = (np.arange(alive.size) + 1) * dt  # row k is recorded after policy step k + 1
        for r, (axis, name) in enumerate(((0, "vx"), (1, "vy"))):
            ax = axes[r, c]
            ax.plot(t[alive], data["cmd"][k, alive, axis], "k--", lw=1, label="command")
            ax.plot(t[alive], data["vel"][k, alive, axis], color="tab:blue", lw=1, label="actual")
            ax.grid(alpha=0.3)
            if c == 0:
                ax.set_ylabel(f"{name} (m/s)")
        axes[0, c].set_title("\n".join(textwrap.wrap(item, 24)), fontsize=7)  # whole: ids share long prefixes
        axes[1, c].set_xlabel("time (s)")
    axes[0, 0].legend(fontsize=7)
    return _save(fig, out)


# ------------------------------------------------------------------------------- (c) waypoint trajectories
def plot_trajectories(heights: np.ndarray, resolution: float, runs: dict[float, dict], out: str | Path,
                      title: str = "") -> Path:
    """One panel per reach distance d: the tile's heights in grey, the path, start, end and waypoints (tile frame),
    drawn as preview.png draws the tile: +x (forward) up, +y (left) to the left, axes in metres."""
    plt = _plt()
    fig, axes = plt.subplots(1, len(runs), figsize=(2.6 * len(runs), 3.1), squeeze=False)
    size_x, size_y = heights.shape[0] * resolution, heights.shape[1] * resolution
    for ax, (d, run) in zip(axes[0], runs.items()):
        # row 0 the front edge (largest x), column 0 the left edge (largest y)
        ax.imshow(heights[::-1, ::-1], extent=(size_y, 0, 0, size_x), cmap="Greys_r")
        pos, wp = run["pos"], run["waypoints"]
        ax.plot(pos[:, 1], pos[:, 0], color="tab:orange", lw=1.2)
        ax.plot(pos[0, 1], pos[0, 0], "go", ms=5, label="start")
        ax.plot(pos[-1, 1], pos[-1, 0], "rs", ms=5, label="end")
        ax.plot(wp[:, 1], wp[:, 0], "b*", ms=7, label="waypoints")
        ax.set_title(f"d = {d:g} m" + (" (reached)" if run.get("finished") else ""), fontsize=8)
        ax.set_xlabel("y (m), +y to the left", fontsize=7)
        ax.tick_params(labelsize=6)
    axes[0, 0].set_ylabel("x (m), +x forward", fontsize=7)
    axes[0, 0].legend(fontsize=6, loc="lower left")
    if title:
        fig.suptitle(title, fontsize=9)
    return _save(fig, out)


def waypoint_figure(task: str, item_id: str, out: str | Path, benchmark: str = "gente100",
                    distances=(0.1, 1.0, 5.0, 20.0), device: str = "cpu", episode_s: float | None = None,
                    **policy) -> Path:
    """Run the waypoint task on one terrain once per reach distance d (one robot) and plot the trajectories
    (``episode_s`` defaults to the waypoint task's, as in ``gente-evaluate --mode waypoints``)."""
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import Evaluation, load_policy
    from legged_gente.evaluation.tasks import WAYPOINT_SPEED, waypoint_episode_s

    item = load_benchmark(benchmark, [item_id])[0]
    episode_s = waypoint_episode_s(WAYPOINT_SPEED) if episode_s is None else episode_s
    evaluation = Evaluation(task, [item], 1, device, episode_s, "waypoints")
    act = load_policy(evaluation, **policy)
    runs = {}  # the single tile starts at world (0, 0), so world xy is the tile frame
    for d in distances:
        result = evaluation.run(act, evaluation.make_task(reach_distance=d), progress=False)
        alive = result.traces["active"][0].astype(bool)
        runs[d] = {"pos": result.traces["pos"][0, alive], "waypoints": result.traces["waypoints"][0],
                   "finished": bool(result.metrics["finished"][0])}
    heights, _ = item.spec().build()
    return plot_trajectories(heights, item.spec().resolution, runs, out, title=item.id)


# ------------------------------------------------------------------------------ (d) success over training
def success_over_training(task: str, run_dirs: list[str | Path], item_ids: list[str], out: str | Path,
                          benchmark: str = "gente100", max_checkpoints: int = 8, robots_per_terrain: int = 16,
                          device: str = "cpu", episode_s: float = 10.0, tracking_threshold: float | None = None) -> Path:
    """Evaluate up to ``max_checkpoints`` evenly spaced checkpoints of a run on ``item_ids``; plot success vs iteration.

    ``run_dirs`` are the run's folders: ``gente-train --resume`` continues in a new one, so a run trained in chunks
    spans several."""
    if max_checkpoints < 1:
        raise ValueError(f"max_checkpoints {max_checkpoints}: evaluate at least 1 checkpoint "
                         f"(--max_checkpoints 1 or more)")
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import Evaluation, load_policy
    from legged_gente.evaluation.report import TRACKING_THRESHOLD, success
    from legged_gente.utils.checkpoints import _iteration, _models

    items = load_benchmark(benchmark, item_ids)
    found = {}
    for run_dir in run_dirs:
        for checkpoint in _models(Path(run_dir)):
            iteration = _iteration(checkpoint)
            if iteration in found:
                raise ValueError(f"{checkpoint.name} is in both {found[iteration].parent} and {run_dir}: give the "
                                 f"folders of one run and its resumes, each once.")
            found[iteration] = checkpoint
    if not found:
        raise FileNotFoundError(f"no model_*.pt in {', '.join(map(str, run_dirs))}; pass a training run's folders.")
    checkpoints = [found[i] for i in sorted(found)]
    pick = np.unique(np.linspace(0, len(checkpoints) - 1, min(max_checkpoints, len(checkpoints))).round().astype(int))
    evaluation = Evaluation(task, items, robots_per_terrain, device, episode_s, "velocity")
    iterations, rates = [], []
    for k in pick:
        result = evaluation.run(load_policy(evaluation, checkpoint=str(checkpoints[k])), progress=False)
        ok = success(result.metrics, "velocity", tracking_threshold or TRACKING_THRESHOLD)
        moving = ~result.metrics["standing"].astype(bool)
        rates.append([ok[(result.tile == t) & moving].mean() for t in range(len(items))])
        iterations.append(_iteration(checkpoints[k]))
        print(f"iteration {iterations[-1]}: success " + ", ".join(f"{item.id} {100 * r:.0f} %"
                                                            for item, r in zip(items, rates[-1])), flush=True)
    rates = np.array(rates)
    plt = _plt()
    fig, ax = plt.subplots(figsize=(5, 3.2))
    for t, item in enumerate(items):
        ax.plot(iterations, 100 * rates[:, t], "o-", ms=3, label=item.id[:28])
    ax.set_xlabel("training iteration")
    ax.set_ylabel("success rate (%)")
    ax.set_ylim(-3, 103)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    return _save(fig, out)


def _save(fig, out: str | Path) -> Path:
    """The figure as a PNG at ``out`` (``.png`` added to a name without a suffix: the path said is the one written)."""
    out = Path(out)
    if out.is_dir():
        raise ValueError(f"--out {out} is a folder; give the PNG's path, e.g. {out / 'figure.png'}")
    if not out.suffix:
        out = out.with_suffix(".png")
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(out, dpi=DPI)
    _plt().close(fig)
    return out


def main(argv=None) -> None:
    """Draw the figure a subcommand names; a user's mistake (a missing file, an unknown id, a bad value) is one line,
    exit status 2, as in the gente-* commands."""
    p = Parser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="figure", required=True)
    a = sub.add_parser("reward", help="(a) training reward over seeds")
    a.add_argument("sources", nargs="+", help="TensorBoard run folders or CSVs, one per seed")
    a.add_argument("--column", default="mean_reward")
    a.add_argument("--label", default="")
    b = sub.add_parser("tracking", help="(b) commanded vs actual velocity")
    b.add_argument("traces", help="traces.npz written by gente-evaluate")
    b.add_argument("--ids", nargs="+")
    for name, help_ in (("waypoints", "(c) waypoint trajectories for several d"), ("training", "(d) success over training")):
        s = sub.add_parser(name, help=help_)
        s.add_argument("--task", default="gente_biped")
        s.add_argument("--benchmark", default="gente100")
        s.add_argument("--device", default="cpu")
    c = sub.choices["waypoints"]
    c.add_argument("--item", required=True, help="benchmark item id (an obstacle field, e.g. image_05_sketch_blocks)")
    c.add_argument("--distances", nargs="+", type=float, default=[0.1, 1.0, 5.0, 20.0])
    src = c.add_mutually_exclusive_group(required=True)
    src.add_argument("--checkpoint")
    src.add_argument("--exported")
    src.add_argument("--pretrained", action="store_true", help="the policy shipped with the package for --task")
    src.add_argument("--baseline", choices=("zero", "random"))
    d = sub.choices["training"]
    d.add_argument("--run", nargs="+", required=True,
                   help="training run folder with model_*.pt, then the folders of its --resume chunks")
    d.add_argument("--items", nargs="+", required=True, help="benchmark item ids (the paper's figure has three)")
    d.add_argument("--max_checkpoints", type=int, default=8)
    d.add_argument("--robots_per_terrain", type=int, default=16)
    for s in sub.choices.values():
        s.add_argument("--out", required=True, help="PNG path")
        add_verbose(s)
    args = p.parse_args(argv)
    quiet_third_party(args.verbose)  # the waypoints and training figures build an env: Warp's module loads
    run_command(PROG, _draw, args)


def _draw(args) -> None:
    if args.figure == "reward":
        path = plot_reward_seeds(args.sources, args.out, args.column, args.label)
    elif args.figure == "tracking":
        path = plot_tracking(args.traces, args.out, args.ids)
    elif args.figure == "waypoints":
        path = waypoint_figure(args.task, args.item, args.out, args.benchmark, tuple(args.distances), args.device,
                               checkpoint=args.checkpoint, exported=args.exported, baseline=args.baseline,
                               pretrained=args.pretrained)
    else:
        path = success_over_training(args.task, args.run, args.items, args.out, args.benchmark, args.max_checkpoints,
                                     args.robots_per_terrain, args.device)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
