"""The results pages (`jaxplan.experiments.results`): the paper's numbers only in the paper column and ours only in
ours, the verdict rule of each cell, the comparability rule, map draws as units, the claims on the page and the
index, the few-units warning, the quick label; the statistics they use (95 % t intervals, Hedges' g)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import config_toml, merged
from scipy import stats as sps

from jaxplan.experiments.claims import Claim, Claims
from jaxplan.experiments.config import ConfigError, parse_config
from jaxplan.experiments.evidence import load_evidence, runs, units
from jaxplan.experiments.results import (
    OURS_HEADS,
    PAPER_HEAD,
    Notes,
    comparability_reason,
    evaluate_claims,
    index_page,
    load_notes,
    page_summary,
    paper_cells,
    table_page,
)
from jaxplan.experiments.stats import TIMING_COLUMNS, analyse, confidence_interval, hedges_g
from jaxplan.experiments.verdicts import Margin

ROOT = Path(__file__).resolve().parents[1]

MAP = {"name": "m", "generator": "random", "seed": 0, "params": {"width": 10, "height": 10, "obstacle_ratio": 0.1},
       "scenarios": {"source": "random", "count": 2}}


def _config(**changes) -> str:
    """A made-up paper table: Ours-ACO against the exact planner on one random map, with the paper's numbers
    (`conftest.config_toml` with ``changes``)."""
    base = dict(
        metrics=["success", "length", "optimality_gap", "plan_time_s"],
        experiment={"name": "demo2020_table9", "description": "a made-up table", "seeds": 6, "chunk": None},
        maps=[MAP], scenarios=None, planners=[{"label": "Ours-ACO", "kind": "plan", "name": "aco"},
                                              {"label": "Exact", "kind": "plan", "name": "astar"}],
        stats={"pairwise": True, "metrics": ["length"]},
        paper={"source": "Demo (2020), Table 9", "n": 30, "values": [{
            "planner": "Ours-ACO", "success": [0.876, 0.0123], "length": [987.654, 4.321],
            "optimality_gap": [0.2345, 0.0111], "plan_time_s": 0.0321}]})
    return config_toml(**merged(base, changes))


CONFIG = _config()

MARGINS = {"success": Margin(0.05, False), "optimality_gap": Margin(0.1, True), "length": Margin(0.03, True)}


def _trials(cfg) -> list[dict]:
    """Two scenarios x the config's seeds on every map: Ours-ACO succeeds on scenario 0 only (rate 0.5), with a
    gap of 0.2345 + 0.001 (s - 2.5) — equal to the paper's up to 0.0025, far inside its 10 % margin — and 543.x m;
    the exact planner always succeeds at 500 m."""
    rows = []
    for mp in cfg.maps:
        for sc in range(2):
            for i, s in enumerate(cfg.seeds):
                rows.append(dict(map=mp.name, planner="Ours-ACO", kind="plan", scenario=sc, seed=s,
                                 success=float(sc == 0), length=543.0 + 0.1 * i + mp.draw,
                                 optimality_gap=0.2345 + 0.001 * (i - 2.5)))
                rows.append(dict(map=mp.name, planner="Exact", kind="plan", scenario=sc, seed=s, success=1.0,
                                 length=500.0 + mp.draw, optimality_gap=0.0))
    return rows


def _write(run: Path, cfg, rows: list[dict]) -> None:
    import csv

    run.mkdir(parents=True, exist_ok=True)
    cols = ["map", "planner", "kind", "scenario", "seed", "success", "length", "optimality_gap"]
    with open(run / "trials.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(cols)
        w.writerows([[r[c] for c in cols] for r in rows])
    with open(run / "timings.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(TIMING_COLUMNS)
        for mp in cfg.maps:
            for pc in cfg.planners:
                w.writerow(["u", mp.name, pc.label, "plan", 0, 2, 12, 0, 1.0, 0.5, 0.00123, ""])


def _evidence(tmp_path: Path, cfg, rows: list[dict] | None = None):
    run = tmp_path / cfg.name
    _write(run, cfg, _trials(cfg) if rows is None else rows)
    return analyse(run / "trials.csv", run / "timings.csv", cfg), load_evidence(run, cfg)


@pytest.fixture
def cfg():
    return parse_config(CONFIG)


@pytest.fixture
def claims():
    return Claims(MARGINS, ())


def _page(tmp_path, cfg, notes=None, claims=None, **kw) -> str:
    a, ev = _evidence(tmp_path, cfg)
    return table_page(a, ev, notes or Notes(), claims or Claims(MARGINS, ()), **kw)


def _tables(text: str) -> list[tuple[list[str], list[list[str]]]]:
    """The Markdown tables of a page: (header cells, body rows)."""
    out, lines = [], text.splitlines()
    i = 0
    while i < len(lines):
        if lines[i].startswith("| ") and i + 1 < len(lines) and lines[i + 1].startswith("| ---"):
            head = [c.strip() for c in lines[i].strip("|").split("|")]
            body, j = [], i + 2
            while j < len(lines) and lines[j].startswith("| "):
                body.append([c.strip() for c in lines[j].strip("|").split("|")])
                j += 1
            out.append((head, body))
            i = j
        else:
            i += 1
    return out


def test_paper_numbers_appear_only_in_paper_columns_and_ours_only_in_ours(cfg, tmp_path):
    page = _page(tmp_path, cfg)
    paper_texts = ["987.7", "4.321", "87.6", "1.23", "0.0321", "1.11"]  # length, success %, sds, time
    ours_texts = ["543.2", "50", "500"]
    tables = _tables(page)
    assert tables, page
    seen_paper = seen_ours = 0
    for head, body in tables:
        for row in body:
            for h, cell in zip(head, row, strict=True):
                for t in paper_texts:
                    if t in cell.split(" "):
                        assert h == PAPER_HEAD, (t, h, row)
                        seen_paper += 1
                for t in ours_texts:
                    if t in cell.split(" ") or f"[{t}," in cell:
                        assert h.startswith("ours"), (t, h, row)
                        seen_ours += 1
        if PAPER_HEAD in head:
            assert head.index(PAPER_HEAD) < head.index(OURS_HEADS[0])
    assert seen_paper >= 4 and seen_ours >= 3
    prose = "\n".join(ln for ln in page.splitlines() if not ln.startswith("|"))
    assert not any(t in prose.split() for t in paper_texts + ["543.2"]), "numbers outside the tables"


def test_each_number_gets_the_rule_its_reporting_allows(cfg, tmp_path):
    a, ev = _evidence(tmp_path, cfg)
    cells = {(c.planner, c.metric): c for c in paper_cells(ev, Notes(), MARGINS)}
    rate = cells["Ours-ACO", "success"]  # 6 of 12 trials: Wilson [0.254, 0.746] excludes the paper's 0.876
    assert (rate.verdict, rate.unit, rate.n) == ("ours worse", "trials", 12) and "Wilson" in rate.rule
    assert rate.ci == pytest.approx((0.2538, 0.7462), abs=1e-4)
    gap = cells["Ours-ACO", "optimality_gap"]  # paper sd and n: Welch + TOST, equivalent within 10 %
    assert gap.verdict == "consistent" and "TOST" in gap.rule and gap.unit == "seeds" and gap.n == 6
    length = cells["Ours-ACO", "length"]
    assert length.verdict == "not comparable" and "stand-in map" in length.reason
    assert cells["Ours-ACO", "plan_time_s"].verdict == "not comparable"
    assert "hardware" in cells["Ours-ACO", "plan_time_s"].reason
    undefined = Notes(undefined={"demo2020": {"optimality_gap": "ours: the octile gap"}})
    c = {(c.planner, c.metric): c for c in paper_cells(ev, undefined, MARGINS)}["Ours-ACO", "optimality_gap"]
    assert c.verdict == "not comparable" and "does not define optimality_gap" in c.reason
    with pytest.raises(ValueError, match="no equivalence margin"):
        paper_cells(ev, Notes(), {})


def test_the_comparability_rule_on_a_stand_in_and_on_the_papers_own_map(cfg):
    import dataclasses

    for metric in ("length", "turns", "converged_iteration", "collisions"):
        assert "stand-in map" in comparability_reason(cfg, Notes(), "m", metric)
    for metric in ("success", "optimality_gap", "smoothness"):
        assert comparability_reason(cfg, Notes(), "m", metric) == ""
    own = cfg.replace(maps=tuple(dataclasses.replace(m, paper_map=True) for m in cfg.maps))
    assert comparability_reason(own, Notes(), "m", "length") == ""
    with pytest.raises(ConfigError, match="never the paper's own"):
        parse_config(_config(maps=[{**MAP, "paper_map": True}]))


def test_a_drawn_map_is_judged_once_with_the_draws_as_units(tmp_path):
    cfg = parse_config(_config(maps=[{**MAP, "draws": 3}]))
    assert [(m.name, m.seed, m.map_family) for m in cfg.maps] == [("m", 0, "m"), ("m~1", 1, "m"), ("m~2", 2, "m")]
    a, ev = _evidence(tmp_path, cfg)
    u = units(ev, "m", "Exact", "length")  # per-draw means: 500 + draw
    np.testing.assert_allclose(u, [500.0, 501.0, 502.0])
    assert runs(ev, "m", "Exact", "length").shape == (18,)
    cells = [c for c in paper_cells(ev, Notes(), MARGINS) if c.metric == "optimality_gap"]
    assert len(cells) == 1 and cells[0].unit == "map draws" and cells[0].n == 3
    page = table_page(a, ev, Notes(), Claims(MARGINS, ()))
    assert "Map draws: m (3)" in page and "### m~1" not in page
    assert parse_config(CONFIG).maps[0].draw == 0
    with pytest.raises(ConfigError, match="only a generated map has draws"):
        parse_config(_config(maps=[{"name": "m", "path": "movingai/x.map", "draws": 2, "scenarios": MAP["scenarios"]}]))


def _claim(**kw) -> Claim:
    base = dict(id="demo.c", paper="cui2025", claim="Ours is shorter", where="Table 9", test="contrast",
                config="demo2020_table9", metric="length", proposed="Exact", baseline="Ours-ACO", direction="lower")
    return Claim(**{**base, **kw})


def test_claims_are_judged_as_paired_contrasts_and_reach_the_index(cfg, tmp_path):
    a, ev = _evidence(tmp_path, cfg)
    claims = Claims(MARGINS, (_claim(), _claim(id="demo.d", direction="higher"),
                              _claim(id="demo.e", metric="success", proposed="Ours-ACO", baseline="Ours-ACO"),
                              _claim(id="demo.f", test="not_testable", reason="no specification")))
    got = {r.claim.id: r for r in evaluate_claims(ev, claims, paper_cells(ev, Notes(), MARGINS))}
    assert got["demo.c"].verdict == "reproduced" and got["demo.c"].effect == pytest.approx(-43.25)
    assert got["demo.c"].unit == "seeds" and got["demo.c"].n == 6
    assert got["demo.d"].verdict == "opposite"
    assert got["demo.e"].verdict == "not reproduced"  # no difference at all, within the 5-point margin
    page = table_page(a, ev, Notes(), claims)
    assert "## The paper's claims tested here" in page and "**reproduced**" in page
    s = page_summary(page)
    text = index_page([("demo2020/table9.md", s)], Notes(), claims, wall_s=120.0)
    assert "**The papers' claims: 4 tested** — 1 reproduced, 1 not reproduced, 1 opposite" in text
    assert "[Ours is shorter](demo2020/table9.md)" in text and "**not testable** — no specification" in text
    assert "[demo2020_table9](demo2020/table9.md)" in text and "2.0 min" in text


def test_page_warns_of_few_units_and_labels_quick_runs(tmp_path):
    cfg = parse_config(_config(experiment={"seeds": 3}))
    page = _page(tmp_path, cfg)
    assert "Few units" in page and "⚠" in page  # 3 seeds < 5
    assert "QUICK" not in page
    quick = _page(tmp_path, cfg, quick=True)
    assert quick.startswith("# demo2020_table9 — QUICK") and "**QUICK RUN.**" in quick
    s = page_summary(quick)
    assert s["quick"] is True and sum(s["counts"].values()) == 4 and s["counts"]["not comparable"] == 2


def test_page_gives_effect_sizes_and_not_reproduced_baselines(cfg, tmp_path):
    notes = Notes(not_reproduced={"demo2020_table9": ("IAC: no specification",)})
    page = _page(tmp_path, cfg, notes)
    assert "Hedges' g" in page and "## Not reproduced" in page and "- IAC: no specification" in page


def test_notes_refuse_the_retired_hand_written_verdicts(tmp_path):
    f = tmp_path / "notes.toml"
    f.write_text('[tables.x]\n[[tables.x.not_comparable]]\nmetric = "length"\nreason = "map"\n')
    with pytest.raises(ValueError, match="retired"):
        load_notes(f)
    f.write_text('[papers.cui2025]\nparagraph = "We confirm X."\n')
    with pytest.raises(ValueError, match="claims table"):
        load_notes(f)


def test_the_project_notes_load_and_name_known_configs():
    notes = load_notes(ROOT / "configs" / "results" / "notes.toml")
    from jaxplan.studies.benchmark_functions import NAME as STUDY

    configs = {p.stem for p in (ROOT / "configs").glob("*_*.toml")} | {STUDY}
    assert set(notes.not_reproduced) <= configs and set(notes.highlights) <= configs
    assert notes.principle and notes.undefined["cui2025"]["accuracy"]


def test_confidence_interval_is_the_t_interval_of_the_mean():
    x = np.array([1.0, 2.0, 4.0, np.nan, 7.0])
    lo, hi = confidence_interval(x)
    ref = sps.t.interval(0.95, 3, loc=np.nanmean(x), scale=sps.sem(x[np.isfinite(x)]))
    np.testing.assert_allclose((lo, hi), ref)
    assert confidence_interval(np.array([3.0, 3.0])) == (3.0, 3.0)
    assert all(math.isnan(v) for v in confidence_interval(np.array([3.0])))


def test_hedges_g():
    x, y = np.array([1.0, 2.0, 3.0]), np.array([3.0, 4.0, 5.0])
    assert hedges_g(x, y) == pytest.approx(-2.0 * (1 - 3 / (4 * 6 - 9)))
    assert math.isnan(hedges_g(np.array([1.0, 1.0]), np.array([2.0, 2.0])))
    assert math.isnan(hedges_g(np.array([1.0]), y))


def test_optimiser_study_curves_and_page(tmp_path):
    """li2026 Fig. 7 (jaxplan.studies.benchmark_functions): best-so-far curves never rise; the page puts the paper's
    one number in its paper column, marked not comparable (no dimension published), and is found by the index."""
    import dataclasses

    from jaxplan.experiments.results import write_index_page
    from jaxplan.studies import benchmark_functions as F

    for name, (f, _) in F.FUNCTIONS.items():
        assert float(f(np.zeros((1, 3), np.float32))[0]) == pytest.approx(0.0, abs=1e-5), name
    spec = dataclasses.replace(F.QUICK, dim=2, population=6, generations=4, seeds=2)
    curves = F.run_study(spec)
    assert set(curves) == {("rastrigin", s) for s in spec.strategies}
    for c in curves.values():
        assert c.shape == (2, 4) and np.all(np.diff(c, axis=1) <= 0)
    page = F.write_study(tmp_path / "results", tmp_path / "figures", spec).read_text()
    row = next(ln for ln in page.splitlines() if ln.startswith("| rastrigin | issa | best fitness"))
    assert "| 6.2 |" in row and "not comparable" in row
    assert (tmp_path / "figures" / "li2026_fig7-quick" / "fig7_fitness.png").stat().st_size > 5_000
    index = write_index_page(tmp_path / "results", Notes(), quick=True).read_text()
    assert "[li2026_fig7](li2026/fig7-quick.md)" in index
    timed = write_index_page(tmp_path / "results", Notes(), quick=True, wall_s=90.0, cache=False).read_text()
    assert "wall time of the call that wrote this index: 1.5 min (no compilation cache)" in timed


def test_the_old_study_path_still_works_with_a_deprecation_warning():
    import importlib
    import sys

    from jaxplan.studies import benchmark_functions as new

    sys.modules.pop("jaxplan.benchmark_functions", None)
    with pytest.warns(DeprecationWarning, match="moved to jaxplan.studies.benchmark_functions"):
        old = importlib.import_module("jaxplan.benchmark_functions")
    assert old.write_study is new.write_study and old.FUNCTIONS is new.FUNCTIONS and old.NAME == "li2026_fig7"


def test_notes_highlight_renders_a_table_and_refuses_stray_keys(cfg, tmp_path):
    notes_file = tmp_path / "notes.toml"
    notes_file.write_text('[tables.demo2020_table9]\n[[tables.demo2020_table9.highlight]]\ntitle = "Focus"\n'
                          'planners = ["Exact"]\nmetrics = ["length"]\n')
    page = _page(tmp_path, cfg, load_notes(notes_file))
    section = page.split("## Focus", 1)[1].split("## All our results", 1)[0]
    assert "| Exact | 500 ± 0 [500, 500] |" in section and "Ours-ACO" not in section
    notes_file.write_text(notes_file.read_text() + 'unknown_key = "lands in the highlight, not the table"\n')
    with pytest.raises(ValueError, match="unknown key"):
        load_notes(notes_file)
