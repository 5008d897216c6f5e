"""Evaluation tasks: what each robot is commanded to do. Pure tensor logic, no simulator.

* :class:`VelocityTask`: one random command per robot for the whole episode, drawn from the task's command
  ranges (vx, vy and a heading, or a yaw rate when the task has no heading mode). A share ``stand_fraction``
  of the robots is told to stand still (vx = vy = 0), and every other command asks for a horizontal speed of
  at least ``min_speed``: a policy that only stands cannot pass a moving command (the success rule is in
  :mod:`legged_gente.evaluation.report`).
* :class:`WaypointTask`: walk at ``speed`` towards the next waypoint, steering through the heading command;
  a waypoint counts as reached when the base is within ``reach_distance`` (d) of it in the xy plane, and
  the task is finished after the last one (the robot is then commanded to stand).
"""

from __future__ import annotations

import math

import torch

MIN_SPEED, STAND_FRACTION = 0.3, 0.1
"""The velocity task's defaults: the slowest moving command (m/s) and the share of robots told to stand still."""
REACH_DISTANCE = 1.0
"""The waypoint task's default d (m): a waypoint is reached within it."""


def _uniform(lo: float, hi: float, n: int, generator: torch.Generator) -> torch.Tensor:
    return lo + (hi - lo) * torch.rand(n, generator=generator)


class VelocityTask:
    name = "velocity"

    def __init__(self, num_robots: int, ranges, heading_command: bool, device: str, seed: int = 0,
                 min_speed: float = MIN_SPEED, stand_fraction: float = STAND_FRACTION):
        check_task_settings(min_speed=min_speed, stand_fraction=stand_fraction)
        self.min_speed, self.stand_fraction = float(min_speed), float(stand_fraction)
        g = torch.Generator().manual_seed(seed)
        n = num_robots
        yaw = _uniform(*ranges.ang_vel_yaw, n, g) if not heading_command else torch.zeros(n)
        heading = _uniform(*ranges.heading, n, g) if heading_command else torch.zeros(n)
        vxy = _moving_commands(ranges, n, min_speed, g)
        self.standing = torch.rand(n, generator=g) < stand_fraction
        """Per robot: told to stand still for the whole episode (scored as its own category)."""
        vxy[self.standing] = 0.0
        yaw[self.standing] = 0.0
        self._commands = torch.cat([vxy, yaw[:, None], heading[:, None]], 1).to(device)
        self.standing = self.standing.to(device)
        self.heading_command = heading_command
        self.finished = torch.zeros(n, dtype=torch.bool, device=device)

    def commands(self, pos_xy: torch.Tensor, current: torch.Tensor) -> torch.Tensor:
        """(n, 4) commands (vx, vy, yaw rate, heading); with a heading the env overwrites the yaw rate."""
        if not self.heading_command:
            return self._commands
        return torch.cat([self._commands[:, :2], current[:, 2:3], self._commands[:, 3:]], 1)

    def update(self, pos_xy: torch.Tensor, active: torch.Tensor) -> None:
        """Nothing to advance: the command is fixed for the episode."""

    def still(self) -> torch.Tensor:
        """Per robot: told to stand still now (in heading mode such a robot does not turn either)."""
        return self.standing


def _moving_commands(ranges, n: int, min_speed: float, generator: torch.Generator, rounds: int = 16) -> torch.Tensor:
    """(n, 2) (vx, vy) uniform in the command ranges, restricted to speeds >= ``min_speed`` (rejection sampling,
    a bounded number of rounds of 64 candidates per robot)."""
    (x0, x1), (y0, y1) = ranges.lin_vel_x, ranges.lin_vel_y
    fastest = math.hypot(max(abs(x0), abs(x1)), max(abs(y0), abs(y1)))
    if fastest < min_speed:
        raise ValueError(f"the command ranges (lin_vel_x {ranges.lin_vel_x}, lin_vel_y {ranges.lin_vel_y}) allow no "
                         f"speed >= min_speed {min_speed} m/s; lower min_speed or widen the ranges.")
    out = torch.zeros(n, 2)
    todo = torch.ones(n, dtype=torch.bool)
    for _ in range(rounds):
        k = int(todo.sum())
        if k == 0:
            return out
        cand = torch.stack([_uniform(x0, x1, k * 64, generator), _uniform(y0, y1, k * 64, generator)], 1).view(k, 64, 2)
        ok = torch.linalg.norm(cand, dim=2) >= min_speed
        found = ok.any(1)
        first = ok.float().argmax(1)
        idx = todo.nonzero().squeeze(1)
        out[idx[found]] = cand[found, first[found]]
        todo[idx[found]] = False
    raise ValueError(f"the command ranges (lin_vel_x {ranges.lin_vel_x}, lin_vel_y {ranges.lin_vel_y}) almost never "
                     f"reach min_speed {min_speed} m/s; lower min_speed or widen the ranges.")


class WaypointTask:
    name = "waypoints"

    def __init__(self, waypoints: torch.Tensor, reach_distance: float, speed: float):
        if waypoints.ndim != 3 or waypoints.shape[-1] != 2 or waypoints.shape[1] < 1:
            raise ValueError(f"waypoints must be (num_robots, K >= 1, 2) world xy, got {tuple(waypoints.shape)}.")
        check_task_settings(reach_distance=reach_distance, speed=speed)
        self.waypoints = waypoints
        self.reach_distance = float(reach_distance)
        self.speed = float(speed)
        n = waypoints.shape[0]
        self.index = torch.zeros(n, dtype=torch.long, device=waypoints.device)
        """Per robot: the waypoint it walks to now (== K once finished)."""
        self.finished = torch.zeros(n, dtype=torch.bool, device=waypoints.device)

    def target(self) -> torch.Tensor:
        k = self.index.clamp(max=self.waypoints.shape[1] - 1)
        return self.waypoints[torch.arange(len(k), device=k.device), k]

    def update(self, pos_xy: torch.Tensor, active: torch.Tensor) -> None:
        """Advance every active robot past each waypoint within reach (several per step when d is large)."""
        for _ in range(self.waypoints.shape[1]):  # bounded: at most K waypoints can be passed in one step
            reached = active & ~self.finished & (torch.norm(self.target() - pos_xy, dim=1) < self.reach_distance)
            self.index += reached.long()
            self.finished |= self.index >= self.waypoints.shape[1]

    def still(self) -> torch.Tensor:
        """Per robot: told to stand still now (after the last waypoint)."""
        return self.finished

    def commands(self, pos_xy: torch.Tensor, current: torch.Tensor) -> torch.Tensor:
        """Forward speed towards the current waypoint, heading = its bearing; once finished: stand, keep the heading."""
        delta = self.target() - pos_xy
        heading = torch.where(self.finished, current[:, 3], torch.atan2(delta[:, 1], delta[:, 0]))
        go = (~self.finished).float()
        return torch.stack([self.speed * go, torch.zeros_like(go), current[:, 2] * go, heading], 1)


WAYPOINTS, WAYPOINT_SPACING, WAYPOINT_LATERAL, WAYPOINT_SPEED = 4, 1.8, 1.5, 0.6
"""The waypoint task's zigzag: 4 waypoints 1.8 m apart along the path's axis, alternately 1.5 m left and right,
walked at a forward command of 0.6 m/s."""
WAYPOINT_TIME_SLACK = 1.5
"""The waypoint episode's time over the time to walk the zigzag at the commanded speed: turning onto each
waypoint and rough ground slow a robot; 50 % more keeps the task one of reaching the waypoints, not of speed."""


def zigzag_length(count: int = WAYPOINTS, spacing: float = WAYPOINT_SPACING, lateral: float = WAYPOINT_LATERAL) -> float:
    """m; the zigzag's polyline from the start through every waypoint: one leg of (spacing, lateral), then legs of
    (spacing, 2 lateral) from side to side."""
    return math.hypot(spacing, lateral) + (count - 1) * math.hypot(spacing, 2 * lateral)


def check_task_settings(**settings: float) -> None:
    """The tasks' settings given (each message starts with its name, which gente-evaluate's flags share): a share
    of standing robots in [0, 1], a positive speed floor and reach distance, a positive and finite waypoint speed
    (an infinite one would make a zero-length episode)."""
    for name, value in settings.items():
        if name == "stand_fraction" and not 0.0 <= value <= 1.0:
            raise ValueError(f"stand_fraction must be in [0, 1], got {value}.")
        if name in ("min_speed", "reach_distance", "speed") and not value > 0:
            raise ValueError(f"{name} must be > 0 {'m' if name == 'reach_distance' else 'm/s'}, got {value}.")
        if name == "speed" and not math.isfinite(value):
            raise ValueError(f"speed must be a finite speed in m/s, got {value}.")


def waypoint_episode_s(speed: float, count: int = WAYPOINTS, spacing: float = WAYPOINT_SPACING,
                       lateral: float = WAYPOINT_LATERAL) -> float:
    """s; the waypoint task's default episode: ``WAYPOINT_TIME_SLACK`` times the zigzag's length over ``speed``."""
    check_task_settings(speed=speed)
    return WAYPOINT_TIME_SLACK * zigzag_length(count, spacing, lateral) / speed


def zigzag_waypoints(starts_xy: torch.Tensor, count: int, spacing: float, lateral: float, seed: int = 0,
                     x_range: torch.Tensor | None = None) -> torch.Tensor:
    """(n, count, 2) waypoints ahead (+x) of each start: ``spacing`` m apart, alternating ``lateral`` m left/right
    with a random first side per robot, so every path needs turns. With ``x_range`` ((n, 2): the x each robot's
    waypoints should stay within, its terrain's) a path that would pass the upper bound runs towards -x instead
    where there is more room that way, so that a robot spawned off its tile's centre is not sent off its terrain."""
    n = starts_xy.shape[0]
    g = torch.Generator().manual_seed(seed)
    side = torch.where(torch.rand(n, generator=g) < 0.5, -1.0, 1.0).to(starts_xy.device)
    k = torch.arange(1, count + 1, device=starts_xy.device, dtype=starts_xy.dtype)
    sign = side[:, None] * torch.where(k % 2 == 1, 1.0, -1.0)[None, :]
    ahead = torch.ones_like(side)
    if x_range is not None:
        room_ahead, room_behind = x_range[:, 1] - starts_xy[:, 0], starts_xy[:, 0] - x_range[:, 0]
        ahead = torch.where((room_ahead < spacing * count) & (room_behind > room_ahead), -1.0, 1.0)
    x = starts_xy[:, None, 0] + ahead[:, None] * spacing * k[None, :]
    return torch.stack([x, starts_xy[:, None, 1] + lateral * sign], -1)
