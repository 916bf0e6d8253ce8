"""The experiment harness's TSP kind and the cui2025 / yu2020 metrics it gained (accuracy, line-of-sight
smoothing before/after).

A tiny 8-city instance (written to a temporary folder, its optimum found by brute force) runs a small P-RACO
through `run_experiment` once per module; the tests check the run folder, its determinism, resume, the
per-seed identity with `jaxplan.solve_tsp`, the Max/Min columns and the figures.
"""

from __future__ import annotations

import csv
import itertools
from pathlib import Path

import numpy as np
import pytest

import jaxplan as jp
from jaxplan.experiments import accuracy, read_manifest, reductions, run_experiment
from jaxplan.experiments.config import ConfigError, parse_config

CITIES = [(0, 0), (3, 1), (6, 0), (7, 4), (5, 7), (2, 8), (-1, 5), (1, 3)]
OVERRIDES = {"colonies": 2, "ants": 4, "iterations": 6}


def _csv(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def instance(tmp_path_factory) -> Path:
    """An 8-city EUC_2D instance and its optimal tour (brute force over the 7! orders from city 1)."""
    d = tmp_path_factory.mktemp("tsp")
    lines = "\n".join(f"{i + 1} {x} {y}" for i, (x, y) in enumerate(CITIES))
    (d / "tiny8.tsp").write_text(f"NAME : tiny8\nTYPE : TSP\nDIMENSION : {len(CITIES)}\nEDGE_WEIGHT_TYPE : EUC_2D\n"
                                 f"NODE_COORD_SECTION\n{lines}\nEOF\n")
    prob = jp.load_tsplib(d / "tiny8.tsp")
    best = min(((0,) + p for p in itertools.permutations(range(1, len(CITIES)))),
               key=lambda t: jp.tour_length(prob, np.asarray(t)))
    (d / "tiny8.opt.tour").write_text("NAME : tiny8.opt.tour\nTYPE : TOUR\nDIMENSION : 8\nTOUR_SECTION\n"
                                      + "\n".join(str(c + 1) for c in best) + "\n-1\nEOF\n")
    return d / "tiny8.tsp"


def _tsp_config(instance: Path, name: str = "tsp_tiny") -> str:
    over = ", ".join(f"{k} = {v}" for k, v in OVERRIDES.items())
    return f"""
metrics = ["success", "tour_length", "optimality_gap", "converged_iteration", "optimum_iteration", "plan_time_s"]
[experiment]
name = "{name}"
seeds = [0, 1, 7]
[experiment.quick]
seeds = 2
overrides = {{ iterations = 3 }}
[[instances]]
name = "tiny"
path = "{instance}"
[[instances]]
name = "tiny_again"
path = "{instance}"
optimum = 1.0
[[planners]]
label = "P-RACO"
kind = "tsp"
name = "praco"
overrides = {{ {over} }}
[stats]
pairwise = false
extremes = true
[[figures]]
kind = "convergence"
[[figures]]
kind = "tours"
seed = 7
[paper]
source = "made-up numbers for the test"
[[paper.values]]
planner = "P-RACO"
tour_length = {{ mean = 30.0, sd = 1.0, min = 28.0, max = 33.5 }}
"""


@pytest.fixture(scope="module")
def tsp_run(instance, tmp_path_factory) -> Path:
    cfg = tmp_path_factory.mktemp("cfg") / "tsp.toml"
    cfg.write_text(_tsp_config(instance))
    return run_experiment(cfg, tmp_path_factory.mktemp("runs"), progress=False)


# ---------------------------------------------------------------------------------------------
# The TSP kind


def test_tsp_run_writes_one_row_per_instance_and_seed(tsp_run, instance):
    rows = _csv(tsp_run / "trials.csv")
    assert [(r["map"], r["seed"]) for r in rows] == [(m, s) for m in ("tiny", "tiny_again") for s in ("0", "1", "7")]
    prob = jp.load_tsplib(instance)
    opt = jp.tour_length(prob, jp.load_tour(instance.with_name("tiny8.opt.tour")))
    for r in rows:
        assert r["kind"] == "tsp" and r["success"] == "1" and r["start_x"] == "" and r["scen_row"] == "-1"
        assert 0 <= int(r["converged_iteration"]) < OVERRIDES["iterations"]
        # yu2020's count from 1 of the iteration the final best was found: never before the 1 % convergence.
        assert int(r["converged_iteration"]) + 1 <= int(r["optimum_iteration"]) <= OVERRIDES["iterations"]
        length = float(r["tour_length"])
        want = opt if r["map"] == "tiny" else 1.0  # the optimal tour file, or the configured optimum
        assert float(r["optimal"]) == want and float(r["optimality_gap"]) == pytest.approx(length / want - 1)
        assert length >= opt - 1e-9


def test_tsp_trials_are_solve_tsp_per_seed(tsp_run, instance):
    """The batched chunk runs `solve_tsp`'s program: every seed's tour length and convergence iterations agree
    (`solve_tsp`'s info gives the 0-based iteration the final best tour was found: yu2020's count less one)."""
    prob = jp.load_tsplib(instance)
    for r in _csv(tsp_run / "trials.csv"):
        if r["map"] != "tiny":
            continue
        res = jp.solve_tsp(prob, planner="praco", seed=int(r["seed"]), **OVERRIDES)
        assert float(r["tour_length"]) == res.length
        assert int(r["optimum_iteration"]) == res.info["converged_iteration"] + 1
        h = np.asarray(res.history, np.float64)
        assert int(r["converged_iteration"]) == np.flatnonzero(h <= 1.01 * h[-1])[0]  # within 1 %


def test_tsp_same_seeds_give_identical_trials_and_resume(tsp_run, instance, tmp_path):
    cfg = tmp_path / "tsp.toml"
    cfg.write_text(_tsp_config(instance))
    out = tmp_path / "runs"
    run_experiment(cfg, out, progress=False, stop_after=1)  # one of the two chunks, then "killed"
    assert len(read_manifest(out / "tsp_tiny")["chunks"]) == 1
    run_dir = run_experiment(cfg, out, progress=False)
    assert (run_dir / "trials.csv").read_bytes() == (tsp_run / "trials.csv").read_bytes()
    assert {e["session"] for e in read_manifest(run_dir)["chunks"].values()} == {1, 2}


def test_tsp_summary_has_max_min_and_the_paper_beside_ours(tsp_run):
    rows = {(r["map"], r["metric"]): r for r in _csv(tsp_run / "summary.csv")}
    trials = _csv(tsp_run / "trials.csv")
    lengths = [float(t["tour_length"]) for t in trials if t["map"] == "tiny"]
    r = rows["tiny", "tour_length"]
    assert float(r["min"]) == min(lengths) and float(r["max"]) == max(lengths)
    assert float(r["mean"]) == pytest.approx(np.mean(lengths)) and float(r["sd"]) == pytest.approx(
        np.std(lengths, ddof=1))
    assert (r["paper_mean"], r["paper_min"], r["paper_max"]) == ("30.0", "28.0", "33.5")
    md = (tsp_run / "summary.md").read_text()
    assert "paper: tour_length" in md and "30 ± 1 [28, 33.5]" in md
    assert "TSPLIB tiny8.tsp, 8 cities (EUC_2D)" in (tsp_run / "report.md").read_text()


def test_tsp_figures(tsp_run, tmp_path):
    from jaxplan.experiments.figures import draw_figures

    drawn, problems = draw_figures(tsp_run, tmp_path)
    assert not problems and {d.kind for d in drawn} == {"convergence", "tours"}
    assert (tmp_path / tsp_run.name / "tours.png").stat().st_size > 0


def test_bad_tsp_config_values_fail_in_validation_with_their_key_paths(tmp_path):
    text = f"""
[experiment]
name = "bad_tsp"
[[instances]]
path = "{tmp_path / 'no-such.tsp'}"
[[instances]]
name = "b"
path = "{tmp_path / 'also-missing.tsp'}"
tour = "missing.opt.tour"
optimum = 5.0
[[planners]]
kind = "tsp"
name = "pracoo"
[[planners]]
label = "AS"
kind = "tsp"
name = "aco"
overrides = {{ antz = 3, rho = 1.5 }}
[[planners]]
label = "AS2"
kind = "tsp"
name = "aco"
overrides = {{ rho = 1.5 }}
[paper]
source = "x"
[[paper.values]]
planner = "AS"
tour_length = {{ mean = 1.0, median = 2.0 }}
"""
    with pytest.raises(ConfigError) as e:
        parse_config(text, data_dir=tmp_path)
    problems = e.value.problems
    assert any(p.startswith("instances[0].path: file not found") for p in problems), problems
    assert any(p.startswith("instances[1].tour: file not found") for p in problems), problems
    assert "instances[1]: give 'tour' (the optimal tour file) or 'optimum' (its length), not both" in problems
    assert any(p.startswith("planners[0].name: unknown TSP planner 'pracoo'") and "'praco'" in p for p in problems)
    assert any(p.startswith("planners[1].overrides.antz: TSP planner 'aco' has no parameter 'antz'")
               for p in problems), problems
    assert any(p.startswith("planners[2].overrides: ") and "rho" in p for p in problems), problems
    assert any(p.startswith("paper.values[0].tour_length: expected a number") for p in problems), problems


def test_planner_kinds_need_their_sites(tmp_path):
    text = """
[experiment]
name = "sites"
[[maps]]
generator = "warehouse_yu2020"
[[planners]]
kind = "tsp"
name = "praco"
"""
    with pytest.raises(ConfigError) as e:
        parse_config(text, data_dir=tmp_path)
    assert "maps[0]: no plan or navigate planner is configured to run on 'warehouse_yu2020'" in e.value.problems
    assert any(p.startswith("planners[0].kind: a kind = 'tsp' planner runs on [[instances]]")
               for p in e.value.problems), e.value.problems


def test_yu2020_tsp_config_validates_and_quick_keeps_eil51(tsplib):
    from jaxplan.experiments.config import apply_quick, load_config

    root = Path(__file__).resolve().parents[1]
    cfg = load_config(root / "configs" / "yu2020_tsp.toml", data_dir=tsplib.parent)
    assert [m.name for m in cfg.maps] == ["eil51", "berlin52"] and all(m.is_tsp for m in cfg.maps)
    assert len(cfg.seeds) == 50 and {p.name for p in cfg.planners} == {"aco", "praco"}
    praco = next(p for p in cfg.planners if p.name == "praco")
    assert dict(praco.overrides) == {"colonies": 5, "ants": 35, "iterations": 200}
    q = apply_quick(cfg)
    assert [m.name for m in q.maps] == ["eil51"] and [p.label for p in q.planners] == ["P-RACO"]
    assert q.planners[0].overrides["iterations"] == 20 and len(q.seeds) == 2


# ---------------------------------------------------------------------------------------------
# cui2025's accuracy and yu2020's smoothing reductions


def test_accuracy_on_a_hand_built_case():
    success = np.array([1, 1, 1, 0, 0, np.nan, 1])
    gap = np.array([0.05, 0.1, 0.1000001, 0.0, np.nan, 0.0, np.nan])
    # within 10 % (inclusive) / exactly 10 % / just over / a failure (whatever its gap) / undefined cases
    np.testing.assert_array_equal(accuracy(success, gap), [1.0, 1.0, 0.0, 0.0, 0.0, np.nan, np.nan])
    assert accuracy(np.ones(1), np.array([11.0 / 10.0 - 1.0]))[0] == 1.0  # 0.10000000000000009 counts as 10 %
    assert float(np.nanmean(accuracy(success, gap))) == pytest.approx(2 / 5)
    np.testing.assert_allclose(reductions([10.0, 4.0, 0.0, np.nan], [9.0, 1.0, 0.0, 1.0]), [0.1, 0.75, np.nan, np.nan])


def test_accuracy_and_los_columns_of_a_plan_run(tmp_path):
    """A* (exact: gap 0) and line-of-sight smoothing on a generated warehouse: accuracy = success and gap <= 10 %,
    the smoothed path no longer and with no more turns, reductions 1 - after / before."""
    cfg = tmp_path / "acc.toml"
    cfg.write_text("""
metrics = ["success", "accuracy", "length", "optimality_gap", "turns", "los_length", "los_turns",
           "los_length_reduction", "los_turns_reduction"]
[experiment]
name = "acc"
seeds = 2
chunk = 3
[[maps]]
name = "wh"
generator = "warehouse"
seed = 0
params = { width = 14, height = 10, shelf_length = 4, shelf_depth = 2, aisle = 1, cross_aisle = 2 }
[scenarios]
source = "random"
count = 3
seed = 3
min_distance = 5.0
[[planners]]
label = "A*"
kind = "plan"
name = "astar"
""")
    rows = _csv(run_experiment(cfg, tmp_path / "runs", progress=False) / "trials.csv")
    assert len(rows) == 6
    for r in rows:
        f = {k: float(v) for k, v in r.items() if k in ("success", "accuracy", "length", "optimality_gap", "turns",
                                                         "los_length", "los_turns", "los_length_reduction",
                                                         "los_turns_reduction")}
        assert f["success"] == 1 and abs(f["optimality_gap"]) < 1e-6 and f["accuracy"] == 1.0  # float32: ±1e-7
        assert f["los_length"] <= f["length"] + 1e-9 and f["los_turns"] <= f["turns"]
        assert f["los_length_reduction"] == pytest.approx(1 - f["los_length"] / f["length"])
        if f["turns"] > 0:
            assert f["los_turns_reduction"] == pytest.approx(1 - f["los_turns"] / f["turns"])


def test_executed_optimum_on_an_open_map_is_the_straight_line():
    """The reference of a navigation episode's gap: on a map without obstacles, the line-of-sight smoothed exact
    path is the straight segment between the cell centres."""
    from jaxplan.experiments import MapWork
    from jaxplan.experiments.config import PlannerConfig
    from jaxplan.experiments.trial_metrics import executed_optimum

    grid = jp.grid_from_array(np.ones((12, 16), bool), resolution=0.5)  # all free; the outside counts as blocked
    starts, goals = np.array([[1, 1], [2, 9]]), np.array([[14, 7], [13, 2]])
    mw = MapWork(None, grid, starts, goals, np.zeros(2), np.full(2, -1), "")
    pc = PlannerConfig("p", "navigate", "iaco_dwa")
    got = executed_optimum(mw, pc, np.arange(2))
    np.testing.assert_allclose(got, np.hypot(*(goals - starts).T) * 0.5, rtol=1e-5)
