"""Progress bars (issue 30): drawn with time left on a terminal, absent with ``--no-progress`` and when piped, and
the results the same either way."""

from __future__ import annotations

import io
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import jaxplan as jp
from jaxplan.core import progress as P

RUN = """
metrics = ["success", "length", "turns"]

[experiment]
name = "bar"
seeds = 2
chunk = 2

[[maps]]
name = "wh"
generator = "warehouse"
seed = 0
params = { width = 14, height = 10, shelf_length = 4, shelf_depth = 2, aisle = 1, cross_aisle = 2 }

[scenarios]
source = "random"
count = 4
seed = 3
min_distance = 5.0

[[planners]]
label = "AS"
kind = "plan"
name = "aco"
overrides = { ants = 4, iterations = 3, dead_end = "retreat" }
"""


class TTY(io.StringIO):
    """A stderr that says it is a terminal."""

    def isatty(self) -> bool:
        return True


@pytest.fixture(autouse=True)
def _no_env(monkeypatch):
    monkeypatch.delenv("JAXPLAN_PROGRESS", raising=False)


@pytest.mark.parametrize("backend", ["rich", "plain"])
def test_a_bar_on_a_terminal_shows_done_total_and_time_left(monkeypatch, backend):
    if backend == "plain":
        monkeypatch.setattr(P, "_rich_progress", lambda stream: None)
    s = TTY()
    with P.ProgressBar("job", 4, unit="trials", stream=s) as bar:
        assert bar.active and bar.rich == (backend == "rich")
        bar.stage("job: compiling", None)
        bar.stage("job: chunk 1/2", 4)
        bar.update(2)
        bar.update(advance=1)
    out = s.getvalue()
    for w in ("job: chunk 1/2", "3/4", "trials", "left"):
        assert w in out, out


@pytest.mark.parametrize("why", ["piped", "disabled", "env"])
def test_no_bar_when_piped_disabled_or_switched_off(monkeypatch, why):
    s = io.StringIO() if why == "piped" else TTY()
    if why == "env":
        monkeypatch.setenv("JAXPLAN_PROGRESS", "off")
    with P.ProgressBar("job", 3, stream=s, enabled=why != "disabled") as bar:
        bar.update(3)
        assert not bar.active
    assert s.getvalue() == ""


def test_a_bar_inside_a_live_bar_draws_nothing():
    s = TTY()
    with P.ProgressBar("outer", 2, stream=s) as outer:
        if not outer.rich:
            pytest.skip("rich is not installed")
        with P.ProgressBar("inner", 2, stream=s) as inner:
            assert not inner.active


_CHILD = textwrap.dedent("""
    import sys, time
    from jaxplan.core.progress import ProgressBar
    with ProgressBar("pty-job", 3, unit="steps") as bar:
        for k in range(3):
            time.sleep(0.05)
            bar.update(k + 1)
    print("done", flush=True)
    """)


def _run_on_a_pty(args: list[str]) -> str:
    """stderr and stdout of ``python args`` on a pseudo-terminal (as in a shell), as text."""
    import pty
    import select

    master, slave = pty.openpty()
    proc = subprocess.Popen([sys.executable, *args], stdout=slave, stderr=slave, stdin=subprocess.DEVNULL,
                            close_fds=True)
    os.close(slave)
    chunks = []
    while True:
        ready, _, _ = select.select([master], [], [], 60)
        if not ready:
            break
        try:
            data = os.read(master, 65536)
        except OSError:  # the child closed the terminal
            break
        if not data:
            break
        chunks.append(data)
    proc.wait(timeout=60)
    os.close(master)
    return b"".join(chunks).decode("utf-8", "replace")


@pytest.mark.skipif(sys.platform == "win32", reason="needs a POSIX pseudo-terminal")
def test_on_a_real_terminal_the_bar_is_drawn_and_piped_it_is_not():
    shown = _run_on_a_pty(["-c", _CHILD])
    assert "pty-job" in shown and "3/3" in shown and "left" in shown and "done" in shown
    piped = subprocess.run([sys.executable, "-c", _CHILD], capture_output=True, text=True, timeout=60)
    assert piped.returncode == 0 and piped.stdout == "done\n" and piped.stderr == ""


def _rows(path):
    """trials.csv without its wall-clock columns."""
    import csv

    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return [{k: v for k, v in r.items() if "time" not in k} for r in rows]


def test_jaxplan_run_draws_a_bar_on_a_terminal_only_and_writes_the_same_files(tmp_path, monkeypatch, capsys):
    from jaxplan.cli import main

    cfg = tmp_path / "bar.toml"
    cfg.write_text(RUN)
    err = {}
    for mode in ("terminal", "no-progress", "piped"):
        stream = TTY() if mode != "piped" else io.StringIO()
        monkeypatch.setattr(sys, "stderr", stream)
        argv = ["run", str(cfg), "--out", str(tmp_path / mode)] + (["--no-progress"] if mode == "no-progress" else [])
        assert main(argv) == 0
        monkeypatch.undo()
        err[mode] = stream.getvalue()
    capsys.readouterr()
    assert "bar: chunk 2/2 wh/AS" in err["terminal"] and "8/8" in err["terminal"] and "left" in err["terminal"]
    assert "trials" in err["terminal"]
    assert err["no-progress"] == "" and err["piped"] == ""
    ref = _rows(tmp_path / "terminal" / "bar" / "trials.csv")
    assert ref and all(_rows(tmp_path / m / "bar" / "trials.csv") == ref for m in ("no-progress", "piped"))


def test_plan_batch_with_progress_gives_the_same_results(monkeypatch):
    scene = jp.WarehouseGenerator(12, 12)(1)
    s, g = np.array([scene.start] * 3), np.array([scene.goal] * 3)
    for planner, kw in (("aco", {"ants": 5, "iterations": 3}), ("astar", {})):
        ref = jp.plan_batch(scene.grid, s, g, planner=planner, seeds=range(2), **kw)
        stream = TTY()
        monkeypatch.setattr(sys, "stderr", stream)
        got = jp.plan_batch(scene.grid, s, g, planner=planner, seeds=range(2), progress=True, **kw)
        monkeypatch.undo()
        for f in ("paths", "length", "cost", "history", "success"):
            np.testing.assert_array_equal(getattr(got, f), getattr(ref, f), err_msg=f"{planner} {f}")
        shown = stream.getvalue()
        assert planner in shown, shown
        if planner == "astar":
            assert "3/3" in shown and "left" in shown


def test_tune_bar_counts_generations(monkeypatch):
    from jaxplan.tune._loop import _Progress

    stream = TTY()
    monkeypatch.setattr(sys, "stderr", stream)
    bar = _Progress("tune-x", 4, True)
    bar.update({"generation": 1, "best": 1.5, "gen_mean": 2.0, "n_bad": 0}, 0.1)
    bar.update({"generation": 2, "best": 1.25, "gen_mean": 1.75, "n_bad": 0}, 0.1)
    bar.close()
    monkeypatch.undo()
    shown = stream.getvalue()
    assert "2/4" in shown and "generations" in shown and "best 1.25" in shown and "left" in shown
