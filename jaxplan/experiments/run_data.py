"""A run folder read back for its figures: the config, the work plan, the manifest, the trials and each
chunk's stored arrays, with the selection helpers every figure kind shares (`jaxplan.experiments.figure_kinds`).

The maps and scenarios are rebuilt from the config (`jaxplan.experiments.prepare`: deterministic, no
planning); a chunk's arrays are read from its orbax checkpoint on first use.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from jaxplan.experiments import plots
from jaxplan.experiments.config import (
    ACCURACY_GAP,
    METRICS,
    ExperimentConfig,
    FigureSpec,
    applies,
    apply_quick,
    parse_config,
    read_config_text,
)

__all__ = ["RunData", "MissingArrays", "load_run", "selected", "panel_grid", "map_layer", "figure_title",
           "figure_metric", "metric_label", "metric_scale", "QUANTITIES", "need_trials", "scenario_of", "scenario_seed",
           "cell_path_m", "trial_obstacles", "disc_positions"]

plt = plots.plt  # the Agg backend is chosen in plots


class MissingArrays(ValueError):
    """A figure needs a chunk's arrays that are missing, damaged or not computed yet (and ``partial`` is off)."""


@dataclass
class RunData:
    """A run folder read back: config (quick applied if it ran quick), maps, manifest, trials.

    ``partial``: a figure may be drawn without the arrays of chunks that are missing or damaged (they are
    listed in ``figure_missing`` while it is drawn, then labelled); otherwise such a figure is refused
    (`MissingArrays`), since a convergence curve that silently drops a planner reads as a result.
    """

    run_dir: Path
    config: ExperimentConfig
    prep: Any  # prepare.Prepared
    manifest: dict
    trials: dict | None
    _arrays: dict
    partial: bool = False
    _missing: dict = field(default_factory=dict)
    figure_missing: dict = field(default_factory=dict)

    def arrays(self, m: int, p: int, scenario: int) -> tuple[dict, int] | None:
        """(chunk arrays, row of ``scenario`` in them) for map ``m``, planner ``p``; None if the run has no such
        chunk, or (with ``partial``) if its arrays are missing or damaged.

        Raises:
          MissingArrays: the chunk's arrays are missing, fail their SHA-256 check, cannot be read or were never
            computed (an unfinished run), and ``partial`` is off.
        """
        from jaxplan.experiments.store import CheckpointError, load_chunk_arrays

        for u in self.prep.units:
            if u.m == m and u.p == p and u.lo <= scenario < u.hi:
                entry = self.manifest.get("chunks", {}).get(u.uid)
                if u.uid not in self._arrays:
                    where = f"[{self.prep.maps[m].spec.name}/{self.config.planners[p].label}, scenarios {u.lo}-" \
                            f"{u.hi - 1}]"
                    if entry is None:
                        self._missing[u.uid] = (f"chunk {u.uid} {where} has not run yet (an unfinished run: "
                                                f"`jaxplan run CONFIG` resumes it)")
                        self._arrays[u.uid] = None
                    else:
                        try:
                            self._arrays[u.uid] = load_chunk_arrays(self.run_dir, u.uid, entry.get("arrays_sha256"))
                        except CheckpointError as e:
                            self._missing[u.uid] = f"{e} {where}; run `jaxplan run CONFIG` again to recompute it"
                            self._arrays[u.uid] = None
                a = self._arrays[u.uid]
                if a is None:
                    why = self._missing[u.uid]
                    if not self.partial:
                        raise MissingArrays(f"{why} (or draw without it: jaxplan figures --partial)")
                    self.figure_missing[u.uid] = why
                    return None
                return a, scenario - u.lo
        return None


def load_run(run_dir: str | os.PathLike, data_dir: str | os.PathLike | None = None, *,
             partial: bool = False) -> RunData:
    """Reads a run folder written by `run_experiment` (``partial``: see `RunData`).

    Raises:
      FileNotFoundError: not a run folder (no config.toml), or no finished chunk.
    """
    from jaxplan.experiments import stats
    from jaxplan.experiments.prepare import fingerprint, prepare
    from jaxplan.experiments.store import read_manifest

    run_dir = Path(run_dir)
    cfg_path = run_dir / "config.toml"
    if not cfg_path.is_file():
        raise FileNotFoundError(f"{run_dir} is not a run folder (no config.toml); run `jaxplan run CONFIG` first")
    meta_path = run_dir / "meta.json"
    try:
        meta = json.loads(meta_path.read_text()) if meta_path.is_file() else {}
    except ValueError:
        raise ValueError(f"{meta_path} is damaged (not JSON); run `jaxplan run` with the run's config again to "
                         f"rewrite it") from None
    meta = meta if isinstance(meta, dict) else {}
    cfg = parse_config(read_config_text(cfg_path), data_dir=data_dir, source=str(cfg_path))
    if meta.get("quick"):
        cfg = apply_quick(cfg)
    if meta.get("chunk"):
        cfg = cfg.replace(chunk=int(meta["chunk"]))  # `--chunk` may have overridden the config's
    prep = prepare(cfg)
    manifest = read_manifest(run_dir, fingerprint(prep))
    if not manifest.get("chunks"):
        raise FileNotFoundError(f"{run_dir} has no finished chunk yet")
    trials_path = run_dir / "trials.csv"
    trials = stats.read_trials(trials_path) if trials_path.is_file() else None
    return RunData(run_dir, cfg, prep, manifest, trials, {}, partial)


# ---------------------------------------------------------------------------------------------
# Helpers shared by the figure kinds


def selected(run: RunData, spec: FigureSpec, kind: str | tuple[str, ...] | None = None
              ) -> tuple[list[int], list[int]]:
    """Indices of the maps and planners the figure names (default all; ``kind`` filters planners, and the maps
    are those at least one selected planner runs on)."""
    cfg = run.config
    kinds = (kind,) if isinstance(kind, str) else kind
    # A drawn map's figures show its first draw unless the figure names the others.
    maps = spec.params.get("maps") or [m.spec.name for m in run.prep.maps if m.spec.draw == 0]
    labels = spec.params.get("planners") or [p.label for p in cfg.planners]
    pi = [i for i, p in enumerate(cfg.planners) if p.label in labels and (kinds is None or p.kind in kinds)]
    mi = [i for i, m in enumerate(run.prep.maps) if m.spec.name in maps
          and any(applies(cfg.planners[p], m.spec) for p in pi)]
    if not mi or not pi:  # e.g. a --quick run that keeps none of the figure's maps or planners
        what = (f"{'/'.join(kinds)} planner" if kinds else "planner") if not pi else "map"
        raise ValueError(f"figure {spec.name!r}: no {what} of this run selected")
    return mi, pi


def panel_grid(n: int, w: float = 5.0, h: float = 4.2, rows: int = 1):
    fig, axes = plt.subplots(rows, n, figsize=(w * n, h * rows), constrained_layout=True, squeeze=False)
    return fig, axes


def map_layer(grid) -> str | None:
    """The map layer worth showing: risk (chen2023) or terrain height (chu2024), else none."""
    if np.any(np.asarray(grid.risk) > 0):
        return "risk"
    if np.ptp(np.asarray(grid.height)) > 0:
        return "height"
    return None


def figure_title(spec: FigureSpec, default: str) -> str:
    return spec.params.get("title") or default


def figure_metric(run: RunData, spec: FigureSpec) -> str:
    m = spec.params.get("metric")
    if m is None:
        m = (run.config.stats.metrics or run.config.metrics)[0]
    return m


QUANTITIES: dict[str, tuple[str, str, float]] = {
    "success": ("success rate", "%", 100.0),
    # the threshold as a length ratio: "gap <= 10 % (%)" read as two percentages of one thing
    "accuracy": (f"accuracy: success with length <= {1 + ACCURACY_GAP:g} x optimum", "% of trials", 100.0),
    "length": ("path length", "m", 1.0),
    "tour_length": ("tour length", "TSPLIB distance", 1.0),
    "optimality_gap": ("gap to the exact optimum", "%", 100.0),
    "turns": ("turns", "count", 1.0),
    "sharp_turns": ("sharp turns (>= 45 deg)", "count", 1.0),
    "los_length": ("length after line-of-sight smoothing", "m", 1.0),
    "los_turns": ("turns after line-of-sight smoothing", "count", 1.0),
    "los_length_reduction": ("length saved by line-of-sight smoothing", "%", 100.0),
    "los_turns_reduction": ("turns saved by line-of-sight smoothing", "%", 100.0),
    "smoothness": ("smoothness 1 - mean |turn|/pi", "0-1", 1.0),
    "min_clearance": ("smallest clearance", "m", 1.0),
    "mean_clearance": ("mean clearance", "m", 1.0),
    "max_curvature": ("largest curvature", "1/m", 1.0),
    "hausdorff": ("Hausdorff distance to the A* path", "m", 1.0),
    "cost": ("the planner's own cost", "its cost units", 1.0),
    "converged_iteration": ("iteration of convergence", "count", 1.0),
    "converged_iteration_strict": ("iteration within 0.1 % of the final best", "count", 1.0),
    "turning_point": ("turning point, counted from 1", "count", 1.0),
    "optimum_iteration": ("iteration of the optimum, counted from 1", "count", 1.0),
    "collisions": ("collisions per episode", "count", 1.0),
    "active_contacts": ("active contacts per episode", "count", 1.0),
    "passive_contacts": ("passive contacts per episode", "count", 1.0),
    "time_s": ("arrival time", "s", 1.0),
    "rmse": ("tracking RMSE", "m", 1.0),
    "energy": ("energy proxy", "J", 1.0),
    "path_length": ("executed path length", "m", 1.0),
    "recoveries": ("control steps without a feasible sample", "count", 1.0),
    "replans": ("re-plans per episode", "count", 1.0),
    "plan_time_s": ("planning wall time per trial", "s", 1.0),
    "step_time_s": ("wall time per control step", "s", 1.0),
}
"""Metric -> (quantity, unit, scale) of a figure axis: values are drawn times ``scale`` (fractions as %), and
the axis reads ``quantity (unit)``; every metric of `METRICS` has an entry."""


def metric_label(metric: str) -> str:
    """The axis label of ``metric``: its quantity and, in parentheses, its unit (``%`` for fractions)."""
    q = QUANTITIES.get(metric)
    if q is None:
        unit = METRICS[metric].unit
        return f"{metric} ({unit or 'dimensionless'})"
    return f"{q[0]} ({q[1]})"


def metric_scale(metric: str) -> float:
    """The factor a figure multiplies ``metric``'s values by (100 for fractions drawn in %)."""
    q = QUANTITIES.get(metric)
    return q[2] if q is not None else 1.0


def need_trials(run: RunData) -> dict:
    if run.trials is None:
        raise FileNotFoundError(f"{run.run_dir}/trials.csv is missing: the run has not finished")
    return run.trials


def scenario_of(run: RunData, spec: FigureSpec, maps: Sequence[int]) -> int:
    """The figure's ``scenario`` (default 0), checked against each of ``maps``' scenarios (the config cannot
    always tell: scen filters and ``--quick`` counts keep fewer)."""
    sc = int(spec.params.get("scenario", 0))
    for m in maps:
        n = len(run.prep.maps[m].starts)
        if sc >= n:
            quick = " in this --quick run" if run.config.is_quick else ""
            raise ValueError(f"figure {spec.name!r}: scenario {sc} is past map {run.prep.maps[m].spec.name!r}'s "
                             f"{n} scenario{'s' if n > 1 else ''}{quick} (0..{n - 1})")
    return sc


def scenario_seed(run: RunData, spec: FigureSpec, maps: Sequence[int] = ()) -> tuple[int, int, int]:
    """(scenario, seed value, seed column) of a per-trial figure (defaults: scenario 0, the first seed)."""
    seeds = run.config.seeds
    sc = scenario_of(run, spec, maps)
    seed = int(spec.params.get("seed", seeds[0]))
    if seed not in seeds:
        raise ValueError(f"figure {spec.name!r}: seed {seed} is not one of the run's seeds {list(seeds)}")
    return sc, seed, seeds.index(seed)


def cell_path_m(path: np.ndarray, n: int, grid) -> np.ndarray:
    """The first ``n`` cell-coordinate points of ``path`` -> ``f64[n, 2]`` world metres (cell centres, the map's
    origin included: `GridMap.centre`)."""
    return grid.centre(np.asarray(path[:n], np.float64))


def trial_obstacles(run: RunData, m: int, p: int, sc: int, seed: int):
    """The trial's `MovingObstacles` (the runner's own per-trial draw), or None."""
    from jaxplan.experiments.execute import obstacle_fn

    fn = obstacle_fn(run.prep.maps[m], m, run.config.planners[p], np.asarray([sc]))
    return None if fn is None else fn(0, seed)


def disc_positions(obs, times: np.ndarray) -> np.ndarray:
    """``f64[len(times), M, 2]`` disc centres (m) at ``times`` (s)."""
    from jaxplan.nav import trajectories

    return np.asarray(trajectories(obs, np.asarray(times, np.float32)), np.float64)  # one vmapped call
