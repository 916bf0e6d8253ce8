"""Tuning studies (`jaxplan.tune.run_study`): held-out splits, counted equal budgets, best.toml into `jaxplan run`,
determinism and exact resume; the own-objective gap and multi-map objectives they use."""

from __future__ import annotations

import csv
import json
import shutil

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxplan as jp
from jaxplan.experiments.config import ConfigError
from jaxplan.tune import (
    STRATEGIES,
    CountedObjective,
    Split,
    check_disjoint,
    function_objective,
    make_strategy,
    parse_study_config,
    path_costs,
    run_study,
    tune_loop,
)

STUDY = """
[tune]
name = "s"
kind = "aco"
planner = "iaco"
train_count = 2
train_seeds = 2
test_seeds = [50, 51]
overrides = { ants = 4, iterations = 2 }
[tune.space]
alpha = [0.5, 3.0]
lambdas = [[0.0, 1.0], [0.0, 1.0], [0.0, 1.0]]
delta = [0.0, 1.0]
[study]
methods = ["grid", "random", "cma_es"]
tuner_seeds = 2
budget = 8
population = 4
gap = "own"
held_out_count = 2
confirm_seeds = [70]
confirm_count = 1
[[maps]]
name = "r"
generator = "random"
seed = 2
params = { width = 10, height = 10, obstacle_ratio = 0.15 }
scenarios = { source = "random", count = 4, seed = 0, min_distance = 4.0 }
"""


def _write(tmp_path, text=STUDY, name="s.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def _log(folder) -> list[dict]:
    with open(folder / "log.csv", newline="") as f:
        return [{k: v for k, v in r.items() if k != "wall_s"} for r in csv.DictReader(f)]


def test_overlapping_splits_raise():
    a = Split(np.array([[0, 0], [1, 1]]), np.array([[3, 3], [4, 4]]), np.ones(2), (0, 1))
    check_disjoint(a, a._replace(starts=np.array([[2, 2]]), goals=np.array([[5, 5]]), seeds=(9,)))
    with pytest.raises(ValueError, match="share seeds"):
        check_disjoint(a, a._replace(seeds=(1, 7)))
    with pytest.raises(ValueError, match="share a scenario row"):
        check_disjoint(a, a._replace(starts=np.array([[1, 1]]), goals=np.array([[4, 4]]), seeds=(9,)))


@pytest.mark.parametrize("edit, match", [
    (("test_seeds = [50, 51]", "test_seeds = [1, 51]"), "must not share seeds"),
    (("confirm_seeds = [70]", "confirm_seeds = [51]"), "confirm_seeds: must not meet"),
    (("budget = 8", "budget = 10"), "not a multiple of study.population"),
    (('methods = ["grid", "random", "cma_es"]', 'methods = ["grid", "random", "cmaes"]'), "unknown strategy 'cmaes'"),
    (('gap = "own"', 'gap = "mine"'), "study.gap"),
    (("tuner_seeds = 2", "tuner_seed = 2"), "study.tuner_seed: unknown key"),
])
def test_bad_study_configs_name_the_key(edit, match):
    with pytest.raises(ConfigError, match=match):
        parse_study_config(STUDY.replace(*edit))


def test_a_held_out_row_that_is_a_training_row_is_refused(tmp_path):
    # an open 2x2 map has four diagonal pairs: 8 draws repeat one in both splits
    text = STUDY.replace("params = { width = 10, height = 10, obstacle_ratio = 0.15 }",
                         "params = { width = 2, height = 2, obstacle_ratio = 0.0 }").replace(
        'scenarios = { source = "random", count = 4, seed = 0, min_distance = 4.0 }',
        'scenarios = { source = "random", count = 8, seed = 0, min_distance = 1.4 }').replace(
        "train_count = 2", "train_count = 4").replace("held_out_count = 2", "held_out_count = 4")
    with pytest.raises(ValueError, match="share a scenario row"):
        run_study(_write(tmp_path, text), out=tmp_path / "runs", progress=False)


def test_every_strategy_spends_exactly_the_counted_budget(tmp_path):
    """The wrapper counts every weight vector a strategy has evaluated on the training split."""
    obj = function_objective(lambda x, s: jnp.sum((x - 0.3) ** 2), {"a": (0.0, 1.0), "b": (0.0, 1.0)})
    counts = {}
    for name in STRATEGIES:
        counted = CountedObjective(obj)
        tune_loop(counted, make_strategy(name, 4, 3), 3, tmp_path / name, progress=False)
        obj.evaluate(np.zeros((2, 2)), "test")  # held-out evaluations of the objective itself are not charged
        counts[name] = counted.count
    assert set(counts.values()) == {12}, counts


def test_the_strategies_that_say_they_ignore_the_key_do():
    """A study runs a strategy with ``uses_key=False`` once for all tuner seeds: that must be exactly what another
    seed would have done, and every other strategy must really differ between seeds."""
    from jaxplan.tune import STRATEGY_SPECS

    bounds = function_objective(lambda x, s: jnp.sum(x), {"a": (0.0, 1.0), "b": (0.0, 1.0)}).bounds
    for name, spec in STRATEGY_SPECS.items():
        strat = make_strategy(name, 4, 3)
        asks = []
        for seed in (0, 1):
            key = jax.random.key(seed)
            state = strat.init(key, bounds, np.array([0.4, 0.6], np.float32))
            pops = []
            for _ in range(3):
                key, k = jax.random.split(key)
                pop = strat.ask(k, state)
                state = strat.tell(state, pop, jnp.sum((pop - 0.3) ** 2, axis=1))
                pops.append(np.asarray(pop))
            asks.append(np.stack(pops))
        assert np.array_equal(asks[0], asks[1]) == (not spec.uses_key), name


def test_own_objective_path_costs_match_exact_search():
    grid = jp.grid_from_array(np.ones((6, 8), bool))
    w = dict(lambdas=(0.5, 0.3, 0.2))
    terms = jp.search.objective_terms(grid, np.array([[0, 0]]), np.array([[7, 4]]), "iaco", **w)
    for planner_path in (jp.search.exact_objective(grid, (0, 0), (7, 4), "iaco", **w).path,
                         jp.plan(grid, (0, 0), (7, 4), planner="astar").path):
        cells = jnp.asarray(planner_path[:, 1] * grid.width + planner_path[:, 0])
        ours = float(path_costs(cells, jnp.asarray(len(planner_path) - 1), grid.width, 1.0,
                                jnp.float32(terms.w_len[0]), terms.w_angle, terms.w_turn,
                                jnp.asarray(terms.cell, jnp.float32)))
        ref = jp.search.path_objectives(planner_path[None], np.array([len(planner_path)]), grid, "iaco", **w)[0]
        assert ours == pytest.approx(ref, rel=1e-5)


@pytest.mark.slow  # ~1 min on 2 shared cores: three studies of a tiny colony (one compilation each) and one run
def test_study_log_budget_best_toml_and_resume(tmp_path, monkeypatch):
    import jaxplan.tune.study.run as study
    from jaxplan.experiments.config import load_config

    cfg = _write(tmp_path)
    a = run_study(cfg, out=tmp_path / "a", progress=False, results=tmp_path / "res", confirm=True)
    s = json.loads((a / "summary.json").read_text())
    # every method and tuner seed received the same counted budget
    assert {m: r["evaluations"] for m, r in s["methods"].items()} == {"grid": 8, "random": 8, "cma_es": 8}
    # the grid ran once (it does not depend on the tuner seed); its run stands for the second seed
    assert sorted(p.name for p in (a / "runs").iterdir()) == ["cma_es-s0", "cma_es-s1", "grid-s0", "random-s0",
                                                              "random-s1"]
    g = s["methods"]["grid"]["per_seed"]
    assert g["0"] == g["1"]
    # compilation is paid in the process's first run (the grid's) and taken out of the wall times compared
    assert s["methods"]["grid"]["compile_s"]["mean"] > 0
    assert s["compile_s_total"] >= s["methods"]["grid"]["compile_s"]["mean"]
    for r in s["methods"].values():
        assert r["run_s"]["mean"] == pytest.approx(r["wall_s"]["mean"] - r["compile_s"]["mean"])
        assert 0 < r["run_s"]["mean"] < r["wall_s"]["mean"] or r["compile_s"]["mean"] == 0
    sessions = json.loads((a / "sessions.json").read_text())
    assert len(sessions) == 1 and sessions[0]["generations"] == 5 * 2  # five runs of two generations
    rows = _log(a)
    assert {int(r["evaluations"]) for r in rows if r["generation"] == "2"} == {8}
    assert all(np.isfinite(float(r["heldout_best"])) for r in rows)
    assert s["defaults"]["heldout"] >= -1e-5  # the own-objective gap of a colony is never below its optimum
    for f in ("s.md", "s.png", "s_best.toml", "s_confirm.toml", "s_confirm.md"):
        assert (tmp_path / "res" / f).is_file(), f

    # same seeds: the same log (wall times aside)
    b = run_study(cfg, out=tmp_path / "b", progress=False)
    assert _log(b) == rows
    man = json.loads((b / "checkpoints" / "manifest.json").read_text())
    assert sorted(man["runs"]) == ["cma_es-s0", "cma_es-s1", "grid-s0", "random-s0", "random-s1"]

    # the committed runs are read back (checked against their SHA-256), not run again
    real = study.tune_loop

    def never(*args, **kw):
        raise AssertionError("a committed run ran again")

    monkeypatch.setattr(study, "tune_loop", never)
    assert _log(run_study(cfg, out=tmp_path / "b", progress=False)) == rows
    monkeypatch.setattr(study, "tune_loop", real)

    # a folder of an earlier version (no commit log: its runs are in runs/ alone) resumes from those runs
    shutil.rmtree(b / "checkpoints")
    assert _log(run_study(cfg, out=tmp_path / "b", progress=False)) == rows
    assert len(json.loads((b / "sessions.json").read_text())) == 3

    # interrupted after the first generation of the second run, then resumed: the same log
    calls = {"n": 0}

    def interrupted(*args, callback=None, **kw):
        calls["n"] += 1

        def cb(g, row):
            callback(g, row)
            if calls["n"] == 2 and g == 1:
                raise KeyboardInterrupt

        return real(*args, callback=cb, **kw)

    monkeypatch.setattr(study, "tune_loop", interrupted)
    with pytest.raises(KeyboardInterrupt):
        run_study(cfg, out=tmp_path / "c", progress=False)
    monkeypatch.setattr(study, "tune_loop", real)
    c = run_study(cfg, out=tmp_path / "c", progress=False)
    assert _log(c) == rows

    # two workers with disjoint methods in one folder (side by side in practice, one per core), then the page
    # pass: the same log, and the page pass finds every run done and every held-out score stored by the workers
    w = tmp_path / "w"
    run_study(cfg, out=w, progress=False, only=["cma_es", "grid"])
    run_study(cfg, out=w, progress=False, only=["random"])
    assert not (w / "s" / "heldout.json").exists() and not (w / "s" / "log.csv").exists()
    assert len(list((w / "s").glob("worker-*.json"))) == 2
    evaluated = []
    real_eval = study._HeldOut.scores

    def counted_scores(self, xs):
        evaluated.extend(study._key(x) for x in xs if study._key(x) not in self.cache)
        return real_eval(self, xs)

    def finished(*args, **kw):
        res = real(*args, **kw)
        assert res.resumed_from == args[2]  # every generation was done by a worker
        return res

    monkeypatch.setattr(study._HeldOut, "scores", counted_scores)
    monkeypatch.setattr(study, "tune_loop", finished)
    d = run_study(cfg, out=w, progress=False)
    monkeypatch.undo()
    assert _log(d) == rows
    assert len(evaluated) == 1  # the defaults alone: the runs' held-out scores came from the workers' folders
    sessions = json.loads((d / "sessions.json").read_text())
    assert sorted(x.get("worker") is not None for x in sessions) == [False, True, True]
    assert not list(d.glob("worker-*.json"))
    assert "2 of them workers (`--only`) running side by side" in (d / "page.md").read_text()

    # best.toml round-trips into `jaxplan run`: the confirmation ran the defaults and the tuned weights
    run = tmp_path / "a" / "s_confirm"
    exp = load_config(run / "config.toml")
    assert (tmp_path / "a" / "s" / "best.toml").read_text() in (tmp_path / "a" / "s" / "confirm.toml").read_text()
    tuned = {p.label: p for p in exp.planners}["IACO (tuned)"]
    for k, v in s["best"]["weights"].items():
        assert np.allclose(tuned.overrides[k], v), k
    with open(run / "trials.csv", newline="") as f:
        planners = {r["planner"] for r in csv.DictReader(f)}
    assert planners == {"IACO (defaults)", "IACO (tuned)"}


@pytest.mark.parametrize("kw, match", [({"only": ["sparrow"]}, "sparrow not among the study's methods"),
                                       ({"only": []}, "give at least one of the study's methods"),
                                       ({"only": ["grid"], "resume": False}, "not with a fresh start"),
                                       ({"only": ["grid"], "confirm": True}, "or the confirmation")])
def test_a_worker_is_refused_a_method_the_study_lacks_or_a_fresh_start(tmp_path, kw, match):
    with pytest.raises(ValueError, match=match):
        run_study(_write(tmp_path), out=tmp_path / "w", progress=False, **kw)
    assert not (tmp_path / "w").exists()  # refused before any work


def test_the_study_command_lists_every_config_problem_before_any_work(tmp_path, capsys):
    from jaxplan.cli import main

    bad = _write(tmp_path, STUDY.replace("budget = 8", "budget = 1").replace('gap = "own"', 'gap = "mine"'))
    assert main(["study", str(bad), "--out", str(tmp_path / "runs")]) == 2
    err = capsys.readouterr().err
    assert "study.budget" in err and "study.gap" in err
    assert not (tmp_path / "runs").exists()
