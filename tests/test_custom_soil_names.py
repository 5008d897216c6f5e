"""A custom soil registered under a name of its own (``register_custom_soil("peat", ...)``, as its docstring shows)
is a soil preset everywhere a preset is named: the soil terrain's parameter, a terrain spec, a curriculum entry and
the generation tool offered to a model. Before, only the name "custom" was accepted, so a run could use one custom
soil, and "peat" was refused with a list that did not say how to get it."""

import pytest

from legged_gente.generation.spec import TerrainSpec
from legged_gente.generation.tools import param_schema
from legged_gente.terrain.composition import tile_spec_from_document
from legged_gente.terrain.registry import ATOMIC_TERRAINS
from legged_gente.terrain.soil import SOIL_PRESETS, register_custom_soil
from legged_gente.terrain.terrain import parse_terrain_type

PEAT = dict(kc=1.0e3, kphi=2.0e5, n=1.0, c=2.0e3, mu=0.4, K=0.03, bulldoze_c=0.0, bulldoze_g=0.0)


@pytest.fixture
def peat():
    register_custom_soil("peat", **PEAT)
    register_custom_soil("marl", **PEAT)
    yield
    SOIL_PRESETS.pop("peat")
    SOIL_PRESETS.pop("marl")


def document(preset):
    return {"size_x": 2.0, "size_y": 2.0, "resolution": 0.1, "seed": 0,
            "calls": [{"tool": "soil", "region": "left", "params": {"preset": preset}},
                      {"tool": "soil", "region": "right", "params": {"preset": "mud"}}]}


def test_an_unregistered_name_is_refused_saying_how_to_register_it():
    with pytest.raises(ValueError, match=r"preset='peat' is not one of .*needs register_custom_soil\(name"):
        ATOMIC_TERRAINS["soil"].check_params({"preset": "peat"})


def test_two_soils_of_their_own_names_reach_the_material_map(peat):
    soil = ATOMIC_TERRAINS["soil"]
    assert soil.check_params({"preset": "peat"}) == {"preset": "peat"}
    assert soil.params["preset"].offered()[-2:] == ["peat", "marl"]
    _, material = tile_spec_from_document(document("peat")).build()
    assert sorted(material.soil_presets) == ["mud", "peat"]
    _, material = tile_spec_from_document(document("marl")).build()
    assert sorted(material.soil_presets) == ["marl", "mud"]
    assert parse_terrain_type("soil:preset=peat")  # a curriculum entry


def test_a_model_is_offered_the_registered_names_and_a_spec_naming_one_loads(peat):
    assert {"peat", "marl"} <= set(param_schema(ATOMIC_TERRAINS["soil"].params["preset"])["enum"])
    spec = TerrainSpec.from_dict({"version": 1, "name": "bog", "size_x": 2.0, "size_y": 2.0, "resolution": 0.1,
                                  "seed": 0, "source": {}, "backend": "planner", "model": None,
                                  "calls": document("peat")["calls"]})
    assert "peat" in spec.build()[1].soil_presets
