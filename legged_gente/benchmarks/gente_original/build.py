"""Rebuild the gente_original benchmark from a clone of GenTe's repository (github.com/HaronW/GenTe).

    git clone https://github.com/HaronW/GenTe /tmp/GenTe
    python legged_gente/benchmarks/gente_original/build.py --gente /tmp/GenTe

GenTe publishes ``dataset/{single_part,multi_parts}/{txt|text,image}/N/`` with ``data.json`` (the tool calls
its language/vision models made, in GenTe's tool schema) and ``array.npy`` (the int16 heightmap GenTe built).
This script translates every transcript with :mod:`legged_gente.generation.gente_compat` and writes, into
:data:`OUT` only: ``specs/<id>.json`` (our spec format: tool names and numbers), ``manifest.json`` (the items
for ``gente-evaluate --benchmark``), ``report.json`` (per item: every issue of the translation, and the
heightmap's overflow check) and ``REPORT.md`` (the summary). GenTe's scene texts and photos are not copied,
and nothing is downloaded: the clone is the only input. The scenes are an evaluation set: nothing in the
project is tuned to them.

GenTe's own heightmaps as terrains (not shipped: they stay in the clone)::

    python legged_gente/benchmarks/gente_original/build.py --gente /tmp/GenTe --heightmaps /tmp/gente_heightmaps
    gente-evaluate --benchmark /tmp/gente_heightmaps ...      # or --terrain /tmp/gente_heightmaps/specs/<id>.json

writes a spec per ``array.npy`` that names the clone's file (0.1 m cells, 0.005 m per unit) and a manifest of
those that build; a heightmap that wrapped around int16 or exceeds the height bound is listed with the reason.
"""

from __future__ import annotations

import argparse
import collections
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

from legged_gente.generation.gente_compat import BLOCKING, GENTE_TOOLS, heightmap_spec, import_heightmap, import_transcript
from legged_gente.generation.validation import ValidationError
from legged_gente.terrain.composition import MAX_ABS_HEIGHT

OUT = Path(__file__).resolve().parent
"""Where the benchmark is written (the one output path)."""
SCHEMAS = {"single_part": "single", "multi_parts": "multi"}
KINDS = {"txt": "text", "text": "text", "image": "image"}


def transcripts(gente: Path) -> list[tuple[str, str, str, Path]]:
    """(id, schema, kind, folder) of every item of GenTe's dataset, in a stable order."""
    items = []
    for part_dir, schema in SCHEMAS.items():
        for kind_dir, kind in KINDS.items():
            root = gente / "dataset" / part_dir / kind_dir
            if not root.is_dir():
                continue
            for folder in sorted((p for p in root.iterdir() if p.name.isdigit()), key=lambda p: int(p.name)):
                items.append((f"{schema}_{kind}_{int(folder.name):02d}", schema, kind, folder))
    if not items:
        raise SystemExit(f"{gente} holds no dataset/{{single_part,multi_parts}}/{{txt,text,image}}/N/; pass a clone of "
                         f"https://github.com/HaronW/GenTe with --gente.")
    return items


def build(gente: Path, out: Path = OUT) -> dict:
    (out / "specs").mkdir(parents=True, exist_ok=True)
    for old in (out / "specs").glob("*.json"):
        old.unlink()
    manifest_items, report_items = [], []
    tools_used: dict[str, collections.Counter] = {"single": collections.Counter(), "multi": collections.Counter()}
    kinds = collections.Counter()
    step_shares: dict[str, list[np.ndarray]] = {"gente": [], "import": []}  # per tile: share of cells at each STEPS
    for number, (item_id, schema, kind, folder) in enumerate(transcripts(gente)):
        data = json.loads((folder / "data.json").read_text(encoding="utf-8"))
        result = import_transcript(data, item_id, schema, seed=number)
        for t in result.translations:
            tools_used[schema][t.gente_tool] += 1
        for issue in result.issues:
            kinds[issue.kind] += 1
        entry = {"id": item_id, "schema": schema, "kind": kind, "gente_calls": len(data.get("tool_calls") or []),
                 "imported": result.spec is not None, "calls": len(result.spec.calls) if result.spec else 0,
                 "error": result.error,
                 "issues": [{"gente_tool": t.gente_tool, "kind": i.kind, "message": i.message}
                            for t in result.translations for i in t.issues]}
        heightmap = folder / "array.npy"
        if heightmap.is_file():
            hm = import_heightmap(np.load(heightmap, allow_pickle=False))
            entry["heightmap"] = {"overflowed": hm.overflowed, "wrap_edges": hm.wrap_edges,
                                  "min_m": round(float(hm.heights.min()), 3), "max_m": round(float(hm.heights.max()), 3),
                                  "beyond_bound": bool(np.abs(hm.heights).max() > MAX_ABS_HEIGHT)}
            if result.spec is not None and not hm.overflowed:
                step_shares["gente"].append(_step_shares(hm.heights))
                step_shares["import"].append(_step_shares(result.spec.build()[0]))
        report_items.append(entry)
        if result.spec is not None:
            spec_rel = f"specs/{item_id}.json"
            result.spec.save(out / spec_rel)
            manifest_items.append({"id": item_id, "kind": kind, "spec": spec_rel})
    commit = _commit(gente)
    manifest = {"name": "gente_original", "tile_size": [20.0, 20.0], "resolution": 0.1,
                "source": f"github.com/HaronW/GenTe dataset/ at {commit}", "items": manifest_items}
    (out / "manifest.json").write_text(json.dumps(manifest, indent=1) + "\n")
    invented = sorted({i["gente_tool"] for e in report_items for i in e["issues"] if i["kind"] == "invented_tool"})
    heightmaps = [e["heightmap"] for e in report_items if "heightmap" in e]
    summary = {
        "source": manifest["source"],
        "transcripts": len(report_items),
        "imported": sum(e["imported"] for e in report_items),
        "not_imported": {e["id"]: e["error"] for e in report_items if not e["imported"]},
        "calls_gente": sum(e["gente_calls"] for e in report_items),
        "calls_blocked": sum(1 for e in report_items for i in e["issues"] if i["kind"] in BLOCKING),
        "issues_by_kind": dict(sorted(kinds.items())),
        "gente_tools_used": {s: dict(sorted(c.items())) for s, c in tools_used.items()},
        "gente_tools_declared_not_used": sorted(set(GENTE_TOOLS) - set(tools_used["single"]) - set(tools_used["multi"])),
        "invented_tools": invented,
        "outside_schema": sorted({i["gente_tool"] for e in report_items for i in e["issues"] if i["kind"] == "outside_schema"}),
        "heightmaps": len(heightmaps),
        "heightmaps_overflowed": [e["id"] for e in report_items if e.get("heightmap", {}).get("overflowed")],
        "heightmaps_beyond_bound": sum(h["beyond_bound"] for h in heightmaps),
        "steps": {"tiles": len(step_shares["gente"]), "heights_m": list(STEPS),
                  **{k: [round(100 * float(v), 2) for v in np.mean(shares, axis=0)] for k, shares in step_shares.items()}
                  } if step_shares["gente"] else None,
    }
    (out / "report.json").write_text(json.dumps({"summary": summary, "items": report_items}, indent=1) + "\n")
    (out / "REPORT.md").write_text(_markdown(summary))
    return summary


STEPS = (0.05, 0.1, 0.2, 0.3)
"""Heights (m) of the steps between neighbouring cells that REPORT.md counts, in GenTe's heightmaps and ours."""


def _step_shares(heights: np.ndarray) -> np.ndarray:
    """The share of a tile's cells whose height differs from a neighbour's (+x or +y) by at least each of STEPS."""
    h = np.asarray(heights, np.float64)
    step = np.maximum(np.abs(np.diff(h, axis=0))[:, :-1], np.abs(np.diff(h, axis=1))[:-1, :])
    return np.array([np.mean(step >= s - 1e-9) for s in STEPS])


def _commit(gente: Path) -> str:
    try:
        return subprocess.run(["git", "-C", str(gente), "rev-parse", "HEAD"], capture_output=True, text=True,
                              check=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "an unknown commit (not a git clone)"


def _markdown(s: dict) -> str:
    lines = [
        "# gente_original: GenTe's published transcripts, imported",
        "",
        f"Built by `build.py` from {s['source']}. Per-item detail: `report.json`.",
        "",
        f"- transcripts: {s['transcripts']}; imported as specs: {s['imported']}",
        f"- GenTe tool calls: {s['calls_gente']}; calls with no translated call: {s['calls_blocked']}",
        f"- tools GenTe never declared (invented by the models): {s['invented_tools'] or 'none'}",
        f"- GenTe tools called outside the tool list the model was given: {s['outside_schema'] or 'none'}",
        f"- GenTe tools declared but never called: {s['gente_tools_declared_not_used']}",
        f"- heightmaps: {s['heightmaps']}; wrapped around int16 (overflow): {len(s['heightmaps_overflowed'])} "
        f"{s['heightmaps_overflowed']}; beyond |{MAX_ABS_HEIGHT:g}| m: {s['heightmaps_beyond_bound']}",
        "",
        "| issue | count | meaning |",
        "|---|---:|---|",
    ]
    meaning = {
        "clamped": "a value outside our parameter's range, imported at the nearest bound",
        "coerced": "a value of the wrong JSON type with an obvious meaning ('4' for 4), or a negative size imported as its magnitude (what GenTe would build instead is named)",
        "defaulted": "a value GenTe leaves implicit (no part: part 1; flow speed) filled in",
        "ignored_argument": "an argument with no equivalent in our terrain, not imported",
        "simplified": "a river path imported as a straight river along its direction",
        "outside_schema": "a GenTe tool the model called although its tool list lacked it",
        "no_effect": "a call that draws nothing in GenTe either",
    }
    lines += [f"| {k} | {v} | {meaning.get(k, 'the call was not imported')} |" for k, v in s["issues_by_kind"].items()]
    if s["steps"]:
        st = s["steps"]
        lines += ["", f"Steps between neighbouring cells (0.1 m apart), the share of cells, mean over the {st['tiles']} "
                      f"tiles whose heightmap did not overflow: GenTe's heightmap (`array.npy`) against this import's "
                      f"tile (its random draws are its own, so only such statistics compare)", "",
                  "| step at least | GenTe's heightmaps | this import |", "|---:|---:|---:|"]
        lines += [f"| {h:g} m | {g:.2f} % | {i:.2f} % |" for h, g, i in zip(st["heights_m"], st["gente"], st["import"])]
    lines += ["", "| schema | GenTe tool | calls |", "|---|---|---:|"]
    lines += [f"| {schema} | {tool} | {n} |" for schema, used in s["gente_tools_used"].items() for tool, n in used.items()]
    return "\n".join(lines) + "\n"


def build_heightmaps(gente: Path, out: Path) -> dict:
    """Specs on GenTe's heightmaps in ``out/specs`` (naming the clone's files) and ``out/manifest.json``."""
    (out / "specs").mkdir(parents=True, exist_ok=True)
    items, refused = [], {}
    for item_id, _, kind, folder in transcripts(gente):
        npy = folder / "array.npy"
        if not npy.is_file():
            continue
        try:
            spec = heightmap_spec(str(npy.resolve()), f"{item_id}_heightmap")
        except ValidationError as exc:
            refused[item_id] = str(exc)
            continue
        spec.save(out / "specs" / f"{item_id}.json")
        items.append({"id": item_id, "kind": kind, "spec": f"specs/{item_id}.json"})
    manifest = {"name": "gente_original_heightmaps", "tile_size": [20.0, 20.0], "resolution": 0.1,
                "source": f"github.com/HaronW/GenTe dataset/ at {_commit(gente)}", "items": items}
    (out / "manifest.json").write_text(json.dumps(manifest, indent=1) + "\n")
    return {"written": len(items), "refused": refused}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--gente", type=Path, required=True, help="a clone of https://github.com/HaronW/GenTe")
    p.add_argument("--heightmaps", type=Path, help="instead: write specs on GenTe's heightmaps into this folder")
    args = p.parse_args(argv)
    if args.heightmaps:
        result = build_heightmaps(args.gente, args.heightmaps)
        print(f"{result['written']} heightmap specs in {args.heightmaps}; refused {len(result['refused'])}:")
        for item_id, reason in result["refused"].items():
            print(f"  {item_id}: {reason}")
        return 0
    summary = build(args.gente)
    print(f"imported {summary['imported']} of {summary['transcripts']} transcripts into {OUT}; invented tools: "
          f"{summary['invented_tools'] or 'none'}; overflowed heightmaps: {len(summary['heightmaps_overflowed'])}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
