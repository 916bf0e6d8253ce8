"""`jaxplan figures RUN`: every configured figure kind is drawn from a run folder, as PNG and SVG, with an index.

Two tiny runs are shared: plan planners (A*, a small Ant System) on three generated random
maps of rising obstacle ratio, and one navigation pipeline among two moving discs on a
generated warehouse (quick: one scenario, two seeds, short episodes).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from jaxplan.cli import main
from jaxplan.experiments import run_experiment
from jaxplan.experiments.config import ConfigError, parse_config
from jaxplan.experiments.figures import draw_figures

PLAN = """
metrics = ["success", "length", "turns", "smoothness", "plan_time_s"]

[experiment]
name = "figplan"
description = "figures test: plan planners against obstacle ratio"
seeds = 2
chunk = 2

{maps}

[scenarios]
source = "random"
count = 2
seed = 0
min_distance = 6.0

[[planners]]
label = "A*"
kind = "plan"
name = "astar"

[[planners]]
label = "AS"
kind = "plan"
name = "aco"
overrides = { ants = 6, iterations = 4, dead_end = "retreat" }

[[figures]]
kind = "convergence"
band = "iqr"

[[figures]]
kind = "diversity"
band = "sd"

[[figures]]
kind = "box"
metric = "length"

[[figures]]
kind = "bar"
metric = "turns"

[[figures]]
kind = "sweep"
metric = "turns"
x = "obstacle_ratio"
xlabel = "obstacle ratio"

[[figures]]
kind = "paths"
maps = ["r10"]
scenario = 1
seed = 1

[[figures]]
kind = "pheromone"
maps = ["r10"]
planners = ["AS"]

[paper]
source = "made-up numbers for the test"
[[paper.values]]
planner = "AS"
map = "r20"
turns = [7.0, 1.0]
"""

MAPS = "\n".join(f"""
[[maps]]
name = "r{int(r * 100)}"
generator = "random"
seed = 1
params = {{ width = 14, height = 14, obstacle_ratio = {r} }}
""" for r in (0.1, 0.2, 0.3))

NAV = """
metrics = ["success", "collisions", "time_s", "energy"]

[experiment]
name = "fignav"
seeds = 2
chunk = 1

[[maps]]
name = "wh"
generator = "warehouse"
seed = 0
params = { width = 14, height = 10, shelf_length = 4, shelf_depth = 2, aisle = 1, cross_aisle = 2 }

[scenarios]
source = "random"
count = 1
seed = 3
min_distance = 6.0

[[planners]]
label = "KNG-DWA"
kind = "navigate"
name = "astar_kng_dwa"
nav = { max_time = 12.0, replan = false }
dwa = { n_v = 5, n_omega = 9 }
obstacles = { n = 2, speed = 0.4, radius = 0.2, seed = 0 }

[[figures]]
kind = "trajectories"

[[figures]]
kind = "controls"
seed = 1

[[figures]]
kind = "fan"
steps = [5]

[[figures]]
kind = "paths"
"""


@pytest.fixture(scope="module")
def plan_run(tmp_path_factory) -> Path:
    cfg = tmp_path_factory.mktemp("cfg") / "figplan.toml"
    cfg.write_text(PLAN.replace("{maps}", MAPS))
    return run_experiment(cfg, tmp_path_factory.mktemp("runs"), progress=False)


@pytest.fixture(scope="module")
def nav_run(tmp_path_factory) -> Path:
    cfg = tmp_path_factory.mktemp("cfg") / "fignav.toml"
    cfg.write_text(NAV)
    return run_experiment(cfg, tmp_path_factory.mktemp("runs"), progress=False)


def _check(out: Path, run: str, drawn, problems, kinds: set[str]) -> None:
    assert not problems, problems
    assert {d.kind for d in drawn} == kinds
    for d in drawn:
        assert d.files == (f"{d.name}.png", f"{d.name}.svg")
        assert (out / run / d.files[0]).stat().st_size > 5_000
        assert (out / run / d.files[1]).read_text().lstrip().startswith("<?xml")
    index = (out / run / "index.md").read_text()
    assert all(f"]({d.name}.png)" in index and d.caption in index for d in drawn)
    assert f"[{run}]({run}/index.md)" in (out / "index.md").read_text()


def test_plan_figures(plan_run, tmp_path):
    drawn, problems = draw_figures(plan_run, tmp_path)
    _check(tmp_path, "figplan", drawn, problems,
           {"convergence", "diversity", "box", "bar", "sweep", "paths", "pheromone"})
    bar = next(d for d in drawn if d.kind == "bar")
    assert "paper's reported values (made-up numbers for the test), not ours" in bar.caption


def test_paths_figure_with_a_smoother(plan_run, tmp_path):
    """yu2020 Fig. 11: each path and, dashed, the same path after line-of-sight smoothing. The run folder is
    copied with a config naming only this figure (figures do not enter the run's fingerprint)."""
    import shutil

    run = tmp_path / "figplan"
    shutil.copytree(plan_run, run)
    text = (run / "config.toml").read_text()
    (run / "config.toml").write_text(text[: text.index("[[figures]]")] + '[[figures]]\nkind = "paths"\n'
                                     'name = "paths_los"\nmaps = ["r10"]\nsmoothing = "los"\n\n'
                                     + text[text.index("[paper]"):])
    drawn, problems = draw_figures(run, tmp_path / "out")
    assert not problems and [d.name for d in drawn] == ["paths_los"]
    assert "dashed: the same path after the 'los' smoother" in drawn[0].caption
    assert (tmp_path / "out" / "figplan" / "paths_los.png").stat().st_size > 5_000


def test_an_unknown_smoother_of_a_paths_figure_is_a_config_problem():
    text = PLAN.replace("{maps}", MAPS).replace('[[figures]]\nkind = "pheromone"',
                                                '[[figures]]\nkind = "paths"\nsmoothing = "lso"\n\n'
                                                '[[figures]]\nkind = "pheromone"')
    with pytest.raises(ConfigError) as e:
        parse_config(text)
    assert any(p.startswith("figures[") and ".smoothing: must be one of" in p and "did you mean 'los'" in p
               for p in e.value.problems), e.value.problems


@pytest.mark.slow  # 18-38 s each on 2 cores; the suite must stay well under CI's 20 minutes
def test_nav_figures_through_the_cli(nav_run, tmp_path, capsys):
    assert main(["figures", str(nav_run), "--out", str(tmp_path)]) == 0
    assert "wrote 4 figures" in capsys.readouterr().out
    for stem in ("trajectories", "controls", "fan", "paths"):
        assert (tmp_path / "fignav" / f"{stem}.png").is_file()


def test_figures_of_a_missing_run_folder(tmp_path, capsys):
    assert main(["figures", str(tmp_path / "nope")]) == 2
    assert "is not a run folder" in capsys.readouterr().err


def test_bad_figure_entries_are_config_problems():
    text = NAV.replace('kind = "fan"\nsteps = [5]', 'kind = "fan"\nsteps = [-1]').replace(
        '[[figures]]\nkind = "paths"', '[[figures]]\nkind = "sweep"\nx = [1, 2]')
    with pytest.raises(ConfigError) as e:
        parse_config(text)
    msg = str(e.value)
    assert "figures[2].steps" in msg and "figures[3].metric: required" in msg and "figures[3].x: expected 1" in msg


def _axis_labels(fig) -> list[str]:
    """Every non-empty axis label of a figure (colour bars included)."""
    return [lab for ax in fig.axes for lab in (ax.get_xlabel(), ax.get_ylabel()) if lab]


@pytest.mark.parametrize("which", ["plan", "nav"])
def test_every_axis_label_names_its_unit(plan_run, nav_run, which):
    """Issue 28, item 5: every axis reads "quantity (unit)"; fractions in %, raw metric keys never."""
    import re

    from jaxplan.experiments.config import METRICS
    from jaxplan.experiments.figure_kinds import DRAW
    from jaxplan.experiments.plots import plt
    from jaxplan.experiments.run_data import load_run

    run = load_run(plan_run if which == "plan" else nav_run)
    for spec in run.config.figures:
        fig, _ = DRAW[spec.kind](run, spec)
        try:
            labels = _axis_labels(fig)
            assert labels, spec.kind
            for lab in labels:
                assert re.search(r"\(.+\)", lab), f"{spec.kind}: axis label {lab!r} names no unit"
                assert not any(k in lab for k in METRICS if "_" in k), f"{spec.kind}: raw metric key in {lab!r}"
        finally:
            plt.close(fig)


def test_sweeps_over_orders_of_magnitude_use_a_log_axis_and_fractions_read_in_percent(tmp_path):
    from jaxplan.experiments.figure_kinds import DRAW
    from jaxplan.experiments.plots import plt
    from jaxplan.experiments.run_data import load_run

    maps = "\n".join(f"""
[[maps]]
name = "r{i}"
generator = "random"
seed = 1
params = {{ width = 12, height = 12, obstacle_ratio = 0.1 }}
""" for i in range(3))
    text = (PLAN.replace("{maps}", maps).replace('x = "obstacle_ratio"', "x = [0.01, 0.1, 10.0]")
            .replace('metric = "turns"\nx =', 'metric = "success"\nx =').replace('map = "r20"', 'map = "r1"')
            .replace('maps = ["r10"]', 'maps = ["r0"]'))
    cfg = tmp_path / "figlog.toml"
    cfg.write_text(text.replace('name = "figplan"', 'name = "figlog"'))
    run = load_run(run_experiment(cfg, tmp_path / "runs", progress=False))
    spec = next(f for f in run.config.figures if f.kind == "sweep")
    fig, caption = DRAW["sweep"](run, spec)
    try:
        ax = fig.axes[0]
        assert ax.get_xscale() == "log" and "log axis" in caption
        assert ax.get_ylabel() == "success rate (%)"
        assert max(max(line.get_ydata()) for line in ax.lines) == pytest.approx(100.0)
    finally:
        plt.close(fig)


def test_convergence_of_planners_with_different_costs_is_drawn_relative_to_each_runs_final_best(plan_run):
    """A* is left out; one planner (AS: cost = length) keeps its own cost in metres; mixed costs would not."""
    from jaxplan.experiments.figure_kinds import DRAW
    from jaxplan.experiments.plots import plt
    from jaxplan.experiments.run_data import load_run

    run = load_run(plan_run)
    spec = next(f for f in run.config.figures if f.kind == "convergence")
    fig, caption = DRAW["convergence"](run, spec)
    try:
        assert fig.axes[0].get_ylabel() == "best path length L (m)"
        assert "relative" not in caption
    finally:
        plt.close(fig)
