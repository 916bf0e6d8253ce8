"""Trial metrics computed on the host from a chunk's batched results, in float64 and independent of the batch.

A chunk's compiled call (`jaxplan.experiments.execute`) returns paths and episode records; the
metrics here turn them into trials.csv values that depend on each trial's own cells only (not on
the batch's layout or padding, so a ``--chunk`` change leaves every number as it was): grid path
lengths as left-to-right float64 sums, optimality gaps, cui2025's accuracy, yu2020's
line-of-sight reductions, the Hausdorff distance to the exact path, the smoothed exact
optimum an executed path is measured against (DESIGN §6), and the gap to each planner's own optimum.
"""

from __future__ import annotations

import numpy as np

from jaxplan.experiments.config import ACCURACY_GAP, PlannerConfig, nav_config
from jaxplan.experiments.prepare import MapWork

__all__ = ["PATH_KEYS", "LOS_KEYS", "INT_METRICS", "accuracy", "reductions", "los_metrics", "grid_path_lengths",
           "optimality_gaps", "objective_gaps", "hausdorff", "executed_optimum"]

PATH_KEYS = ("length", "optimality_gap", "turns", "sharp_turns", "smoothness", "min_clearance", "mean_clearance",
              "max_curvature")
LOS_KEYS = ("los_length", "los_turns", "los_length_reduction", "los_turns_reduction")
INT_METRICS = ("turns", "sharp_turns", "los_turns", "converged_iteration", "collisions", "active_contacts",
               "passive_contacts", "recoveries", "replans")
_GAP_TOL = 1e-9  # a gap of exactly 10 % computes as 0.10000000000000009: count it as within


def accuracy(success: np.ndarray, gap: np.ndarray, threshold: float = ACCURACY_GAP) -> np.ndarray:
    """cui2025's accuracy per trial (DESIGN §6): 1 for a success with ``gap <= threshold``, else 0.

    Args:
      success: ``[...]`` 1/0 outcomes (nan: undefined).
      gap: ``[...]`` optimality gaps (length / optimum − 1; nan where unknown).
      threshold: the largest gap that counts as accurate (default `ACCURACY_GAP`, 10 %).

    Returns:
      ``f64[...]``: 1.0 or 0.0; nan where ``success`` is undefined, or a success has no defined gap (a failure
      is 0 whatever its gap). Its per-seed mean is the share of accurate trials.
    """
    s, g = np.asarray(success, np.float64), np.asarray(gap, np.float64)
    with np.errstate(invalid="ignore"):
        hit = np.where(np.isfinite(g), (g <= threshold + _GAP_TOL).astype(np.float64), np.nan)
    return np.where(np.isnan(s), np.nan, np.where(s == 1, hit, 0.0))


def reductions(before: np.ndarray, after: np.ndarray) -> np.ndarray:
    """``f64[...]`` reduction rates ``1 − after / before`` (yu2020 Table 4); nan where ``before`` is 0 or nan."""
    b, a = np.asarray(before, np.float64), np.asarray(after, np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(b > 0, 1.0 - a / np.where(b > 0, b, 1.0), np.nan)


def los_metrics(grid, paths: np.ndarray, n: np.ndarray, ok: np.ndarray, fill: np.ndarray) -> dict[str, np.ndarray]:
    """Length (m) and turns of each path after line-of-sight smoothing (yu2020 §3.3: an intermediate cell centre
    is dropped while the last kept one sees the next), nan where the plan failed.

    Args:
      grid: the map; paths: ``i32[B, P, 2]`` grid paths (cells) with ``n [B]`` valid points; ok: ``bool[B]`` plans
        that succeeded; fill: ``[B, 2]`` a free cell per path (its start), standing in for a failed path.

    Returns:
      ``{"los_length": f64[B], "los_turns": f64[B]}``.
    """
    from jaxplan.metrics import path_metrics
    from jaxplan.smooth import smooth

    B, P = paths.shape[:2]
    valid = ok[:, None] & (np.arange(P)[None, :] < n[:, None])
    # smooth() checks every valid point against the map: a failed plan (−1 padding) becomes its start alone.
    pts = np.where(valid[..., None], paths, np.asarray(fill)[:, None, :]).astype(np.float64)
    sm = smooth(pts, grid, "los", n=np.where(ok, np.maximum(n, 1), 1))
    pm = path_metrics(np.asarray(sm.points, np.float64), grid, n=np.asarray(sm.n))
    return {"los_length": np.where(ok, np.asarray(pm["length"], np.float64), np.nan),
            "los_turns": np.where(ok, np.asarray(pm["turns"], np.float64), np.nan)}


def grid_path_lengths(paths: np.ndarray, n: np.ndarray, resolution: float) -> np.ndarray:
    """``f64[B]`` metres of grid paths ``int[B, P, 2]`` (cells) with ``n [B]`` valid points: float64 sums taken
    left to right (a running sum), so that a length depends on its own cells only, not on the batch or the
    padding (NumPy's pairwise `sum` groups terms by the padded length)."""
    n = np.asarray(n)
    seg = np.hypot(*np.moveaxis(np.diff(np.asarray(paths, np.float64), axis=1), -1, 0))  # [B, P - 1]
    if seg.shape[1] == 0:
        return np.zeros(len(n))
    run = np.cumsum(seg, axis=1)
    last = np.clip(n - 2, 0, seg.shape[1] - 1)
    return np.where(n >= 2, np.take_along_axis(run, last[:, None], axis=1)[:, 0], 0.0) * resolution


def optimality_gaps(length: np.ndarray, optimal: np.ndarray) -> np.ndarray:
    """``length / optimal − 1`` in float64; 0 for 0/0 (start = goal), inf for x/0 (as `jaxplan.path_metrics`)."""
    length, optimal = np.broadcast_arrays(np.asarray(length, np.float64), np.asarray(optimal, np.float64))
    with np.errstate(divide="ignore", invalid="ignore"):
        gap = length / optimal - 1.0
    return np.where(optimal == 0, np.where(length == 0, 0.0, np.inf), gap)


def objective_gaps(grid, starts: np.ndarray, goals: np.ndarray, planner: str, overrides: dict, paths: np.ndarray,
                   n_cells: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """``f64[n, R]`` each trial's gap to its planner's own optimum: the float64 cost of its path under the planner's
    objective (`jaxplan.search.path_objectives`) / the exact minimum of it (`jaxplan.search.exact_objectives`) − 1.

    nan for failed trials, and for every trial of a planner whose cost `exact_objective` refuses (not a sum over
    moves and turns: sampling planners, `astar_kng`, `opt_ant`'s height term on a map with heights).

    Args:
      grid: the map; starts, goals: ``int[n, 2]`` the scenarios; planner, overrides: as run.
      paths: ``int[n, R, P, 2]`` grid paths with ``n_cells [n, R]`` valid points; ok: ``bool[n, R]`` successes.
    """
    from jaxplan.search import OBJECTIVE_PLANNERS, NonAdditiveCost, exact_objectives, path_objectives

    n, R, P = paths.shape[:3]
    out = np.full((n, R), np.nan)
    if planner not in OBJECTIVE_PLANNERS or not ok.any():
        return out
    try:
        opt = exact_objectives(grid, starts, goals, planner=planner, **overrides)
    except NonAdditiveCost:  # no sum over moves on this map (opt_ant's height term): no gap
        return out
    flat_ok = ok.reshape(-1)
    cost = np.full(n * R, np.nan)
    cost[flat_ok] = path_objectives(paths.reshape(-1, P, 2)[flat_ok], n_cells.reshape(-1)[flat_ok], grid, planner,
                                    **overrides)
    return np.where(ok, optimality_gaps(cost.reshape(n, R), opt[:, None]), np.nan)


def hausdorff(mw: MapWork, idx: np.ndarray, paths: np.ndarray, n_cells: np.ndarray) -> np.ndarray:
    """``f64[n, R]`` Hausdorff distance (m) of each trial's global path ``[n, R, P, 2]`` (cells, ``n_cells``
    valid points) to the scenario's exact A* path (deterministic; nan where a path is empty)."""
    from jaxplan.aco import plan_batch
    from jaxplan.metrics import path_metrics

    ref = plan_batch(mw.grid, mw.starts[idx], mw.goals[idx], planner="astar", seeds=[0])
    n, R, P = paths.shape[:3]
    rp = np.repeat(np.asarray(ref.paths[:, 0]), R, axis=0)
    rn = np.repeat(np.asarray(ref.n_cells[:, 0]), R, axis=0)
    nc = np.asarray(n_cells).reshape(-1)
    ok = (nc > 0) & (rn > 0)
    pm = path_metrics(np.asarray(paths, np.float64).reshape(n * R, P, 2), mw.grid, reference=rp.astype(np.float64),
                      n=np.maximum(nc, 1), reference_n=np.maximum(rn, 1))
    return np.where(ok, np.asarray(pm["hausdorff"], np.float64), np.nan).reshape(n, R)


def executed_optimum(mw: MapWork, pc: PlannerConfig, idx: np.ndarray) -> np.ndarray:
    """``f64[n]`` the reference length (m) an executed path is measured against, per scenario: the exact path on
    the planning map (the map closed within d_safe of obstacles, as the pipelines plan) after the line-of-sight
    smoothing the pipelines apply (clearance d_safe) — DESIGN §6's "the same smoothing applied to the exact path".
    nan where the robot does not fit (start or goal closed, or not connected)."""
    from jaxplan.aco import plan_batch
    from jaxplan.metrics import path_metrics
    from jaxplan.nav import planning_grid
    from jaxplan.search import shortest_lengths
    from jaxplan.smooth import smooth

    d_safe = float(nav_config(pc)[0].dwa.d_safe)
    pg = planning_grid(mw.grid, d_safe)
    s, g = mw.starts[idx], mw.goals[idx]
    free = np.asarray(pg.free)
    ok = free[s[:, 1], s[:, 0]] & free[g[:, 1], g[:, 0]]
    out = np.full(len(idx), np.nan)
    if ok.any():
        ok[ok] = np.isfinite(shortest_lengths(pg, s[ok], g[ok]))
    if ok.any():
        ref = plan_batch(pg, s[ok], g[ok], planner="astar", seeds=[0])
        sm = smooth(np.asarray(ref.paths[:, 0], np.float64), mw.grid, "los", n=np.asarray(ref.n_cells[:, 0]),
                    radius=d_safe)
        out[ok] = np.asarray(path_metrics(np.asarray(sm.points, np.float64), mw.grid, n=np.asarray(sm.n))["length"],
                             np.float64)
    return out
