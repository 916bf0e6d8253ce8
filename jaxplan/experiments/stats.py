"""Result tables from trials.csv: per-seed means, mean ± sd over seeds, ANOVA and Welch t-tests.

The statistic. For a map, a planner and a metric, each seed's trials (one per scenario)
are first averaged — over the trials where the metric is defined: a failed plan has no
length, an infeasible episode (the robot cannot fit) is left out of every navigation
metric, and a metric marked ``given_success`` (arrival time) only counts successful
trials; ``success`` itself averages to a rate. The table then gives the mean and the
sample standard deviation (``ddof=1``) of those per-seed means over the seeds: the
spread a reader should expect from re-running the experiment with new seeds on the same
scenarios — not the spread over scenarios, which mixes easy and hard rows. ``n`` counts
the seeds with a defined per-seed mean. ``min`` and ``max`` are the smallest and largest
single-trial value (not per-seed means): yu2020 reports Max/Min of its runs beside Avg/Sd, and
with one scenario per map (its configs) a trial is a seed's run.

Significance (if ``[stats]`` asks): per map and metric, a one-way ANOVA across planners
(`scipy.stats.f_oneway`) and Welch t-tests between every pair (`scipy.stats.ttest_ind`
with ``equal_var=False``), with the per-seed means as samples (n = seeds per planner).
Pairwise p-values are also given Holm-adjusted within each (map, metric) family. A group without
spread (every seed gave the same per-seed mean: an exact planner, or a smoke run) is named in the
test's ``no_spread``; when no group of a test has spread the test is undefined (scipy would give
F or t = ∞ and p = 0, a "certain" difference that is only an artefact of zero variance), so its
statistic and p are nan and it is never marked significant.

Wall-clock metrics (``plan_time_s``, ``step_time_s``) come from timings.csv, one value
per chunk (the batched call's time divided by its trials): mean ± sd over chunks.
"""

from __future__ import annotations

import csv
import itertools
import math
import os
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from jaxplan.experiments.config import METRICS, ExperimentConfig, PaperValue, applies

__all__ = ["SummaryRow", "TestRow", "Analysis", "read_trials", "trial_mask", "per_seed_means", "trial_range",
           "analyse", "holm", "no_spread", "spread_note", "significant", "confidence_interval", "hedges_g",
           "write_summary", "write_significance", "write_timings",
           "SUMMARY_COLUMNS", "SIGNIFICANCE_COLUMNS", "TIMING_COLUMNS"]

SUMMARY_COLUMNS = ("map", "planner", "metric", "unit", "statistic", "n", "trials", "mean", "sd", "min", "max",
                   "paper_mean", "paper_sd", "paper_min", "paper_max", "paper_source")
SIGNIFICANCE_COLUMNS = ("map", "metric", "test", "planner_a", "planner_b", "statistic", "p_value", "p_adjusted",
                        "n_a", "n_b", "no_spread")
TIMING_COLUMNS = ("uid", "map", "planner", "kind", "scenario_lo", "scenario_hi", "trials", "session", "compile_s",
                  "time_s", "plan_time_s", "step_time_s")
PER_SEED = "mean over seeds of per-seed means (sd: ddof=1)"
PER_CHUNK = "mean over chunks of per-trial wall time (sd: ddof=1)"


@dataclass(frozen=True)
class SummaryRow:
    """One map × planner × metric: ``mean``, ``sd`` over ``n`` seeds (or chunks) from ``trials`` values, ``min``
    and ``max`` of those single values; the paper's numbers in ``paper_*`` (None when the paper gives none)."""

    map: str
    planner: str
    metric: str
    unit: str
    statistic: str
    n: int
    trials: int
    mean: float
    sd: float
    paper_mean: float | None
    paper_sd: float | None
    paper_source: str
    min: float = math.nan
    max: float = math.nan
    paper_min: float | None = None
    paper_max: float | None = None


@dataclass(frozen=True)
class TestRow:
    """An ANOVA (``planner_b`` empty) or a Welch t-test between two planners.

    ``no_spread`` names the groups whose per-seed means are all equal; when it names every group of the
    test, the test is undefined and ``statistic``, ``p_value`` and ``p_adjusted`` are nan.
    """

    map: str
    metric: str
    test: str
    planner_a: str
    planner_b: str
    statistic: float
    p_value: float
    p_adjusted: float
    n_a: int
    n_b: int
    no_spread: tuple[str, ...] = ()


@dataclass(frozen=True)
class Analysis:
    """Everything the tables and the report show.

    Attributes:
      summary: `SummaryRow` per map × planner × applicable metric, in config order.
      tests: `TestRow` per map × tested metric (ANOVA, then pairs).
      per_seed: ``{(map, planner, metric): f64[R]}`` per-seed means (nan where undefined).
      seeds: the seeds, in order.
      infeasible: ``{(map, planner): count}`` navigation trials left out as infeasible.
    """

    summary: tuple[SummaryRow, ...]
    tests: tuple[TestRow, ...]
    per_seed: Mapping[tuple[str, str, str], np.ndarray]
    seeds: tuple[int, ...]
    infeasible: Mapping[tuple[str, str], int]


def read_trials(path: str | os.PathLike) -> dict[str, np.ndarray]:
    """Columns of trials.csv: text columns as ``object`` arrays, the rest ``f64`` (empty cells -> nan)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    head, body = rows[0], rows[1:]
    text = {"map", "planner", "kind", "reason"}
    out = {}
    for j, c in enumerate(head):
        col = [r[j] for r in body]
        out[c] = np.asarray(col, object) if c in text else np.asarray([float(x) if x else math.nan for x in col])
    return out


def trial_mask(t: Mapping[str, np.ndarray], map_: str, planner: str, metric: str) -> np.ndarray:
    """``bool[T]`` the trials of ``map_`` and ``planner`` that count for ``metric``: an infeasible navigation trial
    never counts, and a ``given_success`` metric counts successful trials only."""
    m = (t["map"] == map_) & (t["planner"] == planner)
    if "reason" in t:
        m &= ~np.array([str(x).startswith("infeasible") for x in t["reason"]], bool)
    if METRICS[metric].given_success:
        m &= t["success"] == 1
    return m


def trial_range(t: Mapping[str, np.ndarray], map_: str, planner: str, metric: str) -> tuple[float, float]:
    """(smallest, largest) defined single-trial value of ``metric`` (nan, nan when none is defined)."""
    x = t[metric][trial_mask(t, map_, planner, metric)]
    x = x[np.isfinite(x)]
    return (float(np.min(x)), float(np.max(x))) if x.size else (math.nan, math.nan)


def per_seed_means(t: Mapping[str, np.ndarray], map_: str, planner: str, metric: str,
                   seeds: Sequence[int]) -> tuple[np.ndarray, int]:
    """``f64[R]`` per-seed means of ``metric`` (nan for a seed with no defined value) and the values used."""
    base = trial_mask(t, map_, planner, metric)
    v = t[metric]
    out, used = np.full(len(seeds), math.nan), 0
    for i, s in enumerate(seeds):
        x = v[base & (t["seed"] == s)]
        x = x[np.isfinite(x)]
        used += x.size
        if x.size:
            out[i] = np.mean(x)
    return out, used


def _mean_sd(x: np.ndarray) -> tuple[float, float, int]:
    x = x[np.isfinite(x)]
    if x.size == 0:
        return math.nan, math.nan, 0
    return float(np.mean(x)), (float(np.std(x, ddof=1)) if x.size > 1 else math.nan), int(x.size)


def confidence_interval(x: np.ndarray, level: float = 0.95) -> tuple[float, float]:
    """Student-t interval of the mean of the finite values of ``x`` (ddof=1): (lo, hi).

    A sample of one value has no interval (nan, nan); a constant sample (an exact planner) has a
    zero-width one at its value. The one t interval of the package: `jaxplan.experiments.verdicts.mean_interval`.
    """
    from jaxplan.experiments.verdicts import mean_interval

    return mean_interval(x, level)


def hedges_g(x: np.ndarray, y: np.ndarray) -> float:
    """Hedges' g of two samples (finite values only): (mean(x) - mean(y)) / pooled sd, times the small-sample
    correction 1 - 3 / (4 (n_x + n_y) - 9). The effect size beside a Welch test's p-value: |g| of 0.2, 0.5,
    0.8 are the usual "small", "medium", "large". nan with fewer than two values in a sample or no spread."""
    x = np.asarray(x, np.float64)
    y = np.asarray(y, np.float64)
    x, y = x[np.isfinite(x)], y[np.isfinite(y)]
    nx, ny = x.size, y.size
    if nx < 2 or ny < 2:
        return math.nan
    pooled = math.sqrt(((nx - 1) * np.var(x, ddof=1) + (ny - 1) * np.var(y, ddof=1)) / (nx + ny - 2))
    if pooled == 0.0:
        return math.nan
    return float((np.mean(x) - np.mean(y)) / pooled * (1.0 - 3.0 / (4.0 * (nx + ny) - 9.0)))


def no_spread(groups: Mapping[str, np.ndarray]) -> tuple[str, ...]:
    """The labels of the groups of two or more values that are all equal (zero sample variance), in order."""
    return tuple(k for k, v in groups.items() if v.size >= 2 and float(np.ptp(v)) == 0.0)


def spread_note(t: TestRow) -> str:
    """What a table prints beside a test's p-value about zero variance: nothing when every group has spread,
    ``"(undefined: no spread in any group)"`` when the test has no within-group variance at all, else
    ``"(no spread: A*)"`` naming the constant groups (the test stands, but on the other groups' spread)."""
    if not t.no_spread:
        return ""
    groups = t.n_b if t.test == "anova" else 2
    if len(t.no_spread) == groups:
        return "(undefined: no spread in any group)"
    return f"(no spread: {', '.join(t.no_spread)})"


def significant(p: float, alpha: float) -> bool:
    """Whether a p-value earns the table's star: below ``alpha`` and defined (nan, an undefined test, never)."""
    return bool(math.isfinite(p) and p < alpha)


def holm(p: Sequence[float]) -> np.ndarray:
    """Holm's step-down adjusted p-values (nan stays nan)."""
    p = np.asarray(p, float)
    out = np.full(p.shape, math.nan)
    ok = np.flatnonzero(np.isfinite(p))
    order = ok[np.argsort(p[ok], kind="stable")]
    m, running = len(order), 0.0
    for k, i in enumerate(order):
        running = max(running, min(1.0, (m - k) * p[i]))
        out[i] = running
    return out


def _paper(cfg: ExperimentConfig, map_: str, planner: str, metric: str) -> PaperValue | None:
    """The paper's value for a site: given for its map (a drawn map's every draw) or for every map."""
    family = next((m.map_family for m in cfg.maps if m.name == map_), map_)
    exact = [v for v in cfg.paper if v.planner == planner and v.metric == metric and v.map in (map_, family)]
    anymap = [v for v in cfg.paper if v.planner == planner and v.metric == metric and v.map is None]
    return (exact or anymap or [None])[0]


def _read_timings(path: str | os.PathLike) -> list[dict]:
    if not Path(path).is_file():
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def analyse(trials_path: str | os.PathLike, timings_path: str | os.PathLike | None,
            cfg: ExperimentConfig) -> Analysis:
    """Summary rows and significance tests of a run (see the module docstring for the statistics)."""
    from scipy import stats as sps

    t = read_trials(trials_path)
    timings = _read_timings(timings_path) if timings_path else []
    seeds = tuple(int(s) for s in cfg.seeds)
    summary, per_seed, infeasible = [], {}, {}
    for mp in cfg.maps:
        for pc in cfg.planners:
            if not applies(pc, mp):
                continue
            if "reason" in t:
                rows = (t["map"] == mp.name) & (t["planner"] == pc.label)
                infeasible[mp.name, pc.label] = int(sum(str(x).startswith("infeasible") for x in t["reason"][rows]))
            for metric in cfg.metrics:
                spec = METRICS[metric]
                if pc.kind not in spec.kinds:
                    continue
                if spec.timing:
                    vals = np.asarray([float(r[metric]) for r in timings if r["map"] == mp.name
                                       and r["planner"] == pc.label and r.get(metric, "") != ""], float)
                    mean, sd, n = _mean_sd(vals)
                    used, statistic = n, PER_CHUNK
                    fin = vals[np.isfinite(vals)]
                    lo, hi = (float(fin.min()), float(fin.max())) if fin.size else (math.nan, math.nan)
                else:
                    ps, used = per_seed_means(t, mp.name, pc.label, metric, seeds)
                    per_seed[mp.name, pc.label, metric] = ps
                    mean, sd, n = _mean_sd(ps)
                    lo, hi = trial_range(t, mp.name, pc.label, metric)
                    statistic = PER_SEED + (" (successful trials)" if spec.given_success else "")
                pv = _paper(cfg, mp.name, pc.label, metric)
                summary.append(SummaryRow(mp.name, pc.label, metric, spec.unit, statistic, n, used, mean, sd,
                                          pv.mean if pv else None, pv.sd if pv else None,
                                          cfg.paper_source if pv else "", lo, hi, pv.min if pv else None,
                                          pv.max if pv else None))
    tests = []
    st = cfg.stats
    for mp in cfg.maps:
        for metric in st.metrics if (st.anova or st.pairwise) else ():
            groups = {pc.label: per_seed[mp.name, pc.label, metric] for pc in cfg.planners
                      if (mp.name, pc.label, metric) in per_seed}
            groups = {k: v[np.isfinite(v)] for k, v in groups.items()}
            with warnings.catch_warnings():
                # Constant groups (an exact planner gives the same per-seed mean for every seed) make the
                # statistic undefined: scipy warns and returns nan, which the table shows as such.
                warnings.simplefilter("ignore")
                flat = no_spread(groups)
                if st.anova:
                    usable = [v for v in groups.values() if v.size >= 2]
                    # No within-group variance at all: F = ∞, p = 0 from scipy is an artefact, not evidence.
                    if len(usable) >= 2 and len(usable) == len(groups) and len(flat) < len(groups):
                        r = sps.f_oneway(*usable)
                        f, p = float(r.statistic), float(r.pvalue)
                    else:
                        f, p = math.nan, math.nan
                    tests.append(TestRow(mp.name, metric, "anova", "", "", f, p, p,
                                         sum(v.size for v in groups.values()), len(groups), flat))
                if st.pairwise:
                    pairs = []
                    for a, b in itertools.combinations(groups, 2):
                        x, y = groups[a], groups[b]
                        both_flat = a in flat and b in flat  # t = ±∞, p = 0: undefined, as for the ANOVA
                        if x.size >= 2 and y.size >= 2 and not both_flat:
                            r = sps.ttest_ind(x, y, equal_var=False)
                            pairs.append([a, b, float(r.statistic), float(r.pvalue), x.size, y.size])
                        else:
                            pairs.append([a, b, math.nan, math.nan, x.size, y.size])
                    adj = holm([q[3] for q in pairs]) if st.correction == "holm" else [q[3] for q in pairs]
                    for q, pa in zip(pairs, adj, strict=True):
                        tests.append(TestRow(mp.name, metric, "welch_t", q[0], q[1], q[2], q[3], float(pa), q[4], q[5],
                                             tuple(k for k in flat if k in (q[0], q[1]))))
    return Analysis(tuple(summary), tuple(tests), per_seed, seeds, infeasible)


def _cell(v) -> str:
    if v is None:
        return ""
    if isinstance(v, tuple):  # a list of planner labels (``no_spread``)
        return ";".join(map(str, v))
    if isinstance(v, float):
        return "nan" if math.isnan(v) else repr(v)
    return str(v)


def _write_csv(path: str | os.PathLike, columns: Sequence[str], rows: list[list]) -> None:
    import io

    from jaxplan.core.io import atomic_write

    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(columns)
    for r in rows:
        w.writerow([_cell(x) for x in r])
    atomic_write(Path(path), buf.getvalue().encode())


def write_summary(path: str | os.PathLike, a: Analysis) -> None:
    """summary.csv: `SUMMARY_COLUMNS`; the paper's numbers only in the ``paper_*`` columns."""
    _write_csv(path, SUMMARY_COLUMNS, [[getattr(r, c) for c in SUMMARY_COLUMNS] for r in a.summary])


def write_significance(path: str | os.PathLike, a: Analysis) -> None:
    """significance.csv: `SIGNIFICANCE_COLUMNS` (an ANOVA row has no ``planner_b``; ``n_b`` is its group count;
    ``no_spread`` lists the groups without spread, ``;``-separated)."""
    _write_csv(path, SIGNIFICANCE_COLUMNS, [[getattr(r, c) for c in SIGNIFICANCE_COLUMNS] for r in a.tests])


def write_timings(path: str | os.PathLike, entries: list[dict]) -> None:
    """timings.csv from the manifest entries of the chunks, in run order."""
    rows = [[e["uid"], e["map"], e["planner"], e["kind"], e["scenarios"][0], e["scenarios"][1], e["trials"],
             e["session"], float(e["compile_s"]), float(e["time_s"]), float(e["plan_time_s"]),
             float(e["step_time_s"]) if "step_time_s" in e else None] for e in entries]
    _write_csv(path, TIMING_COLUMNS, rows)
