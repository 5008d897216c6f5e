"""Fuzz: malformed and adversarial tool calls and spec documents; every accepted one builds, nothing crashes.

Reproducible by seed: ``GENTE_FUZZ_SEED=7 pytest tests/test_generation_fuzz.py`` (default 0); run the file
as a script to print the counts (``python tests/test_generation_fuzz.py [seed] [calls]``).
A crash is any exception other than ValidationError from validation, or any exception from building what
validation accepted.
"""

from __future__ import annotations

import json
import math
import os
import sys
import traceback

import numpy as np

from legged_gente.generation.gente_compat import GENTE_TOOLS, translate_call
from legged_gente.generation.spec import TerrainSpec
from legged_gente.generation.tools import named_regions
from legged_gente.generation.validation import ValidationError, validate_call
from legged_gente.terrain.registry import ATOMIC_TERRAINS

SEED = int(os.environ.get("GENTE_FUZZ_SEED", "0"))
CALLS = 1200
TOOLS = sorted(ATOMIC_TERRAINS)
WEIRD = [float("nan"), float("inf"), -float("inf"), 10**400, -(10**30), 2**53 + 1, True, None, "0.1", [], {}, "",
         "x" * 20_000, 1e308, -1e-320, 0, -0.0]


def _pick(rng, options):
    return options[int(rng.integers(len(options)))]


def _number(rng, param, broken):
    lo = -5.0 if param.low is None else param.low
    hi = 5.0 if param.high is None else param.high
    r = rng.random() if broken else 0.7 * rng.random()
    if r < 0.55:
        v = rng.uniform(lo, hi)
    elif r < 0.7:
        v = float(rng.choice([lo, hi]))  # the bounds themselves
    elif r < 0.85:
        v = float(rng.choice([lo - 1e-9, hi + 1e-9, lo - abs(hi - lo), hi * 10 + 1]))  # just or far outside
    else:
        return _pick(rng, WEIRD)
    return int(round(v)) if param.integer and rng.random() < 0.9 else v


def _value(rng, param, broken):
    if param.choices is not None:
        return str(rng.choice(param.choices)) if not broken or rng.random() < 0.5 else _pick(rng, ["", "lava", "custom", 3, None])
    return _number(rng, param, broken)


def _region(rng, size, broken):
    r = rng.random() if broken else 0.8 * rng.random()
    if r < 0.35:
        return str(rng.choice(list(named_regions(size, size))))
    if r < 0.8:
        x0, x1 = sorted(rng.uniform(0.0, size, 2))
        y0, y1 = sorted(rng.uniform(0.0, size, 2))
        if rng.random() < 0.2:  # thinner than a cell
            x1 = x0 + rng.uniform(0.0, 0.05)
        return {"x0": x0, "y0": y0, "x1": x1, "y1": y1}
    return _pick(rng, [
        {"x0": 0, "y0": 0, "x1": size * 2, "y1": size},  # outside the tile
        {"x0": 3, "y0": 3, "x1": 1, "y1": 4},  # reversed
        {"x0": float("nan"), "y0": 0, "x1": 1, "y1": 1},
        {"x0": 0, "y0": 0, "x1": 1},
        "middle", 7, None, [0, 0, 1, 1],
    ])


def _nested(depth):
    text = "[" * depth + "]" * depth
    return '{"region": "full", "x": ' + text + "}"


def random_call(rng, size):
    """(tool, arguments): usually a plausible call with some broken fields, sometimes garbage."""
    r = rng.random()
    if r < 0.03:
        return str(rng.choice(["lava_lake", "", "flat ", "__import__"])), {"region": "full"}
    tool = str(rng.choice(TOOLS))
    atomic = ATOMIC_TERRAINS[tool]
    if r < 0.08:  # raw text a model might send
        return tool, str(rng.choice([
            "{not json", "", "null", "[1, 2]", '{"region": "full", "amplitude": NaN}', '{"region": "full", "a": 1' + "0" * 5000 + "}",
            _nested(100_000), '{"region": "' + "x" * 1_000_000 + '"}', '{"region": "full", "mode": "set", "mode": "add"}',
        ]))
    broken = rng.random() < 0.4  # else every field is plausible (cross-field rules may still fail)
    args = {}
    for name, param in atomic.params.items():
        if rng.random() < 0.85:
            args[name] = _value(rng, param, broken and rng.random() < 0.5)
    if broken and rng.random() < 0.1:
        args["bogus_" + "k" * int(rng.integers(1, 200))] = 1
    if not broken or rng.random() < 0.9:
        args["region"] = _region(rng, size, broken)
    if atomic.kind == "geometric" and rng.random() < 0.6:
        args["mode"] = str(rng.choice(["set", "add", "add", "replace"]))
    if rng.random() < 0.5:
        return tool, json.dumps(args, allow_nan=True, default=str) if rng.random() < 0.98 else args
    return tool, args


def random_gente_call(rng):
    """A GenTe-format call: GenTe's tools (or invented ones) with numbers from typical to absurd, often as Python text."""
    name = _pick(rng, sorted(GENTE_TOOLS) + ["lava_terrain", "", "__import__"])
    declared = GENTE_TOOLS[name].args if name in GENTE_TOOLS else {"x": None}
    args = {}
    for arg_name, arg in declared.items():
        if rng.random() < 0.15:
            continue
        if arg is not None and arg.enum:
            args[arg_name] = _pick(rng, list(arg.enum) + ["lava"])
        elif arg_name == "river_path":
            args[arg_name] = _pick(rng, [[[0, 0], [5, 9]], "[[10, 15], [15, 20]]", [[1]], "x", []])
        elif arg_name == "terrain":
            args[arg_name] = "previous_terrain"
        else:
            args[arg_name] = float(rng.choice([rng.uniform(-1, 1), rng.uniform(-60, 60), 0.0])) if rng.random() < 0.9 else _pick(rng, WEIRD)
    args["part"] = _pick(rng, [1, 2, 3, 4, 1, 2, 3, 4, "4", 0, 5, None, "x", 2.5])
    r = rng.random()
    if r < 0.3:
        return name, json.dumps(args, default=str).replace("0.", ".")  # Python-style literals such as .5
    if r < 0.35:
        return name, _pick(rng, ["__import__('os')", "{'height': 1}", "{" * 3000, "", "[1, 2]"])
    return name, args


def random_spec_dict(rng, accepted, size, resolution):
    """A spec document from accepted calls (stacked, so heights may exceed the bound) with broken fields."""
    calls = [c.to_dict() for c in accepted[-int(rng.integers(1, 8)):]] if accepted else []
    data = TerrainSpec(calls=[], size_x=size, size_y=size, resolution=resolution, seed=int(rng.integers(0, 100))).to_dict()
    data["calls"] = calls
    r = rng.random()
    if r < 0.1:
        data[str(rng.choice(["size_x", "size_y", "resolution"]))] = _pick(rng, WEIRD)
    elif r < 0.15:
        data["size_x"], data["size_y"], data["resolution"] = 200.0, 200.0, 0.02  # 1e8 cells
    elif r < 0.2:
        data["calls"] = calls * 40
    elif r < 0.25:
        data["model"] = 'x"""\nimport os\n' * 1000
    elif r < 0.3:
        data["size_x"] = size + 0.05  # not a whole number of cells
    return data


def _fuzz_spec(rng, accepted, size, resolution, counts, failures) -> None:
    counts["specs"] += 1
    data = random_spec_dict(rng, accepted, size, resolution)
    try:
        spec = TerrainSpec.from_dict(data)
    except ValidationError:
        counts["specs_rejected"] += 1
        return
    except Exception:  # noqa: BLE001
        counts["crashes"] += 1
        failures.append(f"spec validate: {traceback.format_exc(limit=3)}")
        return
    try:
        heights, _ = spec.build()
        assert np.isfinite(heights).all()
        counts["specs_built"] += 1
    except Exception:  # noqa: BLE001
        counts["crashes"] += 1
        failures.append(f"spec build {[c.tool for c in spec.calls]}: {traceback.format_exc(limit=3)}")


def fuzz(seed: int = SEED, n: int = CALLS) -> dict:
    rng = np.random.default_rng(seed)
    counts = {"calls": 0, "rejected": 0, "accepted_and_built": 0, "specs": 0, "specs_rejected": 0,
              "specs_built": 0, "gente_calls": 0, "gente_blocked": 0, "gente_built": 0, "crashes": 0}
    failures: list[str] = []
    accepted = []
    geometry = (4.0, 0.1)
    for k in range(n):
        if k % 50 == 0:  # a new tile geometry now and then
            geometry = (float(rng.choice([1.0, 2.0, 4.0, 6.0, 20.0])), float(rng.choice([0.05, 0.1, 0.2])))
            accepted = []
        size, resolution = geometry
        if k % 3 == 0:  # a spec document made of the calls accepted so far, stacked and broken
            _fuzz_spec(rng, accepted, size, resolution, counts, failures)
        tool, args = random_call(rng, size)
        counts["calls"] += 1
        try:
            call = validate_call(tool, args, size, size, resolution=resolution)
        except ValidationError as exc:
            counts["rejected"] += 1
            assert all(len(m) <= 500 for m in exc.messages)
            continue
        except Exception:  # noqa: BLE001 - anything else is the bug this test hunts
            counts["crashes"] += 1
            failures.append(f"validate {tool} {str(args)[:200]}: {traceback.format_exc(limit=3)}")
            continue
        try:
            TerrainSpec([call], size_x=size, size_y=size, resolution=resolution, seed=k).validated().build()
            counts["accepted_and_built"] += 1
            accepted.append(call)
        except Exception:  # noqa: BLE001
            counts["crashes"] += 1
            failures.append(f"build {call}: {traceback.format_exc(limit=3)}")
    for k in range(n // 4):  # GenTe-format calls through the translator
        name, args = random_gente_call(rng)
        counts["gente_calls"] += 1
        try:
            translation = translate_call(name, args, str(rng.choice(["single", "multi"])))
        except Exception:  # noqa: BLE001
            counts["crashes"] += 1
            failures.append(f"translate {name} {str(args)[:200]}: {traceback.format_exc(limit=3)}")
            continue
        if translation.blocked or not translation.calls:
            counts["gente_blocked"] += 1
            continue
        try:
            spec = TerrainSpec(translation.calls, seed=k, resolution=0.2).validated()
        except ValidationError:
            counts["gente_blocked"] += 1
            continue
        try:
            spec.build()
            counts["gente_built"] += 1
        except Exception:  # noqa: BLE001
            counts["crashes"] += 1
            failures.append(f"gente build {translation.calls}: {traceback.format_exc(limit=3)}")
    counts["failures"] = failures
    return counts


def test_fuzzed_calls_and_specs_are_rejected_or_build():
    counts = fuzz()
    failures = counts.pop("failures")
    print(f"fuzz seed {SEED}: {counts}")
    assert counts["crashes"] == 0, "\n".join(failures[:5])
    assert counts["calls"] >= 1000
    # Both outcomes are frequent, so the test exercises the validator's accept and reject paths.
    assert counts["rejected"] > 0.2 * counts["calls"] and counts["accepted_and_built"] > 0.2 * counts["calls"]
    assert counts["specs_rejected"] > 0.1 * counts["specs"] and counts["specs_built"] > 0.1 * counts["specs"]
    assert counts["rejected"] + counts["accepted_and_built"] == counts["calls"]
    assert counts["gente_blocked"] > 0.1 * counts["gente_calls"] and counts["gente_built"] > 0.3 * counts["gente_calls"]
    assert math.isfinite(counts["calls"])


if __name__ == "__main__":
    result = fuzz(int(sys.argv[1]) if len(sys.argv) > 1 else SEED, int(sys.argv[2]) if len(sys.argv) > 2 else CALLS)
    for line in result.pop("failures")[:10]:
        print(line)
    print(result)
