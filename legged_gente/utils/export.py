"""A trained actor as one self-contained ONNX file that carries what a deployment needs in its metadata.

``policy.onnx`` maps ``obs`` (batch, num_obs: the env's ``policy`` observation group, already scaled as in
training) to ``actions`` (batch, num_actions); the joint targets are ``default_joint_pos + action_scale *
actions``, tracked by a PD controller with ``joint_stiffness`` / ``joint_damping`` every ``control_dt`` seconds.
The weights are inside the file (no ``policy.onnx.data`` beside it). The metadata (ONNX ``metadata_props``,
string values, lists as JSON) names every observation entry and its scale, the action joints, the action scale,
default joint positions, PD gains, the control period and the checkpoint it came from.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import torch

ONNX_OPSET = 18


def policy_observation_layout(env) -> list[tuple[str, float, list[float] | None]]:
    """(name, scale, clip) of each entry of the env's ``policy`` observation, from the env's observation term table
    (``cfg.observations.policy``, resolved by the env): the observation is ``scale * term``, the term clamped to
    ``clip`` ([low, high]; None: not clamped) first."""
    names = env.observation_names["policy"]
    scales = torch.cat([entry[2] for entry in env._obs_groups["policy"]]).tolist()
    clips = [None if clip is None else [float(clip[0]), float(clip[1])]
             for _, _, scale, clip, _ in env._obs_groups["policy"] for _ in range(len(scale))]
    return list(zip(names, scales, clips))


def deployment_metadata(env, checkpoint: str | None = None, task: str | None = None) -> dict[str, str]:
    """What a robot-side controller needs besides the network (all values strings; lists as JSON)."""
    layout = policy_observation_layout(env)
    num_obs = int(env.get_observations()["policy"].shape[1])
    if len(layout) != num_obs:  # a subclass changed the observation: scales unknown (null; JSON has no NaN)
        layout = [(f"obs_{i}", None, None) for i in range(num_obs)]
    mjm = env.mjm
    stiffness = mjm.actuator_gainprm[:, 0]  # position actuators: force = kp (ctrl - q) - kd qdot
    damping = -mjm.actuator_biasprm[:, 2]
    meta = {
        "task": task or "",
        "checkpoint": str(checkpoint or ""),
        "observation_names": [name for name, _, _ in layout],
        "observation_scales": [None if scale is None else float(scale) for _, scale, _ in layout],
        "observation_clips": [clip for _, _, clip in layout],  # [low, high] on the term before its scale, or null
        "clip_observations": float(env.cfg.normalization.clip_observations),
        "clip_actions": float(env.cfg.normalization.clip_actions),  # on the network's output, before action_scale
        "action_names": list(env.layout.joint_names),
        "action_scale": float(env.cfg.control.action_scale),
        "default_joint_pos": [float(x) for x in env.default_dof_pos[0].tolist()],
        "joint_stiffness": [float(x) for x in np.asarray(stiffness)],  # N*m/rad
        "joint_damping": [float(x) for x in np.asarray(damping)],  # N*m*s/rad
        "control_dt": float(env.dt),  # s, one policy step
        "sim_dt": float(env.cfg.sim.dt),
        "decimation": int(env.cfg.control.decimation),
    }
    return {key: value if isinstance(value, str) else json.dumps(value) for key, value in meta.items()}


def export_onnx(policy, path: Path, metadata: dict[str, str]) -> Path:
    """``policy`` (rsl-rl's MLPModel) -> one ONNX file with a dynamic batch and ``metadata`` in its props."""
    import onnx

    model = policy.as_onnx(verbose=False).to("cpu").eval()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    # torch's TorchScript-free exporter (torch.export); weights inside the file, any batch size
    program = torch.onnx.export(model, model.get_dummy_inputs(), dynamo=True, opset_version=ONNX_OPSET,
                                input_names=["obs"], output_names=["actions"],
                                dynamic_shapes=({0: torch.export.Dim("batch")},), verbose=False)
    proto = program.model_proto
    del proto.metadata_props[:]
    for key, value in metadata.items():
        proto.metadata_props.add(key=key, value=value)
    onnx.checker.check_model(proto)
    onnx.save_model(proto, str(path), save_as_external_data=False)
    return path


def read_metadata(path: str | Path) -> dict:
    """The metadata of an exported policy, JSON values decoded."""
    import onnx

    props = onnx.load(str(path), load_external_data=False).metadata_props
    out = {}
    for prop in props:
        try:
            out[prop.key] = json.loads(prop.value)
        except ValueError:
            out[prop.key] = prop.value
    return out


class OnnxPolicy:
    """An exported ``policy.onnx`` run with onnxruntime on the CPU: a TensorDict's ``policy`` group -> actions."""

    def __init__(self, path: str | Path, num_obs: int | None = None, num_actions: int | None = None):
        import onnxruntime

        path = Path(path)
        if not path.is_file():
            raise FileNotFoundError(f"--exported {path}: no such file; gente-play writes <run>/exported/policy.onnx")
        try:
            self.session = onnxruntime.InferenceSession(str(path), providers=["CPUExecutionProvider"])
        except Exception as error:  # onnxruntime raises its own exception types for a bad file
            raise ValueError(f"--exported {path}: not a readable ONNX policy ({str(error).splitlines()[0]})") from None
        inputs, outputs = self.session.get_inputs(), self.session.get_outputs()
        if len(inputs) != 1 or len(inputs[0].shape) != 2 or len(outputs[0].shape) != 2:
            raise ValueError(f"--exported {path} takes {[(i.name, i.shape) for i in inputs]}: not a policy exported by "
                             f"gente-play, which takes one input obs (batch, num_obs) and gives actions "
                             f"(batch, num_actions); export it with gente-play")
        shape, out = inputs[0].shape, outputs[0].shape
        if num_obs is not None and isinstance(shape[1], int) and shape[1] != num_obs:
            raise ValueError(f"--exported {path} takes {shape[1]} observations; this task's policy observation "
                             f"has {num_obs} (a policy of another task?)")
        if num_actions is not None and isinstance(out[1], int) and out[1] != num_actions:
            raise ValueError(f"--exported {path} gives {out[1]} actions; this task has {num_actions}")
        self.input = inputs[0].name

    def __call__(self, obs) -> torch.Tensor:
        x = obs["policy"]
        actions = self.session.run(None, {self.input: x.detach().to("cpu", torch.float32).numpy()})[0]
        return torch.as_tensor(actions, device=x.device)
