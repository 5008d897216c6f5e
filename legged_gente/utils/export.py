"""A trained actor as one self-contained ONNX file that carries what a deployment needs in its metadata.

``policy.onnx`` maps ``obs`` (batch, num_obs: the env's ``policy`` observation group, already scaled as in
training) to ``actions`` (batch, num_actions); the joint targets are ``default_joint_pos + action_scale *
clip(actions, -clip_actions, clip_actions)``, tracked by a PD controller with ``joint_stiffness`` /
``joint_damping`` every ``control_dt`` seconds. The weights are inside the file (no ``policy.onnx.data`` beside
it). The metadata (ONNX ``metadata_props``: string values, JSON but the plain ``TEXT_KEYS``) names every
observation entry and its scale, the action joints, the action scale, default joint positions, PD gains, the
control period and the checkpoint it came from.

An actor trained on more groups (rsl-rl's ``runner.obs_groups``, e.g. actor = ["policy", "critic"]) takes them
concatenated in that order: its metadata adds ``observation_groups`` (the list), and the entries of a group other
than ``policy`` are named ``<group>/<name>`` (the critic group repeats the policy's terms, noise-free).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import torch

ONNX_OPSET = 18
TEXT_KEYS = ("task", "checkpoint")
"""The metadata values written as plain strings; every other value is JSON."""


def observation_layout(env, group: str = "policy") -> list[tuple[str, float, list[float] | None]]:
    """(name, scale, clip) of each entry of the env's observation ``group`` ("policy" or "critic"), from the env's
    observation term tables (``cfg.observations``, resolved by the env): the observation is ``scale * term``, the
    term clamped to ``clip`` ([low, high]; None: not clamped) first. The critic group is the policy's terms, then
    its own (``LeggedRobot._compute_observations``)."""
    entries = env._obs_groups["policy"] + (env._obs_groups["critic"] if group == "critic" else [])
    names = env.observation_names[group]
    scales = torch.cat([entry[2] for entry in entries]).tolist()
    clips = [None if clip is None else [float(clip[0]), float(clip[1])]
             for _, _, scale, clip, _ in entries for _ in range(len(scale))]
    return list(zip(names, scales, clips))


def deployment_metadata(env, checkpoint: str | None = None, task: str | None = None,
                        groups: list[str] | tuple[str, ...] = ("policy",)) -> dict[str, str]:
    """What a robot-side controller needs besides the network (all values strings; lists as JSON). ``groups``: the
    observation groups the actor takes, in order (its ``obs_groups``)."""
    obs = env.get_observations()
    layout = []
    for group in groups:
        width = int(obs[group].shape[1])
        part = observation_layout(env, group) if group in ("policy", "critic") else []
        if len(part) != width:  # a subclass changed the observation: scales unknown (null; JSON has no NaN)
            part = [(f"obs_{i}", None, None) for i in range(width)]
        prefix = "" if group == "policy" else f"{group}/"
        layout += [(prefix + name, scale, clip) for name, scale, clip in part]
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
    if list(groups) != ["policy"]:  # absent: the policy group alone
        meta["observation_groups"] = list(groups)
    return {key: value if key in TEXT_KEYS else json.dumps(value) for key, value in meta.items()}


def export_onnx(policy, path: Path, metadata: dict[str, str]) -> Path:
    """``policy`` (rsl-rl's MLPModel) -> one ONNX file with a dynamic batch and ``metadata`` in its props."""
    import onnx

    model = policy.as_onnx(verbose=False).to("cpu").eval()
    width, named = model.get_dummy_inputs()[0].shape[1], len(json.loads(metadata["observation_names"]))
    if width != named:
        raise ValueError(f"the metadata names {named} observation columns but the actor takes {width} (its obs_groups "
                         f"{policy.obs_groups}); give deployment_metadata the actor's groups")
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
    """The metadata of an exported policy, JSON values decoded; the plain strings (``TEXT_KEYS``: a task named
    "123" stays "123") and a value that is not JSON (another exporter's) as written."""
    import onnx

    props = onnx.load(str(path), load_external_data=False).metadata_props
    out = {}
    for prop in props:
        try:
            out[prop.key] = prop.value if prop.key in TEXT_KEYS else json.loads(prop.value)
        except ValueError:
            out[prop.key] = prop.value
    return out


class OnnxPolicy:
    """An exported ``policy.onnx`` run with onnxruntime on the CPU: a TensorDict's groups the file takes (its
    ``observation_groups``, else ``policy``), concatenated -> actions. ``observations``: the env's, to check the
    file's input width against."""

    def __init__(self, path: str | Path, observations=None, num_actions: int | None = None):
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
        groups = self.session.get_modelmeta().custom_metadata_map.get("observation_groups")
        self.groups = json.loads(groups) if groups else ["policy"]
        if observations is not None:
            missing = [group for group in self.groups if group not in observations.keys()]
            if missing:
                raise ValueError(f"--exported {path} takes the observation groups {self.groups}; this task's env has "
                                 f"no {missing} (a policy of another task?)")
            num_obs = sum(int(observations[group].shape[1]) for group in self.groups)
            if isinstance(shape[1], int) and shape[1] != num_obs:
                raise ValueError(f"--exported {path} takes {shape[1]} observations; this task's "
                                 f"{' + '.join(self.groups)} observation has {num_obs} (a policy of another task?)")
        if num_actions is not None and isinstance(out[1], int) and out[1] != num_actions:
            raise ValueError(f"--exported {path} gives {out[1]} actions; this task has {num_actions}")
        self.input = inputs[0].name

    def __call__(self, obs) -> torch.Tensor:
        x = torch.cat([obs[group] for group in self.groups], dim=-1)
        actions = self.session.run(None, {self.input: x.detach().to("cpu", torch.float32).numpy()})[0]
        return torch.as_tensor(actions, device=x.device)
