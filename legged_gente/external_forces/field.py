"""``TerrainForces``: the terrain force fields installed on a mujoco_warp model.

Usage by the env (per substep, all inside the captured graph)::

    forces = TerrainForces(mjm, m, d, heights, origin_xy, resolution, material, cfg.forces, seed)
    forces.install()                 # once: sets m.callback.contactfilter / m.callback.passive
    ...
    forces.new_policy_step()         # once per policy step, before its first substep's passive forces (redraws
                                     # the flow noise xi; the env draws it before the forward that computes them)
    for _ in range(decimation):
        mjw.step(m, d)               # runs the callbacks
        forces.after_substep()       # foot normal forces and slip for the next substep, privileged obs
    ...
    forces.reset(mask)               # with the env's reset mask (wp.array of bool, nworld), after resetting d
    critic_obs_part = forces.privileged_obs()   # torch (nworld, n_feet * 12), zero-copy

TerrainForces owns ``d.xfrc_applied`` entirely: the passive callback zeroes it every substep and adds the
terrain forces. Anything else that needs external pushes must change velocities instead.
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import mujoco
import numpy as np
import warp as wp

from legged_gente.external_forces import contact as C
from legged_gente.external_forces import kernels as K
from legged_gente.external_forces import rft as R
from legged_gente.external_forces import water as W
from legged_gente.external_forces import water_models as WM
from legged_gente.external_forces.config import ForcesConfig
from legged_gente.terrain.soil import preset_table
from legged_gente.terrain.materials import FLOW_KINDS, NO_SOIL, MaterialMap


_ATTRS = [a for a in vars(ForcesConfig) if not a.startswith("_")]
# numeric settings and the bound each must meet: below it a substep divides by zero, gives NaN forces (a foot at rest
# on soil with bulldozing_speed_reg 0) or forces that add energy (negative drag coefficients or density)
_POSITIVE = ("water_density", "friction_reference", "soil_friction_cap", "sole_contact_max_depth",
             "terrain_contact_max_depth", "bulldozing_speed_reg", "sinkage_load_tau", "traction_load_tau")
_NON_NEGATIVE = ("drag_coefficient", "added_mass_coefficient", "plate_drag_coefficient", "sphere_drag_coefficient",
                 "noise_std", "contact_threshold", "liftoff_time", "liftoff_clearance", "min_friction",
                 "sinkage_rate", "max_rut_depth")


# threads a block for the kernels over (worlds, feet or leg segments): a few thousand robots' feet make a grid of a
# few dozen blocks of Warp's default 256, on a few dozen of the GPU's SMs; smaller blocks spread them over more
# (at 4096 robots the force kernels' share of a substep fell from 5.6 to 5.0-5.1 %: docs/performance.md)
LIMB_BLOCK_DIM = 64

# a soil whose Bekker sinkage under a standing robot's feet passes this (m) has its stiffness in the wrong unit, or
# swallows the legs: the ruts the contacts show stop at max_rut_depth, and the robot sinks until it is reset
MAX_STANDING_SINKAGE = 0.3


def _check_values(cfg) -> None:
    """One ValueError naming the first numeric setting out of its range (infinite ones too: an infinite density
    or noise gives inf / NaN forces, an infinite friction_reference frictionless contacts) and the default to use;
    likewise a sole size given on one side only (the other would be ignored for the geoms' footprint)."""
    for names, positive in ((_POSITIVE, True), (_NON_NEGATIVE, False)):
        for name in names:
            value = getattr(cfg, name)
            try:
                ok = math.isfinite(float(value)) and (float(value) > 0 if positive else float(value) >= 0)
            except (TypeError, ValueError):
                ok = False
            if not ok:
                where = " (in an env: set cfg.terrain.static_friction)" if name == "friction_reference" else ""
                raise ValueError(f"forces.{name}={value!r} must be a finite number {'>' if positive else '>='} 0"
                                 f"{where}; the default is {getattr(ForcesConfig, name)}.")
    if cfg.soil and not cfg.terrain_contact_max_depth > cfg.max_rut_depth:
        # the contact filter caps a foot's penetration, then shows its rut (kernels.contact_filter_kernel): a cap
        # within the rut leaves a foot in it no contact, and it sinks through the soil
        raise ValueError(f"forces.terrain_contact_max_depth={cfg.terrain_contact_max_depth!r} must exceed "
                         f"max_rut_depth={cfg.max_rut_depth!r}, or a foot in its rut gets no contact and sinks "
                         f"through the soil; the defaults are {ForcesConfig.terrain_contact_max_depth} and "
                         f"{ForcesConfig.max_rut_depth}.")
    if (cfg.sole_length is None) != (cfg.sole_width is None):
        raise ValueError(f"forces.sole_length={cfg.sole_length!r} and sole_width={cfg.sole_width!r}: give both (a "
                         f"rectangular sole, m) or neither (the footprint of the foot geoms).")


def _check_material(material: MaterialMap, shape: tuple[int, int]) -> None:
    """One ValueError naming the first layer of the map the kernels would misread: another shape than the heights'
    grid (read out of its bounds at the heights' cell indices), a flow kind the flow formula does not know (still
    water, silently), a soil index below NO_SOIL (rigid ground, silently), a non-finite value or a negative
    friction (a frictionless contact)."""
    for field in dataclasses.fields(MaterialMap):
        if field.name == "soil_presets":
            continue
        layer = np.asarray(getattr(material, field.name))
        if layer.shape != shape:
            raise ValueError(f"material.{field.name} has shape {layer.shape}; the heights' grid is {shape}: give "
                             f"every layer of the MaterialMap one value per heightfield cell.")
        if field.name == "flow_kind":
            bad, fix = layer[~np.isin(layer, tuple(FLOW_KINDS.values()))], "use 0 (still), 1 (current) or 2 (tide)"
        elif field.name == "soil":
            bad, fix = layer[layer < NO_SOIL], f"use {NO_SOIL} (rigid ground) or an index into soil_presets"
        elif field.name == "friction":
            bad, fix = layer[~(layer >= 0) | ~np.isfinite(layer)], "friction must be a finite number >= 0"
        else:
            bad, fix = layer[~np.isfinite(layer)], "its values must be finite (NO_WATER marks a dry cell)"
        if bad.size:
            raise ValueError(f"material.{field.name} holds {bad.flat[0]}; {fix}.")


def _warn_unfelt_materials(material: MaterialMap, cfg) -> None:
    """Water or soil on the terrain that no named geom feels: the robot would walk through it as if it were not
    there (soil: rigid ground with its friction), which a config that forgot the geom names should hear of."""
    foot_water = cfg.foot_water_geom_names if cfg.foot_water_geom_names is not None else cfg.foot_geom_names
    if cfg.wading and material.has_water().any() and not (cfg.leg_geom_names or foot_water):
        warnings.warn("forces: the terrain has water, but forces.leg_geom_names and forces.foot_geom_names name no "
                      "geom: no water force acts on the robot; name its legs' capsules and its feet's geoms (or set "
                      "forces.wading = False)", stacklevel=3)
    if cfg.soil and material.has_soil().any() and not cfg.foot_geom_names:
        warnings.warn("forces: the terrain has soil, but forces.foot_geom_names names no geom: no foot sinks into it "
                      "or is held by its shear strength (it is rigid ground with tan(phi) friction); name the feet's "
                      "sole geoms (or set forces.soil = False)", stacklevel=3)


def _foot_spheres_inside_legs(mjm, foot_geoms, leg_geoms) -> tuple[np.ndarray, np.ndarray]:
    """Per foot water geom: whether it is a sphere lying wholly inside a leg capsule or cylinder welded to it, and
    whether wholly inside that leg's straight part. A ball inside a capsule's end cap (the quadruped's foot in its
    calf) keeps its drag and added mass and loses its buoyancy, which the leg's cap counts (Archimedes on the union);
    a ball inside the straight part gets no water load at all: the leg's strips already hold its volume's buoyancy,
    drag and added mass."""
    data = mujoco.MjData(mjm)
    mujoco.mj_kinematics(mjm, data)
    inside = np.zeros(len(foot_geoms), bool)
    in_straight = np.zeros(len(foot_geoms), bool)
    for k, g in enumerate(foot_geoms):
        if mjm.geom_type[g] != int(mujoco.mjtGeom.mjGEOM_SPHERE):
            continue
        r = mjm.geom_size[g, 0]
        for s in leg_geoms:
            if not _welded(mjm, int(mjm.geom_bodyid[g]), int(mjm.geom_bodyid[s])):
                continue
            axis = data.geom_xmat[s].reshape(3, 3)[:, 2]
            radius, half = mjm.geom_size[s, 0], mjm.geom_size[s, 1]
            t = float(np.dot(data.geom_xpos[g] - data.geom_xpos[s], axis))
            radial = np.linalg.norm(data.geom_xpos[g] - data.geom_xpos[s] - t * axis)
            straight = abs(t) <= half - r + 1e-9 and radial <= radius - r + 1e-9
            in_straight[k] |= straight
            if mjm.geom_type[s] == int(mujoco.mjtGeom.mjGEOM_CAPSULE):
                inside[k] |= np.hypot(max(abs(t) - half, 0.0), radial) <= radius - r + 1e-9
            else:
                inside[k] |= straight
    return inside, in_straight


def geom_body_box(mjm, g: int) -> tuple[np.ndarray, np.ndarray]:
    """Centre and half extents, in its body's frame, of the box around geom ``g`` as it is turned in the body (a
    capsule lying along x spans its length in x): exact for spheres, capsules, cylinders and boxes, the turned
    bounding box (``geom_aabb``) of any other geom."""
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, mjm.geom_quat[g])
    rot = rot.reshape(3, 3)
    r, h, axis = mjm.geom_size[g, 0], mjm.geom_size[g, 1], np.abs(rot[:, 2])
    centre, half = mjm.geom_pos[g] + rot @ mjm.geom_aabb[g, :3], np.abs(rot) @ mjm.geom_aabb[g, 3:]
    if mjm.geom_type[g] == mujoco.mjtGeom.mjGEOM_SPHERE:
        half = np.full(3, r)
    elif mjm.geom_type[g] == mujoco.mjtGeom.mjGEOM_CAPSULE:
        half = axis * h + r
    elif mjm.geom_type[g] == mujoco.mjtGeom.mjGEOM_CYLINDER:
        half = axis * h + r * np.sqrt(np.maximum(1.0 - axis**2, 0.0))
    return centre, half


def _body_box(mjm, geoms) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper corners, in their body's frame, of the box around the geoms (``geom_body_box``'s boxes)."""
    boxes = [geom_body_box(mjm, g) for g in geoms]
    return np.min([c - h for c, h in boxes], axis=0), np.max([c + h for c, h in boxes], axis=0)


def _welded(mjm, body_a: int, body_b: int) -> bool:
    """Whether two bodies move as one: they hang from the same body through jointless bodies only (the same body,
    one a jointless descendant of the other, or jointless children of a common parent)."""

    def weld_root(b: int) -> int:
        while b > 0 and mjm.body_jntnum[b] == 0:
            b = int(mjm.body_parentid[b])
        return b

    return weld_root(body_a) == weld_root(body_b)


def _geom_ids(mjm: mujoco.MjModel, names, what: str) -> np.ndarray:
    ids = []
    for name in names:
        if list(names).count(name) > 1:  # its forces would be applied twice
            raise ValueError(f"forces.{what} lists {name!r} {list(names).count(name)} times; list each geom once.")
        gid = mujoco.mj_name2id(mjm, mujoco.mjtObj.mjOBJ_GEOM, name)
        if gid < 0:
            known = [mujoco.mj_id2name(mjm, mujoco.mjtObj.mjOBJ_GEOM, i) for i in range(mjm.ngeom)
                     if mjm.geom_bodyid[i] != 0]  # the robot's: the terrain's pieces are the world body's
            raise ValueError(f"forces.{what}: no geom named {name!r} in the robot (exact names); its named geoms: "
                             f"{[k for k in known if k]}.")
        ids.append(gid)
    return np.asarray(ids, np.int32)


def _dof_chains(mjm: mujoco.MjModel, bodies: np.ndarray) -> np.ndarray:
    """(len(bodies), longest chain) dofs moving each body, its last dof first, then up to the root; -1 pads (a
    row of -1: a body fixed to the world). At least one row and one column."""
    chains = []
    for body in bodies:
        while body > 0 and mjm.body_dofnum[body] == 0:
            body = mjm.body_parentid[body]
        dof, chain = (mjm.body_dofadr[body] + mjm.body_dofnum[body] - 1 if body > 0 else -1), []
        while dof >= 0:
            chain.append(dof)
            dof = mjm.dof_parentid[dof]
        chains.append(chain)
    out = np.full((max(len(chains), 1), max([len(c) for c in chains] + [1])), -1, np.int32)
    for row, chain in zip(out, chains):
        row[:len(chain)] = chain
    return out


def foot_groups(mjm: mujoco.MjModel, names) -> tuple[list[int], list[np.ndarray]]:
    """The feet of ``forces.foot_geom_names``: the listed geoms grouped by body, one foot per body (a box sole,
    or the spheres at its corners), as (foot bodies, geom ids per foot) in the order listed."""
    geoms = _geom_ids(mjm, names, "foot_geom_names")
    bodies = list(dict.fromkeys(int(b) for b in mjm.geom_bodyid[geoms]))
    return bodies, [geoms[mjm.geom_bodyid[geoms] == b] for b in bodies]


def privileged_obs_size(mjm: mujoco.MjModel, cfg) -> int:
    """Width of ``TerrainForces.privileged_obs()`` for this robot and config, without building the field."""
    return len(foot_groups(mjm, cfg.foot_geom_names)[0]) * K.OBS_PER_FOOT


class PackedArrays:
    """Warp arrays carved from one allocation, in the order given: whoever copies them all (the stage and the
    physics-neutral forward, four times a policy step) copies one buffer instead of one array at a time. The buffer
    is int32 so that comparing two copies compares bits (a float view would hold NaN patterns); every array's
    element is a whole number of its 4-byte words."""

    def __init__(self, layout: dict[str, tuple[int | tuple[int, ...], type]], device):
        sizes = {name: math.prod(np.atleast_1d(shape).tolist()) * wp.types.type_size_in_bytes(dtype)
                 for name, (shape, dtype) in layout.items()}
        odd = [name for name, (_, dtype) in layout.items() if wp.types.type_size_in_bytes(dtype) % 4]
        if odd:
            raise ValueError(f"PackedArrays: {odd} have elements that are not whole 4-byte words; keep such arrays "
                             f"(bool, int8, float16) out of the packed state.")
        self.buffer = wp.zeros(sum(sizes.values()) // 4, dtype=wp.int32, device=device)
        self.arrays: dict[str, wp.array] = {}
        offset = 0
        for name, (shape, dtype) in layout.items():
            view = wp.array(ptr=self.buffer.ptr + offset, dtype=dtype, shape=shape, device=device)
            view._ref = self.buffer  # as Warp's own views: the buffer lives as long as any view of it
            self.arrays[name] = view
            offset += sizes[name]


class TerrainForces:
    """Terrain force fields for ``nworld`` robots on one terrain (see the module docstring for the calls).

    Args:
        mjm: host ``mujoco.MjModel`` (names, geom sizes, masses, timestep, gravity).
        m, d: ``mjw.Model`` / ``mjw.Data`` made from ``mjm``.
        heights: float (nx, ny) terrain heights (m); a plane is ``np.zeros((1, 1))`` with a (1, 1) map.
        origin_xy: world (x, y) of cell (0, 0); resolution: cell size (m).
        material: ``MaterialMap`` of shape (nx, ny).
        cfg: object with the attributes of :class:`ForcesConfig`.
        seed: seed of all per-env draws.
    """

    def __init__(self, mjm, m, d, heights, origin_xy, resolution, material: MaterialMap, cfg, seed: int = 0):
        missing = [a for a in _ATTRS if not hasattr(cfg, a)]
        if missing:
            raise ValueError(f"forces config lacks {missing}; subclass legged_gente.external_forces.field."
                             f"ForcesConfig to get the defaults.")
        _check_values(cfg)
        heights = np.asarray(heights, np.float32)
        if heights.ndim != 2 or heights.shape != material.shape:
            raise ValueError(f"heights {heights.shape} and material map {material.shape} must be the same 2-D "
                             f"grid; build both from the same Terrain.")
        _check_material(material, heights.shape)
        _warn_unfelt_materials(material, cfg)
        if not resolution > 0:
            raise ValueError(f"resolution must be > 0 m, got {resolution}.")
        self.m, self.d, self.cfg = m, d, cfg
        self.nworld = d.nworld
        self.seed = int(seed)
        self.dt = float(mjm.opt.timestep)
        self.g = float(np.linalg.norm(mjm.opt.gravity))
        self.origin = wp.vec2(float(origin_xy[0]), float(origin_xy[1]))
        self.resolution = float(resolution)
        dev = d.xfrc_applied.device
        self.device = dev

        def arr(x, dtype):
            return wp.array(np.ascontiguousarray(x), dtype=dtype, device=dev)

        def one_row_if_empty(x: np.ndarray) -> np.ndarray:
            """``x``, or one row of zeros in its place when it has none (a robot without water points)."""
            return x if len(x) else np.zeros((1, *x.shape[1:]), x.dtype)

        self.heights = arr(heights, float)
        # the contacts' heightfield: a plane's (1, 1) grid as one wide constant cell
        if min(heights.shape) < 2:
            self.hf_heights = arr(np.full((2, 2), heights.flat[0], np.float32), float)
            self.hf_origin, self.hf_res = wp.vec2(-1.0e4, -1.0e4), 2.0e4
        else:
            self.hf_heights, self.hf_origin, self.hf_res = self.heights, self.origin, self.resolution
        self.water = K.WaterMap()
        self.water.origin, self.water.resolution = self.origin, self.resolution
        self.water.surface = arr(material.water_surface.astype(np.float32), float)
        self.water.flow_kind = arr(material.flow_kind.astype(np.int32), int)
        self.water.flow_speed = arr(material.flow_speed.astype(np.float32), float)
        self.water.flow_dir = arr(material.flow_direction.astype(np.float32), float)
        self.water.flow_omega = arr(material.flow_omega.astype(np.float32), float)
        self.water.flow_phase = arr(material.flow_phase.astype(np.float32), float)
        self.soil = arr(material.soil.astype(np.int32), int)
        self.friction = arr(material.friction.astype(np.float32), float)
        self.soilmap = K.SoilMap()
        self.soilmap.origin, self.soilmap.resolution = self.origin, self.resolution
        self.soilmap.soil, self.soilmap.friction = self.soil, self.friction
        if material.has_soil().any() and int(material.soil.max()) >= len(material.soil_presets):
            raise ValueError(f"material.soil indexes preset {int(material.soil.max())} but soil_presets has "
                             f"{len(material.soil_presets)} names; list every soil used in soil_presets.")
        table = preset_table(list(material.soil_presets))
        self.soil_table = arr(table, float)
        self.has_rft = bool((table[:, K.MODEL, 0] > 0.5).any())
        npreset = self.soil_table.shape[0]

        # legs
        seg = _geom_ids(mjm, cfg.leg_geom_names, "leg_geom_names")
        bad = [cfg.leg_geom_names[i] for i, g in enumerate(seg)
               if mjm.geom_type[g] not in (int(mujoco.mjtGeom.mjGEOM_CAPSULE), int(mujoco.mjtGeom.mjGEOM_CYLINDER))]
        if bad:
            raise ValueError(f"forces.leg_geom_names {bad} are not capsules or cylinders; list only the legs' "
                             f"capsule/cylinder geoms.")
        self.nseg = len(seg)
        self.seg_geom = arr(seg, int)
        self.seg_body = arr(mjm.geom_bodyid[seg].astype(np.int32), int)
        self.seg_radius = arr(mjm.geom_size[seg, 0].astype(np.float32), float)
        self.seg_halflen = arr(mjm.geom_size[seg, 1].astype(np.float32), float)  # cylinder part's half-length
        self.seg_caps = arr((mjm.geom_type[seg] == int(mujoco.mjtGeom.mjGEOM_CAPSULE)).astype(np.int32), int)

        bodies, groups = foot_groups(mjm, cfg.foot_geom_names)
        self.nfoot = len(bodies)
        self.foot_names = [mujoco.mj_id2name(mjm, mujoco.mjtObj.mjOBJ_BODY, b) or f"body{b}" for b in bodies]
        self.foot_body = arr(np.asarray(bodies, np.int32), int)
        # sole centre in the foot body's frame: the mean of its geoms' centres
        offsets = [mjm.geom_pos[g].mean(0) for g in groups] or np.zeros((1, 3))
        self.foot_offset = arr(np.asarray(offsets, np.float32), wp.vec3)
        # the sole's contact plane below that centre (body frame, foot level): where the soil forces act
        drops = [offsets[f][2] - _body_box(mjm, group)[0][2] for f, group in enumerate(groups)] or [0.0]
        self.foot_drop = arr(np.asarray(drops, np.float32), float)
        geom_foot = np.full(mjm.ngeom, -1, np.int32)
        for f, g in enumerate(groups):
            geom_foot[g] = f
        self.geom_foot = arr(geom_foot, int)
        self.geom_bodyid = arr(mjm.geom_bodyid.astype(np.int32), int)
        foot_water = self._foot_water_geoms(mjm, groups)
        inside, in_straight = _foot_spheres_inside_legs(mjm, foot_water, seg)
        foot_water, inside = foot_water[~in_straight], inside[~in_straight]
        self.foot_water_geom = arr(foot_water, int)
        self.foot_buoyancy = arr((~inside).astype(np.float32), float)
        self._check_diagonal_mass(mjm, np.concatenate([seg, foot_water]).astype(int))
        sphere = int(mujoco.mjtGeom.mjGEOM_SPHERE)
        foot_added_mass = np.asarray([WM.foot_added_mass("sphere" if mjm.geom_type[g] == sphere else "box",
                                                         mjm.geom_size[g], float(cfg.water_density))
                                      for g in foot_water], np.float32).reshape(-1, 3)
        self.foot_added_mass = arr(one_row_if_empty(foot_added_mass), wp.vec3)
        self.sole_length, self.sole_width, self.sole_disc = self._sole(mjm, groups)
        # Bekker's pressure over the footprint, whose b is a rectangle's smaller side or a disc's radius (Wong,
        # Theory of Ground Vehicles, ch. 2)
        if self.sole_disc:
            self.sole_area, self.bekker_width = math.pi * (0.5 * self.sole_length) ** 2, 0.5 * self.sole_length
        else:
            self.sole_area = self.sole_length * self.sole_width
            self.bekker_width = min(self.sole_length, self.sole_width)
        # a foot's share of the robot's weight, for the standing sinkage below
        stance = float(mjm.body_mass[1:].sum()) * self.g / max(self.nfoot, 1) / self.sole_area
        for s, name in enumerate(material.soil_presets):  # p = (kc / b + kphi) z^n must give a sinkage
            if table[s, K.MODEL, 0] >= 0.5:  # RFT: no Bekker law
                continue
            k = table[s, K.KC, 0] / self.bekker_width + table[s, K.KPHI, 0]
            if not k > 0:
                raise ValueError(f"soil {name!r}: kc/b + kphi = {k:.4g} N/m^(n+2) <= 0 for this robot's sole (b = "
                                 f"{self.bekker_width:.4g} m): Bekker's law gives no sinkage; raise kphi or kc.")
            sinkage = (stance / k) ** (1.0 / table[s, K.N, 0])
            if self.nfoot and sinkage > MAX_STANDING_SINKAGE:
                warnings.warn(f"soil {name!r}: this robot standing on it sinks {sinkage:.3g} m by Bekker's law "
                              f"(its weight shared by its {self.nfoot} feet, {stance:.4g} Pa under a sole); kc and "
                              f"kphi are in N/m^(n+1) and N/m^(n+2), and tables in kN need 1000 times the number",
                              stacklevel=2)
        self._setup_sole_contacts(mjm, groups)
        self._filter_key, self._filter_launches = None, []

        n, nf, ns = self.nworld, max(self.nfoot, 1), max(self.nseg, 1)
        z = lambda shape, dtype: wp.zeros(shape, dtype=dtype, device=dev)  # noqa: E731
        self.counter = z(1, int)
        # the water points that carry added mass (each leg slice's Gauss point, then each foot): their geoms, their
        # added masses along the geom's axes (per kg of a slice: across its axis; a wholly wet foot's), the dofs
        # moving each; every substep the points kernels write each point's scale and offset from the tree's centre
        # of mass (points x worlds), added_mass_kernel reads them
        point_geom = np.concatenate([np.repeat(seg, W.NGAUSS), foot_water]).astype(np.int32)
        axes = np.concatenate([np.tile([1.0, 1.0, 0.0], (W.NGAUSS * len(seg), 1)), foot_added_mass])
        self.point_geom = arr(one_row_if_empty(point_geom), int)
        self.point_axes = arr(one_row_if_empty(axes.astype(np.float32)), wp.vec3)
        self.point_dofs = arr(_dof_chains(mjm, mjm.geom_bodyid[point_geom]), int)
        self.point_mass = z((self.point_dofs.shape[0], n), float)
        self.point_offset = z((self.point_dofs.shape[0], n), wp.vec3)
        self.obs = z((n, self.nfoot * K.OBS_PER_FOOT), float)
        # what the callbacks and hooks carry from one substep to the next, per world (``per_world_state``)
        state = {
            "eps": (n, float), "xi": (n, float),  # drag and flow noise
            "soil_params": ((n, npreset, K.NSOILPARAM), float),
            "seg_force": ((n, ns), wp.vec3), "foot_water_force": ((n, max(len(self.foot_water_geom), 1)), wp.vec3),
            "foot_fn": ((n, nf), float), "foot_vel": ((n, nf), wp.vec3), "foot_slip": ((n, nf), float),
            "foot_air": ((n, nf), float), "foot_sinkage": ((n, nf), float), "foot_soil": ((n, nf), int),
            "foot_touch": ((n, nf), int), "foot_cand": ((n, nf), float), "foot_near": ((n, nf), int),
            "foot_stance": ((n, nf), float), "foot_load": ((n, nf), float), "foot_sink_load": ((n, nf), float),
            "foot_traction_load": ((n, nf), float),
            # RFT's vertical stress under each sole's motion, in units of zeta (rft_force_kernel; 1: at rest)
            "foot_support": ((n, nf), float),
            "foot_force": ((n, nf), wp.vec3),
        }
        # each rut leg's own soil state (kernels.LegSoil), its normal force and time in the air; without rut legs
        # one-element placeholders for the sole kernel's arguments, which are no per-world state to carry
        legs = {"leg_fn": float, "leg_air": float, "leg_load": float, "leg_sink_load": float, "leg_sinkage": float,
                "leg_cand": float, "leg_touch": int, "leg_inrut": int}
        if self.has_rut_legs:
            state.update({name: ((n, self.nleg), dtype) for name, dtype in legs.items()})
        else:
            vars(self).update({name: z((1, 1), dtype) for name, dtype in legs.items()})
        self._state = PackedArrays(state, dev)
        vars(self).update(self._state.arrays)
        self.foot_soil.fill_(-1)
        self.foot_support.fill_(1.0)
        self.legs = K.LegSoil()
        self.legs.load, self.legs.sinkage, self.legs.cand = self.leg_load, self.leg_sinkage, self.leg_cand
        self.legs.sink_load = self.leg_sink_load
        self.legs.touch, self.legs.inrut = self.leg_touch, self.leg_inrut
        self._all = wp.array(np.ones(n, bool), dtype=bool, device=dev)
        # the side branches of ``_in_parallel`` (the passive kernels' second to fifth, the contact filter's second)
        self._side_streams = [wp.Stream(dev) for _ in range(4)] if dev.is_cuda and cfg.parallel_kernels else []
        self.reset(self._all)
        self.new_policy_step()

    def per_world_state(self) -> list[wp.array]:
        """What the callbacks and hooks carry from one substep to the next (ruts, slip, loads, forces, noise, soil
        draws: every per-world array but the observation and the added-mass points, written afresh before they are
        read), which a physics-neutral forward puts back: one array, the allocation they are all views of."""
        return [self._state.buffer]

    # ------------------------------------------------------------------ setup helpers
    def _check_diagonal_mass(self, mjm, geoms):
        """MuJoCo stores only the diagonal of M for "simple" bodies (children of the world with a diagonal inertia,
        e.g. a lone free body or slide joints): the added mass of legs and feet on them loses its coupling between
        dofs."""
        if not self.cfg.wading or self.cfg.paper_added_mass:
            return
        depth = np.zeros(mjm.nv, int)
        for i in range(mjm.nv):
            depth[i] = 1 + (depth[mjm.dof_parentid[i]] if mjm.dof_parentid[i] >= 0 else 0)
        cut = depth > mjm.M_rownnz  # a dof whose row of M is shortened
        cut_geoms = [mujoco.mj_id2name(mjm, mujoco.mjtObj.mjOBJ_GEOM, g)
                     for g, chain in zip(geoms, _dof_chains(mjm, mjm.geom_bodyid[geoms])) if cut[chain[chain >= 0]].any()]
        if cut_geoms:
            warnings.warn(f"forces: water geoms {cut_geoms} are on bodies whose mass matrix MuJoCo keeps diagonal; "
                          f"their added mass enters per dof, without the coupling between dofs (exact only for "
                          f"motion along slide axes). Put such a body under another body to get the full matrix.",
                          stacklevel=3)

    def _foot_water_geoms(self, mjm, groups) -> np.ndarray:
        """The foot geoms that feel water (``foot_water_geom_names``, else the feet's geoms): spheres or boxes."""
        names = self.cfg.foot_water_geom_names
        geoms = (_geom_ids(mjm, names, "foot_water_geom_names") if names is not None
                 else np.concatenate(groups).astype(np.int32) if groups else np.zeros(0, np.int32))
        ok = (int(mujoco.mjtGeom.mjGEOM_SPHERE), int(mujoco.mjtGeom.mjGEOM_BOX))
        bad = [mujoco.mj_id2name(mjm, mujoco.mjtObj.mjOBJ_GEOM, g) for g in geoms if mjm.geom_type[g] not in ok]
        if self.cfg.wading and bad:
            raise ValueError(f"forces: foot geoms {bad} feel water but are neither spheres nor boxes; list sphere or "
                             f"box soles in forces.foot_water_geom_names (or [] for no water force on the feet).")
        return geoms

    def _setup_sole_contacts(self, mjm, groups):
        """Sphere / capsule sole geoms get analytic terrain contacts (``contact.py``) when ``sole_contact`` is on, and
        so do the legs of ``rut_leg_geom_names``; MuJoCo must then not collide them with the terrain (the geoms on
        the world body that collide: a heightfield's pieces, which share their collision settings; the contacts made
        here name the first)."""
        self.npt, self.nleg = 0, 0
        # True once every foot geom has analytic contacts, so none is in MuJoCo's: the contact filter then touches
        # no foot's state, and the feet's cells may be found beside it (``contact_filter``)
        self.feet_apart_from_filter = False
        self.geom_leg = wp.array(np.full(mjm.ngeom, -1, np.int32), dtype=int, device=self.device)
        legs = list(self.cfg.rut_leg_geom_names)
        if legs and not (self.cfg.sole_contact and groups):
            raise ValueError(f"forces.rut_leg_geom_names {legs} follow their feet's analytic sole contacts, but "
                             f"forces.sole_contact is off or there are no foot_geom_names; turn it on or list no legs.")
        if not (self.cfg.sole_contact and groups):
            return
        geoms, ends, feet = C.sole_points(mjm, groups)
        ground = [g for g in range(mjm.ngeom) if mjm.geom_bodyid[g] == 0 and (mjm.geom_contype[g] or
                                                                            mjm.geom_conaffinity[g])]
        if len(geoms) == 0:
            if legs:
                raise ValueError(f"forces.rut_leg_geom_names {legs}: the feet have no sphere or capsule soles, whose "
                                 f"analytic contacts a leg follows; list no legs for box soles.")
            return
        leg_geom_ids, leg_foot = self._rut_legs(mjm, legs, groups)
        leg_geoms, leg_ends, leg_feet, leg_steps, leg_index = C.leg_points(mjm, leg_geom_ids, leg_foot)
        sole_leg = np.full(len(geoms), -1, np.int32)  # a sole point belongs to no leg
        geoms, ends, feet, steps, pt_leg = (np.concatenate(p) for p in (
            (geoms, leg_geoms), (ends, leg_ends), (feet, leg_feet), (np.zeros(len(geoms), np.float32), leg_steps),
            (sole_leg, leg_index)))
        if not ground:
            raise ValueError("forces.sole_contact needs a colliding terrain geom on the world body, found none; set "
                             "forces.sole_contact=False for such scenes.")
        self.terrain_geom = ground[0]
        clash = sorted({mujoco.mj_id2name(mjm, mujoco.mjtObj.mjOBJ_GEOM, int(g)) for g in geoms
                        for t in ground if (mjm.geom_contype[g] & mjm.geom_conaffinity[t]) or
                        (mjm.geom_conaffinity[g] & mjm.geom_contype[t])})
        if clash:
            raise ValueError(f"forces.sole_contact: sole or rut leg geoms {clash} still collide with the terrain in "
                             f"MuJoCo; build the model with external_forces.contact.exclude_sole_collisions(spec, "
                             f"names) (contype = conaffinity = 0) or set forces.sole_contact=False.")
        self.npt, self.nleg = len(geoms), len(leg_geom_ids)
        self.feet_apart_from_filter = set(np.concatenate(groups).tolist()) <= set(geoms.tolist())
        dev = self.device
        self.pt_geom = wp.array(geoms, dtype=int, device=dev)
        self.pt_end = wp.array(ends, dtype=float, device=dev)
        self.pt_foot = wp.array(feet, dtype=int, device=dev)
        self.pt_leg_step = wp.array(steps, dtype=float, device=dev)
        self.pt_leg = wp.array(pt_leg, dtype=int, device=dev)
        geom_leg = np.full(mjm.ngeom, -1, np.int32)
        geom_leg[np.asarray(leg_geom_ids, int)] = np.arange(self.nleg)
        self.geom_leg = wp.array(geom_leg, dtype=int, device=dev)

    @property
    def has_rut_legs(self) -> bool:
        return self.nleg > 0

    def _rut_legs(self, mjm, names, groups) -> tuple[np.ndarray, list[int]]:
        """The geoms of ``rut_leg_geom_names`` and the foot each follows: the one foot whose body is the geom's body
        or hangs below it. A leg follows its foot down the foot's hole only if it is a capsule no wider than the
        sole (a disc's diameter, a rectangle's smaller side)."""
        geoms = _geom_ids(mjm, names, "rut_leg_geom_names")
        capsule = int(mujoco.mjtGeom.mjGEOM_CAPSULE)
        sole = min(self.sole_length, self.sole_width)  # a disc's: its diameter, both
        foot_bodies = [int(mjm.geom_bodyid[group[0]]) for group in groups]
        feet = []
        for name, g in zip(names, geoms):
            if int(mjm.geom_type[g]) != capsule:
                raise ValueError(f"forces.rut_leg_geom_names: {name!r} is not a capsule; list the legs' capsules.")
            if 2.0 * float(mjm.geom_size[g, 0]) > sole + 1e-9:
                raise ValueError(f"forces.rut_leg_geom_names: {name!r} is {2 * mjm.geom_size[g, 0]:.4g} m wide, wider "
                                 f"than the sole ({sole:.4g} m), so it cannot follow its foot into the foot's rut; "
                                 f"leave it out.")
            below = []
            for f, b in enumerate(foot_bodies):
                while b > 0 and b != int(mjm.geom_bodyid[g]):
                    b = int(mjm.body_parentid[b])
                if b > 0:
                    below.append(f)
            if len(below) != 1:
                raise ValueError(f"forces.rut_leg_geom_names: {name!r} is on a body with {len(below)} feet at or below "
                                 f"it; list a geom of one leg, above exactly one foot.")
            feet.append(below[0])
        return geoms, feet

    def _sole(self, mjm, groups):
        """Sole length (along the foot body's x axis), width (along its y axis) and whether it is a disc: from the
        config (a rectangle), else the footprint of the first foot's geoms in its body's x-y plane, each geom as it
        is turned in the body: a lone sphere, or a lone capsule or cylinder standing upright, is a disc of its
        radius, anything else the rectangle around its geoms (a capsule lying along x: its length by its
        diameter)."""
        cfg = self.cfg
        if cfg.sole_length is not None and cfg.sole_width is not None:
            length, width, disc = float(cfg.sole_length), float(cfg.sole_width), False
        elif not groups:
            length, width, disc = 1.0, 1.0, False  # no feet: never used
        else:
            g = groups[0]
            lo, hi = _body_box(mjm, g)
            length, width = float(hi[0] - lo[0]), float(hi[1] - lo[1])
            round_types = (int(mujoco.mjtGeom.mjGEOM_SPHERE), int(mujoco.mjtGeom.mjGEOM_CAPSULE),
                           int(mujoco.mjtGeom.mjGEOM_CYLINDER))
            disc = len(g) == 1 and int(mjm.geom_type[g[0]]) in round_types and math.isclose(length, width)
        if not (0 < length < math.inf and 0 < width < math.inf):
            raise ValueError(f"sole size must be a finite number > 0 m, got length={length}, width={width}; set "
                             f"forces.sole_length / sole_width.")
        return length, width, disc

    # ------------------------------------------------------------------ callbacks
    def install(self):
        """Set the mujoco_warp callbacks (contact filter for the terrain contacts' depth cap, soil and friction;
        passive for the forces)."""
        cfg = self.cfg
        self.m.callback.contactfilter = self.contact_filter
        if cfg.wading or cfg.soil:
            self.m.callback.passive = self.passive

    def contact_filter(self, m, d):
        """The depth cap, ground friction and soil ruts on MuJoCo's terrain contacts, then the analytic sole
        contacts. Where no foot is among MuJoCo's contacts (``feet_apart_from_filter``) the feet's cells are found
        beside the first (parallel branches on a GPU, ``_in_parallel``): neither reads what the other writes. The
        launches are recorded once per (m, d) and replayed: their arguments are persistent arrays, and on the CPU
        packing the sole kernel's ~60 arguments every substep would cost more than the heightfield collision it
        replaces."""
        cells, contacts, *soles = self._recorded_filter(m, d)
        if self.feet_apart_from_filter:
            self._in_parallel(cells.launch, contacts.launch)
        else:
            cells.launch()
            contacts.launch()
        for launch in soles:
            launch.launch()

    def sole_contacts(self, m, d):
        """The contact filter's analytic sole contacts alone: the feet's collision with the terrain, which
        ``gente-benchmark`` times apart from the force kernels (its raw physics has them too)."""
        for launch in self._recorded_filter(m, d):
            if launch.kernel in (C.sole_contact_kernel, C.sole_and_leg_contact_kernel):
                launch.launch()

    def _recorded_filter(self, m, d) -> list:
        key = (id(m), id(d))
        if self._filter_key != key:
            self._filter_launches, self._filter_key = self._record_contact_filter(m, d), key
        return self._filter_launches

    def _record_contact_filter(self, m, d) -> list:
        cfg, dev = self.cfg, self.device
        launches = []
        nf = max(self.nfoot, 1)
        feet = K.FootSoil()
        feet.friction_reference, feet.use_friction = float(cfg.friction_reference), int(bool(cfg.friction_from_map))
        feet.use_soil = int(bool(cfg.soil))  # feet: their traction; other bodies: tan(phi) (ground_friction)
        feet.sole_area, feet.bekker_width = self.sole_area, self.bekker_width
        feet.bulldozing_face = self.sole_length if self.sole_disc else min(self.sole_length, self.sole_width)
        feet.friction_cap, feet.min_friction = float(cfg.soil_friction_cap), float(cfg.min_friction)
        feet.sink_step, feet.liftoff_clearance = float(cfg.sinkage_rate) * self.dt, float(cfg.liftoff_clearance)
        feet.soil_params, feet.load, feet.support = self.soil_params, self.foot_load, self.foot_support
        feet.sink_load = self.foot_sink_load
        feet.traction_load = self.foot_traction_load
        feet.slip, feet.sinkage, feet.soil = self.foot_slip, self.foot_sinkage, self.foot_soil
        launches.append(wp.launch(K.foot_cell_kernel, dim=(self.nworld, nf), device=dev, block_dim=LIMB_BLOCK_DIM,
                  inputs=[self.foot_body, self.foot_offset, d.xpos, d.xmat, self.origin, self.resolution, self.soil,
                          int(feet.use_soil and self.nfoot > 0), self.foot_soil, self.foot_touch, self.foot_cand,
                          self.foot_near, self.foot_fn],
                  record_cmd=True))
        c = d.contact
        launches.append(wp.launch(
            K.contact_filter_kernel, dim=d.naconmax, device=dev,
            inputs=[d.nacon, self.geom_foot, self.geom_bodyid, self.soilmap, feet, float(cfg.max_rut_depth),
                    float(cfg.terrain_contact_max_depth), c.pos,
                    c.geom, c.worldid, c.dist, c.friction, c.dim, self.foot_touch, self.foot_cand], record_cmd=True,
        ))
        if self.npt:
            launches.append(wp.launch(
                C.sole_and_leg_contact_kernel if self.has_rut_legs else C.sole_contact_kernel,
                dim=(self.nworld, self.npt), device=dev, block_dim=LIMB_BLOCK_DIM,
                inputs=[self.pt_geom, self.pt_end, self.pt_foot, self.pt_leg_step, self.pt_leg, self.terrain_geom,
                        m.geom_condim,
                        m.geom_priority, m.geom_solmix, m.geom_solref, m.geom_solimp, m.geom_friction, m.geom_adhesion,
                        m.geom_margin, m.geom_gap, m.geom_size, m.pair_dim, m.pair_solref, m.pair_solreffriction,
                        m.pair_solimp, m.pair_adhesion, m.pair_friction, d.geom_xpos, d.geom_xmat, self.hf_heights,
                        self.hf_origin, self.hf_res, self.soilmap, feet, self.legs, float(cfg.sole_contact_max_depth),
                        d.naconmax,
                        self.foot_touch, self.foot_cand, self.foot_near, c.dist, c.pos, c.frame, c.includemargin,
                        c.friction, c.solref, c.solreffriction, c.solimp, c.dim, c.geom, c.efc_address, c.worldid,
                        c.type, c.geomcollisionid, c.adhesion, d.nacon], record_cmd=True,
            ))
        return launches

    def passive(self, m, d):
        """A substep's terrain forces into the zeroed ``d.xfrc_applied`` and the water's added mass into ``d.M``:
        the legs' water, the feet's water, the soil, and each water group's added mass (computed apart from its
        forces, which it does not need): five independent groups, parallel branches on a GPU (``_in_parallel``),
        adding atomically."""
        d.xfrc_applied.zero_()
        self._in_parallel(lambda: self._feet_water(m, d), lambda: self._legs_water(m, d), lambda: self._soil(m, d),
                          lambda: self._feet_added_mass(m, d), lambda: self._legs_added_mass(m, d))

    def _in_parallel(self, *groups) -> None:
        """Launch each group of kernels (a callable; the groups independent, their forces added atomically) on a
        stream of its own, forked from Warp's current stream and joined back into it. At a few thousand robots each
        kernel fills a small part of the GPU for a latency-bound few microseconds, so the branches overlap; a captured
        graph keeps them as parallel branches. On the CPU, or with ``parallel_kernels`` off, one after another."""
        if not self._side_streams:
            for launch in groups:
                launch()
            return
        if len(groups) - 1 > len(self._side_streams):
            raise ValueError(f"{len(groups)} groups of kernels need {len(groups) - 1} side streams; "
                             f"TerrainForces makes {len(self._side_streams)}")
        main = wp.get_stream(self.device)
        sides = self._side_streams[:len(groups) - 1]
        for launch, side in zip(groups[1:], sides):
            side.wait_stream(main)
            with wp.ScopedStream(side, sync_enter=False):
                launch()
        groups[0]()
        for side in sides:
            main.wait_stream(side)

    def _legs_water(self, m, d):
        cfg = self.cfg
        if cfg.wading and self.nseg:
            wp.launch(
                W.segment_water_kernel, dim=(self.nworld, self.nseg), device=self.device, block_dim=LIMB_BLOCK_DIM,
                inputs=[self.seg_geom, self.seg_body, self.seg_radius, self.seg_halflen, self.seg_caps,
                        m.body_rootid, self.point_dofs,
                        d.geom_xpos, d.geom_xmat, d.xipos, d.cvel, d.cdof_dot, d.qvel, d.subtree_com,
                        d.time, self.water,
                        float(cfg.water_density), float(cfg.drag_coefficient), float(cfg.added_mass_coefficient),
                        self.g, int(bool(cfg.vertical_drag)), int(bool(cfg.paper_drag_area)),
                        int(bool(cfg.paper_added_mass)), int(bool(cfg.paper_flow_force)), self.eps, self.xi,
                        d.xfrc_applied, self.seg_force],
            )

    def _legs_added_mass(self, m, d):
        cfg = self.cfg
        if cfg.wading and self.nseg and not cfg.paper_added_mass:
            wp.launch(
                W.segment_points_kernel, dim=(self.nworld, self.nseg), device=self.device, block_dim=LIMB_BLOCK_DIM,
                inputs=[self.seg_geom, self.seg_body, self.seg_radius, self.seg_halflen, m.body_rootid,
                        d.geom_xpos, d.geom_xmat, d.subtree_com, self.water, float(cfg.water_density),
                        float(cfg.added_mass_coefficient), self.point_mass, self.point_offset],
            )
            self._added_mass(m, d, 0, W.NGAUSS * self.nseg)

    def _feet_water(self, m, d):
        cfg = self.cfg
        if cfg.wading and len(self.foot_water_geom):
            wp.launch(
                W.foot_water_kernel, dim=(self.nworld, len(self.foot_water_geom)), device=self.device,
                block_dim=LIMB_BLOCK_DIM,
                inputs=[self.foot_water_geom, self.foot_buoyancy, self.foot_added_mass, m.geom_type, m.geom_size,
                        m.geom_bodyid, m.body_rootid, self.point_dofs,
                        d.geom_xpos, d.geom_xmat, d.xipos, d.cvel, d.cdof_dot, d.qvel, d.subtree_com, d.time,
                        self.water, float(cfg.water_density), self.g, float(cfg.plate_drag_coefficient),
                        float(cfg.sphere_drag_coefficient), int(bool(cfg.paper_added_mass)), self.eps, self.xi,
                        d.xfrc_applied, self.foot_water_force, W.NGAUSS * self.nseg],
            )

    def _feet_added_mass(self, m, d):
        cfg = self.cfg
        if cfg.wading and len(self.foot_water_geom) and not cfg.paper_added_mass:
            first = W.NGAUSS * self.nseg
            wp.launch(
                W.foot_points_kernel, dim=(self.nworld, len(self.foot_water_geom)), device=self.device,
                block_dim=LIMB_BLOCK_DIM,
                inputs=[self.foot_water_geom, m.geom_type, m.geom_size, m.geom_bodyid, m.body_rootid, d.geom_xpos,
                        d.geom_xmat, d.subtree_com, self.water, first, self.point_mass, self.point_offset],
            )
            self._added_mass(m, d, first, len(self.foot_water_geom))

    def _added_mass(self, m, d, first_point: int, count: int):
        """The added mass of the water points ``first_point`` to ``first_point + count - 1`` into ``d.M``, from the
        scales and offsets their points kernel has just written."""
        wp.launch(
            W.added_mass_kernel, dim=(self.nworld, count, self.point_dofs.shape[1]), device=self.device,
            inputs=[self.point_dofs, self.point_geom, self.point_axes, m.dof_parentid, m.M_rownnz, m.M_rowadr,
                    d.geom_xmat, d.cdof, self.point_mass, self.point_offset, first_point, d.M],
        )

    def _soil(self, m, d):
        """Bekker and bulldozing (then RFT's granular media, which adds to the same feet's forces)."""
        cfg, dev = self.cfg, self.device
        if cfg.soil and self.nfoot:
            wp.launch(
                K.soil_force_kernel, dim=(self.nworld, self.nfoot), device=dev, block_dim=LIMB_BLOCK_DIM,
                inputs=[self.foot_body, self.foot_offset, self.foot_drop, m.body_rootid, d.xpos, d.xmat,
                        d.cvel, d.subtree_com, self.sole_length, self.sole_width, int(self.sole_disc),
                        float(cfg.bulldozing_speed_reg), self.soil_params,
                        self.foot_touch, self.foot_cand, self.foot_soil, self.foot_sinkage,
                        self.foot_vel, self.foot_force],
            )
        if cfg.soil and self.nfoot and self.has_rft:
            wp.launch(
                R.rft_force_kernel, dim=(self.nworld, self.nfoot), device=dev, block_dim=LIMB_BLOCK_DIM,
                inputs=[self.foot_body, self.foot_offset, self.foot_drop, m.body_rootid, d.xpos, d.xmat, d.xipos,
                        d.cvel, d.subtree_com, self.hf_heights, self.hf_origin, self.hf_res, self.sole_length,
                        self.sole_width, int(self.sole_disc), self.sole_area, float(cfg.bulldozing_speed_reg),
                        self.soil_params, self.foot_soil,
                        self.foot_support, self.foot_force, d.xfrc_applied],
            )

    # ------------------------------------------------------------------ env calls
    def restart_draws(self) -> None:
        """Replay the per-env draws (soil scatter, drag noise, flow noise) from the seed's first: the device-side
        counter they are drawn at goes back to 0, so a repeated evaluation meets the same soil and water."""
        self.counter.zero_()

    def after_substep(self):
        """After each ``mjw.step``: sum the feet's (and rut legs') normal forces, low-pass their loads, update slip
        since touchdown and lift-off (the feet's and the rut legs' ruts). The feet and the rut legs are independent
        groups (parallel branches on a GPU, ``_in_parallel``)."""
        if not self.nfoot:
            return
        load_alpha = min(self.dt / float(self.cfg.sinkage_load_tau), 1.0)
        if self.has_rut_legs:
            self._in_parallel(lambda: self._feet_state(load_alpha), lambda: self._legs_state(load_alpha))
        else:
            self._feet_state(load_alpha)

    def _normal_forces(self, geom_limb, limb_fn):
        """Sum the normal forces of the contacts of each limb (``geom_limb``: a geom's limb, else -1) into ``limb_fn``,
        cleared before: the feet's at the substep's start, the rut legs' once read."""
        m, d = self.m, self.d
        c = d.contact
        wp.launch(
            K.normal_force_kernel, dim=d.naconmax, device=self.device,
            inputs=[int(m.opt.cone), d.nacon, geom_limb, c.frame, c.friction, c.dim, c.efc_address,
                    c.adhesion, c.geom, c.worldid, d.efc.force, d.njmax, limb_fn],
        )

    def _feet_state(self, load_alpha: float):
        self._normal_forces(self.geom_foot, self.foot_fn)
        wp.launch(
            K.foot_state_kernel, dim=(self.nworld, self.nfoot), device=self.device, block_dim=LIMB_BLOCK_DIM,
            inputs=[self.dt, float(self.cfg.contact_threshold), load_alpha,
                    min(self.dt / float(self.cfg.traction_load_tau), 1.0), self.foot_fn, self.foot_vel,
                    float(self.cfg.liftoff_time), self.foot_near, self.foot_slip, self.foot_air, self.foot_stance,
                    self.foot_load, self.foot_sink_load, self.foot_traction_load, self.foot_sinkage],
        )

    def _legs_state(self, load_alpha: float):
        self._normal_forces(self.geom_leg, self.leg_fn)
        wp.launch(K.leg_state_kernel, dim=(self.nworld, self.nleg), device=self.device,
                  inputs=[self.dt, float(self.cfg.contact_threshold), load_alpha, float(self.cfg.liftoff_time),
                          self.leg_fn, self.legs, self.leg_air])

    def observe(self):
        """After a step's last substep (its ``after_substep``): the privileged observation of its state. Once per
        policy step, not per substep: only the step's end is observed."""
        if not self.nfoot:
            return
        d = self.d
        wp.launch(
            K.foot_obs_kernel, dim=(self.nworld, self.nfoot), device=self.device, block_dim=LIMB_BLOCK_DIM,
            inputs=[self.foot_body, self.foot_offset, d.xpos, d.xmat, self.heights, d.time, self.water, self.xi,
                    self.soil_params, self.foot_fn, self.foot_sinkage, self.foot_soil, self.obs],
        )

    def reset(self, mask):
        """Redraw eps ~ N(1, noise_std) and the soil parameters of the envs in ``mask`` (wp bool, nworld);
        forget their feet's and rut legs' soil state (slip, ruts, loads). Device-only: safe inside a captured graph."""
        wp.launch(K.reset_kernel, dim=self.nworld, device=self.device,
                  inputs=[mask, self.seed, self.counter, float(self.cfg.noise_std), self.soil_table, self.eps,
                          self.soil_params, self.foot_slip, self.foot_air, self.foot_sinkage,
                          self.foot_load, self.foot_sink_load, self.foot_traction_load, self.foot_stance,
                          self.foot_support])
        if self.has_rut_legs:
            wp.launch(K.leg_reset_kernel, dim=self.nworld, device=self.device, inputs=[mask, self.legs, self.leg_air])
        wp.launch(K.increment_kernel, dim=1, device=self.device, inputs=[self.counter])

    def new_policy_step(self):
        """Redraw the flow noise xi ~ N(1, noise_std) of every env (device-side counter: graph-safe)."""
        wp.launch(K.flow_noise_kernel, dim=self.nworld, device=self.device,
                  inputs=[self.seed, self.counter, float(self.cfg.noise_std), self.xi])
        wp.launch(K.increment_kernel, dim=1, device=self.device, inputs=[self.counter])

    def privileged_obs(self):
        """Torch view (nworld, n_feet * 12), per foot: water depth (m), flow vx, vy (m/s), on-soil flag,
        sinkage (m), normal force / 100 N, kc/1e4, kphi/1e6, n, cohesion c/1e4 (Pa), mu = tan(phi), K (cm); written by
        ``observe``. Its columns' names: ``privileged_obs_names``."""
        return wp.to_torch(self.obs)

    def privileged_obs_names(self) -> list[str]:
        """``<foot body>.<value>`` for each column of ``privileged_obs`` (``left_foot.water_depth``, ...)."""
        return [f"{foot}.{value}" for foot in self.foot_names for value in K.OBS_NAMES]
