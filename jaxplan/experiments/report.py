"""Markdown for a run: the summary tables (summary.md) and the one-page report (report.md).

Pure functions from an `Analysis` (and the config, work plan and meta) to text. The
paper's numbers sit in their own columns headed "paper", never in ours.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from jaxplan.core import markdown as md
from jaxplan.core.markdown import fmt
from jaxplan.experiments.config import METRICS, ExperimentConfig, applies
from jaxplan.experiments.stats import PER_CHUNK, PER_SEED, Analysis, SummaryRow, TestRow, significant, spread_note

if TYPE_CHECKING:  # pragma: no cover
    from jaxplan.experiments.prepare import Prepared

__all__ = ["summary_markdown", "report_markdown", "fmt", "p_cell"]


def _range(lo: float | None, hi: float | None) -> str:
    """`` [min, max]`` for a cell, or nothing when neither is known."""
    if (lo is None or math.isnan(lo)) and (hi is None or math.isnan(hi)):
        return ""
    return f" {md.interval(lo, hi)}"


def _label(metric: str) -> str:
    u = METRICS[metric].unit
    return f"{metric} ({u})" if u else metric


def _map_table(a: Analysis, cfg: ExperimentConfig, map_: str) -> str:
    rows_by = {(r.planner, r.metric): r for r in a.summary if r.map == map_}
    site = next(m for m in cfg.maps if m.name == map_)
    planners = [pc for pc in cfg.planners if applies(pc, site)]
    metrics = [m for m in cfg.metrics if any((pc.label, m) in rows_by for pc in planners)]
    ext = cfg.stats.extremes
    with_paper = {m for m in metrics if any(r.paper_mean is not None for (p, mm), r in rows_by.items() if mm == m)}
    head = ["planner"]
    for m in metrics:
        head.append(_label(m))
        if m in with_paper:
            head.append(f"paper: {m}")
    body = []
    for pc in planners:
        row = [pc.label]
        for m in metrics:
            r: SummaryRow | None = rows_by.get((pc.label, m))
            row.append("n/a" if r is None else md.pm(r.mean, r.sd) + (_range(r.min, r.max) if ext else ""))
            if m in with_paper:
                row.append("" if r is None or r.paper_mean is None else md.pm(r.paper_mean, r.paper_sd)
                           + (_range(r.paper_min, r.paper_max) if ext else ""))
        body.append(row)
    return md.table(head, body)


def p_cell(t: TestRow, p: float, alpha: float) -> str:
    """A p-value cell: the value, `` *`` when significant (never for an undefined test), and the zero-variance
    note (which groups have no spread) so a constant group is seen rather than starred."""
    note = spread_note(t)
    return fmt(p, 3) + (" *" if significant(p, alpha) else "") + (f" {note}" if note else "")


def _tests_markdown(a: Analysis, cfg: ExperimentConfig) -> str:
    if not a.tests:
        return ""
    alpha = cfg.stats.alpha
    out = [f"### Significance (per-seed means as samples; * marks p < {alpha:g})", ""]
    anova = [t for t in a.tests if t.test == "anova"]
    if anova:
        out += ["One-way ANOVA across planners:", "",
                md.table(["map", "metric", "F", "p", "groups"], text=2, rows=
                       [[t.map, t.metric, fmt(t.statistic), p_cell(t, t.p_value, alpha), str(t.n_b)]
                        for t in anova]), ""]
    pairs = [t for t in a.tests if t.test == "welch_t"]
    if pairs:
        adj = "Holm-adjusted p" if cfg.stats.correction == "holm" else "p (unadjusted)"
        out += ["Pairwise Welch t-tests:", "",
                md.table(["map", "metric", "A", "B", "t", "p", adj], text=4, rows=
                       [[t.map, t.metric, t.planner_a, t.planner_b, fmt(t.statistic), fmt(t.p_value, 3),
                         p_cell(t, t.p_adjusted, alpha)] for t in pairs]), ""]
    return "\n".join(out)


def summary_markdown(a: Analysis, cfg: ExperimentConfig) -> str:
    """summary.md: per map, planners × metrics as mean ± sd; the paper's values in "paper:" columns; tests."""
    R = len(a.seeds)
    out = [f"# {cfg.name}: summary", "",
           f"Each cell: {PER_SEED}, over {R} seed{'s' if R != 1 else ''}; wall-clock times: {PER_CHUNK}. "
           + ("[min, max]: the smallest and largest single trial (wall-clock times: chunk). " if cfg.stats.extremes
              else "")
           + "Columns headed \"paper:\" are the numbers the paper reports"
           + (f" ({cfg.paper_source})" if cfg.paper_source else "") + ", not ours.", ""]
    for mp in cfg.maps:
        out += [f"## {mp.name}", "", _map_table(a, cfg, mp.name), ""]
        bad = {p: n for (m, p), n in a.infeasible.items() if m == mp.name and n}
        if bad:
            out += ["Infeasible navigation trials left out (the robot does not fit): "
                    + ", ".join(f"{p} {n}" for p, n in bad.items()), ""]
    tests = _tests_markdown(a, cfg)
    if tests:
        out += [tests]
    return "\n".join(out).rstrip() + "\n"


def _overrides(d) -> str:
    return ", ".join(f"{k}={v}" for k, v in d.items()) or "defaults"


def report_markdown(a: Analysis, cfg: ExperimentConfig, prep: "Prepared", meta: dict[str, Any]) -> str:
    """report.md: what ran (versions, maps, scenarios, planners, seeds), how it is summarised, the tables."""
    R = len(cfg.seeds)
    seeds = f"{R} ({cfg.seeds[0]}..{cfg.seeds[-1]})" if list(cfg.seeds) == list(
        range(cfg.seeds[0], cfg.seeds[0] + R)) else f"{R} ({', '.join(map(str, cfg.seeds))})"
    out = [f"# Experiment {cfg.name}" + (" (quick)" if cfg.is_quick else ""), ""]
    if cfg.description:
        out += [cfg.description, ""]
    out += ["## Run", "",
            f"- jaxplan {meta.get('jaxplan_version')} (git {meta.get('git_revision') or 'unknown'}), "
            f"jax {meta.get('jax_version')}, numpy {meta.get('numpy_version')}, scipy {meta.get('scipy_version')}, "
            f"Python {meta.get('python')}",
            f"- devices: {', '.join(meta.get('devices', []))}",
            f"- started {meta.get('started')}; sessions: {len(meta.get('sessions', []))} "
            "(more than one: the run was resumed from its checkpoints)",
            f"- seeds: {seeds}; chunk: {cfg.chunk} scenarios per compiled call; trials: {prep.trials}", "",
            "## Setup", "", "Maps and scenarios:", ""]
    for mw in prep.maps:
        s = mw.spec
        if mw.problem is not None:
            value = f"optimum {fmt(float(mw.optimal[0]), 8)}"
            opt = (f"{value} ({s.tour.name})" if s.tour is not None else
                   f"{value} (configured)" if s.optimum is not None else "optimum unknown")
            out.append(f"- **{s.name}**: TSPLIB {s.tsplib.name}, {mw.problem.n} cities ({mw.problem.metric}); {opt}; "
                       "one scenario (the instance)")
            continue
        src = (f"{s.path.name}" if s.path is not None else f"generator {s.generator}({_overrides(s.params)}), "
                                                             f"seed {s.seed}")
        sc = s.scenarios
        how = {"scen": f"rows of {s.scen.name if s.scen else '?'} ({sc.spread})", "random":
               f"random connected pairs (seed {sc.seed}, >= {sc.min_distance:g} m apart)",
               "scene": "the generator's start and goal"}[sc.source]
        H, W = mw.grid.shape
        res = float(mw.grid.resolution)
        out.append(f"- **{s.name}**: {src}, {W}x{H} cells at {res:g} m; {len(mw.starts)} scenarios: {how}")
    out += ["", "Planners:", ""]
    for pc in cfg.planners:
        extra = ""
        if pc.kind == "navigate":
            parts = [f"{k}: {_overrides(getattr(pc, k))}" for k in ("nav", "dwa", "robot", "params")
                     if getattr(pc, k)]
            if pc.obstacles is not None and pc.obstacles.n:
                o = pc.obstacles
                parts.append(f"{o.n} moving discs ({o.speed:g} m/s, r {o.radius:g} m)")
            extra = ("; " + "; ".join(parts)) if parts else ""
        out.append(f"- **{pc.label}**: {pc.kind} `{pc.name}` ({_overrides(pc.overrides)}){extra}")
    out += ["", "## How to read the tables", "",
            f"For each map, planner and metric, the trials of one seed (one per scenario) are averaged first; "
            f"the table gives the mean and the sample standard deviation (ddof=1) of these {R} per-seed means — "
            "the spread to expect from new seeds on the same scenarios. A metric is averaged over the trials "
            "where it is defined: a failed plan has no length (see `success`), infeasible navigation trials "
            "(the inflated footprint does not fit) are left out, arrival time counts successful trials only. "
            "Wall-clock times are measured per batched call and divided by its trials (mean ± sd over chunks); "
            "they are in timings.csv, not in trials.csv, which is reproducible byte for byte.", "",
            "Metrics:", ""]
    out += [f"- `{m}`" + (f" ({METRICS[m].unit})" if METRICS[m].unit else "") + f": {METRICS[m].description}"
            for m in cfg.metrics]
    out += [""]
    body = summary_markdown(a, cfg)
    out += [body[body.index("\n## "):].lstrip("\n")]  # the tables, without summary.md's title and preamble
    if cfg.figures:
        out += ["## Figures (configured; drawn by `jaxplan figures`)", ""]
        out += [f"- {f.name}: {f.kind} ({_overrides(f.params)})" for f in cfg.figures]
        out += [""]
    out += ["## Files", "",
            "- `trials.csv`: one row per (map, planner, scenario, seed)",
            "- `summary.csv`, `summary.md`: the tables above; `significance.csv`: the tests",
            "- `timings.csv`: compile and run time per chunk",
            "- `checkpoints/`: manifest, per-chunk rows and arrays (orbax: convergence histories, paths, tours, "
            "trajectories; `jaxplan.experiments.load_chunk_arrays`)", ""]
    return "\n".join(out)
