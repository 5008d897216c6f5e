"""A stand-in for the env state the evaluator's Recorder reads after a step, shared by the by-hand evaluator tests."""

from types import MethodType, SimpleNamespace

import torch

from legged_gente.envs.base.legged_robot import LeggedRobot


def stand_in_env(n: int, yaw: float = 0.0, vx: float = 0.0, penalized_bodies: tuple[int, ...] = ()):
    """n robots at the origin facing ``yaw`` (rad), at rest, commanded ``vx`` (m/s), with ``penalized_bodies``."""
    half = torch.full((n,), yaw / 2)
    zeros = torch.zeros(n, dtype=torch.bool)
    commands = torch.zeros(n, 4)
    commands[:, 0] = vx
    env = SimpleNamespace(
        num_envs=n, device="cpu", dt=0.02, commands=commands, heading_command=False, standing_still=zeros.clone(),
        base_pos=torch.zeros(n, 3), base_lin_vel=torch.zeros(n, 3), base_ang_vel=torch.zeros(n, 3),
        base_quat=torch.stack([half.cos(), 0 * half, 0 * half, half.sin()], 1),
        sim=SimpleNamespace(qvel=torch.zeros(n, 6), qpos=torch.zeros(n, 7)), diverged_buf=zeros.clone(),
        time_out_buf=zeros.clone(), torques=torch.zeros(n, 2), dof_vel=torch.zeros(n, 2),
        penalized_bodies=torch.tensor(penalized_bodies, dtype=torch.long), contact_forces=torch.zeros(n, 1, 3),
        reset_buf=zeros.clone(), terminal_qpos=torch.zeros(n, 7), terminal_qvel=torch.zeros(n, 6),
        terminal_commands=torch.zeros(n, 4))
    env.episode_end = MethodType(LeggedRobot.episode_end, env)  # the env's own rule for a step's row
    return env


def record_step(recorder, env, done):
    """A step's record: the env's reset_buf is the step's dones (what LeggedRobot.step returns), and its
    terminal_commands the commands the step ran under (kept before its resets, as LeggedRobot keeps them)."""
    env.reset_buf = done
    env.terminal_commands = env.commands.clone()
    recorder.record(env, done)
