"""Trial metrics computed on the host from a chunk's batched results, in float64 and independent of the batch.

A chunk's compiled call (`jaxplan.experiments.execute`) returns paths and episode records; the
metrics here turn them into trials.csv values that depend on each trial's own cells only (not on
the batch's layout or padding, so a ``--chunk`` change leaves every number as it was): grid path
lengths as left-to-right float64 sums, optimality gaps, cui2025's accuracy, yu2020's
line-of-sight reductions, the Hausdorff distance to the exact path, the smoothed exact
optimum an executed path is measured against (docs/guide/smoothing-and-metrics.md), the gap to each planner's own
optimum, and the
convergence iterations of an iterative planner's best-so-far history (`convergence_metrics`).
"""

from __future__ import annotations

import numpy as np

from jaxplan.experiments.config import ACCURACY_GAP, PlannerConfig, nav_config
from jaxplan.experiments.prepare import MapWork

__all__ = ["PATH_KEYS", "LOS_KEYS", "CONVERGENCE_KEYS", "INT_METRICS", "accuracy", "reductions", "los_metrics",
           "grid_path_lengths", "optimality_gaps", "objective_gaps", "hausdorff", "executed_optimum",
           "convergence_metrics", "executed_shape"]

PATH_KEYS = ("length", "optimality_gap", "turns", "sharp_turns", "smoothness", "min_clearance", "mean_clearance",
              "max_curvature")
LOS_KEYS = ("los_length", "los_turns", "los_length_reduction", "los_turns_reduction")
CONVERGENCE_KEYS = ("converged_iteration", "converged_iteration_strict", "turning_point", "optimum_iteration")
INT_METRICS = ("turns", "sharp_turns", "los_turns", *CONVERGENCE_KEYS, "collisions", "active_contacts",
               "passive_contacts", "recoveries", "replans")
_GAP_TOL = 1e-9  # a gap of exactly 10 % computes as 0.10000000000000009: count it as within


def accuracy(success: np.ndarray, gap: np.ndarray, threshold: float = ACCURACY_GAP) -> np.ndarray:
    """cui2025's accuracy per trial (docs/guide/smoothing-and-metrics.md): 1 for a success with ``gap <= threshold``,
    else 0.

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
    from jaxplan.smoothing import smooth

    B, P = paths.shape[:2]
    valid = ok[:, None] & (np.arange(P)[None, :] < n[:, None])
    # smooth() checks every valid point against the map: a failed plan (−1 padding) becomes its start alone.
    pts = np.where(valid[..., None], paths, np.asarray(fill)[:, None, :]).astype(np.float64)
    sm = smooth(pts, grid, "los", n=np.where(ok, np.maximum(n, 1), 1))
    pm = path_metrics(np.asarray(sm.points, np.float64), grid, n=np.asarray(sm.n))
    return {"los_length": np.where(ok, np.asarray(pm.length, np.float64), np.nan),
            "los_turns": np.where(ok, np.asarray(pm.turns, np.float64), np.nan)}


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
    from jaxplan.metrics import path_metrics
    from jaxplan.planning import plan_batch

    ref = plan_batch(mw.grid, mw.starts[idx], mw.goals[idx], planner="astar", seeds=[0])
    n, R, P = paths.shape[:3]
    rp = np.repeat(np.asarray(ref.paths[:, 0]), R, axis=0)
    rn = np.repeat(np.asarray(ref.n_cells[:, 0]), R, axis=0)
    nc = np.asarray(n_cells).reshape(-1)
    ok = (nc > 0) & (rn > 0)
    pm = path_metrics(np.asarray(paths, np.float64).reshape(n * R, P, 2), mw.grid, reference=rp.astype(np.float64),
                      n=np.maximum(nc, 1), reference_n=np.maximum(rn, 1))
    return np.where(ok, np.asarray(pm.hausdorff, np.float64), np.nan).reshape(n, R)


def executed_optimum(mw: MapWork, pc: PlannerConfig, idx: np.ndarray) -> np.ndarray:
    """``f64[n]`` the reference length (m) an executed path is measured against, per scenario: the exact path on
    the planning map (the map closed within d_safe of obstacles, as the pipelines plan) after the line-of-sight
    smoothing the pipelines apply (clearance d_safe) — the metrics guide's "the same smoothing applied to the exact
    path".
    nan where the robot does not fit (start or goal closed, or not connected)."""
    from jaxplan.metrics import path_metrics
    from jaxplan.nav import planning_grid
    from jaxplan.planning import plan_batch
    from jaxplan.search import shortest_lengths
    from jaxplan.smoothing import smooth

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
        out[ok] = np.asarray(path_metrics(np.asarray(sm.points, np.float64), mw.grid, n=np.asarray(sm.n)).length,
                             np.float64)
    return out


def convergence_metrics(history: np.ndarray, ok: np.ndarray, metrics) -> dict[str, np.ndarray]:
    """The convergence iterations of `CONVERGENCE_KEYS` named in ``metrics``, each as its paper defines it
    (`jaxplan.metrics.converged_iteration` and siblings), from the best-so-far history the run returns.

    Computed on the host from the history, so the compiled colony kernels stay as they are.

    Args:
      history: ``[n, R, I]`` best-so-far cost after each iteration (``inf`` before the first success).
      ok: ``bool[n, R]`` runs that found a path.
      metrics: metric names; only those in `CONVERGENCE_KEYS` are computed.

    Returns:
      ``{name: f64[n, R]}``: ``converged_iteration`` (0-based, within 1 % of the final best),
      ``converged_iteration_strict`` (0-based, within 0.1 %), ``turning_point`` (chu2024) and
      ``optimum_iteration`` (yu2020), both counted from 1; nan where the run found no path.
    """
    from jaxplan.metrics import CONVERGED_RTOL_STRICT, converged_iteration, optimum_iteration, turning_point

    fns = {"converged_iteration": converged_iteration,
           "converged_iteration_strict": lambda h: converged_iteration(h, rtol=CONVERGED_RTOL_STRICT),
           "turning_point": turning_point, "optimum_iteration": optimum_iteration}
    out = {}
    for k in CONVERGENCE_KEYS:
        if k in metrics:
            v = np.asarray(fns[k](np.asarray(history)), np.float64)
            out[k] = np.where(np.asarray(ok, bool) & (v >= 0), v, np.nan)
    return out


def _resample(points: np.ndarray, steps: np.ndarray, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Polylines ``[N, T, 2]`` (valid up to index ``steps[N]``) resampled every ``spacing`` of arc length, the end
    point kept: ``(f64[N, K, 2], int[N])`` points (padded with the end point) and their counts."""
    P = np.asarray(points, np.float64)
    N, T, _ = P.shape
    steps = np.clip(np.asarray(steps, np.int64), 0, T - 1)
    last = P[np.arange(N), steps]
    P = np.where((np.arange(T)[None, :] <= steps[:, None])[..., None], P, last[:, None, :])
    if T < 2:
        return P, np.ones(N, np.int64)
    seg = np.linalg.norm(np.diff(P, axis=1), axis=-1)  # [N, T-1]
    s = np.concatenate([np.zeros((N, 1)), np.cumsum(seg, axis=1)], axis=1)  # [N, T] arc length at each point
    total = s[:, -1]
    n = np.floor(total / spacing + 1e-9).astype(np.int64) + 1  # samples at 0, h, 2h, ... <= total
    end = total > (n - 1) * spacing + 1e-9  # the end point is a sample of its own
    K = int((n + end).max()) if N else 1
    q = np.minimum(np.arange(K)[None, :] * spacing, total[:, None])  # [N, K]
    j = np.clip((s[:, None, :] <= q[:, :, None]).sum(-1) - 1, 0, T - 2)  # the segment each sample falls on
    s0, ds = np.take_along_axis(s, j, 1), np.take_along_axis(seg, j, 1)
    frac = np.where(ds > 0, (q - s0) / np.where(ds > 0, ds, 1.0), 0.0)
    p0 = np.take_along_axis(P, j[..., None], 1)
    p1 = np.take_along_axis(P, (j + 1)[..., None], 1)
    return p0 + frac[..., None] * (p1 - p0), n + end


def executed_shape(grid, positions: np.ndarray, steps: np.ndarray) -> dict[str, np.ndarray]:
    """``smoothness`` and ``mean_clearance`` (m) of executed paths, ``f64[...]`` per trial.

    A control period moves the robot a few centimetres, so the raw trajectory has hundreds of vertices whose
    heading changes are tiny; it is resampled every cell length (the map's resolution) first, so that its
    smoothness and clearance are measured at the scale of a planned grid path (the same definitions as
    `jaxplan.path_metrics`'s, on these points). cui2025 Table 1 reports both for its executed paths.

    Args:
      grid: the map (world frame: its origin and resolution).
      positions: ``[..., T, 2]`` executed positions (m, world), valid up to index ``steps``.
      steps: ``int[...]`` the last valid index of each trajectory.
    """
    from jaxplan.metrics import path_metrics

    pos = np.asarray(positions, np.float64)
    lead = pos.shape[:-2]
    flat = pos.reshape(-1, *pos.shape[-2:])
    res = float(grid.resolution)
    pts, count = _resample(flat, np.asarray(steps).reshape(-1), res)
    cells = np.asarray(grid.to_local(pts), np.float64) / res - 0.5  # cell coordinates: centres at integers
    pm = path_metrics(cells, grid, n=count)
    return {k: np.where(count >= 3 if k == "smoothness" else count >= 1, np.asarray(getattr(pm, k), np.float64),
                        np.nan).reshape(lead) for k in ("smoothness", "mean_clearance")}
