"""Writes the `steps` benchmark: one 20 m tile per step height, flat ground raised by that height everywhere but a
2 m x 2 m pit at the centre, where the robots spawn. Whatever direction a robot is commanded, it meets a step up of
that height 0.7-1.4 m from its spawn; the velocity task's success then measures whether it climbs it. The step's
face is the composition's seam blend (a smoothstep over 0.3 m, as at every composed region's edge), steepest at
5 x the height per metre: 56 deg for 0.3 m, 68 deg for 0.5 m.

    python legged_gente/benchmarks/steps/build.py
"""

import json
from pathlib import Path

HEIGHTS_CM = (10, 15, 20, 25, 30, 35, 40, 45, 50)
SIZE, PIT = 20.0, 2.0  # m


def spec(height_cm: int) -> dict:
    height = height_cm / 100.0
    lo, hi = (SIZE - PIT) / 2.0, (SIZE + PIT) / 2.0
    raised = [  # four bands around the pit
        {"x0": 0.0, "y0": 0.0, "x1": lo, "y1": SIZE}, {"x0": hi, "y0": 0.0, "x1": SIZE, "y1": SIZE},
        {"x0": lo, "y0": 0.0, "x1": hi, "y1": lo}, {"x0": lo, "y0": hi, "x1": hi, "y1": SIZE},
    ]
    calls = [{"tool": "flat", "region": "full", "params": {}, "mode": "set"}]
    calls += [{"tool": "flat", "region": r, "params": {"height": height}, "mode": "set"} for r in raised]
    return {"version": 1, "name": f"step_{height_cm:02d}cm", "size_x": SIZE, "size_y": SIZE,
            "resolution": 0.1, "seed": 0, "source": {"text": f"a {PIT:g} m pit in ground {height:g} m higher"},
            "backend": "hand-written", "model": None, "calls": calls}


def main() -> None:
    root = Path(__file__).resolve().parent
    (root / "specs").mkdir(exist_ok=True)
    items = []
    for cm in HEIGHTS_CM:
        s = spec(cm)
        (root / "specs" / f"{s['name']}.json").write_text(json.dumps(s, indent=2) + "\n")
        items.append({"id": s["name"], "kind": "text", "prompt": s["source"]["text"], "spec": f"specs/{s['name']}.json"})
    manifest = {"name": "steps", "tile_size": [SIZE, SIZE], "resolution": 0.1, "items": items}
    (root / "manifest.json").write_text(json.dumps(manifest, indent=1) + "\n")


if __name__ == "__main__":
    main()
