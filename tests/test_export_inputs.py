"""An exported policy's metadata is strict JSON a robot-side parser reads, and an ONNX file that is not a
gente-play policy (another input layout) is a one-line error when it is opened, not a traceback mid-evaluation."""

import json

import onnx
import pytest
import torch
from onnx import TensorProto, helper

from legged_gente.envs.task_registry import task_registry
from legged_gente.utils.args import build_parser, parse_args
from legged_gente.utils.export import OnnxPolicy, deployment_metadata


def test_metadata_of_an_observation_the_table_does_not_describe_is_strict_json(monkeypatch):
    """A subclass that changed the policy observation: its scales are unknown, written as null (JSON has no NaN,
    which strict parsers such as a robot's C++ one refuse)."""
    args = parse_args(build_parser("test"), ["--task", "gente_biped_flat", "--device", "cpu", "--num_envs", "1"])
    env, _ = task_registry.make_env(args.task, args)
    monkeypatch.setitem(env.observation_names, "policy", env.observation_names["policy"][:-1])
    meta = deployment_metadata(env)
    scales = json.loads(meta["observation_scales"], parse_constant=lambda name: pytest.fail(f"{name} in JSON"))
    assert scales == [None] * env.get_observations()["policy"].shape[1]
    assert json.loads(meta["observation_names"])[0] == "obs_0"


def onnx_file(path, inputs: dict[str, list]) -> str:
    """An ONNX model summing ``inputs`` (name -> shape) into one output ``actions``."""
    names = list(inputs)
    nodes = [helper.make_node("Identity", [names[0]], ["actions"])] if len(names) == 1 else \
        [helper.make_node("Sum", names, ["actions"])]
    graph = helper.make_graph(nodes, "g", [helper.make_tensor_value_info(n, TensorProto.FLOAT, s)
                                           for n, s in inputs.items()],
                              [helper.make_tensor_value_info("actions", TensorProto.FLOAT, inputs[names[0]])])
    onnx.save_model(helper.make_model(graph, opset_imports=[helper.make_opsetid("", 18)]), str(path))
    return str(path)


@pytest.mark.parametrize("inputs", [{"obs": ["batch", 44], "h_in": ["batch", 44]}, {"obs": [44]}])
def test_an_onnx_file_with_another_input_layout_is_a_one_line_error(tmp_path, inputs):
    """A recurrent policy (obs and a hidden state in) or a model without a batch axis: not what OnnxPolicy runs."""
    path = onnx_file(tmp_path / "policy.onnx", inputs)
    with pytest.raises(ValueError) as error:
        OnnxPolicy(path, {"policy": torch.zeros(1, 44)}, num_actions=44)
    message = str(error.value)
    assert "\n" not in message and "gente-play" in message and "obs" in message, message
