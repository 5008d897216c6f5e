"""``TerrainForces``: the terrain force fields installed on a mujoco_warp model.

Usage by the env (per substep, all inside the captured graph)::

    forces = TerrainForces(mjm, m, d, heights, origin_xy, resolution, material, cfg.forces, seed)
    forces.install()                 # once: sets m.callback.contactfilter / m.callback.passive
    ...
    forces.new_policy_step()         # once per policy step, before the substeps (redraws the flow noise xi)
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

import warnings

import mujoco
import numpy as np
import warp as wp

from legged_gente.external_forces import kernels as K
from legged_gente.external_forces.config import ForcesConfig
from legged_gente.terrain.soil import preset_table
from legged_gente.terrain.materials import MaterialMap


_ATTRS = [a for a in vars(ForcesConfig) if not a.startswith("_")]


def _geom_ids(mjm: mujoco.MjModel, names, what: str) -> np.ndarray:
    ids = []
    for name in names:
        gid = mujoco.mj_name2id(mjm, mujoco.mjtObj.mjOBJ_GEOM, name)
        if gid < 0:
            known = [mujoco.mj_id2name(mjm, mujoco.mjtObj.mjOBJ_GEOM, i) for i in range(mjm.ngeom)]
            raise ValueError(f"forces.{what}: no geom named {name!r} in the model; named geoms: "
                             f"{[k for k in known if k]}.")
        ids.append(gid)
    return np.asarray(ids, np.int32)


def foot_groups(mjm: mujoco.MjModel, names) -> tuple[list[int], list[np.ndarray]]:
    """The feet of ``forces.foot_geom_names``: the listed geoms grouped by body, one foot per body (a box sole,
    or the spheres at its corners), as (foot bodies, geom ids per foot) in the order listed."""
    geoms = _geom_ids(mjm, names, "foot_geom_names")
    bodies = list(dict.fromkeys(int(b) for b in mjm.geom_bodyid[geoms]))
    return bodies, [geoms[mjm.geom_bodyid[geoms] == b] for b in bodies]


def privileged_obs_size(mjm: mujoco.MjModel, cfg) -> int:
    """Width of ``TerrainForces.privileged_obs()`` for this robot and config, without building the field."""
    return len(foot_groups(mjm, cfg.foot_geom_names)[0]) * K.OBS_PER_FOOT


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
        heights = np.asarray(heights, np.float32)
        if heights.ndim != 2 or heights.shape != material.shape:
            raise ValueError(f"heights {heights.shape} and material map {material.shape} must be the same 2-D "
                             f"grid; build both from the same Terrain.")
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

        self.heights = arr(heights, float)
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
        if material.has_soil().any() and int(material.soil.max()) >= len(material.soil_presets):
            raise ValueError(f"material.soil indexes preset {int(material.soil.max())} but soil_presets has "
                             f"{len(material.soil_presets)} names; list every soil used in soil_presets.")
        self.soil_table = arr(preset_table(list(material.soil_presets)), float)
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
        halflen = np.where(mjm.geom_type[seg] == int(mujoco.mjtGeom.mjGEOM_CAPSULE), mjm.geom_size[seg, 1],
                           mjm.geom_size[seg, 1] - mjm.geom_size[seg, 0])
        self.seg_halflen = arr(halflen.astype(np.float32), float)
        self._check_added_mass(mjm, seg, halflen)

        bodies, groups = foot_groups(mjm, cfg.foot_geom_names)
        self.nfoot = len(bodies)
        self.foot_body = arr(np.asarray(bodies, np.int32), int)
        # sole centre in the foot body's frame: the mean of its geoms' centres
        offsets = [mjm.geom_pos[g].mean(0) for g in groups] or np.zeros((1, 3))
        self.foot_offset = arr(np.asarray(offsets, np.float32), wp.vec3)
        geom_foot = np.full(mjm.ngeom, -1, np.int32)
        for f, g in enumerate(groups):
            geom_foot[g] = f
        self.geom_foot = arr(geom_foot, int)
        self.geom_bodyid = arr(mjm.geom_bodyid.astype(np.int32), int)
        self.sole_length, self.sole_width = self._sole(mjm, groups)

        n, nf, ns = self.nworld, max(self.nfoot, 1), max(self.nseg, 1)
        z = lambda shape, dtype: wp.zeros(shape, dtype=dtype, device=dev)  # noqa: E731
        self.counter = z(1, int)
        self.eps = z(n, float)
        self.xi = z(n, float)
        self.soil_params = z((n, npreset, K.NSOILPARAM), float)
        self.seg_vel = z((n, ns), wp.vec3)
        self.seg_vel_valid = z((n, ns), int)
        self.seg_force = z((n, ns), wp.vec3)
        self.foot_fn = z((n, nf), float)
        self.foot_vel = z((n, nf), wp.vec3)
        self.foot_slip = z((n, nf), wp.vec3)
        self.foot_sinkage = z((n, nf), float)
        self.foot_soil = z((n, nf), int)
        self.foot_soil.fill_(-1)
        self.foot_touch = z((n, nf), int)
        self.foot_cand = z((n, nf), float)
        self.foot_load = z((n, nf), float)
        self.foot_force = z((n, nf), wp.vec3)
        self.obs = z((n, self.nfoot * K.OBS_PER_FOOT), float)
        self._all = wp.array(np.ones(n, bool), dtype=bool, device=dev)
        self.reset(self._all)
        self.new_policy_step()

    # ------------------------------------------------------------------ setup helpers
    def _check_added_mass(self, mjm, seg, halflen):
        """The added mass is applied explicitly (from last substep's acceleration): stable only while it is
        smaller than the mass it acts on. Warn where a fully submerged segment would break that."""
        if not self.cfg.wading or self.cfg.paper_added_mass:
            return
        r = mjm.geom_size[seg, 0]
        ma = self.cfg.added_mass_coefficient * self.cfg.water_density * np.pi * r**2 * 2 * (halflen + r)
        body_mass = mjm.body_subtreemass[mjm.geom_bodyid[seg]]
        heavy = [mujoco.mj_id2name(mjm, mujoco.mjtObj.mjOBJ_GEOM, g) for g, a, b in zip(seg, ma, body_mass)
                 if a >= b]
        if heavy:
            warnings.warn(f"forces: the added mass of leg geoms {heavy} fully submerged reaches their bodies' "
                          f"mass; the explicit added-mass force may oscillate. Use paper_added_mass=True or a "
                          f"smaller added_mass_coefficient for such light legs.", stacklevel=3)

    def _sole(self, mjm, groups):
        """Sole length and width (m): from the config, else the footprint of the first foot's geoms in its
        body's x-y plane (box: its x-y extent; sphere, capsule, cylinder: a disc of its radius)."""
        cfg = self.cfg
        if cfg.sole_length is not None and cfg.sole_width is not None:
            length, width = float(cfg.sole_length), float(cfg.sole_width)
        elif not groups:
            length = width = 1.0  # no feet: never used
        else:
            g = groups[0]
            box = mjm.geom_type[g] == int(mujoco.mjtGeom.mjGEOM_BOX)
            half = np.where(box[:, None], mjm.geom_size[g, :2], mjm.geom_size[g, :1])
            lo, hi = (mjm.geom_pos[g, :2] - half).min(0), (mjm.geom_pos[g, :2] + half).max(0)
            length, width = float((hi - lo).max()), float((hi - lo).min())
        if not (length > 0 and width > 0):
            raise ValueError(f"sole size must be > 0 m, got length={length}, width={width}; set "
                             f"forces.sole_length / sole_width.")
        return length, width

    # ------------------------------------------------------------------ callbacks
    def install(self):
        """Set the mujoco_warp callbacks (contact filter for soil/friction, passive for the forces)."""
        cfg = self.cfg
        if cfg.soil or cfg.friction_from_map:
            self.m.callback.contactfilter = self.contact_filter
        if cfg.wading or cfg.soil:
            self.m.callback.passive = self.passive

    def contact_filter(self, m, d):
        dev = self.device
        nf = max(self.nfoot, 1)
        wp.launch(K.foot_untouch_kernel, dim=(self.nworld, nf), device=dev, inputs=[self.foot_touch, self.foot_cand])
        c = d.contact
        wp.launch(
            K.contact_filter_kernel, dim=d.naconmax, device=dev,
            inputs=[d.nacon, self.geom_foot, self.geom_bodyid, self.origin, self.resolution, self.soil,
                    self.friction, float(self.cfg.friction_reference), int(bool(self.cfg.friction_from_map)),
                    int(bool(self.cfg.soil) and self.nfoot > 0), self.sole_length * self.sole_width,
                    self.sole_width, float(self.cfg.sinkage_rate) * self.dt, float(self.cfg.max_rut_depth),
                    self.soil_params, self.foot_load,
                    self.foot_sinkage, c.pos, c.geom, c.worldid, c.dist, c.friction, self.foot_soil,
                    self.foot_touch, self.foot_cand],
        )
        wp.launch(K.foot_rut_kernel, dim=(self.nworld, nf), device=dev,
                  inputs=[self.foot_touch, self.foot_cand, self.foot_sinkage, self.foot_soil])

    def passive(self, m, d):
        cfg, dev = self.cfg, self.device
        d.xfrc_applied.zero_()
        if cfg.wading and self.nseg:
            wp.launch(
                K.wading_kernel, dim=(self.nworld, self.nseg), device=dev,
                inputs=[self.seg_geom, self.seg_body, self.seg_radius, self.seg_halflen, m.body_rootid,
                        d.geom_xpos, d.geom_xmat, d.xipos, d.cvel, d.subtree_com, d.time,
                        self.water,
                        float(cfg.water_density), float(cfg.drag_coefficient), float(cfg.added_mass_coefficient),
                        self.g, self.dt, int(bool(cfg.vertical_drag)), int(bool(cfg.paper_drag_area)),
                        int(bool(cfg.paper_added_mass)), int(bool(cfg.paper_flow_force)), self.eps, self.xi,
                        self.seg_vel, self.seg_vel_valid, d.xfrc_applied, self.seg_force],
            )
        if cfg.soil and self.nfoot:
            wp.launch(
                K.soil_force_kernel, dim=(self.nworld, self.nfoot), device=dev,
                inputs=[self.foot_body, self.foot_offset, m.body_rootid, d.xpos, d.xmat, d.xipos, d.cvel,
                        d.subtree_com, self.sole_width, float(cfg.bulldozing_speed_reg), self.soil_params,
                        self.foot_fn, self.foot_sinkage, self.foot_soil, self.foot_slip,
                        self.foot_vel, self.foot_force, d.xfrc_applied],
            )

    # ------------------------------------------------------------------ env calls
    def after_substep(self):
        """After each ``mjw.step``: sum the feet's normal forces, update slip since touchdown, write obs."""
        if not self.nfoot:
            return
        m, d, dev = self.m, self.d, self.device
        self.foot_fn.zero_()
        c = d.contact
        wp.launch(
            K.foot_normal_kernel, dim=d.naconmax, device=dev,
            inputs=[int(m.opt.cone), d.nacon, self.geom_foot, c.frame, c.friction, c.dim, c.efc_address,
                    c.adhesion, c.geom, c.worldid, d.efc.force, d.njmax, self.foot_fn],
        )
        wp.launch(
            K.foot_state_kernel, dim=(self.nworld, self.nfoot), device=dev,
            inputs=[self.dt, float(self.cfg.contact_threshold), min(self.dt / float(self.cfg.sinkage_load_tau), 1.0),
                    self.foot_body, self.foot_offset, d.xpos, d.xmat, self.heights,
                    d.time, self.water, self.xi, self.soil_params, self.foot_fn,
                    self.foot_vel, self.foot_sinkage, self.foot_soil, self.foot_slip, self.foot_load, self.obs],
        )

    def reset(self, mask):
        """Redraw eps ~ N(1, noise_std) and the soil parameters of the envs in ``mask`` (wp bool, nworld);
        forget their segment velocities and foot slip. Device-only: safe inside a captured graph."""
        wp.launch(K.reset_kernel, dim=self.nworld, device=self.device,
                  inputs=[mask, self.seed, self.counter, float(self.cfg.noise_std), self.soil_table, self.eps,
                          self.soil_params, self.seg_vel_valid, self.foot_slip])
        wp.launch(K.increment_kernel, dim=1, device=self.device, inputs=[self.counter])

    def new_policy_step(self):
        """Redraw the flow noise xi ~ N(1, noise_std) of every env (device-side counter: graph-safe)."""
        wp.launch(K.flow_noise_kernel, dim=self.nworld, device=self.device,
                  inputs=[self.seed, self.counter, float(self.cfg.noise_std), self.xi])
        wp.launch(K.increment_kernel, dim=1, device=self.device, inputs=[self.counter])

    def privileged_obs(self):
        """Torch view (nworld, n_feet * 12), per foot: water depth (m), flow vx, vy (m/s), on-soil flag,
        sinkage (m), normal force / 100 N, kc/1e4, kphi/1e6, n, bulldozing a/1e5, mu, K (cm)."""
        return wp.to_torch(self.obs)
