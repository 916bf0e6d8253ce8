"""The command line: plan prints its table; errors exit 2 with a message (the demo: tests/test_demo.py)."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import pytest

from jaxplan.cli import build_parser, main

COMMANDS = ("demo", "plan", "navigate", "run", "figures", "export", "reproduce", "tune", "study", "bench")


def test_every_command_is_listed():
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    assert tuple(sub.choices) == COMMANDS


@pytest.mark.parametrize("argv", [["--help"]] + [[c, "--help"] for c in COMMANDS])
def test_help_answers_without_jax_or_numba(argv):
    """``jaxplan --help`` and ``jaxplan CMD --help`` import neither JAX nor numba (a fast answer)."""
    code = textwrap.dedent(f"""
        import contextlib, io, json, sys
        from jaxplan.cli import main
        out = io.StringIO()
        try:
            with contextlib.redirect_stdout(out):
                main({argv!r})
        except SystemExit as e:
            status = e.code
        print(json.dumps({{"status": status, "usage": out.getvalue().startswith("usage: jaxplan"),
                           "loaded": [m for m in ("jax", "jaxlib", "numba") if m in sys.modules]}}))
        """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert json.loads(proc.stdout.strip().splitlines()[-1]) == {"status": 0, "usage": True, "loaded": []}


def test_plan_reports_bad_start(movingai, capsys):
    rc = main(["plan", str(movingai / "maze-32-32-2.map"), "--start", "0", "0", "--goal", "1", "27"])
    assert rc == 2
    assert "start (0, 0) is on a blocked cell" in capsys.readouterr().err


def test_plan_on_a_movingai_map(movingai, capsys):
    rc = main(["plan", str(movingai / "maze-32-32-2.map"), "--start", "15", "2", "--goal", "1", "27"])
    assert rc == 0
    assert "64.314" in capsys.readouterr().out  # the scenario file's optimum 64.31370850


def test_tune_lists_every_config_problem_before_any_work(tmp_path, capsys):
    from jaxplan.cli import main

    bad = tmp_path / "bad.toml"
    bad.write_text('[tune]\nname = "x"\nkind = "nope"\n')
    assert main(["tune", str(bad), "--out", str(tmp_path / "runs")]) == 2
    err = capsys.readouterr().err
    assert "tune.kind" in err and "tune.space" in err and "maps" in err
    assert not (tmp_path / "runs").exists()


def _tiny_map(tmp_path):
    m = tmp_path / "tiny.map"
    m.write_text("type octile\nheight 6\nwidth 6\nmap\n......\n......\n..@@..\n..@@..\n......\n......\n")
    return m


def test_plan_with_a_sampling_planner_needs_no_connectivity(tmp_path, capsys):
    # rrt_star has no `connectivity` parameter: the CLI must not pass its own default to it.
    rc = main(["plan", str(_tiny_map(tmp_path)), "--start", "0", "0", "--goal", "5", "5", "--planner", "rrt_star"])
    out = capsys.readouterr()
    assert rc == 0, out.err
    assert "rrt_star on" in out.out


def test_plan_passes_an_explicit_connectivity(tmp_path, capsys):
    rc = main(["plan", str(_tiny_map(tmp_path)), "--start", "0", "0", "--goal", "5", "0", "--connectivity", "4"])
    assert rc == 0
    assert "5.000" in capsys.readouterr().out
    rc = main(["plan", str(_tiny_map(tmp_path)), "--start", "0", "0", "--goal", "5", "5", "--planner", "rrt_star",
               "--connectivity", "4"])
    assert rc == 2 and "connectivity" in capsys.readouterr().err


def _ros_map(tmp_path):
    """A 6x4 ROS map of 0.5 m cells whose origin is (-2, 1) m, with cell (3, 1) blocked."""
    import numpy as np

    import jaxplan as jp
    from jaxplan.grid import save_ros_map

    free = np.ones((4, 6), bool)
    free[1, 3] = False
    path = tmp_path / "ros.yaml"
    save_ros_map(jp.grid_from_array(free, resolution=0.5, origin=(-2.0, 1.0)), path)
    return path


def test_plan_takes_start_and_goal_in_metres_of_the_world_frame(tmp_path, capsys):
    """--start-m/--goal-m go through the map's origin: (-1.9, 1.1) m is cell (0, 0), (0.7, 2.6) m is cell (5, 3)."""
    ros = _ros_map(tmp_path)
    rc = main(["plan", str(ros), "--start-m", "-1.9", "1.1", "--goal-m", "0.7", "2.6", "--out",
               str(tmp_path / "p.json")])
    out = capsys.readouterr()
    assert rc == 0, out.err
    assert "start: (-1.9, 1.1) m is cell (0, 0)" in out.err and "goal: (0.7, 2.6) m is cell (5, 3)" in out.err
    record = json.loads((tmp_path / "p.json").read_text())
    assert record["start"] == [0, 0] and record["goal"] == [5, 3]
    # the same plan from cells
    assert main(["plan", str(ros), "--start", "0", "0", "--goal", "5", "3"]) == 0


@pytest.mark.parametrize("command", ["plan", "navigate"])
@pytest.mark.parametrize("args, words", [
    (["--start", "0", "0", "--start-m", "-1.9", "1.1", "--goal", "5", "3"],
     "--start and --start-m both give the start: use one"),
    (["--start", "0", "0"], "the goal is missing: give --goal X Y (a cell) or --goal-m X Y"),
    (["--start-m", "1.5", "1.1", "--goal", "5", "3"],
     "--start-m 1.5 1.1: the point is outside the map, which covers x -2..1 m and y 1..3 m (world frame, "
     "origin (-2, 1)"),
    (["--start", "0", "0", "--goal-m", "-0.3", "1.7"],
     "--goal-m -0.3 1.7: the point is on an obstacle (cell (3, 1) is blocked)"),
    (["--start-m", "nan", "1.1", "--goal", "5", "3"], "--start-m nan 1.1: the point must be two finite numbers"),
])
def test_metres_are_refused_by_name_outside_the_map_on_an_obstacle_or_with_cells(tmp_path, capsys, command, args,
                                                                                    words):
    rc = main([command, str(_ros_map(tmp_path)), *args])
    assert rc == 2
    assert words in capsys.readouterr().err


def _open_map(tmp_path):
    """A 16x12 room with a short wall: room for walkers away from the start and goal."""
    rows = ["." * 16] * 12
    rows[6] = "....@@@@@@......"
    m = tmp_path / "room.map"
    m.write_text("type octile\nheight 12\nwidth 16\nmap\n" + "\n".join(rows) + "\n")
    return m


@pytest.mark.parametrize("behavior, reactive", [(None, None), ("blind", None), ("social", True)])
def test_navigate_walkers_that_see(tmp_path, capsys, monkeypatch, behavior, reactive):
    """``--walkers N --behavior social`` hands `navigate` walkers that see (`random_obstacles(behavior="social")`:
    ``reactive`` set for every walker); blind, the default, none. The episode itself is stubbed: the walkers are
    what is tested."""
    import types

    import numpy as np

    import jaxplan.nav

    seen = {}

    def fake(grid, start, goal, *, obstacles, **kw):
        seen["obstacles"] = obstacles
        return types.SimpleNamespace(success=True, reason="reached", time_s=1.0, collisions=0,
                                     metrics={"path_length": 1.0, "recoveries": 0, "replans": 0})

    monkeypatch.setattr(jaxplan.nav, "navigate", fake)
    argv = ["navigate", str(_open_map(tmp_path)), "--start", "1", "1", "--goal", "14", "10", "--walkers", "3"]
    assert main(argv + ([] if behavior is None else ["--behavior", behavior])) == 0
    obs = seen["obstacles"]
    assert obs.count == 3
    if reactive is None:
        assert obs.reactive is None
    else:
        assert np.asarray(obs.reactive).shape[-1] == 3 and np.all(np.asarray(obs.reactive))
    assert f"walkers 3 ({behavior or 'blind'})" in capsys.readouterr().out


def test_navigate_behavior_matches_the_library_and_needs_walkers(tmp_path, capsys):
    from jaxplan.nav._traffic import BEHAVIORS

    action = next(a for a in next(a for a in build_parser()._actions if a.dest == "command").choices["navigate"]
                  ._actions if a.dest == "behavior")
    assert tuple(action.choices) == BEHAVIORS
    argv = ["navigate", str(_open_map(tmp_path)), "--start", "1", "1", "--goal", "14", "10"]
    assert main(argv + ["--walkers", "0", "--behavior", "social"]) == 2
    assert "--behavior social describes walkers, but --walkers is 0" in capsys.readouterr().err
