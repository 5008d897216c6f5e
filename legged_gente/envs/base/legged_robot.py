"""LeggedRobot: an rsl-rl ``VecEnv`` of ``num_envs`` MuJoCo-Warp worlds sharing one terrain.

legged_gym's task shape on MuJoCo-Warp: PD position actuators run inside the physics; everything else is
batched torch on zero-copy views of the simulator's arrays. Resets, command resampling and curriculum updates
are masked tensor operations, so a policy step never waits on the host, and on GPU the whole step (the
``decimation`` substeps, terrain force kernels, rewards, resets, observations) is one captured CUDA graph
(``cfg.sim.cuda_graph``): state carried between steps is updated in place, and host-side work (pushes, logging)
happens outside the graph.
"""

from __future__ import annotations

import math

import numpy as np
import torch
import warp as wp
from rsl_rl.env import VecEnv
from tensordict import TensorDict

from legged_gente.envs.base.legged_robot_config import LeggedRobotCfg
from legged_gente.sim.assembly import build_model, owns_sole_contacts
from legged_gente.sim.backend import Simulation
from legged_gente.utils.cuda_graph import StepGraph
from legged_gente.utils.torch_math import quat_rotate, quat_rotate_inverse, rand_uniform, wrap_to_pi, yaw_of, yaw_quat

CUDA_GRAPH_MODES = ("env_step", "physics", "off")  # the values of cfg.sim.cuda_graph


class LeggedRobot(VecEnv):
    step_outputs = ("actions", "policy_obs", "critic_obs", "rew_buf", "reset_buf", "time_out_buf", "base_pos",
                    "base_quat", "base_lin_vel", "base_ang_vel", "projected_gravity", "dof_pos", "dof_vel", "feet_pos")
    """Tensors the step recomputes from scratch (may be rebound); all other state is updated in place."""

    def __init__(self, cfg: LeggedRobotCfg, device: str = "cpu", train_cfg_steps_per_env: int = 24):
        self.cfg = cfg
        self.device = device
        self.num_envs = int(cfg.env.num_envs)
        self.dt = cfg.sim.dt * cfg.control.decimation  # s, policy step
        self.max_episode_length_s = cfg.env.episode_length_s
        self.max_episode_length = int(math.ceil(self.max_episode_length_s / self.dt))
        self._log_every = train_cfg_steps_per_env
        self._validate_cfg()

        self.terrain = self._create_terrain()
        self.mjm, self.layout = build_model(cfg, self.terrain)
        self.sim = Simulation(self.mjm, self.num_envs, device, cfg.sim)
        self.num_actions = len(self.layout.joint_names)
        self.forces = self._create_forces()

        self._init_buffers()
        self._prepare_reward_function()
        self._init_origins()
        self._randomize_model()
        self.reset()
        if self.sim.wp_device.is_cuda and cfg.sim.torch_compile:
            # the step's torch logic (rewards, terminations, resets, curriculum, observations: a few hundred
            # small operations) fused by TorchInductor into a few dozen kernels; compiled at the first step
            self._post_physics_step = torch.compile(self._post_physics_step, fullgraph=False, dynamic=False)
            print("[legged_gente] the step's torch logic is compiled (torch.compile) at the first step: about 20 s "
                  "once per num_envs, cached afterwards; --set sim.torch_compile=False turns it off", flush=True)
        self._step_graph = (StepGraph(self, self._step_body, self.step_outputs, device)
                            if self.sim.wp_device.is_cuda and cfg.sim.cuda_graph == "env_step" else None)

    # ------------------------------------------------------------------------------------------------------
    # construction
    # ------------------------------------------------------------------------------------------------------
    def _validate_cfg(self) -> None:
        cfg = self.cfg
        if self.num_envs < 1:
            raise ValueError(f"cfg.env.num_envs must be >= 1, got {self.num_envs}.")
        if cfg.control.decimation < 1:
            raise ValueError(f"cfg.control.decimation must be >= 1, got {cfg.control.decimation}.")
        if cfg.sim.cuda_graph not in CUDA_GRAPH_MODES:
            raise ValueError(f"cfg.sim.cuda_graph={cfg.sim.cuda_graph!r}; use 'env_step' (the whole step in one "
                             f"CUDA graph), 'physics' (only the substeps) or 'off'.")
        if not isinstance(cfg.sim.torch_compile, bool):
            raise ValueError(f"cfg.sim.torch_compile={cfg.sim.torch_compile!r}; use True (compile the step's torch "
                             f"logic on GPU) or False.")
        if cfg.terrain.solved_top_level not in ("random", "stay"):
            raise ValueError(f"cfg.terrain.solved_top_level={cfg.terrain.solved_top_level!r}; use 'random' "
                             f"(legged_gym) or 'stay'.")
        if cfg.terrain.mesh_type not in ("plane", "heightfield"):
            raise ValueError(f"cfg.terrain.mesh_type={cfg.terrain.mesh_type!r}; use 'plane' or 'heightfield'.")
        if not cfg.asset.file:
            raise ValueError("cfg.asset.file is empty: name the robot's MJCF file.")
        if not cfg.asset.foot_bodies:
            raise ValueError("cfg.asset.foot_bodies is empty: name the robot's feet (body names or patterns).")

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
        if self.cfg.forces.friction_reference != self.cfg.terrain.static_friction:
            raise ValueError(f"cfg.forces.friction_reference={self.cfg.forces.friction_reference} differs from "
                             f"cfg.terrain.static_friction={self.cfg.terrain.static_friction}; set them equal.")
        from legged_gente.external_forces.field import TerrainForces

        forces = TerrainForces(self.mjm, self.sim.m, self.sim.d, self.terrain.height_field, self.terrain.origin_xy,
                               self.terrain.resolution, material, self.cfg.forces,
                               seed=int(torch.randint(0, 2**31 - 1, ()).item()))  # follows torch's (per-rank) seed
        forces.install()
        self.sim.after_substep.append(forces.after_substep)
        self._force_obs = forces.privileged_obs()
        return forces

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
        self.dof_limits = t(lay.joint_limits)
        mid, half = self.dof_limits.mean(1), 0.5 * (self.dof_limits[:, 1] - self.dof_limits[:, 0])
        soft = self.cfg.rewards.soft_dof_pos_limit
        self.soft_dof_limits = torch.stack([mid - soft * half, mid + soft * half], dim=1)
        self.torque_limits = t(lay.torque_limits)
        self.base = lay.base_body
        self.root_body = int(self.mjm.body_rootid[self.base])

        self._step_actions = torch.zeros(n, self.num_actions, device=dev)  # the step's input, read by its graph
        self.actions = torch.zeros(n, self.num_actions, device=dev)
        self.last_actions = torch.zeros_like(self.actions)
        self.last_dof_vel = torch.zeros(n, self.num_actions, device=dev)
        self._episode_length_buf = torch.zeros(n, dtype=torch.long, device=dev)
        self.reset_buf = torch.ones(n, dtype=torch.bool, device=dev)
        self.time_out_buf = torch.zeros(n, dtype=torch.bool, device=dev)
        self.rew_buf = torch.zeros(n, device=dev)
        self.commands = torch.zeros(n, 4, device=dev)  # vx, vy, yaw rate, heading
        scales = self.cfg.normalization.obs_scales
        self.commands_scale = torch.tensor([scales.lin_vel, scales.lin_vel, scales.ang_vel], device=dev)
        self.feet_air_time = torch.zeros(n, len(lay.foot_bodies), device=dev)
        self.last_contacts = torch.zeros(n, len(lay.foot_bodies), dtype=torch.bool, device=dev)
        self.gravity_vec = torch.tensor([0.0, 0.0, -1.0], device=dev).repeat(n, 1)
        self.friction_coeffs = torch.full((n, 1), self.cfg.terrain.static_friction, device=dev)
        self.added_base_mass = torch.zeros(n, 1, device=dev)
        self.common_step_counter = 0
        self._resample_steps = max(1, int(round(self.cfg.commands.resampling_time / self.dt)))
        push = self.cfg.domain_rand
        self._push_steps = max(1, int(round(push.push_interval_s / self.dt)))
        self.init_base_state = torch.tensor(self.cfg.init_state.pos + self.cfg.init_state.rot +
                                            self.cfg.init_state.lin_vel + self.cfg.init_state.ang_vel, device=dev)
        self.height_points = self._init_height_points()
        self.num_height_points = 0 if self.height_points is None else self.height_points.shape[0]
        if self.terrain is not None:
            self.height_samples = torch.as_tensor(self.terrain.height_field, dtype=torch.float32, device=dev)
            self.terrain_origin_xy = torch.tensor(self.terrain.origin_xy, dtype=torch.float32, device=dev)
        # episode statistics, reduced on device and reported once per rollout (no per-step host sync)
        self._stat_count = torch.zeros((), device=dev)
        self.diverged_resets = torch.zeros((), device=dev)
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
                raise AttributeError(f"cfg.rewards.scales.{name} is non-zero but {type(self).__name__} has no "
                                     f"_reward_{name} method; implement it or set the scale to 0.")
            self.reward_scales[name] = scale * self.dt
            self.reward_functions.append((name, method))
        names = [name for name, _ in self.reward_functions]
        self._reward_scale_vec = torch.tensor([self.reward_scales[n] for n in names], device=self.device)
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
        if not self.cfg.terrain.curriculum:
            max_init = rows - 1
        self.terrain_levels = torch.randint(0, max_init + 1, (n,), device=dev)
        self.terrain_columns = torch.div(torch.arange(n, device=dev) * cols, n, rounding_mode="floor")
        self.env_origins = self.terrain_origins[self.terrain_levels, self.terrain_columns]

    def _randomize_model(self) -> None:
        """Per-world friction and base mass, written into the batched model fields once at start."""
        rand = self.cfg.domain_rand
        if rand.randomize_friction:
            self.friction_coeffs = rand_uniform(*rand.friction_range, (self.num_envs, 1), self.device)
            # MuJoCo combines geom frictions with max(): set every geom so the pair's friction is the sample
            self.sim.geom_friction[:, :, 0] = self.friction_coeffs
        if rand.randomize_base_mass:
            self.added_base_mass = rand_uniform(*rand.added_mass_range, (self.num_envs, 1), self.device)
            mass0 = float(self.mjm.body_mass[self.base])
            ratio = (mass0 + self.added_base_mass[:, 0]) / mass0
            self.sim.body_mass[:, self.base] = mass0 * ratio
            self.sim.body_inertia[:, self.base] = torch.as_tensor(
                self.mjm.body_inertia[self.base], dtype=torch.float32, device=self.device) * ratio[:, None]

    # ------------------------------------------------------------------------------------------------------
    # VecEnv
    # ------------------------------------------------------------------------------------------------------
    @property
    def episode_length_buf(self) -> torch.Tensor:
        return self._episode_length_buf

    @episode_length_buf.setter
    def episode_length_buf(self, value: torch.Tensor) -> None:
        """An assignment (rsl-rl's random initial episode lengths) copies into the buffer the step graph reads."""
        self._episode_length_buf.copy_(value)

    def get_observations(self) -> TensorDict:
        return self.obs_buf.clone()  # a copy: the next step overwrites obs_buf in place

    def reset(self) -> TensorDict:
        all_envs = torch.ones(self.num_envs, dtype=torch.bool, device=self.device)
        self._reset_envs(all_envs)
        self._resample_commands(all_envs)
        self._update_state()
        self._compute_observations()
        return self.obs_buf.clone()

    def step(self, actions: torch.Tensor) -> tuple[TensorDict, torch.Tensor, torch.Tensor, dict]:
        """One policy step. Returns copies: the step graph overwrites its buffers in place on the next step,
        and rsl-rl keeps references to observations across it."""
        if actions.shape != self._step_actions.shape:
            raise ValueError(f"actions of shape {tuple(actions.shape)}; this env takes (num_envs, num_actions) = "
                             f"{tuple(self._step_actions.shape)}")
        self._step_actions.copy_(actions)
        if self._step_graph is not None:
            self._step_graph()
        else:
            self._step_body()
        self.common_step_counter += 1
        if self.cfg.domain_rand.push_robots and self.common_step_counter % self._push_steps == 0:
            # after the observations, as in legged_gym: the push shows in the next step
            self._push_robots()
        extras = {"time_outs": self.time_out_buf.clone()}
        if self.common_step_counter % self._log_every == 0:
            extras["episode"] = self._episode_statistics()
        return self.obs_buf.clone(), self.rew_buf.clone(), self.reset_buf.clone(), extras

    def _step_body(self) -> None:
        """Everything a step does on the device: this is what the step graph records."""
        clip = self.cfg.normalization.clip_actions
        self.actions = torch.clamp(self._step_actions, -clip, clip)
        self.sim.ctrl[:] = self.default_dof_pos + self.cfg.control.action_scale * self.actions
        if self.forces is not None:
            self.forces.new_policy_step()
        self.sim.step(self.cfg.control.decimation)
        self._post_physics_step()

    # ------------------------------------------------------------------------------------------------------
    # step internals
    # ------------------------------------------------------------------------------------------------------
    def _post_physics_step(self) -> None:
        self._episode_length_buf += 1
        diverged = self._sanitize_diverged()
        self._update_state()
        self._check_termination(diverged)
        self._compute_reward()
        self._log_and_update_curriculum(self.reset_buf)
        self._reset_envs(self.reset_buf)
        # new commands for the robots just reset and for those whose resampling time came (episode length 0
        # after a reset, so both are caught by the same test)
        self._resample_commands(self.episode_length_buf % self._resample_steps == 0)
        self._update_state()
        self._compute_observations()
        self.last_actions[:] = self.actions
        self.last_dof_vel[:] = self.dof_vel

    def _sanitize_diverged(self) -> torch.Tensor:
        """Diverged worlds: state non-finite or absurdly fast, or constraint rows overflowed. Zero them and flag
        them for reset, so that one exploding world never reaches the observation normalisers or the logs."""
        # "not <=" is also true for NaN, which amax propagates
        bad = ~(self.sim.qvel.abs().amax(1) <= self.cfg.sim.max_qvel) | ~torch.isfinite(self.sim.qpos).all(1)
        bad |= self.sim.nefc >= self.cfg.sim.njmax
        self.sim.qpos[:] = torch.where(bad[:, None], 0.0, self.sim.qpos)
        self.sim.qvel[:] = torch.where(bad[:, None], 0.0, self.sim.qvel)
        self.diverged_resets += bad.sum()
        return bad

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
        self.feet_pos = self.sim.xpos[:, self.feet]

    def _body_linear_velocity(self, bodies: torch.Tensor) -> torch.Tensor:
        """World linear velocity of body origins from MuJoCo's com-based spatial velocity (rot, lin)."""
        cvel = self.sim.cvel[:, bodies]
        offset = self.sim.xpos[:, bodies] - self.sim.subtree_com[:, self.root_body][:, None, :]
        return cvel[..., 3:6] + torch.cross(cvel[..., 0:3], offset, dim=-1)

    def _check_termination(self, diverged: torch.Tensor) -> None:
        asset = self.cfg.asset
        contact = torch.norm(self.contact_forces[:, self.terminate_bodies], dim=-1).gt(1.0).any(1) \
            if self.terminate_bodies.numel() else torch.zeros_like(diverged)
        tilted = self.projected_gravity[:, 2] > -math.cos(asset.terminate_tilt)
        self.reset_buf = contact | tilted | diverged
        if asset.terminate_height > 0:
            self.reset_buf |= (self.base_pos[:, 2] - self._ground_height(self.base_pos[:, :2])) < asset.terminate_height
        self.time_out_buf = self.episode_length_buf >= self.max_episode_length
        self.reset_buf |= self.time_out_buf

    def _compute_reward(self) -> None:
        if not self.reward_functions:
            self.rew_buf.zero_()
            return
        terms = torch.stack([fn() for _, fn in self.reward_functions], dim=1)
        terms = torch.nan_to_num(terms, nan=0.0, posinf=0.0, neginf=0.0) * self._reward_scale_vec
        self.rew_buf = torch.where(self._clipped_terms, terms, 0.0).sum(dim=1)
        if self.cfg.rewards.only_positive_rewards:
            self.rew_buf.clamp_(min=0.0)
        self.rew_buf += torch.where(self._clipped_terms, 0.0, terms).sum(dim=1)
        self.episode_sums += terms

    def _log_and_update_curriculum(self, done: torch.Tensor) -> None:
        """Accumulate finished episodes' statistics on device, then move finished robots' terrain levels."""
        mask = done.float()
        self._stat_reward_sums += mask @ self.episode_sums / self.max_episode_length_s
        if self._terrain_curriculum:
            self._update_terrain_curriculum(done)
        self._stat_count += mask.sum()

    @property
    def _terrain_curriculum(self) -> bool:
        return self.terrain is not None and self.cfg.terrain.curriculum and self.cfg.terrain.mode == "curriculum"

    def curriculum_state(self) -> dict[str, torch.Tensor]:
        """The robots' terrain levels, kept in checkpoints so that a resumed run climbs on from where it stopped."""
        return {"terrain_levels": self.terrain_levels.cpu()}

    def load_curriculum_state(self, state: dict[str, torch.Tensor]) -> str:
        """Restore ``curriculum_state()`` when it fits this env; says what happened (printed on --resume)."""
        if not self._terrain_curriculum:
            return "no terrain curriculum in this env"
        levels = state["terrain_levels"]
        if levels.shape != self.terrain_levels.shape or int(levels.max()) >= self.max_terrain_level:
            return (f"terrain curriculum restarts: the checkpoint's levels ({levels.numel()} robots, up to level "
                    f"{int(levels.max())}) do not fit {self.num_envs} robots on {self.max_terrain_level} levels")
        self.terrain_levels.copy_(levels)
        self.env_origins.copy_(self.terrain_origins[self.terrain_levels, self.terrain_columns])
        return (f"terrain curriculum restored: mean level {levels.float().mean():.2f} (robots move there at their "
                f"next reset)")

    def _update_terrain_curriculum(self, done: torch.Tensor) -> None:
        """Up a level after walking more than half a tile; down after less than half the commanded distance
        (legged_gym's game-inspired curriculum). A robot that solves the hardest level goes to a random level
        (``solved_top_level = "random"``, legged_gym) or stays there (``"stay"``)."""
        distance = torch.norm(self.base_pos[:, :2] - self.env_origins[:, :2], dim=1)
        move_up = distance > 0.5 * self.cfg.terrain.terrain_length
        commanded = torch.norm(self.commands[:, :2], dim=1) * self.max_episode_length_s
        move_down = (distance < 0.5 * commanded) & ~move_up
        level = self.terrain_levels + move_up.long() - move_down.long()
        top = self.max_terrain_level - 1
        if self.cfg.terrain.solved_top_level == "random":
            level = torch.where(level > top, torch.randint_like(level, 0, self.max_terrain_level), level)
        level = level.clamp(0, top)
        self.terrain_levels[:] = torch.where(done, level, self.terrain_levels)
        self.env_origins[:] = torch.where(done[:, None],
                                          self.terrain_origins[self.terrain_levels, self.terrain_columns],
                                          self.env_origins)

    def _episode_statistics(self) -> dict[str, torch.Tensor]:
        """Means over the episodes that ended since the last report (once per rollout, still on device)."""
        count = self._stat_count.clamp(min=1.0)
        rewards = self._stat_reward_sums / count
        stats = {f"rew_{name}": rewards[i] for i, (name, _) in enumerate(self.reward_functions)}
        # legged_gym's statistic: the mean level of all robots now (not only of those whose episode ended)
        stats["terrain_level"] = self.terrain_levels.float().mean()
        stats["diverged_resets"] = self.diverged_resets.clone()
        self._stat_reward_sums.zero_()
        self._stat_count.zero_()
        return stats

    def _reset_envs(self, mask: torch.Tensor) -> None:
        """Masked reset: only worlds where ``mask`` is True get a new state; nothing leaves the device."""
        n, dev = self.num_envs, self.device
        m = mask[:, None]
        qpos, qvel = self.sim.qpos, self.sim.qvel
        dof_pos = self.default_dof_pos + rand_uniform(-1.0, 1.0, (n, self.num_actions), dev) * \
            self.cfg.init_state.joint_pos_noise
        dof_pos = torch.clamp(dof_pos, self.dof_limits[:, 0], self.dof_limits[:, 1])
        base = self.init_base_state
        base_pos = self.env_origins + base[0:3]
        yaw = rand_uniform(-math.pi, math.pi, (n,), dev)
        base_quat = yaw_quat(yaw)
        new_qpos = qpos.clone()
        new_qpos[:, 0:3] = base_pos
        new_qpos[:, 3:7] = base_quat
        new_qpos[:, self.qpos_adr] = dof_pos
        new_qvel = torch.zeros_like(qvel)
        new_qvel[:, 0:2] = rand_uniform(-0.5, 0.5, (n, 2), dev)
        # (ctrl needs no reset: the next step writes it before the physics runs)
        qpos[:] = torch.where(m, new_qpos, qpos)
        qvel[:] = torch.where(m, new_qvel, qvel)
        self.sim.time[:] = torch.where(mask, 0.0, self.sim.time)
        self.sim.body_contact_force[:] = torch.where(m[..., None], 0.0, self.sim.body_contact_force)
        for buf in (self.actions, self.last_actions, self.last_dof_vel, self.feet_air_time):
            buf[:] = torch.where(m, 0.0, buf)
        self.last_contacts &= ~m
        self.episode_length_buf[:] = torch.where(mask, 0, self.episode_length_buf)
        self.episode_sums.masked_fill_(m, 0.0)
        if self.forces is not None:
            self._reset_forces(mask)

    @torch.compiler.disable
    def _reset_forces(self, mask: torch.Tensor) -> None:
        """New force-field draws for the envs in ``mask`` (Warp kernels: left out of torch.compile)."""
        self.forces.reset(wp.from_torch(mask.contiguous(), dtype=wp.bool))

    def _resample_commands(self, mask: torch.Tensor) -> None:
        n, dev, ranges = self.num_envs, self.device, self.cfg.commands.ranges
        new = torch.stack([rand_uniform(*ranges.lin_vel_x, (n,), dev), rand_uniform(*ranges.lin_vel_y, (n,), dev),
                           rand_uniform(*ranges.ang_vel_yaw, (n,), dev), rand_uniform(*ranges.heading, (n,), dev)], 1)
        small = torch.norm(new[:, :2], dim=1) < 0.2  # too slow to learn a gait from: stand still instead
        still = torch.rand(n, device=dev) < self.cfg.commands.still_fraction
        new[:, :2] *= (~(small | still))[:, None]
        new[:, 2] *= (~still)
        self.commands[:] = torch.where(mask[:, None], new, self.commands)

    def _push_robots(self) -> None:
        v = self.cfg.domain_rand.max_push_vel_xy
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

    def _measure_heights(self) -> torch.Tensor:
        """Heights of the scan points (in the base's yaw frame) below the base, relative to the target height."""
        yaw = yaw_quat(yaw_of(self.base_quat))
        points = quat_rotate(yaw[:, None, :].expand(-1, self.num_height_points, -1),
                             self.height_points[None].expand(self.num_envs, -1, -1))
        points = points[..., :2] + self.base_pos[:, None, :2]
        return self.base_pos[:, 2:3] - self.cfg.rewards.base_height_target - self._ground_height(points)

    def _task_observations(self) -> torch.Tensor:
        """Extra proprioceptive observations a task adds (e.g. a gait clock); none by default."""
        return torch.zeros(self.num_envs, 0, device=self.device)

    def _compute_observations(self) -> None:
        s = self.cfg.normalization.obs_scales
        if self.cfg.commands.heading_command:
            heading_error = wrap_to_pi(self.commands[:, 3] - yaw_of(self.base_quat))
            yaw_rate = self.cfg.commands.heading_stiffness * heading_error
            self.commands[:, 2] = yaw_rate.clamp(*self.cfg.commands.ranges.ang_vel_yaw)
        parts = [self.base_lin_vel * s.lin_vel, self.base_ang_vel * s.ang_vel, self.projected_gravity,
                 self.commands[:, :3] * self.commands_scale, (self.dof_pos - self.default_dof_pos) * s.dof_pos,
                 self.dof_vel * s.dof_vel, self.actions, self._task_observations()]
        if self.height_points is not None:
            parts.append(torch.clamp(self._measure_heights(), -1.0, 1.0) * s.height_measurements)
        clean = torch.cat(parts, dim=-1)
        policy = clean + self._noise(clean) if self.cfg.noise.add_noise else clean
        feet_forces = self.contact_forces[:, self.feet].flatten(1) * 0.01
        privileged = [clean, self.friction_coeffs, self.added_base_mass, feet_forces]
        if self._force_obs is not None:
            privileged.append(self._force_obs)
        clip = self.cfg.normalization.clip_observations
        critic = torch.nan_to_num(torch.cat(privileged, dim=-1), nan=0.0)
        self.policy_obs = torch.nan_to_num(policy, nan=0.0).clamp(-clip, clip)
        self.critic_obs = critic.clamp(-clip, clip)

    @property
    def obs_buf(self) -> TensorDict:
        """The latest observations: the policy's and the critic's (privileged) groups, as rsl-rl takes them."""
        return TensorDict({"policy": self.policy_obs, "critic": self.critic_obs}, batch_size=[self.num_envs],
                          device=self.device)

    def _noise(self, clean: torch.Tensor) -> torch.Tensor:
        if not hasattr(self, "_noise_scale"):
            ns, s, lvl = self.cfg.noise.noise_scales, self.cfg.normalization.obs_scales, self.cfg.noise.noise_level
            na, nt = self.num_actions, self._task_observations().shape[1]
            pieces = [torch.full((3,), ns.lin_vel * s.lin_vel), torch.full((3,), ns.ang_vel * s.ang_vel),
                      torch.full((3,), ns.gravity), torch.zeros(3), torch.full((na,), ns.dof_pos * s.dof_pos),
                      torch.full((na,), ns.dof_vel * s.dof_vel), torch.zeros(na), torch.zeros(nt)]
            if self.height_points is not None:
                pieces.append(torch.full((self.num_height_points,), ns.height_measurements * s.height_measurements))
            self._noise_scale = torch.cat(pieces).to(self.device) * lvl
        return (2.0 * torch.rand_like(clean) - 1.0) * self._noise_scale

    # ------------------------------------------------------------------------------------------------------
    # helpers for rewards
    # ------------------------------------------------------------------------------------------------------
    def foot_contacts(self) -> torch.Tensor:
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
        return torch.square(height - self.cfg.rewards.base_height_target)

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

    def _reward_dof_pos_limits(self):
        below = (self.soft_dof_limits[:, 0] - self.dof_pos).clamp(min=0.0)
        above = (self.dof_pos - self.soft_dof_limits[:, 1]).clamp(min=0.0)
        return torch.sum(below + above, dim=1)

    def _reward_tracking_lin_vel(self):
        error = torch.sum(torch.square(self.commands[:, :2] - self.base_lin_vel[:, :2]), dim=1)
        return torch.exp(-error / self.cfg.rewards.tracking_sigma)

    def _reward_tracking_ang_vel(self):
        error = torch.square(self.commands[:, 2] - self.base_ang_vel[:, 2])
        return torch.exp(-error / self.cfg.rewards.tracking_sigma)

    def _reward_feet_air_time(self):
        """Reward steps whose swing lasted longer than the target, paid at touchdown (legged_gym)."""
        contact = self.foot_contacts()
        contact_filt = contact | self.last_contacts
        self.last_contacts.copy_(contact)
        first_contact = (self.feet_air_time > 0.0) & contact_filt
        self.feet_air_time += self.dt
        reward = torch.sum((self.feet_air_time - self.cfg.rewards.feet_air_time_target) * first_contact, dim=1)
        reward *= torch.norm(self.commands[:, :2], dim=1) > 0.1
        self.feet_air_time *= ~contact_filt
        return reward

    def _reward_feet_stumble(self):
        forces = self.contact_forces[:, self.feet]
        return torch.any(torch.norm(forces[..., :2], dim=-1) > 5.0 * torch.abs(forces[..., 2]), dim=1).float()

    def _reward_stand_still(self):
        still = torch.norm(self.commands[:, :2], dim=1) < 0.1
        return torch.sum(torch.abs(self.dof_pos - self.default_dof_pos), dim=1) * still

    def _reward_feet_contact_forces(self):
        excess = torch.norm(self.contact_forces[:, self.feet], dim=-1) - self.cfg.rewards.max_contact_force
        return torch.sum(excess.clamp(min=0.0), dim=1)
