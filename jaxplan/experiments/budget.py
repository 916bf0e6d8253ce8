"""The memory guard of an experiment: every chunk's batch and the run's trials are checked before any work.

A chunk runs ``chunk`` scenarios × every seed as one compiled call (`jaxplan.experiments.execute`),
so its memory grows with seeds × scenarios; a config that asks for more than fits must fail at once,
with the largest size that fits, not after hours of earlier chunks (or as the kernel's kill). Before
the run folder is touched, `check_experiment` estimates:

* each (map, planner) chunk: a plan chunk with `jaxplan.aco.plan_memory` (the colony's working memory,
  the estimate `jaxplan.plan_batch` guards itself with) plus the host's path metrics; a navigate chunk
  with its global plans and `jaxplan.scale.episode_memory`; a TSP chunk with `jaxplan.scale.tsp_memory`
  over its seeds;
* the whole run's trials: ``trials.csv`` merged in memory and read back for the statistics.

Each is checked against `jaxplan.scale.memory_limit` (``$JAXPLAN_MEMORY_LIMIT``, default 80 % of the
available memory) by `jaxplan.scale.check_memory`; a refusal is a `jaxplan.scale.MemoryLimitError`
naming the chunk, the largest number of runs that fits, and the knobs (``--chunk``, the largest seed count, and
when a colony's single run does not fit, the largest ant count).
"""

from __future__ import annotations

from typing import Any, Mapping

from jaxplan.experiments.prepare import Prepared, trial_columns
from jaxplan.scale import Knob, MemoryEstimate, check_memory, episode_memory, memory_limit, table_memory, tsp_memory

__all__ = ["check_experiment", "chunk_memory", "TRIAL_BYTES"]

TRIAL_BYTES = 400
"""Host bytes per trial beside its columns: its row of ``trials.csv`` (merged in memory) and the statistics'
per-trial bookkeeping."""
_COLUMN_BYTES = 80  # one value of a trial read back for the statistics (a Python float or string and its slot)
_METRIC_BYTES = 72  # per path point of a plan trial: int64 and int32 paths, float64 metric temporaries


def _overrides(pc) -> dict:
    return {k: tuple(v) if isinstance(v, tuple) else v for k, v in pc.overrides.items()}


def _path_cells(grid, overrides: dict) -> int:
    """Points of a colony path (``max_steps + 1``; the default cap is 4·(H + W))."""
    steps = overrides.get("max_steps") or 4 * (grid.shape[0] + grid.shape[1])
    return int(steps) + 1


def _chunk_scenarios(prep: Prepared, m: int, p: int) -> int:
    """Scenarios of one compiled call: a colony or navigate chunk is padded to the full chunk size."""
    from jaxplan.aco import COLONIES

    cfg, pc = prep.config, prep.config.planners[p]
    if pc.kind == "tsp":
        return 1
    padded = pc.kind == "navigate" or pc.name in COLONIES
    return cfg.chunk if padded else min(cfg.chunk, len(prep.maps[m].starts))


def chunk_memory(prep: Prepared, m: int, p: int, extra: Mapping[str, Any] | None = None) -> MemoryEstimate:
    """Estimated working memory (bytes) of one chunk of planner ``p`` on map (or instance) ``m`` (with its
    overrides and ``extra`` ones on top: a refusal's "what if fewer ants")."""
    from jaxplan.aco import COLONIES, plan_memory

    cfg = prep.config
    mw, pc = prep.maps[m], cfg.planners[p]
    R = len(cfg.seeds)
    if pc.kind == "tsp":
        from jaxplan.aco import resolve_tsp

        q = resolve_tsp(pc.name, {**_overrides(pc), **(extra or {})})
        return tsp_memory(int(mw.problem.n), int(q.get("colonies", 1)), int(q["ants"]), int(q["iterations"]), R,
                          local_search=q["local_search"] == "2opt")
    runs = _chunk_scenarios(prep, m, p) * R
    if pc.kind == "navigate" and pc.team is not None:
        runs *= int(pc.team.robots)  # a team trial is N robot episodes (and N global plans)
    ov = {**_overrides(pc), **(extra or {})}
    if pc.kind == "plan":
        est = plan_memory(mw.grid, pc.name, runs, **ov)
        host = runs * _path_cells(mw.grid, ov) * _METRIC_BYTES if pc.name in COLONIES else 0
        return MemoryEstimate(est.total + host, {**est.parts, "path metrics": host}, runs,
                              est.per_run + host / max(runs, 1))
    from jaxplan.experiments.config import nav_config

    nav, _ = nav_config(pc)
    glob = pc.global_planner
    plans = plan_memory(mw.grid, glob, runs, **ov) if glob in COLONIES else None
    ep = episode_memory(runs, nav.steps, nav.dwa.samples, rollout_steps=nav.dwa.steps,
                        discs=pc.obstacles.n if pc.obstacles else 0, map_cells=mw.grid.n_cells)
    parts = {**ep.parts, **({"global plans": plans.total} if plans is not None else {})}
    total = ep.total + (plans.total if plans is not None else 0)
    return MemoryEstimate(total, parts, runs, ep.per_run + (plans.per_run if plans is not None else 0))


def _ants_knob(prep: Prepared, m: int, p: int) -> Knob | None:
    """A colony chunk's ant count as the refusal's knob (None for a planner without ants, and navigation)."""
    from jaxplan.aco import COLONIES, resolve_tsp
    from jaxplan.registry import resolve

    pc = prep.config.planners[p]
    if pc.kind == "tsp":
        ants = resolve_tsp(pc.name, _overrides(pc))["ants"]
    elif pc.kind == "plan" and pc.name in COLONIES:
        ants = resolve(pc.name, _overrides(pc))[1]["ants"]
    else:
        return None
    return Knob("ants", int(ants), lambda n: chunk_memory(prep, m, p, {"ants": n}))


def check_experiment(prep: Prepared, limit: int | None = None) -> None:
    """Refuses an experiment whose chunks or trials would not fit in memory, before any work.

    Raises:
      MemoryLimitError: naming the chunk (map × planner) or the trial count, and what fits.
    """
    cfg = prep.config
    R = len(cfg.seeds)
    limit = memory_limit() if limit is None else int(limit)
    seen = set()
    for u in prep.units:
        if (u.m, u.p) in seen:
            continue
        seen.add((u.m, u.p))
        mw, pc = prep.maps[u.m], cfg.planners[u.p]
        est = chunk_memory(prep, u.m, u.p)
        n = _chunk_scenarios(prep, u.m, u.p)
        what = f"a chunk of planner {pc.label!r} on {mw.spec.name!r} ({n} scenario{'s' * (n != 1)} x {R} seeds)"
        fits = est.largest_batch(limit)
        advice = (f"With {R} seeds at most {fits // R} scenarios per chunk fit: lower --chunk (now {cfg.chunk})"
                  if pc.kind != "tsp" and fits >= R else
                  f"Use at most {fits} seeds (now {R}; a chunk runs every seed at once)"
                  + (" with --chunk 1" if pc.kind != "tsp" else ""))
        check_memory(est, what, limit=limit, unit="runs (scenarios x seeds)", advice=advice,
                     knob=_ants_knob(prep, u.m, u.p),
                     single="Use fewer samples or steps of the local planner" if pc.kind == "navigate" else "")
    trials = prep.trials
    per = TRIAL_BYTES + _COLUMN_BYTES * len(trial_columns(cfg))
    check_memory(table_memory(trials, {"trials.csv and its statistics": per}),
                 f"experiment {cfg.name!r} ({trials} trials: scenarios x seeds x planners)", limit=limit,
                 unit="trials", advice="Use fewer seeds, scenarios or planners")
