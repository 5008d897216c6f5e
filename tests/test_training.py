"""PPO through rsl-rl's OnPolicyRunner on the CPU: train, save, resume; play exports a self-contained ONNX."""

import numpy as np
import onnxruntime
import pytest
import torch

from legged_gente.envs.task_registry import task_registry
from legged_gente.scripts import play as play_script
from legged_gente.utils.args import build_parser, parse_args
from legged_gente.utils.checkpoints import find_checkpoint


def tiny_args(tmp_path, *extra):
    args = parse_args(build_parser("test"), ["--task", "gente_biped_flat", "--num_envs", "4", "--device", "cpu",
                                             "--headless", *extra])
    args.log_root = str(tmp_path)
    return args


def make_runner(tmp_path, args):
    env, _ = task_registry.make_env(args.task, args)
    _, train_cfg = task_registry.get_cfgs(args.task)
    from legged_gente.envs.task_registry import apply_args

    apply_args(args, None, train_cfg)
    train_cfg.runner.num_steps_per_env = 4
    train_cfg.runner.save_interval = 1
    train_cfg.algorithm.num_mini_batches = 2
    train_cfg.algorithm.num_learning_epochs = 1
    train_cfg.actor.hidden_dims = [32, 32]
    train_cfg.critic.hidden_dims = [32, 32]
    return task_registry.make_alg_runner(env, args.task, args, train_cfg=train_cfg, log_root=tmp_path)


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    tmp_path = tmp_path_factory.mktemp("logs")
    runner, train_cfg, log_dir = make_runner(tmp_path, tiny_args(tmp_path))
    runner.learn(2)
    return tmp_path, runner, train_cfg


def test_train_saves_checkpoints(trained):
    tmp_path, runner, train_cfg = trained
    path = find_checkpoint(tmp_path / train_cfg.runner.experiment_name)
    assert path.name == "model_1.pt"
    assert runner.current_learning_iteration == 1


def test_resume_continues_from_checkpoint(trained):
    tmp_path, runner, _ = trained
    resumed, _, _ = make_runner(tmp_path, tiny_args(tmp_path, "--resume"))
    assert resumed.current_learning_iteration == 2
    for a, b in zip(runner.alg.get_policy().state_dict().values(), resumed.alg.get_policy().state_dict().values()):
        assert torch.equal(a, b)
    # the rest of the learner too: the critic, Adam's moments and step counts, the adapted learning rate
    for a, b in zip(runner.alg.critic.state_dict().values(), resumed.alg.critic.state_dict().values()):
        assert torch.equal(a, b)
    saved, loaded = runner.alg.optimizer.state_dict()["state"], resumed.alg.optimizer.state_dict()["state"]
    assert saved.keys() == loaded.keys() and saved
    for key in saved:
        for name in ("exp_avg", "exp_avg_sq", "step"):
            assert torch.equal(saved[key][name], loaded[key][name]), (key, name)
    assert float(resumed.alg.learning_rate) == float(runner.alg.learning_rate)
    collection = 4 * 4  # num_steps_per_env x num_envs per iteration
    assert resumed.logger.tot_timesteps == 2 * collection  # "Total steps" goes on from the two trained iterations
    resumed.learn(1)
    assert resumed.current_learning_iteration == 2
    assert resumed.logger.tot_timesteps == 3 * collection
    assert (find_checkpoint(tmp_path / "gente_biped_flat")).name == "model_2.pt"


def test_play_exports_onnx_with_same_actions(trained, monkeypatch, capsys):
    tmp_path = trained[0]
    # play builds the task's default train cfg: give it the tiny network the checkpoint holds
    original = task_registry.get_cfgs

    def tiny_cfgs(name):
        env_cfg, cfg = original(name)
        cfg.actor.hidden_dims = [32, 32]
        cfg.critic.hidden_dims = [32, 32]
        return env_cfg, cfg

    monkeypatch.setattr(task_registry, "get_cfgs", tiny_cfgs)
    args = tiny_args(tmp_path)
    args.steps, args.video = 10, False
    out = play_script.play(args)
    assert "curriculum" not in capsys.readouterr().out  # play has none: nothing to say about the checkpoint's
    assert out["onnx"].is_file() and out["plot"].is_file()
    # per run: beside the checkpoint it came from, one file (no policy.onnx.data)
    assert out["onnx"].parent == out["checkpoint"].parent / "exported"
    assert not list(out["onnx"].parent.glob("*.data"))
    assert out["log"]["cmd"].shape == (10, 3)

    policy, obs = out["policy"], out["env"].get_observations()
    with torch.inference_mode():
        expected = policy(obs).numpy()
    session = onnxruntime.InferenceSession(str(out["onnx"]))
    # one robot's observation (batch 1, as on a real robot) and the whole batch at once
    got = np.concatenate([session.run(None, {"obs": row[None]})[0] for row in obs["policy"].numpy()])
    np.testing.assert_allclose(got, expected, rtol=1e-4, atol=1e-5)
    np.testing.assert_allclose(session.run(None, {"obs": obs["policy"].numpy()})[0], expected, rtol=1e-4, atol=1e-5)
