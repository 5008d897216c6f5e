"""The exported policy: one self-contained ONNX file whose outputs match the torch policy, with the metadata a
robot-side controller needs, and which gente-evaluate --exported runs."""

import numpy as np
import onnx
import onnxruntime
import pytest
import torch

from legged_gente.envs.base.legged_robot_config import LeggedRobotCfgPPO
from legged_gente.envs.task_registry import task_registry
from legged_gente.evaluation.evaluator import load_policy_and_file
from legged_gente.utils.args import build_parser, parse_args
from legged_gente.utils.export import OnnxPolicy, deployment_metadata, export_onnx, read_metadata


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    args = parse_args(build_parser("test"), ["--task", "gente_biped_flat", "--device", "cpu", "--num_envs", "3"])
    env, _ = task_registry.make_env(args.task, args)
    _, train_cfg = task_registry.get_cfgs(args.task)
    train_cfg.actor.hidden_dims = train_cfg.critic.hidden_dims = [16, 16]
    runner, made_cfg, _ = task_registry.make_alg_runner(env, args.task, train_cfg=train_cfg, log_root=None)
    assert made_cfg.algorithm.use_mixed_precision is False  # what ran on the CPU: what the run's config.json says
    policy = runner.alg.get_policy()
    with torch.no_grad():  # a non-trivial normaliser and weights, as after training
        policy.obs_normalizer._mean.uniform_(-0.5, 0.5)
        policy.obs_normalizer._std.uniform_(0.5, 2.0)
        for p in policy.mlp.parameters():
            p.normal_(0.0, 0.3)
    folder = tmp_path_factory.mktemp("exported")
    path = export_onnx(policy, folder / "policy.onnx", deployment_metadata(env, "run/model_7.pt", args.task))
    return env, runner, path


def test_one_self_contained_file(exported):
    _, _, path = exported
    assert [p.name for p in path.parent.iterdir()] == ["policy.onnx"]  # no policy.onnx.data beside it
    model = onnx.load(str(path))  # loads with its weights from this file alone
    assert not any(t.data_location == onnx.TensorProto.EXTERNAL for t in model.graph.initializer)


def test_onnx_runtime_matches_the_torch_policy(exported):
    env, runner, path = exported
    obs = env.get_observations()
    obs["policy"] = obs["policy"] + torch.randn_like(obs["policy"])  # away from the normaliser's mean
    with torch.inference_mode():
        expected = runner.get_inference_policy()(obs).numpy()
    session = onnxruntime.InferenceSession(str(path))
    got = session.run(None, {"obs": obs["policy"].numpy()})[0]  # any batch size
    np.testing.assert_allclose(got, expected, rtol=1e-4, atol=1e-5)
    assert np.abs(expected).max() > 0.1  # a policy that outputs something
    np.testing.assert_allclose(OnnxPolicy(path)(obs).numpy(), expected, rtol=1e-4, atol=1e-5)


def test_metadata_a_deployment_needs(exported):
    env, _, path = exported
    meta = read_metadata(path)
    # biped config (gente_biped_config.py): sim.dt 0.005 s, decimation 4 -> control period 0.02 s; action scale
    # 0.25; hip and knee PD gains by joint name; obs scales of legged_gym (lin_vel 2.0, ang_vel 0.25, dof_vel 0.05)
    assert meta["control_dt"] == pytest.approx(0.005 * 4)
    assert meta["action_scale"] == 0.25
    assert meta["task"] == "gente_biped_flat" and meta["checkpoint"] == "run/model_7.pt"
    joints = meta["action_names"]
    assert len(joints) == 10 and "left_knee" in joints
    assert meta["joint_stiffness"][joints.index("left_knee")] == 200.0
    assert meta["joint_stiffness"][joints.index("left_hip_yaw")] == 150.0
    assert meta["joint_damping"][joints.index("left_knee")] == 5.0
    assert meta["default_joint_pos"][joints.index("left_knee")] == pytest.approx(0.55)
    names, scales = meta["observation_names"], meta["observation_scales"]
    assert len(names) == len(scales) == env.get_observations()["policy"].shape[1]
    # names and scales come from the env's observation term table (cfg.observations.policy)
    assert scales[names.index("base_lin_vel[0]")] == 2.0 and scales[names.index("base_ang_vel[2]")] == 0.25
    assert scales[names.index("dof_vel[9]")] == pytest.approx(0.05)
    first = names.index("actions[0]")
    assert names[first:first + 10] == [f"actions[{i}]" for i in range(10)]
    assert all(n.startswith("gait_clock") for n in names[first + 10:])  # the biped's clock; no height scan on a plane
    assert meta["observation_clips"] == [None] * len(names)  # no term of the flat biped is clamped
    assert meta["clip_actions"] == 100.0 and meta["clip_observations"] == 100.0
    assert "observation_groups" not in meta  # the actor takes the policy group alone (runner.obs_groups' default)


def test_the_observation_layout_names_each_terms_clip():
    """A height scan clamped to [-1, 1] m before its scale 5 (legged_gym's), beside an unclamped term: each entry
    carries its term's clip."""
    from types import SimpleNamespace

    from legged_gente.utils.export import observation_layout

    env = SimpleNamespace(
        observation_names={"policy": ["dof_vel[0]", "dof_vel[1]", "height_scan[0]", "height_scan[1]"]},
        _obs_groups={"policy": [("dof_vel", None, torch.full((2,), 0.05), None, None),
                                ("height_scan", None, torch.full((2,), 5.0), (-1.0, 1.0), None)]})
    assert observation_layout(env) == [("dof_vel[0]", pytest.approx(0.05), None),
                                       ("dof_vel[1]", pytest.approx(0.05), None),
                                       ("height_scan[0]", 5.0, [-1.0, 1.0]), ("height_scan[1]", 5.0, [-1.0, 1.0])]


def test_evaluate_exported_runs_the_onnx_file_and_checks_its_size(exported, tmp_path):
    env, runner, path = exported

    class Evaluation:  # what load_policy_and_file reads of an evaluation
        pass

    evaluation = Evaluation()
    evaluation.env = env
    policy, source = load_policy_and_file(evaluation, exported=str(path))
    assert source == path.resolve()
    assert policy(env.get_observations()).shape == (env.num_envs, env.num_actions)
    with pytest.raises(ValueError, match="takes 44 observations; this task's policy observation has 50"):
        OnnxPolicy(path, {"policy": torch.zeros(1, 50)})
    with pytest.raises(FileNotFoundError, match="no such file"):
        OnnxPolicy(tmp_path / "policy.onnx")


def test_a_cpu_runner_leaves_the_update_uncompiled_and_fp32(exported):
    """runner.compile_update and algorithm.use_mixed_precision (both on by default) apply on CUDA only; the run's
    config records the fp32 update that ran."""
    _, runner, _ = exported
    assert runner.cfg["compile_update"] is True and runner.alg.device_side_update
    assert runner.alg._compiled_mlps == []
    assert LeggedRobotCfgPPO.algorithm.use_mixed_precision is True
    assert runner.alg.use_mixed_precision is False and runner.cfg["algorithm"]["use_mixed_precision"] is False
