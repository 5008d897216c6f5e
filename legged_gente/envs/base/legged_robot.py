"""LeggedRobot: an rsl-rl ``VecEnv`` of ``num_envs`` MuJoCo-Warp worlds sharing one terrain.

legged_gym's task shape on MuJoCo-Warp: PD position actuators run inside the physics; everything else is
batched torch on zero-copy views of the simulator's arrays. Resets, command resampling and curriculum updates
are masked tensor operations, so a policy step never waits on the host. A subclass adds ``_reward_<name>``
methods (scaled by ``cfg.rewards.scales.<name>``) and ``_obs_<fn>`` methods (listed in ``cfg.observations``)
in plain torch. How the step is run (eagerly, compiled with torch.compile, as one CUDA graph) is the business of
``StepRunner`` (step_runner.py), which also checks the step's one rule: it reads no ``cfg``. Settings a run may
change while it trains (command ranges, reward scales and parameters) live in device tensors, ``self.params``
and ``self.reward_scale_vec``, changed with :meth:`set_param`; everything else is read once, at construction.
"""

from __future__ import annotations

import copy
import math
import warnings
from types import SimpleNamespace

import numpy as np
import torch
import warp as wp
from rsl_rl.env import VecEnv
from tensordict import TensorDict

from legged_gente.envs.base.base_config import near_misses
from legged_gente.envs.base.legged_robot_config import LeggedRobotCfg
from legged_gente.envs.base.step_runner import StepRunner
from legged_gente.envs.base.terms import NEEDS, obs_terms
from legged_gente.sim.assembly import build_model, owns_sole_contacts
from legged_gente.sim.backend import Simulation
from legged_gente.terrain.terrain import check_ground_friction
from legged_gente.utils.torch_math import quat_rotate, quat_rotate_inverse, rand_uniform, wrap_to_pi, yaw_of, yaw_quat

CUDA_GRAPH_MODES = ("env_step", "physics", "off")  # the values of cfg.sim.cuda_graph
COMMAND_RANGES = ("lin_vel_x", "lin_vel_y", "ang_vel_yaw", "heading")  # cfg.commands.ranges, in command order
SHARE_OF_LIMIT = (lambda v: 0 < v <= 1, "a share of the hard limit, in (0, 1]")  # legged_gym's soft limits


def _quat_mul(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Hamilton product of (w, x, y, z) quaternions: the rotation b, then a."""
    aw, ax, ay, az = a.unbind(-1)
    bw, bx, by, bz = b.unbind(-1)
    return torch.stack([aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
                        aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw], dim=-1)


class FeetAirTime:
    """Time each foot has spent in the air and the touchdowns of this step (legged_gym's feet_air_time, with its
    contact filter over two steps). Updated every step whatever the reward's scale; reset with the world."""

    def __init__(self, num_envs: int, num_feet: int, device):
        self.air_time = torch.zeros(num_envs, num_feet, device=device)  # s
        self.last_contact = torch.zeros(num_envs, num_feet, dtype=torch.bool, device=device)
        self.touchdown = torch.zeros(num_envs, num_feet, dtype=torch.bool, device=device)
        self.touchdown_air_time = torch.zeros(num_envs, num_feet, device=device)  # s, of the swing just ended

    def update(self, contact: torch.Tensor, dt: float) -> None:
        filtered = contact | self.last_contact
        self.last_contact.copy_(contact)
        self.touchdown.copy_((self.air_time > 0.0) & filtered)
        self.air_time += dt
        self.touchdown_air_time.copy_(self.air_time * self.touchdown)
        self.air_time *= ~filtered

    def reset(self, mask: torch.Tensor) -> None:
        m = mask[:, None]
        self.air_time.masked_fill_(m, 0.0)
        self.touchdown_air_time.masked_fill_(m, 0.0)
        self.last_contact &= ~m
        self.touchdown &= ~m


class LeggedRobot(VecEnv):
    # the numbers the step reads from tensors that have a range (set_param may change them): path in cfg ->
    # (test, what to use); checked at construction and by set_param. A subclass adds its own.
    param_rules = {
        "commands.heading_stiffness": (lambda v: v >= 0, ">= 0 (1/s, yaw rate per rad of heading error)"),
        "commands.still_fraction": (lambda v: 0 <= v <= 1, "a fraction, in [0, 1]"),
        "rewards.tracking_sigma": (lambda v: v > 0, "a kernel width > 0, in (m/s)^2"),  # exp(-err^2 / sigma)
        "rewards.soft_dof_pos_limit": SHARE_OF_LIMIT,
        "rewards.soft_torque_limit": SHARE_OF_LIMIT,
    }

    def __init__(self, cfg: LeggedRobotCfg, device: str = "cpu", train_cfg_steps_per_env: int = 24):
        self.cfg = cfg
        self.device = device
        self.num_envs = int(cfg.env.num_envs)
        self._log_every = train_cfg_steps_per_env
        self._validate_cfg()  # first: the step length below divides by the config's
        self.dt = cfg.sim.dt * cfg.control.decimation  # s, policy step
        self.max_episode_length_s = cfg.env.episode_length_s
        # policy steps, a partial last one counted whole; the quotient rounded first (0.14 s / 0.02 s is
        # 7.000000000000001 in binary floating point: 7 steps, not 8)
        self.max_episode_length = int(math.ceil(round(self.max_episode_length_s / self.dt, 9)))

        self.terrain = self._create_terrain()
        self.mjm, self.layout = build_model(cfg, self.terrain)
        self.sim = Simulation(self.mjm, self.num_envs, device, cfg.sim)
        self.num_actions = len(self.layout.joint_names)
        self.forces = self._create_forces()

        self._read_settings()
        self._init_buffers()
        self._foot_terrain_obs = self._foot_terrain_view()
        self._prepare_reward_function()
        self._init_origins()
        self._randomize_model()
        self._prepare_observations()
        self.reset()
        self._runner = StepRunner(self)

    # ------------------------------------------------------------------------------------------------------
    # construction
    # ------------------------------------------------------------------------------------------------------
    def _validate_cfg(self) -> None:
        """Every check of the config, each a ValueError saying what is wrong and what to use instead."""
        cfg = self.cfg
        checks = [
            (self.num_envs >= 1, f"cfg.env.num_envs={self.num_envs}; use >= 1"),
            (cfg.control.decimation >= 1, f"cfg.control.decimation={cfg.control.decimation}; use >= 1"),
            (cfg.sim.dt > 0, f"cfg.sim.dt={cfg.sim.dt}; use > 0 (s, the physics substep)"),
            (cfg.env.episode_length_s > 0, f"cfg.env.episode_length_s={cfg.env.episode_length_s}; use > 0 (s)"),
            (cfg.sim.max_qvel > 0, f"cfg.sim.max_qvel={cfg.sim.max_qvel}; use > 0 (m/s or rad/s above which a world "
                                   f"has diverged)"),
            # compared as cos(tilt): a negative angle would run as its opposite, one past pi as 2 pi minus it
            (0 < cfg.asset.terminate_tilt <= math.pi,
             f"cfg.asset.terminate_tilt={cfg.asset.terminate_tilt}; use an angle in (0, pi] rad (pi: never)"),
            (cfg.terrain.max_init_terrain_level >= 0,
             f"cfg.terrain.max_init_terrain_level={cfg.terrain.max_init_terrain_level}; use >= 0 (0: the easiest row)"),
            (cfg.sim.cuda_graph in CUDA_GRAPH_MODES,
             f"cfg.sim.cuda_graph={cfg.sim.cuda_graph!r}; use 'env_step' (the whole step in one CUDA graph), "
             f"'physics' (only the substeps) or 'off'"),
            (isinstance(cfg.sim.torch_compile, bool),
             f"cfg.sim.torch_compile={cfg.sim.torch_compile!r}; use True (compile the step's torch logic on GPU) "
             f"or False"),
            (cfg.terrain.solved_top_level in ("random", "stay"),
             f"cfg.terrain.solved_top_level={cfg.terrain.solved_top_level!r}; use 'random' (legged_gym) or 'stay'"),
            (cfg.terrain.mesh_type in ("plane", "heightfield"),
             f"cfg.terrain.mesh_type={cfg.terrain.mesh_type!r}; use 'plane' or 'heightfield'"),
            (bool(cfg.asset.file), "cfg.asset.file is empty; name the robot's MJCF file"),
            (bool(cfg.asset.foot_bodies),
             "cfg.asset.foot_bodies is empty; name the robot's feet (body names or patterns)"),
            (len(cfg.init_state.pos) == 3 and len(cfg.init_state.rot) == 4 and len(cfg.init_state.lin_vel) == 3
             and len(cfg.init_state.ang_vel) == 3,
             "cfg.init_state: pos, lin_vel and ang_vel take 3 numbers, rot 4 (w, x, y, z)"),
            (abs(sum(q * q for q in cfg.init_state.rot) - 1.0) < 1e-3,
             f"cfg.init_state.rot={list(cfg.init_state.rot)} is not a unit quaternion; use (w, x, y, z) of norm 1"),
            (cfg.normalization.clip_actions > 0,
             f"cfg.normalization.clip_actions={cfg.normalization.clip_actions}; use a positive bound"),
            (cfg.normalization.clip_observations > 0,
             f"cfg.normalization.clip_observations={cfg.normalization.clip_observations}; use a positive bound"),
            (cfg.domain_rand.init_lin_vel_xy_noise >= 0,
             f"cfg.domain_rand.init_lin_vel_xy_noise={cfg.domain_rand.init_lin_vel_xy_noise}; use >= 0 (m/s)"),
        ]
        for name in COMMAND_RANGES:
            bounds = list(getattr(cfg.commands.ranges, name))
            ok = len(bounds) == 2 and bounds[0] <= bounds[1]
            checks.append((ok, f"cfg.commands.ranges.{name}={bounds}; use [low, high], low <= high"))
        rand = cfg.domain_rand
        if rand.randomize_friction:
            bounds = list(rand.friction_range)
            checks.append((len(bounds) == 2 and 0 <= bounds[0] <= bounds[1],
                           f"cfg.domain_rand.friction_range={bounds}; use [low, high], 0 <= low <= high"))
        if rand.randomize_base_mass:
            bounds = list(rand.added_mass_range)
            checks.append((len(bounds) == 2 and bounds[0] <= bounds[1],
                           f"cfg.domain_rand.added_mass_range={bounds}; use [low, high] (kg), low <= high"))
        dt = cfg.sim.dt * cfg.control.decimation
        intervals = [("commands.resampling_time", cfg.commands.resampling_time)]
        if rand.push_robots:
            intervals.append(("domain_rand.push_interval_s", rand.push_interval_s))
        for name, seconds in intervals:  # counted in whole policy steps: under half a step would round to none
            checks.append((seconds >= dt / 2, f"cfg.{name}={seconds} s is under half a policy step ({dt:g} s); use "
                                              f"at least {dt:g} s"))
        for path, (test, use) in self.param_rules.items():
            section, name = path.split(".")
            value = getattr(getattr(cfg, section), name)
            number = isinstance(value, (int, float)) and not isinstance(value, bool)
            checks.append((number and test(value), f"cfg.{path}={value}; use {use}"))
        checks.append((cfg.forces.friction_reference is None,
                       f"cfg.forces.friction_reference={cfg.forces.friction_reference}: in an env it is the ground's "
                       f"friction, cfg.terrain.static_friction ({cfg.terrain.static_friction}); set that instead"))
        for ok, message in checks:
            if not ok:
                raise ValueError(message + ".")
        check_ground_friction(cfg.terrain.static_friction)  # a plane builds no terrain grid, which checks it too
        for message in near_misses(cfg, "cfg", open_sections=("observations",)):  # its terms: the user's
            warnings.warn(message, stacklevel=2)

    def _foot_terrain_view(self) -> torch.Tensor:
        """(num_envs, feet, values) view of the force fields' observation for ``foot_terrain``; on a plane, where
        no force field reads ``forces.foot_geom_names``, zeros for each of the env's feet."""
        from legged_gente.external_forces.kernels import OBS_PER_FOOT

        if self._force_obs is None:
            return torch.zeros(self.num_envs, len(self.feet), OBS_PER_FOOT, device=self.device)
        return self._force_obs.view(self.num_envs, -1, OBS_PER_FOOT)

    def _create_terrain(self):
        if self.cfg.terrain.mesh_type == "plane":
            return None
        from legged_gente.terrain.terrain import Terrain

        return Terrain(self.cfg.terrain, self.num_envs)

    def _create_forces(self):
        """Terrain force fields (water, soil, friction) where the terrain has such materials. On a heightfield
        without any, the critic still gets the fields' observation as zeros, so a policy trained with forces
        loads and runs on any terrain. ``self._force_obs``: that observation (a zero-copy view of the fields'
        Warp array), or None without force fields."""
        self._force_obs = None
        if self.terrain is None or not self.cfg.forces.enabled:
            return None
        material = self.terrain.material
        if not (material.has_water().any() or material.has_soil().any() or owns_sole_contacts(self.cfg, self.terrain)
                or (material.friction != self.cfg.terrain.static_friction).any()):
            from legged_gente.external_forces.field import privileged_obs_size

            self._force_obs = torch.zeros(self.num_envs, privileged_obs_size(self.mjm, self.cfg.forces),
                                          device=self.device)
            return None
        from legged_gente.external_forces.field import TerrainForces

        forces_cfg = copy.copy(self.cfg.forces)
        forces_cfg.friction_reference = float(self.cfg.terrain.static_friction)  # the ground geom's friction
        forces = TerrainForces(self.mjm, self.sim.m, self.sim.d, self.terrain.height_field, self.terrain.origin_xy,
                               self.terrain.resolution, material, forces_cfg,
                               seed=int(torch.randint(0, 2**31 - 1, ()).item()))  # follows torch's (per-rank) seed
        forces.install()
        self.sim.after_substep.append(forces.after_substep)
        self.sim.after_step.append(forces.observe)
        self.sim.after_reset.append(self._reset_forces)
        self._force_obs = forces.privileged_obs()
        # the post-reset forward runs the fields' callbacks and hooks: their observation is refreshed for the
        # reset worlds, and what they integrate (ruts, slip, loads, ...) is put back
        self.sim.observed.append(self._force_obs)
        self.sim.add_substep_state(forces.per_world_state())
        return forces

    def _reset_forces(self, mask: torch.Tensor) -> None:
        """New force-field draws for the worlds in ``mask`` (called by ``sim.reset_worlds``)."""
        self.forces.reset(wp.from_torch(mask.contiguous(), dtype=wp.bool))

    def _read_settings(self) -> None:
        """The config the step needs, read once: fixed settings as plain attributes, the ones a run may change
        while it trains as device tensors (``self.params``; :meth:`set_param` changes them)."""
        cfg, dev = self.cfg, self.device
        self.clip_actions = float(cfg.normalization.clip_actions)
        self.clip_observations = float(cfg.normalization.clip_observations)
        self.action_scale = float(cfg.control.action_scale)
        self.decimation = int(cfg.control.decimation)
        self.max_qvel = float(cfg.sim.max_qvel)
        self.njmax = int(cfg.sim.njmax)
        self.only_positive_rewards = bool(cfg.rewards.only_positive_rewards)
        self.heading_command = bool(cfg.commands.heading_command)
        self.send_timeouts = bool(cfg.env.send_timeouts)
        self.terminate_tilt_cos = math.cos(cfg.asset.terminate_tilt)
        self.terminate_height = float(cfg.asset.terminate_height)
        self.terrain_length = float(cfg.terrain.terrain_length)
        self.solved_top_level = cfg.terrain.solved_top_level
        self.terrain_curriculum = cfg.terrain.mesh_type == "heightfield" and cfg.terrain.curriculum and \
            cfg.terrain.mode == "curriculum"
        self.add_noise = bool(cfg.noise.add_noise)
        rand = cfg.domain_rand
        self.push_robots, self.max_push_vel_xy = bool(rand.push_robots), float(rand.max_push_vel_xy)
        self.random_init_yaw, self.init_lin_vel_xy_noise = bool(rand.random_init_yaw), float(rand.init_lin_vel_xy_noise)
        self.joint_pos_noise = float(cfg.init_state.joint_pos_noise)
        # whole policy steps; half a step (the least _validate_cfg accepts) is one, not round()'s 0
        self._resample_steps = max(1, int(round(cfg.commands.resampling_time / self.dt)))
        self._push_steps = max(1, int(round(rand.push_interval_s / self.dt)))  # 1 where pushes are off
        init = cfg.init_state
        self.init_base_state = torch.tensor(list(init.pos) + list(init.rot) + list(init.lin_vel) + list(init.ang_vel),
                                            dtype=torch.float32, device=dev)
        tensor = lambda v: torch.tensor(v, dtype=torch.float32, device=dev)  # noqa: E731
        commands = {name: tensor(getattr(cfg.commands.ranges, name)) for name in COMMAND_RANGES}
        commands.update(heading_stiffness=tensor(cfg.commands.heading_stiffness),
                        still_fraction=tensor(cfg.commands.still_fraction))
        rewards = {name: tensor(getattr(cfg.rewards, name)) for name in dir(cfg.rewards)
                   if not name.startswith("_") and not isinstance(getattr(cfg.rewards, name), bool)
                   and isinstance(getattr(cfg.rewards, name), (int, float, list, tuple))}
        self.params = SimpleNamespace(commands=SimpleNamespace(**commands), rewards=SimpleNamespace(**rewards))

    def set_param(self, path: str, value) -> None:
        """Change a setting the step reads from a device tensor, in place (so that it takes effect under CUDA
        graphs and torch.compile too), and in ``cfg``: ``"commands.ranges.<name>"`` ([low, high]),
        ``"commands.heading_stiffness"``, ``"commands.still_fraction"``, ``"rewards.<number>"`` or
        ``"rewards.scales.<term>"`` (a term of this env: its scale was non-zero at construction)."""
        parts = path.split(".")
        if parts[:2] == ["rewards", "scales"] and len(parts) == 3:
            names = [name for name, _ in self.reward_functions]
            if parts[2] not in names:
                raise ValueError(f"rewards.scales.{parts[2]} is not a reward term of this env (terms: {names}); a "
                                 f"term must have a non-zero scale at construction.")
            self.reward_scale_vec[names.index(parts[2])] = float(value) * self.dt
            self.reward_scales[parts[2]] = float(value) * self.dt
            setattr(self.cfg.rewards.scales, parts[2], value)
            return
        group, name = (parts[0], parts[-1]) if len(parts) == 2 or parts[:2] == ["commands", "ranges"] else ("", "")
        target = getattr(getattr(self.params, group, None), name, None) if group else None
        if target is None or (group == "commands" and (name in COMMAND_RANGES) != (len(parts) == 3)):
            valid = ([f"commands.ranges.{n}" for n in COMMAND_RANGES] + ["commands.heading_stiffness",
                     "commands.still_fraction"] + [f"rewards.{n}" for n in vars(self.params.rewards)]
                     + ["rewards.scales.<term>"])
            raise ValueError(f"{path!r} is not a setting the step reads from a tensor; use one of {valid}.")
        new = torch.as_tensor(value, dtype=torch.float32, device=self.device)
        if new.shape != target.shape:
            raise ValueError(f"{path} takes a value of shape {tuple(target.shape)}, got {value!r}.")
        if group == "commands" and name in COMMAND_RANGES and not float(new[0]) <= float(new[1]):
            raise ValueError(f"{path}={list(value)}; use [low, high], low <= high.")
        rule = self.param_rules.get(path)
        if rule is not None and not rule[0](float(new)):
            raise ValueError(f"{path}={value}; use {rule[1]}.")
        target.copy_(new)
        owner = self.cfg.commands.ranges if len(parts) == 3 else getattr(self.cfg, group)
        setattr(owner, name, value)

    def _init_buffers(self) -> None:
        n, dev, lay = self.num_envs, self.device, self.layout
        t = lambda a, dtype=torch.float32: torch.as_tensor(np.asarray(a), dtype=dtype, device=dev)  # noqa: E731
        self.qpos_adr = t(lay.qpos_adr, torch.long)
        self.dof_adr = t(lay.dof_adr, torch.long)
        self.feet = t(lay.foot_bodies, torch.long)
        self.penalized_bodies = t(lay.penalized_bodies, torch.long)
        self.terminate_bodies = t(lay.terminate_bodies, torch.long)
        self.hip_ids = t(lay.hip_joint_ids, torch.long)
        self.default_dof_pos = t(lay.default_joint_pos)[None, :]
        self.dof_limits = t(lay.joint_limits)  # (-inf, inf) for an unlimited joint
        limited = torch.isfinite(self.dof_limits).all(1)
        self.dof_mid = torch.where(limited, self.dof_limits.mean(1), 0.0)
        self.dof_half_range = torch.where(limited, 0.5 * (self.dof_limits[:, 1] - self.dof_limits[:, 0]), math.inf)
        self.torque_limits = t(lay.torque_limits)  # N*m (inf: none)
        self.base = lay.base_body
        self.root_body = int(self.mjm.body_rootid[self.base])

        self._step_actions = torch.zeros(n, self.num_actions, device=dev)  # the step's input
        self.actions = torch.zeros(n, self.num_actions, device=dev)
        self.last_actions = torch.zeros_like(self.actions)
        self.last_dof_vel = torch.zeros(n, self.num_actions, device=dev)
        self._episode_length_buf = torch.zeros(n, dtype=torch.long, device=dev)
        self._episode_start_step = torch.zeros(n, dtype=torch.long, device=dev)  # > 0 in a randomly started episode
        self.reset_buf = torch.ones(n, dtype=torch.bool, device=dev)
        self.time_out_buf = torch.zeros(n, dtype=torch.bool, device=dev)
        self.diverged_buf = torch.zeros(n, dtype=torch.bool, device=dev)
        self.nonfinite_actions = torch.zeros(n, dtype=torch.bool, device=dev)  # the step's action had a NaN or inf
        self.rew_buf = torch.zeros(n, device=dev)
        self.commands = torch.zeros(n, 4, device=dev)  # vx, vy, yaw rate, heading
        # each world's state at the end of the last step's physics and the commands it ran under, copied before
        # the step's resets: where the step reset a world, what its ended episode ended in (a fall's pose)
        self.terminal_qpos = torch.zeros_like(self.sim.qpos)
        self.terminal_qvel = torch.zeros_like(self.sim.qvel)
        self.terminal_commands = torch.zeros_like(self.commands)
        self.standing_still = torch.zeros(n, dtype=torch.bool, device=dev)  # a stand-still command: no turning
        self.feet_air_time = FeetAirTime(n, len(lay.foot_bodies), dev)
        self.gravity_vec = torch.tensor([0.0, 0.0, -1.0], device=dev).repeat(n, 1)
        self.friction_coeffs = torch.full((n, 1), self.cfg.terrain.static_friction, device=dev)
        self.added_base_mass = torch.zeros(n, 1, device=dev)
        self.common_step_counter = 0
        self.height_points = self._init_height_points()
        self.num_height_points = 0 if self.height_points is None else self.height_points.shape[0]
        if self.terrain is not None:
            self.height_samples = torch.as_tensor(self.terrain.height_field, dtype=torch.float32, device=dev)
            self.terrain_origin_xy = torch.tensor(self.terrain.origin_xy, dtype=torch.float32, device=dev)
        # episode statistics, reduced on device and reported once per rollout (no per-step host sync)
        self._stat_count = torch.zeros((), device=dev)
        self.diverged_resets = torch.zeros((), device=dev)  # diverged resets since the last report (reset by it)
        self._update_state()

    def _init_height_points(self) -> torch.Tensor | None:
        cfg = self.cfg.terrain
        if self.terrain is None or not cfg.measure_heights:
            return None
        xs = torch.tensor(cfg.measured_points_x, device=self.device, dtype=torch.float32)
        ys = torch.tensor(cfg.measured_points_y, device=self.device, dtype=torch.float32)
        gx, gy = torch.meshgrid(xs, ys, indexing="ij")
        return torch.stack([gx.flatten(), gy.flatten(), torch.zeros_like(gx.flatten())], dim=1)

    def _prepare_reward_function(self) -> None:
        """Every non-zero scale needs a ``_reward_<name>`` method; scales are multiplied by the policy dt.

        The terms are evaluated into one (num_envs, n_terms) tensor so that scaling, summing and the episode
        bookkeeping are a handful of batched operations, whatever the number of terms."""
        self.reward_scales: dict[str, float] = {}
        self.reward_functions = []
        for name in sorted(n for n in dir(self.cfg.rewards.scales) if not n.startswith("_")):
            scale = float(getattr(self.cfg.rewards.scales, name))
            if scale == 0.0:
                continue
            method = getattr(self, f"_reward_{name}", None)
            if method is None:
                raise ValueError(f"cfg.rewards.scales.{name} is non-zero but {type(self).__name__} has no "
                                 f"_reward_{name} method; implement it or set the scale to 0.")
            self.reward_scales[name] = scale * self.dt
            self.reward_functions.append((name, method))
        names = [name for name, _ in self.reward_functions]
        self.reward_scale_vec = torch.tensor([self.reward_scales[n] for n in names], device=self.device)
        # termination is added after the only-positive clip, so that dying always costs something
        self._clipped_terms = torch.tensor([n != "termination" for n in names], device=self.device)
        self.episode_sums = torch.zeros(self.num_envs, len(names), device=self.device)
        self._stat_reward_sums = torch.zeros(len(names), device=self.device)

    def _init_origins(self) -> None:
        n, dev = self.num_envs, self.device
        if self.terrain is None:
            cols = int(math.ceil(math.sqrt(n)))
            idx = torch.arange(n, device=dev)
            spacing = self.cfg.env.env_spacing
            self.env_origins = torch.stack([(idx // cols) * spacing, (idx % cols) * spacing,
                                            torch.zeros(n, device=dev)], dim=1).float()
            self.terrain_levels = torch.zeros(n, dtype=torch.long, device=dev)
            self.max_terrain_level = 1
            return
        self.terrain_origins = torch.as_tensor(self.terrain.terrain_origins, dtype=torch.float32, device=dev)
        rows, cols = self.terrain_origins.shape[:2]
        self.max_terrain_level = rows
        max_init = min(self.cfg.terrain.max_init_terrain_level, rows - 1)
        if not self.terrain_curriculum:  # levels never move: spread the robots over every row, as legged_gym does
            max_init = rows - 1
        self.terrain_levels = torch.randint(0, max_init + 1, (n,), device=dev)
        self.terrain_columns = torch.div(torch.arange(n, device=dev) * cols, n, rounding_mode="floor")
        self.env_origins = self.terrain_origins[self.terrain_levels, self.terrain_columns]

    def _randomize_model(self) -> None:
        """Per-world friction and base mass, written into the batched model fields once at start; after a mass
        change ``mjw.set_const`` recomputes what derives from it (subtree masses, the solver's inverse weights)."""
        rand = self.cfg.domain_rand
        if rand.randomize_friction:
            self.friction_coeffs = rand_uniform(*rand.friction_range, (self.num_envs, 1), self.device)
            # MuJoCo combines geom frictions with max(): set every geom so the pair's friction is the sample
            self.sim.geom_friction[:, :, 0] = self.friction_coeffs
        if rand.randomize_base_mass:
            self.added_base_mass = rand_uniform(*rand.added_mass_range, (self.num_envs, 1), self.device)
            mass0 = float(self.mjm.body_mass[self.base])
            low = float(rand.added_mass_range[0])
            if mass0 + low <= 0:
                raise ValueError(f"cfg.domain_rand.added_mass_range={list(rand.added_mass_range)} takes the base mass "
                                 f"{mass0:.4g} kg to {mass0 + low:.4g} kg; use low > -{mass0:.4g}.")
            ratio = (mass0 + self.added_base_mass[:, 0]) / mass0
            self.sim.body_mass[:, self.base] = mass0 * ratio
            self.sim.body_inertia[:, self.base] = torch.as_tensor(
                self.mjm.body_inertia[self.base], dtype=torch.float32, device=self.device) * ratio[:, None]
            self.sim.set_const()

    def _prepare_observations(self) -> None:
        """The groups' term tables (cfg.observations) resolved to methods, widths, scale and noise vectors."""
        available = {None: True, "heightfield": self.height_points is not None, "forces": self._force_obs is not None}
        level = float(self.cfg.noise.noise_level)
        self.observation_names: dict[str, list[str]] = {}
        self.left_out_observations: dict[str, str] = {}  # policy terms this env cannot make -> what they need
        self._obs_groups = {}
        for group in ("policy", "critic"):
            path = f"cfg.observations.{group}"
            entries = []
            for name, term in obs_terms(getattr(self.cfg.observations, group), path):
                if not available[term.when]:
                    if group == "policy":
                        self.left_out_observations[name] = NEEDS[term.when]
                    continue
                method = getattr(self, f"_obs_{term.fn}", None)
                if method is None:
                    raise ValueError(f"{path}.{name}: fn={term.fn!r} but {type(self).__name__} has no _obs_{term.fn} "
                                     f"method; implement it or name an existing one.")
                value = method()
                if value.ndim != 2 or value.shape[0] != self.num_envs:
                    raise ValueError(f"{path}.{name}: _obs_{term.fn} returned shape {tuple(value.shape)}; an observation "
                                     f"term returns (num_envs, k) = ({self.num_envs}, k): keep its column dimension, "
                                     f"e.g. x[:, None].")
                width = value.shape[1]
                scale = torch.as_tensor(term.scale, dtype=torch.float32, device=self.device)
                if scale.numel() not in (1, width):
                    raise ValueError(f"{path}.{name}.scale has {scale.numel()} values; the term has {width} columns: "
                                     f"give one number or {width}.")
                scale = scale.expand(width).clone()
                entries.append((name, method, scale, term.clip, scale * term.noise * level))
                columns = getattr(self, f"_obs_{term.fn}_names", lambda: None)()  # a term may name its columns
                self.observation_names.setdefault(group, []).extend(
                    [f"{name}.{c}" for c in columns] if columns is not None and len(columns) == width
                    else [name] if width == 1 else [f"{name}[{i}]" for i in range(width)])
            self._obs_groups[group] = entries
        self._noise_scale = torch.cat([e[4] for e in self._obs_groups["policy"]])
        self.observation_names["critic"] = self.observation_names["policy"] + self.observation_names.get("critic", [])

    # ------------------------------------------------------------------------------------------------------
    # VecEnv
    # ------------------------------------------------------------------------------------------------------
    @property
    def episode_length_buf(self) -> torch.Tensor:
        return self._episode_length_buf

    @episode_length_buf.setter
    def episode_length_buf(self, value: torch.Tensor) -> None:
        """An assignment (rsl-rl's random initial episode lengths) copies into the buffer the step reads; each robot's
        current episode is then shorter by its start, which the terrain curriculum allows for."""
        self._episode_length_buf.copy_(value)
        self._episode_start_step.copy_(value)

    def get_observations(self) -> TensorDict:
        return self.obs_buf.clone()  # a copy: the next step overwrites obs_buf in place

    def reset(self) -> TensorDict:
        all_envs = torch.ones(self.num_envs, dtype=torch.bool, device=self.device)
        self._reset_envs(all_envs)
        self._resample_commands(all_envs)
        self._next_step_forward(all_envs)
        self._update_state()
        self._update_heading_commands()
        self._compute_observations()
        return self.obs_buf.clone()

    def step(self, actions: torch.Tensor) -> tuple[TensorDict, torch.Tensor, torch.Tensor, dict]:
        """One policy step. Returns copies: the step overwrites its buffers in place on the next step, and
        rsl-rl keeps references to observations across it."""
        if actions.shape != self._step_actions.shape:
            raise ValueError(f"actions of shape {tuple(actions.shape)}; this env takes (num_envs, num_actions) = "
                             f"{tuple(self._step_actions.shape)}")
        self._step_actions.copy_(actions)
        self.sim.ensure_stage()  # outside the step's graph: the graph reuses the stage computed ahead
        self._runner()
        self.common_step_counter += 1
        if self.push_robots and self.common_step_counter % self._push_steps == 0:
            # after the observations, as in legged_gym: the push shows in the next step
            self._push_robots()
        extras = {"time_outs": self.time_out_buf.clone()} if self.send_timeouts else {}
        if self.common_step_counter % self._log_every == 0:
            extras["episode"] = self._episode_statistics()
        return self.obs_buf.clone(), self.rew_buf.clone(), self.reset_buf.clone(), extras

    def _step_body(self) -> None:
        """Everything a step does on the device (what StepRunner compiles and captures)."""
        # in place: rebound here, under rsl-rl's inference_mode, it would become an inference tensor that a reset
        # outside it (a curriculum restored after a rollout) could not write
        # a world given a NaN or inf action holds its default pose for the step and is reset as diverged (a NaN
        # position target would otherwise reach the actuators, which clamp it to a torque limit)
        finite = torch.isfinite(self._step_actions).all(1, keepdim=True)
        self.nonfinite_actions.copy_(~finite[:, 0])
        clipped = torch.clamp(self._step_actions, -self.clip_actions, self.clip_actions)
        self.actions.copy_(torch.where(finite, clipped, 0.0))
        self.sim.ctrl[:] = self.default_dof_pos + self.action_scale * self.actions
        self.sim.step(self.decimation)
        self._post_physics_step()

    def episode_end(self, rows: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """After a step, for the worlds ``rows``: the qpos, qvel and commands a recorder shows for the step. Where
        the step ended an episode, the ended episode's last state and the commands it ran under (kept before the
        step's reset: a fall's pose); elsewhere the state now. A diverged world's ended state is meaningless
        (non-finite, absurdly fast or ill-solved): it shows the respawn."""
        keep = (self.reset_buf[rows] & ~self.diverged_buf[rows])[:, None]
        return (torch.where(keep, self.terminal_qpos[rows], self.sim.qpos[rows]),
                torch.where(keep, self.terminal_qvel[rows], self.sim.qvel[rows]),
                torch.where(keep, self.terminal_commands[rows], self.commands[rows]))

    # ------------------------------------------------------------------------------------------------------
    # step internals
    # ------------------------------------------------------------------------------------------------------
    def _post_physics_step(self) -> None:
        self._episode_length_buf += 1
        self.diverged_buf = self._diverged()
        self._update_state()
        self.feet_air_time.update(self.foot_contacts(), self.dt)
        self._check_termination(self.diverged_buf)
        self._compute_reward()
        self._log_and_update_curriculum(self.reset_buf, self.diverged_buf)
        # in place, every world: a captured graph or compiled step replays the copies into these same buffers
        self.terminal_qpos.copy_(self.sim.qpos)
        self.terminal_qvel.copy_(self.sim.qvel)
        self.terminal_commands.copy_(self.commands)
        self._reset_envs(self.reset_buf)
        # new commands for the robots just reset and for those whose resampling time came (episode length 0
        # after a reset, so both are caught by the same test)
        self._resample_commands(self.episode_length_buf % self._resample_steps == 0)
        self._next_step_forward(self.reset_buf)
        self._update_state()
        self._update_heading_commands()
        self._compute_observations()
        self.last_actions[:] = self.actions
        self.last_dof_vel[:] = self.dof_vel

    @torch.compiler.disable  # Warp launches (torch.compile runs them as they are)
    def _next_step_forward(self, reset: torch.Tensor) -> None:
        """The force fields' flow noise for the next step, then the forward: the reset worlds' bodies, contacts,
        contact forces and force-field observation. The forward's positions, contacts and passive forces are
        the next step's first substep's, computed ahead, so that step's noise is drawn first."""
        if self.forces is not None:
            self.forces.new_policy_step()
        self.sim.forward(reset)

    def _diverged(self) -> torch.Tensor:
        """Worlds whose state is non-finite or absurdly fast, or whose constraint rows overflowed ``njmax`` (MuJoCo
        counts the rows it wanted, so ``nefc > njmax`` means rows were dropped), or that were given a non-finite
        action: reset as time-outs."""
        # "not <=" is also true for NaN, which amax propagates
        bad = ~(self.sim.qvel.abs().amax(1) <= self.max_qvel) | ~torch.isfinite(self.sim.qpos).all(1)
        return bad | (self.sim.nefc > self.njmax) | self.nonfinite_actions

    def _update_state(self) -> None:
        """Base and joint state in the frames the observations and rewards use (views, no copies of sim)."""
        qpos, qvel = self.sim.qpos, self.sim.qvel
        self.base_pos = qpos[:, 0:3]
        self.base_quat = qpos[:, 3:7]
        # free joint: linear velocity in the world frame, angular velocity in the body frame (MuJoCo convention)
        self.base_lin_vel = quat_rotate_inverse(self.base_quat, qvel[:, 0:3])
        self.base_ang_vel = qvel[:, 3:6]
        self.projected_gravity = quat_rotate_inverse(self.base_quat, self.gravity_vec)
        self.dof_pos = qpos[:, self.qpos_adr]
        self.dof_vel = qvel[:, self.dof_adr]
        self.torques = self.sim.actuator_force
        self.contact_forces = self.sim.body_contact_force

    def _body_linear_velocity(self, bodies: torch.Tensor) -> torch.Tensor:
        """World linear velocity of body origins from MuJoCo's com-based spatial velocity (rot, lin)."""
        cvel = self.sim.cvel[:, bodies]
        offset = self.sim.xpos[:, bodies] - self.sim.subtree_com[:, self.root_body][:, None, :]
        return cvel[..., 3:6] + torch.cross(cvel[..., 0:3], offset, dim=-1)

    def _check_termination(self, diverged: torch.Tensor) -> None:
        """Falls (contacts on terminating bodies, tilt, height) end an episode; time-outs and diverged worlds
        end it as a truncation (``time_out_buf``: PPO bootstraps their value, no termination penalty)."""
        contact = torch.norm(self.contact_forces[:, self.terminate_bodies], dim=-1).gt(1.0).any(1) \
            if self.terminate_bodies.numel() else torch.zeros_like(diverged)
        tilted = self.projected_gravity[:, 2] > -self.terminate_tilt_cos
        self.reset_buf = contact | tilted | diverged
        if self.terminate_height > 0:
            self.reset_buf |= (self.base_pos[:, 2] - self._ground_height(self.base_pos[:, :2])) < self.terminate_height
        self.time_out_buf = (self.episode_length_buf >= self.max_episode_length) | diverged
        self.reset_buf |= self.time_out_buf

    def _compute_reward(self) -> None:
        """The scaled terms' sum; a diverged world's state is meaningless, so its reward is zero."""
        if not self.reward_functions:
            self.rew_buf = torch.zeros(self.num_envs, device=self.device)
            return
        values = [fn() for _, fn in self.reward_functions]
        for (name, _), value in zip(self.reward_functions, values):  # shapes are static: checked when traced
            if getattr(value, "shape", None) != (self.num_envs,):
                raise ValueError(f"_reward_{name} returned shape {tuple(getattr(value, 'shape', ()))}; a reward term "
                                 f"returns one value per robot, shape ({self.num_envs},).")
        terms = torch.stack(values, dim=1)
        terms = torch.nan_to_num(terms, nan=0.0, posinf=0.0, neginf=0.0) * self.reward_scale_vec
        terms = torch.where(self.diverged_buf[:, None], 0.0, terms)
        rew = torch.where(self._clipped_terms, terms, 0.0).sum(dim=1)
        if self.only_positive_rewards:
            rew = rew.clamp(min=0.0)
        self.rew_buf = rew + torch.where(self._clipped_terms, 0.0, terms).sum(dim=1)
        self.episode_sums += terms

    def _log_and_update_curriculum(self, done: torch.Tensor, diverged: torch.Tensor) -> None:
        """Accumulate finished episodes' statistics on device, then move finished robots' terrain levels. A
        diverged world's episode says nothing about the policy: it neither counts nor moves level."""
        finished = done & ~diverged
        mask = finished.float()
        self._stat_reward_sums += mask @ self.episode_sums / self.max_episode_length_s
        if self.terrain_curriculum:
            self._update_terrain_curriculum(finished)
        self._stat_count += mask.sum()
        self.diverged_resets += diverged.sum()

    def curriculum_state(self) -> dict[str, torch.Tensor]:
        """The robots' terrain levels, kept in checkpoints so that a resumed run climbs on from where it stopped."""
        return {"terrain_levels": self.terrain_levels.cpu()}

    def load_curriculum_state(self, state: dict[str, torch.Tensor]) -> str:
        """Restore ``curriculum_state()`` when it fits this env; says what happened (printed on --resume)."""
        if not self.terrain_curriculum:
            return "no terrain curriculum in this env"
        levels = state["terrain_levels"]
        if levels.shape != self.terrain_levels.shape or int(levels.max()) >= self.max_terrain_level:
            return (f"terrain curriculum restarts: the checkpoint's levels ({levels.numel()} robots, up to level "
                    f"{int(levels.max())}) do not fit {self.num_envs} robots on {self.max_terrain_level} levels")
        self.terrain_levels.copy_(levels)
        self.env_origins.copy_(self.terrain_origins[self.terrain_levels, self.terrain_columns])
        # every robot starts a new episode at its level's origin: the curriculum measures each episode's walk from
        # that origin, and a robot left where the fresh env spawned it would be promoted for the distance between
        self.reset()
        return f"terrain curriculum restored: mean level {levels.float().mean():.2f}"

    def _update_terrain_curriculum(self, done: torch.Tensor) -> None:
        """Up a level after walking more than half a tile; down after less than half the distance commanded over
        the episode's own time (legged_gym's game-inspired curriculum). A robot that solves the hardest level goes to
        a random level (``solved_top_level = "random"``, legged_gym) or stays there (``"stay"``)."""
        distance = torch.norm(self.base_pos[:, :2] - self.env_origins[:, :2], dim=1)
        move_up = distance > 0.5 * self.terrain_length
        # the commanded distance over the time the episode had: legged_gym takes the whole episode, which demotes
        # every robot whose first episode rsl-rl started at a random length (training's start, each --resume)
        episode_s = self.max_episode_length_s * (1.0 - self._episode_start_step / self.max_episode_length)
        commanded = torch.norm(self.commands[:, :2], dim=1) * episode_s
        move_down = (distance < 0.5 * commanded) & ~move_up
        level = self.terrain_levels + move_up.long() - move_down.long()
        top = self.max_terrain_level - 1
        if self.solved_top_level == "random":
            level = torch.where(level > top, torch.randint_like(level, 0, self.max_terrain_level), level)
        level = level.clamp(0, top)
        self.terrain_levels[:] = torch.where(done, level, self.terrain_levels)
        self.env_origins[:] = torch.where(done[:, None],
                                          self.terrain_origins[self.terrain_levels, self.terrain_columns],
                                          self.env_origins)

    def _episode_statistics(self) -> dict[str, torch.Tensor]:
        """Means over the episodes that ended since the last report (once per rollout, still on device; NaN when
        none ended: a mean of no episodes, which the training logger leaves out); the diverged resets since the
        last report."""
        rewards = torch.where(self._stat_count > 0, self._stat_reward_sums / self._stat_count.clamp(min=1.0),
                              torch.nan)
        stats = {f"rew_{name}": rewards[i] for i, (name, _) in enumerate(self.reward_functions)}
        # legged_gym's statistic: the mean level of all robots now (not only of those whose episode ended)
        stats["terrain_level"] = self.terrain_levels.float().mean()
        stats["diverged_resets"] = self.diverged_resets.clone()
        self._stat_reward_sums.zero_()
        self._stat_count.zero_()
        self.diverged_resets.zero_()
        return stats

    def _reset_envs(self, mask: torch.Tensor) -> None:
        """Masked reset: the worlds where ``mask`` is True get MuJoCo's default Data (``sim.reset_worlds``: warm
        start, applied forces, time, ...), then the initial state (cfg.init_state, randomised by
        cfg.domain_rand); every per-world buffer of the env is reset too. Nothing leaves the device."""
        n, dev = self.num_envs, self.device
        m = mask[:, None]
        self.sim.reset_worlds(mask)
        qpos, qvel = self.sim.qpos, self.sim.qvel
        dof_pos = self.default_dof_pos + rand_uniform(-1.0, 1.0, (n, self.num_actions), dev) * self.joint_pos_noise
        dof_pos = torch.clamp(dof_pos, self.dof_limits[:, 0], self.dof_limits[:, 1])
        base = self.init_base_state
        rot = base[3:7].expand(n, 4)
        if self.random_init_yaw:
            rot = _quat_mul(yaw_quat(rand_uniform(-math.pi, math.pi, (n,), dev)), rot)
        lin_vel = base[7:10].expand(n, 3).clone()
        if self.init_lin_vel_xy_noise > 0:
            a = self.init_lin_vel_xy_noise
            lin_vel[:, 0:2] += rand_uniform(-a, a, (n, 2), dev)
        new_qpos = qpos.clone()
        new_qpos[:, 0:3] = self.env_origins + base[0:3]
        new_qpos[:, 3:7] = rot
        new_qpos[:, self.qpos_adr] = dof_pos
        new_qvel = torch.zeros_like(qvel)
        new_qvel[:, 0:3] = lin_vel
        new_qvel[:, 3:6] = base[10:13]
        qpos[:] = torch.where(m, new_qpos, qpos)
        qvel[:] = torch.where(m, new_qvel, qvel)
        # the PD targets of a zero action until the next step sets them (reset_data zeroed them)
        self.sim.ctrl[:] = torch.where(m, self.default_dof_pos, self.sim.ctrl)
        for buf in (self.actions, self.last_actions, self.last_dof_vel):
            buf[:] = torch.where(m, 0.0, buf)
        self.feet_air_time.reset(mask)
        self.episode_length_buf[:] = torch.where(mask, 0, self.episode_length_buf)
        self._episode_start_step[:] = torch.where(mask, 0, self._episode_start_step)
        self.episode_sums.masked_fill_(m, 0.0)

    def _resample_commands(self, mask: torch.Tensor) -> None:
        n, dev, c = self.num_envs, self.device, self.params.commands
        new = torch.stack([rand_uniform(c.lin_vel_x[0], c.lin_vel_x[1], (n,), dev),
                           rand_uniform(c.lin_vel_y[0], c.lin_vel_y[1], (n,), dev),
                           rand_uniform(c.ang_vel_yaw[0], c.ang_vel_yaw[1], (n,), dev),
                           rand_uniform(c.heading[0], c.heading[1], (n,), dev)], 1)
        small = torch.norm(new[:, :2], dim=1) < 0.2  # too slow to learn a gait from: stand still instead
        still = torch.rand(n, device=dev) < c.still_fraction
        new[:, :2] *= (~(small | still))[:, None]
        new[:, 2] *= (~still)
        self.commands[:] = torch.where(mask[:, None], new, self.commands)
        self.standing_still[:] = torch.where(mask, still, self.standing_still)

    def _update_heading_commands(self) -> None:
        """In heading mode the yaw rate turns the base towards the commanded heading (clamped to the yaw range);
        a stand-still command keeps yaw rate 0."""
        if not self.heading_command:
            return
        c = self.params.commands
        heading_error = wrap_to_pi(self.commands[:, 3] - yaw_of(self.base_quat))
        yaw_rate = torch.clamp(c.heading_stiffness * heading_error, c.ang_vel_yaw[0], c.ang_vel_yaw[1])
        self.commands[:, 2] = torch.where(self.standing_still, 0.0, yaw_rate)

    def set_commands(self, commands: torch.Tensor, still: torch.Tensor | None = None) -> TensorDict:
        """Command the robots from outside the step (a joystick, an evaluation task): ``commands`` (num_envs, 4) =
        vx, vy (m/s), yaw rate (rad/s), heading (rad); ``still``: the robots told to stand still (in heading mode
        they do not turn). Written in place, headings turned into yaw rates and the observations refreshed, so
        the policy's next action sees them; returns those observations. The step still resamples commands (at
        resets and every ``commands.resampling_time``): call this again after each step to keep yours."""
        if commands.shape != self.commands.shape:
            raise ValueError(f"commands of shape {tuple(commands.shape)}; this env takes (num_envs, 4) = "
                             f"{tuple(self.commands.shape)}: vx, vy, yaw rate, heading")
        if still is not None and (still.shape != self.standing_still.shape or still.dtype != torch.bool):
            raise ValueError(f"still of shape {tuple(still.shape)} and dtype {still.dtype}; this env takes (num_envs,) "
                             f"= {tuple(self.standing_still.shape)} booleans: the robots told to stand still")
        self.commands.copy_(commands)
        self.standing_still.copy_(torch.zeros_like(self.standing_still) if still is None else still)
        self._update_heading_commands()
        self._compute_observations()
        return self.obs_buf.clone()

    def _push_robots(self) -> None:
        """An impulse: U(-max_push_vel_xy, max_push_vel_xy) m/s added to the base's x and y velocity."""
        v = self.max_push_vel_xy
        self.sim.qvel[:, 0:2] += rand_uniform(-v, v, (self.num_envs, 2), self.device)

    def _ground_height(self, xy: torch.Tensor) -> torch.Tensor:
        """Terrain height under world points ``xy`` (..., 2), bilinear between heightfield vertices."""
        if self.terrain is None:
            return torch.zeros(xy.shape[:-1], device=self.device)
        # a diverged world's bodies can be non-finite until its reset: never index with them
        grid = torch.nan_to_num((xy - self.terrain_origin_xy) / self.terrain.resolution, nan=0.0, posinf=0.0, neginf=0.0)
        nx, ny = self.height_samples.shape
        gx = grid[..., 0].clamp(0, nx - 1.001)
        gy = grid[..., 1].clamp(0, ny - 1.001)
        i0, j0 = gx.floor().long(), gy.floor().long()
        fx, fy = gx - i0, gy - j0
        h = self.height_samples
        return (h[i0, j0] * (1 - fx) * (1 - fy) + h[i0 + 1, j0] * fx * (1 - fy) +
                h[i0, j0 + 1] * (1 - fx) * fy + h[i0 + 1, j0 + 1] * fx * fy)

    # ------------------------------------------------------------------------------------------------------
    # observations: the terms cfg.observations lists (each (num_envs, k), before its scale and noise)
    # ------------------------------------------------------------------------------------------------------
    def _compute_observations(self) -> None:
        """Each group's terms (clipped, scaled) in table order; the policy's copy gets each term's noise, the
        critic sees the policy's terms noise-free, then its own."""
        def group(name: str) -> torch.Tensor:
            parts = []
            for _, method, scale, clip, _ in self._obs_groups[name]:
                value = method()
                if clip is not None:
                    value = value.clamp(*clip)
                parts.append(value * scale)
            return torch.cat(parts, dim=-1) if parts else torch.zeros(self.num_envs, 0, device=self.device)

        clean = group("policy")
        policy = clean + (2.0 * torch.rand_like(clean) - 1.0) * self._noise_scale if self.add_noise else clean
        critic = torch.cat([clean, group("critic")], dim=-1)
        clip = self.clip_observations
        self.policy_obs = torch.nan_to_num(policy, nan=0.0).clamp(-clip, clip)
        self.critic_obs = torch.nan_to_num(critic, nan=0.0).clamp(-clip, clip)

    @property
    def obs_buf(self) -> TensorDict:
        """The latest observations: the policy's and the critic's (privileged) groups, as rsl-rl takes them."""
        return TensorDict({"policy": self.policy_obs, "critic": self.critic_obs}, batch_size=[self.num_envs],
                          device=self.device)

    def _obs_base_lin_vel(self):
        return self.base_lin_vel

    def _obs_base_ang_vel(self):
        return self.base_ang_vel

    def _obs_projected_gravity(self):
        return self.projected_gravity

    def _obs_commands(self):
        return self.commands[:, :3]

    def _obs_dof_pos(self):
        return self.dof_pos - self.default_dof_pos

    def _obs_dof_vel(self):
        return self.dof_vel

    def _obs_actions(self):
        return self.actions

    def _obs_height_scan(self):
        """Base height above the scan points (in the base's yaw frame) minus the target base height."""
        yaw = yaw_quat(yaw_of(self.base_quat))
        points = quat_rotate(yaw[:, None, :].expand(-1, self.num_height_points, -1),
                             self.height_points[None].expand(self.num_envs, -1, -1))
        points = points[..., :2] + self.base_pos[:, None, :2]
        return self.base_pos[:, 2:3] - self.params.rewards.base_height_target - self._ground_height(points)

    def _obs_friction(self):
        return self.friction_coeffs

    def _obs_added_base_mass(self):
        return self.added_base_mass

    def _obs_feet_contact_forces(self):
        return self.contact_forces[:, self.feet].flatten(1)

    def _obs_force_fields(self):
        return self._force_obs

    def _obs_force_fields_names(self) -> list[str]:
        """``force_fields``' columns: each foot's values (``TerrainForces.privileged_obs_names``)."""
        return self.forces.privileged_obs_names()

    # ------------------------------------------------------------------------------------------------------
    # helpers for rewards
    # ------------------------------------------------------------------------------------------------------
    def foot_terrain(self) -> dict[str, torch.Tensor]:
        """What lies under each foot of ``forces.foot_geom_names`` at the end of the last step, for rewards: views of
        the force fields' observation in SI units, each (num_envs, feet): ``water_depth`` (m), ``flow`` (m/s, x and
        y: (num_envs, feet, 2)), ``on_soil`` (bool), ``sinkage`` (m, the foot's rut) and ``normal_force`` (N, the
        terrain's push on the foot, summed over its contacts). On a plane (then one per foot body), or a terrain with
        no water, soil or friction map, all are zero (False)."""
        obs = self._foot_terrain_obs
        return {"water_depth": obs[..., 0], "flow": obs[..., 1:3], "on_soil": obs[..., 3] > 0.5,
                "sinkage": obs[..., 4], "normal_force": 100.0 * obs[..., 5]}

    def foot_contacts(self) -> torch.Tensor:
        """(num_envs, feet) bool: the foot's vertical contact force is above 1 N (legged_gym's rule; the force fields
        keep their own, ``forces.contact_threshold`` on the normal force)."""
        return self.contact_forces[:, self.feet, 2] > 1.0

    # ------------------------------------------------------------------------------------------------------
    # reward terms (legged_gym's set); each returns a (num_envs,) tensor, scaled by cfg.rewards.scales
    # ------------------------------------------------------------------------------------------------------
    def _reward_lin_vel_z(self):
        return torch.square(self.base_lin_vel[:, 2])

    def _reward_ang_vel_xy(self):
        return torch.sum(torch.square(self.base_ang_vel[:, :2]), dim=1)

    def _reward_orientation(self):
        return torch.sum(torch.square(self.projected_gravity[:, :2]), dim=1)

    def _reward_base_height(self):
        height = self.base_pos[:, 2] - self._ground_height(self.base_pos[:, :2])
        return torch.square(height - self.params.rewards.base_height_target)

    def _reward_torques(self):
        return torch.sum(torch.square(self.torques), dim=1)

    def _reward_dof_vel(self):
        return torch.sum(torch.square(self.dof_vel), dim=1)

    def _reward_dof_acc(self):
        return torch.sum(torch.square((self.last_dof_vel - self.dof_vel) / self.dt), dim=1)

    def _reward_action_rate(self):
        return torch.sum(torch.square(self.last_actions - self.actions), dim=1)

    def _reward_collision(self):
        if not self.penalized_bodies.numel():
            return torch.zeros(self.num_envs, device=self.device)
        return torch.sum(torch.norm(self.contact_forces[:, self.penalized_bodies], dim=-1) > 0.1, dim=1).float()

    def _reward_termination(self):
        return (self.reset_buf & ~self.time_out_buf).float()

    def _reward_torque_limits(self):
        """Torque above soft_torque_limit times the actuator's force limit (legged_gym)."""
        excess = self.torques.abs() - self.torque_limits * self.params.rewards.soft_torque_limit
        return torch.sum(excess.clamp(min=0.0), dim=1)

    @property
    def soft_dof_limits(self) -> torch.Tensor:
        """(num_dofs, 2) the joint ranges shrunk about their middles to ``rewards.soft_dof_pos_limit`` (read from
        its tensor, so that ``set_param`` changes it)."""
        half = self.params.rewards.soft_dof_pos_limit * self.dof_half_range
        return torch.stack([self.dof_mid - half, self.dof_mid + half], dim=1)

    def _reward_dof_pos_limits(self):
        below = (self.soft_dof_limits[:, 0] - self.dof_pos).clamp(min=0.0)
        above = (self.dof_pos - self.soft_dof_limits[:, 1]).clamp(min=0.0)
        return torch.sum(below + above, dim=1)

    def _reward_tracking_lin_vel(self):
        error = torch.sum(torch.square(self.commands[:, :2] - self.base_lin_vel[:, :2]), dim=1)
        return torch.exp(-error / self.params.rewards.tracking_sigma)

    def _reward_tracking_ang_vel(self):
        error = torch.square(self.commands[:, 2] - self.base_ang_vel[:, 2])
        return torch.exp(-error / self.params.rewards.tracking_sigma)

    def _reward_feet_air_time(self):
        """Reward steps whose swing lasted longer than the target, paid at touchdown (legged_gym)."""
        air = self.feet_air_time
        reward = torch.sum((air.touchdown_air_time - self.params.rewards.feet_air_time_target) * air.touchdown, dim=1)
        return reward * (torch.norm(self.commands[:, :2], dim=1) > 0.1)

    def _reward_feet_stumble(self):
        forces = self.contact_forces[:, self.feet]
        return torch.any(torch.norm(forces[..., :2], dim=-1) > 5.0 * torch.abs(forces[..., 2]), dim=1).float()

    def _reward_stand_still(self):
        still = torch.norm(self.commands[:, :2], dim=1) < 0.1
        return torch.sum(torch.abs(self.dof_pos - self.default_dof_pos), dim=1) * still

    def _reward_feet_contact_forces(self):
        excess = torch.norm(self.contact_forces[:, self.feet], dim=-1) - self.params.rewards.max_contact_force
        return torch.sum(excess.clamp(min=0.0), dim=1)
