"""The papers' claims, each tested against our runs: the table that opens the reproduction report.

A claim is a sentence of a paper (its abstract, its conclusion, or what a table or figure is said to show)
declared in ``configs/results/claims.toml`` (`load_claims`) with the test that decides it:

- ``contrast``: the proposed planner against the paper's baseline on the same maps, start-goal pairs and seeds
  (paired: `jaxplan.experiments.evidence.paired_units`), or across two maps (``proposed_map``/``baseline_map``,
  unpaired). Where our map stands in for the paper's, the paper's contrast is what can be tested, not its number.
- ``trend``: a metric against a numeric level (obstacle ratio, a weight), over maps or planners: the fitted
  change over the tested range.
- ``absolute``: the claim is a number the paper prints; its verdict is that number's cell on its page (judged
  there once, linked from here).
- ``not_testable``: with the reason.

Verdicts (`CLAIM_VERDICTS`): *reproduced* (the 95 % interval of the effect lies on the claimed side of zero),
*opposite* (on the other side), *not reproduced* (no effect: the 90 % interval lies within the equivalence
margin, TOST), *inconclusive* (neither), *not testable*. The rules are `jaxplan.experiments.verdicts`'; the
margins, one per metric, are declared in the same file (``[margins]``) and also decide when a paper's number is
*consistent* with ours.
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from jaxplan.experiments.config import METRICS, ExperimentConfig
from jaxplan.experiments.evidence import Evidence, family_sites, paired_units, unit_name, units
from jaxplan.experiments.verdicts import DIRECTIONS, Margin, judge_contrast, judge_trend, parse_margin

__all__ = ["CLAIM_TESTS", "CLAIM_VERDICTS", "Claim", "Claims", "ClaimResult", "load_claims", "check_claims",
           "evaluate_claim", "absolute_verdict", "units_label"]

CLAIM_TESTS = ("contrast", "trend", "absolute", "not_testable")
CLAIM_VERDICTS = ("reproduced", "not reproduced", "opposite", "inconclusive", "not testable")
"""The claim verdicts, in the order the index counts them."""

_KEYS = {"id", "paper", "claim", "where", "test", "config", "metric", "proposed", "baseline", "direction", "map",
         "proposed_map", "baseline_map", "levels", "over", "figure", "note", "reason", "margin"}
_REQUIRED = {"contrast": ("config", "metric", "proposed", "baseline", "direction"),
             "trend": ("config", "metric", "levels", "over", "direction"),
             "absolute": ("config", "metric", "proposed"),
             "not_testable": ("reason",)}


@dataclass(frozen=True)
class Claim:
    """One claim of a paper and the test that decides it (see the module docstring and claims.toml)."""

    id: str
    paper: str
    claim: str
    where: str
    test: str
    config: str | None = None
    metric: str | None = None
    proposed: str | None = None
    baseline: str | None = None
    direction: str | None = None
    map: str | None = None
    proposed_map: str | None = None
    baseline_map: str | None = None
    levels: tuple[tuple[str, float], ...] = ()
    over: str | None = None
    figure: str | None = None
    note: str = ""
    reason: str = ""
    margin: Margin | None = None


@dataclass(frozen=True)
class Claims:
    """The claims file: the equivalence margin of each metric and the claims, in file order."""

    margins: Mapping[str, Margin]
    claims: tuple[Claim, ...]

    def margin(self, metric: str, claim: Claim | None = None) -> Margin | None:
        """The claim's own margin, else the metric's; None when the file gives neither."""
        if claim is not None and claim.margin is not None:
            return claim.margin
        return self.margins.get(metric)


def load_claims(path: str | os.PathLike | None) -> Claims:
    """Reads and checks the claims file (a missing file gives no claims).

    Raises:
      ValueError: naming the claim and key of every problem (unknown key or test, a missing key the test needs,
        a duplicate id, an unknown metric, a bad margin).
    """
    from jaxplan.papers import PAPERS

    if path is None or not Path(path).is_file():
        return Claims({}, ())
    raw = tomllib.loads(Path(path).read_text())
    problems: list[str] = []
    margins = {}
    for metric, v in raw.get("margins", {}).items():
        if metric not in METRICS:
            problems.append(f"margins.{metric}: unknown metric")
            continue
        try:
            margins[metric] = parse_margin(v)
        except ValueError as e:
            problems.append(f"margins.{metric}: {e}")
    extra = sorted(set(raw) - {"margins", "claims"})
    if extra:
        problems.append(f"unknown top-level key(s) {', '.join(extra)}")
    out, ids = [], set()
    for i, c in enumerate(raw.get("claims", [])):
        where = f"claims[{i}]" + (f" ({c.get('id')})" if isinstance(c, dict) and c.get("id") else "")
        if not isinstance(c, dict):
            problems.append(f"{where}: expected a table")
            continue
        bad = sorted(set(c) - _KEYS)
        if bad:
            problems.append(f"{where}: unknown key(s) {', '.join(bad)}")
        for k in ("id", "paper", "claim", "where", "test"):
            if not c.get(k):
                problems.append(f"{where}: '{k}' is required")
        test = c.get("test")
        if test not in CLAIM_TESTS:
            problems.append(f"{where}: test must be one of {', '.join(CLAIM_TESTS)}, got {test!r}")
            continue
        for k in _REQUIRED[test]:
            if c.get(k) in (None, "", {}):
                problems.append(f"{where}: a {test} claim needs '{k}'")
        if c.get("paper") not in PAPERS:
            problems.append(f"{where}: unknown paper {c.get('paper')!r}")
        if c.get("id") in ids:
            problems.append(f"{where}: duplicate id")
        ids.add(c.get("id"))
        if c.get("metric") is not None and c["metric"] not in METRICS:
            problems.append(f"{where}: unknown metric {c['metric']!r}")
        if c.get("direction") is not None and c["direction"] not in DIRECTIONS:
            problems.append(f"{where}: direction must be 'higher' or 'lower'")
        if test == "trend" and c.get("over") not in ("map", "planner"):
            problems.append(f"{where}: over must be 'map' or 'planner'")
        if test == "trend" and c.get("over") == "map" and not c.get("proposed"):
            problems.append(f"{where}: a trend over maps needs 'proposed' (the planner)")
        if c.get("map") and (c.get("proposed_map") or c.get("baseline_map")):
            problems.append(f"{where}: give 'map' or 'proposed_map'/'baseline_map', not both")
        if bool(c.get("proposed_map")) != bool(c.get("baseline_map")):
            problems.append(f"{where}: 'proposed_map' and 'baseline_map' go together")
        levels = c.get("levels", {})
        if not isinstance(levels, dict) or not all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                   for x in levels.values()):
            problems.append(f"{where}: levels must map names to numbers")
            levels = {}
        if test == "trend" and len(levels) < 2:
            problems.append(f"{where}: a trend needs at least two levels")
        margin = None
        if "margin" in c:
            try:
                margin = parse_margin(c["margin"])
            except ValueError as e:
                problems.append(f"{where}: margin: {e}")
        if test in ("contrast", "trend") and c.get("metric") in METRICS and margin is None \
                and c["metric"] not in margins:
            problems.append(f"{where}: no margin for metric {c['metric']!r} (give [margins] {c['metric']} or margin)")
        out.append(Claim(
            id=str(c.get("id")), paper=str(c.get("paper")), claim=str(c.get("claim", "")).strip(),
            where=str(c.get("where", "")), test=test, config=c.get("config"), metric=c.get("metric"),
            proposed=c.get("proposed"), baseline=c.get("baseline"), direction=c.get("direction"), map=c.get("map"),
            proposed_map=c.get("proposed_map"), baseline_map=c.get("baseline_map"),
            levels=tuple((str(k), float(v)) for k, v in levels.items()), over=c.get("over"), figure=c.get("figure"),
            note=str(c.get("note", "")).strip(), reason=str(c.get("reason", "")).strip(), margin=margin))
    if problems:
        raise ValueError(f"{path}: " + "; ".join(problems))
    return Claims(margins, tuple(out))


def check_claims(claims: Claims, configs: Mapping[str, ExperimentConfig]) -> list[str]:
    """Problems of the claims against the configs they name (config name -> config): an unknown config, planner
    label, map, figure, or a metric the config does not record. Empty when every name resolves."""
    problems = []
    for c in claims.claims:
        if c.test == "not_testable" and c.config is None:
            continue
        cfg = configs.get(c.config or "")
        if cfg is None:
            problems.append(f"{c.id}: unknown config {c.config!r}")
            continue
        labels = {p.label for p in cfg.planners}
        families = {m.map_family for m in cfg.maps}
        figures = {f.name for f in cfg.figures}
        names = [c.proposed, c.baseline] + ([k for k, _ in c.levels] if c.over == "planner" else [])
        for lab in names:
            if lab is not None and lab not in labels:
                problems.append(f"{c.id}: {c.config} has no planner {lab!r}")
        maps = [c.map, c.proposed_map, c.baseline_map] + ([k for k, _ in c.levels] if c.over == "map" else [])
        for m in maps:
            if m is not None and m not in families:
                problems.append(f"{c.id}: {c.config} has no map {m!r}")
        if c.metric is not None and c.metric not in cfg.metrics:
            problems.append(f"{c.id}: {c.config} does not record {c.metric!r}")
        if c.figure is not None and c.figure not in figures:
            problems.append(f"{c.id}: {c.config} has no figure {c.figure!r}")
    return problems


@dataclass(frozen=True)
class ClaimResult:
    """A claim's outcome: ``effect`` (proposed − baseline, or the fitted change of a trend, in metric units) with
    its 95 % ``interval``, ``relative`` (effect over the baseline's mean), over ``n`` units of kind ``unit``;
    ``verdict`` one of `CLAIM_VERDICTS`, ``rule`` the rule that made it, ``test`` what we ran."""

    claim: Claim
    verdict: str
    rule: str
    test: str
    effect: float = math.nan
    interval: tuple[float, float] = (math.nan, math.nan)
    relative: float = math.nan
    n: int = 0
    unit: str = ""


def _applies(ev: Evidence, family: str, *labels: str) -> bool:
    return all(ev.has(family, lab) for lab in labels)


def _families(ev: Evidence, c: Claim, *labels: str) -> list[str]:
    if c.map is not None:
        return [c.map]
    return [f for f in ev.families() if _applies(ev, f, *labels)]


def _describe(ev: Evidence, fams: Sequence[str], what: str) -> str:
    cfg = ev.config
    sites = [m for f in fams for m in family_sites(cfg, f)]
    draws = sum(len(family_sites(cfg, f)) for f in fams)
    drawn = any(ev.drawn(f) for f in fams)
    scen = sorted({int(x) for x in ev.trials["scenario"]}) if "scenario" in ev.trials else []
    per_map = {m.name: len({int(s) for s, mp in zip(ev.trials["scenario"], ev.trials["map"], strict=True)
                            if mp == m.name}) for m in sites}
    pairs = max(per_map.values(), default=len(scen))
    maps = ", ".join(fams) + (f" ({draws} map draws)" if drawn else "")
    return f"{what} on {maps}; {pairs} pair{'s' if pairs != 1 else ''} × {len(cfg.seeds)} seeds"


def evaluate_claim(c: Claim, ev: Evidence | None, claims: Claims, *, alpha: float = 0.05) -> ClaimResult:
    """The verdict of a contrast or trend claim from the run's evidence (``ev`` None: the run is missing, which
    makes the claim not testable). Absolute claims take their cell's verdict (`absolute_verdict`)."""
    if c.test == "not_testable":
        return ClaimResult(c, "not testable", c.reason, "—")
    if ev is None:
        return ClaimResult(c, "not testable", f"no run of {c.config}", "—")
    metric = c.metric
    margin = claims.margin(metric, c)
    if c.test == "contrast":
        if c.proposed_map is not None:
            a = units(ev, c.proposed_map, c.proposed, metric)
            b = units(ev, c.baseline_map, c.baseline, metric)
            base = float(np.nanmean(b)) if np.isfinite(b).any() else math.nan
            v = judge_contrast(a, b, paired=False, direction=c.direction, margin=_abs(margin, base), alpha=alpha)
            test = (f"contrast, {c.proposed} on {c.proposed_map} against {c.baseline} on {c.baseline_map} "
                    f"(unpaired); {len(ev.config.seeds)} seeds")
            fams = [c.proposed_map, c.baseline_map]
        else:
            fams = _families(ev, c, c.proposed, c.baseline)
            if not fams:
                return ClaimResult(c, "not testable", f"{c.proposed} and {c.baseline} share no map", "—")
            a, b = paired_units(ev, fams, c.proposed, c.baseline, metric)
            base = float(np.nanmean(b)) if np.isfinite(b).any() else math.nan
            v = judge_contrast(a, b, paired=True, direction=c.direction, margin=_abs(margin, base), alpha=alpha)
            test = _describe(ev, fams, f"contrast {c.proposed} − {c.baseline}, paired")
        unit = units_label(ev, fams)
        return ClaimResult(c, v.verdict, v.rule, test, v.effect, v.interval, v.relative, v.n, unit)
    # trend
    xs, ys = [], []
    if c.over == "map":
        for fam, x in c.levels:
            y = units(ev, fam, c.proposed, metric)
            xs += [x] * y.size
            ys += list(y)
        fams = [k for k, _ in c.levels]
        what = f"trend of {c.proposed} over {', '.join(fams)}"
    else:
        fams = _families(ev, c, *[k for k, _ in c.levels])
        for lab, x in c.levels:
            y = np.concatenate([units(ev, f, lab, metric) for f in fams])
            xs += [x] * y.size
            ys += list(y)
        what = f"trend over {', '.join(k for k, _ in c.levels)} on {', '.join(fams)}"
    xs, ys = np.asarray(xs, float), np.asarray(ys, float)
    ok = np.isfinite(ys)
    base = float(np.mean(ys[ok])) if ok.any() else math.nan
    v = judge_trend(xs[ok], ys[ok], direction=c.direction, margin=_abs(margin, base), alpha=alpha)
    unit = units_label(ev, fams)
    return ClaimResult(c, v.verdict, v.rule, f"{what}; {len(ev.config.seeds)} seeds", v.effect, v.interval,
                       v.relative, v.n, unit)


def units_label(ev: Evidence, fams: Sequence[str]) -> str:
    """What the units of a claim over ``fams`` are: seeds or map draws of one map, (map, seed) means of several."""
    kinds = list(dict.fromkeys(unit_name(ev, f) for f in dict.fromkeys(fams)))
    if len(set(fams)) > 1 and kinds == ["seeds"]:
        return "map × seed means"
    return " + ".join(kinds)


def _abs(margin: Margin | None, reference: float) -> float:
    if margin is None:
        raise ValueError("a contrast or trend claim needs a margin")
    return margin.of(reference if math.isfinite(reference) else 0.0)


_FROM_CELL = {"consistent": "reproduced", "ours better": "reproduced", "ours worse": "not reproduced",
              "inconclusive": "inconclusive", "not comparable": "not testable"}


def absolute_verdict(c: Claim, cell: Any | None) -> ClaimResult:
    """An absolute claim's result from its cell on its page (``cell``: a `jaxplan.experiments.results.Cell`, or
    None when no cell holds it): consistent or ours better -> reproduced, ours worse -> not reproduced,
    not comparable -> not testable (with the cell's reason); the number is judged on its page, not here."""
    if cell is None:
        return ClaimResult(c, "not testable", "no paper value of this planner and metric on the page", "—")
    verdict = _FROM_CELL[cell.verdict]
    rule = f"the page's cell: {cell.verdict}" + (f" ({cell.reason})" if cell.reason else f" by {cell.rule}")
    return ClaimResult(c, verdict, rule, f"absolute, against the paper's {cell.metric}",
                       cell.ours_mean - cell.paper_mean, cell.ci, math.nan, cell.n, cell.unit)
