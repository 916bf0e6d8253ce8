"""The scripts in examples/ run, open as notebooks, and are shown on the documentation site.

Each example runs in quick mode (``--quick``) in a subprocess, with the temporary folder as its working folder
and ``$JAXPLAN_EXAMPLES_OUT``, and its outputs are checked for what they claim: figures that are real PNG
images with something drawn, A*'s gap of zero against the MovingAI optimum, TSP tours that are permutations
no shorter than the optimal tour, a tuning run of the configured size, a robot that keeps to the speed mask.
Those runs are ``slow``: the six take about 3-4 minutes on 2 shared cores with warm compilation caches (each
example's time is in examples/README.md). Examples that need the benchmark data skip without it, and
experiment_pandas without pandas (``pip install 'jaxplan[export]'``).

What always runs (fast): every script is in jupytext's percent format with a header, Markdown cells and code
cells that compile on their own, has a quick mode and an output folder, is listed in examples/README.md, and
has a page under docs/examples/ that includes its source and shows its committed figures.
"""

from __future__ import annotations

import csv
import importlib.util
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT, data_dir

EXAMPLES = ROOT / "examples"
PAGES = ROOT / "docs" / "examples"
NAMES = ("compare_planners", "walkers", "experiment_pandas", "tune_mppi", "ros_map", "tsp")
DATA = {"compare_planners": "movingai", "ros_map": "ros", "tsp": "tsplib"}
"""Examples -> the benchmark folder they read."""

CELL = re.compile(r"^# %%(.*)$", re.M)


def cells(text: str) -> list[tuple[str, str]]:
    """``(kind, source)`` of each ``# %%`` cell of a percent-format script (kind ``"markdown"`` or ``"code"``)."""
    marks = list(CELL.finditer(text))
    out = []
    for m, nxt in zip(marks, [*marks[1:], None], strict=True):
        body = text[m.end():nxt.start() if nxt else len(text)].strip("\n")
        out.append(("markdown" if "[markdown]" in m.group(1) else "code", body))
    return out


def test_every_example_is_listed_here():
    assert sorted(p.stem for p in EXAMPLES.glob("*.py")) == sorted(NAMES)


@pytest.mark.parametrize("name", NAMES)
def test_example_is_a_percent_notebook_with_a_quick_mode(name):
    text = (EXAMPLES / f"{name}.py").read_text()
    assert text.startswith("# ---\n# jupyter:\n#   jupytext:\n"), "no jupytext header"
    assert "format_name: percent" in text.split("# ---", 2)[1]
    parts = cells(text)
    kinds = [k for k, _ in parts]
    assert kinds[0] == "markdown" and kinds.count("code") >= 3 and kinds.count("markdown") >= 3, kinds
    for k, src in parts:
        if k == "markdown":
            assert all(line.startswith("#") for line in src.splitlines() if line.strip()), src[:80]
        else:
            compile(src, f"{name}.py cell", "exec")  # each cell runs on its own in a notebook
    assert '"--quick" in sys.argv' in text and "JAXPLAN_EXAMPLES_QUICK" in text and "JAXPLAN_EXAMPLES_OUT" in text
    jupytext = importlib.util.find_spec("jupytext")
    if jupytext is not None:  # the real reader agrees (jupytext is not a test dependency)
        import jupytext as jt

        nb = jt.reads(text, fmt="py:percent")
        assert [c.cell_type for c in nb.cells] == kinds


@pytest.mark.parametrize("name", NAMES)
def test_example_is_listed_and_has_a_page_with_its_figures(name):
    readme = (EXAMPLES / "README.md").read_text()
    assert f"[{name}.py]({name}.py)" in readme, f"examples/README.md does not list {name}.py"
    page = (PAGES / f"{name}.md").read_text()
    assert f'--8<-- "examples/{name}.py"' in page, "the page does not include the script"
    images = re.findall(r"!\[[^\]]*\]\((img/[^)\s]+)\)", page)
    assert images, "the page shows no figure"
    for img in images:
        path = PAGES / img
        assert path.is_file(), f"{path} is missing: regenerate the figures (examples/README.md)"
        assert path.name.startswith(name), f"{img} is not a figure of {name}"


# ---------------------------------------------------------------------------------------------
# Running them


def run_example(name: str, tmp_path: Path) -> Path:
    """Runs examples/NAME.py --quick in ``tmp_path``; returns its output folder."""
    need = DATA.get(name)
    if need and not (data_dir() / need).is_dir():
        pytest.skip(f"{need} benchmarks not found at {data_dir() / need} (set JAXPLAN_DATA)")
    if name == "experiment_pandas":
        pytest.importorskip("pandas", reason="experiment_pandas needs pandas: pip install 'jaxplan[export]'")
    out = tmp_path / "out"
    env = {**os.environ, "JAXPLAN_EXAMPLES_OUT": str(out), "JAXPLAN_DATA": str(data_dir()), "MPLBACKEND": "Agg"}
    env.pop("JAXPLAN_EXAMPLES_QUICK", None)  # the flag alone must select quick mode
    proc = subprocess.run([sys.executable, str(EXAMPLES / f"{name}.py"), "--quick"], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, f"{name}.py failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    assert [p.name for p in tmp_path.iterdir()] == ["out"], "the example wrote outside $JAXPLAN_EXAMPLES_OUT"
    return out


def check_png(path: Path) -> None:
    """A PNG image of at least 400 x 250 pixels with something drawn (not one flat colour)."""
    import matplotlib.image as mpimg

    assert path.is_file(), f"{path.name} was not written"
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", f"{path.name} is not a PNG"
    img = mpimg.imread(path)
    assert img.shape[0] >= 250 and img.shape[1] >= 400, f"{path.name} is {img.shape[1]}x{img.shape[0]} px"
    rgb = img[..., :3]
    assert rgb.std() > 0.05 and len(np.unique(rgb.reshape(-1, 3), axis=0)) > 16, f"{path.name} looks blank"


@pytest.mark.slow
def test_compare_planners(tmp_path):
    out = run_example("compare_planners", tmp_path)
    for fig in ("compare_planners_gaps.png", "compare_planners_paths.png"):
        check_png(out / fig)
    res = json.loads((out / "compare_planners.json").read_text())
    assert set(res["planners"]) == {"astar", "aco", "iaco", "praco"}
    astar = np.array(res["planners"]["astar"]["gap"], float)
    assert astar.shape == (12, 3) and np.all(np.abs(astar) < 1e-6), "A* must match the .scen optimum"
    for name, r in res["planners"].items():
        gaps = np.array([g for row in r["gap"] for g in row if g is not None])
        assert len(gaps) == round(r["success"] * 36), name
        assert np.all(gaps >= -1e-6), f"{name} beat the optimum of an 8-connected grid"  # f32 sums: ~1e-8


@pytest.mark.slow
def test_walkers(tmp_path):
    out = run_example("walkers", tmp_path)
    for fig in ("walkers_episode.png", "walkers_stats.png"):
        check_png(out / fig)
    gif = out / "walkers.gif"
    assert gif.read_bytes()[:6] in (b"GIF89a", b"GIF87a")
    from PIL import Image

    with Image.open(gif) as im:
        assert im.n_frames >= 10
    stats = json.loads((out / "walkers.json").read_text())
    assert set(stats) == {"dwa", "mppi"}
    for s in stats.values():
        assert len(s["success"]) == 4
        for ok, c, a, p in zip(s["success"], s["collisions"], s["active_contacts"], s["passive_contacts"],
                               strict=True):
            assert a + p == c and (not ok or c == 0)  # a contact ends the episode (stop_on_collision)


@pytest.mark.slow
def test_experiment_pandas(tmp_path):
    out = run_example("experiment_pandas", tmp_path)
    check_png(out / "experiment_pandas_paired.png")
    with open(out / "runs" / "iaco_beta-quick" / "trials.csv") as f:
        trials = list(csv.DictReader(f))
    assert len(trials) == 2 * 5 * 4 * 3  # maps x planners x quick scenarios x quick seeds
    assert all(abs(float(t["optimality_gap"])) < 1e-6 for t in trials if t["planner"] == "A*")
    with open(out / "experiment_pandas_paired.csv") as f:
        paired = list(csv.DictReader(f))
    assert len(paired) == 2 * 3 * 2  # maps x IACO variants x metrics
    assert all(np.isfinite(float(r["mean"])) and float(r["ci95"]) >= 0 for r in paired)


@pytest.mark.slow
def test_tune_mppi(tmp_path):
    out = run_example("tune_mppi", tmp_path)
    check_png(out / "tune_mppi_search.png")
    res = json.loads((out / "tune_mppi.json").read_text())
    s = res["summary"]
    assert s["evaluations"] == 4 * 3  # the quick population x generations
    for name, (lo, hi) in s["space"].items():
        assert lo <= s["best"][name] <= hi, name
    with open(out / "runs" / "mppi_weights-quick" / "generations.csv") as f:
        best = [float(r["best"]) for r in csv.DictReader(f)]
    assert len(best) == 3 and best == sorted(best, reverse=True)
    assert set(res["navigation"]) == {"defaults", "tuned"}
    assert all(0.0 <= r["success"] <= 1.0 for r in res["navigation"].values())


@pytest.mark.slow
def test_ros_map(tmp_path):
    out = run_example("ros_map", tmp_path)
    check_png(out / "ros_map.png")
    res = json.loads((out / "ros_map.json").read_text())
    assert res["keepout_cells_on_path"]["without"] > 0 and res["keepout_cells_on_path"]["with"] == 0
    assert res["length_with_mask"] > res["length_without_mask"]
    for local, d in res["drives"].items():
        v, cap = np.array(d["v"]), np.array(d["cap"])
        assert (cap < cap.max()).any(), f"{local} never entered a speed zone"
        for i in np.flatnonzero(v > cap + 1e-4):  # only while braking on entering a slower cell
            assert i > 0 and (cap[i - 1] > cap[i] or v[i] < v[i - 1]), (local, i, v[i], cap[i])


@pytest.mark.slow
def test_tsp(tmp_path):
    import jaxplan as jp

    out = run_example("tsp", tmp_path)
    check_png(out / "tsp.png")
    res = json.loads((out / "tsp.json").read_text())
    problem = jp.load_tsplib(data_dir() / "tsplib" / "eil51.tsp")
    assert res["optimum"] == 426 and res["n"] == 51
    for runs in res["runs"].values():
        assert len(runs) == 3
        for r in runs:
            assert sorted(r["tour"]) == list(range(51))
            assert r["length"] >= res["optimum"] and jp.tour_length(problem, r["tour"]) == r["length"]
