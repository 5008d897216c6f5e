"""What gente-evaluate reports, worked out by hand on small synthetic inputs (docs/evaluation.md, "Metrics"):
categories of a spec, the report's denominators and weights, the recorder's time window and frames, the CSV, and
the paired comparison's inputs. Nothing here is simulated: the recorder reads a stand-in for the env's state."""

import csv
import math
from types import SimpleNamespace

import numpy as np
import pytest
import torch

from legged_gente.evaluation.benchmark import Item
from legged_gente.evaluation.evaluator import Recorder, RunResult
from legged_gente.evaluation.report import build_report, categories_of, summarize_robots, success, write_reports
from legged_gente.generation.spec import TerrainSpec
from recorder_stand_in import record_step, stand_in_env


def _spec(*calls, name="t"):
    return TerrainSpec.from_dict({"version": 1, "name": name, "size_x": 20.0, "size_y": 20.0, "resolution": 0.1,
                                  "seed": 0, "calls": list(calls), "source": {}, "backend": "planner", "model": None})


def _flat(height, region="full", mode="set"):
    return {"tool": "flat", "region": region, "mode": mode, "params": {"height": height}}


# ------------------------------------------------------------------------------------------------ categories
def test_a_whole_tile_raised_or_lowered_is_no_obstacle():
    """A `flat` call over the whole tile adds a constant (mode add) or sets one level (mode set): no block, no step,
    no relief. GenTe's transcripts raise their whole tile so (gente_original: 227 such calls); only a `flat` over
    part of the tile makes a raised block or a sunken floor, an obstacle."""
    ground = {"tool": "natural_ground", "region": "full", "mode": "add",
              "params": {"amplitude": 0.5, "wavelength": 1.0, "octaves": 6, "persistence": 0.1, "platform": 0.0}}
    whole = {"x0": 0.0, "y0": 0.0, "x1": 20.0, "y1": 20.0}  # the whole tile as a rectangle
    assert categories_of(_spec(_flat(2.0, mode="add"), ground)) == []
    assert categories_of(_spec(_flat(-1.5, whole, mode="add"), _flat(0.3, mode="set"))) == []
    # a block 0.3 m high on the back right quadrant, and a floor sunk by 0.5 m on a 4 m x 4 m square
    assert categories_of(_spec(_flat(0.3, "back_right"))) == ["obstacles"]
    assert categories_of(_spec(_flat(2.0, mode="add"), _flat(-0.5, {"x0": 8, "y0": 8, "x1": 12, "y1": 12},
                                                             mode="add"))) == ["obstacles"]
    assert categories_of(_spec(_flat(0.0, "back_right"))) == []  # level ground at 0 m: no category


# ------------------------------------------------------------------------------------ report's denominators
def _metrics(**columns):
    n = len(next(iter(columns.values())))
    base = {"fell": np.zeros(n, bool), "diverged": np.zeros(n, bool), "left_tile": np.zeros(n, bool),
            "standing": np.zeros(n, bool), "tracking_error": np.full(n, 0.1), "progress": np.full(n, 0.9),
            "heading_error": np.full(n, np.nan), "distance": np.ones(n), "displacement": np.ones(n),
            "collisions": np.zeros(n), "energy": np.ones(n), "finished": np.zeros(n, bool), "time_s": np.ones(n)}
    return base | {k: np.asarray(v) for k, v in columns.items()}


def test_rates_count_every_robot_and_means_only_the_robots_that_did_not_diverge():
    """Five robots: 0 succeeds; 1 fell; 2 diverged (its numbers absurd); 3 tracks badly (0.4 m/s); 4 covers half
    the distance. success 1/5, fall rate 1/5 (the diverged robot is in both denominators, counted apart); the
    means over robots 0, 1, 3, 4: tracking (0.1 + 0.2 + 0.4 + 0.1) / 4 = 0.2 m/s, progress (0.9 + 0.3 + 0.8 +
    0.5) / 4 = 0.625; energy per metre a ratio of sums, (100 + 50 + 300 + 10) J / (2 + 0.5 + 3 + 0.5) m = 76.67
    J/m, not the mean of the ratios (50 + 100 + 100 + 20) / 4 = 67.5."""
    m = _metrics(fell=[False, True, False, False, False], diverged=[False, False, True, False, False],
                 tracking_error=[0.1, 0.2, 300.0, 0.4, 0.1], progress=[0.9, 0.3, -40.0, 0.8, 0.5],
                 distance=[2.0, 0.5, 1e4, 3.0, 0.5], energy=[100.0, 50.0, 1e9, 300.0, 10.0],
                 left_tile=[False, False, False, True, False])
    ok = success(m, "velocity")
    assert ok.tolist() == [True, False, False, False, False]
    s = summarize_robots(m, ok)
    assert s["robots"] == 5 and s["success_rate"] == pytest.approx(0.2) and s["fall_rate"] == pytest.approx(0.2)
    assert s["falls"] == 1 and s["diverged"] == 1 and s["left_tile"] == 1
    assert s["tracking_error"] == pytest.approx(0.2) and s["progress"] == pytest.approx(0.625)
    assert s["distance"] == pytest.approx(1.5)
    assert s["energy_per_m"] == pytest.approx(460.0 / 6.0)


def test_groups_pool_their_robots_and_stand_still_robots_are_scored_apart():
    """Two terrains, four robots each. Terrain A (water): 2 of 3 moving robots succeed, robot 3 stands still and
    stands. Terrain B (water + obstacles): 1 of 4 succeeds. The water group pools robots: 3 of 7 = 42.9 %, not the
    mean of the terrains' rates (66.7 + 25) / 2 = 45.8 %; obstacles holds B alone (25 %); stand_still holds the one
    standing robot of terrain A (100 %); overall = water here."""
    items = [Item("a", "text", None), Item("b", "image", None)]
    specs = {"a": _spec({"tool": "water", "region": "back", "params": {"depth": 0.3}}),
             "b": _spec({"tool": "water", "region": "back", "params": {"depth": 0.3}}, _flat(0.3, "front_left"))}
    items = [SimpleNamespace(id=i.id, kind=i.kind, spec=(lambda s=specs[i.id]: s)) for i in items]
    m = _metrics(tracking_error=[0.1, 0.1, 0.4, 0.05, 0.1, 0.4, 0.4, 0.4],
                 progress=[0.9, 0.9, 0.9, np.nan, 0.9, 0.9, 0.9, 0.9],
                 standing=[False, False, False, True, False, False, False, False])
    result = RunResult(np.repeat([0, 1], 4), m, {}, "velocity", {})
    report = build_report(result, items)
    a, b = report["terrains"]
    assert (a["robots"], b["robots"]) == (3, 4)
    assert a["success_rate"] == pytest.approx(2 / 3) and b["success_rate"] == pytest.approx(1 / 4)
    groups = report["groups"]
    assert groups["water"]["robots"] == 7 and groups["water"]["success_rate"] == pytest.approx(3 / 7)
    assert groups["obstacles"]["terrains"] == 1 and groups["obstacles"]["success_rate"] == pytest.approx(0.25)
    assert groups["text"]["success_rate"] == pytest.approx(2 / 3) and groups["image"]["success_rate"] == 0.25
    still = groups["stand_still"]
    assert (still["robots"], still["terrains"], still["success_rate"]) == (1, 1, 1.0)
    assert still["tracking_error"] == pytest.approx(0.05)
    assert math.isnan(still["progress"])
    assert report["overall"]["robots"] == 7 and report["overall"]["success_rate"] == pytest.approx(3 / 7)


def test_the_csv_holds_the_documented_columns_and_leaves_undefined_values_empty(tmp_path):
    """docs/evaluation.md: `row` (terrain, group or overall), `name`, `kind`, `categories` joined by +, then the
    metrics; an undefined value is empty. Terrain b has no moving robot: its rates and means are empty."""
    items = [SimpleNamespace(id="a", kind="text", spec=lambda: _spec(_flat(0.3, "back_right"),
                                                                      {"tool": "soil", "region": "front",
                                                                       "params": {"preset": "mud"}})),
             SimpleNamespace(id="b", kind="image", spec=lambda: _spec(_flat(0.0)))]
    m = _metrics(standing=[False, False, True, True], progress=[0.9, 0.5, np.nan, np.nan])
    report = build_report(RunResult(np.repeat([0, 1], 2), m, {}, "velocity", {}), items)
    _, path = write_reports(report, tmp_path)
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0]) == ["row", "name", "kind", "categories", "terrains", "robots", "success_rate",
                             "tracking_error", "progress", "heading_error", "distance", "displacement", "collisions",
                             "falls", "fall_rate", "diverged", "energy_per_m", "left_tile"]
    a, b = rows[0], rows[1]
    assert (a["row"], a["name"], a["kind"], a["categories"]) == ("terrain", "a", "text", "soil+obstacles")
    assert a["robots"] == "2" and float(a["success_rate"]) == 0.5 and float(a["progress"]) == pytest.approx(0.7)
    assert b["robots"] == "0" and b["success_rate"] == "" and b["tracking_error"] == "" and b["categories"] == ""
    assert a["heading_error"] == ""  # yaw-rate mode or none measured: undefined, not 0
    assert [r["row"] for r in rows[2:]] == ["group"] * 5 + ["overall"]
    assert [r["name"] for r in rows[2:]] == ["text", "image", "soil", "obstacles", "stand_still", "all"]
    # how many terrains each row covers: one each; a, the text one, has soil and obstacles; b has the standing robots
    assert [r["terrains"] for r in rows] == ["1", "1", "1", "1", "1", "1", "1", "2"]


# ------------------------------------------------------------------------------------------------ recorder
def test_the_tracking_error_leaves_out_exactly_the_settle_steps():
    """settle_s = 0.06 s = 3 steps of 0.02 s. Commanded vx = 0.5 m/s; at step k (1..6) the robot moves at
    0.1 k m/s (base frame = world: it faces +x). Measured: steps 4, 5, 6, errors 0.1, 0.0, 0.1 -> 0.0667 m/s;
    progress (0.4 + 0.5 + 0.6) / (3 x 0.5) = 1.0. One step too many or too few in the window gives 0.0500 or
    0.1000 m/s."""
    env = stand_in_env(1)
    env.commands[0, 0] = 0.5
    recorder = Recorder(env, settle_s=0.06, trace_robots=torch.tensor([0]))
    for k in range(1, 7):
        env.base_lin_vel[0, 0] = env.sim.qvel[0, 0] = 0.1 * k
        recorder.record(env, torch.zeros(1, dtype=torch.bool))
    assert float(recorder.err_sum / recorder.err_steps) == pytest.approx(0.2 / 3, abs=1e-6)
    assert float(recorder.along_cmd / recorder.cmd_distance) == pytest.approx(1.0, abs=1e-6)


def test_tracking_is_in_the_base_frame_and_progress_along_the_path_in_the_world():
    """Commanded vx = 0.5 m/s and no turn; every robot moves at 0.5 m/s along world +y. Robot 0 spawned facing +y:
    in its frame that is vx = 0.5, tracking error 0, progress 1. Robot 1 faces +x: base-frame velocity (0, 0.5),
    error |(0.5, -0.5)| = 0.707 m/s, progress 0 (it walks across its path). Robot 2 spawned facing +x (its path
    runs along world +x) and turned to +y uncommanded: its base-frame velocity matches the command (error 0), but
    it covers none of its path (progress 0), the case a base-frame progress would pass."""
    def face(yaw):
        half = torch.tensor(yaw) / 2
        env.base_quat = torch.stack([half.cos(), 0 * half, 0 * half, half.sin()], 1)

    env = stand_in_env(3)
    face([math.pi / 2, 0.0, 0.0])
    env.commands[:, 0] = 0.5
    recorder = Recorder(env, settle_s=0.0, trace_robots=torch.tensor([0]))
    face([math.pi / 2, 0.0, math.pi / 2])  # robot 2 turned
    env.sim.qvel[:, 1] = 0.5  # world +y, all
    env.base_lin_vel[:, :2] = torch.tensor([[0.5, 0.0], [0.0, 0.5], [0.5, 0.0]])  # the same in each base frame
    for _ in range(5):
        recorder.record(env, torch.zeros(3, dtype=torch.bool))
    tracking = recorder.err_sum / recorder.err_steps
    assert tracking.tolist() == pytest.approx([0.0, math.sqrt(0.5), 0.0], abs=1e-6)
    assert (recorder.along_cmd / recorder.cmd_distance).tolist() == pytest.approx([1.0, 0.0, 0.0], abs=1e-6)


def test_a_fall_ends_the_measured_window_before_the_step_that_ended_it():
    """Robot 0 falls in step 3 (dones, not a time-out): steps 1 and 2 are measured, step 3 (after which the env
    has already reset the world, here to a standstill) is not. Its error stays (0.3 + 0.3) / 2 = 0.3 m/s over its
    two steps, its distance the 2 x 0.01 m it walked; fell, not diverged. Robot 1 walks on for all 4 steps."""
    env = stand_in_env(2)
    env.commands[:, 0] = 0.5
    recorder = Recorder(env, settle_s=0.0, trace_robots=torch.tensor([0]))
    for k in range(1, 5):
        fell = k == 3
        env.base_lin_vel[:, 0] = env.sim.qvel[:, 0] = torch.tensor([0.0 if fell else 0.2, 0.5])
        env.base_pos[:, 0] += torch.tensor([-5.0 if fell else 0.01, 0.01])  # the reset puts robot 0 elsewhere
        record_step(recorder, env, torch.tensor([fell, False]))
    assert recorder.fell.tolist() == [True, False] and not recorder.diverged.any()
    assert recorder.err_steps.tolist() == [2.0, 4.0]
    assert float(recorder.err_sum[0] / recorder.err_steps[0]) == pytest.approx(0.3, abs=1e-6)
    assert recorder.distance.tolist() == pytest.approx([0.02, 0.04], abs=1e-6)
    assert recorder.alive_steps.tolist() == [2.0, 4.0]


def test_energy_is_the_absolute_joint_power_summed_over_policy_steps():
    """tau = (10, -4) N m, qdot = (2, 3) rad/s: |20| + |-12| = 32 W (the negative work counts too), over 3 steps of
    0.02 s: 1.92 J. |tau . qdot| = 8 W would give 0.48 J."""
    env = stand_in_env(1)
    env.torques[0], env.dof_vel[0] = torch.tensor([10.0, -4.0]), torch.tensor([2.0, 3.0])
    recorder = Recorder(env, settle_s=0.0, trace_robots=torch.tensor([0]))
    for _ in range(3):
        recorder.record(env, torch.zeros(1, dtype=torch.bool))
    assert float(recorder.energy[0]) == pytest.approx(1.92, abs=1e-6)


# ------------------------------------------------------------------------------------------------ compare
def test_compare_names_the_fix_for_a_column_that_is_not_a_number(tmp_path):
    from legged_gente.evaluation.compare import compare_reports

    path = tmp_path / "a.csv"
    path.write_text("row,name,kind,categories,robots,success_rate\nterrain,t0,text,water,4,0.5\n")
    with pytest.raises(ValueError, match=r"--metric kind: .*'text'.* not a number; give a numeric column.*success_rate"):
        compare_reports(path, path, metric="kind")


def test_figure_b_plots_each_trace_row_at_the_time_it_was_reached(tmp_path, monkeypatch):
    """traces.npz row k is recorded after policy step k + 1, so figure (b) plots it at t = (k + 1) dt: with dt =
    0.02 s and 5 rows the first point is at 0.02 s and the last at 0.10 s (not 0 and 0.08)."""
    from legged_gente.evaluation import figures

    dt, steps = 0.02, 5
    traces = tmp_path / "traces.npz"
    cmd = np.zeros((1, steps, 3), np.float32)
    np.savez(traces, ids=np.array(["t0"]), dt=np.array(dt), active=np.ones((1, steps), bool), cmd=cmd, vel=cmd)
    plotted = []
    real_subplots = figures._plt().subplots

    def subplots(*args, **kwargs):
        fig, axes = real_subplots(*args, **kwargs)
        for ax in axes.flat:
            original = ax.plot
            ax.plot = lambda x, *a, _orig=original, **k: (plotted.append(np.asarray(x)), _orig(x, *a, **k))[1]
        return fig, axes

    monkeypatch.setattr(figures._plt(), "subplots", subplots)
    figures.plot_tracking(traces, tmp_path / "b.png")
    assert plotted and all(np.allclose(x, [0.02, 0.04, 0.06, 0.08, 0.10]) for x in plotted)


def test_figure_b_titles_each_panel_with_its_whole_terrain_id(tmp_path, monkeypatch):
    """Two ids alike in their first 24 characters (gente100's image items share long prefixes) keep apart: each
    panel's title is its whole id, wrapped over lines of at most 24 characters."""
    from legged_gente.evaluation import figures

    ids = ["image_40_scene_forest_stream_a", "image_40_scene_forest_stream_b"]
    traces = tmp_path / "traces.npz"
    cmd = np.zeros((2, 3, 3), np.float32)
    np.savez(traces, ids=np.array(ids), dt=np.array(0.02), active=np.ones((2, 3), bool), cmd=cmd, vel=cmd)
    drawn = []
    real_subplots = figures._plt().subplots

    def subplots(*args, **kwargs):
        fig, axes = real_subplots(*args, **kwargs)
        drawn.append(axes)
        return fig, axes

    monkeypatch.setattr(figures._plt(), "subplots", subplots)
    figures.plot_tracking(traces, tmp_path / "b.png")
    titles = [ax.get_title() for ax in drawn[0][0]]
    assert [t.replace("\n", "") for t in titles] == ids
    assert all(len(line) <= 24 for t in titles for line in t.split("\n"))


def test_robots_scored_over_a_short_part_of_the_episode_are_said_so():
    """A tile too small for the episode: the robots reach its edge early and are scored over that part alone
    (a 3 m tile, 2.5 s of a 10 s episode scored 100 %): the run says how much of the episode was measured."""
    from legged_gente.evaluation.report import short_measure_note

    metrics = {"left_tile": np.array([True, True, True, False, True]),
               "time_s": np.array([2.0, 3.0, 2.5, 10.0, 1.0]),
               "standing": np.array([False, False, False, False, True])}
    note = short_measure_note(metrics, episode_length_s=10.0)
    # the moving robots: 3 of 4 reached the edge, after (2 + 3 + 2.5) / 3 = 2.5 s; the standing one is not counted
    assert note is not None and note.startswith("3 of 4 moving robots reached their tile's edge after 2.5 s")
    assert "10 s episode" in note and "--tile_edge_margin off" in note
    late = dict(metrics, time_s=np.array([6.0, 7.0, 8.0, 10.0, 1.0]))  # most of the episode measured: no note
    assert short_measure_note(late, episode_length_s=10.0) is None
    assert short_measure_note(dict(metrics, left_tile=np.zeros(5, bool)), episode_length_s=10.0) is None


def test_the_step_a_robot_falls_in_counts_the_command_it_ran_under_not_its_next_episodes():
    """A world reset in a step holds its next episode's commands, drawn by the env, when the step is recorded. Robot 0
    is told to stand (0 m/s) and robot 1 to walk at 0.5 m/s; both fall in step 2 and the env draws 0.8 m/s for their
    next episodes, which the task overwrites before step 3. The standing robot has no commanded distance (progress
    none, as a stand-still command's is), not one step of 0.8 m/s (progress 0); the walker's distance is 3 steps of
    0.5 m/s, not 0.5 + 0.8 + 0.5."""
    env = stand_in_env(2)
    env.commands[:, 0] = torch.tensor([0.0, 0.5])
    recorder = Recorder(env, settle_s=0.0, trace_robots=torch.tensor([0]))
    for k in range(1, 4):
        fell = k == 2
        told = env.commands.clone()
        env.terminal_commands = told  # what the step ran under, kept before its resets
        if fell:
            env.commands = told.clone()
            env.commands[:, 0] = 0.8  # the env's draw for the worlds it reset
        recorder.record(env, torch.tensor([fell, fell]))
        env.commands = told  # the task's commands again, before the next step
    assert recorder.fell.tolist() == [True, True]
    assert recorder.cmd_distance.tolist() == pytest.approx([0.0, 3 * 0.5 * 0.02], abs=1e-7)
