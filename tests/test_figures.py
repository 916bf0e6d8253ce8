"""`jaxplan figures RUN`: every configured figure kind is drawn from a run folder, as PNG and SVG, with an index.

Two tiny runs are shared: plan planners (A*, a small Ant System) on three generated random
maps of rising obstacle ratio, and one navigation pipeline among two moving discs on a
generated warehouse (quick: one scenario, two seeds, short episodes).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import ASTAR, SMALL_ACO, config_toml, merged, unlabelled_marks

from jaxplan.cli import main
from jaxplan.experiments import run_experiment
from jaxplan.experiments.config import ConfigError, parse_config
from jaxplan.experiments.figures import draw_figures

PLAN_FIGURES = [
    {"kind": "convergence", "band": "iqr"}, {"kind": "diversity", "band": "sd"}, {"kind": "box", "metric": "length"},
    {"kind": "bar", "metric": "turns"}, {"kind": "bar", "name": "success_bar", "metric": "success"},
    {"kind": "sweep", "metric": "turns", "x": "obstacle_ratio", "xlabel": "obstacle ratio"},
    {"kind": "paths", "maps": ["r10"], "scenario": 1, "seed": 1},
    {"kind": "pheromone", "maps": ["r10"], "planners": ["AS"]},
]


def _random_map(name: str, ratio: float, size: int = 14) -> dict:
    return {"name": name, "generator": "random", "seed": 1,
            "params": {"width": size, "height": size, "obstacle_ratio": ratio}}


def _plan(**changes) -> str:
    """A* and a small Ant System on three random maps (obstacle ratio 0.1, 0.2, 0.3), with every plan figure kind
    (`conftest.config_toml` with ``changes``)."""
    base = dict(
        metrics=["success", "length", "turns", "smoothness", "plan_time_s"],
        experiment={"name": "figplan", "description": "figures test: plan planners against obstacle ratio"},
        maps=[_random_map(f"r{int(r * 100)}", r) for r in (0.1, 0.2, 0.3)],
        scenarios={"count": 2, "seed": 0, "min_distance": 6.0},
        planners=[ASTAR, {**SMALL_ACO, "overrides": {"ants": 6, "iterations": 4, "dead_end": "retreat"}}],
        figures=PLAN_FIGURES,
        paper={"source": "made-up numbers for the test", "values": [
            {"planner": "AS", "map": "r20", "turns": [7.0, 1.0], "success": [0.9, 0.05]}]})
    return config_toml(**merged(base, changes))


NAV_FIGURES = [{"kind": "trajectories"}, {"kind": "controls", "seed": 1}, {"kind": "fan", "steps": [5]},
               {"kind": "paths"}]


def _nav(**changes) -> str:
    """A KNG-DWA robot among two moving discs on the tiny warehouse, one scenario, with every navigate figure
    kind (`conftest.config_toml` with ``changes``)."""
    base = dict(
        metrics=["success", "collisions", "time_s", "energy"], experiment={"name": "fignav", "chunk": 1},
        scenarios={"count": 1, "min_distance": 6.0},
        planners=[{"label": "KNG-DWA", "kind": "navigate", "name": "astar_kng_dwa",
                   "nav": {"max_time": 12.0, "replan": False}, "dwa": {"n_v": 5, "n_omega": 9},
                   "obstacles": {"n": 2, "speed": 0.4, "radius": 0.2, "seed": 0}}],
        figures=NAV_FIGURES)
    return config_toml(**merged(base, changes))


@pytest.fixture(scope="module")
def plan_run(tmp_path_factory) -> Path:
    cfg = tmp_path_factory.mktemp("cfg") / "figplan.toml"
    cfg.write_text(_plan())
    return run_experiment(cfg, tmp_path_factory.mktemp("runs"), progress=False)


@pytest.fixture(scope="module")
def nav_run(tmp_path_factory) -> Path:
    cfg = tmp_path_factory.mktemp("cfg") / "fignav.toml"
    cfg.write_text(_nav())
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
    bars = {d.name: d for d in drawn if d.kind == "bar"}
    # turns on a generated map: the paper's 7 turns are withheld (not comparable), and the caption says so.
    assert "paper's reported values" not in bars["bar"].caption
    assert "for AS are not drawn: an absolute number on a stand-in map is not comparable" in bars["bar"].caption
    # a success rate is comparable on any map: the paper's bar (± its sd) stands beside ours.
    assert "paper's reported values ± its sd (made-up numbers for the test), not ours" in bars["success_bar"].caption
    assert "Wilson 95 % interval" in bars["success_bar"].caption


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
    text = _plan(figures=PLAN_FIGURES[:-1] + [{"kind": "paths", "smoothing": "lso"}, PLAN_FIGURES[-1]])
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
    text = _nav(figures=NAV_FIGURES[:2] + [{"kind": "fan", "steps": [-1]}, {"kind": "sweep", "x": [1, 2]}])
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

    sweep = {"kind": "sweep", "metric": "success", "x": [0.01, 0.1, 10.0], "xlabel": "obstacle ratio"}
    figures = [sweep if f["kind"] == "sweep" else {**f, "maps": ["r0"]} if "maps" in f else f for f in PLAN_FIGURES]
    cfg = tmp_path / "figlog.toml"
    cfg.write_text(_plan(experiment={"name": "figlog"}, maps=[_random_map(f"r{i}", 0.1, 12) for i in range(3)],
                         figures=figures, paper={"values": [{"planner": "AS", "map": "r1", "turns": [7.0, 1.0],
                                                             "success": [0.9, 0.05]}]}))
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


def test_convergence_is_drawn_in_absolute_cost_one_panel_per_cost_definition(plan_run):
    """A* is left out; one planner (AS: cost = length) keeps its own cost in metres, one panel per map; the
    paper gives no iteration for AS here, so no vertical line is drawn."""
    from jaxplan.experiments.figure_kinds import DRAW
    from jaxplan.experiments.plots import plt
    from jaxplan.experiments.run_data import load_run

    run = load_run(plan_run)
    spec = next(f for f in run.config.figures if f.kind == "convergence")
    fig, caption = DRAW["convergence"](run, spec)
    try:
        assert [ax.get_ylabel() for ax in fig.axes] == ["best path length L (m)"] * 3
        assert "relative" not in caption and "own cost" in caption and "paper" not in caption
        assert all(len(ax.lines) == 1 for ax in fig.axes)  # the median line, no marker
        # Absolute cost: the curve ends at the run's final best length (m), not at 0 %.
        got = run.arrays(0, 1, 0)
        final = np.median(np.asarray(got[0]["history"][got[1]], np.float64)[:, -1])
        assert fig.axes[0].lines[0].get_ydata()[-1] == pytest.approx(final)
    finally:
        plt.close(fig)


def _with_paper(run, values, paper_map: bool):
    """``run`` with extra paper values and every map flagged as the paper's own (or not)."""
    import dataclasses

    cfg = run.config.replace(paper=tuple(run.config.paper) + tuple(values))
    maps = tuple(dataclasses.replace(mw, spec=dataclasses.replace(mw.spec, paper_map=paper_map))
                 for mw in run.prep.maps)
    return dataclasses.replace(run, config=cfg, prep=dataclasses.replace(run.prep, maps=maps))


@pytest.mark.parametrize("paper_map", [True, False])
def test_the_papers_convergence_iteration_is_marked_only_where_comparable(plan_run, paper_map):
    """yu2020's optimum iteration 3 for AS on r10: a dashed line at x = 3 on the paper's own map; on a stand-in
    map the caption names the number and says why it is not drawn."""
    from jaxplan.experiments.config import PaperValue
    from jaxplan.experiments.figure_kinds import DRAW
    from jaxplan.experiments.plots import plt
    from jaxplan.experiments.run_data import load_run

    run = _with_paper(load_run(plan_run), [PaperValue(planner="AS", map="r10", metric="optimum_iteration",
                                                      mean=3.0)], paper_map)
    spec = next(f for f in run.config.figures if f.kind == "convergence")
    fig, caption = DRAW["convergence"](run, spec)
    try:
        r10 = next(ax for ax in fig.axes if ax.get_title().startswith("r10"))
        marks = [ln for ln in r10.lines if ln.get_label().startswith("paper: iteration")]
        if paper_map:
            assert len(marks) == 1 and list(marks[0].get_xdata()) == [3.0, 3.0]
            assert marks[0].get_label() == "paper: iteration 3 (AS)" and marks[0].get_linestyle() == "--"
            assert "paper: iteration 3 (AS)" in [t.get_text() for t in r10.get_legend().get_texts()]
            assert "AS: 3 (optimum_iteration)" in caption
        else:
            assert not marks
            assert "(AS: 3 (optimum_iteration)) are not marked" in caption and "stand-in" in caption
    finally:
        plt.close(fig)


def _error_bar_ys(ax) -> list[tuple[float, float]]:
    """(low, high) of every vertical error bar drawn on ``ax`` (bar charts and errorbar lines)."""
    from matplotlib.collections import LineCollection

    out = []
    for c in ax.collections:
        if isinstance(c, LineCollection):
            out += [(float(min(s[:, 1])), float(max(s[:, 1]))) for s in c.get_segments() if len(s) == 2]
    return out


def _wilson_by_hand(k: int, n: int, z: float = 1.959963984540054) -> tuple[float, float]:
    """The Wilson score interval's closed form: (p + z²/2n ± z·sqrt(p(1 − p)/n + z²/4n²)) / (1 + z²/n)."""
    p = k / n
    centre, half = p + z * z / (2 * n), z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return (centre - half) / (1 + z * z / n), (centre + half) / (1 + z * z / n)


def test_proportions_get_wilson_intervals_inside_0_100_and_the_papers_sd(plan_run):
    """Each bar is the share of the 4 trials (2 seeds x 2 scenarios) of its map and planner, its error bar the
    Wilson interval of k of 4 (closed form), never past 100 %; the paper's 90 ± 5 % is drawn with its sd on r20
    only."""
    from jaxplan.experiments.figure_kinds import DRAW
    from jaxplan.experiments.plots import plt
    from jaxplan.experiments.run_data import load_run

    run = load_run(plan_run)
    t = run.trials
    spec = next(f for f in run.config.figures if f.name == "success_bar")
    fig, _ = DRAW["bar"](run, spec)
    try:
        for ax in fig.axes[:3]:
            assert ax.get_ylim()[1] <= 105.0 + 1e-9
            ys = _error_bar_ys(ax)
            for planner in ("A*", "AS"):
                rows = (t["map"] == ax.get_title()) & (t["planner"] == planner)
                k, n = int(np.sum(t["success"][rows])), int(np.sum(rows))
                assert n == 4
                lo, hi = _wilson_by_hand(k, n)
                assert (100 * lo, 100 * hi) in [(pytest.approx(a), pytest.approx(b)) for a, b in ys]
            assert all(0.0 <= lo and hi <= 100.0 + 1e-9 for lo, hi in ys[:2])
            if ax.get_title() == "r20":
                assert len(ys) == 3 and (pytest.approx(85.0), pytest.approx(95.0)) == ys[2]
            else:
                assert len(ys) == 2
    finally:
        plt.close(fig)


def test_wilson_interval_hand_computed():
    """k = n: [1 / (1 + z²/n), 1]; k = 0: [0, (z²/n) / (1 + z²/n)] (the Wilson score formula at p = 1 and 0)."""
    from jaxplan.experiments.figure_kinds import _wilson

    z2 = 1.959963984540054 ** 2
    assert _wilson(2, 2) == pytest.approx((1.0 / (1.0 + z2 / 2.0), 1.0))
    assert _wilson(0, 10) == pytest.approx((0.0, (z2 / 10.0) / (1.0 + z2 / 10.0)), abs=1e-12)
    lo, hi = _wilson(5, 10)  # symmetric about 1/2: 0.5 ± z·sqrt(0.25/10 + z²/400) / (1 + z²/10)
    half = z2 ** 0.5 * (0.25 / 10 + z2 / 400) ** 0.5 / (1 + z2 / 10)
    assert (lo, hi) == pytest.approx((0.5 - half, 0.5 + half))
    assert all(np.isnan(_wilson(0, 0)))


def test_the_comparability_rule():
    from jaxplan.experiments.comparability import ABSOLUTE_METRICS, comparable
    from jaxplan.experiments.config import METRICS

    assert ABSOLUTE_METRICS <= set(METRICS)
    for metric in ("length", "turns", "converged_iteration", "turning_point", "optimum_iteration", "collisions",
                   "time_s", "energy", "tour_length"):
        assert not comparable(metric, paper_map=False) and comparable(metric, paper_map=True)
    for metric in ("success", "accuracy", "arrived", "optimality_gap", "smoothness", "max_curvature",
                   "los_length_reduction"):
        assert comparable(metric, paper_map=False)
    assert all(not comparable(m, False) for m in METRICS if METRICS[m].timing)  # wall times: never


def test_li2026s_curvature_names_the_ackermann_limit():
    """li2026_table3's robots: wheelbase 0.5 m, steering limit 0.6 rad -> tan(0.6)/0.5 = 1.3683 1/m."""
    from jaxplan.experiments.config import load_config
    from jaxplan.experiments.figure_kinds import _draw_steering_limits, _steering_limits
    from jaxplan.experiments.plots import plt

    cfg = load_config(Path(__file__).parents[1] / "configs" / "li2026_table3.toml")
    limits = _steering_limits(cfg, range(len(cfg.planners)))
    assert limits == [pytest.approx((0.6, 0.5, 1.368274))]
    fig, ax = plt.subplots()
    try:
        _draw_steering_limits(ax, limits)
        (line,) = ax.lines
        assert list(line.get_ydata()) == pytest.approx([1.368274] * 2)
        assert line.get_label() == "Ackermann limit tan(δmax)/L = tan(0.6 rad)/0.5 m = 1.37 1/m"
    finally:
        plt.close(fig)


def test_map_legends_sit_outside_the_map(plan_run):
    """The paths figure's legend (every path, start and goal) is drawn below the map axes, not over it."""
    from jaxplan.experiments.figure_kinds import DRAW
    from jaxplan.experiments.plots import plt
    from jaxplan.experiments.run_data import load_run

    run = load_run(plan_run)
    spec = next(f for f in run.config.figures if f.kind == "paths")
    fig, _ = DRAW["paths"](run, spec)
    try:
        fig.canvas.draw()
        ax = fig.axes[0]
        legend = ax.get_legend()
        assert [t.get_text() for t in legend.get_texts()] == ["A*", "AS", "start", "goal"]
        assert legend.get_window_extent().y1 < ax.get_window_extent().y0
    finally:
        plt.close(fig)


# ---------------------------------------------------------------------------------------------
# One visual language (issue 43, item 4)


def _draw(run_dir, kind):
    from jaxplan.experiments.figure_kinds import DRAW
    from jaxplan.experiments.run_data import load_run

    run = load_run(run_dir)
    spec = next(f for f in run.config.figures if f.kind == kind)
    return DRAW[kind](run, spec)[0]


def test_start_and_goal_look_the_same_in_every_figure_kind(plan_run, nav_run):
    """A green circle and a red star in the paths figure (plan planners) and the trajectories figure
    (navigation), as in `jaxplan.experiments.style`."""
    from matplotlib.colors import to_rgba

    from jaxplan.experiments import style
    from jaxplan.experiments.plots import plt

    seen = []
    for run_dir, kind in ((plan_run, "paths"), (nav_run, "trajectories")):
        fig = _draw(run_dir, kind)
        try:
            ax = fig.axes[0]
            marks = {ln.get_label(): ln for ln in ax.lines if ln.get_label() in ("start", "goal")}
            seen.append({k: (ln.get_marker(), to_rgba(ln.get_markerfacecolor())) for k, ln in marks.items()})
        finally:
            plt.close(fig)
    assert seen[0] == seen[1] == {"start": ("o", to_rgba(style.START["color"])),
                                  "goal": ("*", to_rgba(style.GOAL["color"]))}


def test_trajectories_draw_walkers_at_their_true_radius_and_name_every_mark(nav_run):
    from jaxplan.experiments.plots import plt

    fig = _draw(nav_run, "trajectories")
    try:
        ax = fig.axes[0]
        discs = [p for p in ax.patches if type(p).__name__ == "Circle" and p.get_edgecolor()[:3] == (0, 0, 0)
                 and p.get_facecolor()[3] < 1]
        walkers = [p for p in discs if p.get_radius() == pytest.approx(0.2)]  # the config's obstacles radius
        assert len(walkers) == 2
        assert not unlabelled_marks(ax), unlabelled_marks(ax)
        fig.canvas.draw()
        legend = ax.get_legend()
        assert legend.get_window_extent().y1 < ax.get_window_extent().y0
    finally:
        plt.close(fig)


def test_the_fan_figure_names_every_line_and_marker_outside_the_map(nav_run):
    """cui2025 Fig. 4's fan: red, blue and black rollouts, the sub-goal and the robot, each in the legend; the
    sub-goal is not a star (the goal's marker)."""
    from jaxplan.experiments.plots import plt

    fig = _draw(nav_run, "fan")
    try:
        ax = fig.axes[0]
        assert not unlabelled_marks(ax), unlabelled_marks(ax)
        texts = [t.get_text() for t in ax.get_legend().get_texts()]
        for want in ("feasible rollouts", "chosen rollout", "robot (footprint to scale)", "executed", "global path"):
            assert want in texts, texts
        sub = next(ln for ln in ax.lines if ln.get_label().startswith("sub-goal"))
        assert sub.get_marker() != "*"
        fig.canvas.draw()
        assert ax.get_legend().get_window_extent().y1 < ax.get_window_extent().y0
    finally:
        plt.close(fig)


def test_the_accuracy_axis_reads_its_threshold_once():
    """Not "gap <= 10 % (%)": the threshold as a length ratio, the unit as a share of trials."""
    from jaxplan.experiments.run_data import metric_label

    label = metric_label("accuracy")
    assert label == "accuracy: success with length <= 1.1 x optimum (% of trials)"
    assert "% (%)" not in label
