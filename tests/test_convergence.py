"""The convergence iteration as each paper defines it (issue 42, item 6), on hand-made histories.

* `converged_iteration`: first iteration (0-based) within 1 % of the final best (the general definition);
  ``rtol=CONVERGED_RTOL_STRICT`` (0.1 %) is the sensitivity row ``converged_iteration_strict``;
* `turning_point`: chu2024's stable point, counted from 1: where the curve reaches the value it keeps;
* `optimum_iteration`: yu2020's generation of the optimum, counted from 1: the final best's first appearance.

The expected values below are worked out by hand from the histories, not by the functions under test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from jaxplan.experiments.trial_metrics import CONVERGENCE_KEYS, INT_METRICS, convergence_metrics
from jaxplan.metrics import (
    CONVERGED_RTOL,
    CONVERGED_RTOL_STRICT,
    converged_iteration,
    optimum_iteration,
    turning_point,
)

INF = math.inf


def _all(h) -> tuple[int, int, int, int]:
    """(converged 1 %, converged 0.1 %, turning point, optimum iteration) of one history."""
    h = np.asarray(h, np.float32)
    return (int(converged_iteration(h)), int(converged_iteration(h, rtol=CONVERGED_RTOL_STRICT)),
            int(turning_point(h)), int(optimum_iteration(h)))


def test_the_tolerances_are_one_and_a_tenth_of_a_percent():
    assert CONVERGED_RTOL == 0.01 and CONVERGED_RTOL_STRICT == 0.001


@pytest.mark.parametrize("history, expected", [
    # final 10: within 1 % is <= 10.1 (first at index 3: 10.08), within 0.1 % is <= 10.01 (index 4: 10.005);
    # the final value 10 first appears at index 5, the 6th iteration.
    ([INF, INF, 12.0, 10.08, 10.005, 10.0, 10.0], (3, 4, 6, 6)),
    # inf prefix: no path before the third iteration; the first path is already the final best.
    ([INF, INF, 7.0, 7.0], (2, 2, 3, 3)),
    # flat: the first iteration's path is never improved.
    ([5.0, 5.0, 5.0], (0, 0, 1, 1)),
    # one last improvement of 0.5 % in the last iteration: converged (1 %) early, strict and optimum at the end.
    ([20.0, 10.05, 10.05, 10.05, 10.0], (1, 4, 5, 5)),
    # never found a path: -1 for every definition.
    ([INF, INF, INF], (-1, -1, -1, -1)),
    # a NaN final best counts as no path.
    ([3.0, 2.0, math.nan], (-1, -1, -1, -1)),
    # one iteration.
    ([4.0], (0, 0, 1, 1)),
])
def test_each_definition_on_a_best_so_far_history(history, expected):
    assert _all(history) == expected


def test_the_turning_point_and_the_optimum_differ_on_a_curve_that_rises_again():
    """An iteration-best curve: the final value 10 is first found in iteration 2, lost in iteration 3 and kept from
    iteration 4 on; yu2020 counts the first find (2), chu2024 the start of the stationary stretch (4)."""
    curve = np.asarray([12.0, 10.0, 11.0, 10.0, 10.0], np.float32)
    assert int(optimum_iteration(curve)) == 2
    assert int(turning_point(curve)) == 4
    assert int(converged_iteration(curve)) == 1  # 10.0 <= 10.1 at index 1


def test_empty_histories_and_batch_axes():
    for f in (converged_iteration, turning_point, optimum_iteration):
        assert int(f(np.zeros((0,), np.float32))) == -1
        assert np.asarray(f(np.zeros((2, 3, 0), np.float32))).tolist() == [[-1] * 3] * 2
    h = np.asarray([[[INF, 3.0, 2.0], [1.0, 1.0, 1.0]], [[INF] * 3, [9.0, 8.0, 8.0]]], np.float32)  # [2, 2, 3]
    np.testing.assert_array_equal(np.asarray(converged_iteration(h)), [[2, 0], [-1, 1]])
    np.testing.assert_array_equal(np.asarray(turning_point(h)), [[3, 1], [-1, 2]])
    np.testing.assert_array_equal(np.asarray(optimum_iteration(h)), [[3, 1], [-1, 2]])


def test_convergence_metrics_are_float_columns_with_nan_for_failed_runs():
    history = np.asarray([[[INF, 12.0, 10.08, 10.0], [6.0, 6.0, 6.0, 6.0]]], np.float32)  # [n=1, R=2, I=4]
    ok = np.asarray([[True, False]])  # the second run is marked failed: no value, whatever its history
    got = convergence_metrics(history, ok, ["success", "turning_point", "converged_iteration_strict",
                                            "converged_iteration", "optimum_iteration"])
    assert set(got) == set(CONVERGENCE_KEYS)
    assert all(v.dtype == np.float64 and v.shape == (1, 2) for v in got.values())
    assert got["converged_iteration"][0, 0] == 2.0 and got["converged_iteration_strict"][0, 0] == 3.0
    assert got["turning_point"][0, 0] == 4.0 and got["optimum_iteration"][0, 0] == 4.0
    assert all(np.isnan(v[0, 1]) for v in got.values())
    assert convergence_metrics(history, ok, ["success", "length"]) == {}
    assert set(CONVERGENCE_KEYS) <= set(INT_METRICS)  # written as integers in trials.csv


def test_the_metrics_are_configurable_and_opt_in():
    from jaxplan.experiments.config import METRICS

    for name in ("converged_iteration_strict", "turning_point", "optimum_iteration"):
        spec = METRICS[name]
        assert spec.kinds == {"plan", "tsp"} and not spec.default
    assert "1 %" in METRICS["converged_iteration"].description
    assert "chu2024" in METRICS["turning_point"].description and "yu2020" in METRICS["optimum_iteration"].description


def test_a_plan_run_writes_every_definition(tmp_path):
    """A small Ant System run: per trial, 0-based convergence within 1 % <= within 0.1 %, and yu2020's count (from
    1) of the final best's iteration is at least the strict index + 1; chu2024's turning point on the best-so-far
    history is the same iteration."""
    import csv

    from jaxplan.experiments import run_experiment

    cfg = tmp_path / "conv.toml"
    cfg.write_text("""
metrics = ["success", "length", "converged_iteration", "converged_iteration_strict", "turning_point",
           "optimum_iteration"]
[experiment]
name = "conv"
seeds = 3
chunk = 1
[[maps]]
name = "r"
generator = "random"
seed = 2
params = { width = 12, height = 12, obstacle_ratio = 0.2 }
[scenarios]
source = "random"
count = 1
seed = 0
min_distance = 6.0
[[planners]]
label = "AS"
kind = "plan"
name = "aco"
overrides = { ants = 6, iterations = 8, dead_end = "retreat" }
""")
    run = run_experiment(cfg, tmp_path / "runs", progress=False)
    with open(run / "trials.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 3
    for r in rows:
        assert r["success"] == "1"
        conv, strict = int(r["converged_iteration"]), int(r["converged_iteration_strict"])
        tp, opt = int(r["turning_point"]), int(r["optimum_iteration"])
        assert 0 <= conv <= strict < opt <= 8 and tp == opt


def test_executed_paths_are_resampled_every_cell_before_their_shape_is_measured():
    """cui2025 Table 1's smoothness and obstacle distance of executed paths (`executed_shape`): a trajectory of
    many small steps around one right angle, resampled every 0.5 m, has 3 interior vertices (0, 90, 0 deg):
    smoothness 1 - (pi/2 / 3) / pi = 5/6, whatever the step size; points past `steps` are ignored."""
    import jaxplan as jp
    from jaxplan.experiments.trial_metrics import executed_shape

    grid = jp.grid_from_array(np.ones((8, 8), bool), resolution=0.5)
    leg = np.linspace(0.0, 1.0, 41)[:, None]
    path = np.concatenate([np.hstack([1.25 + leg, np.full_like(leg, 1.25)]),
                           np.hstack([np.full_like(leg, 2.25), 1.25 + leg])[1:]])  # 81 points, 2 m
    junk = np.full((5, 2), 99.0)
    got = executed_shape(grid, np.concatenate([path, junk])[None], np.array([len(path) - 1]))
    assert got["smoothness"][0] == pytest.approx(5 / 6, abs=1e-6)
    # on an open map the clearance is the distance to the map's border (blocked outside), here >= 1.25 m
    assert 1.2 <= got["mean_clearance"][0] <= 2.0
    coarse = executed_shape(grid, path[::8][None], np.array([len(path[::8]) - 1]))
    assert coarse["smoothness"][0] == pytest.approx(got["smoothness"][0], abs=1e-6)
