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
