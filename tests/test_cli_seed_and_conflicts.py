"""A seed out of range and a flag that the others make pointless are one line naming the fix (exit 2), refused
before anything is built or measured."""

import pytest
from test_cli_errors import one_line_error

from legged_gente.scripts import benchmark as benchmark_script
from legged_gente.scripts import evaluate as evaluate_script
from legged_gente.scripts import play as play_script
from legged_gente.scripts import train as train_script


def never(*args, **kwargs):
    raise AssertionError("the command ran past its flag checks")


# torch.manual_seed takes neither; numpy and gente-generate take [0, 2**32)
@pytest.mark.parametrize("seed", ["-1", str(2**32), "99999999999999999999"])
def test_train_refuses_a_seed_out_of_range(capsys, monkeypatch, seed):
    monkeypatch.setattr(train_script, "train", never)
    line = one_line_error(capsys, train_script.main, ["--device", "cpu", "--num_envs", "1", "--seed", seed])
    assert line == f"gente-train: error: argument --seed: must be in [0, 2**32), got {seed}"


@pytest.mark.parametrize("seed", ["-1", str(2**32), "99999999999999999999"])
def test_evaluate_refuses_a_seed_out_of_range(capsys, monkeypatch, tmp_path, seed):
    monkeypatch.setattr(evaluate_script, "evaluate", never)
    line = one_line_error(capsys, evaluate_script.main, ["--baseline", "zero", "--device", "cpu", "--out",
                                                         str(tmp_path), "--seed", seed])
    assert line == f"gente-evaluate: error: argument --seed: must be in [0, 2**32), got {seed}"


def test_a_seed_in_range_passes(monkeypatch, tmp_path):
    seen = []
    monkeypatch.setattr(train_script, "train", lambda args: seen.append(args.seed))
    monkeypatch.setattr(evaluate_script, "evaluate", lambda args: seen.append(args.seed))
    train_script.main(["--device", "cpu", "--num_envs", "1", "--seed", str(2**32 - 1)])
    evaluate_script.main(["--baseline", "zero", "--device", "cpu", "--out", str(tmp_path), "--seed", "0"])
    assert seen == [2**32 - 1, 0]


def test_benchmark_profile_envs_needs_profile(capsys, monkeypatch):
    monkeypatch.setattr(benchmark_script, "run", never)
    line = one_line_error(capsys, benchmark_script.main, ["--device", "cpu", "--num_envs", "2", "--profile_envs", "2"])
    assert line == ("gente-benchmark: error: --profile_envs picks the num_envs that --profile profiles; add "
                    "--profile TRACE_JSON or leave it out")


def test_benchmark_checks_its_flags_before_building_the_terrain_grid(capsys, monkeypatch):
    import legged_gente.terrain.benchmark as terrain_benchmark

    monkeypatch.setattr(terrain_benchmark, "benchmark_grid", never)
    line = one_line_error(capsys, benchmark_script.main, ["--device", "cpu", "--num_envs", "2", "--terrain_build",
                                                          "--check_sync"])
    assert line == "gente-benchmark: error: --check_sync needs a CUDA device (--device cuda)"


def test_play_refuses_a_seed_out_of_range(capsys):
    line = one_line_error(capsys, play_script.main, ["--device", "cpu", "--num_envs", "1", "--seed", "-1"])
    assert line == "gente-play: error: argument --seed: must be in [0, 2**32), got -1"
