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

# Over 800 lines, knowingly: the table pages and the index share one set of cell verdicts, claim lookups and
# page summaries (the index re-reads what each page judged), so they stay one module until the index is written
# from the pages' own records.
from __future__ import annotations

import json
import math
import os
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from jaxplan.core import markdown as md
from jaxplan.core.markdown import fmt
from jaxplan.experiments.claims import (
    CLAIM_VERDICTS,
    Claim,
    ClaimResult,
    Claims,
    absolute_verdict,
    evaluate_claim,
    units_label,
)
from jaxplan.experiments.comparability import comparable
from jaxplan.experiments.config import METRICS, ExperimentConfig, PaperValue
from jaxplan.experiments.evidence import (
    Evidence,
    family_sites,
    load_evidence,
    rate_counts,
    runs,
    units,
)
from jaxplan.experiments.report import p_cell
from jaxplan.experiments.stats import Analysis, hedges_g
from jaxplan.experiments.verdicts import Margin, judge_number, mean_interval, wilson_interval

__all__ = ["Cell", "Notes", "VERDICTS", "HIGHER_BETTER", "FEW_SEEDS", "load_notes", "comparability_reason",
           "paper_cells", "evaluate_claims", "claim_results", "table_page", "index_page", "write_table_page",
           "write_index_page", "page_path", "page_summary"]

VERDICTS = ("consistent", "ours better", "ours worse", "inconclusive", "not comparable")
"""The number verdicts, in the order the index counts them (`jaxplan.experiments.verdicts.judge_number`)."""

HIGHER_BETTER = frozenset({"success", "accuracy", "smoothness", "min_clearance", "mean_clearance",
                           "los_length_reduction", "los_turns_reduction", "arrived"})
"""Metrics where a larger value is better; for every other metric, smaller is better."""

FEW_SEEDS = 5
"""A cell with fewer units (seeds or map draws) than this gets a visible warning on its page."""

_TIMING = "a wall-clock time: hardware-specific"
_PERCENT = frozenset({"success", "accuracy", "optimality_gap", "los_length_reduction", "los_turns_reduction",
                      "arrived"})


@dataclass(frozen=True)
class Notes:
    """The hand-written parts of the pages: per table (config name) the baselines not reproduced and highlight
    tables; per paper the metrics it uses without defining them (``undefined``: metric -> what we measure
    instead), whose numbers are therefore not comparable; and the comparability ``principle`` (index page)."""

    not_reproduced: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    principle: str = ""
    highlights: Mapping[str, tuple[Mapping[str, Any], ...]] = field(default_factory=dict)
    undefined: Mapping[str, Mapping[str, str]] = field(default_factory=dict)


_RETIRED = {"conclusion": "the claims table (configs/results/claims.toml) states what each table shows",
            "not_comparable": "comparability is one rule applied by code (jaxplan.experiments.comparability); a "
                              "metric the paper does not define goes under [undefined.<paper>]",
            "paragraph": "the claims table (configs/results/claims.toml) states what we confirm"}


def load_notes(path: str | os.PathLike | None) -> Notes:
    """Reads a notes TOML file (a missing file gives empty notes)::

        principle = "when a cell is not comparable ..."
        [undefined.cui2025]
        accuracy = "the paper does not define accuracy; ours: success with a gap <= 10 %"
        [tables.cui2025_table2]
        not_reproduced = ["IRL, DRL: no specification"]
        [[tables.chu2024_tables3_5.highlight]]   # a table of our results for some planners and metrics
        title = "..."
        text = "..."
        planners = ["...", "..."]
        metrics = ["length", "turns"]

    Raises:
      ValueError: an unknown metric, an unknown paper, a highlight without its keys, or a key of the retired
        hand-written verdict rules (per-table ``not_comparable``, ``conclusion``, per-paper ``paragraph``).
    """
    from jaxplan.papers import PAPERS

    if path is None or not Path(path).is_file():
        return Notes()
    raw = tomllib.loads(Path(path).read_text())
    extra = sorted(set(raw) - {"principle", "tables", "undefined"})
    if extra:
        why = _RETIRED["paragraph"] if "papers" in extra else "unknown key"
        raise ValueError(f"{path}: unknown top-level key(s) {', '.join(extra)} ({why})")
    undefined = {}
    for paper, ms in raw.get("undefined", {}).items():
        if paper not in PAPERS:
            raise ValueError(f"{path}: undefined.{paper}: unknown paper")
        for m, why in ms.items():
            if m not in METRICS:
                raise ValueError(f"{path}: undefined.{paper}.{m}: unknown metric")
            if not str(why).strip():
                raise ValueError(f"{path}: undefined.{paper}.{m}: say what we measure instead")
        undefined[paper] = {m: str(why).strip() for m, why in ms.items()}
    missing, highlights = {}, {}
    for name, t in raw.get("tables", {}).items():
        for k in sorted(set(t) & set(_RETIRED)):
            raise ValueError(f"{path}: tables.{name}.{k} is retired: {_RETIRED[k]}")
        unknown = sorted(set(t) - {"not_reproduced", "highlight"})
        if unknown:
            raise ValueError(f"{path}: tables.{name}: unknown key(s) {', '.join(unknown)}")
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
    return Notes(missing, str(raw.get("principle", "")).strip(), highlights, undefined)


@dataclass(frozen=True)
class Cell:
    """One number the paper prints, beside ours, judged once: on map ``map`` (a drawn map's draws together),
    ``ours_mean`` ± ``ours_sd`` over ``n`` units of kind ``unit`` (seeds, map draws, or trials for a rate),
    ``ci`` the interval the rule compares with, ``verdict`` (one of `VERDICTS`) by ``rule``, ``p`` the test's p
    where one ran; if not comparable, the ``reason``. ``paper_n``: the runs behind the paper's value."""

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
    rule: str = ""
    unit: str = "seeds"
    p: float = math.nan
    paper_n: int | None = None


def comparability_reason(cfg: ExperimentConfig, notes: Notes, family: str | Sequence[str], metric: str) -> str:
    """Why a paper's number of ``metric`` on map ``family`` (or pooled over several) cannot be set beside ours
    ("" if it can): a wall-clock time; a metric the paper does not define (the notes' ``[undefined.<paper>]``);
    an absolute number on a map or instance that stands in for the paper's (`jaxplan.experiments.comparability`)."""
    if METRICS[metric].timing:
        return _TIMING
    paper = cfg.name.split("_")[0]
    why = notes.undefined.get(paper, {}).get(metric)
    if why:
        return f"the paper does not define {metric} ({why})"
    for fam in ([family] if isinstance(family, str) else family):
        site = next(m for m in cfg.maps if m.map_family == fam)
        if not comparable(metric, site.paper_map):
            what = "instance" if site.is_tsp else "map"
            return f"an absolute number on a stand-in {what} ({fam} is not the paper's {what})"
    return ""


def _units(ev: Evidence, fams: Sequence[str], planner: str, metric: str) -> np.ndarray:
    return np.concatenate([units(ev, f, planner, metric) for f in fams])


def _unit_name(ev: Evidence, fams: Sequence[str]) -> str:
    return units_label(ev, fams)


def _judge(ev: Evidence, fams: Sequence[str], planner: str, pv: PaperValue, margins: Mapping[str, Margin],
           alpha: float) -> tuple[str, str, tuple[float, float], float, int, str, float, float]:
    """(verdict, rule, interval, p, n, unit, ours mean, ours sd) of one comparable paper number."""
    metric = pv.metric
    margin = margins.get(metric)
    if margin is None:
        raise ValueError(f"{ev.config.name}: no equivalence margin for metric {metric!r} (claims.toml [margins])")
    hb = metric in HIGHER_BETTER
    u = _units(ev, fams, planner, metric)
    fin = u[np.isfinite(u)]
    mean = float(np.mean(fin)) if fin.size else math.nan
    sd = float(np.std(fin, ddof=1)) if fin.size > 1 else math.nan
    if not fin.size:
        return "not comparable", "", (math.nan, math.nan), math.nan, 0, _unit_name(ev, fams), mean, sd
    if METRICS[metric].rate:
        k = n = 0
        for f in fams:
            kf, nf = rate_counts(ev, f, planner, metric)
            k, n = k + kf, n + nf
        v = judge_number(u, pv.mean, pv.sd, pv.n, higher_better=hb, margin=margin, alpha=alpha, rate_counts=(k, n))
        return v.verdict, v.rule, v.interval, v.p, n, "trials", k / n if n else math.nan, sd
    welch = pv.sd is not None and pv.n is not None and pv.n >= 2
    ours = u if welch else np.concatenate([runs(ev, f, planner, metric) for f in fams])
    v = judge_number(ours, pv.mean, pv.sd, pv.n, higher_better=hb, margin=margin, alpha=alpha)
    n_used = int(np.isfinite(ours).sum())
    return v.verdict, v.rule, v.interval, v.p, n_used, _unit_name(ev, fams) if welch else "runs", mean, sd


POOLED = "all maps (pooled)"
"""The map column of a paper number given for every map of a config with several: it is judged once, pooled."""


def paper_cells(ev: Evidence, notes: Notes, margins: Mapping[str, Margin], *, alpha: float = 0.05) -> list[Cell]:
    """Every number the paper gives, in config order, judged once by the rule its reporting allows
    (`jaxplan.experiments.verdicts.judge_number`): a number for one map on that map (a drawn map's draws
    together), a number for every map pooled over the maps its planner runs on (the paper's mean over its maps)."""
    cfg = ev.config
    out = []
    for pv in cfg.paper:
        pc = next((p for p in cfg.planners if p.label == pv.planner), None)
        if pc is None:  # a quick run leaves some planners out
            continue
        fams = [f for f in ([pv.map] if pv.map is not None else ev.families()) if ev.has(f, pc.label)]
        if not fams or pc.kind not in METRICS[pv.metric].kinds or pv.metric not in cfg.metrics:
            continue
        where = fams[0] if len(fams) == 1 else POOLED
        why = comparability_reason(cfg, notes, fams, pv.metric)
        u = _units(ev, fams, pc.label, pv.metric) if not METRICS[pv.metric].timing else np.asarray([])
        fin = u[np.isfinite(u)]
        mean = float(np.mean(fin)) if fin.size else math.nan
        sd = float(np.std(fin, ddof=1)) if fin.size > 1 else math.nan
        if why:
            out.append(Cell(where, pc.label, pv.metric, pv.mean, pv.sd, mean, sd, mean_interval(fin), int(fin.size),
                            "not comparable", why, "", _unit_name(ev, fams), paper_n=pv.n))
            continue
        v, rule, ci, p, n, unit, mean, sd = _judge(ev, fams, pc.label, pv, margins, alpha)
        reason = "" if v != "not comparable" else "no value of ours (no run defined it)"
        out.append(Cell(where, pc.label, pv.metric, pv.mean, pv.sd, mean, sd, ci, n, v, reason, rule, unit, p, pv.n))
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
    return md.pm(mean, sd, lambda x: _num(x, metric), lambda x: _num(x, metric, mean))


def _ci(ci: tuple[float, float], metric: str) -> str:
    return md.interval(*ci, num=lambda x: _num(x, metric))


PAPER_HEAD = "paper"
"""The header of the column holding the paper's numbers (the only one that may)."""
OURS_HEADS = ("ours: mean ± sd", "ours: 95 % interval")
"""The headers of the columns holding our numbers."""


def _paper_text(c: Cell) -> str:
    return _pm(c.paper_mean, c.paper_sd, c.metric) + (f" (n = {c.paper_n})" if c.paper_n else "")


def _comparison(cells: Sequence[Cell], few: int) -> str:
    head = ["map", "planner", "metric", PAPER_HEAD, *OURS_HEADS, "n", "rule", "verdict"]
    rows = []
    for c in cells:
        n = f"{c.n} {c.unit}" + (" ⚠" if c.n < few and c.unit != "trials" else "")
        ver = c.verdict + (f": {c.reason}" if c.reason else "")
        ours = _pm(c.ours_mean, None if c.unit == "trials" else c.ours_sd, c.metric)
        rows.append([c.map, c.planner, _metric_head(c.metric), _paper_text(c), ours, _ci(c.ci, c.metric), n,
                     c.rule or "–", ver])
    return md.table(head, rows, text=3, last_text=True)


def _ours_table(a: Analysis, ev: Evidence, family: str, few: int, planners: Sequence[str] | None = None,
                metrics: Sequence[str] | None = None) -> str:
    cfg = ev.config
    first = family_sites(cfg, family)[0].name
    rows_by = {(r.planner, r.metric): r for r in a.summary if r.map == first}
    planners = [pc.label for pc in cfg.planners if ev.has(family, pc.label) and (planners is None or pc.label in
                                                                                  planners)]
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
            if METRICS[m].timing:
                row.append(_pm(r.mean, r.sd, m))
                continue
            u = units(ev, family, p, m)
            fin = u[np.isfinite(u)]
            mean = float(np.mean(fin)) if fin.size else math.nan
            sd = float(np.std(fin, ddof=1)) if fin.size > 1 else math.nan
            if METRICS[m].rate:
                k, n = rate_counts(ev, family, p, m)
                ci = wilson_interval(k, n) if n else (math.nan, math.nan)
            else:
                ci = mean_interval(fin)
            warn = " ⚠" if fin.size < few else ""
            row.append(_pm(mean, sd, m) + (f" {_ci(ci, m)}" if fin.size else "") + warn)
        body.append(row)
    return md.table(head, body)


def _claims_rows(results: Sequence[ClaimResult], link: Callable[[ClaimResult], str] | None = None) -> str:
    head = ["claim", "where", "test we ran", "effect [95 % interval]", "verdict"]
    rows = []
    for r in results:
        c = r.claim
        text = c.claim if link is None else link(r)
        rule = f" — {r.rule}" if r.rule else ""
        rows.append([text + (f" <br>*{c.note}*" if c.note else ""), c.where, r.test, _effect(r),
                     f"**{r.verdict}**{rule}"])
    return md.table(head, rows, text=3, last_text=True)


def _effect(r: ClaimResult) -> str:
    if not math.isfinite(r.effect):
        return "–"
    m = r.claim.metric or ""
    if r.claim.test == "absolute":  # ours with our interval: the difference's interval is not computed here
        unit = _unit(m)
        return (f"ours − paper: {'+' if r.effect > 0 else ''}{_num(r.effect, m)}{' ' + unit if unit else ''}; "
                f"ours in {_ci(r.interval, m)}, {r.n} {r.unit}")
    lo, hi = r.interval
    iv = f" [{_num(lo, m)}, {_num(hi, m)}]" if math.isfinite(lo) and math.isfinite(hi) else ""
    rel = f" ({r.relative * 100:+.1f} %)" if math.isfinite(r.relative) else ""
    unit = _unit(m)
    sign = "+" if r.effect > 0 else ""
    return f"{sign}{_num(r.effect, m)}{' ' + unit if unit else ''}{iv}{rel}; {r.n} {r.unit}".strip()


def _claim_doc(r: ClaimResult) -> dict:
    """A claim's result as stored in its page's summary (read back by the index)."""
    num = lambda x: x if math.isfinite(x) else None  # noqa: E731
    return {"id": r.claim.id, "verdict": r.verdict, "rule": r.rule, "test": r.test, "effect": num(r.effect),
            "lo": num(r.interval[0]), "hi": num(r.interval[1]), "relative": num(r.relative), "n": r.n,
            "unit": r.unit}


def _claim_from_doc(c: Claim, d: Mapping[str, Any]) -> ClaimResult:
    nan = lambda x: math.nan if x is None else float(x)  # noqa: E731
    return ClaimResult(c, d["verdict"], d["rule"], d["test"], nan(d["effect"]), (nan(d["lo"]), nan(d["hi"])),
                       nan(d["relative"]), int(d["n"]), d["unit"])


def evaluate_claims(ev: Evidence, claims: Claims, cells: Sequence[Cell], *, alpha: float = 0.05
                    ) -> list[ClaimResult]:
    """The results of the claims whose evidence is this run (``claims`` naming ``ev``'s config), in file order;
    an absolute claim takes its cell from ``cells`` (the page's)."""
    out = []
    for c in claims.claims:
        if c.config != ev.config.name or c.test == "not_testable":
            continue
        if c.test == "absolute":
            cell = next((x for x in cells if x.planner == c.proposed and x.metric == c.metric
                         and (c.map is None or x.map == c.map)), None)
            out.append(absolute_verdict(c, cell))
        else:
            out.append(evaluate_claim(c, ev, claims, alpha=alpha))
    return out


def _tests(a: Analysis, cfg: ExperimentConfig) -> str:
    pairs = [t for t in a.tests if t.test == "welch_t"]
    anova = [t for t in a.tests if t.test == "anova"]
    if not pairs and not anova:
        return ""
    alpha = cfg.stats.alpha
    out = [f"Per-seed means as samples; * marks p < {alpha:g}. Hedges' g: the difference of the means (A − B) "
           "over the pooled sd, small-sample corrected (|g| ≈ 0.2 small, 0.5 medium, 0.8 large); an exact "
           "planner's constant per-seed means leave g undefined (–) and are named \"no spread\"; a test in which "
           "no group has spread is undefined (–), never starred.", ""]
    if anova:
        out += ["One-way ANOVA across planners:", "",
                md.table(["map", "metric", "F", "p", "groups"], text=2, rows=[
                    [t.map, t.metric, fmt(t.statistic), p_cell(t, t.p_value, alpha), str(t.n_b)] for t in anova]),
                ""]
    if pairs:
        adj = "p (Holm)" if cfg.stats.correction == "holm" else "p"
        rows = []
        for t in pairs:
            x = a.per_seed.get((t.map, t.planner_a, t.metric))
            y = a.per_seed.get((t.map, t.planner_b, t.metric))
            g = hedges_g(x, y) if x is not None and y is not None else math.nan
            rows.append([t.map, t.metric, t.planner_a, t.planner_b, fmt(t.statistic), fmt(t.p_value, 3),
                         p_cell(t, t.p_adjusted, alpha), fmt(g, 3)])
        out += ["Pairwise Welch t-tests:", "",
                md.table(["map", "metric", "A", "B", "t", "p", adj, "Hedges' g"], rows, text=4), ""]
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


_RULES_TEXT = (
    "Each number the paper prints is judged here once, by the rule its reporting allows (the *rule* column): "
    "with the paper's mean, sd and n, a Welch test between its numbers and ours, and *consistent* only by an "
    "equivalence test (TOST) within the metric's margin (stated in configs/results/claims.toml); a number from one "
    "run against our 95 % prediction interval of one run; a rate against our Wilson interval (consistent when our "
    "90 % interval lies within the margin). *Ours better* / *ours worse*: a difference detected; *inconclusive*: "
    "neither a difference nor equivalence. An absolute number (length, turns, iterations, collisions, times) on a "
    "map or instance that stands in for the paper's is *not comparable*: what the paper claims about it is judged "
    "as a contrast in the claims table instead. Fractions in %.")


def table_page(a: Analysis, ev: Evidence, notes: Notes, claims: Claims | None = None, *, config_text: str = "",
               meta: Mapping | None = None, setup: Sequence[str] = (), figures: Sequence[Figure] = (),
               compute_s: float | None = None, quick: bool = False, alpha: float = 0.05) -> str:
    """The Markdown page of one paper table (see the module docstring); pure given its inputs."""
    cfg = ev.config
    claims = claims or Claims({}, ())
    meta = meta or {}
    cells = paper_cells(ev, notes, claims.margins, alpha=alpha)
    counts = _counts(cells)
    tested = evaluate_claims(ev, claims, cells, alpha=alpha)
    R = len(a.seeds)
    ns = [r.n for r in a.summary if not METRICS[r.metric].timing and r.n > 0]
    few = [c for c in cells if c.unit != "trials" and 0 < c.n < FEW_SEEDS]
    title = f"# {cfg.name}" + (" — QUICK smoke run, not a result" if quick else "")
    out = [title, ""]
    summary = {"config": cfg.name, "quick": quick, "seeds": R, "counts": counts, "compute_s": compute_s,
               "claims": [_claim_doc(r) for r in tested]}
    out += [f"<!-- summary: {json.dumps(summary)} -->", ""]
    if quick:
        out += ["> **QUICK RUN.** This page comes from `jaxplan reproduce --quick`: tiny colonies, two seeds, few "
                "scenarios. It checks that the pipeline works; its numbers are not the reproduction.", ""]
    if few:
        out += [f"> ⚠ **Few units.** {len(few)} cell{'s' if len(few) != 1 else ''} of this page rest"
                f"{'s' if len(few) == 1 else ''} on fewer than {FEW_SEEDS} seeds or map draws (marked ⚠): their "
                "interval is wide or undefined.", ""]
    if cfg.description:
        out += [cfg.description, ""]
    out += ["Regenerate: `jaxplan reproduce" + (" --quick" if quick else "") + f" --pattern '{cfg.name}.toml'` "
            "(resumes a finished run; every paper: `jaxplan reproduce`).", ""]
    if tested:
        out += ["## The paper's claims tested here", "", _claims_rows(tested), ""]
    out += ["## Setup", ""]
    out += [f"- {R} seed{'s' if R != 1 else ''} per cell ({min(ns) if ns else 0}–{max(ns) if ns else 0} with a "
            "defined value)" + ("" if R >= 30 else "; fewer than 30 to keep the full reproduction near an hour "
                                 "on two cores") + "."]
    drawn = [f for f in ev.families() if ev.drawn(f)]
    if drawn:
        out.append(f"- Map draws: {', '.join(f'{f} ({len(family_sites(cfg, f))})' for f in drawn)}. Each draw is "
                   "a new map from the generator (key seed + d, named NAME~d); the unit of every interval on these "
                   "maps is the draw (its mean over seeds and pairs), so the intervals hold the map-to-map "
                   "variance; figures show draw 0.")
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
        out += [f"Source: {cfg.paper_source}. {_RULES_TEXT}", "", _comparison(cells, FEW_SEEDS), "",
                "Verdicts: " + ", ".join(f"{v} {counts[v]}" for v in VERDICTS) + ".", ""]
    else:
        out += ["The paper prints no number for this table's cells (its claims are qualitative; see the claims "
                "above and the figures).", ""]
    for h in notes.highlights.get(cfg.name, ()):
        out += [f"## {h['title']}", ""] + ([h["text"], ""] if h["text"] else [])
        for fam in ev.families():
            out += [f"{fam}:", "", _ours_table(a, ev, fam, FEW_SEEDS, h["planners"], h["metrics"]), ""]
    out += ["## All our results", "",
            "Mean ± sd over units (seeds, or map draws for a drawn map) of the per-unit means, then the 95 % "
            "interval of the mean (a rate's: Wilson, over trials); wall-clock times: over chunks. Fractions in %.",
            ""]
    for fam in ev.families():
        out += [f"### {fam}", "", _ours_table(a, ev, fam, FEW_SEEDS), ""]
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


def claim_results(pages: Sequence[tuple[str, dict]], claims: Claims) -> list[tuple[ClaimResult, str | None]]:
    """Every claim of the file, in file order, with its result as its page stored it and that page's relative
    path: a claim whose config has no page is not testable ("no run"); a not_testable claim has no page."""
    by_config = {s["config"]: (rel, {d["id"]: d for d in s.get("claims", [])}) for rel, s in pages}
    out = []
    for c in claims.claims:
        if c.test == "not_testable":
            out.append((ClaimResult(c, "not testable", c.reason, "—"), None))
            continue
        rel, docs = by_config.get(c.config, (None, {}))
        if c.id in docs:
            out.append((_claim_from_doc(c, docs[c.id]), rel))
        else:
            out.append((ClaimResult(c, "not testable", f"no run of {c.config}", "—"), rel))
    return out


def index_page(pages: Sequence[tuple[str, dict]], notes: Notes, claims: Claims | None = None, *,
               quick: bool = False, wall_s: float | None = None, command: str = "jaxplan reproduce",
               cache: bool | None = None, figures_rel: str | None = None,
               beyond: Sequence[tuple[str, dict]] = ()) -> str:
    """``index.md``: the claims table (every claim of ``claims`` with its verdict, linked to its page and figure),
    then one row per page (its relative path and `page_summary`) with its number verdicts, then the pages beyond
    the papers (``beyond``: relative path and summary of e.g. the navigation frontier, `jaxplan.experiments.frontier`),
    which have no paper numbers and count in none of the verdicts.

    ``wall_s``: the wall time of the call that wrote the index; ``cache``: whether that call used JAX's
    persistent compilation cache (a warm cache skips most compilation, so the time depends on it);
    ``figures_rel``: the figure root relative to the index's folder (None: claims link no figure)."""
    from jaxplan.papers import PAPERS

    claims = claims or Claims({}, ())
    title = "# Reproduction results" + (" — QUICK smoke runs, not results" if quick else "")
    out = [title, ""]
    if quick:
        out += ["> **QUICK RUNS.** These pages come from `jaxplan reproduce --quick`; their numbers are not the "
                "reproduction.", ""]
    results = claim_results(pages, claims)
    ccount = {v: sum(r.verdict == v for r, _ in results) for v in CLAIM_VERDICTS}
    tot = {v: sum(s["counts"].get(v, 0) for _, s in pages) for v in VERDICTS}
    if results:
        out += [f"**The papers' claims: {len(results)} tested** — " + ", ".join(f"{ccount[v]} {v}"
                                                                             for v in CLAIM_VERDICTS) + ". "
                "**The papers' numbers** — " + ", ".join(f"{tot[v]} {v}" for v in VERDICTS) + ".", ""]
    compute = sum(s.get("compute_s") or 0.0 for _, s in pages)
    out += [f"Every table below is regenerated by `{command}` (runs resume: a finished run is only re-read). "
            f"Compute of the runs: {compute / 60:.0f} min (sum over chunks of compile and run time)"
            + (f"; wall time of the call that wrote this index: {wall_s / 60:.1f} min" if wall_s is not None else "")
            + ({True: " (JAX's persistent compilation cache on)", False: " (no compilation cache)"}.get(cache, "")
               if wall_s is not None else "") + ".", ""]
    if results:
        out += ["## The papers' claims", "",
                "Each headline claim of the five papers (abstract, conclusion, and what each table or figure is said "
                "to show), with the test we ran on our runs. Where our map stands in for the paper's, the claim is "
                "tested as the paper's *contrast* — the proposed method against its baseline on the same maps, "
                "start-goal pairs and seeds (paired) — not by its absolute number. The effect is proposed − baseline "
                "(or a trend's fitted change over the tested range) with its 95 % interval over the units named; "
                "*reproduced*: the interval lies on the claimed side of zero; *opposite*: on the other side; *not "
                "reproduced*: no effect — the 90 % interval lies within the metric's equivalence margin "
                "(configs/results/claims.toml); *inconclusive*: neither; *not testable*: why. Declared in "
                "configs/results/claims.toml.", ""]
        for key in PAPERS:
            mine = [(r, rel) for r, rel in results if r.claim.paper == key]
            if not mine:
                continue
            page_of = dict(mine)

            def link(r: ClaimResult, page_of=page_of) -> str:
                rel = page_of.get(r)
                text = f"[{r.claim.claim}]({rel})" if rel else r.claim.claim
                if rel and r.claim.figure and figures_rel:
                    run = r.claim.config + ("-quick" if quick else "")
                    text += f" ([figure]({figures_rel}/{run}/{r.claim.figure}.png))"
                return text

            counts = {v: sum(r.verdict == v for r, _ in mine) for v in CLAIM_VERDICTS}
            out += [f"### {PAPERS[key].short}", "",
                    ", ".join(f"{counts[v]} {v}" for v in CLAIM_VERDICTS if counts[v]) + ".", "",
                    _claims_rows([r for r, _ in mine], link), ""]
    out += ["## The papers' numbers, table by table", ""]
    if notes.principle:
        out += [notes.principle, ""]
    head = ["paper", "table", "seeds", *VERDICTS]
    rows = []
    for rel, s in pages:
        c = s["counts"]
        rows.append([s["config"].split("_")[0], f"[{s['config']}]({rel})", str(s["seeds"]),
                     *[str(c.get(v, 0)) for v in VERDICTS]])
    out += [md.table(head, rows, text=2), ""]
    out += ["All tables: " + ", ".join(f"{v} {tot[v]}" for v in VERDICTS) + ".", ""]
    if not quick:
        missing = [(name, m) for name, ms in notes.not_reproduced.items() for m in ms]
        if missing:
            out += ["## Not reproduced", ""] + [f"- {name}: {m}" for name, m in missing] + [""]
    if beyond:
        out += ["## Beyond the papers", "",
                "Results no paper reports, from this repository's own configs (`jaxplan reproduce --pattern "
                "'NAME.toml'`; not part of the default run, and in none of the counts above).", ""]
        out += [f"- {_beyond_line(rel, s)}" for rel, s in beyond] + [""]
    return "\n".join(out).rstrip() + "\n"


def _beyond_line(rel: str, s: Mapping[str, Any]) -> str:
    """One index line of a page beyond the papers: its title linked, its size, and what it must show."""
    text = md.link(str(s.get("title") or s["config"]), rel)
    parts = [f"{s['episodes']} episodes" if s.get("episodes") is not None else "",
             f"{len(s['maps'])} maps" if s.get("maps") else "",
             f"{s['seeds']} seed{'s' if s['seeds'] != 1 else ''}" if s.get("seeds") is not None else ""]
    parts = [x for x in parts if x]
    if parts:
        text += " — " + ", ".join(parts)
    zero = s.get("passive_zero")
    if zero is not None:
        text += (f"; passive safety: zero active contacts in all {s.get('passive_rows')} rows" if zero else
                 "; passive safety: active contacts in some rows (see the page)")
    return text + "."


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


def write_table_page(run_dir: str | os.PathLike, results: str | os.PathLike, notes: Notes,
                     claims: Claims | None = None, *, figures_dir: str | os.PathLike | None = None,
                     drawn: Sequence[Any] = (), data_dir: str | os.PathLike | None = None) -> Path:
    """Writes the page of one finished run folder under ``results`` and returns its path.

    Args:
      run_dir: a finished run folder (`run_experiment`).
      results: the results root (``docs/results``).
      notes: `load_notes`.
      claims: `jaxplan.experiments.claims.load_claims` (the margins and the claims this run tests).
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
    ev = load_evidence(run_dir, cfg)
    text = table_page(a, ev, notes, claims, config_text=(run_dir / "config.toml").read_text(), meta=meta,
                      setup=_setup_lines(run.prep), figures=figs, compute_s=_compute_s(run_dir), quick=quick)
    page.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(page, text)
    return page


def write_index_page(results: str | os.PathLike, notes: Notes, claims: Claims | None = None, *,
                     quick: bool = False, wall_s: float | None = None, cache: bool | None = None,
                     figures_dir: str | os.PathLike | None = None) -> Path:
    """Writes ``results/index.md`` (``index-quick.md`` for quick pages) from every page found under ``results``
    (their stored claim results and verdict counts; pages beyond the papers, ``results/*.md`` whose summary says
    ``beyond``, in a section of their own) and the claims file ``claims``; ``figures_dir``: the figure root the
    claims' figures are linked in."""
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
    beyond = []
    for p in sorted(root.glob("*.md")):
        s = page_summary(p.read_text()) if not p.name.startswith("index") else None
        if s is not None and s.get("beyond") and bool(s.get("quick")) == quick:
            beyond.append((p.name, s))
    out = root / ("index-quick.md" if quick else "index.md")
    rel = Path(os.path.relpath(Path(figures_dir), root)).as_posix() if figures_dir is not None else None
    atomic_write(out, index_page(pages, notes, claims, quick=quick, wall_s=wall_s, cache=cache, figures_rel=rel,
                                 command="jaxplan reproduce --quick" if quick else "jaxplan reproduce",
                                 beyond=beyond))
    return out
