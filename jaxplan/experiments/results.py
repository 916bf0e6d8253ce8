"""The reproduction report: one Markdown page per paper table (``docs/results/<paper>/<table>.md``) and an
index (``docs/results/index.md``), written from finished run folders by `jaxplan reproduce`.

A page puts, for every number the paper prints, the paper's value beside ours (mean ± sd over seeds of
the per-seed means, the 95 % Student-t interval of that mean — a rate's clipped to [0, 100] % — the number
of seeds) and a verdict:

- ``consistent``: the paper's value lies inside our 95 % interval;
- ``ours better`` / ``ours worse``: outside it, on the better or the worse side (`HIGHER_BETTER` says
  which side is better for a metric);
- ``not comparable``: with the reason — a wall-clock time (other hardware), a metric the paper defines
  differently or not at all, a map or instance that is not the paper's (configs/results/notes.toml
  names these per table), or a cell we have no value for.

The paper's numbers appear only in the columns headed "paper", ours only in the columns headed "ours"
(a test checks this). Below: every metric of every planner (mean ± sd and interval), the
significance tests with an effect size (Hedges' g) for each pair, the baselines not reproduced, and the
figures. A page whose cells have fewer than `FEW_SEEDS` seeds says so at the top; a page written from a
``--quick`` run says QUICK in its title, its file name and its banner.

The hand-written parts (a sentence per table, a paragraph per paper, the not-comparable rules and the
baselines not reproduced) come from a notes file (``configs/results/notes.toml``, see `load_notes`).
"""

from __future__ import annotations

import json
import math
import os
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

from jaxplan.experiments.config import METRICS, ExperimentConfig, applies
from jaxplan.experiments.report import fmt
from jaxplan.experiments.stats import Analysis, confidence_interval, hedges_g

__all__ = ["Cell", "Notes", "VERDICTS", "HIGHER_BETTER", "FEW_SEEDS", "load_notes", "verdict", "paper_cells",
           "table_page", "index_page", "write_table_page", "write_index_page", "page_path", "page_summary"]

VERDICTS = ("consistent", "ours better", "ours worse", "not comparable")
"""The four verdicts, in the order the index counts them."""

HIGHER_BETTER = frozenset({"success", "accuracy", "smoothness", "min_clearance", "mean_clearance",
                           "los_length_reduction", "los_turns_reduction"})
"""Metrics where a larger value is better; for every other metric, smaller is better."""

FEW_SEEDS = 5
"""A cell with fewer seeds than this gets a visible warning on its page."""

_TIMING = "a wall-clock time: hardware-specific"
_PERCENT = frozenset({"success", "accuracy", "optimality_gap", "los_length_reduction", "los_turns_reduction"})


@dataclass(frozen=True)
class Rule:
    """A not-comparable rule of the notes: cells matching every given field (None: any) get ``reason``."""

    reason: str
    planner: str | None = None
    metric: str | None = None
    map: str | None = None

    def matches(self, map_: str, planner: str, metric: str) -> bool:
        return ((self.planner is None or self.planner == planner) and (self.metric is None or self.metric == metric)
                and (self.map is None or self.map == map_))


@dataclass(frozen=True)
class Notes:
    """The hand-written parts of the pages: per paper a paragraph (what we confirm and what we do not); per
    table (config name) a one-sentence conclusion, not-comparable rules and baselines not reproduced."""

    papers: Mapping[str, str] = field(default_factory=dict)
    conclusions: Mapping[str, str] = field(default_factory=dict)
    rules: Mapping[str, tuple[Rule, ...]] = field(default_factory=dict)
    not_reproduced: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    principle: str = ""
    highlights: Mapping[str, tuple[Mapping[str, Any], ...]] = field(default_factory=dict)


def load_notes(path: str | os.PathLike | None) -> Notes:
    """Reads a notes TOML file (a missing file gives empty notes)::

        principle = "when a cell is not comparable ..."
        [papers.cui2025]
        paragraph = "..."
        [tables.cui2025_table2]
        conclusion = "..."
        not_reproduced = ["IRL, DRL: no specification"]
        [[tables.cui2025_table2.not_comparable]]
        metric = "path_length"           # and/or planner, map; all optional
        reason = "..."
        [[tables.chu2024_tables3_5.highlight]]   # a table of our results for some planners and metrics
        title = "..."
        text = "..."
        planners = ["...", "..."]
        metrics = ["length", "turns"]

    Raises:
      ValueError: a rule without a reason, or an unknown metric in a rule.
    """
    if path is None or not Path(path).is_file():
        return Notes()
    raw = tomllib.loads(Path(path).read_text())
    papers = {k: str(v.get("paragraph", "")).strip() for k, v in raw.get("papers", {}).items()}
    conclusions, rules, missing, highlights = {}, {}, {}, {}
    for name, t in raw.get("tables", {}).items():
        if "conclusion" in t:
            conclusions[name] = str(t["conclusion"]).strip()
        rs = []
        for r in t.get("not_comparable", []):
            if not r.get("reason"):
                raise ValueError(f"{path}: tables.{name}.not_comparable: every rule needs a reason")
            if r.get("metric") is not None and r["metric"] not in METRICS:
                raise ValueError(f"{path}: tables.{name}.not_comparable: unknown metric {r['metric']!r}")
            rs.append(Rule(str(r["reason"]), r.get("planner"), r.get("metric"), r.get("map")))
        rules[name] = tuple(rs)
        missing[name] = tuple(str(x) for x in t.get("not_reproduced", []))
        hs = []
        for h in t.get("highlight", []):
            extra = sorted(set(h) - {"title", "text", "planners", "metrics"})
            if extra:  # e.g. a table's own key written below its [[highlight]] in the TOML file
                raise ValueError(f"{path}: tables.{name}.highlight: unknown key(s) {', '.join(extra)}")
            if not h.get("title") or not h.get("planners") or not h.get("metrics"):
                raise ValueError(f"{path}: tables.{name}.highlight: needs a title, planners and metrics")
            if any(m not in METRICS for m in h["metrics"]):
                raise ValueError(f"{path}: tables.{name}.highlight: unknown metric in {h['metrics']!r}")
            hs.append({"title": str(h["title"]), "text": str(h.get("text", "")).strip(),
                       "planners": tuple(h["planners"]), "metrics": tuple(h["metrics"])})
        highlights[name] = tuple(hs)
    return Notes(papers, conclusions, rules, missing, str(raw.get("principle", "")).strip(), highlights)


@dataclass(frozen=True)
class Cell:
    """One number the paper prints, beside ours: ``ours_*`` over ``n`` seeds (``ci`` the 95 % interval of the
    mean), the ``verdict`` (one of `VERDICTS`) and, if not comparable, the ``reason``."""

    map: str
    planner: str
    metric: str
    paper_mean: float
    paper_sd: float | None
    ours_mean: float
    ours_sd: float
    ci: tuple[float, float]
    n: int
    verdict: str
    reason: str = ""


def verdict(paper: float, ci: tuple[float, float], mean: float, metric: str, reason: str = "") -> tuple[str, str]:
    """(verdict, reason) of one cell: ``reason`` given -> not comparable; no value of ours -> not comparable;
    the paper's value inside the interval ``ci`` -> consistent; else ours better or worse (`HIGHER_BETTER`)."""
    if reason:
        return "not comparable", reason
    if not math.isfinite(mean):
        return "not comparable", "no value of ours (no run defined it)"
    lo, hi = ci
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return "not comparable", "one seed: no interval"
    if lo <= paper <= hi:
        return "consistent", ""
    higher = mean > paper
    return ("ours better" if higher == (metric in HIGHER_BETTER) else "ours worse"), ""


def _reason(notes: Notes, cfg: ExperimentConfig, map_: str, planner: str, metric: str) -> str:
    if METRICS[metric].timing:
        return _TIMING
    for r in notes.rules.get(cfg.name, ()):
        if r.matches(map_, planner, metric):
            return r.reason
    return ""


def _interval(ps, metric: str) -> tuple[float, float]:
    """The 95 % interval of the mean of per-seed means ``ps``; a rate's is clipped to [0, 1]."""
    if ps is None:
        return math.nan, math.nan
    lo, hi = confidence_interval(ps)
    if METRICS[metric].rate and math.isfinite(lo):
        lo, hi = max(lo, 0.0), min(hi, 1.0)
    return lo, hi


def paper_cells(a: Analysis, cfg: ExperimentConfig, notes: Notes) -> list[Cell]:
    """Every (map, planner, metric) with a paper value, in the summary's order, with its verdict."""
    out = []
    for r in a.summary:
        if r.paper_mean is None:
            continue
        ci = _interval(a.per_seed.get((r.map, r.planner, r.metric)), r.metric)
        v, why = verdict(r.paper_mean, ci, r.mean, r.metric, _reason(notes, cfg, r.map, r.planner, r.metric))
        out.append(Cell(r.map, r.planner, r.metric, r.paper_mean, r.paper_sd, r.mean, r.sd, ci, r.n, v, why))
    return out


# ---------------------------------------------------------------------------------------------
# Formatting


def _scale(metric: str) -> float:
    return 100.0 if metric in _PERCENT else 1.0


def _unit(metric: str) -> str:
    return "%" if metric in _PERCENT else METRICS[metric].unit


def _metric_head(metric: str) -> str:
    u = _unit(metric)
    return f"{metric} ({u})" if u else metric


def _num(x: float | None, metric: str, ref: float = 1.0) -> str:
    """``x`` in the metric's display unit; a value below 1e-9 of ``ref`` (rounding noise of an exact planner's
    sd or gap) shows as 0."""
    if x is None:
        return fmt(None)
    if math.isfinite(x) and abs(x) < 1e-9 * max(1.0, abs(ref)):
        x = 0.0
    return fmt(x * _scale(metric))


def _pm(mean: float, sd: float | None, metric: str) -> str:
    if mean is None or not math.isfinite(mean):
        return "–"
    if sd is None or not math.isfinite(sd):
        return _num(mean, metric)
    return f"{_num(mean, metric)} ± {_num(sd, metric, mean)}"


def _ci(ci: tuple[float, float], metric: str) -> str:
    lo, hi = ci
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return "–"
    return f"[{_num(lo, metric)}, {_num(hi, metric)}]"


def _table(head: Sequence[str], rows: Sequence[Sequence[str]], text: int = 1, last_text: bool = False) -> str:
    """A Markdown table: the first ``text`` columns (and the last, with ``last_text``) left-aligned, the rest
    (numbers) right-aligned."""
    align = ["---"] * text + ["---:"] * (len(head) - text)
    if last_text:
        align[-1] = "---"
    lines = ["| " + " | ".join(head) + " |", "| " + " | ".join(align) + " |"]
    lines += ["| " + " | ".join(c.replace("|", "/") for c in r) + " |" for r in rows]
    return "\n".join(lines)


PAPER_HEAD = "paper"
"""The header of the column holding the paper's numbers (the only one that may)."""
OURS_HEADS = ("ours: mean ± sd", "ours: 95 % CI")
"""The headers of the columns holding our numbers."""


def _comparison(cells: Sequence[Cell], few: int) -> str:
    head = ["map", "planner", "metric", PAPER_HEAD, *OURS_HEADS, "seeds", "verdict"]
    rows = []
    for c in cells:
        paper = _pm(c.paper_mean, c.paper_sd, c.metric)
        seeds = f"{c.n}" + (" ⚠" if c.n < few else "")
        ver = c.verdict + (f": {c.reason}" if c.reason else "")
        rows.append([c.map, c.planner, _metric_head(c.metric), paper, _pm(c.ours_mean, c.ours_sd, c.metric),
                     _ci(c.ci, c.metric), seeds, ver])
    return _table(head, rows, text=3, last_text=True)


def _ours_table(a: Analysis, cfg: ExperimentConfig, map_: str, few: int, planners: Sequence[str] | None = None,
                metrics: Sequence[str] | None = None) -> str:
    rows_by = {(r.planner, r.metric): r for r in a.summary if r.map == map_}
    site = next(m for m in cfg.maps if m.name == map_)
    planners = [pc.label for pc in cfg.planners if applies(pc, site) and (planners is None or pc.label in planners)]
    metrics = [m for m in (metrics or cfg.metrics) if any((p, m) in rows_by for p in planners)]
    head = ["planner"] + [f"ours: {_metric_head(m)}" for m in metrics]
    body = []
    for p in planners:
        row = [p]
        for m in metrics:
            r = rows_by.get((p, m))
            if r is None:
                row.append("n/a")
                continue
            ps = a.per_seed.get((map_, p, m))
            ci = _interval(ps, m)
            warn = " ⚠" if r.n < few and not METRICS[m].timing else ""
            row.append(_pm(r.mean, r.sd, m) + (f" {_ci(ci, m)}" if ps is not None else "") + warn)
        body.append(row)
    return _table(head, body)


def _tests(a: Analysis, cfg: ExperimentConfig) -> str:
    pairs = [t for t in a.tests if t.test == "welch_t"]
    anova = [t for t in a.tests if t.test == "anova"]
    if not pairs and not anova:
        return ""
    alpha = cfg.stats.alpha
    out = [f"Per-seed means as samples; * marks p < {alpha:g}. Hedges' g: the difference of the means (A − B) "
           "over the pooled sd, small-sample corrected (|g| ≈ 0.2 small, 0.5 medium, 0.8 large); an exact "
           "planner's constant per-seed means leave t and g undefined (–).", ""]
    if anova:
        out += ["One-way ANOVA across planners:", "",
                _table(["map", "metric", "F", "p", "groups"], text=2, rows=[
                    [t.map, t.metric, fmt(t.statistic), fmt(t.p_value, 3) + (" *" if t.p_value < alpha else ""),
                     str(t.n_b)] for t in anova]), ""]
    if pairs:
        adj = "p (Holm)" if cfg.stats.correction == "holm" else "p"
        rows = []
        for t in pairs:
            x = a.per_seed.get((t.map, t.planner_a, t.metric))
            y = a.per_seed.get((t.map, t.planner_b, t.metric))
            g = hedges_g(x, y) if x is not None and y is not None else math.nan
            rows.append([t.map, t.metric, t.planner_a, t.planner_b, fmt(t.statistic), fmt(t.p_value, 3),
                         fmt(t.p_adjusted, 3) + (" *" if t.p_adjusted < alpha else ""), fmt(g, 3)])
        out += ["Pairwise Welch t-tests:", "",
                _table(["map", "metric", "A", "B", "t", "p", adj, "Hedges' g"], rows, text=4), ""]
    return "\n".join(out)


def _deviations(config_text: str) -> list[str]:
    """The config's comment header from "Deviations" (or "What the paper") on, as plain lines."""
    lines = []
    for ln in config_text.splitlines():
        if not ln.startswith("#"):
            if lines or ln.strip():
                break
            continue
        lines.append(ln[1:].rstrip()[1:] if ln.startswith("# ") else ln[1:].rstrip())
    start = next((i for i, ln in enumerate(lines) if ln.startswith(("Deviations", "What the paper"))), None)
    return lines[start:] if start is not None else []


def page_path(cfg_name: str, quick: bool = False) -> Path:
    """``<paper>/<table>.md`` (``<table>-quick.md`` for a quick run) of config ``<paper>_<table>``."""
    paper, _, table = cfg_name.partition("_")
    return Path(paper) / f"{table or paper}{'-quick' if quick else ''}.md"


def _counts(cells: Sequence[Cell]) -> dict[str, int]:
    return {v: sum(c.verdict == v for c in cells) for v in VERDICTS}


@dataclass(frozen=True)
class Figure:
    """A drawn figure on a page: its name, the path of its PNG relative to the page, its caption."""

    name: str
    path: str
    caption: str


def table_page(a: Analysis, cfg: ExperimentConfig, notes: Notes, *, config_text: str = "", meta: Mapping | None = None,
               setup: Sequence[str] = (), figures: Sequence[Figure] = (), compute_s: float | None = None,
               quick: bool = False) -> str:
    """The Markdown page of one paper table (see the module docstring); pure."""
    meta = meta or {}
    cells = paper_cells(a, cfg, notes)
    counts = _counts(cells)
    R = len(a.seeds)
    ns = [r.n for r in a.summary if not METRICS[r.metric].timing and r.n > 0]
    few = [r for r in a.summary if not METRICS[r.metric].timing and 0 < r.n < FEW_SEEDS]
    title = f"# {cfg.name}" + (" — QUICK smoke run, not a result" if quick else "")
    out = [title, ""]
    summary = {"config": cfg.name, "quick": quick, "seeds": R, "counts": counts, "compute_s": compute_s}
    out += [f"<!-- summary: {json.dumps(summary)} -->", ""]
    if quick:
        out += ["> **QUICK RUN.** This page comes from `jaxplan reproduce --quick`: tiny colonies, two seeds, few "
                "scenarios. It checks that the pipeline works; its numbers are not the reproduction.", ""]
    if few:
        out += [f"> ⚠ **Few seeds.** {len(few)} cell{'s' if len(few) != 1 else ''} of this page rest"
                f"{'s' if len(few) == 1 else ''} on fewer than {FEW_SEEDS} seeds (marked ⚠): their interval is "
                "wide or undefined.", ""]
    if cfg.description:
        out += [cfg.description, ""]
    conclusion = notes.conclusions.get(cfg.name)
    if conclusion and not quick:
        out += [f"**Conclusion.** {conclusion}", ""]
    out += ["Regenerate: `jaxplan reproduce" + (" --quick" if quick else "") + f" --pattern '{cfg.name}.toml'` "
            "(resumes a finished run; every paper: `jaxplan reproduce`).", ""]
    out += ["## Setup", ""]
    out += [f"- {R} seed{'s' if R != 1 else ''} per cell ({min(ns) if ns else 0}–{max(ns) if ns else 0} with a "
            "defined value)" + ("" if R >= 30 else "; fewer than 30 to keep the full reproduction near an hour "
                                 "on two cores") + "."]
    out += [f"- {ln}" for ln in setup]
    if meta:
        out.append(f"- jaxplan {meta.get('jaxplan_version')} (git {meta.get('git_revision') or 'unknown'}), jax "
                   f"{meta.get('jax_version')}, started {meta.get('started')}"
                   + (f"; compute {compute_s / 60:.1f} min (sum of the chunks' compile and run times)"
                      if compute_s is not None else "") + ".")
    dev = _deviations(config_text)
    if dev:
        out += ["", "<details><summary>Deviations from the paper (from the config)</summary>", "", "```text", *dev,
                "```", "", "</details>"]
    out += ["", "## The paper's numbers beside ours", ""]
    if cells:
        out += [f"Source: {cfg.paper_source}. Verdict: *consistent* when the paper's value lies inside our 95 % "
                "interval of the mean over seeds; otherwise *ours better* or *ours worse*; *not comparable* with "
                "its reason. Fractions in %.", "",
                _comparison(cells, FEW_SEEDS), "",
                "Verdicts: " + ", ".join(f"{v} {counts[v]}" for v in VERDICTS) + ".", ""]
    else:
        out += ["The paper prints no number for this table's cells (its claims are qualitative; see the figures and "
                "the conclusion).", ""]
    for h in notes.highlights.get(cfg.name, ()):
        out += [f"## {h['title']}", ""] + ([h["text"], ""] if h["text"] else [])
        for mp in cfg.maps:
            out += [f"{mp.name}:", "", _ours_table(a, cfg, mp.name, FEW_SEEDS, h["planners"], h["metrics"]), ""]
    out += ["## All our results", "",
            "Mean ± sd over seeds of the per-seed means, then the 95 % interval of the mean; wall-clock times: "
            "over chunks. Fractions in %.", ""]
    for mp in cfg.maps:
        out += [f"### {mp.name}", "", _ours_table(a, cfg, mp.name, FEW_SEEDS), ""]
    tests = _tests(a, cfg)
    if tests:
        out += ["## Significance tests", "", "<details><summary>ANOVA and pairwise tests</summary>", "", tests,
                "</details>", ""]
    missing = notes.not_reproduced.get(cfg.name, ())
    if missing:
        out += ["## Not reproduced", ""] + [f"- {m}" for m in missing] + [""]
    if figures:
        out += ["## Figures", ""]
        for f in figures:
            out += [f"### {f.name}", "", f"![{f.name}]({f.path})", "", f.caption, ""]
    return "\n".join(out).rstrip() + "\n"


_SUMMARY = re.compile(r"<!-- summary: (\{.*\}) -->")


def page_summary(text: str) -> dict | None:
    """The summary a page carries (config, quick, seeds, verdict counts, compute time), or None."""
    m = _SUMMARY.search(text)
    return json.loads(m.group(1)) if m else None


def index_page(pages: Sequence[tuple[str, dict]], notes: Notes, *, quick: bool = False,
               wall_s: float | None = None, command: str = "jaxplan reproduce", cache: bool | None = None) -> str:
    """``index.md``: one row per page (its relative path and `page_summary`), the papers' paragraphs.

    ``wall_s``: the wall time of the call that wrote the index; ``cache``: whether that call used JAX's
    persistent compilation cache (a warm cache skips most compilation, so the time depends on it)."""
    from jaxplan.papers import PAPERS

    title = "# Reproduction results" + (" — QUICK smoke runs, not results" if quick else "")
    out = [title, ""]
    if quick:
        out += ["> **QUICK RUNS.** These pages come from `jaxplan reproduce --quick`; their numbers are not the "
                "reproduction.", ""]
    compute = sum(s.get("compute_s") or 0.0 for _, s in pages)
    out += [f"Every table below is regenerated by `{command}` (runs resume: a finished run is only re-read). "
            f"Compute of the runs: {compute / 60:.0f} min (sum over chunks of compile and run time)"
            + (f"; wall time of the call that wrote this index: {wall_s / 60:.1f} min" if wall_s is not None else "")
            + ({True: " (JAX's persistent compilation cache on)", False: " (no compilation cache)"}.get(cache, "")
               if wall_s is not None else "")
            + ". Each page puts the paper's numbers beside ours with a verdict: *consistent* (the paper's value "
            "inside our 95 % interval), *ours better*, *ours worse*, *not comparable* (with the reason).", ""]
    if notes.principle:
        out += [notes.principle, ""]
    head = ["paper", "table", "seeds", *VERDICTS, "conclusion"]
    rows = []
    for rel, s in pages:
        c = s["counts"]
        rows.append([s["config"].split("_")[0], f"[{s['config']}]({rel})", str(s["seeds"]),
                     *[str(c.get(v, 0)) for v in VERDICTS],
                     notes.conclusions.get(s["config"], "") if not quick else "(quick run)"])
    out += [_table(head, rows, text=2, last_text=True), ""]
    tot = {v: sum(s["counts"].get(v, 0) for _, s in pages) for v in VERDICTS}
    out += ["All tables: " + ", ".join(f"{v} {tot[v]}" for v in VERDICTS) + ".", ""]
    if not quick:
        papers = [k for k in PAPERS if notes.papers.get(k)]
        if papers:
            out += ["## What we confirm and what we do not", ""]
            for k in papers:
                out += [f"### {k}", "", notes.papers[k], ""]
        missing = [(name, m) for name, ms in notes.not_reproduced.items() for m in ms]
        if missing:
            out += ["## Not reproduced", ""] + [f"- {name}: {m}" for name, m in missing] + [""]
    return "\n".join(out).rstrip() + "\n"


# ---------------------------------------------------------------------------------------------
# Writing from run folders


def _setup_lines(prep: Any) -> list[str]:
    out = []
    for mw in prep.maps:
        s = mw.spec
        if mw.problem is not None:
            out.append(f"{s.name}: TSPLIB {s.tsplib.name}, {mw.problem.n} cities.")
            continue
        H, W = mw.grid.shape
        src = s.path.name if s.path is not None else f"generator {s.generator} (seed {s.seed})"
        out.append(f"{s.name}: {src}, {W}x{H} cells of {float(mw.grid.resolution):g} m; {len(mw.starts)} scenario"
                   f"{'s' if len(mw.starts) != 1 else ''}.")
    return out


def _compute_s(run_dir: Path) -> float | None:
    import csv

    p = run_dir / "timings.csv"
    if not p.is_file():
        return None
    with open(p, newline="") as f:
        return float(sum(float(r["compile_s"] or 0) + float(r["time_s"] or 0) for r in csv.DictReader(f)))


def _captions(index: Path) -> dict[str, str]:
    """Figure name -> caption, read back from a figure folder's index.md (`jaxplan.experiments.figures`)."""
    if not index.is_file():
        return {}
    out = {}
    for sec in index.read_text().split("\n## ")[1:]:
        lines = sec.splitlines()
        name = lines[0].split(" ")[0]
        body = [ln for ln in lines[1:] if ln and not ln.startswith(("![", "Files: "))]
        out[name] = body[0] if body else ""
    return out


def write_table_page(run_dir: str | os.PathLike, results: str | os.PathLike, notes: Notes, *,
                     figures_dir: str | os.PathLike | None = None, drawn: Sequence[Any] = (),
                     data_dir: str | os.PathLike | None = None) -> Path:
    """Writes the page of one finished run folder under ``results`` and returns its path.

    Args:
      run_dir: a finished run folder (`run_experiment`).
      results: the results root (``docs/results``).
      notes: `load_notes`.
      figures_dir: the figure root the run's figures were drawn into (``figures``); its PNGs are linked.
      drawn: the `jaxplan.experiments.figures.Drawn` of those figures (their captions), in config order.
      data_dir: as for `run_experiment`.
    """
    from jaxplan.core.io import atomic_write
    from jaxplan.experiments.run_data import load_run
    from jaxplan.experiments.stats import analyse

    run_dir = Path(run_dir)
    run = load_run(run_dir, data_dir)
    cfg = run.config
    quick = bool(cfg.is_quick)
    a = analyse(run_dir / "trials.csv", run_dir / "timings.csv", cfg)
    meta_path = run_dir / "meta.json"
    meta = json.loads(meta_path.read_text()) if meta_path.is_file() else {}
    page = Path(results) / page_path(cfg.name, quick)
    figs = []
    if figures_dir is not None:
        fdir = Path(figures_dir) / run_dir.resolve().name
        rel = Path(os.path.relpath(fdir, page.parent))
        caps = {d.name: d.caption for d in drawn} or _captions(fdir / "index.md")
        names = [d.name for d in drawn] or sorted(p.stem for p in fdir.glob("*.png"))
        figs = [Figure(n, (rel / f"{n}.png").as_posix(), caps.get(n, "")) for n in names
                if (fdir / f"{n}.png").is_file()]
    text = table_page(a, cfg, notes, config_text=(run_dir / "config.toml").read_text(), meta=meta,
                      setup=_setup_lines(run.prep), figures=figs, compute_s=_compute_s(run_dir), quick=quick)
    page.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(page, text)
    return page


def write_index_page(results: str | os.PathLike, notes: Notes, *, quick: bool = False,
                     wall_s: float | None = None, cache: bool | None = None) -> Path:
    """Writes ``results/index.md`` (``index-quick.md`` for quick pages) from every page found under ``results``."""
    from jaxplan.core.io import atomic_write

    root = Path(results)
    root.mkdir(parents=True, exist_ok=True)
    pages = []
    for p in sorted(root.glob("*/*.md")):
        s = page_summary(p.read_text())
        if s is not None and bool(s.get("quick")) == quick:
            pages.append((p.relative_to(root).as_posix(), s))
    from jaxplan.papers import PAPERS

    order = {k: i for i, k in enumerate(PAPERS)}
    pages.sort(key=lambda x: (order.get(x[1]["config"].split("_")[0], 99), x[1]["config"]))
    out = root / ("index-quick.md" if quick else "index.md")
    atomic_write(out, index_page(pages, notes, quick=quick, wall_s=wall_s, cache=cache,
                                 command="jaxplan reproduce --quick" if quick else "jaxplan reproduce"))
    return out
