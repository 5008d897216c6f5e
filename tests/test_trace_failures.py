"""tools/trace_failures.py: the commanded line's direction and its tallest step, worked out by hand."""

import math

import numpy as np
import pytest


@pytest.fixture(scope="module")
def tool(load_file):
    return load_file("tools/trace_failures.py")


def test_the_commanded_direction_is_the_velocity_turned_by_the_heading(tool):
    # forward in heading 90 deg walks +y; sideways left (vy > 0) in heading 0 walks +y; backwards in heading 0 walks -x
    command = np.array([[0.8, 0.0, 0.0, math.pi / 2], [0.0, 0.4, 0.0, 0.0], [-0.5, 0.0, 0.0, 0.0],
                        [0.3, 0.3, 0.0, math.pi]])  # 45 deg left of backwards: (-1, -1) / sqrt(2)
    expected = np.array([[0.0, 1.0], [0.0, 1.0], [-1.0, 0.0], [-math.sqrt(0.5), -math.sqrt(0.5)]])
    np.testing.assert_allclose(tool.commanded_direction(command), expected, atol=1e-12)


def step_ground(x, y):
    """Flat, then a 0.4 m wall from x = 2 m on, its edge a 0.2 m ramp (x from 2.0 to 2.2 m)."""
    return 0.4 * np.clip((np.asarray(x) - 2.0) / 0.2, 0.0, 1.0) + 0.0 * np.asarray(y)


def test_a_wall_across_the_line_is_its_step_and_one_along_it_is_not(tool):
    # across: samples every 0.1 m, the rise over 0.3 m from x = 1.9 (0) to 2.2 (0.4) is the whole wall, its top at 2.2 m
    assert tool.line_step(step_ground, np.array([0.0, 0.0]), np.array([1.0, 0.0]), 4.0) == pytest.approx((0.4, 2.2))
    # from x = 1 m the same top lies 1.2 m along the line
    assert tool.line_step(step_ground, np.array([1.0, 0.0]), np.array([1.0, 0.0]), 4.0) == pytest.approx((0.4, 1.2))
    # over a 0.1 m run the ramp rises 0.2 m per sample, first from 2.0 to 2.1 m
    assert tool.line_step(step_ground, np.array([0.0, 0.0]), np.array([1.0, 0.0]), 4.0,
                          run=0.1) == pytest.approx((0.2, 2.1))
    # along the wall's foot (x = 1 m, walking +y) the ground does not rise; walking down it (-x from x = 3 m) neither
    assert tool.line_step(step_ground, np.array([1.0, 0.0]), np.array([0.0, 1.0]), 4.0) == (0.0, 0.0)
    assert tool.line_step(step_ground, np.array([3.0, 0.0]), np.array([-1.0, 0.0]), 4.0) == (0.0, 0.0)
    # a line that stops before the wall (1.5 m from the origin) sees none of it
    assert tool.line_step(step_ground, np.array([0.0, 0.0]), np.array([1.0, 0.0]), 1.5) == (0.0, 0.0)
    # a slope of 0.1 (rise 0.03 m over 0.3 m, the same everywhere on it)
    slope = lambda x, y: 0.1 * np.asarray(x)  # noqa: E731
    assert tool.line_step(slope, np.array([0.0, 0.0]), np.array([1.0, 0.0]), 2.0)[0] == pytest.approx(0.03)


def ditch(x, y):
    """A channel 1 m deep between x = 2 m and x = 4 m: vertical walls (at 2.0 and 4.0 m), a flat bed."""
    x = np.asarray(x) + 0.0 * np.asarray(y)
    return np.where((x > 2.0) & (x < 4.0), -1.0, 0.0)


def test_a_channel_across_the_line_is_a_drop_and_a_step(tool):
    # samples every 0.1 m: the ground falls 1 m between x = 2.0 and 2.1 (the drop's low end, 2.1 m along the line)
    # and rises 1 m between 3.9 and 4.0 m (the step's top at 4.0 m along the line)
    down = lambda x, y: -ditch(x, y)  # noqa: E731
    assert tool.line_step(down, np.array([0.0, 0.0]), np.array([1.0, 0.0]), 6.0) == pytest.approx((1.0, 2.1))
    assert tool.line_step(ditch, np.array([0.0, 0.0]), np.array([1.0, 0.0]), 6.0) == pytest.approx((1.0, 4.0))
    # a line that ends in the bed, 3 m long, has the drop but not the step out
    assert tool.line_step(ditch, np.array([0.0, 0.0]), np.array([1.0, 0.0]), 3.0) == (0.0, 0.0)
    # walking along the bed (x = 3 m, +y) neither falls nor rises
    assert tool.line_step(down, np.array([3.0, 0.0]), np.array([0.0, 1.0]), 6.0) == (0.0, 0.0)


def test_reach_splits_lines_by_a_step_or_a_drop_of_045_m(tool, capsys):
    """Four robots: (step 0.2, drop 0.1, succeeded), (0.3, 0.44, fell), (0.1, 0.45, failed up) and (0.9, 0.0,
    succeeded): the first two lie within reach (one of two succeeds, one of two fell), the last two beyond (one of
    two succeeds, none fell)."""
    tool.print_reach(np.array([0.2, 0.3, 0.1, 0.9]), np.array([0.1, 0.44, 0.45, 0.0]),
                     np.array([True, False, False, True]), np.array([False, True, False, False]))
    assert capsys.readouterr().out.splitlines() == [
        "lines with no step or drop of 0.45 m or more: 2 robots, success 50.0%, fell 50.0%",
        "lines with a step or a drop beyond: 2 robots, success 50.0%, fell 0.0%"]


def test_walls_count_how_the_robots_that_succeed_pass_them(tool, capsys):
    """Four robots on lines with a wall: one failed (not counted), one succeeded with the wall past the asked
    distance, two got past it, 1.0 m and 3.0 m off the line at most: median 2.0 m."""
    tool.print_walls(np.array([False, True, True, True]), np.array([True, True, False, False]),
                     np.array([True, False, True, True]), np.array([9.0, 0.1, 1.0, 3.0]))
    assert capsys.readouterr().out.strip() == ("succeed on a line rising 0.7 m or more: 3; the rise past the asked "
                                               "distance: 1; past the rise's distance along the line: 2, their "
                                               "median largest sideways offset 2.0 m")
    tool.print_walls(np.array([False]), np.array([False]), np.array([False]), np.array([0.0]))
    assert capsys.readouterr().out.strip().endswith("or more: 0; the rise past the asked distance: 0; past the "
                                                    "rise's distance along the line: 0")


def test_bins_count_success_falls_and_the_stalled_share_of_robots_up_and_failing(tool, capsys):
    """Six robots: steps 0.05 (succeeded), 0.15 (up, failed, stalled), 0.15 (up, failed, moving), 0.15 (fell;
    marked stalled, which must not count), 0.5 (up, failed, stalled) and 2.0 (fell): the first bin 1 robot at
    100 %, none fell; the second 3 at 0 %, one in three fell, half of the two up ones stalled; 0.5 m lies in
    [0.45, 0.7): 1 robot, stalled; the wall bin 1 robot, fallen, with no robot up and failing."""
    tool.print_bins(np.array([0.05, 0.15, 0.15, 0.15, 0.5, 2.0]),
                    np.array([True, False, False, False, False, False]),
                    np.array([False, False, False, True, False, True]),
                    np.array([False, True, False, True, True, False]))
    lines = capsys.readouterr().out.splitlines()
    assert lines[1].split()[-4:] == ["1", "100.0%", "0.0%", "-"]
    assert lines[2].split()[-4:] == ["3", "0.0%", "33.3%", "50.0%"]
    assert lines[3].split()[-4:] == ["0", "-", "-", "-"] and lines[4].split()[-4:] == ["0", "-", "-", "-"]
    assert lines[5].split()[:2] == ["[0.45,", "0.70)"] and lines[5].split()[-4:] == ["1", "0.0%", "0.0%", "100.0%"]
    assert lines[6].split()[:2] == [">=", "0.70"] and lines[6].split()[-4:] == ["1", "0.0%", "100.0%", "-"]


class PondTerrain:
    """A 10 x 10 m grid of 0.1 m cells (origin at -1 m): ground at 0 m, a pond from x = 4 m on whose water
    stands at 0.3 m over a bed sloping down from 0 m at x = 4 m to -0.5 m at x = 9 m, dry elsewhere."""

    def __init__(self):
        from legged_gente.terrain.materials import NO_WATER

        self.resolution, self.origin_xy = 0.1, (-1.0, -1.0)
        x = self.origin_xy[0] + np.arange(100) * self.resolution
        self.material = type("M", (), {"water_surface": np.where(x[:, None] >= 4.0 + 0.0 * x[None, :], 0.3,
                                                                 NO_WATER).astype(np.float32)})()

    def height_at(self, x, y):
        return np.where(np.asarray(x) >= 4.0, -0.1 * (np.asarray(x) - 4.0), 0.0) + 0.0 * np.asarray(y)


def test_the_water_on_the_line_is_its_deepest_point(tool):
    # the pond's depth at x is 0.3 m of water over a bed at -0.1 (x - 4): 0.3 m at its edge, 0.5 m at x = 6 m
    depth = tool.water_depth(PondTerrain())
    np.testing.assert_allclose(depth(np.array([0.0, 3.9, 4.0, 6.0]), np.zeros(4)), [0.0, 0.0, 0.3, 0.5], atol=1e-6)
    # walking +x from the origin for 6 m reaches x = 6 m: 0.5 m deep; for 3 m it stays dry
    assert tool.line_depth(depth, np.array([0.0, 0.0]), np.array([1.0, 0.0]), 6.0) == pytest.approx(0.5, abs=1e-6)
    assert tool.line_depth(depth, np.array([0.0, 0.0]), np.array([1.0, 0.0]), 3.0) == 0.0
    # walking +y along x = 5 m stays 0.4 m deep; walking -x from x = 7 m (0.6 m) out of the pond keeps its start
    assert tool.line_depth(depth, np.array([5.0, 0.0]), np.array([0.0, 1.0]), 4.0) == pytest.approx(0.4, abs=1e-6)
    assert tool.line_depth(depth, np.array([7.0, 0.0]), np.array([-1.0, 0.0]), 5.0) == pytest.approx(0.6, abs=1e-6)


def test_water_bins_count_dry_lines_apart(tool, capsys):
    """Three robots: a dry line (succeeded), one 0.3 m deep (fell) and one 0.9 m deep (up, failed, stalled)."""
    tool.print_bins(np.array([0.0, 0.3, 0.9]), np.array([True, False, False]), np.array([False, True, False]),
                    np.array([False, False, True]), what="water", bins=tool.WATER_BINS)
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("water on the line (m)")
    assert lines[1].split()[:2] == ["[0.00,", "0.01)"] and lines[1].split()[-4:] == ["1", "100.0%", "0.0%", "-"]
    assert lines[3].split()[:2] == ["[0.20,", "0.40)"] and lines[3].split()[-4:] == ["1", "0.0%", "100.0%", "-"]
    assert lines[-1].split()[:2] == [">=", "0.60"] and lines[-1].split()[-4:] == ["1", "0.0%", "0.0%", "100.0%"]


def test_the_report_picks_terrains_where_robots_stay_up_and_fail(tool, tmp_path):
    report = tmp_path / "report.csv"
    report.write_text("row,name,success_rate,fall_rate\nterrain,up_and_failing,0.3,0.1\nterrain,falling,0.3,0.5\n"
                      "terrain,succeeding,0.9,0.0\nterrain,no_moving_robot,,\ngroup,text,0.1,0.1\n")
    assert tool.failing_terrains(str(report)) == ["up_and_failing"]
    report.write_text("row,name,success_rate,fall_rate\nterrain,succeeding,0.9,0.0\n")
    with pytest.raises(SystemExit, match="no terrain with fall rate < 0.2 and success < 0.5"):
        tool.failing_terrains(str(report))


def test_on_flat_ground_every_robot_has_a_line_without_a_step(tool, monkeypatch, capsys):
    """The shipped biped on the flat benchmark: every line lies in the first bin, which holds every moving robot
    (none diverges on flat ground)."""
    monkeypatch.setattr("sys.argv", ["trace_failures.py", "--task", "gente_biped", "--pretrained", "--benchmark",
                                     "flat", "--robots_per_terrain", "6", "--episode_s", "4", "--turn_s", "0.5",
                                     "--no_progress"])
    tool.main()
    lines = capsys.readouterr().out.splitlines()
    header = next(line for line in lines if "moving robots" in line).split()
    moving, succeeded, fell, up_failing = int(header[2]), int(header[5]), int(header[7]), int(header[9])
    assert moving >= 1 and succeeded + up_failing + fell == moving
    table = lines[lines.index("step on the line (m)   robots  success     fell  up, failed: stalled") + 1:]
    assert table[0].split()[:3] == ["[0.00,", "0.10)", str(moving)]
    assert all(row.split()[-4:] == ["0", "-", "-", "-"] for row in table[1:6])
    assert table[6].startswith("succeed on a line rising 0.7 m or more: 0;")
    assert table[7] == "drop on the line (m)   robots  success     fell  up, failed: stalled"
    assert table[8].split()[:3] == ["[0.00,", "0.10)", str(moving)]
    assert all(row.split()[-4:] == ["0", "-", "-", "-"] for row in table[9:14])
    assert table[14].startswith(f"lines with no step or drop of 0.45 m or more: {moving} robots")
    assert table[15] == "lines with a step or a drop beyond: 0 robots, -"
    assert table[16] == "water on the line (m)  robots  success     fell  up, failed: stalled"
    assert table[17].split()[:3] == ["[0.00,", "0.01)", str(moving)]  # the flat benchmark is dry
    assert all(row.split()[-4:] == ["0", "-", "-", "-"] for row in table[18:22])
