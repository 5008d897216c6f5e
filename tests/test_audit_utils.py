"""Training utilities and the train/play scripts, checked by hand: the --resume flag against a --set of the field it
sets, and the maths the training relies on worked out here from its formulas."""

import math

import mujoco
import numpy as np
import pytest
import torch
from test_cli_errors import one_line_error as command_error
from test_cli_flags_by_hand import CPU, Built, no_env, one_line_error  # noqa: F401 (no_env is a fixture)
from test_ppo_by_hand import algorithm

from legged_gente.scripts import play as play_script
from legged_gente.scripts import train as train_script
from legged_gente.utils.torch_math import quat_rotate, quat_rotate_inverse, wrap_to_pi, yaw_of, yaw_quat


@pytest.mark.parametrize("value", ["False", "True"])
def test_resume_and_a_set_of_runner_resume_are_refused(capsys, no_env, value):  # noqa: F811
    """--resume sets runner.resume = True after the --set; `--resume --set runner.resume=False` resumed anyway."""
    line = one_line_error(capsys, [*CPU, "--resume", "--set", f"runner.resume={value}"])
    assert line.startswith("gente-train: error: ") and "runner.resume" in line and "give one" in line


def test_pretrained_and_a_set_of_runner_resume_are_refused(capsys, no_env):  # noqa: F811
    """--pretrained with --resume is refused ('pick one'); with --set runner.resume=True the run resumed the latest
    run of the experiment and the shipped policy was silently not loaded (make_alg_runner's resume comes first)."""
    line = one_line_error(capsys, [*CPU, "--pretrained", "--set", "runner.resume=True"])
    assert "--pretrained" in line and "runner.resume" in line


def test_a_set_of_runner_resume_alone_still_passes(no_env):  # noqa: F811
    with pytest.raises(Built):
        train_script.main([*CPU, "--set", "runner.resume=False"])


@pytest.mark.parametrize("picks", [["--set", "runner.checkpoint=5"],
                                   ["--set", "runner.resume=False", "--set", "runner.checkpoint=5"]])
def test_a_set_picking_a_checkpoint_without_resuming_is_refused(capsys, no_env, picks):  # noqa: F811
    """As --checkpoint without --resume ('add --resume'): the run started from scratch, the pick silently unused."""
    line = one_line_error(capsys, [*CPU, *picks])
    assert "add --resume" in line


@pytest.mark.parametrize("argv", [["--resume", "--set", "runner.checkpoint=5"],
                                  ["--set", "runner.resume=True", "--set", "runner.checkpoint=5"],
                                  ["--set", "runner.resume=True", "--checkpoint", "5"]])
def test_a_checkpoint_picked_to_resume_passes(no_env, argv):  # noqa: F811
    with pytest.raises(Built):
        train_script.main([*CPU, *argv])


@pytest.mark.parametrize("extra", [[], ["--pretrained"]])
def test_play_refuses_a_set_of_runner_resume(capsys, extra):
    """gente-play always loads a checkpoint: it set runner.resume = True after the --set, which it ignored."""
    line = command_error(capsys, play_script.main, [*CPU, *extra, "--set", "runner.resume=False"])
    assert line.startswith("gente-play: error: ") and "runner.resume" in line


@pytest.mark.parametrize("algorithm_cfg", [{"schedule": "fixed"}, {"schedule": "adaptive", "desired_kl": None}])
def test_a_fixed_learning_rate_is_the_configs_after_a_resume(algorithm_cfg):
    """Without a KL target the learning rate is a setting, not training state: `--resume --set
    algorithm.learning_rate=1e-4` of a run trained at a fixed 1e-3 kept training at 1e-3 (the checkpoint's
    optimizer state carries its rate)."""
    saved = algorithm(learning_rate=1e-3, **algorithm_cfg).save()
    resumed = algorithm(learning_rate=1e-4, **algorithm_cfg)
    resumed.load(saved, None, True)
    assert float(resumed.learning_rate) == pytest.approx(1e-4)
    assert all(float(group["lr"]) == pytest.approx(1e-4) for group in resumed.optimizer.param_groups)


def test_an_adaptive_learning_rate_resumes_where_it_was():
    """With a KL target the rate is state the rule adapted: a resume goes on from the checkpoint's rate."""
    trained = algorithm(learning_rate=1e-3)
    trained._learning_rate_tensor().fill_(3.375e-3)  # 1e-3 raised by 1.5 three times
    resumed = algorithm(learning_rate=1e-3)
    resumed.load(trained.save(), None, True)
    assert float(resumed.learning_rate) == pytest.approx(3.375e-3)
    assert float(resumed.optimizer.param_groups[0]["lr"]) == pytest.approx(3.375e-3)


# --- torch_math: MuJoCo's (w, x, y, z) quaternions ---------------------------------------------------------------

def axis_angle(axis, angle: float) -> torch.Tensor:
    """q = (cos(a/2), sin(a/2) * n), the unit quaternion of a rotation by ``angle`` about the unit ``axis``."""
    return torch.tensor([math.cos(angle / 2), *(math.sin(angle / 2) * c for c in axis)], dtype=torch.float64)


def test_quat_rotate_by_hand():
    # 90 deg about z takes x to y; 90 deg about x takes y to z (right-hand rule)
    about_z, about_x = axis_angle((0, 0, 1), math.pi / 2), axis_angle((1, 0, 0), math.pi / 2)
    ex, ey, ez = torch.eye(3, dtype=torch.float64)
    torch.testing.assert_close(quat_rotate(about_z, ex), ey)
    torch.testing.assert_close(quat_rotate(about_x, ey), ez)
    torch.testing.assert_close(quat_rotate_inverse(about_z, ey), ex)
    torch.testing.assert_close(quat_rotate_inverse(about_x, ez), ey)


def test_projected_gravity_of_a_pitched_body_by_hand():
    """A body pitched by theta about y: R_y = [[c, 0, s], [0, 1, 0], [-s, 0, c]], so gravity (0, 0, -1) in its
    frame is R_y^T (0, 0, -1) = (sin theta, 0, -cos theta)."""
    theta = 0.3
    got = quat_rotate_inverse(axis_angle((0, 1, 0), theta), torch.tensor([0.0, 0.0, -1.0], dtype=torch.float64))
    torch.testing.assert_close(got, torch.tensor([math.sin(theta), 0.0, -math.cos(theta)], dtype=torch.float64))


def test_quat_rotate_is_mujocos_rotation_of_its_quaternions():
    generator = torch.Generator().manual_seed(3)
    q = torch.randn(20, 4, generator=generator, dtype=torch.float64)
    q /= q.norm(dim=1, keepdim=True)
    v = torch.randn(20, 3, generator=generator, dtype=torch.float64)
    expected, back = np.zeros(3), np.zeros(3)
    for qi, vi, rotated, inverse in zip(q, v, quat_rotate(q, v), quat_rotate_inverse(q, v)):
        mujoco.mju_rotVecQuat(expected, vi.numpy(), qi.numpy())
        conjugate = qi.numpy() * np.array([1.0, -1.0, -1.0, -1.0])
        mujoco.mju_rotVecQuat(back, vi.numpy(), conjugate)
        np.testing.assert_allclose(rotated.numpy(), expected, atol=1e-12)
        np.testing.assert_allclose(inverse.numpy(), back, atol=1e-12)


def test_yaw_of_a_yawed_and_pitched_body_is_its_heading():
    """Yaw 2.0 rad then a pitch of 0.4 about the body's y axis: the body x axis projected on the ground points at
    2.0 rad, whatever the pitch (q = q_yaw * q_pitch, rotations composed in the body frame)."""
    q = torch.from_numpy(np.zeros(4))
    mujoco.mju_mulQuat(q.numpy(), axis_angle((0, 0, 1), 2.0).numpy(), axis_angle((0, 1, 0), 0.4).numpy())
    assert float(yaw_of(q)) == pytest.approx(2.0)
    torch.testing.assert_close(yaw_quat(torch.tensor(2.0, dtype=torch.float64)), axis_angle((0, 0, 1), 2.0))


@pytest.mark.parametrize("angle, wrapped", [
    (0.0, 0.0), (1.5 * math.pi, -0.5 * math.pi), (-1.5 * math.pi, 0.5 * math.pi), (2 * math.pi, 0.0),
    (7.0, 7.0 - 2 * math.pi), (-0.25, -0.25), (math.pi, -math.pi),  # [-pi, pi): pi itself is -pi
])
def test_wrap_to_pi_by_hand(angle, wrapped):
    assert float(wrap_to_pi(torch.tensor(angle, dtype=torch.float64))) == pytest.approx(wrapped, abs=1e-12)
