"""An actor that takes more observation groups than ``policy`` (rsl-rl's ``runner.obs_groups``, e.g. actor =
["policy", "critic"]): the export's metadata describes every column the network takes, and gente-evaluate
--exported feeds it the same groups."""

from types import SimpleNamespace

import numpy as np
import pytest
import torch

from legged_gente.envs.task_registry import task_registry
from legged_gente.evaluation.evaluator import load_policy_and_file
from legged_gente.scripts.play import export_policy
from legged_gente.utils.args import build_parser, parse_args
from legged_gente.utils.export import OnnxPolicy, read_metadata


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    args = parse_args(build_parser("test"), ["--task", "gente_biped_flat", "--device", "cpu", "--num_envs", "2"])
    env, _ = task_registry.make_env(args.task, args)
    _, train_cfg = task_registry.get_cfgs(args.task)
    train_cfg.actor.hidden_dims = train_cfg.critic.hidden_dims = [16]
    train_cfg.runner.obs_groups = {"actor": ["policy", "critic"], "critic": ["critic"]}
    runner, _, _ = task_registry.make_alg_runner(env, args.task, train_cfg=train_cfg, log_root=None)
    with torch.no_grad():
        for p in runner.alg.get_policy().mlp.parameters():
            p.normal_(0.0, 0.3)
    path = export_policy(runner, env, tmp_path_factory.mktemp("exported"), "run/model_1.pt", args.task)
    return env, runner, path


def test_the_metadata_names_every_column_of_the_actors_groups(exported):
    env, _, path = exported
    obs = env.get_observations()
    meta = read_metadata(path)
    width = obs["policy"].shape[1] + obs["critic"].shape[1]
    assert OnnxPolicy(path).session.get_inputs()[0].shape[1] == width
    assert meta["observation_groups"] == ["policy", "critic"]
    names, scales, clips = meta["observation_names"], meta["observation_scales"], meta["observation_clips"]
    assert len(names) == len(scales) == len(clips) == width
    assert len(set(names)) == width  # the critic's copy of the policy terms is told apart from the policy's
    p = obs["policy"].shape[1]
    assert names[:p] == env.observation_names["policy"]
    assert names[p:] == [f"critic/{name}" for name in env.observation_names["critic"]]
    # the critic group: the policy's terms (noise-free), then its own; feet_contact_forces is scaled 0.01 (1/N)
    assert scales[names.index("critic/base_lin_vel[0]")] == 2.0
    assert scales[names.index("critic/feet_contact_forces[0]")] == pytest.approx(0.01)


def test_evaluate_exported_feeds_the_groups_the_file_takes(exported):
    env, runner, path = exported

    policy, _ = load_policy_and_file(SimpleNamespace(env=env), exported=str(path))  # an evaluation's env alone
    obs = env.get_observations()
    with torch.inference_mode():
        expected = runner.get_inference_policy()(obs).numpy()
    np.testing.assert_allclose(policy(obs).numpy(), expected, rtol=1e-4, atol=1e-5)


def test_metadata_that_misses_a_group_the_actor_takes_is_refused(exported, tmp_path):
    """The metadata and the network are made apart: a width they disagree on is an error, not a file that lies."""
    from legged_gente.utils.export import deployment_metadata, export_onnx

    env, runner, _ = exported
    with pytest.raises(ValueError, match=r"names 44 observation columns but the actor takes 96 .*'critic'"):
        export_onnx(runner.alg.get_policy(), tmp_path / "policy.onnx", deployment_metadata(env))
    assert not (tmp_path / "policy.onnx").exists()


def test_a_file_taking_a_group_the_env_does_not_give_is_a_one_line_error(tmp_path):
    import onnx
    from onnx import TensorProto, helper

    graph = helper.make_graph([helper.make_node("Identity", ["obs"], ["actions"])], "g",
                              [helper.make_tensor_value_info("obs", TensorProto.FLOAT, ["batch", 4])],
                              [helper.make_tensor_value_info("actions", TensorProto.FLOAT, ["batch", 4])])
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 18)])
    model.metadata_props.add(key="observation_groups", value='["policy", "privileged"]')
    onnx.save_model(model, str(tmp_path / "policy.onnx"))
    with pytest.raises(ValueError, match=r"takes the observation groups \['policy', 'privileged'\]; this task's env "
                                         r"has no \['privileged'\]"):
        OnnxPolicy(tmp_path / "policy.onnx", {"policy": torch.zeros(1, 2), "critic": torch.zeros(1, 3)})
