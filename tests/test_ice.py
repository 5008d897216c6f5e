"""Frozen water: level ice at the water's surface, not an empty basin with an icy floor."""

from __future__ import annotations

import numpy as np
import pytest

from legged_gente.generation.backends.planner import CUES, plan_text
from legged_gente.generation.checker import _visible
from legged_gente.generation.score import features
from legged_gente.generation.spec import TerrainSpec
from legged_gente.generation.validation import ValidationError, check_height_stack, validate_call
from legged_gente.terrain.composition import Operation, Part, Region, TileSpec, stacked_height_bounds
from legged_gente.terrain.materials import NO_SOIL, NO_WATER
from legged_gente.terrain.physical import LOW_FRICTION_RANGES
from legged_gente.terrain.registry import ATOMIC_TERRAINS

RES = 0.1


def _pit_tile(*physical: Operation) -> tuple[np.ndarray, np.ndarray, object]:
    """A 6 x 6 m tile of flat ground with a 0.4 m deep, 3 m wide pit in its middle 4 x 4 m, then ``physical``."""
    ground = Part(Region(0, 0, 6, 6), [Operation("flat", {"height": 0.0})])
    pit = Part(Region(1, 1, 5, 5), [Operation("pit", {"depth": 0.4, "width": 3.0}, mode="add")])
    before, _ = TileSpec(6, 6, RES, 0, [ground, pit]).build()
    after, material = TileSpec(6, 6, RES, 0, [ground, pit, Part(Region(1, 1, 5, 5), list(physical))]).build()
    return before, after, material


def test_ice_fills_a_depression_to_a_level_surface_of_ice_friction():
    before, after, material = _pit_tile(Operation("ice", {"depth": 0.3}))
    window = np.s_[10:50, 10:50]
    surface = before[window].min() + 0.3  # ice stands 0.3 m above the region's lowest ground, as water would
    filled = np.zeros(before.shape, bool)
    filled[window] = before[window] < surface
    assert filled.sum() > 0.5 * (30 * 30)  # most of the 3 x 3 m pit floor
    np.testing.assert_allclose(after[filled], surface, atol=1e-6)
    np.testing.assert_array_equal(after[~filled], before[~filled])  # ground above the ice is left as it was
    lo, hi = LOW_FRICTION_RANGES["ice"]
    assert np.all((material.friction[filled] >= lo) & (material.friction[filled] <= hi))
    assert np.all(material.friction[~filled] == material.friction[0, 0])  # the rim keeps the ground's friction
    assert not material.has_water().any()
    # the step down from the rim to the ice: pit depth 0.4 less the ice's 0.3 (it was 0.4 into an empty pit)
    assert after[30, 30] - after[0, 0] == pytest.approx(-0.1, abs=1e-6)


def test_ice_freezes_water_painted_before_it():
    _, _, material = _pit_tile(Operation("water", {"depth": 0.3}), Operation("ice", {"depth": 0.3}))
    assert not material.has_water().any()
    # thinner ice leaves the water above it: a frozen floor under 0.1 m of water
    _, after, material = _pit_tile(Operation("water", {"depth": 0.3}), Operation("ice", {"depth": 0.2}))
    wet = material.has_water()
    assert wet[30, 30]
    assert material.water_surface[30, 30] - after[30, 30] == pytest.approx(0.1, abs=1e-6)
    assert np.all(material.water_surface[~wet] == NO_WATER)


def test_ice_deeper_than_its_depression_raises_a_level_plateau():
    before, after, _ = _pit_tile(Operation("ice", {"depth": 0.6}))
    surface = before[10:50, 10:50].min() + 0.6
    np.testing.assert_allclose(after[10:50, 10:50], surface, atol=1e-6)  # 0.2 m above the ground around
    assert after[5, 5] == before[5, 5]


def test_a_frozen_lake_is_level_ice_at_its_water_surface():
    plan = plan_text("a frozen lake")
    tools = [c.tool for c in plan.calls]
    assert "water" not in tools and tools.count("ice") == 1
    lake_water = [c for c in plan_text("a lake").calls if c.tool == "water"][0]
    ice = [c for c in plan.calls if c.tool == "ice"][0]
    assert ice.params["depth"] == lake_water.params["depth"] and ice.region == lake_water.region
    heights, material = TerrainSpec(plan.calls, name="lake").build()
    dry_heights, dry_material = TerrainSpec(plan_text("a dry lake").calls, name="lake").build()
    x0, y0, x1, y1 = (round(v / 0.1) for v in ice.rect(20.0, 20.0))
    region = np.s_[x0:x1, y0:y1]
    # the water's level turned to ice: 0.3 m above the region's lowest ground, which the dry lake leaves bare
    surface = dry_heights[region].min() + 0.3
    frozen = dry_heights[region] < surface
    assert 0.8 * 60 * 60 < frozen.sum() < 1.2 * 60 * 60  # the 6 m wide pit's floor
    np.testing.assert_allclose(heights[region][frozen], surface, atol=1e-6)
    np.testing.assert_array_equal(heights[region][~frozen], dry_heights[region][~frozen])
    # the pit is 0.4 m deep (0.3 m of water and FREEBOARD): the step from the bank down to the ice is about 0.1 m
    assert float(heights[:x0].mean() - surface) == pytest.approx(0.1, abs=0.03)
    assert not material.has_water().any() and not dry_material.has_water().any()
    assert features(plan.calls) == {"ice"}


def test_ice_is_seen_by_the_checker_and_the_scorer():
    _, after, material = _pit_tile(Operation("ice", {"depth": 0.3}))
    assert _visible("ice", after, material, np.s_[10:50, 10:50], float(material.friction[0, 0]))
    _, after, material = _pit_tile(Operation("ice", {"depth": 0.0}))
    assert not _visible("ice", after, material, np.s_[10:50, 10:50], float(material.friction[0, 0]))


def test_the_checker_bounds_the_heights_ice_makes():
    def op(name, mode="set", **params):
        return Operation(name, ATOMIC_TERRAINS[name].check_params(params), mode=mode)

    ground = Part(Region(0, 0, 6, 6), [op("flat", height=0.0)])
    pit = Part(Region(1, 1, 5, 5), [op("pit", mode="add", depth=0.4, width=3.0), op("ice", depth=0.3)])
    spec = TileSpec(6, 6, RES, 0, [ground, pit])
    bounds = stacked_height_bounds(spec)
    # the pit's cells lie in [-0.4, 0] m; ice lifts the lowest to -0.4 + 0.3 and may lift a cell to 0 + 0.3
    lo, hi = bounds.at(np.array([3.0]), np.array([3.0]))
    assert (float(lo[0]), float(hi[0])) == pytest.approx((-0.1, 0.3))
    lo, hi = bounds.at(np.array([0.5]), np.array([0.5]))  # outside the ice's rectangle: the flat ground
    assert (float(lo[0]), float(hi[0])) == pytest.approx((0.0, 0.0))
    heights, _ = spec.build()
    assert -0.1 - 1e-6 <= heights[30, 30] <= 0.3


def test_ice_stacked_past_the_height_limit_is_refused_before_building():
    # six 2 m layers of ice on flat ground: the sixth would stand at 12 m, past MAX_ABS_HEIGHT (10 m)
    calls = [validate_call("ice", {"depth": 2.0, "region": "full"}, 20.0, 20.0) for _ in range(6)]
    check_height_stack(calls[:5], 20.0, 20.0)  # 10 m: at the limit, allowed
    with pytest.raises(ValidationError, match=r"calls\[5\] \(ice\) can raise the ground to 12.00 m > 10.0 m; "
                                              r"lower its depth or lay it on lower ground\."):
        check_height_stack(calls, 20.0, 20.0)


def test_ice_covers_the_soil_below_it_and_takes_snow_painted_after_it():
    mud = Operation("soil", {"preset": "mud"})
    _, after, material = _pit_tile(mud, Operation("ice", {"depth": 0.3}))
    frozen = material.friction < 0.5
    assert frozen.any() and (~frozen[10:50, 10:50]).any()
    assert np.all(material.soil[frozen] == NO_SOIL)  # a frozen bog is ice to walk on
    assert np.all(material.soil[10:50, 10:50][~frozen[10:50, 10:50]] != NO_SOIL)  # the bank stays mud
    _, _, material = _pit_tile(Operation("ice", {"depth": 0.3}), Operation("soil", {"preset": "snow"}))
    assert np.all(material.soil[10:50, 10:50] != NO_SOIL)  # snow on the ice


def test_frozen_water_is_slippery_where_it_is_ice_and_icy_ground_without_water_everywhere():
    lake = plan_text("a frozen lake")
    assert "low_friction" not in [c.tool for c in lake.calls]  # the banks are frozen ground, not glare ice
    heights, material = TerrainSpec(lake.calls, name="lake").build()
    ice = [c for c in lake.calls if c.tool == "ice"][0]
    x0, y0, x1, y1 = (round(v / 0.1) for v in ice.rect(20.0, 20.0))
    slippery = material.friction < 0.5
    assert slippery[x0:x1, y0:y1].sum() == slippery.sum() > 0.8 * 60 * 60  # the pond's floor only
    lo, hi = LOW_FRICTION_RANGES["ice"]
    assert np.all((material.friction[slippery] >= lo) & (material.friction[slippery] <= hi))
    # with no water to freeze, "icy" still makes the cue's ground icy
    path = [c for c in plan_text("an icy path").calls if c.tool == "low_friction"]
    assert [c.params["preset"] for c in path] == ["ice"]


@pytest.mark.parametrize("cue", [c for c in CUES if any(s.tool == "water" for s in c.steps)], ids=lambda c: c.name)
def test_every_frozen_water_cue_is_ice_inside_its_depression(cue):
    """The planner holds each cue's water in a depression FREEBOARD deeper; frozen, that water is ice below its banks:
    no ice cell stands more than 2 cm above a 4-neighbour that is not ice (an ice plateau's edge)."""
    plan = plan_text(f"a frozen {cue.keywords[0]} next to stone stairs")
    assert "water" not in [c.tool for c in plan.calls] and "ice" in [c.tool for c in plan.calls]
    heights, material = TerrainSpec(plan.calls, name="frozen").build()
    ice = material.friction < 0.5
    for a, b in ((np.s_[:-1, :], np.s_[1:, :]), (np.s_[1:, :], np.s_[:-1, :]),
                 (np.s_[:, :-1], np.s_[:, 1:]), (np.s_[:, 1:], np.s_[:, :-1])):
        edge = ice[a] & ~ice[b]
        assert not edge.any() or float((heights[a] - heights[b])[edge].max()) <= 0.02


@pytest.mark.parametrize("text", ["a frozen swamp", "a frozen bog beside a path", "a frozen mud field"])
def test_frozen_wet_soil_is_hard_ground(text):
    """Frost hardens a saturated soil: a frozen swamp is ice on its pools and frozen ground on its banks, not mud
    that the feet sink into. Soils without water in them (dry sand, snow) stay as they are."""
    thawed = plan_text(text.replace("frozen ", ""))
    assert any(c.tool == "soil" and c.params["preset"] == "mud" for c in thawed.calls)
    plan = plan_text(text)
    assert not any(c.tool == "soil" and c.params["preset"] in ("mud", "wet_sand", "clay_loam") for c in plan.calls)
    _, material = TerrainSpec(plan.calls, name="frozen").build()
    assert np.all(material.soil == NO_SOIL)
    assert any(c.params.get("preset") == "snow" for c in plan_text("a frozen snowy swamp").calls if c.tool == "soil")


def test_stacked_height_bounds_fills_parameter_defaults_as_the_builder_does():
    """docs/terrain.md's spec, written with only the parameters it changes: bounded as the builder builds it
    (defaults filled, as spec.build() fills them), not a KeyError on the first default."""
    partial = TileSpec(6, 6, RES, 0, [Part(Region(0, 0, 6, 6), [Operation("stairs", {"step_height": 0.12}),
                                                                 Operation("hills", {}, mode="add"),
                                                                 Operation("ice", {})])])
    complete = TileSpec(6, 6, RES, 0, [Part(Region(0, 0, 6, 6), [
        Operation("stairs", ATOMIC_TERRAINS["stairs"].check_params({"step_height": 0.12})),
        Operation("hills", ATOMIC_TERRAINS["hills"].check_params({}), mode="add"),
        Operation("ice", ATOMIC_TERRAINS["ice"].check_params({}))])])
    x, y = np.array([0.5, 3.0, 5.5]), np.array([0.5, 3.0, 5.5])
    np.testing.assert_array_equal(stacked_height_bounds(partial).at(x, y), stacked_height_bounds(complete).at(x, y))
    heights, _ = partial.build()
    lo, hi = stacked_height_bounds(partial).at(np.array([3.0]), np.array([3.0]))
    assert lo[0] - 1e-6 <= heights[30, 30] <= hi[0] + 1e-6
