"""Score the offline planner on a labelled evaluation set of scene texts and photos.

    python -m legged_gente.generation.score                       # legged_gente/benchmarks/generation_eval
    python -m legged_gente.generation.score --set DIR --kind photo --split held_out

The set is a folder with ``texts.json`` (``{"items": [{"text", "labels"}]}``) and ``photos/manifest.json``
(``{"items": [{"file", "labels"}]}``, files relative to ``photos/``). An item's ``split`` says which half it is
in: ``tune`` (rules may be adjusted while looking at it) or ``held_out`` (only scored); items without one
alternate, the 1st, 3rd, ... being ``tune``.

Each item's planner calls are reduced to the terrain *features* a walking robot meets (:data:`FEATURES`,
defined on the calls by :func:`features`), compared with the item's hand labels, and reported as per-feature
precision / recall, micro-averaged F1, the share of items with every labelled feature found ("complete"),
the share predicted exactly, the median number of tool calls, and for photos the number whose sky was read
as water or snow (a photo labelled without water/snow that gets water/snow; 0 is required).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
from pathlib import Path
from typing import Iterable, Sequence

from legged_gente.generation.validation import ToolCall

FEATURES = ("water", "flowing", "sand", "mud", "snow", "ice", "tall", "low", "stairs", "slope", "rough")
"""Labels of the evaluation set: surfaces, flowing water (current or tide), obstacles a ~1 m biped cannot
step over (``tall``, >= 0.3 m) or can (``low``), stairs, slopes, and rough (uneven) ground."""

TALL = 0.3
"""Height (m) from which an obstacle counts as ``tall``: about the knee of the ~1 m biped."""

DEFAULT_SET = Path(__file__).resolve().parents[1] / "benchmarks" / "generation_eval"
"""The set in a source checkout (it is not package data: a development tool, 1.2 MB of pictures)."""


def features(calls: Iterable[ToolCall], size_x: float = 20.0, size_y: float = 20.0) -> set[str]:
    """The :data:`FEATURES` a list of calls builds (thresholds in the code below, one line per feature)."""
    out: set[str] = set()
    for c in calls:
        p = c.params
        if c.tool == "water" and p["depth"] > 0:
            out.add("water")
            if p["flow"] != "still" and p["speed"] > 0:
                out.add("flowing")
        elif c.tool == "soil":
            out |= {"dry_sand": {"sand"}, "wet_sand": {"sand"}, "mud": {"mud"}, "snow": {"snow"}}.get(p["preset"], set())
        elif c.tool == "low_friction" and (p["preset"] == "ice" or (p["preset"] == "custom" and p["mu"] < 0.15)):
            out.add("ice")
        elif c.tool == "ice" and p["depth"] > 0:
            out.add("ice")
        elif c.tool == "pillars" and p["density"] > 0:
            out.add("tall" if p["height"] >= TALL else "low")
        elif c.tool in ("discrete_obstacles", "rocks"):
            height = p["max_height"]
            if height > 0 and p["density"] > 0:
                out.add("tall" if height >= TALL else "low")
        elif c.tool == "flat" and c.mode == "set" and p["height"] >= TALL:
            x0, y0, x1, y1 = c.rect(size_x, size_y)
            if (x1 - x0) * (y1 - y0) < 0.5 * size_x * size_y:  # a raised block, not the whole ground
                out.add("tall")
        elif c.tool in ("stairs", "pyramid_stairs") and p["step_height"] > 0:
            out.add("stairs")
        elif (c.tool == "pyramid_slope" and p["slope"] >= 0.05) or (c.tool == "hills" and p["amplitude"] >= 0.3):
            out.add("slope")
        elif ((c.tool == "natural_ground" and p["amplitude"] >= 0.08) or (c.tool == "random_uniform" and p["amplitude"] >= 0.02)
              or (c.tool == "waves" and p["amplitude"] >= 0.05) or c.tool == "stepping_stones"):
            out.add("rough")
    return out


def load_items(root: Path, kind: str) -> list[dict]:
    """Items of ``kind`` ("text" or "photo") with their ``split``; unknown labels are an error."""
    path = root / ("texts.json" if kind == "text" else "photos/manifest.json")
    if not path.is_file():
        raise FileNotFoundError(f"{path} not found; pass --set with a folder holding texts.json and photos/manifest.json.")
    try:
        items = json.loads(path.read_text(encoding="utf-8"))
    except ValueError as exc:  # JSONDecodeError, bad UTF-8
        raise ValueError(f"{path} is not valid JSON ({exc}); fix the file.") from None
    if not isinstance(items, dict) or not isinstance(items.get("items"), list):
        raise ValueError(f"{path} holds no 'items' list; write {{\"items\": [{{\"labels\": [...], ...}}, ...]}}.")
    items = items["items"]
    for i, item in enumerate(items):
        if not isinstance(item, dict) or not isinstance(item.get("labels"), list):
            raise ValueError(f"{path}: item {i} has no 'labels' list; write {{\"labels\": [...], ...}} with labels "
                             f"from {list(FEATURES)}.")
        needed = "text" if kind == "text" else "file"
        if not isinstance(item.get(needed), str):
            raise ValueError(f"{path}: item {i} has no '{needed}'; give each item its {needed} as a string.")
        bad = sorted({label if isinstance(label, str) else json.dumps(label) for label in item["labels"]} - set(FEATURES))
        if bad:
            raise ValueError(f"{path}: item {i} has unknown label(s) {bad}; labels are {list(FEATURES)}.")
        item.setdefault("split", "tune" if i % 2 == 0 else "held_out")
        if item["split"] not in ("tune", "held_out"):
            raise ValueError(f"{path}: item {i} has split {item['split']!r}; use 'tune' or 'held_out'.")
        if kind == "photo":
            item["path"] = path.parent / item["file"]
    return items


def predict(item: dict, kind: str) -> tuple[set[str], int]:
    """Features and number of calls the planner produces for one item."""
    if kind == "text":
        from legged_gente.generation.backends.planner import plan_text

        result = plan_text(item["text"])
    else:
        from legged_gente.generation.backends.image import plan_image

        result = plan_image(item["path"])
    return features(result.calls), len(result.calls)


def score(items: Sequence[dict], predictions: Sequence[tuple[set[str], int]]) -> dict:
    """Per-feature counts and the summary numbers (see the module docstring)."""
    per = {f: {"tp": 0, "fp": 0, "fn": 0} for f in FEATURES}
    complete = exact = sky = 0
    for item, (pred, _) in zip(items, predictions):
        truth = set(item["labels"])
        for f in FEATURES:
            key = "tp" if f in pred and f in truth else "fp" if f in pred else "fn" if f in truth else None
            if key:
                per[f][key] += 1
        complete += truth <= pred
        exact += truth == pred
        sky += bool({"water", "snow"} & (pred - truth))
    tp = sum(v["tp"] for v in per.values())
    fp = sum(v["fp"] for v in per.values())
    fn = sum(v["fn"] for v in per.values())
    n = max(len(items), 1)
    return {
        "per_feature": per,
        "micro_f1": 2 * tp / max(2 * tp + fp + fn, 1),
        "complete": complete / n,
        "exact": exact / n,
        "median_calls": statistics.median([c for _, c in predictions]) if predictions else 0,
        "false_water_or_snow": sky,
        "n": len(items),
    }


def table(result: dict, title: str) -> str:
    """A Markdown table of one score."""
    lines = [f"### {title} ({result['n']} items)", "", "| feature | precision | recall | tp | fp | fn |", "|---|---|---|---|---|---|"]
    for f, v in result["per_feature"].items():
        prec = f"{v['tp'] / (v['tp'] + v['fp']):.2f}" if v["tp"] + v["fp"] else "-"
        rec = f"{v['tp'] / (v['tp'] + v['fn']):.2f}" if v["tp"] + v["fn"] else "-"
        lines.append(f"| {f} | {prec} | {rec} | {v['tp']} | {v['fp']} | {v['fn']} |")
    lines += ["", f"micro-F1 {result['micro_f1']:.3f}; every expected feature found: {100 * result['complete']:.0f}%; "
              f"exact: {100 * result['exact']:.0f}%; median calls {result['median_calls']:g}; "
              f"items given water or snow they do not have: {result['false_water_or_snow']}", ""]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m legged_gente.generation.score", description=__doc__.splitlines()[0])
    parser.add_argument("--set", type=Path, default=DEFAULT_SET, help="evaluation folder (default: %(default)s)")
    parser.add_argument("--kind", choices=("text", "photo", "all"), default="all")
    parser.add_argument("--split", choices=("tune", "held_out", "all"), default="all",
                        help="which half to report; 'all' reports tune, held_out and both")
    parser.add_argument("--verbose", action="store_true", help="print every item of the reported split(s) that is not predicted exactly")
    args = parser.parse_args(argv)
    kinds = ("text", "photo") if args.kind == "all" else (args.kind,)
    try:
        for kind in kinds:
            items = load_items(args.set, kind)
            preds = [predict(item, kind) for item in items]
            splits = ("tune", "held_out", "all") if args.split == "all" else (args.split,)
            for split in splits:
                chosen = [(i, p) for i, p in zip(items, preds) if split == "all" or i["split"] == split]
                print(table(score([i for i, _ in chosen], [p for _, p in chosen]), f"{kind}s, {split}"))
            if args.verbose:
                for item, (pred, n) in zip(items, preds):
                    truth = set(item["labels"])
                    if pred != truth and args.split in ("all", item["split"]):
                        name = item.get("text") or item["file"]
                        print(f"  [{item['split']}] {name!r}: missing {sorted(truth - pred)}, extra {sorted(pred - truth)} ({n} calls)")
    except (FileNotFoundError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
