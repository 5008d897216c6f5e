"""Per-robot metrics -> per-terrain, per-category and overall summaries; JSON and CSV reports.

Categories of a terrain come from its spec's calls (a terrain can be in several): each registered atomic
terrain maps to one of the paper's four groups, or to none (plain base ground). Items are also grouped by
their source kind (text / image).
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np

from legged_gente.evaluation.benchmark import Item

CATEGORY_OF_TOOL = {
    "water": "water", "river": "water", "basin": "water",
    "soil": "soil", "low_friction": "soil", "ice": "soil",  # the ground's material: deformable or slippery
    "pillars": "obstacles", "discrete_obstacles": "obstacles", "rocks": "obstacles", "stepping_stones": "obstacles",
    "gap": "obstacles", "pit": "obstacles",
    "hills": "slopes_and_stairs", "pyramid_slope": "slopes_and_stairs", "stairs": "slopes_and_stairs",
    "pyramid_stairs": "slopes_and_stairs",
}
"""Atomic terrain -> category. Base-ground atomics (flat, natural_ground, random_uniform, waves) have none,
except a ``flat`` call at a non-zero height over part of the tile: a raised block (a sketch's black obstacle) or a
sunken floor. Over the whole tile it raises or lowers all of it (GenTe's transcripts do): no obstacle."""
BASE_GROUND = ("flat", "natural_ground", "random_uniform", "waves")
CATEGORIES = ("water", "soil", "obstacles", "slopes_and_stairs")

METRIC_COLUMNS = ("robots", "success_rate", "tracking_error", "progress", "heading_error", "distance", "displacement",
                  "collisions", "falls", "fall_rate", "diverged", "energy_per_m", "left_tile")


def categories_of(spec) -> list[str]:
    """The categories of a spec's calls, in CATEGORIES order; raises for an atomic with no category decision."""
    found = set()
    for call in spec.calls:
        if call.tool == "flat":
            x0, y0, x1, y1 = call.rect(spec.size_x, spec.size_y)
            whole = x0 <= 0.0 and y0 <= 0.0 and x1 >= spec.size_x and y1 >= spec.size_y
            if float(call.params["height"]) != 0.0 and not whole:  # a block or a floor, with edges on the tile
                found.add("obstacles")
        elif call.tool in CATEGORY_OF_TOOL:
            found.add(CATEGORY_OF_TOOL[call.tool])
        elif call.tool not in BASE_GROUND:
            raise KeyError(f"atomic terrain {call.tool!r} has no evaluation category; add it to CATEGORY_OF_TOOL or "
                           f"BASE_GROUND in legged_gente/evaluation/report.py.")
    return [c for c in CATEGORIES if c in found]


TRACKING_THRESHOLD = 0.25
"""m/s; a velocity-task success needs a mean tracking error below it."""
MIN_PROGRESS = 0.7
"""A moving command's success needs at least this share of the commanded distance covered along the command."""
STAND_GROUP = "stand_still"
"""The report group of the robots commanded to stand still; every other group counts moving commands only."""


def success(metrics: dict[str, np.ndarray], task: str, tracking_threshold: float = TRACKING_THRESHOLD,
            min_progress: float = MIN_PROGRESS) -> np.ndarray:
    """Per-robot success (see the evaluator's docstring for the definitions); a diverged robot never succeeds."""
    healthy = ~_diverged(metrics)
    if task == "waypoints":
        return metrics["finished"].astype(bool) & healthy
    standing = metrics["standing"].astype(bool)
    with np.errstate(invalid="ignore"):
        tracked = ~metrics["fell"].astype(bool) & (metrics["tracking_error"] < tracking_threshold)
        progressed = metrics["progress"] >= min_progress
    return tracked & (standing | progressed) & healthy


def _diverged(metrics: dict[str, np.ndarray]) -> np.ndarray:
    return metrics.get("diverged", np.zeros(len(metrics["fell"]), bool)).astype(bool)


def summarize_robots(metrics: dict[str, np.ndarray], ok: np.ndarray) -> dict[str, float]:
    """Aggregate a group of robots: success and fall rates over all of them (a diverged robot is a failure),
    means over the robots whose simulation did not diverge (a diverged robot's numbers are the simulator's, not
    the policy's), the diverged ones counted apart; energy per metre as total energy / total distance."""
    n = int(ok.size)
    diverged = _diverged(metrics)
    kept = {k: v[~diverged] for k, v in metrics.items()}
    m = int((~diverged).sum())
    distance = float(kept["distance"].sum())
    falls = int(metrics["fell"].sum())
    finite = np.isfinite(kept["tracking_error"])
    progress = kept["progress"][np.isfinite(kept["progress"])] if "progress" in kept else np.zeros(0)
    heading = kept["heading_error"][np.isfinite(kept["heading_error"])] if "heading_error" in kept else np.zeros(0)
    return {
        "robots": n,
        "success_rate": float(ok.mean()) if n else math.nan,
        "tracking_error": float(kept["tracking_error"][finite].mean()) if finite.any() else math.nan,
        "progress": float(progress.mean()) if progress.size else math.nan,
        "heading_error": float(heading.mean()) if heading.size else math.nan,
        "distance": float(kept["distance"].mean()) if m else math.nan,
        "displacement": float(kept["displacement"].mean()) if m else math.nan,
        "collisions": float(kept["collisions"].mean()) if m else math.nan,
        "falls": falls,
        "fall_rate": falls / n if n else math.nan,
        "diverged": int(diverged.sum()),
        "energy_per_m": float(kept["energy"].sum()) / distance if distance > 0 else math.nan,
        "left_tile": int(metrics["left_tile"].sum()),
    }


SHORT_MEASURE = 0.5
"""Share of the episode under which the robots that reached their tile's edge are said to be scored on a short part."""


def short_measure_note(metrics: dict[str, np.ndarray], episode_length_s: float) -> str | None:
    """A sentence when the robots with a moving command that reached their tile's edge did so, on average, within
    the first ``SHORT_MEASURE`` of the episode: their success and progress are over that part alone (a tile small
    for the commanded speed and the episode), else None."""
    moving = ~metrics.get("standing", np.zeros_like(metrics["left_tile"])).astype(bool)
    left = metrics["left_tile"].astype(bool) & moving
    if not left.any():
        return None
    measured = float(metrics["time_s"][left].mean())
    if measured >= SHORT_MEASURE * episode_length_s:
        return None
    return (f"{int(left.sum())} of {int(moving.sum())} moving robots reached their tile's edge after {measured:.1f} s "
            f"on average, of the {episode_length_s:g} s episode, and are scored over that part alone; a larger tile "
            f"measures more of it (--tile_edge_margin off walks them on past the edge).")


def check_success_rule(tracking_threshold: float, min_progress: float) -> None:
    """The success rule's thresholds, or a one-line error: a tracking error bound in m/s, a share of the distance."""
    if not tracking_threshold > 0:
        raise ValueError(f"tracking_threshold must be > 0 m/s, got {tracking_threshold}.")
    if not 0.0 < min_progress <= 1.0:
        raise ValueError(f"min_progress is a share of the commanded distance, in (0, 1]; got {min_progress}.")


def build_report(result, items: list[Item], tracking_threshold: float = TRACKING_THRESHOLD,
                 meta: dict | None = None, min_progress: float = MIN_PROGRESS) -> dict:
    """JSON-ready report: ``terrains`` (one entry per item), ``groups`` (kinds and categories) and ``overall``.

    Terrains, kinds, categories and overall count the robots with a moving command; the robots told to stand
    still are the group ``stand_still`` (velocity task)."""
    check_success_rule(tracking_threshold, min_progress)
    ok = success(result.metrics, result.task, tracking_threshold, min_progress)
    standing = result.metrics.get("standing", np.zeros_like(ok)).astype(bool)

    def select(mask):
        mask = mask & ~standing
        return {k: v[mask] for k, v in result.metrics.items()}, ok[mask]

    terrains, group_masks = [], {}
    for k, item in enumerate(items):
        cats = categories_of(item.spec())
        mask = result.tile == k
        terrains.append({"id": item.id, "kind": item.kind, "categories": cats, **summarize_robots(*select(mask))})
        for group in [item.kind] + cats:
            group_masks[group] = group_masks.get(group, np.zeros_like(mask)) | mask
    order = ["text", "image", *CATEGORIES]
    groups = {g: {"terrains": sum(1 for t in terrains if g in (t["kind"], *t["categories"])),
                  **summarize_robots(*select(group_masks[g]))} for g in order if g in group_masks}
    if standing.any():
        groups[STAND_GROUP] = {"terrains": len(np.unique(result.tile[standing])),  # those with a standing robot
                               **summarize_robots({k: v[standing] for k, v in result.metrics.items()}, ok[standing])}
    everything = np.ones_like(ok)
    # the velocity task's success rule; the waypoint task's (the last waypoint reached) has no threshold
    rule = {"tracking_threshold": tracking_threshold, "min_progress": min_progress} if result.task == "velocity" else {}
    return {
        "meta": {"task_mode": result.task, **rule, **result.params, **(meta or {})},
        "overall": {"terrains": len(items), **summarize_robots(*select(everything))},
        "groups": groups,
        "terrains": terrains,
    }


def _json_safe(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_json_safe(v) for v in value]
    return value


def write_reports(report: dict, out_dir: str | Path) -> tuple[Path, Path]:
    """``report.json`` (NaN written as null) and ``report.csv`` (one row per terrain, group and overall)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    json_path, csv_path = out / "report.json", out / "report.csv"
    json_path.write_text(json.dumps(_json_safe(report), indent=1) + "\n")
    with open(csv_path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["row", "name", "kind", "categories", "terrains", *METRIC_COLUMNS])
        fmt = lambda v: "" if isinstance(v, float) and not math.isfinite(v) else (f"{v:.4g}" if isinstance(v, float) else v)  # noqa: E731
        for t in report["terrains"]:
            writer.writerow(["terrain", t["id"], t["kind"], "+".join(t["categories"]), 1,
                             *(fmt(t[c]) for c in METRIC_COLUMNS)])
        for name, g in report["groups"].items():
            writer.writerow(["group", name, "", "", g["terrains"], *(fmt(g[c]) for c in METRIC_COLUMNS)])
        overall = report["overall"]
        writer.writerow(["overall", "all", "", "", overall["terrains"], *(fmt(overall[c]) for c in METRIC_COLUMNS)])
    return json_path, csv_path
