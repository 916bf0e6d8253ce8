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
