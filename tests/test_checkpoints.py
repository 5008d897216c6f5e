"""Checkpoints load safely (torch.load weights_only=True: a checkpoint cannot run code), --resume gets past a
truncated latest checkpoint, SIGTERM saves one like Ctrl-C, so does --max_minutes at its deadline, and a run
folder records how it was made."""

import json
import os
import pickle
import signal
import subprocess
import sys
import time
import warnings
import zipfile
from pathlib import Path

import pytest
import torch

from legged_gente.envs.task_registry import load_newest_readable, task_registry
from legged_gente.utils.args import build_parser, parse_args
from legged_gente.utils.checkpoints import CheckpointError, UnreadableCheckpoint, load_checkpoint

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def runner():
    args = parse_args(build_parser("test"), ["--task", "gente_biped_flat", "--device", "cpu", "--num_envs", "1"])
    env, _ = task_registry.make_env(args.task, args)
    _, train_cfg = task_registry.get_cfgs(args.task)
    train_cfg.actor.hidden_dims = train_cfg.critic.hidden_dims = [8]
    runner, _, _ = task_registry.make_alg_runner(env, args.task, train_cfg=train_cfg, log_root=None)
    return runner


class RunsCode:
    """Unpickling this calls os.system: what weights_only=False would do with a hostile checkpoint."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return os.system, (f"touch {self.marker}",)


def test_a_checkpoint_cannot_run_code(tmp_path):
    marker = tmp_path / "code_ran"
    path = tmp_path / "model_0.pt"
    torch.save({"actor_state_dict": {}, "payload": RunsCode(marker)}, path)
    with pytest.raises(CheckpointError, match="safe loader refuses"):
        load_checkpoint(path)
    assert not marker.exists()


def test_saved_checkpoints_load_with_weights_only_and_say_what_they_are_for(runner, tmp_path):
    path = tmp_path / "model_3.pt"
    runner.current_learning_iteration = 3
    runner.save(str(path))
    assert not list(tmp_path.glob("*.partial"))  # written whole, then renamed
    loaded = torch.load(path, weights_only=True)
    assert loaded["iter"] == 3
    assert loaded["infos"]["task"] == "gente_biped_flat" and loaded["infos"]["num_actions"] == 10


def test_truncated_and_garbage_files_are_unreadable_checkpoints(runner, tmp_path):
    good = tmp_path / "good.pt"
    runner.save(str(good))
    truncated = tmp_path / "truncated.pt"
    truncated.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    garbage = tmp_path / "garbage.pt"
    garbage.write_bytes(b"\x00not a checkpoint" * 10)
    text, sentence = tmp_path / "text.pt", tmp_path / "sentence.pt"  # the legacy unpickler: KeyError, IndexError
    text.write_text("hello")
    sentence.write_text("this is not a torch file")
    for path in (truncated, garbage, text, sentence):
        with pytest.raises(UnreadableCheckpoint, match="unreadable"):
            load_checkpoint(path)
    plain = tmp_path / "plain.pt"
    pickle.dump([1, 2], plain.open("wb"))
    with pytest.raises(CheckpointError):
        load_checkpoint(plain)


def test_a_flipped_bit_in_a_name_of_torchs_is_a_corrupt_checkpoint_not_an_unsafe_one(runner, tmp_path):
    """A bit flipped in the pickled name torch._utils._rebuild_tensor_v2 (the zip's checksum misses it) makes the
    safe loader refuse a GLOBAL that names nothing: corrupt (resume moves on to an older checkpoint), not
    unsafe (a GLOBAL naming a real object, os.system, is still unsafe: test_a_checkpoint_cannot_run_code)."""
    good = tmp_path / "good.pt"
    runner.save(str(good))
    raw = good.read_bytes()
    i = raw.index(b"_rebuild_tensor_v2") + 5  # the "l"
    flipped = tmp_path / "flipped.pt"
    flipped.write_bytes(raw[:i] + bytes([raw[i] ^ 4]) + raw[i + 1:])  # "l" -> "h"
    with pytest.raises(UnreadableCheckpoint, match="unreadable"):
        load_checkpoint(flipped)


def test_resume_falls_back_to_the_newest_readable_checkpoint(runner, tmp_path, capsys):
    root = tmp_path / "gente_biped_flat"
    older, newer = root / "2026-01-01_00-00-00", root / "2026-01-02_00-00-00"
    older.mkdir(parents=True)
    newer.mkdir()
    for run, iteration in ((older, 7), (newer, 8), (newer, 9)):
        runner.current_learning_iteration = iteration
        runner.save(str(run / f"model_{iteration}.pt"))
    latest = newer / "model_9.pt"
    latest.write_bytes(latest.read_bytes()[:1000])  # killed while writing (before saves were atomic)
    assert load_newest_readable(runner, root) == newer / "model_8.pt"
    assert runner.current_learning_iteration == 8
    out = capsys.readouterr().out
    assert "model_9.pt is unreadable" in out and "skipped model_9.pt" in out
    (newer / "model_8.pt").write_bytes(b"")
    assert load_newest_readable(runner, root) == older / "model_7.pt"  # then the earlier run
    (older / "model_7.pt").write_bytes(b"")
    with pytest.raises(CheckpointError, match="no readable checkpoint under .* \\(tried model_9.pt, model_8.pt, "
                                              "model_7.pt: each truncated or corrupt\\); pick another run, or train"):
        load_newest_readable(runner, root)
    # a checkpoint named explicitly is loaded or refused, never replaced by another
    with pytest.raises(UnreadableCheckpoint):
        load_newest_readable(runner, root, load_run=newer.name, checkpoint=9)


def test_resume_names_the_later_run_folders_it_skips_for_holding_no_checkpoint(runner, tmp_path, capsys):
    """A run stopped before its first iteration leaves a folder with a config.json alone: --resume takes the latest
    run that has a checkpoint, and now says which later folders it passed over."""
    root = tmp_path / "gente_biped_flat"
    done, stopped = root / "2026-01-01_00-00-00", root / "2026-01-02_00-00-00"
    done.mkdir(parents=True)
    stopped.mkdir()
    (stopped / "config.json").write_text("{}")
    runner.save(str(done / "model_3.pt"))
    assert load_newest_readable(runner, root) == done / "model_3.pt"
    assert (f"the run folder(s) {stopped.name} after {done.name} hold no checkpoint; resuming from {done.name}"
            in capsys.readouterr().out)


def saved_as_on_a_gpu(path: Path) -> None:
    """Rewrite a CPU checkpoint as ``torch.save`` writes one from a GPU: every storage's location tag reads
    cuda:0, so a plain ``torch.load`` on a machine without CUDA refuses it."""
    with zipfile.ZipFile(path) as source:
        entries = {info: source.read(info) for info in source.infolist()}
    with zipfile.ZipFile(path, "w", zipfile.ZIP_STORED) as target:
        for info, data in entries.items():
            if info.filename.endswith("/data.pkl"):
                data = data.replace(b"X\x03\x00\x00\x00cpu", b"X\x06\x00\x00\x00cuda:0")
            target.writestr(info, data)


def test_resume_reads_a_checkpoint_saved_on_a_gpu(runner, tmp_path):
    """A run trained on a GPU continues on a machine without one (--resume maps the tensors to the env's
    device, as --pretrained and gente-play do)."""
    run = tmp_path / "gente_biped_flat" / "2026-01-01_00-00-00"
    run.mkdir(parents=True)
    runner.current_learning_iteration = 5
    runner.save(str(run / "model_5.pt"))
    saved_as_on_a_gpu(run / "model_5.pt")
    if not torch.cuda.is_available():
        with pytest.raises(RuntimeError, match="CUDA"):
            torch.load(run / "model_5.pt", weights_only=True)
    runner.current_learning_iteration = 0
    assert load_newest_readable(runner, tmp_path / "gente_biped_flat") == run / "model_5.pt"
    assert runner.current_learning_iteration == 5
    assert all(p.device == torch.device(runner.device) for p in runner.alg.get_policy().parameters())


@pytest.fixture(scope="module")
def terminated_run(tmp_path_factory):
    """train.py started in an empty folder (no $GENTE_LOG_ROOT), stopped with SIGTERM once it has logged."""
    cwd = tmp_path_factory.mktemp("project")
    env = {k: v for k, v in os.environ.items() if k != "GENTE_LOG_ROOT"}
    env.update(PYTHONPATH=str(REPO), PYTHONUNBUFFERED="1", OMP_NUM_THREADS="1")
    cmd = [sys.executable, str(REPO / "legged_gente/scripts/train.py"), "--task", "gente_biped_flat", "--device",
           "cpu", "--num-envs", "1", "--max_iterations", "100000", "--set", "runner.num_steps_per_env=2",
           "--set", "algorithm.num_mini_batches=1",
           "--set", "actor.hidden_dims=[8]", "--set", "critic.hidden_dims=[8]", "--set", "runner.save_interval=1000"]
    proc = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    lines, deadline = [], time.monotonic() + 240
    for line in proc.stdout:
        lines.append(line)
        if "Learning iteration 0/" in line or time.monotonic() > deadline:
            break
    proc.send_signal(signal.SIGTERM)
    out, _ = proc.communicate(timeout=120)
    return cwd, proc.returncode, "".join(lines) + out


def test_load_run_takes_the_path_of_a_run_folder_anywhere(runner, tmp_path):
    """A run copied from another machine resumes from where it lies, with no run under the log root yet."""
    copied = tmp_path / "copied" / "2026-01-03_00-00-00"
    copied.mkdir(parents=True)
    for iteration in (50, 61):
        runner.current_learning_iteration = iteration
        runner.save(str(copied / f"model_{iteration}.pt"))
    empty_root = tmp_path / "logs" / "gente_biped_flat"
    assert load_newest_readable(runner, empty_root, load_run=str(copied)) == copied / "model_61.pt"
    assert runner.current_learning_iteration == 61
    assert load_newest_readable(runner, empty_root, load_run=str(copied), checkpoint=50) == copied / "model_50.pt"
    # a name under the log root still wins, and a name that is neither is one clear error
    (empty_root / "mine").mkdir(parents=True)
    runner.save(str(empty_root / "mine" / "model_3.pt"))
    assert load_newest_readable(runner, empty_root, load_run="mine") == empty_root / "mine" / "model_3.pt"
    with pytest.raises(FileNotFoundError, match=r"run 'nowhere' is neither a run under .* \(runs: \['mine'\]\) nor a folder"):
        load_newest_readable(runner, empty_root, load_run="nowhere")


def test_sigterm_saves_a_checkpoint(terminated_run):
    """... and exits with 128 + SIGTERM, as a killed command does, so `gente-train ... && next` stops there."""
    cwd, code, out = terminated_run
    assert code == 128 + signal.SIGTERM, out
    assert "Terminated (SIGTERM): saved" in out, out
    run = next((cwd / "logs" / "gente_biped_flat").iterdir())
    saved = sorted(run.glob("model_*.pt"))
    assert saved and load_checkpoint(saved[-1])["infos"]["task"] == "gente_biped_flat"


def test_max_minutes_stops_after_a_whole_iteration_and_saves_it(tmp_path, monkeypatch, capsys):
    """A deadline already passed after the first iteration: training ends there, with that iteration saved."""
    from legged_gente.scripts import train as train_script

    monkeypatch.setenv("GENTE_LOG_ROOT", str(tmp_path))
    train_script.main(["--task", "gente_biped_flat", "--device", "cpu", "--num_envs", "1", "--max_iterations", "50",
                       "--max_minutes", "1e-6", "--set", "runner.num_steps_per_env=2", "--set",
                       "algorithm.num_mini_batches=1", "--set", "actor.hidden_dims=[8]", "--set",
                       "critic.hidden_dims=[8]", "--set", "runner.save_interval=1000"])
    out = capsys.readouterr().out
    assert "Time limit of 1e-06 min reached: saved" in out, out
    run = next((tmp_path / "gente_biped_flat").iterdir())
    assert [p.name for p in run.glob("model_*.pt")] == ["model_0.pt"]  # iteration 0 only, not 50
    assert load_checkpoint(run / "model_0.pt")["iter"] == 0


def test_max_minutes_counts_the_envs_build(tmp_path, monkeypatch, capsys):
    """A time-limited job's clock runs from its start: on a fresh machine building the env (compiling the kernels)
    takes minutes. Here the build takes 3 s and --max_minutes 0.04 allows 2.4 s: the deadline has passed when the
    first iteration ends, so training stops after it (counted from the start of learning, it would run on)."""
    from legged_gente.envs.task_registry import task_registry
    from legged_gente.scripts import train as train_script

    make_env = task_registry.make_env

    def slow_make_env(*args, **kwargs):
        time.sleep(3.0)
        return make_env(*args, **kwargs)

    monkeypatch.setenv("GENTE_LOG_ROOT", str(tmp_path))
    monkeypatch.setattr(task_registry, "make_env", slow_make_env)
    train_script.main([*TINY[:6], "--max_iterations", "50", "--max_minutes", "0.04", *TINY[8:]])
    assert "Time limit of 0.04 min reached: saved" in capsys.readouterr().out
    run = next((tmp_path / "gente_biped_flat").iterdir())
    assert [p.name for p in run.glob("model_*.pt")] == ["model_0.pt"]


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_stops_training_after_the_iteration_it_arrives_in(tmp_path, monkeypatch, capsys, signum):
    """Ctrl-C (or SIGTERM) in the middle of iteration 1's policy update: the update and iteration 1 finish, then
    training stops and saves model_1 (iteration 1), exiting with 128 + the signal. An exception raised in the
    middle of the update would leave iteration 1 unfinished and unsaved."""
    from legged_gente.scripts import train as train_script
    from legged_gente.utils.ppo import GentePPO

    update, calls = GentePPO.update, []

    def update_signalled_in_the_second(self):
        calls.append(len(calls))
        if len(calls) == 2:
            os.kill(os.getpid(), signum)  # delivered now, in the middle of the update
        return update(self)

    monkeypatch.setenv("GENTE_LOG_ROOT", str(tmp_path))
    monkeypatch.setattr(GentePPO, "update", update_signalled_in_the_second)
    with pytest.raises(SystemExit) as stop:
        train_script.main(TINY)
    out = capsys.readouterr().out
    assert stop.value.code == 128 + signum, out
    assert ("Interrupted" if signum == signal.SIGINT else "Terminated (SIGTERM)") + ": saved" in out, out
    assert len(calls) == 2  # no third iteration began
    run = next((tmp_path / "gente_biped_flat").iterdir())
    assert sorted(p.name for p in run.glob("model_*.pt")) == ["model_0.pt", "model_1.pt"]  # rsl-rl saves the first
    assert load_checkpoint(run / "model_1.pt")["iter"] == 1


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_still_stops_training_after_a_library_replaced_its_handler(tmp_path, monkeypatch, capsys, signum):
    """Triton, which torch.compile loads in the first iterations on a GPU, installs LLVM's handlers for SIGINT and
    SIGTERM at the C level, over Python's: the signal then killed training with nothing saved. Here a stand-in
    library sets the C-level disposition to "ignore" (behind Python's back) in iteration 0's update, and the signal
    comes in iteration 2's: it must still stop training after iteration 2 and save it. Ignored, training would run
    to its 4 iterations and exit without one."""
    import ctypes

    from legged_gente.scripts import train as train_script
    from legged_gente.utils.ppo import GentePPO

    libc_signal = ctypes.CDLL(None).signal
    libc_signal.argtypes, libc_signal.restype = [ctypes.c_int, ctypes.c_void_p], ctypes.c_void_p
    update, calls = GentePPO.update, []

    def update_with_a_library_then_a_signal(self):
        calls.append(len(calls))
        if len(calls) == 1:
            libc_signal(signum, 1)  # SIG_IGN, as a C library's own handler would, unseen by Python's signal module
        if len(calls) == 3:
            os.kill(os.getpid(), signum)
        return update(self)

    monkeypatch.setenv("GENTE_LOG_ROOT", str(tmp_path))
    monkeypatch.setattr(GentePPO, "update", update_with_a_library_then_a_signal)
    with pytest.raises(SystemExit) as stop:
        train_script.main([*TINY[:6], "--max_iterations", "4", *TINY[8:]])
    assert stop.value.code == 128 + signum, capsys.readouterr().out
    run = next((tmp_path / "gente_biped_flat").iterdir())
    assert load_checkpoint(max(run.glob("model_*.pt"), key=lambda p: int(p.stem[6:])))["iter"] == 2


def test_a_second_ctrl_c_stops_at_once(tmp_path, monkeypatch, capsys):
    """Ctrl-C twice in iteration 1's update: the second stops there, so the last finished iteration, 0, is saved."""
    from legged_gente.scripts import train as train_script
    from legged_gente.utils.ppo import GentePPO

    update, calls = GentePPO.update, []

    def update_signalled_twice_in_the_second(self):
        calls.append(len(calls))
        if len(calls) == 2:
            os.kill(os.getpid(), signal.SIGINT)
            os.kill(os.getpid(), signal.SIGINT)
        return update(self)

    monkeypatch.setenv("GENTE_LOG_ROOT", str(tmp_path))
    monkeypatch.setattr(GentePPO, "update", update_signalled_twice_in_the_second)
    with pytest.raises(SystemExit) as stop:
        train_script.main(TINY)
    assert stop.value.code == 128 + signal.SIGINT
    run = next((tmp_path / "gente_biped_flat").iterdir())
    assert "Interrupted: saved" in capsys.readouterr().out
    assert sorted(p.name for p in run.glob("model_*.pt")) == ["model_0.pt"]


@pytest.mark.parametrize("minutes", ["0", "-3"])
def test_max_minutes_must_be_positive(minutes, capsys):
    from legged_gente.scripts import train as train_script

    with pytest.raises(SystemExit) as stop:
        train_script.main(["--task", "gente_biped_flat", "--device", "cpu", "--max_minutes", minutes])
    assert stop.value.code == 2
    assert "--max_minutes must be > 0" in capsys.readouterr().err


def test_runs_go_to_the_working_directory_and_record_how_they_were_made(terminated_run):
    cwd, _, out = terminated_run
    run = next((cwd / "logs" / "gente_biped_flat").iterdir())  # ./logs of the working directory
    assert not (run / "git").exists()
    config = json.loads((run / "config.json").read_text())
    assert config["command"].startswith("train.py --task gente_biped_flat --device cpu --num-envs 1")
    code = config["code"]
    assert code["package_version"] or code["git_commit"]
    if code["git_commit"]:
        head = subprocess.run(["git", "-C", str(REPO), "rev-parse", "HEAD"], capture_output=True, text=True).stdout
        assert code["git_commit"] == head.strip()
    assert config["terrain"] == {"mode": "plane"}
    assert config["world_size"] == 1 and config["resumed_from"] is None  # one process, a fresh run
    import torch

    assert config["platform"]["device"] == "cpu" and config["platform"]["libraries"]["torch"] == torch.__version__
    assert len(code["source_sha256"]) == 64
    assert "Module " not in out  # Warp's per-module load lines stay quiet without --verbose


def test_config_records_the_resolved_terrain_of_a_heightfield_run(tmp_path):
    """The tile grid the robots got (names per tile) and a generated spec's content, not only the config."""
    from types import SimpleNamespace

    from legged_gente.scripts.train import resolved_terrain
    from legged_gente.terrain.terrain import Terrain

    env_cfg, _ = task_registry.get_cfgs("gente_biped")
    env_cfg.terrain.num_rows, env_cfg.terrain.num_cols = 2, 3
    terrain = Terrain(env_cfg.terrain, num_robots=2)
    record = resolved_terrain(SimpleNamespace(terrain=terrain, cfg=env_cfg))
    assert record["mode"] == terrain.mode and record["resolution_m"] == env_cfg.terrain.resolution
    assert len(record["tiles"]) == 2 and all(len(row) == 3 for row in record["tiles"])
    assert all(isinstance(name, str) and name for row in record["tiles"] for name in row)
    json.dumps(record)  # serialisable as config.json
    spec = tmp_path / "spec.json"
    spec.write_text(json.dumps({"version": 1, "calls": []}))
    env_cfg.terrain.generated_specs = [str(spec)]
    record = resolved_terrain(SimpleNamespace(terrain=terrain, cfg=env_cfg))
    assert record["generated_specs"] == {str(spec): {"version": 1, "calls": []}}


def test_config_records_the_parameters_of_each_soil_the_robots_got():
    """A custom soil is registered by the user's code, which may change after the run: config.json keeps each soil's
    parameters, (mean, std) pairs in SI units, as they were."""
    from types import SimpleNamespace

    from legged_gente.scripts.train import resolved_terrain
    from legged_gente.terrain.soil import SOIL_PRESETS, register_custom_soil
    from legged_gente.terrain.terrain import Terrain

    register_custom_soil("peat", kc=1.0e3, kphi=2.0e5, n=1.0, c=2.0e3, mu=(0.4, 0.04), K=0.03, bulldoze_c=0.0,
                         bulldoze_g=0.0)
    try:
        env_cfg, _ = task_registry.get_cfgs("gente_biped")
        env_cfg.terrain.num_rows, env_cfg.terrain.num_cols = 1, 2
        env_cfg.terrain.terrain_types = ["soil:preset=peat", "soil:preset=mud"]
        env_cfg.terrain.terrain_proportions = [0.5, 0.5]
        record = json.loads(json.dumps(resolved_terrain(SimpleNamespace(terrain=Terrain(env_cfg.terrain, 2),
                                                                        cfg=env_cfg))))
    finally:
        SOIL_PRESETS.pop("peat")
    assert sorted(record["soils"]) == ["mud", "peat"]
    assert record["soils"]["peat"]["kphi"] == [2.0e5, 0.0] and record["soils"]["peat"]["mu"] == [0.4, 0.04]
    assert record["soils"]["mud"]["n"] == list(SOIL_PRESETS["mud"].n)


TINY = ["--task", "gente_biped_flat", "--device", "cpu", "--num_envs", "1", "--max_iterations", "50", "--set",
        "runner.num_steps_per_env=2", "--set", "algorithm.num_mini_batches=1", "--set", "actor.hidden_dims=[8]",
        "--set", "critic.hidden_dims=[8]", "--set", "runner.save_interval=1000"]


def test_a_stop_before_the_first_iteration_finishes_saves_nothing(tmp_path, monkeypatch, capsys):
    """Ctrl-C in a run's first iteration: no iteration finished, so no model_0 claiming one (its weights would be
    the untrained ones, and a --resume would go on at iteration 1)."""
    from rsl_rl.runners import OnPolicyRunner

    from legged_gente.scripts import train as train_script

    def interrupted(self, *args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setenv("GENTE_LOG_ROOT", str(tmp_path))
    monkeypatch.setattr(OnPolicyRunner, "learn", interrupted)
    with pytest.raises(SystemExit) as info:
        train_script.main(TINY)
    assert info.value.code == 128 + signal.SIGINT
    assert "Interrupted before the first iteration finished: nothing to save" in capsys.readouterr().out
    run = next((tmp_path / "gente_biped_flat").iterdir())
    assert list(run.glob("model_*.pt")) == []


def test_a_stop_after_an_iteration_saves_that_iteration(tmp_path, monkeypatch, capsys):
    """Ctrl-C after iteration 0 was logged: model_0 with iter 0, so --resume goes on at iteration 1."""
    from legged_gente.scripts import train as train_script
    from legged_gente.utils.episode_logger import DeferredLogger

    logged = DeferredLogger.log

    def log_then_interrupt(self, *args, **kwargs):
        logged(self, *args, **kwargs)
        raise KeyboardInterrupt

    monkeypatch.setenv("GENTE_LOG_ROOT", str(tmp_path))
    monkeypatch.setattr(DeferredLogger, "log", log_then_interrupt)
    with pytest.raises(SystemExit):
        train_script.main(TINY)
    assert "Interrupted: saved" in capsys.readouterr().out
    run = next((tmp_path / "gente_biped_flat").iterdir())
    assert [p.name for p in run.glob("model_*.pt")] == ["model_0.pt"]
    assert load_checkpoint(run / "model_0.pt")["iter"] == 0


def _run_with_small_networks(runner, root: Path) -> Path:
    """A run folder of gente_biped_flat whose networks (8 wide, recorded in its config.json) are not the task's."""
    run = root / "gente_biped_flat" / "2026-01-04_00-00-00"
    run.mkdir(parents=True)
    runner.current_learning_iteration = 4
    runner.save(str(run / "model_4.pt"))
    sizes = {"hidden_dims": [8]}
    (run / "config.json").write_text(json.dumps({"train": {"actor": sizes, "critic": sizes}}))
    return run


def test_a_run_with_networks_of_its_own_resumes_and_plays(runner, tmp_path):
    """A run trained with --set actor.hidden_dims=... or from a --pretrained policy (32 x 32) could not be resumed,
    played or viewed: the runner was built with the task's default networks, which its checkpoint does not fit."""
    run = _run_with_small_networks(runner, tmp_path)
    env = runner.env
    resumed = parse_args(build_parser("test"), ["--task", "gente_biped_flat", "--device", "cpu", "--resume"])
    loaded, train_cfg, _ = task_registry.make_alg_runner(env, "gente_biped_flat", resumed, log_root=tmp_path)
    assert loaded.loaded_checkpoint == run / "model_4.pt" and train_cfg.actor.hidden_dims == [8]
    _, play_cfg = task_registry.get_play_cfgs("gente_biped_flat", 1)  # gente-play and gente-view --play
    play_cfg.runner.resume = True
    played, _, _ = task_registry.make_alg_runner(env, "gente_biped_flat", train_cfg=play_cfg, log_root=tmp_path)
    assert played.loaded_checkpoint == run / "model_4.pt"


def test_resuming_refuses_other_network_sizes_in_one_line(runner, tmp_path):
    _run_with_small_networks(runner, tmp_path)
    args = parse_args(build_parser("test"), ["--task", "gente_biped_flat", "--device", "cpu", "--resume",
                                             "--set", "actor.hidden_dims=[64,64]"])
    with pytest.raises(ValueError, match=r"--set actor.hidden_dims=\[64,64\]: a resumed run keeps the networks "
                                         r"recorded in .*config.json; leave it out") as error:
        task_registry.make_alg_runner(runner.env, "gente_biped_flat", args, log_root=tmp_path)
    assert "\n" not in str(error.value)


def test_the_code_version_counts_changes_to_tracked_files_only(tmp_path, monkeypatch):
    """The README's generate examples write terrains/ into the checkout: an untracked file is no change to the code,
    so git_dirty stays False; a changed tracked file makes it True. Checked on a checkout of its own."""
    import shutil
    import subprocess

    from legged_gente.utils import provenance

    repo = tmp_path / "checkout"
    (repo / "legged_gente" / "utils").mkdir(parents=True)
    (repo / "legged_gente" / "__init__.py").write_text("")
    shutil.copy(provenance.__file__, repo / "legged_gente" / "utils" / "provenance.py")
    git = lambda *cmd: subprocess.run(["git", "-C", str(repo), *cmd], check=True, capture_output=True)  # noqa: E731
    git("init", "-q")
    git("add", ".")
    git("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "c")
    monkeypatch.setattr(provenance, "__file__", str(repo / "legged_gente" / "utils" / "provenance.py"))
    (repo / "terrains").mkdir()
    (repo / "terrains" / "spec.json").write_text("{}")
    clean = provenance.code_version()
    assert clean["git_dirty"] is False
    (repo / "legged_gente" / "__init__.py").write_text("# changed\n")
    dirty = provenance.code_version()
    assert dirty["git_dirty"] is True
    # the source digest tells the two states apart (a dirty flag does not), and names code outside git too
    assert dirty["source_sha256"] != clean["source_sha256"] and len(clean["source_sha256"]) == 64
    shutil.rmtree(repo / ".git")
    outside = provenance.code_version()
    assert outside["git_commit"] is None and outside["source_sha256"] == dirty["source_sha256"]


def test_resuming_on_another_terrain_than_the_run_s_is_said(runner, tmp_path, monkeypatch):
    """--resume builds the terrain of its own flags: a run trained on a generated tile resumed without its --terrain
    went on on the task's default terrain, and the console said the curriculum was restored. Now a one-line warning
    names the change; resumed as it was, nothing is said."""
    from legged_gente.scripts import train as train_script
    from legged_gente.scripts.train import resolved_terrain, terrain_change

    generated = {"mode": "generated", "tile_size_m": [20.0, 20.0], "resolution_m": 0.1, "tiles": [["mud_creek"]],
                 "generated_specs": {"/t/spec.json": {"calls": []}}}
    plane = {"mode": "plane"}
    assert terrain_change(generated, generated) is None and terrain_change(None, plane) is None
    said = terrain_change(generated, plane)
    assert said.startswith("--resume: the resumed run trained on generated (1 rows of tiles) terrain; this run "
                           "builds plane (0 rows of tiles), its mode, tile_size_m, resolution_m, tiles, "
                           "generated_specs other than")
    run = _run_with_small_networks(runner, tmp_path)
    record = json.loads((run / "config.json").read_text())
    (run / "config.json").write_text(json.dumps(record | {"terrain": generated}))
    monkeypatch.setenv("GENTE_LOG_ROOT", str(tmp_path))
    argv = [*TINY[:6], "--max_iterations", "1", "--resume", "--set", "runner.num_steps_per_env=2", "--set",
            "algorithm.num_mini_batches=1"]
    with pytest.warns(UserWarning, match=r"^--resume: the resumed run trained on generated"):
        train_script.main(argv)
    # resuming the run just made, whose config.json records this very terrain: nothing is said
    assert json.loads(max((tmp_path / "gente_biped_flat").iterdir()).joinpath("config.json").read_text())[
        "terrain"] == resolved_terrain(runner.env)
    with warnings.catch_warnings():
        warnings.filterwarnings("error", message="--resume")
        train_script.main(argv)


def test_train_writes_its_run_under_log_root_and_resumes_from_there(tmp_path, monkeypatch):
    """gente-train --log_root, as gente-play and gente-view take it: the run goes there, and --resume finds it
    there, not under $GENTE_LOG_ROOT."""
    from legged_gente.scripts import train as train_script

    monkeypatch.setenv("GENTE_LOG_ROOT", str(tmp_path / "elsewhere"))
    root = tmp_path / "mine"
    short = [*TINY[:6], "--max_iterations", "1", "--set", "runner.num_steps_per_env=2", "--set",
             "algorithm.num_mini_batches=1", "--log_root", str(root)]
    train_script.main([*short, "--set", "actor.hidden_dims=[8]", "--set", "critic.hidden_dims=[8]"])
    runs = sorted((root / "gente_biped_flat").iterdir())
    assert len(runs) == 1 and list(runs[0].glob("model_*.pt")) and not (tmp_path / "elsewhere").exists()
    train_script.main([*short, "--resume"])  # the networks: the resumed run's config.json
    assert len(sorted((root / "gente_biped_flat").iterdir())) == 2 and not (tmp_path / "elsewhere").exists()
    # the resumed run names the checkpoint it continued from: "latest" changes as runs are added
    continued = json.loads((sorted((root / "gente_biped_flat").iterdir())[1] / "config.json").read_text())
    assert continued["resumed_from"] == str((runs[0] / "model_0.pt").resolve())
