"""read_metadata gives back what deployment_metadata wrote: the JSON-encoded values decoded, the plain strings
(task, checkpoint) as the strings they are, whatever they look like."""

import onnx
from onnx import TensorProto, helper

from legged_gente.utils.export import read_metadata


def test_plain_string_values_stay_strings_even_when_they_look_like_json(tmp_path):
    graph = helper.make_graph([helper.make_node("Identity", ["obs"], ["actions"])], "g",
                              [helper.make_tensor_value_info("obs", TensorProto.FLOAT, ["batch", 2])],
                              [helper.make_tensor_value_info("actions", TensorProto.FLOAT, ["batch", 2])])
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 18)])
    # as deployment_metadata writes them: a task and checkpoint named like numbers, JSON, or a JSON keyword
    props = {"task": "123", "checkpoint": "null", "action_scale": "0.25", "decimation": "4",
             "observation_names": '["base_lin_vel[0]", "obs_1"]', "observation_scales": "[2.0, null]"}
    for key, value in props.items():
        model.metadata_props.add(key=key, value=value)
    path = tmp_path / "policy.onnx"
    onnx.save_model(model, str(path))
    meta = read_metadata(path)
    assert meta["task"] == "123" and meta["checkpoint"] == "null"
    assert meta["action_scale"] == 0.25 and meta["decimation"] == 4
    assert meta["observation_names"] == ["base_lin_vel[0]", "obs_1"] and meta["observation_scales"] == [2.0, None]
