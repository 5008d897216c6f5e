"""tools/forces_cpu_timing.py (docs/forces.md) still runs against the env and the simulator: one robot, one block
of one substep per measurement."""


def test_it_times_the_four_measurements(load_file, capsys):
    tool = load_file("tools/forces_cpu_timing.py")
    tool.main(["--task", "gente_biped", "--num_envs", "1", "--repeats", "1", "--block", "1"])
    out = capsys.readouterr().out
    for line in ("step, forces on", "step, forces off", "collision ", "collision, no terrain", "forces' cost"):
        assert line in out, out
