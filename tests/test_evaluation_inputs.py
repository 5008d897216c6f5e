"""gente-evaluate's episode timing and its bad inputs: whole episodes get no extra step, and a time, a speed or an
item list it cannot use is a one-line error, never a traceback or a silent run."""

import json
import math
from pathlib import Path

import pytest
import torch

BENCHMARK = Path(__file__).resolve().parents[1] / "legged_gente" / "benchmarks" / "gente100"
ITEM = "image_05_sketch_blocks"


def test_an_episode_of_whole_policy_steps_gets_no_extra_step():
    """gente_biped's policy step is sim.dt 0.005 s x decimation 4 = 0.02 s: 0.14 s is 7 steps (0.14 / 0.02 is
    7.000000000000001 in binary floating point), 2.22 s is 111; a partial last step counts whole: 0.15 s is 8."""
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import Evaluation, episode_steps

    dt = 0.005 * 4
    assert [episode_steps(s, dt) for s in (0.14, 2.22, 0.15, 10.0)] == [7, 111, 8, 500]
    evaluation = Evaluation("gente_biped", load_benchmark(str(BENCHMARK), [ITEM]), 1, "cpu", 0.14)
    assert evaluation.num_steps == 7
    result = evaluation.run(lambda obs: torch.zeros(1, evaluation.env.num_actions), settle_s=0.04, progress=False)
    assert result.traces["pos"].shape[1] == 7
    assert result.params["episode_length_s"] == pytest.approx(0.14)


def test_an_infinite_episode_or_settle_time_is_a_one_line_error(tmp_path, capsys):
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import Evaluation
    from legged_gente.scripts.evaluate import main

    with pytest.raises(SystemExit) as exit_info:
        main(["--task", "gente_biped", "--baseline", "zero", "--benchmark", str(BENCHMARK), "--items", ITEM,
              "--episode_s", "inf", "--device", "cpu", "--out", str(tmp_path), "--no_progress"])
    assert exit_info.value.code == 2
    error = capsys.readouterr().err.strip()
    assert error.startswith("gente-evaluate: error: episode_s") and "inf" in error and "\n" not in error
    evaluation = Evaluation("gente_biped", load_benchmark(str(BENCHMARK), [ITEM]), 1, "cpu", 0.1)
    with pytest.raises(ValueError, match="settle_s must be"):
        evaluation.run(lambda obs: torch.zeros(1, evaluation.env.num_actions), settle_s=math.inf, progress=False)


def test_an_infinite_waypoint_speed_is_refused_by_name():
    """--speed inf made the default waypoint episode 1.5 * 12.8 m / inf = 0 s, refused as an episode_s nobody
    gave; with --episode_s given, it commanded every robot an infinite forward velocity."""
    from legged_gente.evaluation.tasks import WaypointTask, waypoint_episode_s

    with pytest.raises(ValueError, match="speed must be a finite"):
        waypoint_episode_s(math.inf)
    with pytest.raises(ValueError, match="speed must be a finite"):
        WaypointTask(torch.zeros(1, 4, 2), reach_distance=1.0, speed=math.inf)


def test_an_item_given_twice_is_refused(tmp_path):
    """Report rows are named by item id (and compared by it): two tiles of one id cannot be told apart."""
    from legged_gente.evaluation.benchmark import load_benchmark

    with pytest.raises(ValueError, match=f"{ITEM}.*more than once"):
        load_benchmark(str(BENCHMARK), [ITEM, "text_02_wide_river_strong_current", ITEM])
    manifest = json.loads((BENCHMARK / "manifest.json").read_text())
    first = manifest["items"][0]
    manifest["items"] = [first, {**first, "spec": manifest["items"][1]["spec"]}]
    (tmp_path / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(ValueError, match=f"{first['id']}.*more than once"):
        load_benchmark(tmp_path)


def test_waypoint_paths_turn_back_by_the_runs_own_tile_edge_margin():
    """4 waypoints 1.8 m apart need 7.2 m. A robot 11 m from its tile's low x edge has 9 m ahead: 8.5 m inside a
    0.5 m margin, enough; 7.0 m inside a 2 m margin, not enough, and 9 m behind it, so with that margin its path
    runs towards -x (where the measured episode does not end at the margin first)."""
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.evaluation.evaluator import Evaluation

    evaluation = Evaluation("gente_biped", load_benchmark("gente100", ["text_02_wide_river_strong_current"]), 1,
                            "cpu", 0.2, "waypoints")
    x_lo = float(evaluation.tile_bounds(0.0)[0, 0])
    evaluation.env.env_origins[0, 0] = x_lo + 11.0
    ahead = evaluation.make_task(tile_edge_margin=0.5).waypoints[0, :, 0] - (x_lo + 11.0)
    behind = evaluation.make_task(tile_edge_margin=2.0).waypoints[0, :, 0] - (x_lo + 11.0)
    assert torch.allclose(ahead, torch.tensor([1.8, 3.6, 5.4, 7.2]))
    assert torch.allclose(behind, torch.tensor([-1.8, -3.6, -5.4, -7.2]))


def test_a_generated_terrain_folder_names_its_spec_not_a_manifest(tmp_path):
    from legged_gente.evaluation.benchmark import load_benchmark

    (tmp_path / "spec.json").write_text("{}")  # what gente-generate writes, beside its terrain_cfg.py
    with pytest.raises(FileNotFoundError, match=r"holds one generated terrain, not a benchmark .*pass its .*spec\.json"):
        load_benchmark(tmp_path)


def test_a_settle_time_as_long_as_the_episode_is_refused_before_the_envs_are_built(tmp_path, capsys, monkeypatch):
    """--episode_s 1 with the default --settle_s 1 leaves no step to measure: one line naming the flag, before the
    evaluation builds its envs and loads the policy."""
    import legged_gente.evaluation.evaluator as evaluator
    from legged_gente.scripts.evaluate import main

    monkeypatch.setattr(evaluator, "Evaluation", lambda *a, **k: pytest.fail("the envs were built"))
    with pytest.raises(SystemExit) as exit_info:
        main(["--task", "gente_biped", "--baseline", "zero", "--benchmark", str(BENCHMARK), "--items", ITEM,
              "--episode_s", "1", "--device", "cpu", "--out", str(tmp_path), "--no_progress"])
    assert exit_info.value.code == 2
    assert capsys.readouterr().err.strip().startswith("gente-evaluate: error: --settle_s 1.0 s leaves nothing")


def test_one_generated_terrain_is_evaluated_through_its_spec_json(tmp_path, capsys):
    """gente-evaluate --benchmark terrains/x said 'pass its spec.json', and the spec.json was then refused: a spec is
    now a benchmark of one item, its id the spec's name and its kind text (image when an image made it)."""
    import json

    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.scripts.evaluate import main

    folder = tmp_path / "mudcreek"
    folder.mkdir()
    (folder / "spec.json").write_text(json.dumps({
        "version": 1, "name": "mud_creek", "size_x": 8.0, "size_y": 8.0, "resolution": 0.1, "seed": 0,
        "calls": [{"tool": "soil", "region": "left", "params": {"preset": "mud"}}],
        "source": {"text": "a muddy creek"}, "backend": "planner", "model": None}))
    with pytest.raises(SystemExit):
        main(["--task", "gente_biped", "--baseline", "zero", "--benchmark", str(folder), "--out", str(tmp_path / "a")])
    assert f"pass its {folder / 'spec.json'}" in capsys.readouterr().err
    (item,) = load_benchmark(folder / "spec.json")
    assert (item.id, item.kind, item.prompt) == ("mud_creek", "text", "a muddy creek")
    main(["--task", "gente_biped", "--baseline", "zero", "--benchmark", str(folder / "spec.json"), "--device", "cpu",
          "--robots_per_terrain", "1", "--episode_s", "0.1", "--settle_s", "0", "--out", str(tmp_path / "b"),
          "--no_progress"])
    rows = (tmp_path / "b" / "report.csv").read_text().splitlines()
    assert rows[1].startswith("terrain,mud_creek,text,soil,1,")


def test_all_robots_told_to_stand_names_the_flag_that_scores_moving_ones(tmp_path, capsys):
    from legged_gente.scripts.evaluate import main

    main(["--task", "gente_biped", "--baseline", "zero", "--benchmark", str(BENCHMARK), "--items", ITEM,
          "--stand_fraction", "1", "--robots_per_terrain", "2", "--episode_s", "0.1", "--settle_s", "0",
          "--device", "cpu", "--out", str(tmp_path), "--no_progress"])
    out = capsys.readouterr().out
    assert "lower --stand_fraction below 1 to score moving ones" in out and "--robots_per_terrain" not in out


def test_an_unusable_opengl_backend_says_when_leaving_it_unset_helps(capsys, monkeypatch):
    from legged_gente.utils.args import _opengl_error

    monkeypatch.setenv("MUJOCO_GL", "osmesa")
    with pytest.raises(SystemExit):
        _opengl_error("gente-play", OSError("libOSMesa.so: cannot open shared object file"))
    err = capsys.readouterr().err
    assert "MUJOCO_GL=egl" in err and "unset for a run that renders nothing (no --video" in err


def test_gente_view_replays_the_traces_of_one_evaluated_spec_json(tmp_path):
    """gente-evaluate --benchmark spec.json scores one terrain; gente-view refused that spec.json with --traces ("give
    its folder") and the folder ("pass its spec.json"). The spec.json replays now."""
    from legged_gente.scripts.evaluate import main as evaluate
    from legged_gente.scripts.view import _benchmark_items, build_arg_parser
    from legged_gente.utils.args import parse_args

    spec = tmp_path / "creek" / "spec.json"
    spec.parent.mkdir()
    spec.write_text(json.dumps({
        "version": 1, "name": "creek", "size_x": 8.0, "size_y": 8.0, "resolution": 0.1, "seed": 0,
        "calls": [{"tool": "soil", "region": "left", "params": {"preset": "mud"}}],
        "source": {"text": "a muddy creek"}, "backend": "planner", "model": None}))
    evaluate(["--task", "gente_biped", "--baseline", "zero", "--benchmark", str(spec), "--device", "cpu",
              "--robots_per_terrain", "1", "--episode_s", "0.1", "--settle_s", "0", "--out", str(tmp_path / "ev"),
              "--no_progress"])
    args = parse_args(build_arg_parser(), [str(spec), "--traces", str(tmp_path / "ev" / "traces.npz")])
    items, trace = _benchmark_items(spec, args)
    assert [item.label for item in items] == ["creek"] and trace["qpos"].shape[0] == 5  # 0.1 s of 0.02 s steps
    import socket

    from legged_gente.scripts.view import main as view

    with socket.socket() as free:
        free.bind(("127.0.0.1", 0))
        port = free.getsockname()[1]
    view([str(spec), "--traces", str(tmp_path / "ev" / "traces.npz"), "--headless", "--seconds", "0",
          "--port", str(port)])  # served and stopped: no "give its folder" refusal
