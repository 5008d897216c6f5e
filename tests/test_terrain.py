"""Atomic terrains, materials and tile composition (pure numpy, CPU, fast)."""

import json
import subprocess
import sys

import numpy as np
import pytest

from legged_gente.terrain.soil import SOIL_PRESETS
from legged_gente.terrain.composition import (
    MAX_ABS_HEIGHT,
    SEAM_BAND,
    Operation,
    Part,
    Region,
    TileSpec,
    build_tile,
    quadrant,
)
from legged_gente.terrain.materials import FLOW_CURRENT, NO_SOIL, MaterialMap, MaterialPatch
from legged_gente.terrain.registry import ATOMIC_TERRAINS

GEOMETRIC = sorted(n for n, a in ATOMIC_TERRAINS.items() if a.kind == "geometric")
PHYSICAL = sorted(n for n, a in ATOMIC_TERRAINS.items() if a.kind == "physical")
RES = 0.1
EXPECTED = {
    "flat", "pyramid_slope", "random_uniform", "natural_ground", "waves", "stairs", "pyramid_stairs",
    "discrete_obstacles", "stepping_stones", "gap", "pit", "pillars", "rocks", "river", "hills",
    "water", "soil", "low_friction",
}


def heights(name, params, shape=(80, 80), seed=0):
    a = ATOMIC_TERRAINS[name]
    return a.fn(shape, RES, np.random.default_rng(seed), **a.check_params(params))


def test_registry_has_every_atomic_with_docs():
    assert EXPECTED <= set(ATOMIC_TERRAINS)
    for a in ATOMIC_TERRAINS.values():
        assert a.description.endswith(".") and len(a.description) > 10
        for p in a.params.values():
            assert p.doc and (p.choices is not None or (p.low is not None and p.high is not None and p.unit))


def test_terrain_package_imports_no_simulator():
    code = (
        "import sys, legged_gente.terrain.terrain, legged_gente.terrain.composition;"
        "bad = [m for m in ('mujoco', 'mujoco_warp', 'warp', 'torch') if m in sys.modules];"
        "assert not bad, bad"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


@pytest.mark.parametrize("name", GEOMETRIC)
@pytest.mark.parametrize("shape", [(80, 80), (23, 9)])
def test_geometric_finite_bounded_deterministic(name, shape):
    a = ATOMIC_TERRAINS[name]
    for d in (0.0, 0.5, 1.0):
        params = a.params_for_difficulty(d)
        h = a.fn(shape, RES, np.random.default_rng(7), **params)
        assert h.dtype == np.float32 and h.shape == shape
        assert np.all(np.isfinite(h))
        lo, hi = a.height_bounds(params, shape[0] * RES, shape[1] * RES)
        assert lo - 1e-5 <= h.min() and h.max() <= hi + 1e-5, (name, d, h.min(), h.max(), lo, hi)
        assert np.array_equal(h, a.fn(shape, RES, np.random.default_rng(7), **params))


def _max_abs(h):
    return float(np.abs(h).max())


MONOTONE = {
    # terrain -> measure that must not decrease with difficulty (same seed)
    "pyramid_slope": _max_abs,
    "random_uniform": _max_abs,
    "natural_ground": _max_abs,
    "hills": _max_abs,
    "waves": _max_abs,
    "stairs": _max_abs,
    "pyramid_stairs": _max_abs,
    "discrete_obstacles": _max_abs,
    "pit": _max_abs,
    "rocks": _max_abs,
    "river": _max_abs,
    "gap": lambda h: int((h < 0).sum()),
    "pillars": lambda h: int((h > 0).sum()),
}


@pytest.mark.parametrize("name", sorted(MONOTONE))
def test_monotone_in_difficulty(name):
    a = ATOMIC_TERRAINS[name]
    values = [MONOTONE[name](heights(name, a.params_for_difficulty(d), seed=3)) for d in np.linspace(0, 1, 6)]
    assert all(b >= v for v, b in zip(values, values[1:])), values
    assert values[-1] > values[0], values


def test_stepping_stones_harder_means_more_gap():
    a = ATOMIC_TERRAINS["stepping_stones"]
    gaps = [(heights("stepping_stones", a.params_for_difficulty(d), (200, 200)) < -0.1).mean() for d in (0.0, 1.0)]
    assert gaps[1] > gaps[0] + 0.2


def test_spawn_platforms_are_flat():
    for name in GEOMETRIC:
        h = heights(name, {})
        centre = h[35:45, 35:45]
        assert np.ptp(centre) <= 1e-6 or name in ("flat",), name


def test_stairs_have_steps_of_the_declared_height():
    h = heights("stairs", {"step_height": 0.15, "step_width": 0.5, "direction": "up"})
    profile = h[:, 0]
    rises = np.diff(profile)[np.diff(profile) != 0]
    assert np.allclose(rises, 0.15, atol=1e-6)
    # Treads between two rises: 0.5 m / 0.1 m = 5 cells; the landing 1.2 m (the default platform) = 12 cells. The
    # 80 cells hold 6 whole treads each side of the landing, then a cut one (4 cells) at each end.
    edges = np.flatnonzero(np.diff(profile))
    assert np.diff(edges).tolist() == [5] * 6 + [12] + [5] * 6
    down = heights("stairs", {"step_height": 0.15, "step_width": 0.5, "direction": "down"})
    assert np.allclose(down, -h)


@pytest.mark.parametrize("cells", [80, 81])
@pytest.mark.parametrize("platform", [0.0, 0.2])
def test_stairs_without_a_landing_rise_one_step_at_a_time(cells, platform):
    """With a landing narrower than a tread (0: none, as the sketch planner's and GenTe's imported stairs ask for)
    the first step up and the first step down met at the centre in one riser of twice step_height on an even
    number of cells. A flight has one rise per tread: its middle tread (0.5 m = 5 cells) is centred, then treads of
    5 cells each way; 80 cells: 7.5 treads each side of the middle one's 5 cells, cut at the ends."""
    h = heights("stairs", {"step_height": 0.15, "step_width": 0.5, "platform": platform, "direction": "up"},
                (cells, cells))
    profile = h[:, 0]
    rises = np.diff(profile)[np.diff(profile) != 0]
    assert np.allclose(rises, 0.15, atol=1e-6), rises
    edges = np.flatnonzero(np.diff(profile))
    assert np.all(np.diff(edges) == 5), np.diff(edges)
    assert np.all(profile[cells // 2 - 2: (cells + 1) // 2 + 2] == 0.0)  # the middle tread is the level 0
    bound = ATOMIC_TERRAINS["stairs"].height_bounds({"step_height": 0.15, "step_width": 0.5, "platform": platform,
                                                      "direction": "up"}, cells * 0.1, cells * 0.1)
    assert bound[1] >= profile.max() - 1e-6 and bound[0] <= profile.min() + 1e-6


def test_param_validation_errors_are_clear():
    a = ATOMIC_TERRAINS["stairs"]
    with pytest.raises(ValueError, match=r"stairs: step_height=0.9 m is outside \[0.0, 0.3\]"):
        a.check_params({"step_height": 0.9})
    with pytest.raises(ValueError, match="unknown parameter.*'height'.*valid parameters"):
        a.check_params({"height": 0.1})
    with pytest.raises(ValueError, match="not one of"):
        a.check_params({"direction": "sideways"})
    with pytest.raises(ValueError, match="must be a number"):
        a.check_params({"step_width": "wide"})
    with pytest.raises(ValueError, match="min_radius=0.9 must not exceed max_radius=0.2"):
        heights("pillars", {"min_radius": 0.9, "max_radius": 0.2})
    with pytest.raises(ValueError, match="bank_width"):
        heights("river", {"width": 1.0, "bank_width": 0.8})


# ------------------------------------------------------------------------------------------------ physical
def physical(name, params, ground):
    a = ATOMIC_TERRAINS[name]
    return a.fn(ground.shape, RES, np.random.default_rng(0), ground, **a.check_params(params))


def test_water_fills_up_to_depth_above_lowest_ground():
    ground = heights("river", {"depth": 0.5, "width": 3.0})
    patch = physical("water", {"depth": 0.3, "flow": "current", "speed": 0.8}, ground)
    wet = patch.water_surface > -1e8
    assert np.allclose(patch.water_surface[wet], ground.min() + 0.3)
    assert np.array_equal(wet, ground < ground.min() + 0.3)
    assert wet.any() and not wet.all()
    assert patch.flow_kind == FLOW_CURRENT and patch.flow_speed == 0.8


def test_water_depth_monotone_in_difficulty():
    a = ATOMIC_TERRAINS["water"]
    ground = np.zeros((10, 10), np.float32)
    depths = [float(physical("water", a.params_for_difficulty(d), ground).water_surface.max()) for d in (0, 0.5, 1)]
    assert depths[0] < depths[1] < depths[2]


def test_soil_presets_follow_the_forces_module():
    assert set(SOIL_PRESETS) <= set(ATOMIC_TERRAINS["soil"].params["preset"].choices)
    patch = physical("soil", {"preset": "snow"}, np.zeros((4, 4), np.float32))
    assert patch.soil == "snow"
    assert "custom" not in SOIL_PRESETS  # a name for the user's own soils, registered under their own names
    with pytest.raises(ValueError, match="register_custom_soil"):
        physical("soil", {"preset": "custom"}, np.zeros((4, 4), np.float32))


def test_low_friction_presets_and_monotone_difficulty():
    ground = np.zeros((4, 4), np.float32)
    assert 0.05 <= physical("low_friction", {"preset": "ice"}, ground).friction <= 0.10
    assert 0.30 <= physical("low_friction", {"preset": "wet_tiles"}, ground).friction <= 0.40
    assert physical("low_friction", {"preset": "custom", "mu": 0.2}, ground).friction == 0.2
    a = ATOMIC_TERRAINS["low_friction"]
    mus = [physical("low_friction", a.params_for_difficulty(d), ground).friction for d in (0, 0.5, 1)]
    assert mus[0] > mus[1] > mus[2]


def test_material_map_paint_and_paste_keep_water_over_soil():
    m = MaterialMap.rigid((6, 6))
    m.paint(MaterialPatch((3, 3), soil="wet_sand"), 0, 0)
    surface = np.full((3, 3), 0.2, np.float32)
    m.paint(MaterialPatch((3, 3), water_surface=surface, flow_kind=FLOW_CURRENT, flow_speed=0.5), 1, 1)
    assert m.has_water()[1, 1] and m.has_soil()[1, 1] and m.soil_presets[m.soil[1, 1]] == "wet_sand"
    assert m.flow_speed[1, 1] == 0.5 and m.flow_speed[0, 0] == 0.0
    big = MaterialMap.rigid((10, 10))
    big.paint(MaterialPatch((2, 2), soil="snow"), 0, 0)
    big.paste(m, 4, 4)
    assert big.soil_presets == ["snow", "wet_sand"]
    assert big.soil_presets[big.soil[4, 4]] == "wet_sand" and big.soil[9, 9] == NO_SOIL
    with pytest.raises(ValueError, match="does not fit"):
        m.paint(MaterialPatch((3, 3), friction=0.1), 5, 5)


# --------------------------------------------------------------------------------------------- composition
def test_seam_keeps_stairs_next_to_flat():
    size = 8.0
    stairs_op = Operation("stairs", {"step_height": 0.1, "step_width": 0.4})
    spec = TileSpec(size, size, RES, 1, [
        Part(Region(0, 0, 4, 8), [stairs_op]),
        Part(Region(4, 0, 8, 8), [Operation("flat")]),
    ])
    h, _ = spec.build()
    alone, _ = TileSpec(size, size, RES, 1, [Part(Region(0, 0, 4, 8), [stairs_op])]).build()
    band = int(np.ceil(SEAM_BAND / RES))
    # Away from the seam the steps are exactly those of the stairs alone, and the flat part is flat.
    assert np.array_equal(h[: 40 - band], alone[: 40 - band])
    assert np.allclose(h[40:], 0.0)
    assert len(np.unique(h[: 40 - band, 0])) >= 8
    # Within the band the heights go smoothly from the stairs' edge to the flat part.
    seam = h[40 - band : 41, 0]
    assert np.all(np.diff(seam) <= 1e-6) and seam[0] <= alone[40 - band, 0]


def test_add_operation_stacks_on_earlier_parts():
    spec = TileSpec(4, 4, RES, 2, [
        Part(Region(0, 0, 4, 4), [Operation("pyramid_slope", {"slope": 0.3})]),
        Part(Region(0, 0, 4, 4), [Operation("rocks", {"platform": 0.0}, "add")]),
    ])
    h, _ = spec.build()
    base, _ = TileSpec(4, 4, RES, 2, spec.parts[:1]).build()
    assert np.all(h >= base - 1e-6) and np.any(h > base + 0.05)


def test_composition_deterministic_json_roundtrip_and_part_independence():
    parts = [
        Part(quadrant("front_left", 8, 8), [Operation("natural_ground", {"amplitude": 0.2})]),
        Part(quadrant("back_right", 8, 8), [Operation("river"), Operation("water", {"depth": 0.2}, "set")]),
        Part(quadrant("front_right", 8, 8), [Operation("soil", {"preset": "mud"})]),
    ]
    spec = TileSpec(8, 8, RES, 11, parts)
    h1, m1 = spec.build()
    spec2 = TileSpec.from_dict(json.loads(json.dumps(spec.to_dict())))
    h2, m2 = spec2.build()
    assert np.array_equal(h1, h2) and np.array_equal(m1.water_surface, m2.water_surface)
    assert np.array_equal(m1.soil, m2.soil) and m1.soil_presets == ["mud"]
    h3, _ = TileSpec(8, 8, RES, 12, parts).build()
    assert not np.array_equal(h1, h3)
    # Changing the river part leaves the natural ground part's heights untouched (own SeedSequence).
    parts4 = [parts[0], Part(parts[1].region, [Operation("pit")]), parts[2]]
    h4, _ = TileSpec(8, 8, RES, 11, parts4).build()
    assert np.array_equal(h1[45:, 45:], h4[45:, 45:])
    assert m1.has_water()[10:30, 10:30].any() and not m1.has_water()[40:, 40:].any()


def test_composition_errors_are_clear():
    with pytest.raises(ValueError, match="not inside the 8 x 8 m tile"):
        TileSpec(8, 8, RES, 0, [Part(Region(6, 0, 9, 8), [Operation("flat")])]).build()
    with pytest.raises(ValueError, match="holds no cell"):
        TileSpec(8, 8, RES, 0, [Part(Region(1.01, 0, 1.05, 8), [Operation("flat")])]).build()
    with pytest.raises(ValueError, match="unknown atomic terrain 'lava'"):
        TileSpec(8, 8, RES, 0, [Part(Region(0, 0, 8, 8), [Operation("lava")])]).build()
    with pytest.raises(ValueError, match="gap_width=5.0 m is outside"):
        TileSpec(8, 8, RES, 0, [Part(Region(0, 0, 8, 8), [Operation("gap", {"gap_width": 5.0})])]).build()
    with pytest.raises(ValueError, match="whole number"):
        TileSpec(8.05, 8, RES, 0, []).build()
    with pytest.raises(ValueError, match="unknown quadrant"):
        quadrant("middle", 8, 8)
    with pytest.raises(ValueError, match="malformed"):
        TileSpec.from_dict({"size_x": 8})
    stacked = [Part(Region(0, 0, 8, 8), [Operation("pyramid_stairs", {"step_height": 0.3, "step_width": 0.15}, "add")] * 2)]
    with pytest.raises(ValueError, match=f"> {MAX_ABS_HEIGHT} m; its 'add' operations stack"):
        build_tile(TileSpec(8, 8, RES, 0, stacked))


def test_one_operation_over_the_height_bound_names_the_parameters_to_change():
    """Steps of 0.3 m every 0.15 m around a 1.2 m platform on a 20 m tile: its edge cell lies 9.95 m from the centre,
    ceil((9.95 - 0.6) / 0.15) = 63 steps up, 18.9 m. No 'add' is involved: lower the rise, or widen the treads or
    the platform (fewer steps fit)."""
    alone = [Part(Region(0, 0, 20, 20), [Operation("pyramid_stairs", {"step_height": 0.3, "step_width": 0.15})])]
    with pytest.raises(ValueError, match=r"^part 0 \(\['pyramid_stairs'\]\) makes \|height\| reach 18.90 m > 10.0 m; "
                                         r"pyramid_stairs alone does: lower its step_height or raise its step_width, "
                                         r"platform\.$"):
        build_tile(TileSpec(20, 20, RES, 0, alone))


def test_docs_table_lists_every_atomic_with_intact_columns():
    from legged_gente.terrain.gallery import atomic_table_markdown

    rows = atomic_table_markdown().splitlines()[2:]
    assert [r.split("|")[1].strip(" `") for r in rows] == list(ATOMIC_TERRAINS)
    assert all(r.replace("\\|", "").count("|") == 7 for r in rows)


def test_curriculum_map_reaches_a_declared_bound_exactly():
    """A linear map that lands on a parameter's bound is in range despite float rounding (0.4 x 1.75 is
    0.7000000000000001 in binary), and one step further still raises, naming the parameter."""
    slope = ATOMIC_TERRAINS["pyramid_slope"]
    assert slope.params["slope"].high == 0.7
    assert slope.params_for_difficulty(1.75)["slope"] == pytest.approx(0.4 * 1.75)
    with pytest.raises(ValueError, match="slope"):
        slope.params_for_difficulty(1.76)


def test_an_obstacle_block_covers_the_cells_inside_its_box():
    """A cell is inside when its point i * resolution lies in [low, high) (as Region.cells counts it): a 0.4 m x
    0.6 m block centred at (1.23, 2.07) m on 0.1 m cells covers x in [1.03, 1.43) -> cells 11..14 and y in
    [1.77, 2.37) -> cells 18..23."""
    from legged_gente.terrain.atomic import _boxes

    h = np.zeros((40, 40), np.float32)
    _boxes(h, 0.1, np.array([[1.23, 2.07]]), np.array([[0.2, 0.3]]), np.array([0.5]))
    cells = np.argwhere(h == 0.5)
    assert (cells.min(0).tolist(), cells.max(0).tolist(), len(cells)) == ([11, 18], [14, 23], 24)


def test_the_docs_table_is_the_one_the_registry_makes():
    """docs/terrain.md's atomics table is generated: regenerate it (python -m legged_gente.terrain.gallery) when a
    terrain's parameters change."""
    from pathlib import Path

    from legged_gente.terrain.gallery import END, START, atomic_table_markdown

    doc = (Path(__file__).resolve().parents[1] / "docs" / "terrain.md").read_text()
    assert doc.split(START)[1].split(END)[0].strip() == atomic_table_markdown().strip()
