"""Rollout videos with ``mujoco.Renderer``: the robot on its terrain drawn in the material colours.

The simulation model's ground is one grey checker (rendering is no part of the physics); a video needs to show
what the robot walks on. :class:`VideoRenderer` builds a render-only model — the robot's MJCF (the qpos layout of
the task's worlds) and the terrain's heightfield, textured with the viewer's material colours (soil presets,
low friction, ground) under a 1 m checker, the water as a translucent surface at its real level — with a sun
that casts shadows, and films it with a camera that follows the robot's base. Flow arrows are drawn on the
water (as long as the water travels in 1 s, as in the web viewer).

Offscreen OpenGL: ``MUJOCO_GL=egl`` (Mesa's llvmpipe on a CPU machine, the driver on a GPU) or ``osmesa``, set
before Python starts (MuJoCo picks its OpenGL backend when it is first imported).
"""

from __future__ import annotations

import os
from pathlib import Path

import mujoco
import numpy as np

from legged_gente.utils.args import GL_FIX
from legged_gente.viewer.scene import Arrows, Mesh, material_colours, terrain_scene

CHECKER = 1.0
"""m, side of the ground's checker squares (a gait's step length is readable against it)."""
CHECKER_DARK = 0.82
"""brightness of the dark checker squares relative to the light ones."""
TEXELS_PER_CELL = 4
"""texture pixels per heightfield cell (sharp checker edges)."""


def ground_texture(colours: np.ndarray, resolution: float, origin: tuple[float, float]) -> np.ndarray:
    """(H, W, 3) uint8 texture of the heightfield: ``colours`` (nx, ny, 3) in [0, 1] per cell, darkened on every
    other ``CHECKER`` square. MuJoCo stretches a heightfield's 2-D texture over the heightfield, from its first
    sample to its last ((nx - 1) x (ny - 1) cells; render_gl3.c, settexture), with texture column = x and texture
    row 0 at the largest y, so the image is the (x, y) grid transposed and flipped. Each texel takes the colour of
    its nearest sample, the cell whose material the force kernels read there."""
    k = TEXELS_PER_CELL
    nx, ny = colours.shape[:2]
    u = (np.arange((nx - 1) * k) + 0.5) / k  # texel centres, in cells from the first sample
    v = (np.arange((ny - 1) * k) + 0.5) / k
    rgb = colours[np.ix_(np.round(u).astype(int), np.round(v).astype(int))]
    x, y = origin[0] + u * resolution, origin[1] + v * resolution
    dark = (np.floor(x / CHECKER)[:, None] + np.floor(y / CHECKER)[None, :]) % 2 == 1
    rgb = rgb * np.where(dark, CHECKER_DARK, 1.0)[..., None]
    return np.ascontiguousarray(np.round(255 * np.clip(rgb, 0, 1)).astype(np.uint8).transpose(1, 0, 2)[::-1])


def render_model(robot_file: str | Path, terrain) -> tuple[mujoco.MjModel, np.ndarray]:
    """The robot and ``terrain`` (None: a plane) for rendering only; also the flow arrows (A, 2, 3) to draw."""
    spec = mujoco.MjSpec.from_file(str(robot_file))
    spec.visual.quality.shadowsize = 4096
    spec.visual.headlight.ambient = [0.35, 0.35, 0.35]
    spec.visual.headlight.diffuse = [0.35, 0.35, 0.35]
    spec.visual.headlight.specular = [0.0, 0.0, 0.0]
    spec.add_texture(name="sky", type=mujoco.mjtTexture.mjTEXTURE_SKYBOX, builtin=mujoco.mjtBuiltin.mjBUILTIN_GRADIENT,
                     rgb1=[0.55, 0.72, 0.92], rgb2=[0.95, 0.97, 1.0], width=256, height=1536)
    spec.worldbody.add_light(name="sun", type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL, pos=[0, 0, 20],
                             dir=[0.4, 0.5, -1.0], castshadow=True, diffuse=[0.65, 0.65, 0.65])
    arrows = np.zeros((0, 2, 3))
    if terrain is None:
        spec.add_texture(name="ground", type=mujoco.mjtTexture.mjTEXTURE_2D, builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER,
                         rgb1=[0.62, 0.62, 0.58], rgb2=[0.51, 0.51, 0.48], width=64, height=64)
        ground = spec.add_material(name="ground", texrepeat=[1 / CHECKER / 2] * 2, texuniform=True)
        ground.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "ground"
        spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.05], material="ground",
                                contype=0, conaffinity=0)
        return spec.compile(), arrows
    heights = np.asarray(terrain.height_field, np.float64)
    nx, ny = heights.shape
    res, (ox, oy) = float(terrain.resolution), terrain.origin_xy
    colours, _ = material_colours(terrain.material)
    image = ground_texture(colours, res, (ox, oy))
    texture = spec.add_texture(name="ground", type=mujoco.mjtTexture.mjTEXTURE_2D, width=image.shape[1],
                               height=image.shape[0], nchannel=3)
    texture.data = image.tobytes()
    ground = spec.add_material(name="ground", texrepeat=[1, 1], texuniform=False, reflectance=0.0)
    ground.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "ground"
    lo, span = float(heights.min()), max(float(heights.max() - heights.min()), 1e-3)
    half_x, half_y = (nx - 1) * res / 2, (ny - 1) * res / 2
    hfield = spec.add_hfield(name="ground", nrow=ny, ncol=nx, size=[half_x, half_y, span, 0.5])
    hfield.userdata = ((heights.T - lo) / span).ravel().tolist()  # MuJoCo: rows along y, values in [0, 1]
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_HFIELD, hfieldname="ground", material="ground",
                            pos=[ox + half_x, oy + half_y, lo], contype=0, conaffinity=0)
    scene = terrain_scene(terrain, max_vertices=nx * ny)
    water = scene.nodes.get("/terrain/water")
    if isinstance(water, Mesh) and len(water.faces):
        used, faces = np.unique(water.faces, return_inverse=True)
        mesh = spec.add_mesh(name="water", uservert=water.vertices[used].ravel().tolist(),
                             userface=faces.reshape(-1, 3).ravel().tolist())
        mesh.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL  # a sheet: no volume
        spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="water", contype=0, conaffinity=0,
                                rgba=[*np.asarray(water.color) / 255, 0.5], group=1)
    flow = scene.nodes.get("/terrain/flow")
    if isinstance(flow, Arrows):
        arrows = np.asarray(flow.points, np.float64)
    return spec.compile(), arrows


class OffscreenGLError(OSError):
    """No OpenGL context for offscreen rendering: the machine's set-up, reported in one line like a missing file."""


def offscreen_renderer(model: mujoco.MjModel, width: int, height: int) -> mujoco.Renderer:
    """``mujoco.Renderer`` of ``model``; without an OpenGL context an OffscreenGLError that says how to get one."""
    try:
        return mujoco.Renderer(model, height=height, width=width)
    except Exception as error:  # no GL context: say how to get one
        backend = f"MUJOCO_GL={os.environ['MUJOCO_GL']}" if "MUJOCO_GL" in os.environ else "MUJOCO_GL is unset"
        raise OffscreenGLError(f"{backend}: offscreen rendering failed "
                               f"({type(error).__name__}: {error}); {GL_FIX}") from error


def check_offscreen_rendering() -> None:
    """Refuse a video before any work when no offscreen OpenGL context can be made (an empty scene, closed at once):
    otherwise the error would come after the env is built and the policy exported."""
    offscreen_renderer(mujoco.MjModel.from_xml_string("<mujoco/>"), 2, 2).close()


class VideoRenderer:
    """Frames of one robot (qpos per frame) on its terrain, from a camera that follows its base."""

    def __init__(self, robot_file: str | Path, terrain, width: int = 640, height: int = 480,
                 distance: float = 3.5, elevation: float = -20.0, azimuth: float = 60.0):
        # the frames are encoded as H.264 in yuv420p (gente-play --video, tools/make_videos.py), whose colour is
        # stored per 2 x 2 pixels: libx264 refuses an odd size, after every frame was rendered
        if not (width >= 2 and height >= 2 and width % 2 == 0 and height % 2 == 0):
            raise ValueError(f"video size {width} x {height} pixels: width and height must be even and >= 2 (H.264 in "
                             f"yuv420p encodes 2 x 2 pixel blocks); use e.g. 640 x 480.")
        self.model, self.arrows = render_model(robot_file, terrain)
        self.model.vis.global_.offwidth = max(self.model.vis.global_.offwidth, width)
        self.model.vis.global_.offheight = max(self.model.vis.global_.offheight, height)
        self.data = mujoco.MjData(self.model)
        self.renderer = offscreen_renderer(self.model, width, height)
        self.renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = True
        self.renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SKYBOX] = True
        self.camera = mujoco.MjvCamera()
        self.camera.type = mujoco.mjtCamera.mjCAMERA_TRACKING
        self.camera.trackbodyid = int(self.model.jnt_bodyid[0])  # the floating base
        self.camera.distance, self.camera.elevation, self.camera.azimuth = distance, elevation, azimuth
        self.frames: list[np.ndarray] = []

    def capture(self, qpos: np.ndarray) -> np.ndarray:
        if len(qpos) != self.model.nq:
            raise ValueError(f"qpos has {len(qpos)} values, the robot model {self.model.nq}: another robot's state")
        self.data.qpos[:] = qpos
        mujoco.mj_forward(self.model, self.data)  # body poses and the subtree centre the camera tracks
        self.renderer.update_scene(self.data, self.camera)
        scn = self.renderer.scene
        for start, end in self.arrows:
            if scn.ngeom >= scn.maxgeom:
                break
            geom = scn.geoms[scn.ngeom]
            mujoco.mjv_initGeom(geom, mujoco.mjtGeom.mjGEOM_ARROW, np.zeros(3), np.zeros(3), np.zeros(9),
                                np.array([0.08, 0.24, 0.78, 1.0], np.float32))
            mujoco.mjv_connector(geom, mujoco.mjtGeom.mjGEOM_ARROW, 0.02, start, end)
            scn.ngeom += 1
        frame = self.renderer.render().copy()
        self.frames.append(frame)
        return frame

    def close(self) -> None:
        self.renderer.close()
