"""GenTe compatibility: tool translation (values by hand), reporting, heightmap overflow, the toolset, the benchmark.

The transcripts here are made up in GenTe's format; GenTe's own scene texts are not used in tests.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from test_generation_openai import FakeServer, _completion, ok

from legged_gente.generation.backends import GenerationError
from legged_gente.generation.backends.openai_backend import OpenAIBackend
from legged_gente.generation.gente_compat import (
    GENTE_TOOLS,
    gente_tool_schemas,
    import_heightmap,
    import_transcript,
    translate_call,
)
from legged_gente.generation.spec import TerrainSpec

ROOT = Path(__file__).resolve().parents[1]


def _gcall(name, args, i=0):
    return {"id": f"g{i}", "type": "function", "function": {"name": name, "arguments": args if isinstance(args, str) else json.dumps(args)}}


def test_parts_and_additive_heights():
    t = translate_call("flat_ground_terrain", {"terrain": "previous_terrain", "height": 0.3, "part": 4})
    assert not t.issues and len(t.calls) == 1
    c = t.calls[0]
    # GenTe's part 4 is the second half along both x and y: our front-left quadrant; GenTe adds heights
    assert (c.tool, c.region, c.mode, c.params["height"]) == ("flat", "front_left", "add", 0.3)
    assert translate_call("flat_ground_terrain", {"height": 0.1, "part": 2}).calls[0].region == "front_right"
    assert translate_call("flat_ground_terrain", {"height": 0.1}, schema="single").calls[0].region == "full"
    defaulted = translate_call("flat_ground_terrain", {"height": 0.1})
    assert defaulted.calls[0].region == "back_right" and defaulted.issues[0].kind == "defaulted"


def test_unit_conversions_by_hand():
    # waves: 2 periods across a 10 m part -> 5 m wavelength; amplitude kept (GenTe: amp/2 * (cos + sin))
    w = translate_call("wave_terrain", {"num_waves": 2, "amplitude": 0.2, "part": 1}).calls[0].params
    assert w["wavelength"] == pytest.approx(10.0 / 2) and w["amplitude"] == pytest.approx(0.2)
    # 20 blocks on a 10 m x 10 m part -> 0.2 blocks per m^2
    o = translate_call("discrete_obstacles_terrain", {"max_height": 0.2, "min_size": 0.4, "max_size": 1.0,
                                                      "num_rects": 20, "part": 3}).calls[0].params
    assert o["density"] == pytest.approx(20 / (10.0 * 10.0))
    # a slope of 0.1 m/m to the centre of a 10 m part: peak 0.1 * (5 + 5) = 1.0 m; our slope atan(0.1) falls away
    flat, pyr = translate_call("sloped_terrain", {"slope": 0.1, "part": 1}).calls
    assert flat.params["height"] == pytest.approx(1.0)
    assert pyr.params["slope"] == pytest.approx(math.atan(0.1)) and pyr.params["direction"] == "down"
    # uniform heights in [0, 0.2] m -> 0.1 m offset + +-0.1 m; step 1 -> int(1 / 0.1) * 0.005 = 0.05 m
    off, uni = translate_call("random_uniform_terrain", {"min_height": 0.0, "max_height": 0.2, "step": 1,
                                                         "downsampled_scale": 5, "part": 1}).calls
    assert off.params["height"] == pytest.approx(0.1) and uni.params["amplitude"] == pytest.approx(0.1)
    assert uni.params["step"] == pytest.approx(0.05) and uni.params["spacing"] == pytest.approx(0.5)
    # no step given: GenTe's function runs with its default step=1, so 0.05 m again
    _, uni = translate_call("random_uniform_terrain", {"min_height": 0.0, "max_height": 0.2, "part": 1}).calls
    assert uni.params["step"] == pytest.approx(0.05)
    # gap depth in 0.005 m units: 200 -> 1.0 m
    assert translate_call("gap_terrain", {"gap_size": 0.5, "depth": 200, "part": 1}).calls[0].params["depth"] == pytest.approx(1.0)


def test_physical_tools_map_to_water_and_soil():
    (w,) = translate_call("water_resistance_terrain", {"depth": 0.4, "part": 2}).calls
    assert (w.tool, w.params["depth"], w.params["flow"], w.mode) == ("water", 0.4, "still", None)
    t = translate_call("water_wave_terrain", {"water_type": "tide", "part": 2})
    assert t.calls[0].params["flow"] == "tide" and t.issues[0].kind == "defaulted"
    s = translate_call("deformable_terrain", {"singkage": 0.05, "terrain_type": "sand", "part": 1})
    assert s.calls[0].params["preset"] == "dry_sand" and s.issues[0].kind == "ignored_argument"


def test_nothing_is_dropped_silently():
    clamped = translate_call("stairs_terrain", {"step_width": 0.3, "step_height": 30, "part": 1})
    assert clamped.calls[0].params["step_height"] == 0.3
    assert [i.kind for i in clamped.issues] == ["clamped"] and "step_height=30" in clamped.issues[0].message
    invented = translate_call("lava_terrain", {"heat": 3})
    assert invented.blocked and not invented.calls and invented.issues[0].kind == "invented_tool"
    missing = translate_call("random_gaussian_terrain", {"mean_height": 0, "std_dev": 1})
    assert missing.blocked and missing.issues[0].kind == "no_equivalent"
    outside = translate_call("natural_ground_terrain", {"height_multiplier": 0.1, "part": 1}, schema="multi")
    assert outside.calls and outside.issues[0].kind == "outside_schema"
    extra = translate_call("flat_ground_terrain", {"height": 0.1, "part": 1, "colour": "red"})
    assert extra.calls and extra.issues[0].kind == "ignored_argument" and "colour" in extra.issues[0].message
    bad = translate_call("flat_ground_terrain", {"height": "high", "part": 1})
    assert bad.blocked and bad.issues[-1].kind == "bad_value"


def test_python_literal_arguments_are_parsed_never_run(tmp_path):
    # GenTe's models wrote Python (".5", implicit string concatenation); GenTe eval'd it
    t = translate_call("gap_terrain", '{"gap_size": .5, "platform_size": 1.5, "part": "4"}')
    assert t.calls[0].params["gap_width"] == 0.5 and t.calls[0].region == "front_left"
    assert [i.kind for i in t.issues] == ["coerced", "clamped"]  # and the default depth 1000 units = 5 m > 2 m
    t = translate_call("flat_ground_terrain", '{"height": 0.2, "" "part": 2}')
    assert t.calls[0].region == "front_right"
    marker = tmp_path / "ran"
    for payload in (f'__import__("pathlib").Path({str(marker)!r}).touch()', '{"height": (lambda: 1)(), "part": 1}',
                    "[" * 5000 + "]" * 5000, "x" * 100_000):
        t = translate_call("flat_ground_terrain", payload)
        assert t.blocked and t.issues[0].kind == "unreadable_arguments"
    assert not marker.exists()


def test_transcript_import_reports_and_validates():
    data = {"scene_description": "not read", "tool_calls": [
        _gcall("flat_ground_terrain", {"terrain": "init_terrain", "height": 0.2, "part": 1}, 0),
        _gcall("lava_terrain", {"part": 2}, 1),
        _gcall("generate_river_terrain", {"river_width": 3, "river_depth": 0.4, "river_path": [[0, 0], [0, 50]],
                                          "bank_height": 0.2, "part": 3}, 2),
    ]}
    result = import_transcript(data, "made_up", "multi")
    assert [c.tool for c in result.spec.calls] == ["flat", "river"]
    river = result.spec.calls[1].params
    assert river["direction"] == pytest.approx(math.pi / 2)  # the path runs along +y
    kinds = [i.kind for i in result.issues]
    assert "invented_tool" in kinds and "simplified" in kinds and "ignored_argument" in kinds
    assert "made_up" == result.spec.name and "scene" not in json.dumps(result.spec.to_dict())
    heights, _ = result.spec.build()
    assert heights.shape == (200, 200)
    assert import_transcript({"tool_calls": []}, "x", "multi").spec is None


def test_heightmap_overflow_detection():
    ramp = np.arange(200, dtype=np.int32)[:, None] * np.ones((1, 200), np.int32)
    fine = (ramp * 10).astype(np.int16)  # at most 1990 units = 9.95 m
    hm = import_heightmap(fine)
    assert not hm.overflowed and hm.heights[199, 0] == pytest.approx(1990 * 0.005)
    wrapped = (ramp * 200).astype(np.int16)  # 199 * 200 = 39800 > 32767: wraps once, between rows 163 and 164
    hm = import_heightmap(wrapped)
    assert hm.overflowed and hm.wrap_edges == 200
    with pytest.raises(ValueError, match="2-D int16"):
        import_heightmap(np.zeros((4, 4), np.float32))


def test_gente_schemas_are_gentes_tool_lists():
    multi = {t["function"]["name"]: t["function"] for t in gente_tool_schemas("multi")}
    single = {t["function"]["name"]: t["function"] for t in gente_tool_schemas("single")}
    assert set(multi) == {n for n, t in GENTE_TOOLS.items() if "multi" in t.schemas} - {"random_gaussian_terrain"}
    assert "natural_ground_terrain" in single and "natural_ground_terrain" not in multi
    assert "part" in multi["sloped_terrain"]["parameters"]["properties"]
    assert "part" not in single["sloped_terrain"]["parameters"]["properties"]
    assert multi["deformable_terrain"]["parameters"]["properties"]["terrain_type"]["enum"] == ["wet soil", "dry soil", "sand"]


def test_openai_backend_serves_gentes_tools_and_translates():
    prompt = "A made-up GenTe-style prompt: a stream by a slope. Use part 1 to 4."
    first = _completion([_gcall("flat_ground_terrain", {"terrain": "init_terrain", "height": 0.2, "part": 2}, 0),
                         _gcall("volcano_terrain", {"part": 1}, 1)])
    second = _completion([_gcall("water_resistance_terrain", {"terrain": "previous_terrain", "depth": 0.3, "part": 1}, 2)])
    with FakeServer([ok(first), ok(second)]) as srv:
        result = OpenAIBackend(srv.url, "m", toolset="gente", timeout=5.0).generate(text=prompt)
    assert [(c.tool, c.region) for c in result.calls] == [("flat", "front_right"), ("water", "back_right")]
    req = srv.requests[0]
    assert {t["function"]["name"] for t in req["tools"]} == {t["function"]["name"] for t in gente_tool_schemas("multi")}
    assert req["messages"] == [{"role": "user", "content": [{"type": "text", "text": prompt}]}]  # the prompt unchanged
    rejection = [m for m in srv.requests[1]["messages"] if m["role"] == "tool" and m["tool_call_id"] == "g1"][0]
    assert "REJECTED" in rejection["content"] and "volcano_terrain" in rejection["content"]
    with pytest.raises(ValueError, match="unknown toolset"):
        OpenAIBackend("http://127.0.0.1:9", "m", toolset="genty")


def test_gente_toolset_rejects_stacks_beyond_the_bound():
    calls = [_gcall("flat_ground_terrain", {"height": 2.0, "part": 1}, i) for i in range(6)]  # 12 m on one part
    with FakeServer([ok(_completion(calls))]) as srv:
        with pytest.raises(GenerationError, match=r"reach 12.00 m > 10.0 m"):
            OpenAIBackend(srv.url, "m", toolset="gente", timeout=5.0, max_retries=0).generate(text="x")


def test_converter_on_a_made_up_clone(tmp_path, load_file):
    build = load_file("legged_gente/benchmarks/gente_original/build.py")
    for i, (part, kind) in enumerate([("single_part", "txt"), ("multi_parts", "image")], start=1):
        folder = tmp_path / "GenTe" / "dataset" / part / kind / str(i)
        folder.mkdir(parents=True)
        calls = [_gcall("flat_ground_terrain", {"height": 0.1, "part": 2}), _gcall("made_up_terrain", {})]
        (folder / "data.json").write_text(json.dumps({"scene_description": "SECRET SCENE", "tool_calls": calls}))
        np.save(folder / "array.npy", (np.arange(200)[:, None] * np.full((1, 200), 300)).astype(np.int16))
    summary = build.build(tmp_path / "GenTe", tmp_path / "out")
    assert summary["transcripts"] == 2 and summary["imported"] == 2 and summary["invented_tools"] == ["made_up_terrain"]
    assert len(summary["heightmaps_overflowed"]) == 2
    written = "".join(p.read_text() for p in (tmp_path / "out").rglob("*.*"))
    assert "SECRET SCENE" not in written
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert [i["id"] for i in manifest["items"]] == ["single_text_01", "multi_image_02"]


def test_converter_writes_heightmap_specs(tmp_path, load_file):
    from legged_gente.evaluation.benchmark import load_benchmark

    build = load_file("legged_gente/benchmarks/gente_original/build.py")
    ramp = np.arange(200)[:, None] * np.ones((1, 200), np.int64)
    for i, units in enumerate([5, 200], start=1):  # 199 * 5 = 995 units; 199 * 200 = 39800 wraps around int16
        folder = tmp_path / "GenTe" / "dataset" / "multi_parts" / "image" / str(i)
        folder.mkdir(parents=True)
        (folder / "data.json").write_text(json.dumps({"tool_calls": []}))
        np.save(folder / "array.npy", (ramp * units).astype(np.int16))
    result = build.build_heightmaps(tmp_path / "GenTe", tmp_path / "hm")
    assert result["written"] == 1 and list(result["refused"]) == ["multi_image_02"]
    assert "wrapped around the int16 range" in result["refused"]["multi_image_02"]
    (item,) = load_benchmark(tmp_path / "hm")
    heights, _ = item.spec().build()
    assert heights[199, 7] == pytest.approx(199 * 5 * 0.005)  # 4.975 m at the far edge
    assert not list((tmp_path / "hm").rglob("*.npy"))  # the clone's files are named, not copied


def test_the_shipped_benchmark_loads():
    from legged_gente.evaluation.benchmark import load_benchmark

    root = ROOT / "legged_gente" / "benchmarks" / "gente_original"
    items = load_benchmark("gente_original")  # shipped: found by name from any directory
    assert all(i.spec_path.is_relative_to(root) for i in items)
    summary = json.loads((root / "report.json").read_text())["summary"]
    assert len(items) == summary["imported"] == 200 and {i.kind for i in items} == {"text", "image"}
    assert all(i.prompt is None and i.image is None for i in items)  # no GenTe scene text or photo in the project
    for item in items[::25]:
        heights, _ = item.spec().build()
        assert np.isfinite(heights).all() and np.abs(heights).max() <= 10.0
    assert isinstance(TerrainSpec.load(items[0].spec_path), TerrainSpec)


def test_cli_toolset_gente(tmp_path, capsys):
    from legged_gente.scripts.generate import main

    reply = _completion([_gcall("flat_ground_terrain", {"height": 0.2, "part": 4}, 0),
                         _gcall("stairs_terrain", {"step_width": 0.3, "step_height": 30, "part": 1}, 1)])
    corrected = _completion([_gcall("stairs_terrain", {"step_width": 0.3, "step_height": 0.2, "part": 1}, 2)])
    with FakeServer([ok(reply), ok(corrected)]) as srv:
        code = main(["--text", "made-up prompt", "--backend", "openai", "--base-url", srv.url, "--model", "m",
                     "--toolset", "gente", "--out", str(tmp_path / "g")])
    captured = capsys.readouterr()
    assert code == 0 and "flat(" in captured.out and "stairs(" in captured.out
    assert "rejected: stairs_terrain: step_height=30" in captured.err  # the rejection is a printed warning
    spec = TerrainSpec.load(tmp_path / "g" / "spec.json")
    assert spec.source["toolset"] == "gente" and [c.region for c in spec.calls] == ["front_left", "back_right"]
    with pytest.raises(SystemExit):
        main(["--text", "x", "--toolset", "gente", "--out", str(tmp_path / "p")])  # the planner has our tools only


def test_every_gente_tool_is_in_the_documented_mapping_table():
    docs = (ROOT / "docs" / "generation.md").read_text()
    assert [name for name in GENTE_TOOLS if f"`{name}(" not in docs] == []


@pytest.mark.parametrize("name, args, param, value, reported", [
    ("natural_ground_terrain", {"height_multiplier": -0.2}, "amplitude", 0.2,
     [("coerced", "height_multiplier=-0.2 is negative (GenTe turns its noise upside down: relief of the same kind); "
                  "imported as 0.2.")]),
    ("generate_river_terrain", {"river_width": 2, "river_depth": -0.4, "bank_height": 0.2}, "depth", 0.4,
     [("coerced", "river_depth=-0.4 is negative (GenTe would raise the river above its surroundings); imported as 0.4.")]),
    ("discrete_obstacles_terrain", {"max_height": -0.2, "min_size": 0.5, "max_size": 1, "num_rects": 20}, "max_height", 0.2,
     [("coerced", "max_height=-0.2 is negative (GenTe's blocks rise and sink by it either way); imported as 0.2.")]),
    ("wave_terrain", {"num_waves": 2, "amplitude": -0.2}, "amplitude", 0.2,
     [("coerced", "amplitude=-0.2 is negative (GenTe draws the same waves shifted by half a period); imported as 0.2.")]),
    ("stepping_stones_terrain", {"stone_size": 0.5, "stone_distance": 0.2, "max_height": -0.05, "depth": -0.5}, "depth", 0.5,
     [("coerced", "max_height=-0.05 is negative (GenTe declares it a height); imported as 0.05."),
      ("coerced", "depth=-0.5 is negative (GenTe declares it a depth); imported as 0.5.")]),
    ("gap_terrain", {"gap_size": 0.5, "depth": -200}, "depth", 1.0,
     [("coerced", "depth=-200 is negative (GenTe would raise a wall around the platform instead of a trench); "
                  "imported as 200.")]),
    ("pit_terrain", {"depth": -0.5, "platform_size": 1}, "depth", 0.5,
     [("coerced", "depth=-0.5 is negative (GenTe would raise a block instead of digging a pit); imported as 0.5.")]),
    ("water_resistance_terrain", {"depth": -0.4}, "depth", 0.4,
     [("coerced", "depth=-0.4 is negative (GenTe declares it a depth); imported as 0.4.")]),
    ("random_uniform_terrain", {"min_height": 0.2, "max_height": 0.0}, "amplitude", 0.1,
     [("clamped", "min_height=0.2 > max_height=0; imported swapped.")]),
])
def test_a_value_changed_in_translation_is_reported(name, args, param, value, reported):
    t = translate_call(name, args | {"part": 1}, None)
    assert t.calls[-1].params[param] == pytest.approx(value)
    assert [(i.kind, i.message) for i in t.issues if i.kind in ("coerced", "clamped")] == reported


def test_negative_step_heights_are_stairs_going_down():
    # GenTe's stairs rise with +x and its pyramid's towards the centre; a negative step_height reverses them
    stairs = translate_call("stairs_terrain", {"step_width": 0.3, "step_height": -0.1, "part": 1})
    pyramid = translate_call("pyramid_stairs_terrain", {"step_width": 0.3, "step_height": -0.1, "part": 1})
    assert not stairs.issues and not pyramid.issues
    assert [(c.params["step_height"], c.params["direction"]) for c in stairs.calls + pyramid.calls if c.tool != "flat"] == [(0.1, "down"), (0.1, "up")]


@pytest.mark.parametrize("name, args, message", [
    ("natural_ground_terrain", {"octaves": 2.4}, "natural_ground_terrain: octaves=2.4 is not a whole number; GenTe "
                                                 "declares it an integer."),
    ("discrete_obstacles_terrain", {"max_height": 0.2, "min_size": 0.5, "max_size": 1, "num_rects": 20.7},
     "discrete_obstacles_terrain: num_rects=20.7 is not a whole number; GenTe declares it an integer."),
    ("wave_terrain", {"num_waves": 1.5}, "wave_terrain: num_waves=1.5 is not a whole number; GenTe declares it an integer."),
])
def test_integer_arguments_must_be_whole_numbers(name, args, message):
    t = translate_call(name, args | {"part": 1}, None)
    assert t.blocked and not t.calls and [(i.kind, i.message) for i in t.issues] == [("bad_value", message)]
    whole = translate_call("natural_ground_terrain", {"octaves": 3.0, "part": 1}, None).calls[0].params["octaves"]
    assert whole == 3 and isinstance(whole, int)


def test_a_live_model_corrects_values_outside_our_range_that_an_import_clamps():
    """A live model is told the range and corrects the value; a recorded transcript cannot be, so it is clamped."""
    call = {"step_width": 0.3, "step_height": 30, "part": 1}
    first = _completion([_gcall("flat_ground_terrain", {"height": 0.2, "part": 4}, 0), _gcall("stairs_terrain", call, 1)])
    second = _completion([_gcall("stairs_terrain", call | {"step_height": 0.2}, 2)])
    with FakeServer([ok(first), ok(second)]) as srv:
        result = OpenAIBackend(srv.url, "m", toolset="gente", timeout=5.0).generate(text="x")
    assert [(c.tool, c.params.get("step_height")) for c in result.calls] == [("flat", None), ("stairs", 0.2)]
    (rejection,) = [m["content"] for m in srv.requests[1]["messages"] if m["role"] == "tool" and m["tool_call_id"] == "g1"]
    assert rejection.startswith("REJECTED: stairs_terrain: step_height=30 gives stairs.step_height=30 m, outside our "
                                "range [0.0, 0.3]; send a value inside it.")
    assert not any("imported as" in w for w in result.warnings)
    imported = import_transcript({"tool_calls": [_gcall("stairs_terrain", call)]}, "t", "multi")
    assert imported.spec.calls[0].params["step_height"] == 0.3
    assert [(i.kind, i.message) for i in imported.issues] == [
        ("clamped", "step_height=30 gives stairs.step_height=30 m, outside our range [0.0, 0.3]; imported as 0.3.")]


def test_a_live_gente_call_finer_than_the_cells_goes_back_to_the_model():
    """At --resolution 0.5 a 0.3 m tread is under one cell: the live model is told so and corrects it, as with our
    own tools, instead of the finished spec failing its grid check with no round left to fix it."""
    fine = {"step_width": 0.3, "step_height": 0.1, "part": 1}
    first = _completion([_gcall("stairs_terrain", fine, 0)])
    second = _completion([_gcall("stairs_terrain", fine | {"step_width": 1.0}, 1)])
    with FakeServer([ok(first), ok(second)]) as srv:
        result = OpenAIBackend(srv.url, "m", toolset="gente", timeout=5.0, resolution=0.5).generate(text="x")
    assert [(c.tool, c.params["step_width"]) for c in result.calls] == [("stairs", 1.0)]
    (rejection,) = [m["content"] for m in srv.requests[1]["messages"] if m["role"] == "tool" and m["tool_call_id"] == "g0"]
    assert rejection.startswith("REJECTED: stairs_terrain -> stairs:") and "0.5 m cell" in rejection


def test_a_transcript_of_too_many_calls_is_refused_whole_not_cut():
    call = _gcall("flat_ground_terrain", {"terrain": "init_terrain", "height": 0.2, "part": 1})
    result = import_transcript({"tool_calls": [call] * 257}, "long", "multi")
    assert result.spec is None and result.error == "the transcript has 257 tool calls; at most 256 are read"
    assert "at most 256" not in (import_transcript({"tool_calls": [call] * 256}, "long", "multi").error or "")


@pytest.mark.parametrize("size", [(20.0, 20.0), (12.0, 8.0)])
def test_live_gente_toolset_spec_is_smoothed_across_its_seams_as_gente_smooths(tmp_path, size):
    """GenTe's dataset script smooths every tile after its calls (2 m bands either side of the seams between the
    four parts, sigma 2 cells of 0.1 m); a live ``--toolset gente`` spec must carry the same filters, the seams at
    the middle of whatever tile it builds and the bands cut at the tile's edges."""
    from legged_gente.generation.pipeline import generate_spec

    sx, sy = size
    reply = _completion([_gcall("flat_ground_terrain", {"height": 0.2, "part": 4}, 0)])
    with FakeServer([ok(reply)]) as srv:
        spec, _ = generate_spec(text="x", backend="openai", base_url=srv.url, model="m", toolset="gente",
                                size_x=sx, size_y=sy)
    hx, hy, band = sx / 2, sy / 2, 2.0
    x_lo, x_hi = max(hx - band, 0.0), min(hx + band, sx)
    y_lo, y_hi = max(hy - band, 0.0), min(hy + band, sy)
    expected = [({"x0": x_lo, "y0": 0.0, "x1": x_hi, "y1": hy}, "x"), ({"x0": x_lo, "y0": hy, "x1": x_hi, "y1": sy}, "x"),
                ({"x0": 0.0, "y0": y_lo, "x1": hx, "y1": y_hi}, "y"), ({"x0": hx, "y0": y_lo, "x1": sx, "y1": y_hi}, "y")]
    assert [(f["region"], f["axis"]) for f in spec.smoothing] == expected
    assert all(f["sigma"] == pytest.approx(0.2) for f in spec.smoothing)
    heights, _ = spec.build()
    assert np.isfinite(heights).all()


def test_a_live_model_is_offered_only_tools_that_translate_and_told_what_to_call_instead():
    """A live model (``--toolset gente``) is never offered a tool whose every call is refused; a call of one (or of
    a tool never offered) is answered with the tools to call, all of them, and the refusal's reason comes first."""
    offered = {t["function"]["name"] for t in gente_tool_schemas("multi")}
    assert "random_gaussian_terrain" not in offered and "random_uniform_terrain" in offered
    assert offered == {n for n, t in GENTE_TOOLS.items() if "multi" in t.schemas and t.translate is not None}
    gaussian = translate_call("random_gaussian_terrain", {"mean_height": 0, "std_dev": 0.1, "part": 1}, live=True)
    assert gaussian.blocked and "random_uniform_terrain" in gaussian.issues[0].message
    assert "reported" not in gaussian.issues[0].message
    invented = translate_call("volcano_terrain_" + "x" * 200, {"part": 1}, live=True)
    message = invented.issues[0].message
    assert all(name in message for name in offered) and "random_gaussian_terrain" not in message
    calls = [_gcall("volcano_terrain_" + "x" * 200, {"part": 1}, 0), _gcall("random_gaussian_terrain", {"mean_height": 0, "std_dev": 0.1, "part": 2}, 1),
             _gcall("stairs_terrain", {"step_width": 0.3, "step_height": 5.0}, 2)]
    with FakeServer([ok(_completion(calls)), ok(_completion([]))]) as srv:
        with pytest.raises(GenerationError):
            OpenAIBackend(srv.url, "m", toolset="gente", timeout=5.0, max_retries=1).generate(text="x")
        replies = {m["tool_call_id"]: m["content"] for m in srv.requests[1]["messages"] if m["role"] == "tool"}
    assert all(name in replies["g0"] for name in offered) and "characters in all" not in replies["g0"]  # not cut
    assert "random_uniform_terrain" in replies["g1"]
    # the refusal's reason first, the note that part 1 was taken after it
    assert replies["g2"].startswith("REJECTED: stairs_terrain: step_height=5"), replies["g2"]
    assert "default part 1" in replies["g2"]
