"""The verdict rules (`jaxplan.experiments.verdicts`) against hand-computed cases: margins, Wilson, prediction and
mean intervals, Welch and TOST from the paper's (mean, sd, n), the number rule's branches, the claim rule's verdicts
(paired, unpaired, trend), the counts and the input errors. Quantiles quoted from tables: t_{0.975,4} = 2.776445,
t_{0.95,4} = 2.131847, t_{0.975,8} = 2.306004, t_{0.975,3} = 3.182446, z_{0.975} = 1.959964, z_{0.95} = 1.644854."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats as sps

from jaxplan.experiments.verdicts import (
    CLAIM_VERDICTS,
    NUMBER_VERDICTS,
    Margin,
    count,
    judge_contrast,
    judge_number,
    judge_trend,
    mean_interval,
    parse_margin,
    prediction_interval,
    t_quantile,
    tost_from_stats,
    welch_from_stats,
    wilson_interval,
)

T975_4, T95_4, T975_8, T975_3 = 2.776445, 2.131847, 2.306004, 3.182446
ONE_TO_FIVE = np.array([1.0, 2.0, 3.0, 4.0, 5.0])  # mean 3, sd sqrt(10/4) = 1.581139, n 5


def with_stats(mean: float, sd: float, n: int, seed: int = 0) -> np.ndarray:
    """n values with exactly this sample mean and sd (ddof=1)."""
    z = np.random.default_rng(seed).normal(size=n)
    return mean + sd * (z - z.mean()) / z.std(ddof=1)


# ---------------------------------------------------------------------------------------------------- margins
def test_margin_of_and_describe():
    assert Margin(0.05, True).of(-200.0) == pytest.approx(10.0)  # 5 % of |−200|
    assert Margin(0.05, False).of(-200.0) == 0.05
    assert Margin(0.05, True).describe("m") == "±5 %"
    assert Margin(0.07, True).describe("m") == "±7 %"
    assert Margin(0.05, False).describe("") == "±0.05"
    assert Margin(0.05, False).describe("cm", scale=100.0) == "±5 cm"


def test_parse_margin():
    assert parse_margin({"abs": 0.05}) == Margin(0.05, False)
    assert parse_margin({"rel": 0.1}) == Margin(0.1, True)
    assert parse_margin({"abs": 0}) == Margin(0.0, False)
    for bad, word in [({"abs": -1.0}, "negative"), ({"rel": math.nan}, "NaN"), ({"abs": 1, "rel": 0.1}, "exactly one"),
                      ({"pct": 5}, "unknown"), ({}, "exactly one"), ({"abs": "5"}, "number"), (0.05, "table"),
                      ({"rel": math.inf}, "infinite"), ({"abs": True}, "number")]:
        with pytest.raises(ValueError, match=word):
            parse_margin(bad)
    with pytest.raises(ValueError, match="margin"):
        Margin(-0.1, True)


# ----------------------------------------------------------------------------------------------------- Wilson
def test_wilson_hand_cases():
    # k = 0, n = 10: centre = half = (z²/2n)/(1 + z²/n), so lo = 0 and hi = (z²/n)/(1 + z²/n)
    # = 0.3841459 / 1.3841459 = 0.2775328.
    lo, hi = wilson_interval(0, 10)
    assert lo == 0.0 and hi == pytest.approx(0.2775328, abs=1e-6)
    # k = n = 10: mirror image, hi exactly 1.
    lo, hi = wilson_interval(10, 10)
    assert hi == 1.0 and lo == pytest.approx(1 - 0.2775328, abs=1e-6)
    # k = 45, n = 50, 95 %: p = 0.9, z² = 3.841459, z²/n = 0.0768292, denom = 1.0768292,
    # centre = (0.9 + 0.0384146) / 1.0768292 = 0.871461,
    # half = 1.959964 / 1.0768292 · sqrt(0.9·0.1/50 + 3.841459/2500/4) = 1.820122 · sqrt(0.00218415) = 0.085063.
    lo, hi = wilson_interval(45, 50)
    assert lo == pytest.approx(0.871461 - 0.085063, abs=2e-6) and hi == pytest.approx(0.871461 + 0.085063, abs=2e-6)
    # 90 %: z² = 2.705543, denom = 1.0541109, centre = 0.9270554 / 1.0541109 = 0.879467,
    # half = 1.644854 / 1.0541109 · sqrt(0.0018 + 2.705543/10000) = 1.560417 · 0.0455033 = 0.071004.
    lo, hi = wilson_interval(45, 50, 0.90)
    assert lo == pytest.approx(0.808463, abs=2e-6) and hi == pytest.approx(0.950471, abs=2e-6)


@pytest.mark.parametrize("k,n", [(0, 1), (1, 1), (0, 3), (3, 3), (1, 7), (45, 50), (17, 30), (99, 100), (0, 1000)])
def test_wilson_matches_scipy_and_stays_in_unit_interval(k, n):
    for c in (0.9, 0.95, 0.99):
        lo, hi = wilson_interval(k, n, c)
        assert 0.0 <= lo <= k / n <= hi <= 1.0
        ref = sps.binomtest(k, n).proportion_ci(c, method="wilson")
        assert lo == pytest.approx(max(0.0, ref.low), abs=1e-12) and hi == pytest.approx(min(1.0, ref.high), abs=1e-12)


def test_wilson_edges():
    assert all(math.isnan(x) for x in wilson_interval(0, 0))
    for k, n in [(-1, 5), (6, 5), (1.5, 5)]:
        with pytest.raises(ValueError):
            wilson_interval(k, n)


# ----------------------------------------------------------------------------------- prediction / mean intervals
def test_prediction_interval_hand():
    # 3 ± t_{0.975,4} · sqrt(2.5) · sqrt(1 + 1/5) = 3 ± 2.776445 · sqrt(3) = 3 ± 4.808944
    lo, hi = prediction_interval(ONE_TO_FIVE)
    assert lo == pytest.approx(3 - 4.808944, abs=1e-5) and hi == pytest.approx(3 + 4.808944, abs=1e-5)
    # nan dropped
    assert prediction_interval(np.append(ONE_TO_FIVE, np.nan)) == pytest.approx((lo, hi))
    assert all(math.isnan(x) for x in prediction_interval([1.0, np.nan]))
    assert prediction_interval([0.1, 0.1, 0.1]) == (0.1, 0.1)  # no spread: exactly the value


def test_mean_interval_hand():
    # 3 ± t_{0.975,4} · sqrt(2.5) / sqrt(5) = 3 ± 2.776445 · 0.7071068 = 3 ± 1.963243
    lo, hi = mean_interval(ONE_TO_FIVE)
    assert lo == pytest.approx(3 - 1.963243, abs=1e-5) and hi == pytest.approx(3 + 1.963243, abs=1e-5)
    assert all(math.isnan(x) for x in mean_interval([2.0]))
    assert mean_interval([2.0, 2.0]) == (2.0, 2.0)


def test_t_quantile_table_values_and_undefined_df():
    assert t_quantile(0.95, 4) == pytest.approx(T975_4, abs=1e-6)
    assert t_quantile(0.90, 4) == pytest.approx(T95_4, abs=1e-6)
    assert t_quantile(0.95, 3) == pytest.approx(T975_3, abs=1e-6)
    assert math.isnan(t_quantile(0.95, 0)) and math.isnan(t_quantile(0.95, math.nan))
    # mean_interval is mean ± t_quantile · sd / sqrt(n)
    lo, hi = mean_interval(ONE_TO_FIVE)
    assert (hi - lo) / 2 == pytest.approx(t_quantile(0.95, 4) * math.sqrt(2.5 / 5), rel=1e-12)


# ---------------------------------------------------------------------------------------------- Welch and TOST
def test_welch_from_stats_hand():
    # paper (10, 2, 30), ours (11, 1, 10): v1 = 4/30, v2 = 1/10, se = sqrt(v1 + v2),
    # t = (10 − 11)/se = −2.070197, df = (v1 + v2)² / (v1²/29 + v2²/9) = 0.0544444 / 0.00172414 = 31.5778.
    v1, v2 = 4 / 30, 1 / 10
    t_hand = -1 / math.sqrt(v1 + v2)
    df_hand = (v1 + v2) ** 2 / (v1**2 / 29 + v2**2 / 9)
    assert t_hand == pytest.approx(-2.070197, abs=1e-6) and df_hand == pytest.approx(31.5778, abs=1e-4)
    t, df, p = welch_from_stats(10, 2, 30, 11, 1, 10)
    assert t == pytest.approx(t_hand, abs=1e-6) and df == pytest.approx(df_hand, abs=1e-6)
    assert p == pytest.approx(2 * sps.t.sf(abs(t_hand), df_hand), abs=1e-6)
    # the same test on raw samples with these statistics
    raw = sps.ttest_ind(with_stats(10, 2, 30), with_stats(11, 1, 10), equal_var=False)
    assert p == pytest.approx(raw.pvalue, rel=1e-9)


def test_welch_no_spread():
    t, df, p = welch_from_stats(1.0, 0.0, 5, 2.0, 0.0, 5)
    assert t == -math.inf and math.isnan(df) and math.isnan(p)
    t, df, p = welch_from_stats(1.0, 0.0, 5, 1.0, 0.0, 5)
    assert math.isnan(t) and math.isnan(p)
    # one side without spread: df = n − 1 of the other side
    assert welch_from_stats(1.0, 0.0, 5, 2.0, 1.0, 8)[1] == pytest.approx(7.0)


def test_tost_hand():
    # (10, 1, 30) vs (10.1, 1, 30): se = sqrt(2/30) = 0.258199, df = 2 · 29 = 58 (equal sd and n).
    se, df = math.sqrt(2 / 30), 58
    # margin 1: t_low = 1.1/se = 4.2603, t_high = −0.9/se = −3.4857; p = max(sf(4.26), cdf(−3.49)) = cdf(−3.4857)
    p = tost_from_stats(10, 1, 30, 10.1, 1, 30, 1.0)
    assert p == pytest.approx(sps.t.cdf(-0.9 / se, df), abs=1e-9) and p < 0.001  # equivalent
    # margin 0.2: t_high = −0.1/se = −0.3873, p ≈ 0.35 — not shown equivalent
    p = tost_from_stats(10, 1, 30, 10.1, 1, 30, 0.2)
    assert p == pytest.approx(sps.t.cdf(-0.1 / se, df), abs=1e-9) and 0.3 < p < 0.4
    # difference below the paper: the other one-sided test decides
    p = tost_from_stats(10, 1, 30, 9.9, 1, 30, 0.2)
    assert p == pytest.approx(sps.t.sf(0.1 / se, df), abs=1e-9)
    assert math.isnan(tost_from_stats(1, 0, 5, 1, 0, 5, 0.1))


# --------------------------------------------------------------------------------------------------- judge_number
def test_number_rate_branch():
    # 45/50 against 0.9 ± 0.1: Wilson 90 % [0.808463, 0.950471] inside [0.8, 1.0] -> consistent
    v = judge_number(np.array([]), 0.9, None, None, higher_better=True, margin=Margin(0.1, False),
                     rate_counts=(45, 50))
    assert v.verdict == "consistent" and v.rule.startswith("Wilson 95 %")
    assert v.interval == pytest.approx((0.786398, 0.956524), abs=2e-6) and math.isnan(v.p)
    # ±5 % of 0.9 = ±0.045: [0.855, 0.945] does not hold the 90 % interval, 0.9 is inside the 95 % -> inconclusive
    v = judge_number(np.array([]), 0.9, None, None, higher_better=True, margin=Margin(0.05, True),
                     rate_counts=(45, 50))
    assert v.verdict == "inconclusive"
    # 30/50: 95 % Wilson ≈ [0.462, 0.724] lies below 0.9 -> ours worse (success: higher better)
    v = judge_number(np.array([]), 0.9, None, None, higher_better=True, margin=Margin(0.05, True),
                     rate_counts=(30, 50))
    assert v.verdict == "ours worse" and 0.0 <= v.interval[0] and v.interval[1] <= 1.0
    v = judge_number(np.array([]), 0.9, None, None, higher_better=False, margin=Margin(0.05, True),
                     rate_counts=(30, 50))
    assert v.verdict == "ours better"
    # 100 % success: the interval ends at exactly 1, never past it
    v = judge_number(np.array([]), 0.95, None, None, higher_better=True, margin=Margin(0.05, False),
                     rate_counts=(30, 30))
    assert v.interval[1] == 1.0
    with pytest.raises(ValueError, match="paper_mean"):  # a percentage passed as a rate
        judge_number(np.array([]), 90.0, None, None, higher_better=True, margin=Margin(0.05, False),
                     rate_counts=(45, 50))
    with pytest.raises(ValueError, match="rate_counts"):
        judge_number(np.array([]), 0.9, None, None, higher_better=True, margin=Margin(0.05, False),
                     rate_counts=(51, 50))


def test_number_welch_branch():
    m5 = Margin(0.05, True)
    # Paper 10 ± 1 (n = 30), ours 10.1 ± 1 (n = 30): Δ = 0.5; TOST p = cdf((0.1 − 0.5)/0.258199, 58) ≈ 0.06 -> not
    # shown equivalent; Welch p ≈ 0.70 -> no difference either -> inconclusive.
    ours = with_stats(10.1, 1.0, 30)
    v = judge_number(ours, 10.0, 1.0, 30, higher_better=False, margin=m5)
    assert v.verdict == "inconclusive" and v.rule == "Welch + TOST (paper sd, n = 30; margin ±5 %)"
    assert v.p == pytest.approx(2 * sps.t.sf(0.1 / math.sqrt(2 / 30), 58), abs=1e-9)
    assert v.interval == pytest.approx(mean_interval(ours))
    # Margin 10 % (Δ = 1): TOST p = cdf(−0.9/0.258199, 58) < 0.001 -> consistent.
    assert judge_number(ours, 10.0, 1.0, 30, higher_better=False, margin=Margin(0.1, True)).verdict == "consistent"
    # Significant AND equivalent: paper 10 ± 1 (n = 1000), ours 10.2 ± 1 (n = 1000), Δ = 0.5.
    # se = sqrt(2/1000) = 0.044721: Welch t = 4.47 (p ≈ 8e-6) but TOST t_high = −0.3/se = −6.7 -> consistent.
    big = with_stats(10.2, 1.0, 1000)
    v = judge_number(big, 10.0, 1.0, 1000, higher_better=False, margin=Margin(0.5, False))
    assert v.p < 1e-4 and v.verdict == "consistent"
    # Same difference, Δ = 0.1: not equivalent, different -> ours 10.2 > 10 with lower better: worse.
    assert judge_number(big, 10.0, 1.0, 1000, higher_better=False, margin=Margin(0.1, False)).verdict == "ours worse"
    assert judge_number(big, 10.0, 1.0, 1000, higher_better=True, margin=Margin(0.1, False)).verdict == "ours better"


def test_number_welch_no_spread():
    m = Margin(0.5, False)
    v = judge_number(np.array([9.0, 9.0, 9.0]), 9.2, 0.0, 30, higher_better=False, margin=m)
    assert v.verdict == "consistent" and "no spread" in v.detail and math.isnan(v.p)
    v = judge_number(np.array([9.0, 9.0, 9.0]), 10.0, 0.0, 30, higher_better=False, margin=m)
    assert v.verdict == "ours better" and "no spread" in v.detail
    v = judge_number(np.array([0.1, 0.1, 0.1]), 0.1, 0.0, 30, higher_better=False, margin=Margin(0.0, False))
    assert v.verdict == "consistent"  # equal values, even with a zero margin


def test_number_one_run_branch():
    # ours 1..5 per run: 95 % prediction interval 3 ± 4.808944 = [−1.808944, 7.808944]
    for sd, n in [(None, None), (None, 1), (0.5, 1)]:
        v = judge_number(ONE_TO_FIVE, 7.0, sd, n, higher_better=True, margin=Margin(0.05, True))
        assert v.verdict == "consistent" and v.rule == "95 % prediction interval of one run"
        assert v.interval == pytest.approx((3 - 4.808944, 3 + 4.808944), abs=1e-5) and math.isnan(v.p)
    # 8 lies above: ours (3) lower than the paper
    assert judge_number(ONE_TO_FIVE, 8.0, None, 1, higher_better=True, margin=Margin(0, True)).verdict == "ours worse"
    assert judge_number(ONE_TO_FIVE, 8.0, None, 1, higher_better=False, margin=Margin(0, True)).verdict == "ours better"
    assert judge_number(ONE_TO_FIVE, -2.0, None, 1, higher_better=True, margin=Margin(0, True)).verdict == "ours better"


def test_number_sd_without_n_and_n_without_sd():
    v = judge_number(ONE_TO_FIVE, 7.0, 0.3, None, higher_better=True, margin=Margin(0.05, True))
    assert v.rule == "n not reported: 95 % prediction interval of one run" and v.verdict == "consistent"
    assert v.interval == pytest.approx((3 - 4.808944, 3 + 4.808944), abs=1e-5)
    # n = 4 runs, no sd: 3 ± t_{0.975,4} · sqrt(2.5) · sqrt(1/4 + 1/5) = 3 ± 2.776445 · 1.0606602 = 3 ± 2.944865
    v = judge_number(ONE_TO_FIVE, 6.5, None, 4, higher_better=True, margin=Margin(0.05, True))
    assert v.rule == "sd not reported: 95 % prediction interval of a mean of 4 runs"
    assert v.interval == pytest.approx((3 - 2.944865, 3 + 2.944865), abs=1e-5) and v.verdict == "ours worse"


def test_number_too_few_values():
    for sd, n in [(1.0, 30), (None, None)]:
        v = judge_number(np.array([1.0, np.nan]), 1.0, sd, n, higher_better=True, margin=Margin(0.05, True))
        assert v.verdict == "inconclusive" and v.detail == "fewer than 2 values"
        assert all(math.isnan(x) for x in v.interval)


def test_number_input_errors():
    ok = dict(higher_better=True, margin=Margin(0.05, True))
    with pytest.raises(ValueError, match="paper_mean"):
        judge_number(ONE_TO_FIVE, math.nan, None, None, **ok)
    with pytest.raises(ValueError, match="paper_sd"):
        judge_number(ONE_TO_FIVE, 1.0, -1.0, 30, **ok)
    with pytest.raises(ValueError, match="paper_sd"):
        judge_number(ONE_TO_FIVE, 1.0, math.nan, 30, **ok)
    with pytest.raises(ValueError, match="paper_n"):
        judge_number(ONE_TO_FIVE, 1.0, 1.0, 0, **ok)
    with pytest.raises(ValueError, match="margin"):
        judge_number(ONE_TO_FIVE, 1.0, 1.0, 30, higher_better=True, margin=Margin(-0.1, False))
    with pytest.raises(ValueError, match="alpha"):
        judge_number(ONE_TO_FIVE, 1.0, 1.0, 30, alpha=0.6, **ok)


# ------------------------------------------------------------------------------------------------- judge_contrast
def test_contrast_paired_verdicts():
    base = np.array([10.0, 20.0, 30.0, 40.0, 50.0])
    # differences 1..5: effect 3, 95 % interval 3 ± 1.963243 (see test_mean_interval_hand), p of t = 3/0.707107
    v = judge_contrast(base + ONE_TO_FIVE, base, paired=True, direction="higher", margin=0.5)
    assert v.verdict == "reproduced" and v.effect == pytest.approx(3.0) and v.n == 5
    assert v.interval == pytest.approx((3 - 1.963243, 3 + 1.963243), abs=1e-5)
    assert v.relative == pytest.approx(3 / 30) and v.p == pytest.approx(2 * sps.t.sf(3 / math.sqrt(0.5), 4))
    assert judge_contrast(base + ONE_TO_FIVE, base, paired=True, direction="lower", margin=0.5).verdict == "opposite"
    # differences −0.2..0.2: effect 0; 90 % interval 0 ± t_{0.95,4} · 0.158114/sqrt(5) = ±0.150745
    d = np.array([-0.2, -0.1, 0.0, 0.1, 0.2])
    v = judge_contrast(base + d, base, paired=True, direction="lower", margin=0.2)
    assert v.verdict == "not reproduced"
    half95 = T975_4 * math.sqrt(0.1 / 4) / math.sqrt(5)
    assert v.interval == pytest.approx((-half95, half95), abs=1e-5)
    assert judge_contrast(base + d, base, paired=True, direction="lower", margin=0.15).verdict == "inconclusive"
    assert T95_4 * math.sqrt(0.1 / 4) / math.sqrt(5) == pytest.approx(0.150745, abs=1e-6)
    # differences given directly; a nan pair is dropped
    v = judge_contrast(d, None, paired=True, direction="lower", margin=0.2)
    assert v.verdict == "not reproduced" and math.isnan(v.relative)
    v = judge_contrast(np.append(base + ONE_TO_FIVE, np.nan), np.append(base, 1.0), paired=True, direction="higher",
                       margin=0.5)
    assert v.n == 5 and v.effect == pytest.approx(3.0)


def test_contrast_unpaired_welch():
    # a = 11..15, b = 1..5: effect 10; se = sqrt(2.5/5 + 2.5/5) = 1; df = 1 / (2 · 0.5²/4) = 8;
    # 95 % interval 10 ± t_{0.975,8} = [7.693996, 12.306004]
    v = judge_contrast(ONE_TO_FIVE + 10, ONE_TO_FIVE, paired=False, direction="higher", margin=1.0)
    assert v.verdict == "reproduced" and v.effect == pytest.approx(10.0) and v.n == 10
    assert v.interval == pytest.approx((10 - T975_8, 10 + T975_8), abs=1e-5)
    assert v.relative == pytest.approx(10 / 3)
    assert v.p == pytest.approx(sps.ttest_ind(ONE_TO_FIVE + 10, ONE_TO_FIVE, equal_var=False).pvalue)
    assert judge_contrast(ONE_TO_FIVE + 10, ONE_TO_FIVE, paired=False, direction="lower", margin=1.0).verdict \
        == "opposite"
    # Same means, wide spread: interval 0 ± 2.306004 spans both sides; margin 1 too narrow -> inconclusive
    assert judge_contrast(ONE_TO_FIVE, ONE_TO_FIVE, paired=False, direction="higher", margin=1.0).verdict \
        == "inconclusive"
    # ... 90 % interval 0 ± t_{0.95,8} = ±1.859548 inside ±2 -> not reproduced
    assert judge_contrast(ONE_TO_FIVE, ONE_TO_FIVE, paired=False, direction="higher", margin=2.0).verdict \
        == "not reproduced"


def test_contrast_no_spread_and_too_few():
    same = np.array([2.0, 2.0, 2.0])
    v = judge_contrast(same + 1, same, paired=True, direction="higher", margin=0.5)
    assert v.verdict == "reproduced" and "no spread" in v.rule and v.interval == (1.0, 1.0) and math.isnan(v.p)
    assert judge_contrast(same + 1, same, paired=True, direction="lower", margin=0.5).verdict == "opposite"
    assert judge_contrast(same + 1, same, paired=True, direction="higher", margin=2.0).verdict == "not reproduced"
    assert judge_contrast(same, same, paired=False, direction="higher", margin=0.0).verdict == "not reproduced"
    v = judge_contrast(np.array([1.0]), np.array([0.0]), paired=True, direction="higher", margin=0.1)
    assert v.verdict == "inconclusive" and v.n == 1
    v = judge_contrast(np.array([1.0, 2.0]), np.array([0.0]), paired=False, direction="higher", margin=0.1)
    assert v.verdict == "inconclusive"


def test_contrast_input_errors():
    with pytest.raises(ValueError, match="direction"):
        judge_contrast(ONE_TO_FIVE, None, paired=True, direction="up", margin=0.1)
    with pytest.raises(ValueError, match="margin"):
        judge_contrast(ONE_TO_FIVE, None, paired=True, direction="higher", margin=-0.1)
    with pytest.raises(ValueError, match="same length"):
        judge_contrast(ONE_TO_FIVE, ONE_TO_FIVE[:3], paired=True, direction="higher", margin=0.1)


# ---------------------------------------------------------------------------------------------------- judge_trend
def test_trend_exact_line():
    x = np.array([0.0, 1.0, 2.0, 3.0])
    y = 2 * x + 1  # fitted change over [0, 3] = 2 · 3 = 6, from y(0) = 1
    v = judge_trend(x, y, direction="higher", margin=1.0)
    assert v.verdict == "reproduced" and v.effect == pytest.approx(6.0) and v.relative == pytest.approx(6.0)
    assert v.interval == pytest.approx((6.0, 6.0)) and "no spread" in v.rule
    assert judge_trend(x, y, direction="lower", margin=1.0).verdict == "opposite"
    assert judge_trend(x, y, direction="higher", margin=10.0).verdict == "not reproduced"


def test_trend_hand():
    # x = 0..4, y = (0, 2, 1, 3, 4): Sxy = 9, Sxx = 10, slope 0.9, intercept 0.2; residuals (−0.2, 0.9, −1, 0.1,
    # 0.2), SSE 1.9, se(slope) = sqrt(1.9/3/10) = 0.251661; effect 0.9 · 4 = 3.6 ± t_{0.975,3} · 4 · 0.251661
    # = 3.6 ± 3.203592; relative 3.6 / 0.2 = 18.
    x, y = np.arange(5.0), np.array([0.0, 2.0, 1.0, 3.0, 4.0])
    v = judge_trend(x, y, direction="higher", margin=0.5)
    assert v.effect == pytest.approx(3.6) and v.relative == pytest.approx(18.0) and v.n == 5
    assert v.interval == pytest.approx((3.6 - 3.203592, 3.6 + 3.203592), abs=1e-5)
    assert T975_3 * 4 * math.sqrt(1.9 / 30) == pytest.approx(3.203592, abs=1e-5)
    assert v.verdict == "reproduced" and v.p == pytest.approx(sps.linregress(x, y).pvalue)
    assert judge_trend(x, y, direction="lower", margin=0.5).verdict == "opposite"
    # too few points / one x level
    assert judge_trend(x[:2], y[:2], direction="higher", margin=0.5).verdict == "inconclusive"
    assert judge_trend(np.ones(4), np.arange(4.0), direction="higher", margin=0.5).verdict == "inconclusive"


# --------------------------------------------------------------------------------------------------------- count
def test_count():
    assert count(["consistent", "ours worse", "consistent"], NUMBER_VERDICTS) == {
        "consistent": 2, "ours better": 0, "ours worse": 1, "inconclusive": 0}
    assert list(count([], CLAIM_VERDICTS)) == list(CLAIM_VERDICTS)
    with pytest.raises(ValueError, match="not one of"):
        count(["reproduced", "maybe"], CLAIM_VERDICTS)
