"""Roll a policy out on benchmark terrains laid out as tiles of one terrain and measure every robot.

The task's env is built in terrain mode "generated" with one spec per tile (all tiles of equal size),
``robots_per_terrain`` robots assigned to each tile, observation noise, pushes and friction and mass randomisation
off (the spawn's random yaw and initial velocity stay, as in training: the settle time covers them). The env is the
task's own class and steps as in training (on a GPU: the whole step as one CUDA graph, its torch logic compiled):
the evaluation only reads what a step leaves (its outputs and the state after it) and commands the robots between
steps through :meth:`LeggedRobot.set_commands`. The env's episode is set longer than the evaluated one, so no robot
times out inside it. Every robot is measured over its first episode only: ``num_steps`` policy steps, or until
its world is reset (a fall) or diverges. The step that ends a robot's episode is not measured: after it the env has
already reset that world. All accumulation stays on the device.

Metric definitions (per robot; docs/evaluation.md repeats them):

* ``diverged``: the simulation of the robot's world broke down: the env flagged it (non-finite state, a joint or
  base moving faster than ``sim.max_qvel``, constraint rows overflowing) or its base moved faster than
  ``MAX_BASE_SPEED``. Such a robot is a failure and enters no other metric's mean (its numbers are the
  simulator's, not the policy's); it is counted on its own.
* ``fell``: the episode ended by a termination (terminating contact, tilt, height), not by divergence.
* ``tracking_error`` (m/s): mean over the robot's steps after ``settle_s`` of |v_cmd_xy - v_xy|, the
  horizontal base velocity in the base frame against the commanded (vx, vy).
* ``progress``: velocity task: the distance covered along the commanded path over the commanded distance, both
  after ``settle_s``, the commanded distance to the episode's end for a robot that fell (to its last measured
  step for one that reached its tile's edge): sum over steps of (v_xy . u) dt divided by the sum of |c_xy| dt, with v_xy the base's world
  velocity and u the command's direction (c_xy / |c_xy|, given in the base frame) turned by a reference yaw: the
  yaw of a robot that turned exactly at the yaw rates it was commanded, from its spawn yaw (in heading mode it
  stops at the commanded heading: the env commands the rate from the robot's own yaw, so a robot that turns late
  is commanded on after the reference has arrived). A robot that stands scores 0, one that follows the command
  1, one that walks the commanded speed facing the wrong way less (cos of the angle); undefined (NaN) for a
  stand-still command.
* ``heading_error`` (deg): heading mode only (else NaN): |commanded heading - base yaw| at the robot's last
  measured step after ``settle_s`` (NaN if it has none), for moving commands: how far from its heading a robot
  ends, which ``progress`` weighs only through the distance lost (not part of ``success``).
* ``standing``: the robot was commanded to stand still (velocity task).
* ``left_tile``: the robot's base came within ``tile_edge_margin`` (default :data:`TILE_EDGE_MARGIN`) of its
  tile's edge, where its terrain ends (the next tile or the border lies at any height: often a cliff on GenTe's
  terrains); its measured episode ended there, not as a fall. With ``tile_edge_margin=None`` robots walk on past
  their tile's edge.
* ``success``: never for a diverged robot; velocity task, moving command (|c_xy| >= 0.3 m/s): not fell,
  tracking_error < ``tracking_threshold`` (0.25 m/s) and progress >= ``min_progress`` (0.7); stand-still
  command (its own category): not fell and tracking_error < ``tracking_threshold``; waypoint task: the last
  waypoint was reached before any termination.
* ``distance`` (m): xy path length of the base, summed over policy steps; ``displacement`` (m): straight
  xy distance from the spawn to the last position.
* ``collisions``: onsets of contact (|F| > 1 N) on any penalised body (thighs, shanks: the task's
  ``penalize_contacts_on``), counted once per contact episode.
* ``energy`` (J): sum over policy steps of sum_j |tau_j * qdot_j| * dt (mechanical power of the joints,
  positive and negative work both counted, sampled at the policy rate). The report's ``energy_per_m`` is not
  per robot: a group's total energy over its total distance (:mod:`legged_gente.evaluation.report`).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import torch

from legged_gente.evaluation.benchmark import TILE_EDGE_MARGIN, Item, tile_geometry
from legged_gente.evaluation.tasks import (MIN_SPEED, REACH_DISTANCE, STAND_FRACTION, WAYPOINT_LATERAL,
                                           WAYPOINT_SPACING, WAYPOINT_SPEED, WAYPOINTS, VelocityTask, WaypointTask,
                                           zigzag_waypoints)
from legged_gente.terrain.composition import MAX_ABS_HEIGHT
from legged_gente.utils.torch_math import quat_rotate_inverse, wrap_to_pi, yaw_of, yaw_quat

CONTACT_THRESHOLD = 1.0
"""N; a penalised body with a larger contact force is touching something."""
MAX_BASE_SPEED = math.sqrt(2.0 * 9.81 * 2.0 * MAX_ABS_HEIGHT) + 5.0
"""m/s (24.8): no robot base moves this fast on a benchmark terrain. A free fall through the terrain library's
whole height range (2 x MAX_ABS_HEIGHT = 20 m) reaches sqrt(2 g h) = 19.8 m/s (energy conservation); 5 m/s more
cover running and river currents. A faster base is a simulation that blew up (a launched robot)."""


def grid_shape(n: int) -> tuple[int, int]:
    """(rows, cols) with rows * cols == n and the grid as square as possible (one tile per spec)."""
    rows = max(r for r in range(1, int(math.isqrt(n)) + 1) if n % r == 0)
    return rows, n // rows


def lay_out_items(terrain_cfg, items: list[Item]) -> tuple[int, int]:
    """Set ``terrain_cfg`` (a task's terrain config) to the benchmark layout: ``items`` as the tiles of a
    (rows, cols) grid (:func:`grid_shape`), row-major, as generated heightfield tiles. Returns (rows, cols)."""
    size_x, size_y, resolution = tile_geometry([item.spec() for item in items])
    rows, cols = grid_shape(len(items))
    terrain_cfg.mesh_type, terrain_cfg.mode, terrain_cfg.curriculum = "heightfield", "generated", False
    terrain_cfg.generated_specs = [str(item.spec_path) for item in items]
    terrain_cfg.num_rows, terrain_cfg.num_cols = rows, cols
    terrain_cfg.terrain_length, terrain_cfg.terrain_width, terrain_cfg.resolution = size_x, size_y, resolution
    return rows, cols


def settle_steps(settle_s: float, dt: float) -> int:
    """The policy steps at the start of an episode left out of the tracking error."""
    return int(round(settle_s / dt))


def episode_steps(episode_s: float, dt: float) -> int:
    """The policy steps of an evaluated episode, a partial last step counted whole. The quotient is rounded first:
    0.14 s / 0.02 s is 7.000000000000001 in binary floating point, which is 7 steps, not 8."""
    return math.ceil(round(episode_s / dt, 9))


def check_settle(settle_s: float, num_steps: int, dt: float) -> None:
    """``settle_s``, the start of an episode of ``num_steps`` policy steps of ``dt`` s left out of the tracking error,
    or a one-line error: it must leave a step to measure."""
    if not settle_s >= 0.0:
        raise ValueError(f"settle_s must be >= 0 s, got {settle_s}.")
    if not math.isfinite(settle_s):
        raise ValueError(f"settle_s must be a finite time in s, got {settle_s}.")
    if settle_steps(settle_s, dt) >= num_steps:
        raise ValueError(f"settle_s {settle_s} s leaves nothing of the {num_steps * dt:g} s episode to measure (steps "
                         f"of {dt:g} s); give a value in [0, episode_s - one step).")


class Recorder:
    """Per-robot accumulators on the env's device, updated after every policy step from what the step left."""

    def __init__(self, env, settle_s: float, trace_robots: torch.Tensor, tile_bounds: torch.Tensor | None = None):
        n, dev = env.num_envs, env.device
        self.tile_bounds = tile_bounds
        """(n, 4) x_lo, y_lo, x_hi, y_hi (m, world) of the part of its tile a robot is measured on, or None."""
        z = lambda dtype=torch.float32: torch.zeros(n, dtype=dtype, device=dev)  # noqa: E731
        self.dt, self.settle_steps = env.dt, settle_steps(settle_s, env.dt)
        self.active = torch.ones(n, dtype=torch.bool, device=dev)
        self.fell, self.diverged, self.left_tile = z(torch.bool), z(torch.bool), z(torch.bool)
        self.err_sum, self.err_steps, self.distance, self.energy, self.alive_steps = z(), z(), z(), z(), z()
        self.along_cmd, self.cmd_distance = z(), z()
        self.heading_error = torch.full((n,), float("nan"), device=dev)
        self.reference_yaw = yaw_of(env.base_quat).clone()
        self.reference_arrived = torch.zeros(n, dtype=torch.bool, device=dev)
        self.yaw_rate = env.commands[:, 2].clone()  # commanded for the coming step
        self.collisions = z()
        self.in_contact = z(torch.bool)
        self.start_xy = env.base_pos[:, :2].clone()
        self.last_xy = self.start_xy.clone()
        self.step = 0
        self.trace_robots = trace_robots
        self.trace: dict[str, list[torch.Tensor]] = {"cmd": [], "heading": [], "vel": [], "world_vel": [], "pos": [],
                                                     "active": [], "qpos": []}

    def record(self, env, dones: torch.Tensor) -> None:
        """One policy step: ``dones`` is the step's output, everything else the env's state after the step.
        A world the step reset already holds its next episode: its robot's episode ended (a fall, or a
        divergence the env flagged) and this step is not measured."""
        a = self.active
        self.step += 1
        speed = torch.linalg.norm(env.sim.qvel[:, 0:3], dim=1)  # world-frame base velocity
        launched = ~dones & ~(speed <= MAX_BASE_SPEED)  # "not <=": NaN too
        diverged = a & (env.diverged_buf | launched)
        alive = a & ~dones & ~diverged
        self.fell |= a & dones & ~env.time_out_buf & ~diverged
        self.diverged |= diverged
        af = alive.float()
        xy = env.base_pos[:, :2]
        # the commands the step ran under: a world the step reset already holds its next episode's, drawn by the env
        command = torch.where(dones[:, None], env.terminal_commands[:, :2], env.commands[:, :2])
        err = torch.norm(command - env.base_lin_vel[:, :2], dim=1)
        counted = af * float(self.step > self.settle_steps)
        self.err_sum += torch.where(alive, err, 0.0) * counted
        self.err_steps += counted
        cmd_speed = torch.norm(command, dim=1)
        self._turn_reference(env)
        # the base's world velocity (free joint) in the reference frame, where the command is given
        velocity = quat_rotate_inverse(yaw_quat(self.reference_yaw), env.sim.qvel[:, 0:3])[:, :2]
        along = torch.sum(velocity * command, dim=1) / cmd_speed.clamp(min=1e-6)
        self.along_cmd += torch.where(alive, along, 0.0) * self.dt * counted
        # a fallen robot stays told to walk: its progress is over the whole episode's commanded distance (over its
        # live steps alone, a lunge before a fall scored above walking); one that reached its tile's edge stops
        self.cmd_distance += cmd_speed * self.dt * float(self.step > self.settle_steps) * (alive | self.fell).float()
        if env.heading_command:
            heading_error = torch.rad2deg(wrap_to_pi(env.commands[:, 3] - yaw_of(env.base_quat)).abs())
            measured = alive & ~env.standing_still & (self.step > self.settle_steps)
            self.heading_error = torch.where(measured, heading_error, self.heading_error)
        self.distance += torch.where(alive, torch.norm(xy - self.last_xy, dim=1), 0.0)
        self.last_xy = torch.where(alive[:, None], xy, self.last_xy)
        power = torch.sum(torch.abs(env.torques * env.dof_vel), dim=1)
        self.energy += torch.where(alive, power, 0.0) * self.dt
        if env.penalized_bodies.numel():
            contact = torch.norm(env.contact_forces[:, env.penalized_bodies], dim=-1).gt(CONTACT_THRESHOLD).any(1)
        else:
            contact = torch.zeros_like(a)
        self.collisions += (contact & ~self.in_contact).float() * af
        self.in_contact = contact
        self.alive_steps += af
        if self.tile_bounds is not None:
            b = self.tile_bounds
            outside = (xy < b[:, :2]).any(1) | (xy > b[:, 2:]).any(1)
            self.left_tile |= alive & outside  # its terrain ends here: the measured episode does too
            alive = alive & ~outside
        self.active = alive
        r = self.trace_robots
        self.trace["cmd"].append(env.commands[r, :3].clone())
        self.trace["heading"].append(env.commands[r, 3].clone())  # the commanded heading (heading mode), rad
        self.trace["vel"].append(torch.cat([env.base_lin_vel[r, :2], env.base_ang_vel[r, 2:3]], 1))
        self.trace["world_vel"].append(env.sim.qvel[r, 0:3].clone())  # the free joint's: world frame
        # a world the step reset (not a diverged one): the pose its episode ended in, which gente-view replays
        qpos, _, _ = env.episode_end(r)
        self.trace["pos"].append(qpos[:, :2])
        self.trace["active"].append(alive[r].clone())
        self.trace["qpos"].append(qpos)

    def _turn_reference(self, env) -> None:
        """Advance the reference yaw by the yaw rate commanded for the step just taken; in heading mode it stays
        at the commanded heading once it gets there. Then keep the rate commanded for the next step."""
        turned = wrap_to_pi(self.reference_yaw + self.yaw_rate * self.dt)
        if env.heading_command:
            heading = env.commands[:, 3]
            before, after = wrap_to_pi(heading - self.reference_yaw), wrap_to_pi(heading - turned)
            passed = (before.abs() < 1e-6) | ((torch.sign(before) != torch.sign(after)) & (before.abs() < math.pi / 2))
            self.reference_arrived |= passed
            turned = torch.where(self.reference_arrived, heading, turned)
        self.reference_yaw = turned
        self.yaw_rate = env.commands[:, 2].clone()


@dataclasses.dataclass
class RunResult:
    """Per-robot metrics (numpy, one entry per robot) and traces of the first robot of every tile."""

    tile: np.ndarray
    metrics: dict[str, np.ndarray]
    traces: dict[str, np.ndarray]
    task: str
    params: dict


class Evaluation:
    """The task's env over ``items`` as tiles, ``robots_per_terrain`` robots each; :meth:`run` rolls a policy."""

    def __init__(self, task: str, items: list[Item], robots_per_terrain: int = 16, device: str = "cpu",
                 episode_length_s: float = 10.0, mode: str = "velocity", seed: int = 0):
        from legged_gente.envs.task_registry import nominal, task_registry

        if robots_per_terrain < 1:
            raise ValueError(f"robots_per_terrain must be >= 1, got {robots_per_terrain}.")
        if not episode_length_s > 0:
            raise ValueError(f"episode_s must be > 0 s, got {episode_length_s}.")
        if not math.isfinite(episode_length_s):
            raise ValueError(f"episode_s must be a finite time in s, got {episode_length_s}.")
        if mode not in ("velocity", "waypoints"):
            raise ValueError(f"mode {mode!r}: use 'velocity' or 'waypoints'.")
        self.items, self.mode, self.seed = list(items), mode, seed
        env_cfg, self.train_cfg = task_registry.get_cfgs(task)
        _, cols = lay_out_items(env_cfg.terrain, self.items)
        env_cfg.env.num_envs = len(self.items) * robots_per_terrain
        self.dt = env_cfg.sim.dt * env_cfg.control.decimation
        self.num_steps = episode_steps(episode_length_s, self.dt)
        """Policy steps of the evaluated episode."""
        env_cfg.env.episode_length_s = episode_length_s + 1.0  # the env times no robot out inside it
        nominal(env_cfg)
        env_cfg.commands.resampling_time = episode_length_s + 1.0  # the task commands, set between steps
        if mode == "waypoints":
            env_cfg.commands.heading_command = True  # waypoints steer through the heading
        self.env_cfg = env_cfg
        env_class = task_registry.tasks[task][0]
        torch.manual_seed(self.seed)  # the env's own draws (the force fields' seed among them) follow the seed
        self.env = env_class(env_cfg, device=device, train_cfg_steps_per_env=self.train_cfg.runner.num_steps_per_env)
        self.task_name = task
        self.robots_per_terrain = robots_per_terrain
        tile = torch.arange(self.env.num_envs, device=device) // robots_per_terrain
        self.tile = tile
        self.env.terrain_levels = tile // cols
        self.env.terrain_columns = tile % cols
        self.env.env_origins = self.env.terrain_origins[self.env.terrain_levels, self.env.terrain_columns]

    def tile_bounds(self, margin: float | None) -> torch.Tensor | None:
        """(n, 4) x_lo, y_lo, x_hi, y_hi of every robot's tile, ``margin`` (m) inside its edges; None without one."""
        if margin is None:
            return None
        size_x, size_y = self.env.terrain.tile_size
        if not 0.0 <= margin < min(size_x, size_y) / 2:
            raise ValueError(f"tile_edge_margin {margin} m must be in [0, {min(size_x, size_y) / 2:g}) for "
                             f"{size_x:g} x {size_y:g} m tiles.")
        tile = self.tile.cpu().numpy()
        bounds = torch.as_tensor(self.env.terrain.tile_bounds(tile // self.env_cfg.terrain.num_cols,
                                                             tile % self.env_cfg.terrain.num_cols),
                                 dtype=torch.float32, device=self.tile.device)
        return bounds + torch.tensor([margin, margin, -margin, -margin], device=bounds.device)

    def make_task(self, reach_distance: float = REACH_DISTANCE, speed: float = WAYPOINT_SPEED,
                  num_waypoints: int = WAYPOINTS, spacing: float = WAYPOINT_SPACING, lateral: float = WAYPOINT_LATERAL,
                  min_speed: float = MIN_SPEED, stand_fraction: float = STAND_FRACTION,
                  tile_edge_margin: float | None = TILE_EDGE_MARGIN):
        """The run's commands: the velocity task, or waypoint paths kept within ``tile_edge_margin`` of their tile
        where they can turn back (the margin ``run`` ends a measured episode at; None: the tile's edge)."""
        env = self.env
        if self.mode == "velocity":
            return VelocityTask(env.num_envs, self.env_cfg.commands.ranges, self.env_cfg.commands.heading_command,
                                env.device, seed=self.seed, min_speed=min_speed, stand_fraction=stand_fraction)
        inside = self.tile_bounds(tile_edge_margin or 0.0)
        points = zigzag_waypoints(env.env_origins[:, :2], num_waypoints, spacing, lateral, seed=self.seed,
                                  x_range=inside[:, [0, 2]])
        return WaypointTask(points, reach_distance, speed)

    def run(self, policy, task=None, settle_s: float = 1.0, progress: bool = True,
            tile_edge_margin: float | None = TILE_EDGE_MARGIN) -> RunResult:
        """Roll ``policy`` (obs TensorDict -> actions) for one episode of every robot; returns per-robot metrics.
        A robot's measured episode ends when its base comes ``tile_edge_margin`` (m) close to its tile's edge,
        where its terrain ends and the next tile or the border begins (``left_tile``); None measures on past it.
        Without a ``task``, the mode's default task, its waypoint paths kept within that same margin."""
        from tqdm import tqdm

        env = self.env
        check_settle(settle_s, self.num_steps, self.dt)
        task = task or self.make_task(tile_edge_margin=tile_edge_margin)  # waypoint paths within this run's margin
        torch.manual_seed(self.seed)
        if env.forces is not None:
            env.forces.restart_draws()  # every run meets the same soil and water draws
        first = torch.arange(0, env.num_envs, self.robots_per_terrain, device=env.device)

        def command():
            return env.set_commands(task.commands(env.base_pos[:, :2], env.commands), task.still())

        # the reset too: buffers made inside an earlier run are inference tensors
        with torch.inference_mode():
            env.reset()  # every robot to its tile's spawn
            obs = command()
            recorder = Recorder(env, settle_s, first, self.tile_bounds(tile_edge_margin))
            for _ in tqdm(range(self.num_steps), desc=f"{self.mode} rollout", disable=not progress, unit="step"):
                _, _, dones, _ = env.step(policy(obs))
                recorder.record(env, dones)
                task.update(env.base_pos[:, :2], recorder.active)
                obs = command()
        r = recorder
        steps = r.err_steps.clamp(min=1.0)
        tracking = torch.where(r.err_steps > 0, r.err_sum / steps, torch.full_like(steps, float("nan")))
        progress = torch.where(r.cmd_distance > 0, r.along_cmd / r.cmd_distance.clamp(min=1e-9),
                               torch.full_like(steps, float("nan")))
        standing = getattr(task, "standing", torch.zeros_like(r.fell))
        metrics = {
            "fell": r.fell, "tracking_error": tracking, "distance": r.distance,
            "displacement": torch.norm(r.last_xy - r.start_xy, dim=1), "collisions": r.collisions,
            "energy": r.energy, "time_s": r.alive_steps * env.dt, "finished": task.finished,
            "progress": progress, "heading_error": r.heading_error, "standing": standing, "diverged": r.diverged,
            "left_tile": r.left_tile,
        }
        out = {k: v.detach().cpu().numpy() for k, v in metrics.items()}
        traces = {k: torch.stack(v, 1).cpu().numpy() for k, v in r.trace.items()}
        traces["spawn"] = env.env_origins[first].cpu().numpy()
        traces["fell"] = r.fell[first].cpu().numpy()  # why a traced episode ended: a fall, or the tile's edge, or time
        traces["dt"] = np.array(env.dt)
        params = {"settle_s": settle_s, "dt": env.dt, "episode_length_s": self.num_steps * env.dt,
                  "max_base_speed": MAX_BASE_SPEED, "tile_edge_margin": tile_edge_margin}
        if isinstance(task, WaypointTask):
            traces["waypoints"] = task.waypoints[first].cpu().numpy()
            params |= {"reach_distance": task.reach_distance, "speed": task.speed}
        else:  # the commands' draw: which robots stand, how fast the others are told to go
            params |= {"min_speed": task.min_speed, "stand_fraction": task.stand_fraction}
        return RunResult(self.tile.cpu().numpy(), out, traces, self.mode, params)


def load_policy(evaluation, **sources):
    """obs TensorDict -> actions (see ``load_policy_and_file``)."""
    return load_policy_and_file(evaluation, **sources)[0]


def load_policy_and_file(evaluation, checkpoint: str | None = None, exported: str | None = None,
                         baseline: str | None = None, pretrained: bool = False):
    """(obs TensorDict -> actions, the file it came from) from an rsl-rl checkpoint (file or run folder), an
    exported ONNX policy, the policy shipped for the task, or a baseline."""
    env = evaluation.env
    given = [x for x in (checkpoint, exported, baseline, pretrained) if x]
    if len(given) != 1:
        raise ValueError("give exactly one of --checkpoint (rsl-rl model_N.pt or its run folder), --exported "
                         "(policy.onnx from gente-play), --pretrained or --baseline (zero | random).")
    if baseline:
        if baseline == "zero":
            return (lambda obs: torch.zeros(env.num_envs, env.num_actions, device=env.device)), None
        if baseline == "random":
            return (lambda obs: 0.5 * torch.randn(env.num_envs, env.num_actions, device=env.device)), None
        raise ValueError(f"--baseline {baseline!r}: use 'zero' or 'random'.")
    if exported:
        from legged_gente.utils.export import OnnxPolicy

        return OnnxPolicy(exported, env.get_observations(), env.num_actions), Path(exported).resolve()
    from legged_gente.envs.task_registry import task_registry
    from legged_gente.utils.checkpoints import checkpoint_candidates, load_newest_readable_of

    if pretrained:
        runner, path = task_registry.make_pretrained_runner(env, evaluation.task_name, evaluation.train_cfg)
        return runner.get_inference_policy(device=env.device), path
    path = Path(checkpoint)
    if not path.exists():
        raise FileNotFoundError(f"--checkpoint {checkpoint}: no such file or run folder.")
    # a run folder: its newest readable checkpoint, as gente-play takes it; a file: that file or an error
    candidates = checkpoint_candidates(path.parent, path.name) if path.is_dir() else [path]
    path, runner = load_newest_readable_of(
        candidates, lambda path: task_registry.make_policy_runner(env, evaluation.task_name, path, evaluation.train_cfg),
        path)
    return runner.get_inference_policy(device=env.device), path.resolve()
