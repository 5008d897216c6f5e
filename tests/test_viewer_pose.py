"""The robot as the browser draws it: each geom's mesh in its body's frame, the frame placed by the body's position
and its quaternion (viser's wxyz, w first as MuJoCo's), lands where MuJoCo puts the geom."""

from __future__ import annotations

import socket

import mujoco
import numpy as np

from legged_gente.terrain.materials import MaterialMap
from legged_gente.viewer.rollout import Rollout, robot_geoms, robot_model
from legged_gente.viewer.scene import BareTerrain
from legged_gente.viewer.server import TerrainItem, Viewer


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def rotation(wxyz) -> np.ndarray:
    """Rotation matrix of the unit quaternion (w, x, y, z) (Diebel 2006, eq. 125)."""
    w, x, y, z = wxyz
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def test_a_tilted_robot_is_drawn_where_mujoco_puts_its_geoms():
    """The quadruped's hip cylinders lie along x (quat="0.707 0 0.707 0" in its MJCF): they were drawn upright,
    the geom's quaternion written into a copy of the transform instead of the transform."""
    mjm = robot_model("gente_quadruped")
    # the base 30 deg about z then 20 deg about x (q = q_z * q_x), at (1, 2, 0.5) m; every joint bent by 0.3 rad
    qz = np.array([np.cos(np.radians(15)), 0.0, 0.0, np.sin(np.radians(15))])
    qx = np.array([np.cos(np.radians(10)), np.sin(np.radians(10)), 0.0, 0.0])
    quat = np.zeros(4)
    mujoco.mju_mulQuat(quat, qz, qx)
    qpos = mjm.qpos0.copy()
    qpos[:3], qpos[3:7] = (1.0, 2.0, 0.5), quat
    qpos[7:] += 0.3
    data = mujoco.MjData(mjm)
    data.qpos[:] = qpos
    mujoco.mj_kinematics(mjm, data)
    plane = BareTerrain(np.zeros((2, 2), np.float32), MaterialMap.rigid((2, 2)), 10.0, (-5.0, -5.0))
    viewer = Viewer([TerrainItem("plane", lambda: plane)], port=free_port(), shadows=False)
    try:
        rollout = Rollout("gente_quadruped", 0.02, qpos[None, None], np.zeros((1, 1, 3)), np.zeros((1, 1, 3)),
                          np.zeros((1, 1), bool), np.zeros((1, 1), bool), [], np.zeros((1, 1, 0, 3)),
                          np.zeros((1, 1, 0, 3)), plane.height_field, plane.origin_xy, plane.resolution, plane.material)
        player = viewer.attach_rollout(rollout, mjm, play=False)
        player.draw(0)
        drawn = [g for g in range(mjm.ngeom)  # collision-only geoms (group 3) are hidden, as MuJoCo's viewer does
                 if mjm.geom_bodyid[g] != 0 and mjm.geom_rgba[g, 3] > 0 and mjm.geom_group[g] < 3]
        shapes = robot_geoms(mjm)
        assert len(shapes) == len(drawn) > 10
        for g, shape in zip(drawn, shapes):
            frame = player.bodies[0, shape.body]
            world = shape.vertices @ rotation(frame.wxyz).T + frame.position
            centre = (world.max(0) + world.min(0)) / 2 if mjm.geom_type[g] != mujoco.mjtGeom.mjGEOM_MESH else None
            if centre is not None:  # primitives are symmetric about their centre: MuJoCo's geom_xpos
                np.testing.assert_allclose(centre, data.geom_xpos[g], atol=1e-5)
            # the geom's long axis (its local z) as MuJoCo turns it: the mesh's extent along it is the geom's
            axis = data.geom_xmat[g].reshape(3, 3)[:, 2]
            along = (world - data.geom_xpos[g]) @ axis
            size = mjm.geom_size[g]
            half = {mujoco.mjtGeom.mjGEOM_CAPSULE: size[1] + size[0], mujoco.mjtGeom.mjGEOM_CYLINDER: size[1],
                    mujoco.mjtGeom.mjGEOM_BOX: size[2], mujoco.mjtGeom.mjGEOM_SPHERE: size[0]}.get(int(mjm.geom_type[g]))
            if half is not None:
                np.testing.assert_allclose([along.min(), along.max()], [-half, half], atol=1e-5)
    finally:
        viewer.stop()
