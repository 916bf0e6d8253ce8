"""The experiment harness: config validation, reproducible trials, resume after SIGKILL, statistics.

One tiny experiment (a generated 14x10 warehouse, A* and a small Ant System, 5 random
scenarios in chunks of 2, 3 seeds) is run once per module and shared.
"""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import ASTAR, SMALL_ACO, config_toml, merged
from scipy import stats as sps

from jaxplan.cli import main
from jaxplan.experiments import RunFolderError, read_manifest, run_experiment
from jaxplan.experiments.config import ConfigError, apply_quick, load_config, parse_config

ROOT = Path(__file__).resolve().parents[1]

TINY_ACO = {**SMALL_ACO, "overrides": {"ants": 6, "iterations": 4, "dead_end": "retreat"}}


def _tiny(**changes) -> str:
    """The tiny experiment (A* and a small Ant System on the 14x10 warehouse, 5 scenarios x 3 seeds, a paper value)
    with ``changes`` (`conftest.config_toml`)."""
    base = dict(
        metrics=["success", "length", "optimality_gap", "turns", "smoothness", "converged_iteration", "plan_time_s"],
        experiment={"name": "tiny", "description": "harness test", "seeds": 3, "chunk": 2,
                    "quick": {"seeds": 2, "count": 2, "overrides": {"iterations": 2}}},
        scenarios={"count": 5}, planners=[ASTAR, TINY_ACO],
        stats={"anova": True, "pairwise": True, "metrics": ["length", "smoothness"]},
        paper={"source": "made-up numbers for the test", "values": [{"planner": "AS", "length": [99.5, 1.5]}]})
    return config_toml(**merged(base, changes))


TINY = _tiny()


def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def tiny_config(tmp_path_factory) -> Path:
    return _write(tmp_path_factory.mktemp("cfg") / "tiny.toml", TINY)


@pytest.fixture(scope="module")
def reference(tiny_config, tmp_path_factory) -> Path:
    """An uninterrupted in-process run of the tiny experiment."""
    return run_experiment(tiny_config, tmp_path_factory.mktemp("ref"), progress=False)


def _csv(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


# ---------------------------------------------------------------------------------------------
# Validation


BAD = """
metrics = ["success", "length", "smoothness", "turns", "lenght"]

[experiment]
name = "bad"
seeds = -3
chunck = 4

[[maps]]
path = "movingai/no-such-map.map"

[[maps]]
generator = "warehouse"
params = { width = 20, hieght = 20 }

[[planners]]
kind = "plan"
name = "aco"
overrides = { ants = 10, antz = 5 }

[[planners]]
kind = "plan"
name = "iaco"
overrides = { rho = 1.5 }

[[planners]]
kind = "plan"
name = "iaco2"

[[planners]]
kind = "navigate"
name = "iaco_dwa"
nav = { max_tme = 10.0 }
obstacles = { n = -1 }

[stats]
metrics = ["energy"]

[paper]
source = "x"
[[paper.values]]
planner = "IACO"
length = 1.0
"""


def test_bad_config_lists_every_problem_before_any_work(tmp_path, monkeypatch):
    import jaxplan as jp

    def boom(*a, **k):  # pragma: no cover - reached only if validation let work start
        raise AssertionError("planning started before validation finished")

    monkeypatch.setattr(jp, "plan_batch", boom)
    monkeypatch.setattr(jp, "navigate_batch", boom)
    cfg = _write(tmp_path / "bad.toml", BAD)
    with pytest.raises(ConfigError) as ei:
        run_experiment(cfg, tmp_path / "runs", data_dir=tmp_path)
    problems = ei.value.problems
    text = "\n".join(problems)
    expected = [
        "experiment.seeds: must be >= 1, got -3",
        "experiment.chunck: unknown key; did you mean 'chunk'?",
        "metrics[4]: unknown metric 'lenght'",
        f"maps[0].path: file not found: {tmp_path / 'movingai' / 'no-such-map.map'}",
        "maps[1].params.hieght: generator 'warehouse' has no parameter 'hieght'",
        "planners[0].overrides.antz: planner 'aco' has no parameter 'antz'",
        "planners[1].overrides: planner 'iaco': parameter 'rho' must lie in [0, 1]",
        "planners[2].name: unknown planner 'iaco2' (known: ",
        "planners[3].nav.max_tme: unknown key; did you mean 'max_time'?",
        "planners[3].obstacles.n: must be >= 0, got -1",
        "stats.metrics[0]: 'energy' is not one of the configured metrics",
        "paper.values[0].planner: unknown planner label 'IACO'",
    ]
    for e in expected:
        assert e in text, f"missing problem {e!r} in:\n{text}"
    assert len(problems) == len(expected), text
    assert str(ei.value).count("\n  - ") == len(problems)  # one message lists them all
    assert not (tmp_path / "runs").exists()


def test_cli_exits_2_with_the_problems(tmp_path, capsys):
    cfg = _write(tmp_path / "bad.toml", BAD)
    assert main(["run", str(cfg), "--out", str(tmp_path / "runs"), "--data-dir", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "12 problems" in err and "planners[2].name: unknown planner 'iaco2'" in err


@pytest.mark.parametrize("text, problem", [
    ("[experiment]\nname = 'x'\nseeds = [1, 1]\n", "experiment.seeds: seeds must be distinct"),
    ("[experiment]\nname = 'a/b'\n", "experiment.name: must match"),
    ("[experiment]\nname = 'x'\nseeds = 'many'\n", "experiment.seeds: expected a seed count"),
    ("[experiment\nname = 'x'\n", "TOML syntax"),
    ("colour = 1\n[experiment]\nname = 'x'\n", "colour: unknown key"),
    ("[experiment]\nname = 'x'\n[[maps]]\ngenerator = 'warehouse'\n[scenarios]\nsource = 'scen'\n",
     "scenarios.source: a generated map has no scenario file"),
    ("[experiment]\nname = 'x'\n[[planners]]\nkind = 'plan'\nname = 'astar'\nlabel = 'A'\n[[planners]]\nkind = 'plan'"
     "\nname = 'aco'\nlabel = 'A'\n", "planners[1].label: duplicate label 'A'"),
    ("metrics = ['rmse']\n[experiment]\nname = 'x'\n[[planners]]\nkind = 'plan'\nname = 'astar'\n",
     "metrics[0]: metric 'rmse' applies to kind navigate planners"),
    ("[experiment]\nname = 'x'\n[[planners]]\nkind = 'plan'\nname = 'astar'\n[[figures]]\nkind = 'box'\nmetric = 'x'"
     "\nbnd = 1\n", "figures[0].bnd: unknown key"),
])
def test_single_problems(text, problem, tmp_path):
    with pytest.raises(ConfigError) as ei:
        parse_config(text, data_dir=tmp_path)
    assert any(problem in p for p in ei.value.problems), ei.value.problems


@pytest.mark.parametrize("override, problem", [
    ({"alpha": [1.0, 2.0]}, "parameter 'alpha' must be a single number, got (1.0, 2.0)"),
    ({"rho": [0.1]}, "parameter 'rho' must be a single number, got (0.1,)"),
    ({"alpha": True}, "parameter 'alpha' must be a real number (not a bool or a string), got True"),
    ({"alpha": "1.0"}, "parameter 'alpha' must be a real number (not a bool or a string), got '1.0'"),
    ({"lambdas": [0.5, True, 0.2]}, "parameter 'lambdas' must be a real number (not a bool or a string) per "
                                    "component"),
    ({"lambdas": [0.5, 0.3]}, "lambdas must be three weights"),
])
def test_planner_weights_need_their_default_shape_and_real_numbers(override, problem, tmp_path):
    text = _tiny(planners=[ASTAR, {**TINY_ACO, "name": "iaco", "overrides": {**override, **TINY_ACO["overrides"]}}])
    with pytest.raises(ConfigError) as ei:
        parse_config(text, data_dir=tmp_path)
    assert len(ei.value.problems) == 1 and ei.value.problems[0].startswith("planners[1].overrides: planner 'iaco': ")
    assert problem in ei.value.problems[0], ei.value.problems


def _quick_nav(max_time) -> str:
    """A navigate experiment whose ``[experiment.quick]`` sets ``nav.max_time``."""
    return config_toml(
        experiment={"name": "quicknav", "seeds": 2, "chunk": None,
                    "quick": {"seeds": 1, "nav": {"max_time": max_time}}},
        maps=[{"name": "g", "generator": "random", "params": {"width": 12, "height": 12, "obstacle_ratio": 0.1},
               "scenarios": {"source": "random", "count": 1, "min_distance": 4.0}}], scenarios=None,
        planners=[{"label": "nav", "kind": "navigate", "name": "iaco_dwa", "overrides": {"ants": 8, "iterations": 3}}])


@pytest.mark.parametrize("value", [-5.0, float("nan"), "x"])
def test_quick_nav_values_are_checked_at_load_time(value, tmp_path):
    with pytest.raises(ConfigError) as ei:
        parse_config(_quick_nav(value), data_dir=tmp_path)
    assert len(ei.value.problems) == 1, ei.value.problems
    assert ei.value.problems[0].startswith("experiment.quick.nav.max_time: for 'nav': NavConfig.max_time must be")


def test_good_quick_nav_values_pass(tmp_path):
    assert dict(apply_quick(parse_config(_quick_nav(7.5), data_dir=tmp_path)).planners[0].nav) == {"max_time": 7.5}


def test_quick_changes_seeds_counts_and_overrides(tiny_config):
    cfg = load_config(tiny_config)
    q = apply_quick(cfg)
    assert cfg.seeds == (0, 1, 2) and q.seeds == (0, 1)
    assert q.maps[0].scenarios.count == 2 and q.is_quick
    assert dict(q.planners[1].overrides) == {"ants": 6, "iterations": 2, "dead_end": "retreat"}
    assert dict(q.planners[0].overrides) == {}  # A* has no iterations: the override skips it


# ---------------------------------------------------------------------------------------------
# Runs


def test_run_folder(reference):
    for f in ("config.toml", "meta.json", "trials.csv", "timings.csv", "summary.csv", "summary.md", "report.md",
              "significance.csv"):
        assert (reference / f).is_file(), f
    rows = _csv(reference / "trials.csv")
    assert len(rows) == 2 * 5 * 3  # planners x scenarios x seeds
    order = [(r["planner"], int(r["scenario"]), int(r["seed"])) for r in rows]
    assert order == [(p, s, r) for p in ("A*", "AS") for s in range(5) for r in range(3)]
    assert "plan_time_s" not in rows[0]  # wall-clock times live in timings.csv
    assert len(_csv(reference / "timings.csv")) == 2 * 3  # planners x chunks
    meta = json.loads((reference / "meta.json").read_text())
    assert meta["jax_version"] and meta["devices"] and meta["started"]
    m = read_manifest(reference)
    assert len(m["chunks"]) == 6 and {e["session"] for e in m["chunks"].values()} == {1}
    report = (reference / "report.md").read_text()
    assert "per-seed means" in report and "paper: length" in report


def test_same_config_twice_gives_identical_trials(reference, tiny_config, tmp_path):
    again = run_experiment(tiny_config, tmp_path, progress=False)
    assert (again / "trials.csv").read_bytes() == (reference / "trials.csv").read_bytes()


CHUNK_BITS = config_toml(
    metrics=["success", "length", "optimality_gap"], experiment={"name": "chunkbits", "chunk": None},
    maps=[{"name": "r", "generator": "random", "seed": 1, "params": {"width": 30, "height": 30, "obstacle_ratio": 0.2},
           "scenarios": {"source": "random", "count": 5, "seed": 3, "min_distance": 20.0}}], scenarios=None,
    planners=[{**SMALL_ACO, "overrides": {"ants": 6, "iterations": 3, "dead_end": "retreat", "max_steps": 600}}])


def test_chunk_size_does_not_change_lengths_or_gaps(tmp_path):
    """Same seeds, same paths: a trial's length and gap are float64 sums of its stored cells. The float32 device
    sums they were before moved in the last bits with the batch (here: 2 vs 10 paths of 601 padded points)."""
    cfg = _write(tmp_path / "c.toml", CHUNK_BITS)
    one, five = (_csv(run_experiment(cfg, tmp_path / f"c{k}", progress=False, chunk=k) / "trials.csv") for k in (1, 5))
    assert [(r["scenario"], r["seed"]) for r in one] == [(r["scenario"], r["seed"]) for r in five]
    assert any(r["success"] == "1" for r in one)
    for col in ("length", "optimality_gap"):
        assert [r[col] for r in one] == [r[col] for r in five], col


def test_grid_path_lengths_are_float64_sums_independent_of_the_padding():
    from jaxplan.experiments import grid_path_lengths, optimality_gaps

    paths = np.array([[[0, 0], [1, 1], [2, 1], [-1, -1]], [[3, 3], [-1, -1], [-1, -1], [-1, -1]]], np.int32)
    got = grid_path_lengths(paths, np.array([3, 1]), 0.5)
    assert got.dtype == np.float64 and got.tolist() == [(np.sqrt(2.0) + 1.0) * 0.5, 0.0]
    # A long zig-zag, padded to two different widths (as two chunk sizes pad a batch): the same bits.
    rng = np.random.default_rng(0)
    walk = np.cumsum(rng.integers(-1, 2, (1, 301, 2)), axis=1)
    pad = lambda k: np.concatenate([walk, np.full((1, k, 2), -1)], axis=1)  # noqa: E731
    assert grid_path_lengths(pad(3), [301], 1.0).tolist() == grid_path_lengths(pad(700), [301], 1.0).tolist()
    assert optimality_gaps(np.array([2.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0])).tolist() == [1.0, 0.0, np.inf]


def test_a_different_experiment_in_the_same_folder_is_refused(reference, tiny_config, tmp_path):
    import shutil

    shutil.copytree(reference, tmp_path / "tiny")
    cfg = load_config(tiny_config)
    with pytest.raises(RunFolderError, match="different experiment"):
        run_experiment(cfg.replace(seeds=(0, 1, 2, 3)), tmp_path, progress=False)


def test_summary_is_the_numpy_recomputation(reference):
    rows = _csv(reference / "trials.csv")
    summary = {(r["planner"], r["metric"]): r for r in _csv(reference / "summary.csv")}
    for planner in ("A*", "AS"):
        for metric in ("success", "length", "optimality_gap", "turns", "smoothness", "converged_iteration"):
            per_seed = []
            for seed in range(3):
                v = np.array([float(r[metric]) for r in rows if r["planner"] == planner and int(r["seed"]) == seed])
                v = v[np.isfinite(v)]
                per_seed.append(v.mean())
            s = summary[planner, metric]
            assert float(s["mean"]) == pytest.approx(np.mean(per_seed), rel=1e-12, abs=1e-15)
            assert float(s["sd"]) == pytest.approx(np.std(per_seed, ddof=1), rel=1e-12, abs=1e-15)
            assert int(s["n"]) == 3
    # The paper's numbers only in the paper columns.
    assert summary["AS", "length"]["paper_mean"] == "99.5" and summary["AS", "length"]["paper_sd"] == "1.5"
    assert summary["AS", "length"]["mean"] != "99.5" and summary["A*", "length"]["paper_mean"] == ""


def test_anova_and_welch_are_scipy_on_the_per_seed_means(reference):
    rows = _csv(reference / "trials.csv")
    tests = _csv(reference / "significance.csv")

    def per_seed(planner, metric):
        return np.array([np.mean([float(r[metric]) for r in rows if r["planner"] == planner and int(r["seed"]) == s])
                         for s in range(3)])

    import warnings

    warnings.simplefilter("ignore")  # A*'s per-seed means are constant: scipy warns about precision
    for metric in ("length", "smoothness"):
        a, b = per_seed("A*", metric), per_seed("AS", metric)
        anova = next(t for t in tests if t["metric"] == metric and t["test"] == "anova")
        assert float(anova["p_value"]) == pytest.approx(sps.f_oneway(a, b).pvalue, rel=1e-12)
        welch = next(t for t in tests if t["metric"] == metric and t["test"] == "welch_t")
        assert float(welch["p_value"]) == pytest.approx(sps.ttest_ind(a, b, equal_var=False).pvalue, rel=1e-12)


def test_zero_variance_is_named_and_never_starred(tmp_path):
    """A smoke run whose planners give the same per-seed mean every seed: scipy says F = ∞, p = 0; the tables
    must say the test is undefined and star nothing. A group without spread beside one with spread keeps its
    (defined) test, with the constant group named."""
    from jaxplan.experiments.report import summary_markdown
    from jaxplan.experiments.stats import analyse

    cfg = parse_config(TINY, data_dir=tmp_path)
    metrics = ["success", "length", "optimality_gap", "turns", "smoothness", "converged_iteration"]
    rows = []
    for seed in range(3):
        # length: A* always 10, AS always 12 (no spread anywhere); smoothness: A* constant, AS varies.
        rows.append(["wh", "A*", "plan", seed, 1, 10.0, 0.0, 2, 0.5, 1])
        rows.append(["wh", "AS", "plan", seed, 1, 12.0, 0.2, 3, 0.5 + 0.1 * seed, 2])
    trials = tmp_path / "trials.csv"
    trials.write_text("\n".join(",".join(map(str, r)) for r in [["map", "planner", "kind", "seed", *metrics], *rows]))
    a = analyse(trials, None, cfg)
    by = {(t.metric, t.test): t for t in a.tests}
    for test in ("anova", "welch_t"):
        flat = by["length", test]
        assert flat.no_spread == ("A*", "AS")
        assert np.isnan(flat.statistic) and np.isnan(flat.p_value) and np.isnan(flat.p_adjusted)
        half = by["smoothness", test]
        assert half.no_spread == ("A*",) and np.isfinite(half.p_value)
    text = summary_markdown(a, cfg)
    length_rows = [ln for ln in text.splitlines() if ln.startswith("| wh | length")]
    assert len(length_rows) == 2 and all("undefined: no spread in any group" in ln for ln in length_rows)
    assert not any("*" in ln.replace("A*", "") for ln in length_rows)  # no star beyond the planner's name
    assert "∞" not in text
    assert all("(no spread: A*)" in ln for ln in text.splitlines() if ln.startswith("| wh | smoothness"))


def test_orbax_arrays_are_kept_per_chunk(reference):
    from jaxplan.experiments import load_chunk_arrays

    uid = sorted(read_manifest(reference)["chunks"])[-1]  # an Ant System chunk: 2 scenarios x 3 seeds
    arrays = load_chunk_arrays(reference, uid)
    assert arrays["history"].shape == (1, 3, 4)  # the last chunk holds scenario 4 only; 4 iterations
    assert arrays["paths"].shape[:2] == (1, 3)


def test_resume_skips_committed_chunks_and_redoes_uncommitted_ones(reference, tiny_config, tmp_path):
    """In-process twin of the SIGKILL test: stop after two chunks, leave a chunk file that never reached the
    manifest (a kill between writing rows and committing), resume."""
    run_experiment(tiny_config, tmp_path, progress=False, stop_after=2)
    run = tmp_path / "tiny"
    first = read_manifest(run)["chunks"]
    assert sorted(first) == ["00000-m0-p0-c0", "00001-m0-p0-c1"] and not (run / "trials.csv").exists()
    (run / "checkpoints" / "chunks" / "00002-m0-p0-c2.csv").write_text("half a row,")
    (run / "checkpoints" / "chunks" / ".00003-m0-p1-c0.csv.tmp-1").write_text("a temporary file")
    run_experiment(tiny_config, tmp_path, progress=False)
    final = read_manifest(run)
    assert final["sessions"] == 2
    assert {u: e["session"] for u, e in final["chunks"].items()} == {
        u: 1 if u in first else 2 for u in final["chunks"]}
    assert (run / "trials.csv").read_bytes() == (reference / "trials.csv").read_bytes()
    assert not list((run / "checkpoints" / "chunks").glob(".*"))


@pytest.mark.slow  # two CLI processes, each importing JAX and compiling the colony: ~30 s on a busy 2-core box
def test_resume_after_sigkill_gives_identical_trials(reference, tiny_config, tmp_path):
    """Kill the CLI once the first chunk is committed; the restart skips it and ends byte-identical."""
    cmd = [sys.executable, "-m", "jaxplan.cli", "run", str(tiny_config), "--out", str(tmp_path), "--no-progress"]
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    manifest = tmp_path / "tiny" / "checkpoints" / "manifest.json"
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            if manifest.is_file() and read_manifest(tmp_path / "tiny")["chunks"]:
                break
            assert proc.poll() is None, proc.stderr.read().decode()
            time.sleep(0.02)
        proc.send_signal(signal.SIGKILL)
        proc.wait(30)
    finally:
        if proc.poll() is None:
            proc.kill()
    first = read_manifest(tmp_path / "tiny")["chunks"]
    assert 1 <= len(first) < 6, "the run was not interrupted mid-way"
    assert not (tmp_path / "tiny" / "trials.csv").exists()

    done = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    final = read_manifest(tmp_path / "tiny")
    assert final["sessions"] == 2
    for uid, entry in first.items():  # finished chunks were not redone
        assert final["chunks"][uid]["session"] == 1 and final["chunks"][uid]["sha256"] == entry["sha256"]
    assert {e["session"] for uid, e in final["chunks"].items() if uid not in first} == {2}
    assert (tmp_path / "tiny" / "trials.csv").read_bytes() == (reference / "trials.csv").read_bytes()


# ---------------------------------------------------------------------------------------------
# Figures whose scenario the run does not have

SCENARIO_FIGURES = [{"kind": "paths", "name": "paths_sc3", "scenario": 3},
                    {"kind": "convergence", "name": "conv_sc3", "scenario": 3},
                    {"kind": "box", "metric": "length"}, {"kind": "bar", "metric": "length"}]


def test_figure_scenario_past_the_configured_count_is_a_config_error(tmp_path):
    text = _tiny(figures=[{"kind": "paths", "scenario": 5}, {"kind": "convergence", "scenario": 4}])
    with pytest.raises(ConfigError) as ei:
        parse_config(text, data_dir=tmp_path)
    assert ei.value.problems == ("figures[0].scenario: figure 'paths': scenario 5 is past map 'wh''s 5 scenarios "
                                 "(0..4)",)


def test_figure_scenario_past_a_quick_run_is_reported_and_the_other_figures_drawn(tmp_path, monkeypatch, capsys):
    from jaxplan.experiments import figures

    cfg = _write(tmp_path / "f.toml", _tiny(experiment={"name": "tinyfig"}, figures=SCENARIO_FIGURES))
    run = run_experiment(cfg, tmp_path / "runs", quick=True, progress=False)  # 2 scenarios: 3 is valid only in full

    def boom(run, spec):
        raise RuntimeError("a bug in one figure")

    monkeypatch.setitem(figures.DRAW, "bar", boom)
    drawn, problems = figures.draw_figures(run, tmp_path / "figs")
    assert [d.name for d in drawn] == ["box"]
    assert problems == [
        "paths_sc3 (paths): figure 'paths_sc3': scenario 3 is past map 'wh''s 2 scenarios in this --quick run (0..1)",
        "conv_sc3 (convergence): figure 'conv_sc3': scenario 3 is past map 'wh''s 2 scenarios in this --quick run "
        "(0..1)",
        "bar (bar): RuntimeError: a bug in one figure",
    ]
    assert not (tmp_path / "figs" / run.name / "conv_sc3.png").exists()  # no empty plot
    assert main(["figures", str(run), "--out", str(tmp_path / "figs")]) == 1
    assert "not drawn: paths_sc3" in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------
# The example configs


def test_example_configs_validate():
    data = Path(os.environ.get("JAXPLAN_DATA", ROOT.parent / "shared" / "benchmarks"))
    if not (data / "movingai").is_dir():
        pytest.skip(f"MovingAI benchmarks not found at {data}")
    for name in ("example_plan.toml", "example_nav.toml"):
        cfg = load_config(ROOT / "configs" / name, data_dir=data)
        assert cfg.planners and cfg.quick.seeds


@pytest.mark.slow
@pytest.mark.parametrize("name", ["example_plan.toml", "example_nav.toml"])
def test_example_configs_run_quick(name, tmp_path, movingai):
    run_dir = run_experiment(ROOT / "configs" / name, tmp_path, quick=True, data_dir=movingai.parent, progress=False)
    rows = _csv(run_dir / "trials.csv")
    assert rows and all(r["success"] in ("0", "1") for r in rows)


def test_planners_sharing_an_obstacle_spec_meet_the_same_discs_drawn_once(tmp_path, monkeypatch):
    """`obstacle_fn` draws a trial's discs once per map and process: a second planner with the same spec gets the
    very set the first one met (the comparison is paired), a planner with another spec draws its own."""
    import jaxplan.nav as nav
    from jaxplan.experiments.execute import obstacle_fn
    from jaxplan.experiments.prepare import prepare

    walkers = {"n": 2, "speed": 1.0, "radius": 0.25}
    nav_planner = {"kind": "navigate", "name": "astar_kng_dwa"}
    text = config_toml(planners=[{**nav_planner, "label": "a", "obstacles": walkers},
                                 {**nav_planner, "label": "b", "obstacles": walkers},
                                 {**nav_planner, "label": "c", "obstacles": {**walkers, "speed": 0.5}}])
    prep = prepare(parse_config(text, data_dir=tmp_path))
    mw, (a, b, c) = prep.maps[0], prep.config.planners
    calls = []
    draw = nav.random_obstacles
    monkeypatch.setattr(nav, "random_obstacles", lambda *args, **kw: calls.append(kw["seed"]) or draw(*args, **kw))
    rows = np.arange(len(mw.starts))
    first, second, other = (obstacle_fn(mw, 0, p, rows) for p in (a, b, c))
    assert second(1, 1) is first(1, 1) and len(calls) == 1
    assert other(1, 1) is not first(1, 1) and len(calls) == 2
    assert calls[0] == calls[1]  # the same trial's seed: only the spec (its speed) differs
    np.testing.assert_array_equal(other(1, 1).waypoints, first(1, 1).waypoints)
    assert float(np.asarray(other(1, 1).speeds).max()) == 0.5
