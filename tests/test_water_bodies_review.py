"""Review of "water lies in ground that holds it": planner cases the first tests did not reach (a fountain's bowl,
a depression near but not on a seam inside the tile, a part too small to keep its water off the seams).

A *water wall* is a wet cell beside a dry cell of the tile whose ground lies more than 5 cm below the wet cell's
water surface (docs/evaluation.md, rule 5).
"""

import pytest
from test_water_bodies import worst_wall

from legged_gente.generation.backends.planner import plan_text
from legged_gente.generation.pipeline import generate_spec
from legged_gente.generation.validation import ValidationError


@pytest.mark.parametrize("text, depth", [("a fountain", 0.3), ("a deep fountain", 0.6)])
def test_a_fountains_water_stands_inside_its_rim(text, depth):
    """The fountain is a 0.5 m rim on the middle 40 % of the tile (8 m square from 6 to 14 m) with water inside its
    bowl, the middle 20 % (8 to 12 m).
    Its water is 0.3 m deep (0.6 m when deep) and must stand FREEBOARD = 0.1 m below the rim: surface 0.4 m.
    Before the review its water lay on a 0.1 m floor whose 0.3 m seam band pulled the rim down beside the water's
    edge: at 0.1 m outside it the blend weight is smoothstep(2/3) = 20/27, ground 0.5 - 0.4 * 20/27 = 0.204 m, a
    0.196 m wall; with 0.6 m of water a 0.496 m wall."""
    spec, result = generate_spec(text)
    heights, material = spec.build()
    assert not [w for w in result.warnings if w.startswith("water wall")], result.warnings
    assert worst_wall(heights, material) <= 0.05
    water = next(c for c in spec.calls if c.tool == "water")
    assert water.params["depth"] == pytest.approx(depth)
    wet = material.has_water()
    assert wet[100, 85]  # water inside the bowl at (10, 8.5) m, beside the 1.2 m column (9.4-11 m square)
    assert float(material.water_surface[wet].max()) == pytest.approx(0.5 - 0.1, abs=0.02)
    assert float(heights[60:140, 60:140].max()) == pytest.approx(1.2, abs=1e-3)  # the column is kept


@pytest.mark.parametrize("size, resolution", [(20.0, 0.05), (10.0, 0.1), (10.0, 0.05), (8.0, 0.1)])
def test_a_fountain_on_a_small_part_keeps_its_water_inside_the_rim(size, resolution):
    """"a fountain in a plaza" gives the fountain half the tile: on a 10 m tile a 5 m x 10 m part, its rim 2 m
    across (x 1.5-3.5 m). With the bowl on the middle 30 % of the part (x 1.75-3.25 m) its water, reaching 0.3 m
    (SEAM_BAND) past the bowl, ended at x 3.55 m: on the rim's outer blend, whose ground falls from 0.5 m to the
    plaza's 0 m, and stood 0.27 m above the plaza beside it. The bowl on the middle 20 % (x 2-3 m) keeps the water
    (x 1.7-3.3 m) 0.2 m inside the rim; on a part 4 m across (an 8 m tile) 0.1 m inside it."""
    spec, result = generate_spec("a fountain in a plaza", size_x=size, size_y=size, resolution=resolution)
    heights, material = spec.build()
    assert material.has_water().any()
    assert worst_wall(heights, material) <= 0.05
    assert not [w for w in result.warnings if w.startswith("water wall")], result.warnings


def test_a_depression_near_a_seam_inside_the_tile_keeps_off_it():
    """"a bog and stairs" on an 8 m tile: the bog's back slot is x 0-4 m, the stairs' front slot x 4-8 m. The
    bog's second basin lies on x 0.55-0.9 of its slot, 2.2-3.6 m: 0.4 m from the seam at x = 4 m, nearer than
    WATER_MARGIN (0.8 m: twice SEAM_BAND and two cells). It must keep 0.8 m off: x1 = 3.2 m, its water 0.3 m
    (SEAM_BAND) past it, x1 = 3.5 m.
    Before the review only an edge lying on the seam was moved, and the stairs' low end (about -1.3 m below the
    0 m mid-flight) pulled the basin's rim 0.34 m below the water's surface."""
    spec, result = generate_spec("a bog and stairs", size_x=8.0, size_y=8.0)
    basins = sorted(c.rect(8.0, 8.0) for c in spec.calls if c.tool == "basin")
    waters = sorted(c.rect(8.0, 8.0) for c in spec.calls if c.tool == "water")
    assert basins[1][2] == pytest.approx(4.0 - 0.8)
    assert waters[1][2] == pytest.approx(4.0 - 0.8 + 0.3)
    heights, material = spec.build()
    assert worst_wall(heights, material) <= 0.05
    assert not [w for w in result.warnings if w.startswith("water wall")], result.warnings


def test_the_same_near_seam_rule_leaves_a_20_m_tile_alone():
    """On a 20 m tile the bog's basins lie 1 m (0.1 of a 10 m slot) from the seam, beyond WATER_MARGIN: unmoved
    (x 0.55-0.9 of the back slot: 5.5-9.0 m)."""
    calls = plan_text("a bog and stairs").calls
    assert sorted(c.rect(20.0, 20.0)[2] for c in calls if c.tool == "basin") == pytest.approx([4.5, 9.0])


def test_a_part_too_small_to_keep_its_water_off_the_seams_says_to_ask_for_a_larger_tile():
    """A beach and stairs on a 2 m tile: the beach's water front is x 0.6-1.0 of its 1 m slot (0.6-1.0 m); kept
    0.8 m off the seam at x = 1 m it would end at 0.2 m, before it starts. The error must ask for a larger tile (it
    asked for a smaller one) in one line."""
    with pytest.raises(ValidationError) as info:
        plan_text("a beach and stairs", size_x=2.0, size_y=2.0)
    message = str(info.value)
    assert "\n" not in message
    assert "larger tile" in message and "smaller" not in message and "'beach'" in message
