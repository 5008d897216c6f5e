"""The soil tool offers a model the presets registered when its schema is built: a model cannot register a soil,
so an unregistered "custom" is never offered, and a refusal names the presets it can use."""

from __future__ import annotations

import pytest

from legged_gente.generation.tools import tool_schemas
from legged_gente.generation.validation import ValidationError, validate_call
from legged_gente.terrain.soil import SOIL_PRESETS, register_custom_soil

BUILT_IN = ["dry_sand", "wet_sand", "snow", "mud", "clay_loam", "poppy_seeds_rft"]


def _preset_schema():
    (soil,) = [t["function"] for t in tool_schemas() if t["function"]["name"] == "soil"]
    return soil["parameters"]["properties"]["preset"]


def test_an_unregistered_custom_soil_is_not_offered(monkeypatch):
    monkeypatch.delitem(SOIL_PRESETS, "custom", raising=False)
    schema = _preset_schema()
    assert schema["enum"] == BUILT_IN
    assert f"One of {BUILT_IN}" in schema["description"]


def test_a_registered_custom_soil_is_offered_and_accepted(monkeypatch):
    monkeypatch.setitem(SOIL_PRESETS, "custom", SOIL_PRESETS["mud"])  # restored after the test
    register_custom_soil("custom", kc=0.0, kphi=1e6, n=1.0, c=1e3, mu=0.5, K=0.02, bulldoze_c=0.0, bulldoze_g=0.0)
    assert _preset_schema()["enum"] == BUILT_IN + ["custom"]
    assert validate_call("soil", {"preset": "custom", "region": "full"}).params == {"preset": "custom"}


@pytest.mark.parametrize("preset", ["custom", "lava"])
def test_a_refused_preset_names_the_registered_ones(monkeypatch, preset):
    monkeypatch.delitem(SOIL_PRESETS, "custom", raising=False)
    with pytest.raises(ValidationError) as info:
        validate_call("soil", {"preset": preset, "region": "full"})
    (message,) = info.value.messages
    assert message.startswith("soil: preset") and repr(preset) in message and f"one of {BUILT_IN}" in message
