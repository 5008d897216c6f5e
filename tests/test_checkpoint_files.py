"""Checkpoints that do not fit, lack parts, or are corrupt or foreign are one-line CheckpointErrors that name the
problem and the fix, never torch's multi-line 'Error(s) in loading state_dict', a KeyError or a traceback."""

import random
import zipfile

import pytest
import torch

from legged_gente.envs.task_registry import task_registry
from legged_gente.utils.args import build_parser, parse_args
from legged_gente.utils.checkpoints import CheckpointError, UnreadableCheckpoint, load_checkpoint


@pytest.fixture(scope="module")
def make_runner():
    args = parse_args(build_parser("test"), ["--task", "gente_biped_flat", "--device", "cpu", "--num_envs", "1"])
    env, _ = task_registry.make_env(args.task, args)

    def make(actor_normalization=False, critic_hidden=(8,)):
        _, train_cfg = task_registry.get_cfgs(args.task)
        train_cfg.actor.hidden_dims = [8]
        train_cfg.critic.hidden_dims = list(critic_hidden)
        train_cfg.actor.obs_normalization = actor_normalization
        return task_registry.make_alg_runner(env, args.task, train_cfg=train_cfg, log_root=None)[0]

    return make


def one_line_error(call) -> str:
    with pytest.raises(CheckpointError) as error:
        call()
    message = str(error.value)
    assert "\n" not in message, message
    return message


@pytest.mark.parametrize("load_cfg", [None, {"actor": True}])
def test_an_actor_with_other_layers_is_a_one_line_error(make_runner, tmp_path, load_cfg):
    """A run trained with the actor's observation normaliser has obs_normalizer.* weights that an actor built
    without one lacks (and the other way round): torch's strict load lists them over several lines."""
    path = tmp_path / "model_4.pt"
    make_runner(actor_normalization=True).save(str(path))
    message = one_line_error(lambda: make_runner(actor_normalization=False).load(str(path), load_cfg=load_cfg))
    assert "actor" in message and "obs_normalizer._mean" in message and "config.json" in message
    path_without = tmp_path / "model_5.pt"
    make_runner(actor_normalization=False).save(str(path_without))
    message = one_line_error(lambda: make_runner(actor_normalization=True).load(str(path_without), load_cfg=load_cfg))
    assert "obs_normalizer._mean" in message and "not in the checkpoint" in message


def test_resuming_with_another_critic_size_is_a_one_line_error(make_runner, tmp_path):
    path = tmp_path / "model_4.pt"
    make_runner(critic_hidden=(8,)).save(str(path))
    message = one_line_error(lambda: make_runner(critic_hidden=(16,)).load(str(path)))
    assert "critic" in message and "(8, 52) in the checkpoint, (16, 52) here" in message
    make_runner(critic_hidden=(16,)).load(str(path), load_cfg={"actor": True})  # playing needs no critic


def test_a_checkpoint_without_infos_loads_its_actor(make_runner, tmp_path):
    """A bare {'actor_state_dict': ...} (written by hand or another tool) has no infos: its actor still loads."""
    runner = make_runner()
    path = tmp_path / "actor.pt"
    torch.save({"actor_state_dict": runner.alg.get_policy().state_dict()}, path)
    assert runner.load(str(path), load_cfg={"actor": True}) is None
    assert runner.curriculum_message == "the checkpoint has no curriculum state"


@pytest.mark.parametrize("part", ["optimizer_state_dict", "iter"])
def test_resuming_from_a_checkpoint_without_its_optimizer_or_iteration_is_a_one_line_error(make_runner, tmp_path,
                                                                                            part):
    runner = make_runner()
    path = tmp_path / "model_4.pt"
    runner.save(str(path))
    loaded = torch.load(path, weights_only=True)
    del loaded[part]
    torch.save(loaded, path)
    assert part in one_line_error(lambda: runner.load(str(path)))


def test_an_older_rsl_rl_checkpoint_is_named_as_such(tmp_path):
    """legged_gym's and older rsl-rl's model_<N>.pt keep actor and critic in one model_state_dict."""
    path = tmp_path / "model_1500.pt"
    torch.save({"model_state_dict": {"actor.0.weight": torch.zeros(2, 2)}, "optimizer_state_dict": {}, "iter": 1500,
                "infos": None}, path)
    message = one_line_error(lambda: load_checkpoint(path))
    assert "model_state_dict" in message and "older rsl-rl" in message


def test_a_torchscript_policy_is_unreadable_without_advice_to_unpickle_it(tmp_path):
    """torch's own message for it suggests weights_only=False, which would let a file run code: not ours."""
    path = tmp_path / "policy.pt"
    torch.jit.script(torch.nn.Linear(2, 2)).save(str(path))
    message = one_line_error(lambda: load_checkpoint(path))
    assert "TorchScript" in message and "weights_only` set to `False`" not in message


def test_every_corruption_of_a_checkpoint_is_a_checkpoint_error(tmp_path):
    """Flipped bits, overwritten bytes and truncation (fixed seed): the file loads, or is a CheckpointError (mostly
    an UnreadableCheckpoint, which --resume skips); never a TypeError or AttributeError from inside torch."""
    good = tmp_path / "good.pt"
    layer = torch.nn.Linear(4, 8)
    torch.save({"actor_state_dict": layer.state_dict(), "critic_state_dict": layer.state_dict(), "iter": 3,
                "infos": {"task": "t", "num_actions": 8, "curriculum": {"terrain_levels": torch.zeros(3).long()}}},
               good)
    raw = good.read_bytes()
    rng = random.Random(0)
    corrupt = tmp_path / "corrupt.pt"
    for trial in range(900):
        data = bytearray(raw)
        i = rng.randrange(len(data))
        if trial % 3 == 0:
            data[i] ^= 1 << rng.randrange(8)
        elif trial % 3 == 1:
            data[i] = rng.randrange(256)
        else:
            data = data[:i]
        corrupt.write_bytes(bytes(data))
        try:
            load_checkpoint(corrupt)
        except CheckpointError:
            pass


def with_pickle(path, pickled: bytes) -> None:
    """Replace the pickle inside a torch.save zip (torch does not check the zip's checksums)."""
    with zipfile.ZipFile(path) as source:
        entries = {info: source.read(info) for info in source.infolist()}
    with zipfile.ZipFile(path, "w") as target:
        for info, data in entries.items():
            target.writestr(info, pickled if info.filename.endswith("/data.pkl") else data)


def test_what_the_safe_loader_stumbles_on_without_a_real_global_is_corrupt_not_unsafe(tmp_path):
    """Only a GLOBAL naming a Python object is 'unsafe' (test_a_checkpoint_cannot_run_code): a NEWOBJ of a number,
    or a GLOBAL that is no Python name (a byte overwritten in 'collections'), is a corrupt file that --resume skips."""
    path = tmp_path / "model_1.pt"
    torch.save({"actor_state_dict": torch.nn.Linear(2, 2).state_dict()}, path)
    with zipfile.ZipFile(path) as source:
        pickled = next(source.read(name) for name in source.namelist() if name.endswith("/data.pkl"))
    assert b"collections" in pickled
    for broken in (b"\x80\x02K\x03K\x03\x85\x81.", pickled.replace(b"collections", b"collec{ions", 1)):
        with_pickle(path, broken)
        with pytest.raises(UnreadableCheckpoint, match="unreadable"):
            load_checkpoint(path)


def test_running_out_of_memory_while_loading_is_not_called_a_corrupt_file(tmp_path, monkeypatch):
    # torch's OutOfMemoryError is a RuntimeError, as a truncated file's is; the file is fine, the device is full
    path = tmp_path / "model_1.pt"
    torch.save({"actor_state_dict": {}}, path)

    def out_of_memory(*args, **kwargs):
        raise torch.OutOfMemoryError("CUDA out of memory. Tried to allocate 2.00 GiB")

    monkeypatch.setattr(torch, "load", out_of_memory)
    with pytest.raises(torch.OutOfMemoryError):
        load_checkpoint(path, map_location="cpu")


def test_a_policy_that_observes_a_term_this_env_leaves_out_is_named_with_what_the_term_needs():
    """The shipped gente_biped policy observes the height scan; on a plane the env leaves that term out, and the
    error says so, instead of advising other network settings."""
    env_cfg, _ = task_registry.get_cfgs("gente_biped")
    env_cfg.env.num_envs = 1
    env_cfg.terrain.mesh_type = "plane"
    args = parse_args(build_parser("test"), ["--task", "gente_biped", "--device", "cpu"])
    env, _ = task_registry.make_env("gente_biped", args, env_cfg=env_cfg)
    message = one_line_error(lambda: task_registry.make_pretrained_runner(env, "gente_biped"))
    assert "height_scan" in message and "heightfield terrain" in message, message
    assert "hidden_dims" not in message, message
