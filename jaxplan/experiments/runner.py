"""`run_experiment`: a config's trials as batched, checkpointed, resumable work.

Work plan. Maps are loaded (or generated) and their scenarios chosen first; then the
trials are cut into *chunks*: one chunk is one map × one planner × up to ``chunk``
consecutive scenarios × every seed, and runs as ONE compiled call (`jaxplan.plan_batch`
or `jaxplan.navigate_batch`, seeds on the second batch axis — never a Python loop over
seeds). A TSP instance (``[[instances]]``) is one scenario: its chunk is the instance × one
``kind = "tsp"`` planner × every seed, `jaxplan.aco._tsp.run_tsp` vmapped over the seeds' keys
(the program `jaxplan.solve_tsp` runs for one seed). Planners run only where they apply
(`jaxplan.experiments.config.applies`): grid planners on maps, tsp planners on instances.
Chunks run in a fixed order (map, planner, scenarios), so the trials file has rows ordered
by (map, planner, scenario, seed). The last chunk of a (map, planner) is
padded to the full chunk size with copies of its last scenario (rows dropped after the
call): every chunk then has the same shapes and the program compiles once.

Run folder ``OUT/NAME/`` (``OUT/NAME-quick/`` with ``quick=True``, so a smoke run never
mixes with the real one)::

    config.toml          the config file, verbatim
    meta.json            versions (jaxplan, jax, numpy, scipy, python), git revision, devices, session start times
    trials.csv           one row per (map, planner, scenario, seed); deterministic (see below)
    timings.csv          wall-clock times per chunk (compile and run); NOT reproducible, hence apart
    summary.csv/.md      mean ± sd per map × planner × metric, the paper's numbers in `paper_*` columns
    significance.csv     ANOVA and pairwise Welch t-tests, if the config asks
    report.md            the whole run in one page
    checkpoints/manifest.json       the commit log of finished chunks
    checkpoints/chunks/ID.csv       each finished chunk's rows
    checkpoints/arrays/ID/          each chunk's arrays (orbax): convergence histories, paths, tours, trajectories

Checkpoints and resume. A finished chunk is committed in three steps: its rows are
written to ``chunks/ID.csv`` (temporary file, fsync, `os.replace`), its arrays saved
with orbax, and only then is its entry added to ``manifest.json`` (again written to a
temporary file and renamed). The manifest is the single commit point: a process killed
at any instant (SIGKILL included) leaves at worst a chunk that is not in the manifest,
which the next run recomputes and overwrites. Restarting with the same config skips
every chunk in the manifest; ``trials.csv`` is the header plus the chunk files in chunk
order, so it comes out byte-identical to an uninterrupted run's. The manifest holds a
fingerprint of everything that shapes the trials (seeds, chunk size, maps and their
files' SHA-256, scenarios, planners, metrics): a folder written by a different
experiment is refused rather than silently mixed. Each manifest entry records the
session (1 for the first invocation, 2 for the first restart, …) that computed it.

Reproducibility. Floats are written with Python's ``repr`` (shortest round-trip text),
integers as integers, and undefined values (a failed plan's length, an infeasible
episode's metrics) as ``nan``; wall-clock times never enter trials.csv.
"""

from __future__ import annotations

import csv
import dataclasses
import datetime as _dt
import hashlib
import io
import json
import math
import os
import shutil
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterator, Mapping, Sequence

import numpy as np

from jaxplan.core.cache import Built, memoize
from jaxplan.core.io import TMP_GLOB, atomic_write
from jaxplan.experiments.config import (
    ACCURACY_GAP, METRICS, ConfigError, ExperimentConfig, MapSpec, PlannerConfig, applies, apply_quick, load_config,
    nav_config,
)

__all__ = ["run_experiment", "prepare", "Prepared", "MapWork", "Unit", "trial_columns", "read_manifest",
           "load_chunk_arrays", "RunFolderError", "ID_COLUMNS", "accuracy", "reductions", "clock",
           "load_map_spec", "spec_scenarios"]

ID_COLUMNS = ("map", "planner", "kind", "scenario", "scen_row", "start_x", "start_y", "goal_x", "goal_y", "optimal",
              "seed")
"""The identifying columns of trials.csv, before the metric columns (``optimal``: exact octile optimum, m — for
a TSP instance the optimal tour's length, nan if unknown; ``scenario``: index among the map's chosen scenarios;
``scen_row``: row in the .scen file, −1 if generated; a TSP row leaves the start and goal cells empty)."""

MANIFEST_VERSION = 1


class RunFolderError(ValueError):
    """The run folder holds a different experiment (or a damaged manifest)."""


# ---------------------------------------------------------------------------------------------
# The work plan


@dataclass(frozen=True)
class MapWork:
    """A loaded map and its chosen scenarios.

    Attributes:
      spec: the config entry.
      grid: the `GridMap`.
      starts, goals: ``int64[S, 2]`` cells.
      optimal: ``f64[S]`` exact 8-connected octile optimum (m).
      rows: ``int64[S]`` row of each scenario in the .scen file (−1 when generated).
      digest: SHA-256 of the map (and scenario) file bytes, or of the generated grid.
      problem: a TSP instance's `TSPProblem` (then ``grid`` is None, S = 1, starts/goals are −1 and
        ``optimal`` is the optimal tour length); None for a map.
    """

    spec: MapSpec
    grid: Any
    starts: np.ndarray
    goals: np.ndarray
    optimal: np.ndarray
    rows: np.ndarray
    digest: str
    problem: Any = None


@dataclass(frozen=True)
class Unit:
    """One chunk: map ``m`` × planner ``p`` × scenarios ``lo:hi`` × every seed (``uid`` sorts in run order)."""

    index: int
    uid: str
    m: int
    p: int
    lo: int
    hi: int


@dataclass(frozen=True)
class Prepared:
    """The resolved config, its loaded maps and the chunks in run order."""

    config: ExperimentConfig
    maps: tuple[MapWork, ...]
    units: tuple[Unit, ...]

    @property
    def trials(self) -> int:
        return sum((u.hi - u.lo) * len(self.config.seeds) for u in self.units)


def _sha(*chunks: bytes) -> str:
    h = hashlib.sha256()
    for c in chunks:
        h.update(c)
    return h.hexdigest()


def load_map_spec(spec: MapSpec):
    """(grid, default start, default goal, digest) of a map entry."""
    from jaxplan.grid import load_map
    from jaxplan.experiments.config import _generators

    if spec.path is not None:
        grid = load_map(spec.path, resolution=spec.resolution)
        extra = spec.scen.read_bytes() if (spec.scen is not None and spec.scenarios.source == "scen") else b""
        return grid, None, None, _sha(spec.path.read_bytes(), extra)
    factory, is_dc = _generators()[spec.generator]
    params = {k: tuple(v) if isinstance(v, (list, tuple)) else v for k, v in spec.params.items()}
    if is_dc:
        scene = factory(**params, resolution=spec.resolution)(spec.seed)
    elif spec.generator == "demo_warehouse":
        scene = factory()
    else:
        scene = factory(spec.seed, **params)
    grid = scene.grid if scene.grid.resolution == spec.resolution else scene.grid._replace(resolution=spec.resolution)
    arrays = [np.ascontiguousarray(a).tobytes() for a in (grid.free, grid.height, grid.clearance_height, grid.risk,
                                                            grid.turn_rule)]
    return grid, np.asarray(scene.start), np.asarray(scene.goal), _sha(*arrays, repr(grid.resolution).encode())


def _load_instance(spec: MapSpec) -> MapWork:
    """A TSP instance as one scenario: the problem, its optimum (from the optimal tour, the configured length, or
    nan) and a digest of the files."""
    from jaxplan.aco import load_tour, load_tsplib, tour_length

    problem = load_tsplib(spec.tsplib)
    if spec.tour is not None:
        optimum = float(tour_length(problem, load_tour(spec.tour)))
        extra = spec.tour.read_bytes()
    else:
        optimum = math.nan if spec.optimum is None else float(spec.optimum)
        extra = repr(spec.optimum).encode()
    none = np.full((1, 2), -1, np.int64)
    return MapWork(spec, None, none, none, np.asarray([optimum], np.float64), np.full(1, -1, np.int64),
                   _sha(spec.tsplib.read_bytes(), extra), problem=problem)


def _choose(n: int, count: int | None, spread: str, seed: int) -> np.ndarray:
    """Indices of ``count`` of ``n`` filtered rows, in file order."""
    if count is None or count >= n:
        return np.arange(n)
    if spread == "first":
        return np.arange(count)
    if spread == "even":
        return np.unique(np.round(np.linspace(0, n - 1, count)).astype(np.int64))
    return np.sort(np.random.default_rng(seed).choice(n, size=count, replace=False))


def _random_pairs(grid, count: int, seed: int, min_distance: float,
                  min_clearance: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``count`` connected (start, goal) pairs of free cells at least ``min_distance`` m apart (straight line),
    each cell at least ``min_clearance`` m from the nearest blocked square."""
    from jaxplan.search import shortest_lengths

    ok_cells = np.asarray(grid.free)
    if min_clearance > 0:
        from jaxplan.grid import clearance_field

        ok_cells = ok_cells & (np.asarray(clearance_field(grid)) >= min_clearance)
    free = np.argwhere(ok_cells)[:, ::-1]  # (x, y)
    if len(free) < 2:
        raise ValueError("the map has fewer than two free cells" + (
            f" at least {min_clearance} m from obstacles" if min_clearance > 0 else ""))
    rng = np.random.default_rng(seed)
    S, G, L = [], [], []
    for _ in range(50):
        k = 4 * count
        a, b = free[rng.integers(len(free), size=k)], free[rng.integers(len(free), size=k)]
        d = np.hypot(*(a - b).T) * grid.resolution
        keep = (d >= max(min_distance, 1e-9))
        a, b = a[keep], b[keep]
        if len(a):
            lens = shortest_lengths(grid, a, b)
            ok = np.isfinite(lens)
            S += list(a[ok])
            G += list(b[ok])
            L += list(lens[ok])
        if len(S) >= count:
            break
    if len(S) < count:
        raise ValueError(f"found only {len(S)} of {count} connected start-goal pairs at least {min_distance} m apart")
    return np.asarray(S[:count], np.int64), np.asarray(G[:count], np.int64), np.asarray(L[:count], np.float64)


def spec_scenarios(spec: MapSpec, grid, start0, goal0) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(starts, goals, optimal m, scen rows) of a map, as its `ScenarioSpec` asks."""
    from jaxplan.grid import load_scenarios
    from jaxplan.search import shortest_lengths

    sc = spec.scenarios
    if sc.source == "scene":
        s, g = start0[None].astype(np.int64), goal0[None].astype(np.int64)
        opt = shortest_lengths(grid, s, g)
        if not np.isfinite(opt[0]):
            raise ValueError("the generator's start and goal are not connected")
        return s, g, opt, np.full(1, -1, np.int64)
    if sc.source == "random":
        s, g, opt = _random_pairs(grid, sc.count or 10, sc.seed, sc.min_distance, sc.min_clearance)
        return s, g, opt, np.full(len(s), -1, np.int64)
    scen = load_scenarios(spec.scen, grid=grid)
    keep = np.ones(len(scen.starts), bool)
    opt_file = np.asarray(scen.optimal, np.float64) * spec.resolution
    if sc.min_bucket is not None:
        keep &= scen.buckets >= sc.min_bucket
    if sc.max_bucket is not None:
        keep &= scen.buckets <= sc.max_bucket
    if sc.min_optimal is not None:
        keep &= opt_file >= sc.min_optimal
    if sc.max_optimal is not None:
        keep &= opt_file <= sc.max_optimal
    keep &= np.any(scen.starts != scen.goals, axis=1)
    rows = np.flatnonzero(keep)
    if rows.size == 0:
        raise ValueError(f"no scenario row of {spec.scen.name} passes the bucket/optimal filters")
    rows = rows[_choose(rows.size, sc.count, sc.spread, sc.seed)]
    s, g = scen.starts[rows].astype(np.int64), scen.goals[rows].astype(np.int64)
    return s, g, shortest_lengths(grid, s, g), rows.astype(np.int64)


def prepare(cfg: ExperimentConfig) -> Prepared:
    """Loads every map, chooses every scenario and cuts the chunks — before any planning.

    Raises:
      ConfigError: problems only visible with the data (an empty scenario filter,
        scenario rows that do not fit the map, too few connected random pairs), all at once.
    """
    problems, maps = [], []
    for i, spec in enumerate(cfg.maps):
        try:
            if spec.is_tsp:
                maps.append(_load_instance(spec))
                continue
            grid, s0, g0, digest = load_map_spec(spec)
            s, g, opt, rows = spec_scenarios(spec, grid, s0, g0)
        except (ValueError, FileNotFoundError) as e:
            problems.append(f"{spec.key or f'maps[{i}]'} ({spec.name}): {e}")
            continue
        maps.append(MapWork(spec, grid, s, g, np.asarray(opt, np.float64), rows, digest))
    if problems:
        raise ConfigError(problems, str(cfg.path or cfg.name))
    units, k = [], 0
    for mi, mw in enumerate(maps):
        for pi, pc in enumerate(cfg.planners):
            if not applies(pc, mw.spec):
                continue
            for ci, lo in enumerate(range(0, len(mw.starts), cfg.chunk)):
                hi = min(lo + cfg.chunk, len(mw.starts))
                units.append(Unit(k, f"{k:05d}-m{mi}-p{pi}-c{ci}", mi, pi, lo, hi))
                k += 1
    return Prepared(cfg, tuple(maps), tuple(units))


def trial_columns(cfg: ExperimentConfig) -> tuple[str, ...]:
    """The header of trials.csv: `ID_COLUMNS`, ``success`` (always), the configured non-timing metrics, and
    ``reason`` with navigation."""
    metrics = ("success",) + tuple(m for m in cfg.metrics if not METRICS[m].timing and m != "success")
    return ID_COLUMNS + metrics + (("reason",) if "navigate" in cfg.kinds else ())


def _plain(x: Any) -> Any:
    """JSON-able form of config values (for the fingerprint)."""
    if dataclasses.is_dataclass(x):
        return {f.name: _plain(getattr(x, f.name)) for f in dataclasses.fields(x)}
    if isinstance(x, Mapping):
        return {str(k): _plain(v) for k, v in sorted(x.items())}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, Path):
        return x.name
    if isinstance(x, float) and not math.isfinite(x):
        return repr(x)
    return x


def _spec_doc(spec: MapSpec) -> dict:
    """A map's part of the fingerprint. The instance fields are left out while unset (and ``key`` always: it names
    the config entry, it does not shape trials), so a map's fingerprint is the one written before instances."""
    doc = _plain(spec)
    doc.pop("key", None)
    for k in ("tsplib", "tour", "optimum"):
        if doc.get(k) is None:
            doc.pop(k, None)
    return doc


def fingerprint(prep: Prepared) -> str:
    """SHA-256 of everything that shapes trials.csv (not stats, figures or paper numbers)."""
    cfg = prep.config
    doc = {
        "seeds": list(cfg.seeds), "chunk": cfg.chunk, "columns": list(trial_columns(cfg)),
        "maps": [{"spec": _spec_doc(m.spec), "digest": m.digest} for m in prep.maps],
        "planners": _plain(cfg.planners), "quick": cfg.is_quick,
    }
    return _sha(json.dumps(doc, sort_keys=True).encode())


# ---------------------------------------------------------------------------------------------
# Running one chunk


def _fmt(v: Any) -> str:
    """The fixed text of a value: ``repr`` of a float (nan for undefined), an integer as an integer."""
    if isinstance(v, (bool, np.bool_)):
        return "1" if v else "0"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        f = float(v)
        return "nan" if math.isnan(f) else repr(f)
    return str(v)


def _pad(idx: np.ndarray, size: int) -> np.ndarray:
    return np.concatenate([idx, np.full(size - len(idx), idx[-1])]) if len(idx) < size else idx


_PATH_KEYS = ("length", "optimality_gap", "turns", "sharp_turns", "smoothness", "min_clearance", "mean_clearance",
              "max_curvature")
_LOS_KEYS = ("los_length", "los_turns", "los_length_reduction", "los_turns_reduction")
_INT_METRICS = ("turns", "sharp_turns", "los_turns", "converged_iteration", "collisions", "recoveries", "replans")
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


def _los_metrics(grid, paths: np.ndarray, n: np.ndarray, ok: np.ndarray, fill: np.ndarray) -> dict[str, np.ndarray]:
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


def _hausdorff(mw: MapWork, idx: np.ndarray, paths: np.ndarray, n_cells: np.ndarray) -> np.ndarray:
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


def _run_plan(mw: MapWork, pc: PlannerConfig, idx: np.ndarray, seeds: tuple[int, ...], chunk: int,
              metrics: Sequence[str]) -> tuple[dict, dict, dict]:
    """Metric arrays ``[n, R]``, arrays to keep, and timings of one plan chunk (one `plan_batch` call)."""
    from jaxplan.aco import COLONIES, plan_batch
    from jaxplan.metrics import path_metrics

    batched = pc.name in COLONIES
    run_idx = _pad(idx, chunk) if batched else idx  # equal shapes: one compilation per (map, planner)
    overrides = {k: tuple(v) if isinstance(v, tuple) else v for k, v in pc.overrides.items()}
    br = plan_batch(mw.grid, mw.starts[run_idx], mw.goals[run_idx], planner=pc.name, seeds=seeds, **overrides)
    n, R = len(idx), len(seeds)
    ok = br.success[:n]
    out: dict[str, np.ndarray] = {"success": ok.astype(np.int64)}
    los = any(m in _LOS_KEYS for m in metrics)
    if any(m in _PATH_KEYS for m in metrics) or los or "accuracy" in metrics:
        P = br.paths.shape[2]
        pm = path_metrics(br.paths[:n].reshape(n * R, P, 2), mw.grid, optimal=np.repeat(mw.optimal[idx], R),
                          n=br.n_cells[:n].reshape(-1))
        raw = {k: np.where(ok, np.asarray(pm[k], np.float64).reshape(n, R), np.nan) for k in _PATH_KEYS}
        # The device's float32 sums depend on the batch's layout, so a --chunk change moved the last bits of a
        # stored path's length; DESIGN promises same seed, same result: recompute from the integer cells.
        length = grid_path_lengths(br.paths[:n].reshape(n * R, P, 2), br.n_cells[:n].reshape(-1),
                                   float(mw.grid.resolution)).reshape(n, R)
        raw["length"] = np.where(ok, length, np.nan)
        raw["optimality_gap"] = np.where(ok, optimality_gaps(length, mw.optimal[idx][:, None]), np.nan)
        out.update({k: v for k, v in raw.items() if k in metrics})
        if "accuracy" in metrics:  # the raw grid path against the exact octile optimum
            out["accuracy"] = accuracy(ok, raw["optimality_gap"])
        if los:
            sm = _los_metrics(mw.grid, br.paths[:n].reshape(n * R, P, 2), br.n_cells[:n].reshape(-1), ok.reshape(-1),
                              np.repeat(mw.starts[idx], R, axis=0))
            sm = {k: v.reshape(n, R) for k, v in sm.items()}
            sm["los_length_reduction"] = reductions(raw["length"], sm["los_length"])
            sm["los_turns_reduction"] = reductions(raw["turns"], sm["los_turns"])
            out.update({k: v for k, v in sm.items() if k in metrics})
    if "hausdorff" in metrics:
        out["hausdorff"] = np.where(ok, _hausdorff(mw, idx, br.paths[:n], br.n_cells[:n]), np.nan)
    if "cost" in metrics:
        out["cost"] = np.where(ok, br.cost[:n], np.nan)
    if "converged_iteration" in metrics:
        out["converged_iteration"] = np.where(ok, br.converged[:n].astype(np.float64), np.nan)
    keep = {"history": br.history[:n].astype(np.float32), "diversity": br.diversity[:n].astype(np.float32),
            "successes": br.successes[:n].astype(np.int32), "paths": br.paths[:n].astype(np.int32),
            "n_cells": br.n_cells[:n].astype(np.int32), "success": ok}
    trials = len(run_idx) * R
    timing = {"compile_s": float(br.compile_s), "time_s": float(br.time_s), "plan_time_s": float(br.time_s) / trials}
    return out, keep, timing


def _obstacle_fn(mw: MapWork, m: int, pc: PlannerConfig, run_idx: np.ndarray) -> Callable | None:
    """``f(e, seed) -> MovingObstacles``: every (scenario, seed) trial draws its own discs, reproducibly."""
    o = pc.obstacles
    if o is None or o.n == 0:
        return None
    from jaxplan.nav import random_obstacles

    res = float(mw.grid.resolution)

    def fn(e: int, seed: int):
        sc = int(run_idx[e])
        s = int(np.random.SeedSequence([o.seed, m, sc, int(seed)]).generate_state(1)[0])
        avoid = (np.stack([mw.starts[sc], mw.goals[sc]]) + 0.5) * res
        return random_obstacles(mw.grid, n=o.n, speed=o.speed, radius=o.radius, seed=s, waypoints=o.waypoints,
                                avoid=avoid, avoid_radius=o.avoid_radius, loop=o.loop)

    return fn


_NAV_KEYS = ("success", "collisions", "time_s", "rmse", "max_curvature", "energy", "path_length", "recoveries",
             "replans")


def _executed_optimum(mw: MapWork, pc: PlannerConfig, idx: np.ndarray) -> np.ndarray:
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


def _run_navigate(mw: MapWork, m: int, pc: PlannerConfig, idx: np.ndarray, seeds: tuple[int, ...], chunk: int,
                  metrics: Sequence[str]) -> tuple[dict, dict, dict]:
    """Metric arrays ``[n, R]`` (and ``reason``), arrays to keep, and timings of one `navigate_batch` call."""
    from jaxplan.nav import navigate_batch

    run_idx = _pad(idx, chunk)
    cfg, weights = nav_config(pc)
    overrides = {k: tuple(v) if isinstance(v, tuple) else v for k, v in pc.overrides.items()}
    eb = navigate_batch(mw.grid, mw.starts[run_idx], mw.goals[run_idx], pipeline=pc.name, seeds=list(seeds),
                        obstacles=_obstacle_fn(mw, m, pc, run_idx), config=cfg, params=weights or None,
                        **overrides)
    n = len(idx)
    out: dict[str, np.ndarray] = {}
    for k in _NAV_KEYS:
        if k in metrics:
            v = getattr(eb, k)[:n, :, 0]
            out[k] = v.astype(np.int64) if k in ("success", "collisions", "recoveries", "replans") else \
                np.asarray(v, np.float64)
    if "hausdorff" in metrics:
        out["hausdorff"] = _hausdorff(mw, idx, eb.plans[:n, :, 0], eb.n_plan[:n, :, 0])
    if "accuracy" in metrics:  # the executed path against the smoothed exact path the robot fits
        gap = np.asarray(eb.path_length[:n, :, 0], np.float64) / _executed_optimum(mw, pc, idx)[:, None] - 1.0
        out["accuracy"] = accuracy(eb.success[:n, :, 0], gap)
    out["reason"] = eb.reason[:n, :, 0]
    T = int(eb.steps[:n].max()) + 1
    # states (x, y, theta, v, omega) feed the velocity traces and the DWA fans of `jaxplan figures`.
    keep = {"positions": eb.states[:n, :, 0, :T, :2].astype(np.float32),
            "states": eb.states[:n, :, 0, :T].astype(np.float32), "steps": eb.steps[:n, :, 0].astype(np.int32),
            "plans": eb.plans[:n, :, 0].astype(np.float32), "n_plan": eb.n_plan[:n, :, 0].astype(np.int32),
            "success": eb.success[:n, :, 0]}
    timing = {"compile_s": float(eb.compile_s), "time_s": float(eb.run_time_s), "plan_time_s": float(eb.plan_time_s),
              "step_time_s": float(eb.step_time_s)}
    return out, keep, timing


def _tsp_program(cfg, dist, params: dict, keys) -> tuple[Callable, float]:
    """`run_tsp` vmapped over ``keys [R]``, compiled for these shapes, and the seconds spent compiling now (0 if
    cached): one compile per (config, instance size, seeds, parameter names); a sweep over many sizes keeps only
    the last 8 executables alive."""
    return _compiled_tsp(cfg, dist, params, keys).take()


@memoize(maxsize=8, key=lambda cfg, dist, params, keys: (cfg, dist.shape, keys.shape, tuple(sorted(params))))
def _compiled_tsp(cfg, dist, params: dict, keys) -> Built:
    import jax

    from jaxplan.aco import run_tsp

    program = jax.jit(jax.vmap(lambda d, p, k: run_tsp(cfg, d, p, k), in_axes=(None, None, 0)))
    return Built.timed(lambda: program.lower(dist, params, keys).compile())


def _run_tsp(mw: MapWork, pc: PlannerConfig, seeds: tuple[int, ...], metrics: Sequence[str]
             ) -> tuple[dict, dict, dict]:
    """Metric arrays ``[1, R]``, arrays to keep and timings of one TSP chunk: every seed in one compiled call.

    Each seed's run is `jaxplan.solve_tsp`'s (same parameter resolution, program and PRNG key
    ``jax.random.key(seed)``), vmapped over the seeds; lengths are recomputed in float64 on the host from the tours,
    as `solve_tsp` does.
    """
    import jax
    import jax.numpy as jnp

    from jaxplan.aco import TSP_STATIC_PARAMS, TSPConfig, resolve_tsp, tour_length

    problem = mw.problem
    p = resolve_tsp(pc.name, {k: tuple(v) if isinstance(v, tuple) else v for k, v in pc.overrides.items()})
    cfg = TSPConfig(pc.name, int(p.get("colonies", 1)), int(p["ants"]), int(p["iterations"]), p["local_search"])
    params = {k: jnp.asarray(v, jnp.float32) for k, v in p.items() if k not in TSP_STATIC_PARAMS}
    dist = jnp.asarray(np.asarray(problem.dist, np.float64), jnp.float32)
    keys = jax.random.wrap_key_data(jnp.stack([jax.random.key_data(jax.random.key(int(s))) for s in seeds]))
    fn, compile_s = _tsp_program(cfg, dist, params, keys)
    t0 = time.perf_counter()
    res = jax.block_until_ready(fn(dist, params, keys))
    time_s = time.perf_counter() - t0
    tours = np.asarray(res.tour, np.int64)  # [R, n], any rotation
    tours = np.stack([np.roll(t, -int(np.flatnonzero(t == 0)[0])) for t in tours])
    lengths = np.asarray([tour_length(problem, t) for t in tours], np.float64)
    history = np.asarray(res.history, np.float64)  # [R, I] best length so far
    R = len(seeds)
    values = {"success": np.ones((1, R), np.int64), "tour_length": lengths[None],
              "optimality_gap": (lengths / mw.optimal[0] - 1.0)[None],
              # The iteration the final best tour was found: Table 1's "number of iterations" (yu2020).
              "converged_iteration": np.argmax(history <= history[:, -1:], axis=1).astype(np.float64)[None]}
    keep = {"history": history[None].astype(np.float32), "tours": tours[None].astype(np.int32),
            "success": np.ones((1, R), bool)}
    timing = {"compile_s": float(compile_s), "time_s": float(time_s), "plan_time_s": float(time_s) / R}
    return {k: v for k, v in values.items() if k in metrics}, keep, timing


def _rows(prep: Prepared, u: Unit, values: dict) -> str:
    """The CSV text (no header) of a chunk's trials, scenario-major then seed."""
    cfg = prep.config
    mw, pc = prep.maps[u.m], cfg.planners[u.p]
    cols = trial_columns(cfg)
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    for i, sc in enumerate(range(u.lo, u.hi)):
        for r, seed in enumerate(cfg.seeds):
            row = {"map": mw.spec.name, "planner": pc.label, "kind": pc.kind, "scenario": sc,
                   "scen_row": int(mw.rows[sc]), "start_x": int(mw.starts[sc, 0]), "start_y": int(mw.starts[sc, 1]),
                   "goal_x": int(mw.goals[sc, 0]), "goal_y": int(mw.goals[sc, 1]),
                   "optimal": float(mw.optimal[sc]), "seed": seed}
            if mw.problem is not None:  # a TSP has no start or goal cell
                row.update(start_x="", start_y="", goal_x="", goal_y="")
            for c in cols[len(ID_COLUMNS):]:
                if c == "reason":
                    row[c] = str(values["reason"][i, r]) if "reason" in values else (
                        "goal" if values["success"][i, r] else "no path")
                elif c in values:
                    v = values[c][i, r]
                    row[c] = int(v) if (c in _INT_METRICS and np.isfinite(v)) else v
                else:
                    row[c] = ""  # the metric does not apply to this planner kind
            w.writerow([_fmt(row[c]) for c in cols])
    return buf.getvalue()


def run_unit(prep: Prepared, u: Unit) -> tuple[str, dict, dict]:
    """(CSV rows, arrays to keep, timings) of chunk ``u``: one compiled batch call."""
    cfg = prep.config
    mw, pc = prep.maps[u.m], cfg.planners[u.p]
    idx = np.arange(u.lo, u.hi)
    metrics = ("success",) + cfg.metrics  # success is always a column: other metrics are read given it
    if pc.kind == "tsp":
        values, keep, timing = _run_tsp(mw, pc, cfg.seeds, metrics)
    elif pc.kind == "plan":
        values, keep, timing = _run_plan(mw, pc, idx, cfg.seeds, cfg.chunk, metrics)
    else:
        values, keep, timing = _run_navigate(mw, u.m, pc, idx, cfg.seeds, cfg.chunk, metrics)
    return _rows(prep, u, values), keep, timing


# ---------------------------------------------------------------------------------------------
# Checkpoints


def read_manifest(run_dir: str | os.PathLike) -> dict:
    """The manifest of a run folder: ``{"fingerprint", "sessions", "chunks": {uid: entry}}``."""
    p = Path(run_dir) / "checkpoints" / "manifest.json"
    return json.loads(p.read_text()) if p.is_file() else {"chunks": {}, "sessions": 0}


class _Store:
    """The run folder's checkpoint store (see the module docstring)."""

    def __init__(self, run_dir: Path, fp: str):
        self.dir = run_dir
        self.ck = run_dir / "checkpoints"
        self.chunks = self.ck / "chunks"
        self.arrays = self.ck / "arrays"
        for d in (self.chunks, self.arrays):
            d.mkdir(parents=True, exist_ok=True)
        self.path = self.ck / "manifest.json"
        if self.path.is_file():
            try:
                self.manifest = json.loads(self.path.read_text())
            except json.JSONDecodeError as e:  # cannot happen with atomic writes; say so if it does
                raise RunFolderError(f"{self.path}: damaged manifest ({e}); delete the run folder") from None
            if self.manifest.get("fingerprint") != fp:
                raise RunFolderError(
                    f"{run_dir} holds the checkpoints of a different experiment (seeds, chunk size, maps, "
                    "scenarios, planners or metrics changed); delete that folder or pass another --out")
        else:
            self.manifest = {"version": MANIFEST_VERSION, "fingerprint": fp, "sessions": 0, "chunks": {}}
        # Leftovers of a killed writer: our temporary files and orbax's unfinished saves.
        for p in list(self.chunks.glob(TMP_GLOB)) + list(self.ck.glob(TMP_GLOB)):
            p.unlink(missing_ok=True)
        for p in self.arrays.glob("*.orbax-checkpoint-tmp*"):
            shutil.rmtree(p, ignore_errors=True)
        self.manifest["sessions"] += 1
        self.session = self.manifest["sessions"]
        self._save()

    def _save(self) -> None:
        atomic_write(self.path, json.dumps(self.manifest, indent=1, sort_keys=True).encode())

    def done(self, u: Unit) -> bool:
        e = self.manifest["chunks"].get(u.uid)
        f = self.chunks / f"{u.uid}.csv"
        return e is not None and f.is_file() and f.stat().st_size == e["bytes"]

    def commit(self, u: Unit, info: dict, text: str, arrays: dict, timing: dict) -> None:
        data = text.encode()
        atomic_write(self.chunks / f"{u.uid}.csv", data)
        arrays = {k: np.asarray(v) for k, v in arrays.items() if np.asarray(v).size}
        if arrays:
            import orbax.checkpoint as ocp

            ocp.PyTreeCheckpointer().save((self.arrays / u.uid).resolve(), arrays, force=True)
        self.manifest["chunks"][u.uid] = {**info, "bytes": len(data), "sha256": _sha(data), "session": self.session,
                                          "arrays": sorted(arrays), **timing}
        self._save()

    def merged(self, units: Sequence[Unit], header: str) -> bytes:
        return header.encode() + b"".join((self.chunks / f"{u.uid}.csv").read_bytes() for u in units)


def load_chunk_arrays(run_dir: str | os.PathLike, uid: str) -> dict[str, np.ndarray]:
    """The arrays (orbax) kept for chunk ``uid``: plan chunks ``history f32[n, R, I]``, ``diversity``,
    ``successes``, ``paths i32[n, R, P, 2]``, ``n_cells``, ``success``; navigate chunks ``positions
    f32[n, R, T, 2]`` (m), ``states f32[n, R, T, 5]`` (x, y, theta, v, omega), ``steps``, ``plans``, ``n_plan``,
    ``success``; tsp chunks ``history f32[1, R, I]`` (best tour length so far), ``tours i32[1, R, n]`` (the best
    tour, from city 0), ``success``. The manifest entry of ``uid`` names its map, planner and scenario range."""
    import orbax.checkpoint as ocp

    return ocp.PyTreeCheckpointer().restore((Path(run_dir) / "checkpoints" / "arrays" / uid).resolve())


# ---------------------------------------------------------------------------------------------
# Meta and progress


def _meta(run_dir: Path, cfg: ExperimentConfig, session: int, started: str) -> dict:
    """Writes ``meta.json``: the run's settings, its sessions and the provenance record (`jaxplan.core.provenance`).
    The flat version keys of earlier run folders stay, so readers of old and new folders read the same keys."""
    from jaxplan.core.provenance import provenance
    from jaxplan.core.version import VERSION

    p = run_dir / "meta.json"
    old = json.loads(p.read_text()) if p.is_file() else {}
    record = provenance()
    versions = record["versions"]
    rev = record["git_revision"]
    meta = {
        "experiment": cfg.name, "quick": cfg.is_quick, "chunk": cfg.chunk, "seeds": list(cfg.seeds),
        "jaxplan_version": VERSION, "git_revision": rev and (rev + ("+dirty" if record["git_dirty"] else "")),
        "jax_version": versions["jax"], "numpy_version": versions["numpy"], "scipy_version": versions["scipy"],
        "python": record["python"], "platform": record["platform"], "devices": record["devices"],
        "started": old.get("started", started),
        "sessions": old.get("sessions", []) + [{"session": session, "started": started}],
        "config_sha256": _sha(cfg.text.encode()), "provenance": record,
    }
    atomic_write(p, json.dumps(meta, indent=1).encode())
    return meta


def clock(s: float) -> str:
    """Seconds as ``H:MM:SS``."""
    s = int(round(s))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


class _Progress:
    """``NAME: done/total trials (pct) | chunk k/K | elapsed | left ~`` on stderr (one rewritten line on a TTY)."""

    def __init__(self, name: str, total: int, done: int, chunks: int, enabled: bool):
        self.name, self.total, self.start_done, self.chunks, self.enabled = name, total, done, chunks, enabled
        self.t0 = time.perf_counter()
        self.tty = sys.stderr.isatty()

    def update(self, done: int, chunk: int, what: str) -> None:
        if not self.enabled:
            return
        el = time.perf_counter() - self.t0
        new = done - self.start_done
        left = el / new * (self.total - done) if new else float("nan")
        msg = (f"{self.name}: {done}/{self.total} trials ({done / max(self.total, 1):.0%}) | chunk {chunk}/"
               f"{self.chunks} {what} | elapsed {clock(el)} | left ~{clock(left) if math.isfinite(left) else '?'}")
        print(("\r" + msg.ljust(110)) if self.tty else msg, end="" if self.tty else "\n", file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.enabled and self.tty:
            print(file=sys.stderr, flush=True)


# ---------------------------------------------------------------------------------------------
# The front door


def run_experiment(config: ExperimentConfig | str | os.PathLike, out_dir: str | os.PathLike = "runs", *,
                   quick: bool = False, data_dir: str | os.PathLike | None = None, progress: bool = True,
                   chunk: int | None = None, stop_after: int | None = None) -> Path:
    """Runs (or resumes) an experiment and writes its run folder.

    Args:
      config: an `ExperimentConfig` or the path of a TOML config (validated in full first).
      out_dir: parent of the run folder ``NAME`` (``NAME-quick`` with ``quick``).
      quick: apply the config's ``[experiment.quick]`` changes (a smoke run).
      data_dir: where relative map paths resolve (default ``$JAXPLAN_DATA`` or ../shared/benchmarks).
      progress: print a progress line on stderr.
      chunk: scenarios per compiled call, overriding the config's ``experiment.chunk``.
      stop_after: compute at most this many chunks in this session, then return without
        the summary (for tests and for splitting a run over several jobs).

    Returns:
      The run folder.

    Raises:
      ConfigError: the config or its data has problems (all listed; nothing was run).
      RunFolderError: the folder holds checkpoints of a different experiment.
    """
    cfg = config if isinstance(config, ExperimentConfig) else load_config(config, data_dir=data_dir)
    if quick and not cfg.is_quick:
        cfg = apply_quick(cfg)
    if chunk is not None:
        if not isinstance(chunk, int) or chunk < 1:
            raise ConfigError([f"chunk: must be an integer >= 1, got {chunk!r}"], "--chunk")
        cfg = cfg.replace(chunk=chunk)
    prep = prepare(cfg)
    run_dir = Path(out_dir) / (cfg.name + ("-quick" if cfg.is_quick else ""))
    run_dir.mkdir(parents=True, exist_ok=True)
    store = _Store(run_dir, fingerprint(prep))
    started = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
    atomic_write(run_dir / "config.toml", cfg.text.encode())
    _meta(run_dir, cfg, store.session, started)

    R = len(cfg.seeds)
    done_units = [u for u in prep.units if store.done(u)]
    done = sum((u.hi - u.lo) * R for u in done_units)
    bar = _Progress(cfg.name, prep.trials, done, len(prep.units), progress)
    if progress and done_units:
        print(f"{cfg.name}: resuming, {len(done_units)}/{len(prep.units)} chunks already done", file=sys.stderr)
    computed = 0
    for u in prep.units:
        if store.done(u):
            continue
        if stop_after is not None and computed >= stop_after:
            bar.close()
            return run_dir
        text, arrays, timing = run_unit(prep, u)
        info = {"map": prep.maps[u.m].spec.name, "planner": cfg.planners[u.p].label, "kind": cfg.planners[u.p].kind,
                "scenarios": [u.lo, u.hi], "trials": (u.hi - u.lo) * R}
        store.commit(u, info, text, arrays, timing)
        computed += 1
        done += (u.hi - u.lo) * R
        bar.update(done, u.index + 1, f"{info['map']}/{info['planner']}")
    bar.close()

    header = ",".join(trial_columns(cfg)) + "\n"
    atomic_write(run_dir / "trials.csv", store.merged(prep.units, header))
    from jaxplan.experiments import report, stats

    timings = [{"uid": u.uid, **store.manifest["chunks"][u.uid]} for u in prep.units]
    stats.write_timings(run_dir / "timings.csv", timings)
    result = stats.analyse(run_dir / "trials.csv", run_dir / "timings.csv", cfg)
    stats.write_summary(run_dir / "summary.csv", result)
    stats.write_significance(run_dir / "significance.csv", result)
    meta = json.loads((run_dir / "meta.json").read_text())
    atomic_write(run_dir / "summary.md", report.summary_markdown(result, cfg))
    atomic_write(run_dir / "report.md", report.report_markdown(result, cfg, prep, meta))
    return run_dir
