"""A spec's smoothing filters (Gaussian along x or y inside a rectangle, after the geometric calls) against values
worked out by hand, and GenTe's smoothing as the import writes it (GenTe's generate_dataset.py, smooth_transitions)."""

import json
import math

import numpy as np
import pytest

from legged_gente.generation.gente_compat import import_transcript
from legged_gente.generation.spec import TerrainSpec
from legged_gente.generation.validation import ValidationError
from legged_gente.terrain.composition import stacked_height_bounds, tile_spec_from_document

RES = 0.1


def _document(calls, smoothing=None, size_x=20.0, size_y=4.0):
    doc = {"version": 1, "name": "t", "size_x": size_x, "size_y": size_y, "resolution": RES, "seed": 0,
           "calls": calls, "source": {}, "backend": "test", "model": None}
    if smoothing is not None:
        doc["smoothing"] = smoothing
    return doc


WAVES_ALONG_X = {"tool": "waves", "region": "full",
                 "params": {"amplitude": 0.2, "wavelength": 2.0, "pattern": "x", "platform": 0.0}}


def _build(doc):
    return tile_spec_from_document(doc).build()[0].astype(np.float64)


def test_a_gaussian_along_x_scales_a_sine_along_x_by_its_fourier_transform():
    """A Gaussian of standard deviation s multiplies a sine of wavelength L by exp(-(2 pi s / L)^2 / 2) (the
    Gaussian's Fourier transform): s = 0.2 m, L = 2 m gives exp(-0.02 pi^2) = 0.8209. Checked away from the
    tile's ends (where the edge cells repeat) on waves varying along x only."""
    before = _build(_document([WAVES_ALONG_X]))
    after = _build(_document([WAVES_ALONG_X], [{"region": "full", "axis": "x", "sigma": 0.2}]))
    factor = math.exp(-0.5 * (2 * math.pi * 0.2 / 2.0) ** 2)
    assert factor == pytest.approx(0.8209, abs=1e-4)
    middle = slice(20, 180)  # 2 m (10 sigma) from either end
    assert np.abs(before[middle]).max() > 0.19  # the waves are there to smooth
    np.testing.assert_allclose(after[middle], factor * before[middle], atol=2e-3)


def test_a_gaussian_along_y_leaves_heights_constant_along_y_as_they_are():
    """Waves varying along x only are constant along y: a normalised kernel leaves a constant as it is."""
    before = _build(_document([WAVES_ALONG_X]))
    after = _build(_document([WAVES_ALONG_X], [{"region": "full", "axis": "y", "sigma": 0.5}]))
    np.testing.assert_allclose(after, before, atol=1e-6)


def test_a_filter_touches_only_the_cells_of_its_rectangle():
    """Region [0, 10) x [0, 4) m holds cells i = 0..99: cells 100.. keep their heights exactly."""
    doc = _document([WAVES_ALONG_X], [{"region": {"x0": 0.0, "y0": 0.0, "x1": 10.0, "y1": 4.0}, "axis": "x",
                                       "sigma": 0.3}])
    before, after = _build(_document([WAVES_ALONG_X])), _build(doc)
    assert np.array_equal(after[100:], before[100:])
    assert not np.allclose(after[:100], before[:100], atol=1e-3)


def test_the_declared_bounds_hold_the_smoothed_heights():
    """A block 0.5 m high beside flat ground: smoothed along x across its edge, cells outside the block rise above
    their own (0 m) bound; the bounds of the filter's rectangle are those of all its heights, 0 to 0.5 m."""
    calls = [{"tool": "flat", "region": {"x0": 10.0, "y0": 0.0, "x1": 20.0, "y1": 4.0}, "params": {"height": 0.5}}]
    doc = _document(calls, [{"region": "full", "axis": "x", "sigma": 0.4}])
    tile = tile_spec_from_document(doc)
    heights = tile.build()[0]
    bounds = stacked_height_bounds(tile)
    x = np.arange(heights.shape[0])[:, None] * RES + np.zeros(heights.shape)
    y = np.arange(heights.shape[1])[None, :] * RES + np.zeros(heights.shape)
    lo, hi = bounds.at(x, y)
    assert heights[95, 0] > 0.03  # 0.5 m before the block (0.3 m beyond its seam band): raised by the filter
    assert np.all(heights >= lo - 1e-6) and np.all(heights <= hi + 1e-6)


def test_a_spec_with_smoothing_round_trips_and_refuses_a_bad_filter_in_one_line():
    smoothing = [{"region": "full", "axis": "x", "sigma": 0.2},
                 {"region": {"x0": 0.0, "y0": 0.0, "x1": 10.0, "y1": 4.0}, "axis": "y", "sigma": 0.1}]
    doc = _document([WAVES_ALONG_X], smoothing)
    spec = TerrainSpec.from_dict(json.loads(json.dumps(doc)))
    assert spec.to_dict()["smoothing"] == smoothing
    assert np.array_equal(spec.build()[0], tile_spec_from_document(doc).build()[0])
    for bad, message in (({"region": "full", "axis": "z", "sigma": 0.2}, r"smoothing.*axis.*\['x', 'y'\]"),
                         ({"region": "full", "axis": "x", "sigma": 0.0}, r"smoothing.*sigma"),
                         ({"region": "full", "axis": "x", "sigma": 3.0}, r"smoothing.*sigma"),
                         ({"region": {"x0": 0.0, "y0": 0.0, "x1": 30.0, "y1": 4.0}, "axis": "x", "sigma": 0.2},
                          r"smoothing\[0\]: region .* is not inside the 20.0 x 4.0 m tile")):
        with pytest.raises(ValidationError, match=message) as info:
            TerrainSpec.from_dict(_document([WAVES_ALONG_X], [bad]))
        assert all("\n" not in m for m in info.value.messages)


def _gente_call(name, **args):
    return {"function": {"name": name, "arguments": json.dumps({"terrain": "previous_terrain", **args})}}


def test_an_imported_single_part_tile_is_smoothed_whole_along_x_then_y():
    """terrain_utils_single.smooth_transitions: gaussian_filter1d(sigma=2 cells) along axis 0 (x) over the whole
    array, then along axis 1 (y): 0.2 m at GenTe's 0.1 m cells."""
    imported = import_transcript({"tool_calls": [_gente_call("flat_ground_terrain", height=0.1)]}, "t", "single")
    assert imported.spec.smoothing == [{"region": "full", "axis": "x", "sigma": 0.2},
                                       {"region": "full", "axis": "y", "sigma": 0.2}]


def test_an_imported_multi_part_tile_is_smoothed_in_bands_across_its_seams():
    """terrain_utils_parts.smooth_transitions(n=20) on GenTe's 200 x 200 cells (w1 = l1 = 0, w2 = l2 = 100, parts of
    100): along x on x cells [80, 120) for y cells [0, 100) then [100, 200); along y on y cells [80, 120) for x cells
    [0, 100) then [100, 200). In metres at 0.1 m: x in [8, 12) m, y halves of 10 m; then the same along y."""
    imported = import_transcript({"tool_calls": [_gente_call("flat_ground_terrain", height=0.1, part=1)]}, "t",
                                 "multi")

    def band(x0, y0, x1, y1, axis):
        return {"region": {"x0": x0, "y0": y0, "x1": x1, "y1": y1}, "axis": axis, "sigma": 0.2}

    assert imported.spec.smoothing == [band(8.0, 0.0, 12.0, 10.0, "x"), band(8.0, 10.0, 12.0, 20.0, "x"),
                                       band(0.0, 8.0, 10.0, 12.0, "y"), band(10.0, 8.0, 20.0, 12.0, "y")]
