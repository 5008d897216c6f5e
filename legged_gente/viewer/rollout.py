"""Rollouts to replay in the viewer: a small npz format, a recorder, and the robot drawn from its MJCF geoms.

Rollout file (``np.savez_compressed``; T policy steps, R robots, K force arrows per robot; row k is the state
after policy step k + 1, at t = (k + 1) dt)::

    version          ()            int, ROLLOUT_VERSION
    task             ()            str, the registered task (its MJCF draws the robot)
    dt               ()            float, s per policy step
    qpos             (T, R, nq)    float32, MuJoCo qpos of each robot (free joint: world x y z, quaternion w x y z)
    cmd              (T, R, 3)     float32, commanded vx, vy (m/s, base frame) and yaw rate (rad/s)
    vel              (T, R, 3)     float32, actual vx, vy (m/s, base frame) and yaw rate (rad/s)
    done             (T, R)        bool, the episode ended at this step. This row's qpos and vel are the ended
                                   episode's last state and cmd the command it ran under (the env keeps them
                                   before it resets the world within the step: a fall's pose); a diverged
                                   world's row (env.diverged_buf: a non-finite, absurdly fast or ill-solved
                                   state) holds its respawn. The next row is one step into the next episode
    fell             (T, R)        bool, ended by a termination (fall), not by the time-out
    force_labels     (K,)          str, "<kind>:<geom or body>", kind one of FORCE_KINDS
    forces           (T, R, K, 3)  float32, N, world frame (last substep of the policy step; 0 on a done row: the
                                   reset recomputed the world's forces for the respawned robot)
    force_points     (T, R, K, 3)  float32, m, where each force acts
    terrain_heights  (nx, ny)      float32, m; terrain_origin (2,) m; terrain_resolution () m
    terrain_<field>  (nx, ny)      the material map (water_surface, flow_kind, flow_speed, flow_direction,
                                   flow_omega, flow_phase, soil, friction) and terrain_soil_presets (S,) str

Force kinds: ``buoyancy`` (Archimedes on each leg segment's submerged volume, cylinder and caps, as the kernel),
``drag`` (the rest of the water force on the segment: drag, added mass, flow), ``soil`` (under each foot: Bekker's
bulldozing resistance against its motion, which the contacts' friction limit applies, or an RFT soil's forces).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import mujoco
import numpy as np

from legged_gente.terrain.materials import NO_WATER, MaterialMap
from legged_gente.utils.tables import open_npz
from legged_gente.viewer.scene import plane_terrain


ROLLOUT_VERSION = 2
"""2: a done row holds the ended episode's last state (1: the next episode's start, as the env held it after
the step; the same arrays, so a version 1 file is refused rather than shown as version 2)."""
FORCE_KINDS = ("buoyancy", "drag", "soil")
FORCE_COLOURS = {"buoyancy": (0, 200, 80), "drag": (255, 140, 0), "soil": (150, 75, 0)}
_MATERIAL_FIELDS = ("water_surface", "flow_kind", "flow_speed", "flow_direction", "flow_omega", "flow_phase",
                    "soil", "friction")
_KEYS = ("task", "dt", "qpos", "cmd", "vel", "done", "fell", "force_labels", "forces", "force_points",
         "terrain_heights", "terrain_origin", "terrain_resolution", "terrain_soil_presets",
         *(f"terrain_{f}" for f in _MATERIAL_FIELDS))
"""The arrays of a rollout file besides ``version``."""


@dataclasses.dataclass
class Rollout:
    task: str
    dt: float
    qpos: np.ndarray
    cmd: np.ndarray
    vel: np.ndarray
    done: np.ndarray
    fell: np.ndarray
    force_labels: list[str]
    forces: np.ndarray
    force_points: np.ndarray
    heights: np.ndarray
    origin: tuple[float, float]
    resolution: float
    material: MaterialMap

    @property
    def num_steps(self) -> int:
        return self.qpos.shape[0]

    @property
    def num_robots(self) -> int:
        return self.qpos.shape[1]

    def save(self, path: str | Path) -> Path:
        """Write the rollout; returns the file written (numpy adds ``.npz`` to a name without it)."""
        path = Path(path)
        if path.suffix != ".npz":
            path = path.with_name(path.name + ".npz")
        path.parent.mkdir(parents=True, exist_ok=True)
        m = self.material
        np.savez_compressed(
            path, version=ROLLOUT_VERSION, task=self.task, dt=self.dt, qpos=self.qpos.astype(np.float32),
            cmd=self.cmd.astype(np.float32), vel=self.vel.astype(np.float32), done=self.done, fell=self.fell,
            force_labels=np.array(self.force_labels, dtype=str), forces=self.forces.astype(np.float32),
            force_points=self.force_points.astype(np.float32), terrain_heights=self.heights.astype(np.float32),
            terrain_origin=np.asarray(self.origin, np.float64), terrain_resolution=self.resolution,
            terrain_soil_presets=np.array(m.soil_presets, dtype=str),
            **{f"terrain_{f}": getattr(m, f) for f in _MATERIAL_FIELDS},
        )
        return path

    @classmethod
    def load(cls, path: str | Path) -> "Rollout":
        path = Path(path)
        if not path.is_file():
            raise FileNotFoundError(f"rollout {path} does not exist; record one with `gente-view --play ... "
                                    f"--record {path.name}`.")
        with open_npz(path) as f:
            keys = set(f.files)
            if "version" not in keys or "qpos" not in keys:
                hint = " (this is gente-evaluate's traces.npz: open it with --traces)" if "pos" in keys else ""
                raise ValueError(f"{path} is not a rollout file{hint}; it has {sorted(keys)[:8]}.")
            if int(f["version"]) != ROLLOUT_VERSION:
                raise ValueError(f"{path}: rollout version {int(f['version'])}, this viewer reads {ROLLOUT_VERSION}; "
                                 f"record it again.")
            missing = [k for k in _KEYS if k not in keys]
            if missing:
                raise ValueError(f"{path} has no {', '.join(missing)}: it is not a complete rollout file; record it "
                                 f"again.")
            material = MaterialMap(**{k: f[f"terrain_{k}"] for k in _MATERIAL_FIELDS},
                                   soil_presets=[str(s) for s in f["terrain_soil_presets"]])
            rollout = cls(str(f["task"]), float(f["dt"]), f["qpos"], f["cmd"], f["vel"], f["done"], f["fell"],
                          [str(s) for s in f["force_labels"]], f["forces"], f["force_points"], f["terrain_heights"],
                          tuple(f["terrain_origin"].tolist()), float(f["terrain_resolution"]), material)
        problem = _problem(rollout)
        if problem:
            raise ValueError(f"{path}: {problem}; record it again.")
        return rollout


def _problem(rollout: Rollout) -> str | None:
    """What makes the arrays no rollout (shapes that disagree, no steps, a time step or cell size that is no
    positive number, poses that are not finite), or None: the viewer draws every (step, robot) of them."""
    if rollout.qpos.ndim != 3 or 0 in rollout.qpos.shape:
        return (f"qpos has shape {rollout.qpos.shape}: a rollout holds (T, R, nq) with at least one step and one "
                f"robot")
    tr, k = rollout.qpos.shape[:2], len(rollout.force_labels)
    for name, tail in (("cmd", (3,)), ("vel", (3,)), ("done", ()), ("fell", ()), ("forces", (k, 3)),
                       ("force_points", (k, 3))):
        shape = np.shape(getattr(rollout, name))
        if shape != tr + tail:
            return f"{name} has shape {shape}, qpos's (T, R) = {tr} needs {tr + tail}"
    for label in rollout.force_labels:
        kind, colon, _ = label.partition(":")
        if not colon or kind not in FORCE_KINDS:
            return f"force label {label!r} is not <kind>:<name> with kind one of {FORCE_KINDS}"
    for name, value, unit in (("dt", rollout.dt, "s"), ("terrain_resolution", rollout.resolution, "m")):
        if not (np.isfinite(value) and value > 0):
            return f"{name} = {value} {unit} must be a finite number > 0"
    if rollout.heights.ndim != 2 or len(rollout.origin) != 2:
        return (f"terrain_heights has shape {rollout.heights.shape} and terrain_origin {len(rollout.origin)} values: "
                f"a rollout holds (nx, ny) heights and an (x, y) origin")
    for name in _MATERIAL_FIELDS:
        if getattr(rollout.material, name).shape != rollout.heights.shape:
            return (f"terrain_{name} has shape {getattr(rollout.material, name).shape}, terrain_heights "
                    f"{rollout.heights.shape}")
    bad = ~np.isfinite(rollout.qpos).all(axis=(1, 2))
    if bad.any():
        return f"qpos is not finite at step {int(np.argmax(bad))}"
    return None


# ------------------------------------------------------------------------------------------------ the robot
@dataclasses.dataclass
class GeomShape:
    body: int
    vertices: np.ndarray  # (N, 3) in the body frame
    faces: np.ndarray
    color: tuple[int, int, int]


def robot_geoms(mjm: mujoco.MjModel) -> list[GeomShape]:
    """Triangle meshes of the robot's visible geoms (boxes, spheres, capsules, cylinders, ellipsoids, meshes)
    in their bodies' frames; the world body's geoms (terrain, floor) are left out, and so are geom groups 3 and
    above, which MuJoCo's viewer and the videos hide by default (collision-only geoms: the biped's sole spheres,
    the quadruped's calf capsules drawn over its visual calves)."""
    import trimesh

    G = mujoco.mjtGeom
    shapes = []
    for g in range(mjm.ngeom):
        body = int(mjm.geom_bodyid[g])
        if body == 0 or mjm.geom_rgba[g, 3] == 0 or mjm.geom_group[g] >= 3:
            continue
        t, size = int(mjm.geom_type[g]), mjm.geom_size[g]
        if t == G.mjGEOM_BOX:
            mesh = trimesh.creation.box(extents=2 * size)
        elif t == G.mjGEOM_SPHERE:
            mesh = trimesh.creation.icosphere(subdivisions=2, radius=size[0])
        elif t == G.mjGEOM_CAPSULE:
            mesh = trimesh.creation.capsule(height=2 * size[1], radius=size[0], count=[12, 8])
        elif t == G.mjGEOM_CYLINDER:
            mesh = trimesh.creation.cylinder(radius=size[0], height=2 * size[1], sections=12)
        elif t == G.mjGEOM_ELLIPSOID:
            mesh = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
            mesh.apply_scale(size)
        elif t == G.mjGEOM_MESH:
            mid = int(mjm.geom_dataid[g])
            v0, nv = mjm.mesh_vertadr[mid], mjm.mesh_vertnum[mid]
            f0, nf = mjm.mesh_faceadr[mid], mjm.mesh_facenum[mid]
            mesh = trimesh.Trimesh(mjm.mesh_vert[v0:v0 + nv], mjm.mesh_face[f0:f0 + nf], process=False)
        else:
            continue  # planes, heightfields: not part of a robot
        mat = np.zeros(9)  # mju_quat2Mat writes in place: a reshaped slice of a 4 x 4 would be a copy
        mujoco.mju_quat2Mat(mat, mjm.geom_quat[g])
        pose = np.eye(4)
        pose[:3, :3], pose[:3, 3] = mat.reshape(3, 3), mjm.geom_pos[g]
        mesh.apply_transform(pose)
        color = tuple(int(round(255 * c)) for c in mjm.geom_rgba[g, :3])
        shapes.append(GeomShape(body, np.asarray(mesh.vertices, np.float32), np.asarray(mesh.faces, np.uint32), color))
    return shapes


class Kinematics:
    """Body poses from qpos with ``mj_kinematics`` on the CPU (no dynamics)."""

    def __init__(self, mjm: mujoco.MjModel):
        self.mjm, self.data = mjm, mujoco.MjData(mjm)

    def __call__(self, qpos: np.ndarray) -> mujoco.MjData:
        if qpos.shape[-1] != self.mjm.nq:
            raise ValueError(f"qpos has {qpos.shape[-1]} values, the robot model {self.mjm.nq}; the rollout was "
                             f"recorded with another robot: open it with its own --task.")
        self.data.qpos[:] = qpos
        mujoco.mj_kinematics(self.mjm, self.data)
        return self.data


def robot_model(task: str) -> mujoco.MjModel:
    """The robot's MJCF alone (the qpos layout of the task's worlds: the terrain adds no joints)."""
    from legged_gente.envs.task_registry import task_registry
    from legged_gente.sim.assembly import resolve_path

    if task not in task_registry.tasks:
        raise ValueError(f"the rollout is of task {task!r}, not registered here (registered: "
                         f"{sorted(task_registry.tasks)}); a task kept outside the package is registered by its own "
                         f"module: replay it from a script that imports it (docs/new_robot.md)")
    env_cfg, _ = task_registry.get_cfgs(task)
    return mujoco.MjModel.from_xml_path(str(resolve_path(env_cfg.asset.file)))


# ------------------------------------------------------------------------------------------------ recording
def force_layout(env) -> list[str]:
    """The force arrows of one robot of ``env``: buoyancy and drag per wading segment, soil per foot."""
    forces = env.forces
    if forces is None:
        return []
    name = lambda obj, i: mujoco.mj_id2name(env.mjm, obj, int(i)) or str(int(i))  # noqa: E731
    segs = [name(mujoco.mjtObj.mjOBJ_GEOM, g) for g in forces.seg_geom.numpy()[: forces.nseg]]
    feet = [name(mujoco.mjtObj.mjOBJ_BODY, b) for b in forces.foot_body.numpy()[: forces.nfoot]]
    return [f"buoyancy:{s}" for s in segs] + [f"drag:{s}" for s in segs] + [f"soil:{f}" for f in feet]


def robot_forces(env, robots: np.ndarray, kin: Kinematics) -> tuple[np.ndarray, np.ndarray]:
    """(R, K, 3) forces (N) and their points (m) for ``robots`` now, in :func:`force_layout`'s order.

    The water force of a segment is split into buoyancy, eps * rho g V (Archimedes; V the submerged volume of its
    cylinder slices and hemispherical caps as the kernel computes it, ``water_models``; the kernel's noise factor
    eps included), at the volume-weighted mean of the points the kernel applies it at, and the rest (drag, added
    mass, flow).
    """
    from legged_gente.external_forces.water_models import segment_slices, sphere_cap_volume

    f = env.forces
    if f is None:
        return np.zeros((len(robots), 0, 3), np.float32), np.zeros((len(robots), 0, 3), np.float32)
    cfg, nseg, nfoot = f.cfg, f.nseg, f.nfoot
    seg_geom, seg_r, seg_half = f.seg_geom.numpy(), f.seg_radius.numpy(), f.seg_halflen.numpy()
    seg_caps = f.seg_caps.numpy()
    total = f.seg_force.numpy()[robots, :nseg]
    soil = f.foot_force.numpy()[robots, :nfoot]
    eps = f.eps.numpy()[robots]
    foot_body, foot_offset = f.foot_body.numpy()[:nfoot], f.foot_offset.numpy()[:nfoot]
    surface = env.terrain.material.water_surface if env.terrain is not None else None

    def surface_at(p):
        return float(_surface_at(env.terrain, surface, np.asarray(p)[None])[0]) if surface is not None else NO_WATER

    qpos = env.sim.qpos[robots].cpu().numpy()
    out_f = np.zeros((len(robots), 2 * nseg + nfoot, 3), np.float32)
    out_p = np.zeros_like(out_f)
    for k, q in enumerate(qpos):  # a handful of robots, outside the env's step
        d = kin(q)
        for s in range(nseg):
            centre, axis = d.geom_xpos[seg_geom[s]], d.geom_xmat[seg_geom[s]].reshape(3, 3)[:, 2]
            r, half = float(seg_r[s]), float(seg_half[s])
            parts = [(p, vol) for p, _, vol in segment_slices(centre, axis, r, half, surface_at)]
            if seg_caps[s]:  # half the submerged sphere at each end of the cylinder part, as the kernel
                for end in (centre - half * axis, centre + half * axis):
                    parts.append((end, 0.5 * sphere_cap_volume(r, surface_at(end) - (end[2] - r))))
            volume = sum(vol for _, vol in parts)
            if volume <= 0.0:
                continue
            point = sum(vol * p for p, vol in parts) / volume
            lift = np.array([0.0, 0.0, eps[k] * cfg.water_density * f.g * volume])
            out_f[k, s], out_p[k, s] = lift, point
            out_f[k, nseg + s], out_p[k, nseg + s] = total[k, s] - lift, point
        rot = d.xmat[foot_body].reshape(-1, 3, 3)
        out_f[k, 2 * nseg:] = soil[k]
        out_p[k, 2 * nseg:] = d.xpos[foot_body] + np.einsum("fij,fj->fi", rot, foot_offset)
    return out_f, out_p


def _surface_at(terrain, surface: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Water surface z of the cells under ``points`` (the kernel's nearest cell)."""
    i = np.clip(np.round((points[:, 0] - terrain.origin_xy[0]) / terrain.resolution).astype(int), 0, surface.shape[0] - 1)
    j = np.clip(np.round((points[:, 1] - terrain.origin_xy[1]) / terrain.resolution).astype(int), 0, surface.shape[1] - 1)
    return surface[i, j]


class Recorder:
    """Collects a :class:`Rollout` of the first ``num_robots`` robots of ``env``, one :meth:`add` per policy step."""

    def __init__(self, env, task: str, num_robots: int):
        if not 1 <= num_robots <= env.num_envs:
            raise ValueError(f"num_robots={num_robots}: record between 1 and the env's {env.num_envs} robots.")
        self.env, self.task = env, task
        self.robots = np.arange(num_robots)
        self.kin = Kinematics(env.mjm)
        self.labels = force_layout(env)
        self.frames: dict[str, list[np.ndarray]] = {k: [] for k in ("qpos", "cmd", "vel", "done", "fell", "forces",
                                                                     "force_points")}

    def add(self) -> None:
        import torch

        from legged_gente.utils.torch_math import quat_rotate_inverse

        env, r = self.env, self.robots
        # a done row: the state the ended episode ended in (LeggedRobot.episode_end); the velocity as
        # LeggedRobot._update_state's (free joint: world linear, body angular velocity)
        qpos, qvel, cmd = env.episode_end(r)
        vel = torch.cat([quat_rotate_inverse(qpos[:, 3:7], qvel[:, 0:3])[:, :2], qvel[:, 5:6]], 1)
        cmd = cmd[:, :3]
        forces, points = robot_forces(env, r, self.kin)
        done = env.reset_buf[r].cpu().numpy()
        # the reset redrew the ended episode's force noise and recomputed its forces at the respawn: no arrows
        forces[done], points[done] = 0.0, 0.0
        for key, value in (("qpos", qpos.cpu().numpy()), ("cmd", cmd.cpu().numpy()),
                           ("vel", vel.cpu().numpy()), ("done", done),
                           ("fell", done & ~env.time_out_buf[r].cpu().numpy()), ("forces", forces),
                           ("force_points", points)):
            self.frames[key].append(value)

    def rollout(self) -> Rollout:
        if not self.frames["qpos"]:
            raise ValueError("no steps recorded yet; call add() after env.step().")
        t = self.env.terrain if self.env.terrain is not None else plane_terrain()
        arrays = {k: np.stack(v) for k, v in self.frames.items()}
        return Rollout(self.task, float(self.env.dt), arrays["qpos"], arrays["cmd"], arrays["vel"],
                       arrays["done"].astype(bool), arrays["fell"].astype(bool), list(self.labels), arrays["forces"],
                       arrays["force_points"], t.height_field, tuple(t.origin_xy), float(t.resolution), t.material)
