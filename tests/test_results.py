"""The results pages (`jaxplan.experiments.results`): the paper's numbers only in the paper column and ours only in
ours, verdicts, not-comparable rules, the few-seeds warning, the quick label, the index; the statistics they use
(95 % t intervals, Hedges' g)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy import stats as sps

from jaxplan.experiments.config import parse_config
from jaxplan.experiments.results import (
    OURS_HEADS,
    PAPER_HEAD,
    Notes,
    Rule,
    index_page,
    load_notes,
    page_summary,
    paper_cells,
    table_page,
    verdict,
)
from jaxplan.experiments.stats import Analysis, SummaryRow, confidence_interval, hedges_g
from jaxplan.experiments.stats import TestRow as _Test  # not a pytest class

ROOT = Path(__file__).resolve().parents[1]

CONFIG = """
metrics = ["success", "length", "turns", "plan_time_s"]

[experiment]
name = "demo2020_table9"
description = "a made-up table"
seeds = 3

[[maps]]
name = "m"
generator = "random"
seed = 0
params = { width = 10, height = 10, obstacle_ratio = 0.1 }

[scenarios]
source = "random"
count = 1

[[planners]]
label = "Ours-ACO"
kind = "plan"
name = "aco"

[[planners]]
label = "Exact"
kind = "plan"
name = "astar"

[stats]
pairwise = true
metrics = ["length"]

[paper]
source = "Demo (2020), Table 9"
[[paper.values]]
planner = "Ours-ACO"
success = [0.876, 0.0123]
length = [987.654, 4.321]
turns = 7777.0
plan_time_s = 0.0321
"""

# Our per-seed means: distinct digits from every paper number, so a misplaced number is found by its text.
OURS = {("Ours-ACO", "success"): [0.5, 0.6, 0.55], ("Ours-ACO", "length"): [543.0, 543.4, 543.2],
        ("Ours-ACO", "turns"): [7777.0, 7777.0, 7777.0], ("Exact", "success"): [1.0, 1.0, 1.0],
        ("Exact", "length"): [500.0, 500.0, 500.0], ("Exact", "turns"): [3.0, 3.0, 3.0]}


def _analysis(cfg) -> Analysis:
    per_seed = {("m", p, m): np.asarray(v) for (p, m), v in OURS.items()}
    rows = []
    for pc in cfg.planners:
        for metric in cfg.metrics:
            pv = next((v for v in cfg.paper if v.planner == pc.label and v.metric == metric), None)
            if metric == "plan_time_s":
                mean, sd, n = 0.00123, 0.0001, 4
            else:
                x = np.asarray(OURS[pc.label, metric])
                mean, sd, n = float(x.mean()), float(x.std(ddof=1)), x.size
            rows.append(SummaryRow("m", pc.label, metric, "", "", n, n, mean, sd, pv.mean if pv else None,
                                   pv.sd if pv else None, cfg.paper_source if pv else ""))
    tests = (_Test("m", "length", "welch_t", "Ours-ACO", "Exact", 1.0, 0.5, 0.5, 3, 3),)
    return Analysis(tuple(rows), tests, per_seed, (0, 1, 2), {})


@pytest.fixture
def cfg():
    return parse_config(CONFIG)


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


def test_paper_numbers_appear_only_in_paper_columns_and_ours_only_in_ours(cfg):
    page = table_page(_analysis(cfg), cfg, Notes())
    paper_texts = ["987.7", "4.321", "87.6", "1.23", "0.0321"]  # length mean/sd, success in %, time
    ours_texts = ["543.2", "0.2", "55", "500"]
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


def test_verdicts_and_their_reasons(cfg):
    cells = {(c.planner, c.metric): c for c in paper_cells(_analysis(cfg), cfg, Notes())}
    assert cells["Ours-ACO", "length"].verdict == "ours better"  # 543.2 < 987.654, shorter is better
    assert cells["Ours-ACO", "success"].verdict == "ours worse"  # 55 % < 87.6 %
    assert cells["Ours-ACO", "turns"].verdict == "consistent"  # constant 7777 = the paper's
    assert cells["Ours-ACO", "plan_time_s"].verdict == "not comparable"
    assert "hardware" in cells["Ours-ACO", "plan_time_s"].reason
    notes = Notes(rules={"demo2020_table9": (Rule("different map", metric="length"),)})
    c = {(c.planner, c.metric): c for c in paper_cells(_analysis(cfg), cfg, notes)}["Ours-ACO", "length"]
    assert (c.verdict, c.reason) == ("not comparable", "different map")
    assert verdict(1.0, (0.5, 2.0), 1.2, "length") == ("consistent", "")
    assert verdict(3.0, (0.5, 2.0), 1.2, "length") == ("ours better", "")
    assert verdict(3.0, (0.5, 2.0), 1.2, "smoothness") == ("ours worse", "")
    assert verdict(3.0, (math.nan, math.nan), 1.2, "length")[0] == "not comparable"
    assert verdict(3.0, (0.5, 2.0), math.nan, "length")[0] == "not comparable"


def test_page_warns_of_few_seeds_and_labels_quick_runs(cfg):
    page = table_page(_analysis(cfg), cfg, Notes())
    assert "Few seeds" in page and "⚠" in page  # 3 seeds < 5
    assert "QUICK" not in page
    quick = table_page(_analysis(cfg), cfg, Notes(), quick=True)
    assert quick.startswith("# demo2020_table9 — QUICK") and "**QUICK RUN.**" in quick
    s = page_summary(quick)
    assert s["quick"] is True and s["counts"] == {"consistent": 1, "ours better": 1, "ours worse": 1,
                                                   "not comparable": 1}


def test_page_gives_effect_sizes_and_not_reproduced_baselines(cfg):
    notes = Notes(not_reproduced={"demo2020_table9": ("IAC: no specification",)},
                  conclusions={"demo2020_table9": "One sentence."})
    page = table_page(_analysis(cfg), cfg, notes)
    assert "Hedges' g" in page and "## Not reproduced" in page and "- IAC: no specification" in page
    assert "**Conclusion.** One sentence." in page


def test_index_counts_verdicts_per_table_and_writes_paragraphs(cfg):
    s = page_summary(table_page(_analysis(cfg), cfg, Notes()))
    notes = Notes(papers={"cui2025": "We confirm X."}, conclusions={"demo2020_table9": "Holds."})
    text = index_page([("demo2020/table9.md", s)], notes, wall_s=120.0)
    assert "[demo2020_table9](demo2020/table9.md)" in text and "| 1 | 1 | 1 | 1 | Holds. |" in text
    assert "### cui2025" in text and "We confirm X." in text and "2.0 min" in text
    assert "QUICK" in index_page([("demo2020/table9.md", s)], notes, quick=True)


def test_the_project_notes_load_and_name_known_configs():
    notes = load_notes(ROOT / "configs" / "results" / "notes.toml")
    from jaxplan.benchmark_functions import NAME as STUDY

    configs = {p.stem for p in (ROOT / "configs").glob("*_*.toml")} | {STUDY}
    assert set(notes.rules) <= configs and set(notes.not_reproduced) <= configs and set(notes.conclusions) <= configs
    assert notes.principle


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
    """li2026 Fig. 7 (jaxplan.benchmark_functions): best-so-far curves never rise; the page puts the paper's one
    number in its paper column, marked not comparable (no dimension published), and is found by the index."""
    import dataclasses

    from jaxplan import benchmark_functions as F
    from jaxplan.experiments.results import write_index_page

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


def test_notes_highlight_renders_a_table_and_refuses_stray_keys(cfg, tmp_path):
    notes_file = tmp_path / "notes.toml"
    notes_file.write_text('[tables.demo2020_table9]\n[[tables.demo2020_table9.highlight]]\ntitle = "Focus"\n'
                          'planners = ["Exact"]\nmetrics = ["length"]\n')
    page = table_page(_analysis(cfg), cfg, load_notes(notes_file))
    section = page.split("## Focus", 1)[1].split("## All our results", 1)[0]
    assert "| Exact | 500 ± 0 [500, 500] ⚠ |" in section and "Ours-ACO" not in section
    notes_file.write_text(notes_file.read_text() + 'conclusion = "lands in the highlight, not the table"\n')
    with pytest.raises(ValueError, match="unknown key"):
        load_notes(notes_file)
