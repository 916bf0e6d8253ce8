"""The navigation frontier (`jaxplan.experiments.frontier`, configs/navigation.toml): the design read from the planner
entries, the rows' Wilson and t intervals over seeds × rows, the passive-safety line, the page, its figure, the
"Beyond the papers" entry of the results index, and `jaxplan reproduce` writing page and figures from a run."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from conftest import ROOT, config_toml

from jaxplan.experiments.config import ConfigError, apply_quick, load_config, parse_config
from jaxplan.experiments.frontier import (
    SAFETY_ORDER,
    Arm,
    Mean,
    Rate,
    arms,
    frontier_figure,
    frontier_page,
    frontier_rows,
    is_frontier,
    passive_verdict,
    pooled_rows,
)
from jaxplan.experiments.results import Notes, index_page, page_summary, write_index_page
from jaxplan.experiments.verdicts import mean_interval, wilson_interval

MAP = {"name": "m", "generator": "random", "seed": 0, "params": {"width": 10, "height": 10, "obstacle_ratio": 0.1},
       "scenarios": {"source": "random", "count": 2, "min_distance": 5.0}}


def _planner(label: str, pipeline: str, safety: str, behavior: str, speed: float, oracle: bool = False) -> dict:
    nav = {"safety": safety, "stop_on_collision": False, **({"prediction": "oracle"} if oracle else {})}
    return {"label": label, "kind": "navigate", "name": pipeline, "nav": nav,
            "obstacles": {"n": 1, "speed": speed, "radius": 0.25, "behavior": behavior}}


# Labels that say nothing of the design: the coordinates must come from the entries themselves.
PLANNERS = [_planner("p0", "astar_kng_dwa", "none", "blind", 1.0), _planner("p1", "astar_kng_dwa", "passive",
                                                                            "blind", 1.0),
            _planner("p2", "astar_kng_mppi", "predicted", "social", 0.5),
            _planner("p3", "astar_kng_dwa", "none", "blind", 1.0, oracle=True)]


def _config(planners=PLANNERS, **changes):
    text = config_toml(metrics=["success", "active_contacts", "passive_contacts", "time_s"],
                       experiment={"name": "navigation_test", "seeds": 2, "chunk": 2}, maps=[MAP], scenarios=None,
                       planners=planners, **changes)
    return parse_config(text)


def test_arms_come_from_the_planner_entries_not_their_labels():
    got = arms(_config())
    assert got == (Arm("p0", "dwa", "none", "blind", 1.0, False), Arm("p1", "dwa", "passive", "blind", 1.0, False),
                   Arm("p2", "mppi", "predicted", "seeing", 0.5, False), Arm("p3", "dwa", "none", "blind", 1.0, True))
    assert is_frontier("navigation") and is_frontier("navigation_big") and not is_frontier("cui2025_table2")


def test_a_planner_outside_the_design_is_refused():
    with pytest.raises(ValueError, match="among walkers"):
        arms(_config([*PLANNERS, {"label": "A*", "kind": "plan", "name": "astar"}]))
    with pytest.raises(ValueError, match="has no safety mode"):
        arms(_config([{"label": "f", "kind": "navigate", "name": "iaco_follow", "obstacles": {"n": 1}}]))


def test_the_navigation_config_runs_the_whole_design_paired(movingai):
    """configs/navigation.toml: 2 local planners x 3 safety modes x 2 walker kinds x 3 speeds, an oracle ceiling
    per local planner and speed, every planner on the same walker draws (paired), the eight shared maps at
    1 m per cell with rows of optimal <= 80 cells; the quick run two small maps and every kind of arm at one speed."""
    cfg = load_config(ROOT / "configs" / "navigation.toml", data_dir=movingai.parent)
    got = arms(cfg)
    plain = sorted((a.local, a.safety, a.walkers, a.speed) for a in got if not a.oracle)
    assert plain == sorted(itertools.product(("dwa", "mppi"), SAFETY_ORDER, ("blind", "seeing"), (0.5, 1.0, 1.5)))
    oracle = sorted((a.local, a.safety, a.walkers, a.speed) for a in got if a.oracle)
    assert oracle == sorted(itertools.product(("dwa", "mppi"), ("none",), ("blind",), (0.5, 1.0, 1.5)))
    assert {pc.name for pc in cfg.planners} == {"iaco_dwa", "iaco_mppi"}
    assert len({(pc.obstacles.n, pc.obstacles.seed, pc.obstacles.radius, pc.obstacles.avoid_radius)
                for pc in cfg.planners}) == 1  # the same walkers' routes for every arm at a speed
    assert all(pc.nav["stop_on_collision"] is False for pc in cfg.planners)
    assert {m.name for m in cfg.maps} == {"warehouse-10-20-10-2-1", "random-32-32-20", "random-64-64-20",
                                         "room-64-64-8", "maze-32-32-2", "brc202d", "den520d", "ost003d"}
    assert all(m.resolution == 1.0 and m.scenarios.max_optimal == 80.0 and m.scenarios.spread == "even"
               for m in cfg.maps)
    assert is_frontier(cfg.name)
    q = apply_quick(cfg)
    assert [m.name for m in q.maps] == ["random-32-32-20", "maze-32-32-2"]
    qa = arms(q)
    assert {a.speed for a in qa} == {1.0} and len(qa) == 6 and len(q.seeds) == 1
    # the smoke run still takes every path: both local planners, every safety mode, both walker kinds, the ceiling
    assert {a.local for a in qa} == {"dwa", "mppi"} and {a.safety for a in qa} == set(SAFETY_ORDER)
    assert {a.walkers for a in qa} == {"blind", "seeing"} and any(a.oracle for a in qa)
    assert {a.local for a in qa if a.safety == "passive" and not a.oracle} == {"dwa", "mppi"}


# ---------------------------------------------------------------------------------------------
# Rows from trials


def _trials(rows: list[tuple]) -> dict[str, np.ndarray]:
    """trials.csv columns from ``(map, planner, seed, success, active, passive, time_s, reason)`` tuples."""
    cols = list(zip(*rows, strict=True))
    return {"map": np.asarray(cols[0], object), "planner": np.asarray(cols[1], object),
            "seed": np.asarray(cols[2], float), "success": np.asarray(cols[3], float),
            "active_contacts": np.asarray(cols[4], float), "passive_contacts": np.asarray(cols[5], float),
            "time_s": np.asarray(cols[6], float), "reason": np.asarray(cols[7], object)}


NAN = math.nan
TRIALS = _trials([
    # p0: 6 feasible episodes over 2 seeds x 3 rows, 4 successes, 2 with an active contact; one infeasible row.
    ("m", "p0", 0, 1, 0, 0, 10.0, "goal"), ("m", "p0", 0, 1, 0, 0, 12.0, "goal"),
    ("m", "p0", 0, 0, 2, 0, 40.0, "time limit"), ("m", "p0", 1, 1, 0, 0, 14.0, "goal"),
    ("m", "p0", 1, 0, 1, 1, 30.0, "time limit"), ("m", "p0", 1, 1, 0, 0, 16.0, "goal"),
    ("m", "p0", 1, 0, 0, 0, NAN, "infeasible: start closer than d_safe to an obstacle"),
    # p1 (passive): touched only at rest
    ("m", "p1", 0, 1, 0, 0, 20.0, "goal"), ("m", "p1", 0, 0, 0, 2, 60.0, "time limit"),
    ("m", "p1", 1, 1, 0, 0, 22.0, "goal"), ("m", "p1", 1, 1, 0, 1, NAN, "time limit"),
    ("m", "p2", 0, 1, 0, 0, 11.0, "goal"), ("m", "p2", 1, 0, 0, 0, NAN, "time limit"),
    ("m", "p3", 0, 1, 0, 0, 9.0, "goal"), ("m", "p3", 1, 1, 0, 0, 9.5, "goal"),
])


def _by_label(rows):
    return {r.arm.label: r for r in rows}


def test_rows_pool_seeds_and_rows_with_wilson_and_t_intervals():
    cfg = _config()
    rows = frontier_rows(TRIALS, cfg)
    assert list(rows) == ["m"]
    r = _by_label(rows["m"])["p0"]
    assert r.infeasible == 1 and r.episodes == 6  # the infeasible row is counted apart, not run
    assert r.success == Rate(4, 6) and r.success.interval == wilson_interval(4, 6)
    assert r.touched == Rate(2, 6) and r.touched.interval == wilson_interval(2, 6)
    lo, hi = mean_interval([0, 0, 2, 0, 1, 0])
    assert r.active.mean == pytest.approx(0.5) and lo < 0 and (r.active.lo, r.active.hi) == (0.0, hi)  # clipped at 0
    assert r.passive.mean == pytest.approx(1 / 6)
    # time to goal: the successful episodes only (a failed one's 40 s does not count)
    assert r.time.n == 4 and r.time.mean == pytest.approx(13.0)
    assert (r.time.lo, r.time.hi) == mean_interval([10.0, 12.0, 14.0, 16.0])
    # order: DWA's plain arms (blind, by speed, by safety), DWA's oracle, then MPPI
    assert [x.arm.label for x in rows["m"]] == ["p0", "p1", "p3", "p2"]
    pooled = {(x.arm.local, x.arm.safety, x.arm.oracle): x for x in pooled_rows(TRIALS, cfg)}
    assert list(pooled) == [("dwa", "none", False), ("dwa", "passive", False), ("dwa", "none", True),
                            ("mppi", "predicted", False)]
    assert pooled["dwa", "none", False].success == Rate(4, 6) and pooled["dwa", "passive", False].success == Rate(3, 4)


def test_a_cell_without_episodes_or_interval_says_so():
    assert Rate(0, 0).cell() == "–" and Mean.of(np.array([])).cell() == "–"
    assert Mean.of(np.array([3.0])).cell() == "3"  # one value: no interval, the mean alone
    assert Rate(0, 5).cell().startswith("0 [0, ")


def test_the_passive_line_holds_only_when_no_passive_row_had_an_active_contact():
    cfg = _config()
    rows = frontier_rows(TRIALS, cfg)
    assert passive_verdict(rows) == (True, 1, 4, [])
    page = frontier_page(rows, pooled_rows(TRIALS, cfg), cfg)
    assert "**Passive safety: zero active contacts in every passive-mode row** (1 rows, 4 episodes)" in page
    touched = dict(TRIALS)
    touched["active_contacts"] = TRIALS["active_contacts"].copy()
    touched["active_contacts"][(TRIALS["planner"] == "p1") & (TRIALS["seed"] == 1)] = [1, 0]
    bad = frontier_rows(touched, cfg)
    zero, n, eps, offenders = passive_verdict(bad)
    assert zero is False and offenders == ["m: p1 (1 of 4 episodes)"]
    assert "active contacts in 1 of 1 passive-mode rows" in frontier_page(bad, pooled_rows(touched, cfg), cfg)


def test_the_page_has_a_table_per_map_with_the_oracle_ceiling_and_a_summary_for_the_index():
    cfg = _config()
    rows = frontier_rows(TRIALS, cfg)
    page = frontier_page(rows, pooled_rows(TRIALS, cfg), cfg, quick=True)
    s = page_summary(page)
    assert s["beyond"] is True and s["quick"] is True and s["passive_zero"] is True and s["episodes"] == 14
    assert "QUICK" in page.splitlines()[0] and "## m" in page
    table = [ln for ln in page.split("## m", 1)[1].splitlines() if ln.startswith("| ")]
    head = [c.strip() for c in table[0].strip("|").split("|")]
    assert head[-1].startswith("oracle ceiling") and "success % [Wilson 95 %]" in head
    body = {ln.split("|")[4].strip() + ln.split("|")[2].strip(): ln for ln in table[2:]}
    ceiling = Rate(2, 2).cell()
    # a blind row carries its planner's and speed's oracle success; a seeing row has no route oracle
    assert body["noneblind"].rstrip(" |").endswith(ceiling) and body["passiveblind"].rstrip(" |").endswith(ceiling)
    assert body["predictedseeing"].rstrip(" |").endswith("–")
    assert body["oracle (none)blind"].count(Rate(4, 6).cell()) == 0  # the ceiling row is its own, not p0's
    assert "`passive`" in page and "no faster than a known bound" in page  # the guarantee's assumption is stated


def test_the_index_lists_pages_beyond_the_papers(tmp_path):
    cfg = _config()
    rows = frontier_rows(TRIALS, cfg)
    (tmp_path / "navigation_test.md").write_text(frontier_page(rows, pooled_rows(TRIALS, cfg), cfg))
    (tmp_path / "notes.md").write_text("# not a results page\n")
    out = write_index_page(tmp_path, Notes())
    text = out.read_text()
    assert "## Beyond the papers" in text
    line = next(ln for ln in text.splitlines() if "(navigation_test.md)" in ln)
    assert "14 episodes" in line and "zero active contacts in all 1 rows" in line
    assert "notes.md" not in text
    # without such a page, no section; a quick page goes only to the quick index
    assert "Beyond the papers" not in index_page([], Notes())
    assert "Beyond the papers" not in write_index_page(tmp_path, Notes(), quick=True).read_text()


def test_the_figure_has_a_point_per_arm_with_its_intervals_and_a_legend_for_every_encoding():
    from matplotlib.container import ErrorbarContainer

    from jaxplan.experiments.plots import plt

    cfg = _config()
    rows = frontier_rows(TRIALS, cfg)["m"]
    fig, caption = frontier_figure("m", rows)
    try:
        assert len(fig.axes) == 4  # DWA and MPPI, each: against active contacts and against time
        bars = [[c for c in ax.containers if isinstance(c, ErrorbarContainer)] for ax in fig.axes]
        assert [len(b) for b in bars] == [3, 3, 1, 1]  # p2 (MPPI) has one success: its time point has no t interval
        p0 = bars[0][0]
        x, y = p0.lines[0].get_data()
        assert (x[0], y[0]) == pytest.approx((100 * 2 / 6, 100 * 4 / 6))
        texts = [t.get_text() for t in fig.legends[0].get_texts()]
        for want in ("safety none", "safety passive", "safety predicted", "blind walkers", "seeing walkers",
                     "walkers at 0.5 m/s", "walkers at 1 m/s"):
            assert want in texts, texts
        assert any(t.startswith("oracle prediction") for t in texts)
        assert "Wilson 95 %" in caption and "Student-t" in caption
    finally:
        plt.close(fig)


def test_reproduce_writes_the_frontier_page_figures_and_index(tmp_path):
    """A frontier config through `jaxplan reproduce`: the run, one figure per map, the page and its index line."""
    from jaxplan.cli import main

    small = [_planner("none", "astar_kng_dwa", "none", "blind", 0.5), _planner("fast", "astar_kng_dwa", "none",
                                                                                  "blind", 1.0)]
    text = config_toml(metrics=["success", "active_contacts", "passive_contacts", "time_s"],
                       experiment={"name": "navigation", "seeds": 1, "chunk": 1}, maps=[MAP], scenarios=None,
                       planners=[{**p, "nav": {**p["nav"], "max_time": 20.0, "replan": False}} for p in small])
    configs = tmp_path / "configs"
    configs.mkdir()
    (configs / "navigation.toml").write_text(text)
    rc = main(["reproduce", "--configs", str(configs), "--pattern", "navigation.toml", "--out", str(tmp_path / "runs"),
               "--figures", str(tmp_path / "figures"), "--results", str(tmp_path / "results"), "--no-progress",
               "--no-cache"])
    assert rc == 0
    page = (tmp_path / "results" / "navigation.md").read_text()
    assert "![m: the frontier](../figures/navigation/frontier_m.png)" in page
    assert (tmp_path / "figures" / "navigation" / "frontier_m.png").is_file()
    assert "frontier_m" in (tmp_path / "figures" / "navigation" / "index.md").read_text()
    assert "(navigation.md)" in (tmp_path / "results" / "index.md").read_text()


def test_a_frontier_config_with_an_unknown_safety_is_refused():
    with pytest.raises(ConfigError, match="safety"):
        _config([_planner("x", "astar_kng_dwa", "sometimes", "blind", 1.0)])
