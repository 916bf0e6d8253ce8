"""Verdict rules of the reproduction report: one paper number against ours, and one claim of a paper.

Every rule here is a pure function of numbers (no configs, no files); ``scipy.stats`` does the arithmetic.

**A paper's number against ours** (`judge_number`). The question is not "do the two means differ?" — with enough
seeds every difference is significant, and a 2 % gap would read "ours worse" — but "are they the same up to a stated
margin Δ?". That is an equivalence question, and the test built for it is TOST (two one-sided tests): the difference
is shown to lie inside (−Δ, +Δ) when both one-sided tests reject at level α, which is the same as our (1 − 2α)
interval of the difference lying inside the margin. So *consistent* is a positive finding, backed by data; failing to
find a difference is not evidence of sameness, and a small sample is *inconclusive*, not "consistent". Δ is stated
per metric (`Margin`: absolute in the metric's unit, or relative to the paper's value), so the reader sees what
"consistent" tolerated. The rule depends on what the paper reports:

- **A rate** (successes k of N trials): Wilson score intervals. A t interval of a proportion passes 0 or 1 and is
  wrong near them (a 100 % success rate has sd 0 and a zero-width t interval); the Wilson interval stays inside
  [0, 1] and keeps close to its nominal coverage for small N and extreme rates. Consistent when our
  (1 − 2α) Wilson interval lies inside [paper − Δ, paper + Δ] (TOST in interval form); better or worse when the
  paper's value lies outside our (1 − α) interval. The interval treats the N trials as independent; trials that
  share a seed or a map draw are correlated, so with such clustering it is narrower than the truth.
- **Mean, sd and n of the paper**: a Welch t test between the paper's (mean, sd, n) and ours (Welch, because
  the two spreads need not be equal), with Welch–Satterthwaite degrees of freedom. Consistent when the TOST p
  < α; else better or worse when the Welch p < α; else inconclusive. Both sides with no spread (exact planners)
  admit no test: the difference is set against Δ directly ("no spread").
- **One run of the paper** (n = 1, or neither sd nor n given): a single run scatters like a single run, not
  like a mean, so the paper's number is set against our 95 % *prediction interval of one new run* —
  mean ± t·sd·sqrt(1 + 1/n) over our per-run values — not against the interval of our mean, which shrinks with
  our sample size and would call almost any single run "different". Here ``ours`` must be per-run values.
- **sd without n**: Welch needs n, and guessing it decides the verdict, so the conservative one-run
  prediction interval is used and the rule says "n not reported".
- **n without sd** (n ≥ 2): the paper's number is a mean of n runs whose spread we take from ours: the
  prediction interval of a mean of n new runs, mean ± t·sd·sqrt(1/n + 1/n_ours) (per-run values of ours).

**A claim of a paper** (`judge_contrast`, `judge_trend`): a within-paper contrast, "the proposed method is better
than the baseline" (proposed − baseline has the claimed sign) or "the metric rises with the parameter" (the fitted
change over the tested range has the claimed sign), tested on our runs. Paired over units (seed × map draw ×
scenario pair) when both methods ran on the same units, which removes the unit-to-unit variance from the contrast;
Welch otherwise. *Reproduced* when the 95 % interval of the effect lies strictly on the claimed side of 0,
*opposite* when strictly on the other side, *not reproduced* when the 90 % interval lies inside ±margin (an
equivalence finding: no effect of the size the margin names), *inconclusive* otherwise (the interval is too wide
to tell). With no spread at all the effect is set against the margin directly.

Verdict vocabularies: `NUMBER_VERDICTS` = ("consistent", "ours better", "ours worse", "inconclusive");
`CLAIM_VERDICTS` = ("reproduced", "not reproduced", "opposite", "inconclusive").
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable, Mapping, NamedTuple, Sequence

import numpy as np
from scipy import stats as sps

__all__ = ["Margin", "parse_margin", "t_quantile", "wilson_interval", "prediction_interval", "mean_interval",
           "welch_from_stats",
           "tost_from_stats", "NumberVerdict", "judge_number", "ContrastVerdict", "judge_contrast", "judge_trend",
           "count", "NUMBER_VERDICTS", "CLAIM_VERDICTS"]

NUMBER_VERDICTS = ("consistent", "ours better", "ours worse", "inconclusive")
CLAIM_VERDICTS = ("reproduced", "not reproduced", "opposite", "inconclusive")
DIRECTIONS = ("higher", "lower")

_NAN2 = (math.nan, math.nan)


# --------------------------------------------------------------------------------------------------------- margins
@dataclass(frozen=True)
class Margin:
    """The equivalence margin Δ of a metric: ``value`` in the metric's unit, or a fraction of the reference
    (the paper's value) when ``relative``."""

    value: float
    relative: bool

    def __post_init__(self) -> None:
        if isinstance(self.value, bool) or not isinstance(self.value, (int, float)):
            raise ValueError(f"margin: value must be a number, got {self.value!r}")
        if not math.isfinite(self.value) or self.value < 0:
            raise ValueError(f"margin: value must be finite and >= 0, got {self.value!r}")

    def of(self, reference: float) -> float:
        """The absolute half-width Δ around ``reference``: ``value * |reference|`` if relative, else ``value``."""
        return self.value * abs(reference) if self.relative else float(self.value)

    def describe(self, unit: str, scale: float = 1.0) -> str:
        """"±5 %" (relative) or "±0.05 m" (absolute, multiplied by ``scale`` to the display ``unit``)."""
        if self.relative:
            return f"±{self.value * 100:g} %"
        return f"±{self.value * scale:g} {unit}".rstrip()


def parse_margin(x: object) -> Margin:
    """A `Margin` from its TOML form: ``{abs = 0.05}`` (metric units) or ``{rel = 0.05}`` (fraction of the paper's
    value). Raises ValueError naming the problem: not a table, no key or both keys, an unknown key, a value that is
    not a number, NaN, infinite or negative."""
    if not isinstance(x, Mapping):
        raise ValueError(f"margin: expected a table {{abs = ...}} or {{rel = ...}}, got {x!r}")
    unknown = sorted(set(x) - {"abs", "rel"})
    if unknown:
        raise ValueError(f"margin: unknown key(s) {unknown}; use 'abs' or 'rel'")
    if len(x) != 1:
        raise ValueError(f"margin: give exactly one of 'abs' or 'rel', got {sorted(x)}")
    key, value = next(iter(x.items()))
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"margin: {key} must be a number, got {value!r}")
    if math.isnan(value):
        raise ValueError(f"margin: {key} is NaN")
    if math.isinf(value):
        raise ValueError(f"margin: {key} is infinite")
    if value < 0:
        raise ValueError(f"margin: {key} is negative ({value})")
    return Margin(float(value), key == "rel")


# ------------------------------------------------------------------------------------------------------- intervals
def _finite(values) -> np.ndarray:
    """The finite values of ``values`` as float64, 1-D (nan and ±inf dropped: undefined trials)."""
    v = np.asarray(values, np.float64).ravel()
    return v[np.isfinite(v)]


def _mean_sd(v: np.ndarray) -> tuple[float, float]:
    """Mean and sd (ddof=1) of finite ``v`` (size >= 2); a constant sample gives exactly (its value, 0) — the
    float mean of [0.1, 0.1, 0.1] is not 0.1, and a spurious 1e-17 spread would turn "no spread" into a test."""
    if np.ptp(v) == 0.0:
        return float(v[0]), 0.0
    return float(np.mean(v)), float(np.std(v, ddof=1))


def _check_confidence(confidence: float) -> None:
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be in (0, 1), got {confidence!r}")


def t_quantile(confidence: float, df: float) -> float:
    """The two-sided Student-t quantile t_{(1+c)/2, df}: the half-width of a ``confidence`` interval in standard
    errors. The one place the package asks scipy for it (every t interval goes through here or `mean_interval`);
    ``df <= 0`` or NaN gives NaN (as does a confidence outside [0, 1]: callers check theirs)."""
    return float(sps.t.ppf(0.5 + confidence / 2.0, df))


def wilson_interval(k: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson score interval of a proportion k / n: (lo, hi), always inside [0, 1].

    centre = (p + z²/2n) / (1 + z²/n), half = z / (1 + z²/n) · sqrt(p(1 − p)/n + z²/4n²), with p = k/n and
    z the standard normal (1 + confidence)/2 quantile. k = 0 gives lo = 0 and k = n gives hi = 1 exactly (set
    so, rather than left to rounding). n == 0: (nan, nan).
    """
    _check_confidence(confidence)
    if isinstance(k, bool) or isinstance(n, bool) or int(k) != k or int(n) != n:
        raise ValueError(f"wilson_interval: k and n must be integers, got k={k!r}, n={n!r}")
    k, n = int(k), int(n)
    if n < 0 or not 0 <= k <= n:
        raise ValueError(f"wilson_interval: need 0 <= k <= n, got k={k}, n={n}")
    if n == 0:
        return _NAN2
    z = float(sps.norm.ppf(0.5 + confidence / 2.0))
    p, z2 = k / n, z * z
    denom = 1.0 + z2 / n
    centre = (p + z2 / (2 * n)) / denom
    half = z / denom * math.sqrt(p * (1.0 - p) / n + z2 / (4 * n * n))
    lo = 0.0 if k == 0 else max(0.0, centre - half)
    hi = 1.0 if k == n else min(1.0, centre + half)
    return lo, hi


def _prediction_interval(values, confidence: float, runs: float) -> tuple[float, float]:
    """Interval that a mean of ``runs`` new runs falls in with probability ``confidence``, from the sample
    ``values``: mean ± t_{(1+c)/2, n−1} · sd · sqrt(1/runs + 1/n); ``runs = inf`` gives the interval of the mean."""
    _check_confidence(confidence)
    v = _finite(values)
    if v.size < 2:
        return _NAN2
    m, sd = _mean_sd(v)
    if sd == 0.0:
        return m, m
    half = t_quantile(confidence, v.size - 1) * sd * math.sqrt(1.0 / runs + 1.0 / v.size)
    return m - half, m + half


def prediction_interval(values, confidence: float = 0.95) -> tuple[float, float]:
    """Prediction interval of ONE new run from the per-run sample ``values``: mean ± t_{(1+c)/2, n−1} · sd ·
    sqrt(1 + 1/n) (sd with ddof=1). Non-finite values are dropped; fewer than 2 left -> (nan, nan); no spread
    -> (mean, mean). Unlike the interval of the mean it does not shrink to a point as n grows: it keeps the
    run-to-run scatter a single run of the paper is subject to."""
    return _prediction_interval(values, confidence, 1)


def mean_interval(values, confidence: float = 0.95) -> tuple[float, float]:
    """Student-t interval of the mean of ``values``: mean ± t_{(1+c)/2, n−1} · sd / sqrt(n) (ddof=1).
    Non-finite values are dropped; fewer than 2 left -> (nan, nan); no spread -> (mean, mean)."""
    return _prediction_interval(values, confidence, math.inf)


# ------------------------------------------------------------------------------------------- tests from summaries
def _check_stats(name: str, m: float, s: float, n: int) -> None:
    if not math.isfinite(m):
        raise ValueError(f"{name}: mean must be finite, got {m!r}")
    if not math.isfinite(s) or s < 0:
        raise ValueError(f"{name}: sd must be finite and >= 0, got {s!r}")
    if int(n) != n or n < 2:
        raise ValueError(f"{name}: n must be an integer >= 2, got {n!r}")


def _welch_df(s1: float, n1: int, s2: float, n2: int) -> float:
    """Welch–Satterthwaite df: (v1 + v2)² / (v1²/(n1 − 1) + v2²/(n2 − 1)), v = s²/n; nan if both v are 0."""
    v1, v2 = s1 * s1 / n1, s2 * s2 / n2
    if v1 + v2 == 0.0:
        return math.nan
    return (v1 + v2) ** 2 / (v1 * v1 / (n1 - 1) + v2 * v2 / (n2 - 1))


def welch_from_stats(m1: float, s1: float, n1: int, m2: float, s2: float, n2: int) -> tuple[float, float, float]:
    """Welch's t test from two summaries (mean, sd with ddof=1, n ≥ 2): (t, df, two-sided p), t of m1 − m2.

    t and p from `scipy.stats.ttest_ind_from_stats` (equal_var=False); df by Welch–Satterthwaite. Both sds 0
    (no spread on either side) admits no test: t = ±inf when the means differ (nan when equal), df = nan and
    p = nan — the caller decides such a case without a p-value (`judge_number` says "no spread").
    """
    _check_stats("sample 1", m1, s1, n1)
    _check_stats("sample 2", m2, s2, n2)
    if s1 == 0.0 and s2 == 0.0:
        t = math.nan if m1 == m2 else math.copysign(math.inf, m1 - m2)
        return t, math.nan, math.nan
    res = sps.ttest_ind_from_stats(m1, s1, n1, m2, s2, n2, equal_var=False)
    return float(res.statistic), _welch_df(s1, n1, s2, n2), float(res.pvalue)


def tost_from_stats(m1: float, s1: float, n1: int, m2: float, s2: float, n2: int, margin: float) -> float:
    """TOST p that |m2 − m1| < ``margin`` (absolute, ≥ 0) from two summaries: the larger p of the one-sided Welch
    tests of H0: m2 − m1 ≤ −margin and H0: m2 − m1 ≥ +margin, with the Welch–Satterthwaite df. A p below α
    shows equivalence at level α. Both sds 0: nan (no test; see `welch_from_stats`)."""
    _check_stats("sample 1", m1, s1, n1)
    _check_stats("sample 2", m2, s2, n2)
    if not math.isfinite(margin) or margin < 0:
        raise ValueError(f"margin must be finite and >= 0, got {margin!r}")
    se = math.sqrt(s1 * s1 / n1 + s2 * s2 / n2)
    if se == 0.0:
        return math.nan
    df, d = _welch_df(s1, n1, s2, n2), m2 - m1
    p_low = float(sps.t.sf((d + margin) / se, df))  # H0: d <= -margin
    p_high = float(sps.t.cdf((d - margin) / se, df))  # H0: d >= +margin
    return max(p_low, p_high)


# ------------------------------------------------------------------------------------------------- number verdicts
class NumberVerdict(NamedTuple):
    """One paper number judged: ``verdict`` (`NUMBER_VERDICTS`), ``rule`` (short name of the rule used),
    ``interval`` (ours, shown beside the verdict: Wilson, t interval of the mean, or prediction interval),
    ``p`` (the Welch p of the difference where a test ran, else nan; the TOST p is in ``detail``), ``detail``."""

    verdict: str
    rule: str
    interval: tuple[float, float]
    p: float
    detail: str


def _g(x: float) -> str:
    return f"{x:.4g}"


def _pct(level: float) -> str:
    return f"{100 * level:g} %"


def _side(diff: float, higher_better: bool) -> str:
    """"ours better" / "ours worse" from ours − paper (nonzero)."""
    return "ours better" if (diff > 0) == higher_better else "ours worse"


def _check_alpha(alpha: float) -> None:
    if not 0.0 < alpha < 0.5:
        raise ValueError(f"alpha must be in (0, 0.5), got {alpha!r}")


def _judge_rate(paper: float, counts: tuple[int, int], higher_better: bool, margin: Margin,
                alpha: float) -> NumberVerdict:
    k, n = counts
    if isinstance(k, bool) or isinstance(n, bool) or int(k) != k or int(n) != n or n < 0 or not 0 <= k <= n:
        raise ValueError(f"rate_counts: need integers 0 <= k <= N, got {counts!r}")
    if not 0.0 <= paper <= 1.0:
        raise ValueError(f"paper_mean: a rate must be a fraction in [0, 1], got {paper!r}")
    rule = f"Wilson {_pct(1 - alpha)} (rate; margin {margin.describe('')})"
    if n == 0:
        return NumberVerdict("inconclusive", rule, _NAN2, math.nan, "no trials")
    ci = wilson_interval(k, n, 1 - alpha)
    lo90, hi90 = wilson_interval(k, n, 1 - 2 * alpha)
    delta = margin.of(paper)
    detail = (f"ours {k}/{n} = {_g(k / n)}, Wilson {_pct(1 - 2 * alpha)} [{_g(lo90)}, {_g(hi90)}] vs paper "
              f"{_g(paper)} ± Δ {_g(delta)}")
    if paper - delta <= lo90 and hi90 <= paper + delta:
        return NumberVerdict("consistent", rule, ci, math.nan, detail)
    if not ci[0] <= paper <= ci[1]:
        return NumberVerdict(_side(k / n - paper, higher_better), rule, ci, math.nan, detail)
    return NumberVerdict("inconclusive", rule, ci, math.nan, detail)


def _judge_welch(v: np.ndarray, paper: float, sd: float, n: int, higher_better: bool, margin: Margin,
                 alpha: float, rule: str) -> NumberVerdict:
    m, s = _mean_sd(v)
    ci, delta, diff = mean_interval(v, 1 - alpha), margin.of(paper), m - paper
    head = f"ours {_g(m)} ± {_g(s)} (n = {v.size}) vs paper {_g(paper)} ± {_g(sd)} (n = {n}); Δ = {_g(delta)}"
    if sd == 0.0 and s == 0.0:
        # No spread on either side: nothing to test; the difference itself is set against the margin.
        detail = f"{head}; no spread on either side: |difference| {_g(abs(diff))} against Δ"
        if diff == 0.0 or abs(diff) < delta:
            return NumberVerdict("consistent", rule, ci, math.nan, detail)
        return NumberVerdict(_side(diff, higher_better), rule, ci, math.nan, detail)
    t, df, p = welch_from_stats(paper, sd, n, m, s, v.size)
    p_tost = tost_from_stats(paper, sd, n, m, s, v.size, delta)
    detail = f"{head}; Welch t = {_g(t)}, df = {_g(df)}, p = {_g(p)}; TOST p = {_g(p_tost)}"
    if p_tost < alpha:
        return NumberVerdict("consistent", rule, ci, p, detail)
    if p < alpha:
        return NumberVerdict(_side(diff, higher_better), rule, ci, p, detail)
    return NumberVerdict("inconclusive", rule, ci, p, detail)


def _judge_prediction(v: np.ndarray, paper: float, runs: int, higher_better: bool, alpha: float,
                      rule: str) -> NumberVerdict:
    lo, hi = _prediction_interval(v, 1 - alpha, runs)
    m = _mean_sd(v)[0]
    detail = f"ours {_g(m)} (n = {v.size} runs), interval [{_g(lo)}, {_g(hi)}] vs paper {_g(paper)}"
    if lo == hi:
        detail += "; no spread"
    if lo <= paper <= hi:
        return NumberVerdict("consistent", rule, (lo, hi), math.nan, detail)
    return NumberVerdict(_side(m - paper, higher_better), rule, (lo, hi), math.nan, detail)


def judge_number(ours: np.ndarray, paper_mean: float, paper_sd: float | None, paper_n: int | None, *,
                 higher_better: bool, margin: Margin, alpha: float = 0.05,
                 rate_counts: tuple[int, int] | None = None) -> NumberVerdict:
    """Judge one paper number against ours, choosing the rule from what the paper reports.

    Args:
        ours: our independent per-unit values, 1-D. For the Welch rule (paper sd and n ≥ 2) the per-unit means
            (per seed, or per seed × map draw); for the prediction-interval rules (one run of the paper, or a
            missing sd or n) per-run values, since those rules predict single runs. Non-finite values dropped.
        paper_mean: the paper's value (for a rate, a fraction in [0, 1]).
        paper_sd: the paper's sd (ddof=1 assumed), or None.
        paper_n: the number of runs behind the paper's value, or None.
        higher_better: the metric's direction, for "ours better" / "ours worse".
        margin: the equivalence margin Δ (relative margins are taken of ``paper_mean``).
        alpha: test level: (1 − α) intervals for differences, (1 − 2α) intervals / TOST for equivalence.
        rate_counts: (k, N), our successes of N trials, when the number is a proportion; ``ours`` is then unused.

    Rules, first match wins: rate_counts -> Wilson; sd and n ≥ 2 -> Welch + TOST; n == 1 or neither given ->
    prediction interval of one run; sd without n -> the same, labelled "n not reported"; n ≥ 2 without sd ->
    prediction interval of a mean of n runs. Fewer than 2 finite values of ours (non-rate rules) ->
    "inconclusive". Raises ValueError naming the argument for a non-finite paper_mean, a negative or NaN
    paper_sd, paper_n < 1, a negative margin, alpha outside (0, 0.5) or bad rate_counts.
    """
    if not math.isfinite(paper_mean):
        raise ValueError(f"paper_mean must be finite, got {paper_mean!r}")
    if paper_sd is not None and not (math.isfinite(paper_sd) and paper_sd >= 0):
        raise ValueError(f"paper_sd must be finite and >= 0, got {paper_sd!r}")
    if paper_n is not None and (isinstance(paper_n, bool) or int(paper_n) != paper_n or paper_n < 1):
        raise ValueError(f"paper_n must be an integer >= 1, got {paper_n!r}")
    if not isinstance(margin, Margin) or margin.value < 0:
        raise ValueError(f"margin must be a non-negative Margin, got {margin!r}")
    _check_alpha(alpha)
    if rate_counts is not None:
        return _judge_rate(paper_mean, rate_counts, higher_better, margin, alpha)

    level = _pct(1 - alpha)
    if paper_sd is not None and paper_n is not None and paper_n >= 2:
        kind, rule = "welch", f"Welch + TOST (paper sd, n = {int(paper_n)}; margin {margin.describe('')})"
    elif paper_n is None and paper_sd is not None:
        kind, rule = "one", f"n not reported: {level} prediction interval of one run"
    elif paper_n is not None and paper_n >= 2:
        kind, rule = "mean", f"sd not reported: {level} prediction interval of a mean of {int(paper_n)} runs"
    else:
        kind, rule = "one", f"{level} prediction interval of one run"

    v = _finite(ours)
    if v.size < 2:
        return NumberVerdict("inconclusive", rule, _NAN2, math.nan, "fewer than 2 values")
    if kind == "welch":
        return _judge_welch(v, paper_mean, float(paper_sd), int(paper_n), higher_better, margin, alpha, rule)
    runs = int(paper_n) if kind == "mean" else 1
    return _judge_prediction(v, paper_mean, runs, higher_better, alpha, rule)


# -------------------------------------------------------------------------------------------------- claim verdicts
class ContrastVerdict(NamedTuple):
    """One claim judged: ``effect`` (proposed − baseline, or the fitted change over the range), its ``interval``
    (95 % t), ``relative`` (effect / |baseline|, nan without one), ``verdict`` (`CLAIM_VERDICTS`), ``rule``,
    ``p`` (two-sided test of no effect), ``n`` (units: pairs, both samples' sizes summed, or points)."""

    effect: float
    interval: tuple[float, float]
    relative: float
    verdict: str
    rule: str
    p: float
    n: int


def _check_claim(direction: str, margin: float, alpha: float) -> None:
    if direction not in DIRECTIONS:
        raise ValueError(f"direction must be one of {DIRECTIONS}, got {direction!r}")
    if not (math.isfinite(margin) and margin >= 0):
        raise ValueError(f"margin must be finite and >= 0, got {margin!r}")
    _check_alpha(alpha)


def _claim_verdict(effect: float, ci: tuple[float, float], ci_eq: tuple[float, float], direction: str,
                   margin: float) -> str:
    """Reproduced / opposite from the (1 − α) interval ``ci`` against 0; not reproduced from the (1 − 2α)
    interval ``ci_eq`` inside ±margin. A zero-width interval (no spread) is judged from the effect and margin."""
    sign = 1.0 if direction == "higher" else -1.0
    lo, hi = ci
    if lo == hi:
        if effect == 0.0 or abs(effect) < margin:
            return "not reproduced"
        return "reproduced" if sign * effect > 0 else "opposite"
    if (sign > 0 and lo > 0) or (sign < 0 and hi < 0):
        return "reproduced"
    if (sign > 0 and hi < 0) or (sign < 0 and lo > 0):
        return "opposite"
    if -margin <= ci_eq[0] and ci_eq[1] <= margin:
        return "not reproduced"
    return "inconclusive"


def _relative(effect: float, base: float) -> float:
    return effect / abs(base) if math.isfinite(base) and base != 0.0 else math.nan


def _interval_from_se(effect: float, se: float, df: float, confidence: float) -> tuple[float, float]:
    if se == 0.0:
        return effect, effect
    half = t_quantile(confidence, df) * se
    return effect - half, effect + half


def _finish(effect: float, se: float, df: float, p: float, base: float, n: int, direction: str, margin: float,
            alpha: float, rule: str) -> ContrastVerdict:
    ci = _interval_from_se(effect, se, df, 1 - alpha)
    ci_eq = _interval_from_se(effect, se, df, 1 - 2 * alpha)
    verdict = _claim_verdict(effect, ci, ci_eq, direction, margin)
    rule = f"{rule}; margin ±{_g(margin)}"
    if se == 0.0:
        rule += "; no spread: effect against margin"
        p = math.nan
    return ContrastVerdict(effect, ci, _relative(effect, base), verdict, rule, p, n)


def _inconclusive(rule: str, n: int, effect: float = math.nan, base: float = math.nan) -> ContrastVerdict:
    return ContrastVerdict(effect, _NAN2, _relative(effect, base), "inconclusive", rule, math.nan, n)


def judge_contrast(a: np.ndarray, b: np.ndarray | None, *, paired: bool, direction: str, margin: float,
                   alpha: float = 0.05) -> ContrastVerdict:
    """Judge a claim "proposed − baseline has sign ``direction``" from per-unit values.

    Args:
        a: the proposed method's per-unit values (or, with ``b`` None, the per-unit differences proposed −
            baseline), 1-D.
        b: the baseline's per-unit values, or None.
        paired: unit i of ``a`` and of ``b`` is the same unit (seed, map draw, scenario pair): the effect is the
            mean of the differences with a one-sample t interval (n − 1 df); a pair with a non-finite value in
            either is dropped. Unpaired: mean(a) − mean(b), Welch interval with Welch–Satterthwaite df.
        direction: "higher" or "lower", the claimed sign of proposed − baseline.
        margin: absolute equivalence margin (metric units, ≥ 0) for "not reproduced".
        alpha: (1 − α) interval for reproduced / opposite, (1 − 2α) for not reproduced.

    Returns:
        `ContrastVerdict`; fewer than 2 units (per sample, when unpaired) -> "inconclusive". Zero spread -> the
        effect is judged against the margin (|effect| < margin or 0 -> not reproduced, else by its sign).
    """
    _check_claim(direction, margin, alpha)
    a = np.asarray(a, np.float64).ravel()
    if b is None or paired:
        if b is None:
            d, base, rule = a[np.isfinite(a)], math.nan, "paired t (differences given)"
        else:
            b = np.asarray(b, np.float64).ravel()
            if a.shape != b.shape:
                raise ValueError(f"paired: a and b must have the same length, got {a.size} and {b.size}")
            keep = np.isfinite(a) & np.isfinite(b)
            d, rule = a[keep] - b[keep], "paired t"
            base = float(np.mean(b[keep])) if keep.any() else math.nan
        if d.size < 2:
            return _inconclusive(f"{rule}; fewer than 2 units", int(d.size))
        effect, sd = _mean_sd(d)
        p = float(sps.ttest_1samp(d, 0.0).pvalue) if sd > 0 else math.nan
        return _finish(effect, sd / math.sqrt(d.size), d.size - 1, p, base, int(d.size), direction, margin,
                       alpha, f"{rule}, n = {d.size}")
    b = np.asarray(b, np.float64).ravel()
    a, b = a[np.isfinite(a)], b[np.isfinite(b)]
    rule = "Welch t"
    if a.size < 2 or b.size < 2:
        return _inconclusive(f"{rule}; fewer than 2 units", int(a.size + b.size))
    (ma, sa), (mb, sb) = _mean_sd(a), _mean_sd(b)
    se = math.sqrt(sa * sa / a.size + sb * sb / b.size)
    if se == 0.0:
        p, df = math.nan, math.nan
    else:
        _, df, p = welch_from_stats(ma, sa, a.size, mb, sb, b.size)
    return _finish(ma - mb, se, df, p, mb, int(a.size + b.size), direction, margin, alpha,
                   f"{rule}, n = {a.size} vs {b.size}")


def judge_trend(x: np.ndarray, y: np.ndarray, *, direction: str, margin: float,
                alpha: float = 0.05) -> ContrastVerdict:
    """Judge a claim "y rises (``direction`` "higher") / falls ("lower") with x" by an OLS line
    (`scipy.stats.linregress`) through the per-unit points (x_i, y_i).

    The effect is the fitted change over the tested range, slope × (max x − min x), in y's unit, so ``margin``
    is in y's unit as for a contrast; its interval is the slope's t interval (standard error, n − 2 df) scaled
    the same way; p is the two-sided test of slope 0; ``relative`` is the effect over |fitted y at min x|.
    Points with a non-finite x or y are dropped; fewer than 3 points or a single x level -> "inconclusive".
    Verdicts as in `judge_contrast`; an exact line (no residual spread) is judged against the margin.
    """
    _check_claim(direction, margin, alpha)
    x = np.asarray(x, np.float64).ravel()
    y = np.asarray(y, np.float64).ravel()
    if x.shape != y.shape:
        raise ValueError(f"x and y must have the same length, got {x.size} and {y.size}")
    keep = np.isfinite(x) & np.isfinite(y)
    x, y = x[keep], y[keep]
    rule = f"OLS trend over x in [{_g(float(x.min()))}, {_g(float(x.max()))}]" if x.size else "OLS trend"
    if x.size < 3:
        return _inconclusive(f"{rule}; fewer than 3 points", int(x.size))
    span = float(x.max() - x.min())
    if span == 0.0:
        return _inconclusive(f"{rule}; one x level", int(x.size))
    fit = sps.linregress(x, y)
    effect, se = float(fit.slope) * span, float(fit.stderr) * span
    if se <= 1e-12 * max(abs(effect), float(np.ptp(y))):
        se = 0.0  # points on a line up to rounding: no residual spread
    start = float(fit.intercept + fit.slope * x.min())
    return _finish(effect, se, x.size - 2, float(fit.pvalue), start, int(x.size), direction, margin, alpha,
                   f"{rule}, n = {x.size}")


def count(verdicts: Iterable[str], vocabulary: Sequence[str]) -> dict[str, int]:
    """How many of each verdict: every word of ``vocabulary`` (in its order, zeros included). Raises ValueError
    on a verdict outside the vocabulary (a typo would otherwise vanish from the counts)."""
    out = dict.fromkeys(vocabulary, 0)
    for v in verdicts:
        if v not in out:
            raise ValueError(f"verdict {v!r} is not one of {tuple(vocabulary)}")
        out[v] += 1
    return out
