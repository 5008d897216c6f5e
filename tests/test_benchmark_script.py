"""gente-benchmark end to end on the CPU with tiny sizes: a well-formed table and CSV."""

import csv

from legged_gente.scripts import benchmark


def test_benchmark_prints_and_writes_a_table(tmp_path, capsys):
    out = tmp_path / "bench.csv"
    benchmark.main(["--task", "gente_biped_flat", "--num_envs", "2", "3", "--steps", "2", "--iterations", "1",
                    "--device", "cpu", "--csv", str(out)])
    printed = capsys.readouterr().out
    assert "device: CPU" in printed and "raw substeps/s" in printed
    rows = list(csv.DictReader(open(out)))
    assert [int(r["num_envs"]) for r in rows] == [2, 3]
    for r in rows:
        for key in ("raw_substeps_per_s", "env_steps_per_s", "ppo_steps_per_s"):
            assert float(r[key]) > 0.0
        assert float(r["env_over_raw"]) == float(r["env_steps_per_s"]) / (float(r["raw_substeps_per_s"]) / 4)


def test_force_kernels_are_timed_on_a_terrain_with_materials(capsys):
    rows = benchmark.run("gente_biped", [3], "cpu", steps=2, iterations=0)
    assert 0.0 < rows[0]["forces_share"] < 1.0
    assert 0.0 <= rows[0]["forces_slowdown"] < 1.0
