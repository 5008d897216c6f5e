"""--pretrained: gente-play and gente-evaluate load the policy shipped with the package for the task
(resources/policies/<task>/); a task without one gets a one-line error."""

import json

import numpy as np
import pytest
import torch

from legged_gente.envs.task_registry import task_registry
from legged_gente.scripts import evaluate as evaluate_script
from legged_gente.scripts import play as play_script
from legged_gente.utils.args import build_parser, parse_args
from legged_gente.utils.checkpoints import load_checkpoint, policies_root, pretrained_policy, ship_policy

SHIPPED = "gente_biped_flat"


def test_the_shipped_policy_is_small_cpu_loadable_and_says_how_it_was_made():
    path, config = pretrained_policy(SHIPPED)
    assert path.parent == policies_root() / SHIPPED
    assert path.stat().st_size < 100_000
    loaded = load_checkpoint(path, map_location="cpu")  # weights_only, on a machine without a GPU
    assert set(loaded) == {"actor_state_dict", "iter", "infos"} and loaded["infos"]["task"] == SHIPPED
    assert all(t.device.type == "cpu" for t in loaded["actor_state_dict"].values())
    assert config["task"] == SHIPPED and config["note"]
    assert len(config["code"]["git_commit"]) == 40  # the commit it was trained at
    assert config["train"]["actor"]["hidden_dims"]


def test_play_pretrained(tmp_path, capsys):
    args = parse_args(play_script.build_play_parser(), ["--task", SHIPPED, "--device", "cpu", "--num_envs", "2", "--headless",
                                             "--pretrained", "--steps", "3", "--log_root", str(tmp_path)])
    out = play_script.play(args)
    assert out["checkpoint"] == policies_root() / SHIPPED / "model.pt"
    assert out["onnx"] == tmp_path / SHIPPED / "pretrained" / "exported" / "policy.onnx"
    assert np.isfinite(out["log"]["vel"]).all()
    # the played actor is the shipped one
    shipped = load_checkpoint(out["checkpoint"])["actor_state_dict"]
    for key, value in out["policy"].state_dict().items():
        assert torch.equal(value, shipped[key])


def test_play_logs_each_step_s_command_not_the_last_one(tmp_path):
    """On the CPU, .cpu() of a slice is the live tensor: every logged command was the rollout's last. Episodes of
    0.2 s (10 steps) over 30 steps resample robot 0's command at each reset, so the logged commands differ."""
    args = parse_args(play_script.build_play_parser(), [
        "--task", SHIPPED, "--device", "cpu", "--num_envs", "1", "--headless", "--pretrained", "--steps", "30",
        "--log_root", str(tmp_path), "--set", "env.episode_length_s=0.2"])
    log = play_script.play(args)["log"]
    assert log["reset"].sum() >= 2 and len(np.unique(log["cmd"], axis=0)) >= 3


def test_evaluate_pretrained_records_the_file(tmp_path, capsys):
    args = evaluate_script.build_parser().parse_args([
        "--task", SHIPPED, "--pretrained", "--out", str(tmp_path), "--device", "cpu", "--limit", "1",
        "--robots_per_terrain", "1", "--episode_s", "0.2", "--settle_s", "0", "--no_progress"])
    report = evaluate_script.evaluate(args)
    out = capsys.readouterr().out
    assert "diverged 0; stopped at their tile's edge 0" in out
    assert "Actor Model" not in out and "Resolved observation sets" not in out  # rsl-rl's printout is for training
    assert report["meta"]["policy"] == "pretrained" and report["meta"]["tile_edge_margin"] == 0.5
    assert report["meta"]["policy_file"] == str(policies_root() / SHIPPED / "model.pt")
    assert json.loads((tmp_path / "report.json").read_text())["meta"]["policy_file"].endswith("model.pt")
    # what reproduces it: the scored policy's bytes, the command, the code and the platform
    import hashlib

    shipped = (policies_root() / SHIPPED / "model.pt").read_bytes()
    assert report["meta"]["policy_sha256"] == hashlib.sha256(shipped).hexdigest()
    assert report["meta"]["command"] and len(report["meta"]["code"]["source_sha256"]) == 64
    assert report["meta"]["platform"]["device"] == "cpu"


def test_a_task_without_a_shipped_policy(capsys):
    with pytest.raises(SystemExit) as exit_info:
        play_script.main(["--task", "gente_quadruped_flat", "--device", "cpu", "--num_envs", "1", "--pretrained"])
    assert exit_info.value.code == 2
    line = capsys.readouterr().err.strip().splitlines()[-1]
    assert "no policy is shipped for task 'gente_quadruped_flat'" in line and SHIPPED in line


def test_ship_policy_keeps_the_actor_and_the_run_config(tmp_path):
    args = parse_args(build_parser("t"), ["--task", SHIPPED, "--device", "cpu", "--num_envs", "1"])
    env, _ = task_registry.make_env(args.task, args)
    _, train_cfg = task_registry.get_cfgs(args.task)
    train_cfg.actor.hidden_dims = train_cfg.critic.hidden_dims = [8]
    runner, _, _ = task_registry.make_alg_runner(env, args.task, train_cfg=train_cfg, log_root=None)
    run = tmp_path / "run"
    run.mkdir()
    runner.save(str(run / "model_4.pt"))
    (run / "config.json").write_text(json.dumps({"task": SHIPPED, "code": {"git_commit": "0" * 40}}))
    folder = ship_policy(run / "model_4.pt", SHIPPED, "a test", destination=tmp_path / "shipped")
    loaded = load_checkpoint(folder / "model.pt")
    assert set(loaded) == {"actor_state_dict", "iter", "infos"} and loaded["iter"] == 0
    config = json.loads((folder / "config.json").read_text())
    assert config["note"] == "a test" and config["source_checkpoint"] == "run/model_4.pt"
    with pytest.raises(ValueError, match="is for gente_biped_flat, not gente_quadruped: ship it as --task gente_biped_flat, or pick a checkpoint"):
        ship_policy(run / "model_4.pt", "gente_quadruped", "wrong", destination=tmp_path / "other")
    (run / "config.json").unlink()
    with pytest.raises(FileNotFoundError, match="needs its run's config.json .*ship a model_<N>.pt from the run folder"):
        ship_policy(run / "model_4.pt", SHIPPED, "no config", destination=tmp_path / "other")


def test_evaluate_checkpoint_takes_a_shipped_policy_file(tmp_path):
    """A shipped model.pt holds only the actor: --checkpoint evaluates it like --pretrained (it needs no critic)."""
    args = evaluate_script.build_parser().parse_args([
        "--task", SHIPPED, "--checkpoint", str(policies_root() / SHIPPED / "model.pt"), "--out", str(tmp_path),
        "--device", "cpu", "--limit", "1", "--robots_per_terrain", "1", "--episode_s", "0.2", "--settle_s", "0",
        "--no_progress"])
    report = evaluate_script.evaluate(args)
    assert report["meta"]["policy_file"] == str(policies_root() / SHIPPED / "model.pt")


def _policy_only_run(tmp_path):
    """A run folder holding a shipped, actor-only model.pt as its model_7.pt."""
    run = tmp_path / SHIPPED / "shipped_run"
    run.mkdir(parents=True)
    (run / "model_7.pt").write_bytes((policies_root() / SHIPPED / "model.pt").read_bytes())
    return run


def test_play_takes_a_policy_only_checkpoint_from_a_run_folder(tmp_path, capsys):
    """gente-play loads a run's policy alone, as gente-evaluate --checkpoint does: an actor-only file plays."""
    run = _policy_only_run(tmp_path)
    play_script.main(["--task", SHIPPED, "--device", "cpu", "--num_envs", "1", "--headless", "--steps", "1",
                      "--log_root", str(tmp_path), "--set", "actor.hidden_dims=[32, 32]",
                      "--set", "critic.hidden_dims=[32, 32]"])
    assert f"Loaded model from {run / 'model_7.pt'}" in capsys.readouterr().out


def test_resuming_training_from_a_policy_only_checkpoint_is_a_one_line_error(tmp_path, capsys, monkeypatch):
    from legged_gente.scripts import train as train_script

    _policy_only_run(tmp_path)
    monkeypatch.setenv("GENTE_LOG_ROOT", str(tmp_path))
    with pytest.raises(SystemExit) as exit_info:
        train_script.main(["--task", SHIPPED, "--device", "cpu", "--num_envs", "1", "--headless", "--resume",
                           "--max_iterations", "1", "--set", "actor.hidden_dims=[32, 32]",
                           "--set", "critic.hidden_dims=[32, 32]"])
    assert exit_info.value.code == 2
    line = capsys.readouterr().err.strip().splitlines()[-1]
    assert "holds only the policy" in line and "model_7.pt" in line, line


def test_train_pretrained_starts_from_the_shipped_actor(tmp_path, capsys):
    """gente-train --pretrained fine-tunes the shipped policy: its actor (weights, observation normaliser, action
    noise) at iteration 0 of a new run, with a fresh critic that trains alone for the warm-up's iterations (here
    one); one iteration after the warm-up the actor has moved from it."""
    from legged_gente.scripts import train as train_script

    args = parse_args(train_script.build_train_parser(), [
        "--task", SHIPPED, "--device", "cpu", "--num_envs", "2", "--headless", "--pretrained", "--max_iterations", "1",
        "--set", "runner.critic_warmup_iterations=1"])
    env, _ = task_registry.make_env(args.task, args)
    runner, _, _ = task_registry.make_alg_runner(env, args.task, args, log_root=tmp_path)
    out = capsys.readouterr().out
    assert "Starting from the policy shipped for gente_biped_flat" in out
    assert "the first 1 iterations train the critic alone" in out
    assert "Note: --max_iterations 1 ends inside that warm-up, so this run leaves the actor as shipped" in out
    shipped = load_checkpoint(policies_root() / SHIPPED / "model.pt")["actor_state_dict"]
    actor = runner.alg.get_policy().state_dict()
    assert actor.keys() == shipped.keys() and all(torch.equal(actor[k], shipped[k]) for k in shipped)
    assert runner.current_learning_iteration == 0
    critic = {k: v.clone() for k, v in runner.alg.critic.state_dict().items()}
    runner.learn(1)
    held = runner.alg.get_policy().state_dict()
    assert all(torch.equal(held[k], shipped[k]) for k in shipped)
    assert not torch.equal(runner.alg.critic.state_dict()["mlp.0.weight"], critic["mlp.0.weight"])
    runner.learn(1)
    moved = runner.alg.get_policy().state_dict()
    assert not torch.equal(moved["mlp.0.weight"], shipped["mlp.0.weight"])


def test_train_pretrained_notes_a_run_that_ends_inside_the_warmup_only(tmp_path, capsys):
    """A --pretrained run no longer than the critic warm-up would leave the actor as shipped: the start message
    says so; a longer one gets no note."""
    from legged_gente.scripts import train as train_script

    def start_message(max_iterations: int) -> str:
        args = parse_args(train_script.build_train_parser(), [
            "--task", SHIPPED, "--device", "cpu", "--num_envs", "2", "--headless", "--pretrained",
            "--max_iterations", str(max_iterations), "--set", "runner.critic_warmup_iterations=3"])
        env, _ = task_registry.make_env(args.task, args)
        task_registry.make_alg_runner(env, args.task, args, log_root=tmp_path)
        return capsys.readouterr().out

    assert "Note: --max_iterations 3 ends inside that warm-up" in start_message(3)
    assert "Note:" not in start_message(4)


def test_train_pretrained_and_resume_exclude_each_other(capsys):
    from legged_gente.scripts import train as train_script

    with pytest.raises(SystemExit) as exit_info:
        train_script.main(["--task", SHIPPED, "--device", "cpu", "--num_envs", "1", "--pretrained", "--resume"])
    assert exit_info.value.code == 2
    assert "--pretrained starts a new run from the shipped policy" in capsys.readouterr().err


def test_train_pretrained_with_rsl_rls_ppo_names_the_warmup_setting(tmp_path):
    """The critic warm-up needs GentePPO's update: with rsl-rl's own PPO, --pretrained's default warm-up is a
    one-line error that names the setting to change."""
    from legged_gente.scripts import train as train_script

    args = parse_args(train_script.build_train_parser(), [
        "--task", SHIPPED, "--device", "cpu", "--num_envs", "2", "--headless", "--pretrained",
        "--set", "algorithm.class_name=PPO"])
    env, _ = task_registry.make_env(args.task, args)
    default = task_registry.get_cfgs(SHIPPED)[1].runner.critic_warmup_iterations
    assert default > 0
    with pytest.raises(ValueError, match=rf"runner.critic_warmup_iterations={default} needs algorithm.class_name "
                                         r"legged_gente.utils.ppo:GentePPO, not PPO; set it to 0"):
        task_registry.make_alg_runner(env, args.task, args, log_root=tmp_path)
    args = parse_args(train_script.build_train_parser(), [
        "--task", SHIPPED, "--device", "cpu", "--num_envs", "2", "--headless", "--pretrained",
        "--set", "algorithm.class_name=PPO", "--set", "runner.critic_warmup_iterations=0"])
    runner, _, _ = task_registry.make_alg_runner(env, args.task, args, log_root=tmp_path)
    assert type(runner.alg).__name__ == "PPO"


def test_a_task_of_one_s_own_fine_tunes_the_policy_it_is_registered_from(capsys):
    """A task of new rewards is a subclassed task with no policy shipped for it: registered with
    pretrained_from=<a shipped task>, gente-train --pretrained starts it from that task's actor."""
    from legged_gente.scripts.train import build_train_parser

    env_class, env_cfg, train_cfg = task_registry.tasks[SHIPPED]

    class MyCfg(env_cfg):
        class rewards(env_cfg.rewards):
            class scales(env_cfg.rewards.scales):
                feet_air_time = 2.0

    with pytest.raises(ValueError, match="no policy is shipped for 'gente_quadruped_flat'"):
        task_registry.register("my_biped_flat", env_class, MyCfg, train_cfg, pretrained_from="gente_quadruped_flat")
    assert "my_biped_flat" not in task_registry.tasks  # refused whole
    with pytest.raises(FileNotFoundError, match=r"pretrained_from="):
        task_registry.shipped_policy("my_biped_flat_unregistered")
    task_registry.register("my_biped_flat", env_class, MyCfg, train_cfg, pretrained_from=SHIPPED)
    try:
        args = parse_args(build_train_parser(), ["--task", "my_biped_flat", "--device", "cpu", "--num_envs", "1",
                                                 "--pretrained"])
        env, _ = task_registry.make_env(args.task, args)
        runner, _, _ = task_registry.make_alg_runner(env, args.task, args, log_root=None)
        assert f"Starting from the policy shipped for {SHIPPED} (my_biped_flat's pretrained_from)" in \
            capsys.readouterr().out
        shipped = load_checkpoint(policies_root() / SHIPPED / "model.pt")["actor_state_dict"]
        for key, value in runner.alg.actor.state_dict().items():
            assert torch.equal(value.cpu(), shipped[key])
    finally:
        task_registry.tasks.pop("my_biped_flat")
        task_registry.pretrained_from.pop("my_biped_flat")
