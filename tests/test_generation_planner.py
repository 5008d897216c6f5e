"""The offline planner (text): deterministic, sensible calls; specs round-trip and rebuild identically."""

from __future__ import annotations

import json

import numpy as np
import pytest

from legged_gente.generation.backends.planner import CUES, MODIFIERS, NEGATED, Modifier, Step, _apply, plan_text
from legged_gente.generation.score import features
from legged_gente.generation.spec import TerrainSpec, text_source
from legged_gente.generation.tools import tool_schemas
from legged_gente.generation.validation import ValidationError, validate_call
from legged_gente.terrain.registry import ATOMIC_TERRAINS


def test_every_atomic_has_a_valid_schema_and_default_call():
    names = [t["function"]["name"] for t in tool_schemas()]
    assert names == sorted(ATOMIC_TERRAINS) and len(names) >= 18
    for name in names:
        call = validate_call(name, {"region": "full"})
        assert call.params == ATOMIC_TERRAINS[name].check_params({})


def test_recipes_use_registered_tools_only():
    for cue in CUES:
        for step in cue.steps:
            assert step.tool in ATOMIC_TERRAINS, (cue.name, step.tool)
    for mod in MODIFIERS:
        for tool in list(mod.set) + list(mod.scale) + [s.tool for s in mod.extra]:
            assert tool in ATOMIC_TERRAINS, (mod.name, tool)


def _tools(text):
    return [(c.tool, c.params) for c in plan_text(text).calls]


SCENES = {
    "a sandy beach on the shore": {"water", "soil"},
    "a river to cross": {"river", "water"},
    "a small stream in a meadow": {"river", "water", "natural_ground"},
    "a calm lake": {"pit", "water"},
    "desert dunes": {"hills", "soil"},
    "a dense forest": {"pillars", "natural_ground"},
    "a city street with stairs": {"flat", "stairs"},
    "ruins and rubble": {"discrete_obstacles", "rocks"},
    "a construction site": {"flat", "pit", "soil"},
    "fresh snow": {"soil", "natural_ground"},
    "an icy path": {"low_friction"},
    "a muddy swamp": {"soil", "water"},
    "rolling hills": {"hills"},
    "a mountain trail": {"hills", "natural_ground"},
    "a cave": {"rocks", "low_friction"},
}


@pytest.mark.parametrize("text, expected", SCENES.items())
def test_scenes_give_sensible_tools(text, expected):
    result = plan_text(text)
    assert expected <= {c.tool for c in result.calls}
    assert [w for w in result.warnings if "flight of stairs" not in w] == []  # a flight's end drops: said (below)
    # geometry before materials
    kinds = [ATOMIC_TERRAINS[c.tool].kind for c in result.calls]
    assert kinds == sorted(kinds, key=lambda k: k == "physical")


def test_modifiers_change_the_right_values():
    def param(text, tool, name):
        return [p[name] for t, p in _tools(text) if t == tool]

    assert param("a knee-deep river", "water", "depth") == [0.3]
    assert param("an ankle-deep river", "water", "depth")[0] < 0.3
    assert param("a river with a strong current", "water", "speed") == [1.5]
    assert param("a beach with big waves", "water", "flow") == ["tide"]
    assert param("steep stairs", "stairs", "step_height")[0] > param("stairs", "stairs", "step_height")[0]
    assert param("gentle hills", "hills", "amplitude")[0] < param("hills", "hills", "amplitude")[0]
    assert "rocks" in [t for t, _ in _tools("a rocky meadow")]
    assert "low_friction" in [t for t, _ in _tools("slippery stairs")]
    assert "water" in [t for t, _ in _tools("a flooded city street")]
    # negation and nearest-cue attachment
    assert "forest" not in " ".join(plan_text("a meadow, no forest").notes)
    assert "water" not in [t for t, _ in _tools("hills, no river")]
    calls = plan_text("steep stairs next to a calm lake").calls
    assert [c.params["step_height"] for c in calls if c.tool == "stairs"] == [pytest.approx(0.216)]


def test_layout_by_order_of_mention():
    result = plan_text("a forest, then a river, then stairs, then snow")
    assert result.notes == ["forest on back_right", "river on back_left", "stairs on front_right", "snow on front_left"]
    result = plan_text("beach, river, forest, stairs, snow")
    assert any("dropped ['snow']" in w for w in result.warnings)


def test_unknown_text_is_flat_with_a_warning():
    result = plan_text("zzz qqq")
    assert [c.tool for c in result.calls] == ["flat"] and "no scene cue" in result.warnings[0]


def test_modifier_out_of_range_is_clamped_with_a_warning():
    stairs = ATOMIC_TERRAINS["stairs"]
    warnings: list[str] = []
    steep = Modifier("steep", ("steep",), scale={"stairs": {"step_height": 3.0}})
    params = _apply(Step("stairs", {"step_height": 0.2}), [steep], stairs, warnings)
    assert params["step_height"] == stairs.params["step_height"].high
    assert warnings == ["'steep' asks stairs.step_height=0.6 m, outside [0.0, 0.3]; clamped to 0.3."]


def test_modifier_that_does_not_apply_warns():
    assert plan_text("deep snow").warnings == ["modifier 'deep' does not apply to snow; ignored."]
    assert [w for w in plan_text("steep stairs").warnings if "flight" not in w] == []  # 0.12 m * 1.8 = 0.216 m: in range


def test_deterministic_and_round_trip(tmp_path):
    text = "a forest trail along a knee-deep stream, slippery"
    a, b = plan_text(text), plan_text(text)
    assert a.calls == b.calls
    spec = TerrainSpec(a.calls, name="forest_stream", seed=3, source=text_source(text))
    path = spec.save(tmp_path / "spec.json")
    loaded = TerrainSpec.load(path)
    assert loaded == spec
    h1, m1 = spec.build()
    h2, m2 = loaded.build()
    assert h1.shape == (200, 200) and h1.dtype == np.float32
    assert np.array_equal(h1, h2) and np.array_equal(m1.water_surface, m2.water_surface)
    assert np.array_equal(m1.friction, m2.friction) and m1.soil_presets == m2.soil_presets
    assert m1.has_water().any()
    other = TerrainSpec(a.calls, name="forest_stream", seed=4, source=text_source(text)).build()[0]
    assert not np.array_equal(h1, other)


def test_spec_load_errors_are_precise(tmp_path):
    spec = TerrainSpec(plan_text("stairs").calls, name="s")
    data = spec.to_dict()
    data["calls"][0]["params"]["step_height"] = 0.9
    data["version"] = 1
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    with pytest.raises(ValidationError, match=r"bad.json: spec: calls\[0\]: stairs: argument 'step_height'=0.9 is outside"):
        TerrainSpec.load(path)
    data["version"] = 99
    path.write_text(json.dumps(data))
    with pytest.raises(ValidationError, match="field 'version'"):
        TerrainSpec.load(path)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        TerrainSpec.load(tmp_path / "missing.json")


def test_tall_qualifies_trees_not_slopes():
    calls = plan_text("tall trees in a quiet forest").calls
    assert not [c for c in calls if c.tool in ("hills", "pyramid_slope", "stairs")]
    heights = sorted({c.params["height"] for c in calls if c.tool == "pillars"})
    assert heights == [3.0, 4.5]  # the trees' pillars are 1.5 x taller; the forest's keep 3 m
    assert plan_text("a field of tall grass").warnings == ["modifier 'tall' does not apply to grass; ignored."]


def test_state_words_change_the_water():
    assert features(plan_text("a frozen stream").calls) == {"ice"}  # no flowing water under the ice
    assert "water" not in features(plan_text("a frozen lake").calls)
    assert "water" not in features(plan_text("a dry riverbed").calls)
    river = [c.params for c in plan_text("a calm lake next to a river").calls if c.tool == "water"]
    assert sorted(p["flow"] for p in river) == ["current", "still"]  # calm binds to the lake only


def test_shore_is_not_a_tidal_beach():
    calls = plan_text("a grassy shore").calls
    assert features(calls) == {"water"}
    assert {c.params["flow"] for c in calls if c.tool == "water"} == {"still"}


@pytest.mark.parametrize("word", ["building", "wall", "fence", "benches", "fountain", "cliff", "lighthouse",
                                  "lamp posts", "parked cars", "hedge", "statue", "houses"])
def test_structures_and_street_furniture_are_tall_obstacles(word):
    result = plan_text(f"a street with a {word}")
    assert "tall" in features(result.calls) and result.warnings == []


def test_negated_nouns_remove_parts_of_recipes():
    assert "sand" not in features(plan_text("a beach without sand").calls)
    calm = plan_text("a beach with no waves").calls
    assert {c.params["flow"] for c in calm if c.tool == "water"} == {"still"}
    assert "snow" not in features(plan_text("a frozen lake with no snow on it").calls)
    assert set(NEGATED) >= {"sand", "snow", "water", "waves"}


def test_a_long_text_binds_as_its_one_sentence():
    """Binding walks the cues nearest first (bisection over the sorted mentions): a sentence said as often as
    gente-generate's longest text holds it plans what it plans once."""
    once = "Icy stone steps by a calm sea, a deep river beside them. "
    many = once * (10_000 // len(once))
    assert len(many) > 9_900 and plan_text(many).calls == plan_text(once).calls


def test_modifier_binds_to_the_following_noun():
    calls = plan_text("icy stone steps by a calm sea").calls
    stairs = [c.rect(20, 20) for c in calls if c.tool == "stairs"]
    ice = [c.rect(20, 20) for c in calls if c.tool == "low_friction"]
    assert stairs == ice  # the ice lies on the steps, not on the sea
    assert {c.params["flow"] for c in calls if c.tool == "water"} == {"still"}
    snowy = plan_text("a snowy hillside dotted with pine trees").calls
    assert [c.params["preset"] for c in snowy if c.tool == "soil"] == ["snow"]


def test_numbers_the_planner_does_not_read_and_the_words_it_did_are_said():
    """The planner sets sizes from words: "20 cm steps" or "2 m deep" was dropped without a word, and a warning
    about "a high staircase" named the modifier 'tall', a word the user never wrote."""
    warnings = plan_text("stairs with 20 cm steps, then a lake 2 m deep and a slope of 30 degrees").warnings
    said = [w for w in warnings if "numbers" in w]
    assert len(said) == 1 and all(q in said[0] for q in ("'20 cm'", "'2 m'", "'30 degrees'")), warnings
    assert not [w for w in plan_text("a 1.5 m wide ditch of mud").warnings if "'1.5'" in w]  # the quantity is whole
    assert [w for w in plan_text("a 1.5 m wide ditch of mud").warnings if "'1.5 m'" in w]
    assert not [w for w in plan_text("a muddy field").warnings if "numbers" in w]
    assert plan_text("a high staircase").warnings[0] == "modifier 'high' (tall) does not apply to stairs; ignored."
    assert plan_text("a field of tall grass").warnings == ["modifier 'tall' does not apply to grass; ignored."]


def test_a_flight_of_stairs_whose_ends_are_drops_is_said_so():
    """'stairs, then ice': the flight across the back half (10 m of 0.35 m treads, 0.12 m risers: 15 treads either
    side of the middle one, 1.8 m) ends 1.44-1.56 m above and below the ground beside it, with no word."""
    (said,) = [w for w in plan_text("stairs, then ice").warnings if "flight of stairs" in w]
    assert "on back:" in said and "up to 1.56 m below" in said and "up to 1.56 m above" in said
    heights, _ = TerrainSpec(plan_text("stairs, then ice").calls, size_x=20.0, size_y=20.0, resolution=0.1).build()
    assert heights[:100].min() < -1.4 and heights[:100].max() > 1.4  # what it says is there
