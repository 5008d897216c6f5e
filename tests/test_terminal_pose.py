"""The state an episode ended in: the env resets a world within the step that ends its episode, so it keeps the
state the world had before that reset (``terminal_qpos``, ``terminal_qvel``, ``terminal_commands``), and the
viewer's recorder puts it on the ``done`` row, where it used to put the next episode's start."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

G = 9.81  # m/s^2, the MJCF's gravity


def _play(*extra: str):
    from legged_gente.scripts import view as view_script
    from legged_gente.utils.args import parse_args

    args = parse_args(view_script.build_arg_parser(), ["--task", "gente_biped_flat", "--device", "cpu", "--play",
                                                       "--policy", "zero", "--robots", "1", *extra])
    return view_script._make_play(args)


def test_a_fall_row_holds_the_pose_that_ended_the_episode():
    """The biped is put 3 m above the plane, tilted 120 deg about y (past its terminate_tilt of 1 rad), its joints
    at their PD targets, moving at 1 m/s along world x. In free fall nothing but gravity acts (no contact, no joint
    torque: every body falls alike), so MuJoCo's semi-implicit Euler over N = 4 substeps of h = 5 ms gives
        v_z = -g N h = -0.1962 m/s,   z = z0 - g h^2 (1 + 2 + ... + N) = 3 - 9.81 * 2.5e-5 * 10 = 2.9975475 m,
        x = x0 + N h * 1 m/s = 0.32 m,
    pose and joints otherwise unchanged. The tilt ends the episode at that step (a fall); the done row must hold
    that state, and its velocity in the base frame: v_b = R^T v_w with R = R_y(120 deg), so vx_b = c vx - s vz,
    vy_b = vy; the yaw rate 0. The next row is one step into the new episode, back near the upright spawn."""
    env, policy, recorder = _play()
    n_sub, h = env.cfg.control.decimation, env.cfg.sim.dt
    assert (n_sub, h) == (4, 0.005)
    np.testing.assert_allclose(env.mjm.opt.gravity, [0.0, 0.0, -G])
    theta = math.radians(120.0)
    assert theta > env.cfg.asset.terminate_tilt
    quat = [math.cos(theta / 2), 0.0, math.sin(theta / 2), 0.0]  # w x y z: theta about y
    q0 = np.concatenate([[0.3, -0.2, 3.0], quat, env.default_dof_pos[0].numpy()])
    env.sim.qpos[0] = torch.tensor(q0, dtype=torch.float32)
    env.sim.qvel[0] = 0.0
    env.sim.qvel[0, 0] = 1.0
    env.set_commands(torch.tensor([[0.5, -0.1, 0.0, 0.3]]))
    commanded = env.commands[0, :3].clone().numpy()

    obs = env.get_observations()
    with torch.inference_mode():
        obs, _, done, _ = env.step(policy(obs))
        recorder.add()
        respawn = env.sim.qpos[0].clone().numpy()
        env.step(policy(obs))
        recorder.add()
    assert done.tolist() == [True]
    rollout = recorder.rollout()
    assert rollout.done[:, 0].tolist() == [True, False] and rollout.fell[:, 0].tolist() == [True, False]

    vz = -G * n_sub * h
    expected = q0.copy()
    expected[0] += n_sub * h * 1.0
    expected[2] -= G * h**2 * n_sub * (n_sub + 1) / 2
    np.testing.assert_allclose(expected[[0, 2]], [0.32, 2.9975475])
    np.testing.assert_allclose(rollout.qpos[0, 0], expected, atol=2e-5)
    c, s = math.cos(theta), math.sin(theta)
    np.testing.assert_allclose(rollout.vel[0, 0], [c * 1.0 - s * vz, 0.0, 0.0], atol=1e-4)
    np.testing.assert_allclose(rollout.cmd[0, 0], commanded, atol=1e-6)  # the command the fall happened under
    assert rollout.forces[0].shape[1] == 0  # a plane: no force fields, no arrows

    # the respawn is upright at the spawn height (init_state.pos z = 1.03 m), not the fallen pose
    _, x, y, _ = respawn[3:7]
    upright = 1 - 2 * (x * x + y * y)  # the z component of the base's z axis (any yaw: random_init_yaw)
    assert respawn[2] == pytest.approx(1.03, abs=1e-6) and upright > math.cos(math.radians(45))
    assert np.abs(rollout.qpos[0, 0, :3] - respawn[:3]).max() > 1.0
    assert np.abs(rollout.qpos[1, 0, :3] - respawn[:3]).max() < 0.05  # one step (0.02 s) after it


def test_the_terminal_state_is_the_live_state_in_worlds_not_reset():
    """Two robots, one tilted past its limit: only it is reset. The other's terminal state is its live state after
    the step (the copy is made for every world, before the reset); its commands are those the step ran under."""
    env, policy, _ = _play("--num_envs", "2")
    theta = math.radians(120.0)
    env.sim.qpos[1, 3:7] = torch.tensor([math.cos(theta / 2), 0.0, math.sin(theta / 2), 0.0])
    env.sim.qpos[1, 2] = 3.0
    env.sim.qvel[1] = 0.0
    with torch.inference_mode():
        _, _, done, _ = env.step(policy(env.get_observations()))
    assert done.tolist() == [False, True]
    assert torch.equal(env.terminal_qpos[0], env.sim.qpos[0]) and torch.equal(env.terminal_qvel[0], env.sim.qvel[0])
    # the heading's yaw rate is updated after the reset, from the new pose: vx, vy and heading are the step's
    assert torch.equal(env.terminal_commands[0, [0, 1, 3]], env.commands[0, [0, 1, 3]])
    assert env.terminal_qpos[1, 2] > 2.99 and env.sim.qpos[1, 2] == pytest.approx(1.03, abs=1e-6)


def test_a_diverged_world_row_holds_its_respawn(tmp_path):
    """A world whose state blew up (here a NaN velocity: its qpos turns NaN in the step) is reset as a diverged
    world; its ended state is meaningless, and a NaN pose would make the whole rollout file unreadable ("qpos is
    not finite"). Its done row keeps the respawn, the env's state after the step, and the file loads."""
    from legged_gente.viewer.rollout import Rollout

    env, policy, recorder = _play()
    env.sim.qvel[0, 0] = float("nan")
    with torch.inference_mode():
        _, _, done, _ = env.step(policy(env.get_observations()))
        recorder.add()
    assert done.tolist() == [True] and env.diverged_buf.tolist() == [True]
    assert not torch.isfinite(env.terminal_qpos[0]).all()
    rollout = recorder.rollout()
    np.testing.assert_array_equal(rollout.qpos[0, 0], env.sim.qpos[0].numpy())
    np.testing.assert_array_equal(rollout.cmd[0, 0], env.commands[0, :3].numpy())
    assert np.isfinite(rollout.vel).all() and not rollout.fell.any()
    assert Rollout.load(rollout.save(tmp_path / "r.npz")).num_steps == 1
