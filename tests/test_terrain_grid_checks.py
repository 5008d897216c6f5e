"""The terrain grid and tile composition: mesh export axes, preview grid lines, bad sizes, seeds and
friction, each with its expected value worked out by hand."""

import math
import warnings

import numpy as np
import pytest

from legged_gente.terrain.composition import TileSpec, tile_spec_from_document
from legged_gente.terrain.terrain import Terrain


class FlatCfg:
    """Two 2 m x 3 m tiles (20 x 30 cells at 0.1 m, one row, two columns) of flat ground 0.5 m high, no border."""

    mesh_type = "heightfield"
    mode = "selected"
    resolution = 0.1
    border_size = 0.0
    terrain_length = 2.0
    terrain_width = 3.0
    num_rows = 1
    num_cols = 2
    terrain_types = ["flat"]
    terrain_proportions = [1.0]
    selected_terrain = "flat"
    selected_params = {"height": 0.5}
    generated_specs = []
    max_difficulty = 1.0
    static_friction = 0.9
    seed = 0


def cfg(**overrides):
    return type("Cfg", (FlatCfg,), overrides)


# ------------------------------------------------------------------------------------------------ mesh export
def test_a_glb_mesh_has_y_up_as_gltf_requires(tmp_path):
    """glTF 2.0 (section 3.4, coordinate system): +Y is up. The grid is 20 x 60 samples at 0.1 m from world (0, 0):
    x in [0, 1.9] m, y in [0, 5.9] m, ground at z = 0.5 m. In the .glb that is x in [0, 1.9], Y (up) = 0.5 and
    Z = -y in [-5.9, 0]; every face faces up, +Y. The .obj keeps the world's z up."""
    import trimesh

    t = Terrain(cfg(), 1)
    assert t.height_field.shape == (20, 60)
    glb = trimesh.load(t.export_mesh(tmp_path / "terrain.glb"), force="mesh")
    assert np.allclose(glb.bounds, [[0.0, 0.5, -5.9], [1.9, 0.5, 0.0]], atol=1e-5), glb.bounds
    assert np.allclose(glb.face_normals, [0.0, 1.0, 0.0], atol=1e-6)
    obj = trimesh.load(t.export_mesh(tmp_path / "terrain.obj"), force="mesh")
    assert np.allclose(obj.bounds, [[0.0, 0.0, 0.5], [1.9, 5.9, 0.5]], atol=1e-5), obj.bounds


# -------------------------------------------------------------------------------------------------- preview
def test_preview_grid_lines_frame_every_tile_without_a_border(tmp_path):
    """No border, 20 x 60 cells, no resize (60 px < max_size): the image is 60 rows (y up) x 20 columns. Tile
    borders along y at j = 0, 30, 60 are image rows 59, 29 and the top edge 0; along x at i = 0, 20 are columns 0
    and the right edge 19. A line darkens its pixels once, to 0.4 of the uniform flat colour."""
    from PIL import Image

    t = Terrain(cfg(), 1)
    plain = np.asarray(Image.open(t.save_preview(tmp_path / "plain.png", grid=False)))
    lined = np.asarray(Image.open(t.save_preview(tmp_path / "lined.png", grid=True)))
    assert plain.shape == (60, 20, 3) and (plain == plain[0, 0]).all()  # flat: one colour
    once = (plain[0, 0] * 0.4).astype(np.uint8)
    for row in (0, 29, 59):
        assert (lined[row, 5] == once).all(), (row, lined[row, 5], once)
    for col in (0, 19):
        assert (lined[10, col] == once).all(), (col, lined[10, col], once)
    assert (lined[10, 5] == plain[0, 0]).all()


# -------------------------------------------------------------------------------------------- bad grid sizes
@pytest.mark.parametrize("field", ["terrain_length", "terrain_width", "border_size"])
@pytest.mark.parametrize("value", [math.nan, math.inf])
def test_a_non_finite_size_is_refused_naming_the_field(field, value):
    """A NaN border passed both `< 0` and `> 0` and became no border at all, silently; an infinite or NaN tile size
    or border crashed in round() (OverflowError, or ValueError 'cannot convert float NaN to integer')."""
    with pytest.raises(ValueError, match=rf"^{field}={value} m must be a finite number of metres"):
        Terrain(cfg(**{field: value}), 1)


@pytest.mark.parametrize("value", [math.nan, math.inf])
def test_a_tile_of_non_finite_size_is_refused_in_one_line(value):
    with pytest.raises(ValueError, match=rf"^tile {value} x 3.0 m is not a whole number \(>= 1\) of 0.1 m cells"):
        TileSpec(value, 3.0, 0.1, 0, []).build()
    document = {"size_x": value, "size_y": 3.0, "resolution": 0.1, "seed": 0, "calls": []}
    # JSON's NaN compares false with the schema's bounds, so the loader's own check names it; inf is over them
    expected = (r"^terrain spec: size_x nan, size_y 3 and resolution 0.1 must be finite numbers of metres$"
                if math.isnan(value) else r"^not a terrain spec document: spec: field 'size_x': inf is greater than "
                                          r"the maximum of 200.0\. Fix the file")
    with pytest.raises(ValueError, match=expected):
        tile_spec_from_document(document)


# ----------------------------------------------------------------------------------------------- seed, friction
@pytest.mark.parametrize("seed, problem", [(2.7, "2.7 is not of type 'integer'"), (-3, "-3 is less than the minimum of 0"),
                                           ("5", "'5' is not of type 'integer'"), (True, "True is not of type 'integer'"),
                                           (math.nan, "nan is not of type 'integer'"),
                                           (math.inf, "inf is not of type 'integer'")])
def test_a_spec_document_seed_that_is_not_a_whole_number_ge_0_is_refused(seed, problem):
    """int() truncated a seed of 2.7 to 2 and built that tile silently (the spec's schema says: an integer >= 0); a
    negative seed failed in numpy with 'expected non-negative integer', naming no field."""
    document = {"size_x": 2.0, "size_y": 2.0, "resolution": 0.1, "seed": seed,
                "calls": [{"tool": "rocks", "region": "full", "params": {}}]}
    with pytest.raises(ValueError) as refused:
        tile_spec_from_document(document)
    assert str(refused.value).startswith(f"not a terrain spec document: spec: field 'seed': {problem}.")


def test_a_whole_number_seed_written_as_a_float_is_that_seed():
    document = {"size_x": 2.0, "size_y": 2.0, "resolution": 0.1, "seed": 7.0,
                "calls": [{"tool": "rocks", "region": "full", "params": {}}]}
    tile = tile_spec_from_document(document)
    assert tile.seed == 7 and type(tile.seed) is int
    assert np.array_equal(tile.build()[0], tile_spec_from_document({**document, "seed": 7}).build()[0])


@pytest.mark.parametrize("friction", [math.nan, math.inf, -0.5])
def test_a_ground_friction_that_is_not_a_coefficient_is_refused(friction):
    """MuJoCo compiles a geom of friction -1 or NaN without a word; the map took it for every rigid cell."""
    with pytest.raises(ValueError, match=rf"^terrain.static_friction={friction} must be a finite coefficient >= 0"):
        Terrain(cfg(static_friction=friction), 1)
    assert Terrain(cfg(static_friction=0.0), 1).material.friction.max() == 0.0  # frictionless ground is allowed


def test_a_terrain_selected_on_a_plane_is_warned_of_not_built_silently():
    """mesh_type "plane" builds flat tiles whatever the mode: a selected terrain left unbuilt is said."""
    class PitOnPlane(FlatCfg):
        mesh_type = "plane"
        selected_terrain = "pit"
        selected_params = {"depth": 0.3}

    with pytest.warns(UserWarning, match=r"selected_terrain='pit'.*mesh_type='plane'.*mesh_type='heightfield'"):
        terrain = Terrain(PitOnPlane(), 4)
    assert (terrain.height_field == 0).all()

    class PlainPlane(FlatCfg):
        mesh_type = "plane"
        mode = "curriculum"

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Terrain(PlainPlane(), 4)
