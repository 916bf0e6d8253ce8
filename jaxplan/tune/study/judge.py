"""The study's statistics: each method's scores over tuner seeds, 95 % t-intervals, the best method, the verdict.

Per method (over its tuner seeds): the training score the tuner found, the held-out score of those weights, wall
and compile seconds, each as mean, sd and the 95 % t-interval of the mean
(`jaxplan.experiments.verdicts.t_quantile`). The best method is the one with the lowest held-out mean; its best
tuner seed is chosen by the TRAINING score (the held-out split only judges). The verdict compares the best method's
held-out interval with the defaults' held-out cost minus its own 95 % half-width (over the held-out seeds):

* ``"beats"``: the upper end of the best method's interval lies below that;
* ``"worse"``: the best method's held-out mean is above the defaults' cost (over-fitted to the training split);
* ``"within"``: neither: at this budget the defaults are at the optimum within noise.
"""

from __future__ import annotations

import math
import os
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from jaxplan.tune._objective import Evaluation, Objective
from jaxplan.tune.study.config import StudyConfig

__all__ = ["VERDICTS", "interval_stats", "summary"]

VERDICTS = ("beats", "within", "worse")
"""The verdicts of a study (module docstring)."""


def _t95(n: int) -> float:
    """The 95 % two-sided t quantile for a mean of ``n`` values (NaN below 2)."""
    from jaxplan.experiments.verdicts import t_quantile

    return t_quantile(0.95, n - 1) if n > 1 else math.nan


def interval_stats(values: Sequence[float]) -> dict[str, Any]:
    """``{"mean", "sd", "ci95": [lo, hi], "n"}`` of ``values`` (sd and interval NaN for fewer than 2 values)."""
    v = np.asarray(values, np.float64)
    n = len(v)
    sd = float(v.std(ddof=1)) if n > 1 else math.nan
    hw = _t95(n) * sd / math.sqrt(n) if n > 1 else math.nan
    return {"mean": float(v.mean()), "sd": sd, "ci95": [float(v.mean() - hw), float(v.mean() + hw)], "n": n}


def summary(cfg: StudyConfig, objective: Objective, runs: Mapping[tuple[str, int], Mapping[str, Any]],
            d_train: Evaluation, d_test: Mapping[str, Any],
            heldout_metrics: Callable[[np.ndarray], Mapping[str, float]], wall: float, heldout_s: float,
            load0: Sequence[float]) -> dict[str, Any]:
    """The study's ``summary.json`` (without its sessions): settings, per-method statistics, defaults, verdict.

    Args:
      cfg: the study.
      objective: its objective (the search box, splits and metric weights).
      runs: ``(method, tuner seed) -> run`` (``rows``, ``evaluations``, ``wall_s``, ``compile_s``, ``best_x``,
        ``best_f``, ``heldout``; ``same_as_seed`` for a run that stands for another seed's).
      d_train: the defaults' evaluation on the training split.
      d_test: the defaults' held-out score (``fitness``, ``per_seed``, ``metrics``).
      heldout_metrics: the held-out metrics of a weight vector ``f32[D]`` (of the best run's).
      wall: this session's wall seconds so far.
      heldout_s: this session's seconds of held-out evaluation.
      load0: the load averages at the session's start.
    """
    methods = {}
    for m in cfg.methods:
        rs = [runs[(m, s)] for s in cfg.tuner_seeds]
        methods[m] = {
            "train": interval_stats([r["best_f"] for r in rs]),
            "heldout": interval_stats([r["heldout"][-1] for r in rs]),
            "wall_s": interval_stats([r["wall_s"][-1] for r in rs]),
            "compile_s": interval_stats([r["compile_s"] for r in rs]),
            "run_s": interval_stats([r["wall_s"][-1] - r["compile_s"] for r in rs]),
            "evaluations": rs[0]["evaluations"][-1],
            "per_seed": {str(s): {"train": runs[(m, s)]["best_f"], "heldout": runs[(m, s)]["heldout"][-1],
                                  "weights": objective.params(runs[(m, s)]["best_x"])} for s in cfg.tuner_seeds},
        }
    ps = np.asarray(d_test["per_seed"], np.float64)
    R = len(ps)
    d_hw = _t95(R) * ps.std(ddof=1) / math.sqrt(R) if R > 1 else math.nan
    best_m, best_s = best_run(cfg, runs, methods)
    best = runs[(best_m, best_s)]
    bm = methods[best_m]["heldout"]
    hi = bm["ci95"][1] if math.isfinite(bm["ci95"][1]) else bm["mean"]
    lo_d = d_test["fitness"] - (d_hw if math.isfinite(d_hw) else 0.0)
    verdict = "beats" if hi < lo_d else ("worse" if bm["mean"] > d_test["fitness"] else "within")
    kinds = len(getattr(objective, "walkers", ())) or 1  # a navigation objective runs every row among each kind
    return {
        "name": cfg.name, "description": cfg.description, "quick": cfg.is_quick, "kind": cfg.tunes[0].kind,
        "planner": cfg.tunes[0].planner, "gap": cfg.gap, "methods_order": list(cfg.methods),
        "tuner_seeds": list(cfg.tuner_seeds), "budget": cfg.budget, "population": cfg.population,
        "generations": cfg.generations,
        "space": {n: [float(lo), float(hi_)] for n, lo, hi_ in zip(objective.bounds.names, objective.bounds.low,
                                                                   objective.bounds.high, strict=True)},
        "metric_weights": dict(objective.weights),
        "maps": [{"name": t.map.name, "train_rows": int(min(t.train_count, 10**9)),
                  "train_seeds": list(t.train_seeds), "heldout_seeds": list(t.test_seeds)} for t in cfg.tunes],
        "train_runs": int(len(objective.splits["train"].starts) * len(objective.splits["train"].seeds) * kinds),
        "heldout_runs": int(len(objective.splits["test"].starts) * len(objective.splits["test"].seeds) * kinds),
        "train_rows": int(len(objective.splits["train"].starts)),
        "heldout_rows": int(len(objective.splits["test"].starts)),
        "defaults": {"weights": objective.params(objective.defaults), "train": float(d_train.fitness[0]),
                     "heldout": d_test["fitness"], "heldout_per_seed": d_test["per_seed"],
                     "heldout_ci95_halfwidth": d_hw, "heldout_metrics": d_test["metrics"]},
        "methods": methods,
        "best": {"method": best_m, "tuner_seed": best_s, "heldout": best["heldout"][-1], "train": best["best_f"],
                 "heldout_metrics": dict(heldout_metrics(best["best_x"])), "weights": objective.params(best["best_x"])},
        "verdict": verdict,
        "compile_s_total": float(sum(r["compile_s"] for r in runs.values() if "same_as_seed" not in r)),
        "wall_s_this_session": wall, "heldout_eval_s_this_session": heldout_s,
        "loadavg_start": list(load0), "loadavg_end": list(os.getloadavg()),
    }


def best_run(cfg: StudyConfig, runs: Mapping[tuple[str, int], Mapping[str, Any]],
             methods: Mapping[str, Mapping[str, Any]]) -> tuple[str, int]:
    """(method, tuner seed) of the best weights: the method with the lowest held-out mean (``methods``: its
    statistics), then its tuner seed with the lowest TRAINING score."""
    best_m = min(cfg.methods, key=lambda m: methods[m]["heldout"]["mean"])
    best_s = min(cfg.tuner_seeds, key=lambda s: runs[(best_m, s)]["best_f"])
    return best_m, best_s
