"""tools/diagnose_divergence.py on the CPU: a world made to diverge is found, at its step, with the env's reason."""

import torch


def test_a_world_given_a_runaway_joint_is_reported_with_its_reason_and_step(load_file):
    tool = load_file("tools/diagnose_divergence.py")
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import Evaluation

    items = load_benchmark("flat")
    evaluation = Evaluation("gente_biped", items, robots_per_terrain=2, device="cpu", episode_length_s=0.2)
    env = evaluation.env
    calls = []

    def policy(obs):
        calls.append(1)
        if len(calls) == 3:  # before the third step: robot 1's first leg joint spins at 10x sim.max_qvel
            env.sim.qvel[1, 6] = 10.0 * env.max_qvel
        return torch.zeros(env.num_envs, env.num_actions)

    rows, summary = tool.diagnose(evaluation, policy)
    assert [(r["world"], r["step"], r["reason"], r["flagged_by_env"]) for r in rows] == [(1, 3, "qvel>max_qvel", True)]
    assert tuple(rows[0]) == tool.COLUMNS  # the CSV's header names every value of a row, in order
    assert summary["worlds"] == 2 and summary["steps"] == evaluation.num_steps
    assert 0 < summary["max_nacon"] <= summary["naconmax"]
    assert "diverged robots: 1" in tool.report(rows, summary)


def test_seed_reaches_the_evaluation_as_in_gente_evaluate(load_file, monkeypatch):
    """--seed picks the same commands and spawn points as gente-evaluate's --seed."""
    tool = load_file("tools/diagnose_divergence.py")
    import legged_gente.evaluation.evaluator as evaluator

    seen = []

    class Stop(Exception):
        pass

    def recording_evaluation(*args):
        seen.append(args)
        raise Stop

    monkeypatch.setattr(evaluator, "Evaluation", recording_evaluation)
    try:
        tool.main(["--task", "gente_biped", "--benchmark", "flat", "--seed", "7"])
    except Stop:
        pass
    assert len(seen) == 1 and seen[0][-1] == 7


def test_contacts_and_a_lower_launch_speed_show_what_the_terrain_did(load_file):
    """--contacts: the diverged robot's terrain contacts before its step (the biped stands on its soles), and that
    its world was reset; --launch_speed: a base faster than it counts as launched, the env not flagging it."""
    tool = load_file("tools/diagnose_divergence.py")
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import Evaluation

    evaluation = Evaluation("gente_biped", load_benchmark("flat"), robots_per_terrain=2, device="cpu",
                            episode_length_s=0.4)
    env = evaluation.env
    calls = []

    def policy(obs):
        calls.append(1)
        if len(calls) == 12:  # landed on its soles by then
            env.sim.qvel[1, 6] = 10.0 * env.max_qvel
        return torch.zeros(env.num_envs, env.num_actions)

    rows, summary = tool.diagnose(evaluation, policy, contacts=True)
    assert [(r["world"], r["step"]) for r in rows] == [(1, 12)]
    (block,) = summary["contacts"]
    lines = block.splitlines()
    assert lines[0].startswith("world 1 (") and "step 12" in lines[0]
    soles = [line for line in lines[1:-1] if "sole" in line]
    normals = [[float(v) for v in line.split("normal (")[1].rstrip(")").split(",")] for line in soles]
    assert normals and all(abs(x) < 0.01 and abs(y) < 0.01 and z > 0.99 for x, y, z in normals)  # flat: straight up
    assert lines[-1].strip() == "after step 12: its world was reset in the step"
    assert block in tool.report(rows, summary)

    # a speed every robot passes while it settles: launched, not flagged, with its contacts after the step too
    calls.clear()
    rows, summary = tool.diagnose(evaluation, lambda obs: torch.zeros(env.num_envs, env.num_actions),
                                  launch_speed=1e-6, contacts=True)
    assert {r["world"] for r in rows} == {0, 1} and all(r["launched"] and not r["flagged_by_env"] for r in rows)
    assert all(len(b.split("after step")) == 3 for b in summary["contacts"])  # before, and after the step
    assert "base over 1e-06 m/s" in tool.report(rows, summary)


def test_a_launch_speed_that_is_not_a_speed_is_refused(load_file, capsys):
    tool = load_file("tools/diagnose_divergence.py")
    for bad in ("0", "-1", "inf", "nan"):
        try:
            tool.main(["--task", "gente_biped", "--benchmark", "flat", "--launch_speed", bad])
        except SystemExit as exit:
            assert exit.code == 2
        err = capsys.readouterr().err.strip().splitlines()[-1]
        assert f"--launch_speed {float(bad)} must be a finite speed > 0 m/s" in err
