"""The training utilities checked against values computed here by hand: two ranks over gloo (gradient mean,
identical parameters, the observation normaliser of the union of both ranks' samples, per-rank seeds, rank 0
alone writing), checkpoint round trips and refusals, the episode logger's means and tb_export's CSV."""

import os
import socket
from pathlib import Path

import numpy as np
import pytest
import torch

REPO = Path(__file__).resolve().parents[1]

TASK = "gente_biped"  # the terrain curriculum, so the checkpoint carries curriculum state
TRAIN_FLAGS = ["--set", "actor.hidden_dims=[8]", "--set", "critic.hidden_dims=[8]",
               "--set", "algorithm.max_grad_norm=1e9",  # no clipping: the step's gradient is the plain rank mean
               "--set", "algorithm.num_learning_epochs=1", "--set", "algorithm.num_mini_batches=2"]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def flat(module: torch.nn.Module) -> torch.Tensor:
    return torch.cat([p.detach().reshape(-1).clone() for p in module.parameters()])


def _train_rank(rank: int, port: int, folder: str) -> None:
    """One rank of a two-rank torchrun-like launch on the CPU: one PPO iteration, recording what it computed."""
    os.environ.update(RANK=str(rank), LOCAL_RANK=str(rank), WORLD_SIZE="2", LOCAL_WORLD_SIZE="2",
                      MASTER_ADDR="127.0.0.1", MASTER_PORT=str(port), GLOO_SOCKET_IFNAME="lo")
    torch.set_num_threads(1)
    from legged_gente.envs.task_registry import task_registry
    from legged_gente.utils.args import build_parser, parse_args

    args = parse_args(build_parser("test"), ["--task", TASK, "--device", "cpu", "--num_envs", "2", "--seed", "7",
                                             "--max_iterations", "1", *TRAIN_FLAGS])
    env, _ = task_registry.make_env(TASK, args)
    built = {"commands": env.commands.clone(), "dof_pos": env.dof_pos.clone(), "force_seed": env.forces.seed,
             "heights": torch.from_numpy(env.terrain.height_field.copy())}
    runner, _, _ = task_registry.make_alg_runner(env, TASK, args, log_root=Path(folder) / f"host{rank}")
    alg = runner.alg
    record = {"built": built, "seed": runner.cfg["seed"], "initial_seed": torch.initial_seed(), "local": [],
              "stepped": [], "params_before": torch.cat([flat(alg.actor), flat(alg.critic)])}

    all_reduce = alg._all_reduce_gradients

    def recorded_all_reduce():
        record["local"].append(alg._gradients.clone())  # this rank's own gradients and KL
        all_reduce()

    step = alg.optimizer.step

    def recorded_step(*a, **k):
        record["stepped"].append(alg._gradients.clone())  # what Adam steps with
        return step(*a, **k)

    normaliser = alg.actor.obs_normalizer
    update = normaliser.update

    def recorded_update(x):
        record["normaliser_input"] = x.clone()
        update(x)

    alg._all_reduce_gradients, alg.optimizer.step = recorded_all_reduce, recorded_step
    normaliser.update = recorded_update
    runner.learn(1, init_at_random_ep_len=True)
    record.update(params_after=torch.cat([flat(alg.actor), flat(alg.critic)]),
                  normaliser_mean=normaliser._mean.clone(), normaliser_var=normaliser._var.clone(),
                  normaliser_count=normaliser.count.clone(), terrain_levels=env.terrain_levels.clone(),
                  wrote=runner.logger.writer is not None)
    torch.save(record, Path(folder) / f"rank{rank}.pt")


@pytest.fixture(scope="module")
def two_ranks(tmp_path_factory):
    import torch.multiprocessing as mp

    folder = tmp_path_factory.mktemp("two_ranks")
    mp.spawn(_train_rank, args=(free_port(), str(folder)), nprocs=2, join=True)
    return folder, [torch.load(folder / f"rank{r}.pt", weights_only=True) for r in (0, 1)]


def test_two_ranks_step_with_the_mean_of_their_gradients(two_ranks):
    _, (r0, r1) = two_ranks
    assert len(r0["local"]) == len(r1["local"]) == 2  # 1 epoch x 2 mini-batches
    for own0, own1, stepped0, stepped1 in zip(r0["local"], r1["local"], r0["stepped"], r1["stepped"]):
        assert not torch.equal(own0, own1)  # each rank's rollout is its own
        mean = (own0 + own1) / 2.0  # gradients and (last element) the mini-batch KL
        torch.testing.assert_close(stepped0, mean, rtol=1e-6, atol=1e-9)
        assert torch.equal(stepped0, stepped1)


def test_rank_0s_parameters_reach_rank_1_and_stay_identical(two_ranks):
    _, (r0, r1) = two_ranks
    assert not torch.equal(r0["params_before"], r1["params_before"])  # seed + rank: different initial networks
    assert torch.equal(r0["params_after"], r1["params_after"])
    assert not torch.equal(r0["params_after"], r0["params_before"])  # the update moved them


def test_observation_normaliser_holds_the_union_of_both_ranks_samples(two_ranks):
    _, (r0, r1) = two_ranks
    union = np.concatenate([r0["normaliser_input"].double().numpy(), r1["normaliser_input"].double().numpy()])
    n = union.shape[0]
    assert n == 2 * 2 * 24  # two ranks x 2 robots x 24 steps
    mean = union.sum(axis=0) / n
    var = ((union - mean) ** 2).sum(axis=0) / n  # population variance of all samples of both ranks
    for r in (r0, r1):
        assert int(r["normaliser_count"]) == n
        np.testing.assert_allclose(r["normaliser_mean"].numpy()[0], mean, rtol=1e-5, atol=1e-5)
        np.testing.assert_allclose(r["normaliser_var"].numpy()[0], var, rtol=1e-4, atol=1e-5)


def test_ranks_seed_differently_and_only_rank_0_writes(two_ranks):
    folder, (r0, r1) = two_ranks
    assert (r0["seed"], r1["seed"]) == (7, 8) and (r0["initial_seed"], r1["initial_seed"]) == (7, 8)
    assert r0["wrote"] and not r1["wrote"]
    checkpoints = list((folder / "host0").glob(f"{TASK}/*/model_0.pt"))
    assert len(checkpoints) == 1 and not (folder / "host1").exists()
    saved = torch.load(checkpoints[0], weights_only=True)
    # the checkpoint carries rank 0's curriculum
    assert torch.equal(saved["infos"]["curriculum"]["terrain_levels"], r0["terrain_levels"])


def test_docs_say_what_each_rank_builds(two_ranks):
    """docs/multi_gpu.md, "Seeds": the terrain is the same on every rank; the envs' initial state (commands,
    joint positions) and the force noise follow the rank's seed (task_registry.make_env seeds seed + RANK)."""
    _, (r0, r1) = two_ranks
    b0, b1 = r0["built"], r1["built"]
    assert torch.equal(b0["heights"], b1["heights"])
    assert not torch.equal(b0["commands"], b1["commands"]) and not torch.equal(b0["dof_pos"], b1["dof_pos"])
    assert b0["force_seed"] != b1["force_seed"]
    doc = " ".join((REPO / "docs" / "multi_gpu.md").read_text().split())
    assert "the envs' initial state is the same on every rank" not in doc
    assert "force draws seeded from it are the same on every rank" not in doc


def make_runner(env, task: str, seed: int):
    from legged_gente.envs.task_registry import task_registry
    from legged_gente.utils.args import build_parser, parse_args

    args = parse_args(build_parser("test"), ["--task", task, "--device", "cpu", "--seed", str(seed), *TRAIN_FLAGS])
    return task_registry.make_alg_runner(env, task, args, log_root=None)[0]


def make_biped_env():
    from legged_gente.envs.task_registry import task_registry
    from legged_gente.utils.args import build_parser, parse_args

    args = parse_args(build_parser("test"), ["--task", TASK, "--device", "cpu", "--num_envs", "2"])
    return task_registry.make_env(TASK, args)[0]


@pytest.fixture(scope="module")
def biped_env():
    return make_biped_env()


def test_a_checkpoint_round_trip_restores_everything_it_saved(biped_env, tmp_path):
    """Model, optimiser (Adam moments, step, learning rate), observation normalisers, curriculum, iteration."""
    trained = make_runner(biped_env, TASK, seed=1)
    trained.learn(1)  # Adam moments and normaliser statistics that are not their initial values
    trained.current_learning_iteration = 5
    biped_env.terrain_levels[:] = torch.tensor([3, 1])
    path = tmp_path / "model_5.pt"
    trained.save(str(path))
    saved = {"actor": {k: v.clone() for k, v in trained.alg.actor.state_dict().items()},
             "critic": {k: v.clone() for k, v in trained.alg.critic.state_dict().items()},
             "optimizer": trained.alg.optimizer.state_dict()}
    assert saved["actor"]["obs_normalizer.count"] == 2 * 24  # 2 robots x 24 steps

    env = make_biped_env()  # a new process resuming: its own env, its own networks
    fresh = make_runner(env, TASK, seed=2)
    assert not torch.equal(fresh.alg.actor.state_dict()["mlp.0.weight"], saved["actor"]["mlp.0.weight"])
    env.terrain_levels.zero_()
    fresh.load(str(path))
    assert fresh.current_learning_iteration == 5
    for name in ("actor", "critic"):
        restored = getattr(fresh.alg, name).state_dict()
        assert restored.keys() == saved[name].keys()
        for key, value in saved[name].items():
            assert torch.equal(restored[key], value), (name, key)
    optimizer = fresh.alg.optimizer.state_dict()
    assert float(optimizer["param_groups"][0]["lr"]) == float(saved["optimizer"]["param_groups"][0]["lr"])
    for index, state in saved["optimizer"]["state"].items():
        for key in ("step", "exp_avg", "exp_avg_sq"):
            assert torch.equal(optimizer["state"][index][key].float(), state[key].float()), (index, key)
    assert env.terrain_levels.tolist() == [3, 1]
    assert torch.equal(env.env_origins, env.terrain_origins[torch.tensor([3, 1]), env.terrain_columns])
    assert "terrain curriculum restored: mean level 2.00" == fresh.curriculum_message


@pytest.mark.parametrize("damage", ["truncated", "text"])
def test_a_damaged_checkpoint_is_one_line_naming_it(biped_env, tmp_path, damage):
    from legged_gente.utils.checkpoints import UnreadableCheckpoint

    runner = make_runner(biped_env, TASK, seed=1)
    path = tmp_path / "model_0.pt"
    runner.save(str(path))
    if damage == "truncated":
        path.write_bytes(path.read_bytes()[:1000])
    else:
        path.write_text("not a checkpoint")
    with pytest.raises(UnreadableCheckpoint) as error:
        runner.load(str(path))
    assert "\n" not in str(error.value) and str(path) in str(error.value)


def test_a_checkpoint_of_another_task_is_one_line_naming_the_fix(biped_env, tmp_path):
    from legged_gente.envs.task_registry import task_registry
    from legged_gente.utils.args import build_parser, parse_args
    from legged_gente.utils.checkpoints import CheckpointError

    quadruped = "gente_quadruped_flat"
    args = parse_args(build_parser("test"), ["--task", quadruped, "--device", "cpu", "--num_envs", "1"])
    path = tmp_path / "model_0.pt"
    make_runner(task_registry.make_env(quadruped, args)[0], quadruped, seed=1).save(str(path))
    with pytest.raises(CheckpointError) as error:
        make_runner(biped_env, TASK, seed=1).load(str(path))
    assert str(error.value) == (f"checkpoint {path} is for gente_quadruped_flat (12 actions); this task is "
                                f"gente_biped (10 actions). Pick a checkpoint of this task, or the task of this "
                                f"checkpoint (--task).")


class RecordingWriter:
    """What rsl-rl's Logger.log writes, as {tag: {step: value}}."""

    def __init__(self):
        self.scalars = {}

    def add_scalar(self, tag, value, step):
        self.scalars.setdefault(tag, {})[step] = float(value)


def deferred_logger(num_envs: int, writer):
    from legged_gente.envs.base.legged_robot_config import LeggedRobotCfgPPO, rsl_rl_train_cfg
    from legged_gente.utils.episode_logger import DeferredLogger

    cfg = rsl_rl_train_cfg(LeggedRobotCfgPPO())
    cfg["num_steps_per_env"] = 6
    logger = DeferredLogger(log_dir=None, cfg=cfg, env_cfg={}, num_envs=num_envs, is_distributed=False,
                            gpu_world_size=1, gpu_global_rank=0, device="cpu")
    logger.writer = writer
    return logger


def log_iteration(logger, it: int) -> None:
    logger.log(it=it, start_it=0, total_it=2, collect_time=1.5, learn_time=0.5, loss_dict={"value": 0.25},
               learning_rate=1e-3, action_std=torch.tensor([0.5, 1.5]), rnd_weight=None)


def test_episode_means_are_weighted_by_episodes_not_by_robots(capsys):
    """Robot 0 earns 1 per step and ends episodes after steps 2 and 5 (3 steps each), robot 1 earns 2 per step and
    ends one after step 3 (4 steps), robot 2 earns 3 per step and ends none: episode returns 3, 8, 3."""
    writer = RecordingWriter()
    logger = deferred_logger(3, writer)
    rewards = torch.tensor([1.0, 2.0, 3.0])
    ends = {2: [0], 3: [1], 5: [0]}
    for step in range(6):
        dones = torch.zeros(3)
        dones[ends.get(step, [])] = 1.0
        logger.process_env_step(rewards, dones, {})
    log_iteration(logger, 0)
    assert writer.scalars["Train/mean_reward"][0] == pytest.approx((3 + 8 + 3) / 3)  # not (3 + 8) / 2 per robot
    assert writer.scalars["Train/mean_episode_length"][0] == pytest.approx((3 + 4 + 3) / 3)
    assert logger.cur_reward_sum.tolist() == [0.0, 2.0 * 2, 3.0 * 6]  # unfinished episodes go on
    assert writer.scalars["Perf/total_fps"][0] == int(6 * 3 / (1.5 + 0.5))
    assert writer.scalars["Policy/mean_std"][0] == pytest.approx(1.0)


def test_an_iteration_in_which_no_episode_ended_logs_no_episode_mean(capsys):
    writer = RecordingWriter()
    logger = deferred_logger(2, writer)
    for _ in range(6):
        logger.process_env_step(torch.ones(2), torch.zeros(2), {})
    log_iteration(logger, 0)
    assert "Train/mean_reward" not in writer.scalars and "Train/mean_episode_length" not in writer.scalars
    assert "Loss/value" in writer.scalars  # the iteration itself is logged
    assert logger.cur_episode_length.tolist() == [6.0, 6.0]


def test_tb_export_gives_back_what_the_logger_wrote(tmp_path, capsys):
    """Two iterations through DeferredLogger into TensorBoard: in iteration 0 no episode ends, in iteration 1 the
    two robots end episodes of 12 steps (returns 12 x 0.5 = 6 and 12 x 1.5 = 18)."""
    import csv

    from torch.utils.tensorboard import SummaryWriter

    from legged_gente.utils.tb_export import export_scalars

    writer = SummaryWriter(log_dir=str(tmp_path / "run"))
    logger = deferred_logger(2, writer)
    rewards = torch.tensor([0.5, 1.5])
    for it in range(2):
        for step in range(6):
            logger.process_env_step(rewards, torch.full((2,), float(it == 1 and step == 5)), {})
        log_iteration(logger, it)
    writer.close()
    rows = list(csv.DictReader(open(export_scalars(tmp_path / "run", tmp_path / "scalars.csv"))))
    by_step = {int(row["step"]): row for row in rows}
    # iterations at steps 0 and 1; the ".../time" tags at the seconds trained, 4.0 s (none at 2.0 s: no episode)
    assert sorted(by_step) == [0, 1, 4]
    assert by_step[0]["Train/mean_reward"] == "" and float(by_step[1]["Train/mean_reward"]) == (6 + 18) / 2
    assert float(by_step[1]["Train/mean_episode_length"]) == 12.0
    assert float(by_step[4]["Train/mean_reward/time"]) == 12.0 and by_step[4]["Loss/value"] == ""
    for it in (0, 1):
        assert float(by_step[it]["Loss/value"]) == 0.25 and float(by_step[it]["Perf/total_fps"]) == 6.0
        assert float(by_step[it]["Loss/learning_rate"]) == pytest.approx(1e-3, rel=1e-7)  # stored as float32


def test_docs_give_the_size_of_the_gradient_all_reduce(biped_env):
    """docs/multi_gpu.md sizes PPO's all-reduce; counted by hand for gente_biped's default 512-256-128 networks:
    weights and biases of obs->512->256->128->out, plus the actor's 10 action stds, 4 bytes each."""
    from legged_gente.envs.task_registry import task_registry

    runner = task_registry.make_alg_runner(biped_env, TASK, log_root=None)[0]
    actor_in, critic_in = runner.alg.actor.obs_dim, runner.alg.critic.obs_dim

    def mlp(inputs, outputs):
        sizes = [inputs, 512, 256, 128, outputs]
        return sum(a * b + b for a, b in zip(sizes[:-1], sizes[1:]))

    count = mlp(actor_in, 10) + 10 + mlp(critic_in, 1)
    assert runner.alg._gradients.numel() == count + 1  # the gradients, then the KL
    megabytes = 4 * count / 1e6
    assert megabytes == pytest.approx(2.34, abs=0.01)
    doc = " ".join((REPO / "docs" / "multi_gpu.md").read_text().split())
    assert f"{megabytes:.1f} MB for gente_biped" in doc


def test_an_episode_mean_the_env_could_not_take_is_left_out_not_logged():
    """The env reports NaN for a reward term's mean when no episode ended since its last report (a mean of no
    episodes); the logger leaves that key out of the iteration, as rsl-rl does for a key an env did not send, and
    logs the defined ones (terrain level 2.5, diverged resets 0)."""
    writer = RecordingWriter()
    logger = deferred_logger(2, writer)
    episode = {"rew_alive": torch.tensor(float("nan")), "terrain_level": torch.tensor(2.5),
               "diverged_resets": torch.tensor(0.0)}
    for step in range(6):
        logger.process_env_step(torch.ones(2), torch.zeros(2), {"episode": episode} if step == 5 else {})
    log_iteration(logger, 0)
    assert "Episode/rew_alive" not in writer.scalars
    assert writer.scalars["Episode/terrain_level"][0] == 2.5 and writer.scalars["Episode/diverged_resets"][0] == 0.0
