"""gente-train and gente-play as a user runs them on a CPU (tiny settings, runs in a temporary $GENTE_LOG_ROOT),
with the expected values worked out in the test."""

import json

import numpy as np
import onnxruntime
import pytest
import torch

from legged_gente.scripts import play as play_script
from legged_gente.scripts import train as train_script
from legged_gente.utils.export import read_metadata

TASK = "gente_biped_flat"
TINY = ["--task", TASK, "--device", "cpu", "--num_envs", "2", "--headless", "--seed", "5",
        "--set", "runner.num_steps_per_env=4", "--set", "algorithm.num_mini_batches=2"]
NETS = ["--set", "actor.hidden_dims=[16,16]", "--set", "critic.hidden_dims=[16,16]"]


@pytest.fixture(scope="module")
def log_root(tmp_path_factory):
    """One run of one iteration: a checkpoint of iteration 0 (the last finished one)."""
    root = tmp_path_factory.mktemp("logs")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("GENTE_LOG_ROOT", str(root))
        train_script.main([*TINY, *NETS, "--max_iterations", "1"])
    return root


def checkpoints(root):
    return sorted(path.name for path in (root / TASK).glob("*/model_*.pt"))


@pytest.mark.parametrize("zero", [["--max_iterations", "0"], ["--set", "runner.max_iterations=0"]])
def test_a_resume_of_no_iterations_saves_no_checkpoint_of_an_iteration_that_never_ran(log_root, monkeypatch,
                                                                                       capsys, zero):
    """A checkpoint is named after the last finished iteration; resuming after iteration 0 for 0 iterations
    finishes none, so no model_1.pt may appear (it would claim iteration 1, and the next --resume would skip
    it). Zero iterations is a one-line error."""
    assert checkpoints(log_root) == ["model_0.pt"]
    monkeypatch.setenv("GENTE_LOG_ROOT", str(log_root))
    with pytest.raises(SystemExit) as exit_info:
        train_script.main([*TINY, "--resume", *zero])
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and "Traceback" not in err
    assert "max_iterations" in err.strip().splitlines()[-1]
    assert checkpoints(log_root) == ["model_0.pt"]


def test_the_exported_policy_is_the_checkpoints_normaliser_and_network(log_root, monkeypatch):
    """policy.onnx of a played run: actions = MLP((obs - mean) / (std + eps)) with the checkpoint's own
    normaliser (rsl-rl's EmpiricalNormalization, eps = 0.01) and ELU layers, computed here from the state dict;
    its metadata: the biped's config (action scale 0.25, sim.dt 0.005 s x decimation 4 = 0.02 s)."""
    monkeypatch.setenv("GENTE_LOG_ROOT", str(log_root))
    args = play_script.parse_args(play_script.build_play_parser(),
                                  ["--task", TASK, "--device", "cpu", "--num_envs", "2", "--headless", "--steps", "1"])
    out = play_script.play(args)
    state = torch.load(out["checkpoint"], weights_only=True)["actor_state_dict"]
    mean, std = state["obs_normalizer._mean"], state["obs_normalizer._std"]
    assert mean.abs().max() > 1e-3  # one iteration moved the normaliser away from (0, 1)
    obs = torch.as_tensor(np.random.default_rng(0).normal(0.0, 2.0, (5, mean.shape[-1])), dtype=torch.float32)
    hidden = (obs - mean) / (std + 0.01)
    layers = sorted({int(key.split(".")[1]) for key in state if key.startswith("mlp.")})
    for i in layers:
        hidden = hidden @ state[f"mlp.{i}.weight"].T + state[f"mlp.{i}.bias"]
        if i != layers[-1]:
            hidden = torch.nn.functional.elu(hidden)
    got = onnxruntime.InferenceSession(str(out["onnx"])).run(None, {"obs": obs.numpy()})[0]
    np.testing.assert_allclose(got, hidden.numpy(), atol=1e-5)

    meta = read_metadata(out["onnx"])
    assert meta["action_scale"] == 0.25 and meta["control_dt"] == pytest.approx(0.005 * 4)
    assert meta["checkpoint"] == str(out["checkpoint"]) and meta["task"] == TASK
    # gente_biped_config: default pose by joint-name pattern, joints in the MJCF's order, left leg first
    pose = {"hip_yaw": 0.0, "hip_roll": 0.0, "hip_pitch": -0.25, "knee": 0.55, "ankle": -0.3}
    assert meta["action_names"] == [f"{side}_{joint}" for side in ("left", "right") for joint in pose]
    np.testing.assert_allclose(meta["default_joint_pos"], list(pose.values()) * 2, atol=1e-6)
    # legged_gym's scales: lin_vel 2.0, ang_vel 0.25, commands (2, 2, 0.25), dof_vel 0.05, the rest 1
    scales = dict(zip(meta["observation_names"], meta["observation_scales"]))
    assert scales["base_lin_vel[0]"] == 2.0 and scales["base_ang_vel[2]"] == 0.25
    assert [scales[f"commands[{i}]"] for i in range(3)] == [2.0, 2.0, 0.25]
    assert scales["dof_vel[9]"] == pytest.approx(0.05) and scales["actions[0]"] == 1.0
    assert json.loads(json.dumps(meta["observation_clips"])) == [None] * mean.shape[-1]


def test_a_run_never_writes_into_the_folder_of_another_run(tmp_path, monkeypatch):
    """Run folders are named to the second: two runs started in the same second (a job array of seeds, or a
    --resume right after its run) got the same folder, the second overwriting the first's config.json and
    checkpoints. The second now takes the name with _1, and the first run's files stay as they were."""
    from datetime import datetime

    import legged_gente.envs.task_registry as registry

    class FixedClock(datetime):
        @classmethod
        def now(cls, tz=None):
            return cls(2030, 1, 2, 3, 4, 5)

    monkeypatch.setattr(registry, "datetime", FixedClock)
    monkeypatch.setenv("GENTE_LOG_ROOT", str(tmp_path))
    first = tmp_path / TASK / "2030-01-02_03-04-05"
    first.mkdir(parents=True)
    (first / "config.json").write_text('{"seed": 1}')
    train_script.main([*TINY, *NETS, "--max_iterations", "1"])
    assert [p.name for p in first.iterdir()] == ["config.json"] and (first / "config.json").read_text() == '{"seed": 1}'
    second = tmp_path / TASK / "2030-01-02_03-04-05_1"
    assert sorted(p.name for p in second.glob("model_*.pt")) == ["model_0.pt"] and (second / "config.json").exists()


def test_samples_no_mini_batch_takes_are_named(capsys):
    """A rollout of 3 robots x 5 steps = 15 samples in 2 mini-batches of 15 // 2 = 7: the update permutes the first
    14 only (as rsl-rl's generator does), so 1 sample of every rollout is never learned from. Said once, up front;
    a batch that divides evenly says nothing."""
    from legged_gente.envs.task_registry import task_registry, validate_cfgs

    env_cfg, train_cfg = task_registry.get_cfgs(TASK)
    env_cfg.env.num_envs, train_cfg.runner.num_steps_per_env, train_cfg.algorithm.num_mini_batches = 3, 5, 2
    with pytest.warns(UserWarning, match=r"1 of the 15 samples .*never used.*num_mini_batches=2"):
        validate_cfgs(env_cfg, train_cfg)
    env_cfg.env.num_envs = 4  # 20 samples, 2 mini-batches of 10
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        validate_cfgs(env_cfg, train_cfg)
