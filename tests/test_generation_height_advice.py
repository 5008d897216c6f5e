"""What a refused call is told (docs/generation.md)."""

import math

import pytest

from legged_gente.generation.validation import ValidationError, validate_call


def test_a_call_beyond_the_height_bound_on_its_own_is_told_its_own_fix():
    # docs/generation.md: "A call whose own height range exceeds the bound (fine stairs across a 20 m tile) is
    # rejected too". Stairs from the centre of a 20 m region widened by the 0.3 m seam band on each side:
    # ceil(10.3 m / 0.15 m) = 69 steps of 0.3 m, 20.7 m > 10 m. A lone 'set' call stacks on nothing, so the fix is
    # in its own parameters, not in its mode.
    peak = math.ceil(10.3 / 0.15) * 0.3
    with pytest.raises(ValidationError) as caught:
        validate_call("stairs", {"step_height": 0.3, "step_width": 0.15, "platform": 0.0, "region": "full"},
                      20.0, 20.0, resolution=0.1)
    message = caught.value.messages[0]
    assert f"{peak:.2f} m" in message
    assert "mode 'set'" not in message and "stack" not in message
    assert "lower its step_height" in message and "raise its step_width" in message
