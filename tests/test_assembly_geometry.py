"""sim/assembly.py against MuJoCo itself: the surface MuJoCo ray-casts equals heights worked out by hand, and the
contact friction MuJoCo mixes is the configured ground friction."""

from types import SimpleNamespace

import mujoco
import numpy as np
import pytest

from legged_gente.envs.gente_quadruped.gente_quadruped_config import GenteQuadrupedCfg
from legged_gente.sim.assembly import _add_terrain, build_model


def _surface(mjm: mujoco.MjModel, x: float, y: float) -> float:
    """Height of the first terrain surface a ray straight down from z = 10 m hits at (x, y)."""
    data = mujoco.MjData(mjm)
    mujoco.mj_forward(mjm, data)
    geomid = np.zeros(1, np.int32)
    dist = mujoco.mj_ray(mjm, data, np.array([x, y, 10.0]), np.array([0.0, 0.0, -1.0]), None, 1, -1, geomid)
    assert geomid[0] >= 0, (x, y)
    return 10.0 - dist


def _terrain_model(heights: np.ndarray, resolution: float, origin_xy, piece_size: float) -> mujoco.MjModel:
    spec = mujoco.MjSpec()
    terrain = SimpleNamespace(height_field=heights, resolution=resolution, origin_xy=origin_xy)
    _add_terrain(spec, SimpleNamespace(static_friction=1.0, hfield_piece_size=piece_size), terrain)
    return spec.compile()


def test_a_tilted_plane_in_pieces_is_that_plane_everywhere():
    """Samples of z = 0.2 x - 0.1 y - 0.5 (all below zero) at world (-1 + 0.1 i, 2 + 0.1 j), i < 13, j < 8, laid down
    in pieces of 5 cells (3 x 2 pieces, the last ones shorter): any triangulation of a plane is the plane, so at any
    point, on a seam or inside a cell, MuJoCo's surface is 0.2 x - 0.1 y - 0.5. A swap of x and y, a half-cell
    shift or a gap at a seam moves it by centimetres."""
    i, j = np.meshgrid(np.arange(13), np.arange(8), indexing="ij")
    heights = 0.2 * (-1.0 + 0.1 * i) - 0.1 * (2.0 + 0.1 * j) - 0.5
    mjm = _terrain_model(heights, 0.1, (-1.0, 2.0), piece_size=0.5)
    assert mjm.nhfield == 6
    for x, y in [(-0.97, 2.03), (-0.5, 2.26), (-0.31, 2.5), (0.0, 2.37), (0.17, 2.69), (0.13, 2.5)]:
        assert _surface(mjm, x, y) == pytest.approx(0.2 * x - 0.1 * y - 0.5, abs=1e-5), (x, y)


def test_sub_millimetre_relief_keeps_its_height():
    """A 0.4 mm bump in flat ground (a smoothed edge, a rounded ramp foot) stays 0.4 mm high: MuJoCo rescales a
    heightfield's data to [0, 1] and multiplies by its elevation size, so that size must be the patch's own relief,
    not a floor of 1 mm that would raise the bump to 1 mm."""
    heights = np.zeros((3, 3))
    heights[1, 1] = 0.0004
    mjm = _terrain_model(heights, 0.1, (0.0, 0.0), piece_size=10.0)
    assert _surface(mjm, 0.1, 0.1) == pytest.approx(0.0004, abs=1e-6)
    assert _surface(mjm, 0.03, 0.15) == pytest.approx(0.0, abs=1e-6)  # the flat ground beside it stays at 0


@pytest.mark.parametrize("terrain_is_plane", [True, False])
def test_the_ground_friction_is_the_contact_friction(terrain_is_plane):
    """cfg.terrain.static_friction = 0.5 under feet whose MJCF friction is 1.0: a foot contact's sliding friction is
    0.5, as the env's friction observation (friction_coeffs = static_friction without randomisation) and the force
    fields' map scaling (cell friction / static_friction) assume. MuJoCo mixes a pair's friction as the larger of
    the two geoms' (or the higher-priority geom's), so the terrain's 0.5 alone would give 1.0."""
    cfg = GenteQuadrupedCfg()
    cfg.terrain.static_friction = 0.5
    cfg.forces.sole_contact = False  # MuJoCo collides the spheres: its contacts show its mixing
    terrain = None if terrain_is_plane else SimpleNamespace(
        height_field=np.zeros((41, 41), np.float32), resolution=0.1, origin_xy=(-2.0, -2.0))
    mjm, layout = build_model(cfg, terrain)
    feet = [mjm.geom(f"{leg}_foot_geom").id for leg in ("FL", "FR", "RL", "RR")]
    data = mujoco.MjData(mjm)
    mujoco.mj_kinematics(mjm, data)
    lowest = min(data.geom_xpos[g, 2] - mjm.geom_size[g, 0] for g in feet)
    data.qpos[2] -= lowest + 0.002  # every foot 2 mm or more into the ground at z = 0
    mujoco.mj_forward(mjm, data)
    n = data.ncon
    on_feet = np.isin(data.contact.geom[:n], feet).any(axis=1)
    assert on_feet.sum() >= 4
    np.testing.assert_allclose(data.contact.friction[:n][on_feet, :2], 0.5)
