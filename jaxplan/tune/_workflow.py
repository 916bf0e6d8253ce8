"""The tuning workflow of a config (`run_tuning`): the objective built from the config, `tune_loop`, the summary on
the held-out split, the best weights as a ``[[planners]]`` entry, the convergence figure.

Run folder ``OUT/NAME`` (``OUT/NAME-quick`` for quick runs)::

    config.toml          the config, verbatim
    generations.csv      one row per generation, timings.csv, checkpoints/ and .lock: `tune_loop`'s
                         (`jaxplan.tune._loop`: exact resume from the last checkpoint)
    summary.json         defaults vs best weights on the train and held-out test sets, the
                         seed-to-seed spread (sd over seeds of the per-seed mean cost; null with
                         one seed), NaN count; strict JSON (a NaN or inf number is written null)
    best.toml            the best weights as a [[planners]] entry for `jaxplan run`, with the config's
                         own overrides (never a quick run's smaller ants or iterations)
    convergence.png      best-so-far and generation mean against evaluations

Before anything, `run_tuning` checks that a generation's population fits in memory (`Objective.check_population`)
and locks the run folder against a second process (`jaxplan.core.run_folder.RunFolder.lock`).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping

import numpy as np

from jaxplan.core import toml
from jaxplan.core.io import atomic_write, confined
from jaxplan.core.run_folder import RunFolder
from jaxplan.tune._loop import tune_loop
from jaxplan.tune._objective import Objective, Split
from jaxplan.tune._strategies import make_strategy

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from jaxplan.grid import GridMap
    from jaxplan.tune._config import TuneConfig

__all__ = ["run_tuning", "fragment_toml", "plot_tuning", "build_objective", "compare"]


# ---------------------------------------------------------------------------------------------
# Outputs


def fragment_toml(objective: Objective, x: ArrayLike, *, label: str, overrides: Mapping[str, Any] | None = None,
                  pipeline: str | None = None, comment: str = "") -> str:
    """A ``[[planners]]`` entry of an experiment config (`jaxplan run`) with the weights ``x [D]``.

    ACO: ``kind = "plan"``, the planner with ``overrides`` = its settings plus the tuned weights.
    DWA: ``kind = "navigate"``, ``pipeline`` with ``params`` = the tuned critic weights (and
    ``dwa`` = the DWAConfig settings the tuning used). MPPI and navigation objectives (`nav_objective`): the same
    with the MPPI params (``mppi`` = the MPPIConfig settings); a navigation objective's own pipeline by default.
    """
    p = objective.params(np.asarray(x))
    head = "".join(f"# {line}\n" for line in comment.splitlines())
    if objective.kind == "aco":
        ov = {**dict(overrides or {}), **p}
        return (f"{head}[[planners]]\nlabel = {toml.literal(label)}\nkind = \"plan\"\n"
                f"name = {toml.literal(objective.planner)}\noverrides = {toml.literal(ov)}\n")
    # a navigation objective (`nav_objective`) names its local planner and pipeline
    local = "mppi" if objective.kind == "mppi" or getattr(objective, "local", "") == "mppi" else "dwa"
    pipeline = pipeline or getattr(objective, "pipeline", "") or f"astar_kng_{local}"
    body = (f"{head}[[planners]]\nlabel = {toml.literal(label)}\nkind = \"navigate\"\n"
            f"name = {toml.literal(pipeline)}\nparams = {toml.literal(p)}\n")
    if overrides:
        body += f"{local} = {toml.literal(dict(overrides))}\n"
    return body


def plot_tuning(rows_by_label: dict[str, list[dict]], path: str | Path, title: str = "") -> list[str]:
    """Convergence figure: best-so-far (solid) and generation mean (dotted) against evaluations."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from jaxplan.experiments.plots import save_figure

    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for i, (label, rows) in enumerate(rows_by_label.items()):
        ev = [r["evaluations"] for r in rows]
        c = f"C{i % 10}"
        ax.plot(ev, [r["best"] for r in rows], "-", color=c, label=label)
        if len(rows_by_label) == 1:
            ax.plot(ev, [r["gen_mean"] for r in rows], ":", color=c, label=f"{label} (generation mean)")
    ax.set_xlabel("evaluations (weight vectors)")
    ax.set_ylabel("training objective (lower is better)")
    ax.set_title(title or "tuning convergence")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    out = save_figure(fig, str(path))
    plt.close(fig)
    return out


def split_scenarios(cfg: TuneConfig, grid: GridMap, starts: np.ndarray, goals: np.ndarray, optimal: np.ndarray
                    ) -> tuple[Split, Split]:
    """The training split (the first ``cfg.train_count`` scenarios, at least one fewer than there are) and the
    held-out split (the rest, at most ``cfg.test_count``), with the config's train and test seeds.

    Raises:
      ValueError: fewer than 2 scenarios.
    """
    n = len(starts)
    if n < 2:
        raise ValueError(f"a tuning run needs at least 2 scenarios (train and test), the map gave {n}")
    k = min(cfg.train_count, n - 1)
    te = slice(k, n if cfg.test_count is None else min(n, k + cfg.test_count))
    return (Split(starts[:k], goals[:k], optimal[:k], tuple(cfg.train_seeds)),
            Split(starts[te], goals[te], optimal[te], tuple(cfg.test_seeds)))


def _alternate(rows: np.ndarray, n_train: int, n_test: int | None) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """A map's selected rows (in their order) alternately train and held-out, until ``n_train`` train (the rest
    held-out, at most ``n_test``): both splits spread over the selection, as `spread_rows` does."""
    order = list(range(0, len(rows), 2)) + list(range(1, len(rows), 2))
    pick = set(order[:n_train])
    rest = [i for i in range(len(rows)) if i not in pick]
    test = rest if n_test is None else rest[:n_test]
    return tuple(int(rows[i]) for i in sorted(pick)), tuple(int(rows[i]) for i in test)


def _nav_objective(cfg: TuneConfig) -> Objective:
    """The `nav_objective` of a ``kind = "nav"`` config: every map's selected scen rows split alternately."""
    from jaxplan.experiments import load_map_spec, spec_scenarios
    from jaxplan.grid import load_scenarios
    from jaxplan.nav import NavConfig
    from jaxplan.tune._nav_objective import NavMap, nav_objective

    maps = []
    for spec in cfg.maps:
        grid, s0, g0, _ = load_map_spec(spec)
        _, _, _, rows = spec_scenarios(spec, grid, s0, g0)
        train, test = _alternate(rows, cfg.train_count, cfg.test_count)
        if not train or not test:
            raise ValueError(f"map {spec.name!r}: its {len(rows)} selected scenario rows leave no "
                             f"{'held-out' if train else 'train'} rows (train_count = {cfg.train_count})")
        scen = load_scenarios(spec.scen, grid)
        maps.append(NavMap(spec.name, grid, np.asarray(scen.starts), np.asarray(scen.goals), np.asarray(scen.optimal),
                           train, test))
    base = NavConfig()
    ov = dict(cfg.overrides)
    nav = base.replace(max_time=cfg.max_time, **({"mppi": base.mppi.replace(**ov)} if cfg.planner == "mppi" else
                                                 {"dwa": base.dwa.replace(**ov)}))
    space = {k: (list(v) if isinstance(v, list) else tuple(v)) for k, v in cfg.space.items()}
    return nav_objective(maps, cfg.train_seeds, cfg.test_seeds, cfg.planner, pipeline=cfg.pipeline,
                         walkers=cfg.walkers, n_walkers=cfg.walker_count, speed=cfg.walker_speed, space=space,
                         weights=dict(cfg.weights), config=nav, time_limit=cfg.time_limit, name=cfg.name)


def build_objective(cfg: TuneConfig) -> Objective:
    """The `Objective` of a `TuneConfig` (map loaded, scenarios chosen and split)."""
    from jaxplan.experiments import load_map_spec, spec_scenarios
    from jaxplan.tune._objective import aco_objective, dwa_objective, mppi_objective

    if cfg.kind == "nav":
        return _nav_objective(cfg)
    grid, s0, g0, _ = load_map_spec(cfg.map)
    starts, goals, optimal, _ = spec_scenarios(cfg.map, grid, s0, g0)
    train, test = split_scenarios(cfg, grid, starts, goals, optimal)
    space = {k: (list(v) if isinstance(v, list) else tuple(v)) for k, v in cfg.space.items()}
    if cfg.kind == "aco":
        return aco_objective(grid, train, test, cfg.planner, space, dict(cfg.weights), dict(cfg.overrides),
                             name=cfg.name)
    if cfg.kind == "mppi":
        return mppi_objective(grid, train, test, space, dict(cfg.weights), dict(cfg.overrides), max_time=cfg.max_time,
                              n_discs=cfg.discs, name=cfg.name)
    return dwa_objective(grid, train, test, cfg.planner, space, dict(cfg.weights), dict(cfg.overrides),
                         max_time=cfg.max_time, n_discs=cfg.discs, name=cfg.name)


def compare(objective: Objective, x: ArrayLike, split: str, population: int = 2) -> dict[str, Any]:
    """Defaults vs ``x`` on a split, in one compiled call: mean cost, seed-to-seed sd (nan with one seed), metric
    means.

    The two rows are padded to ``population`` rows (copies of ``x``), so that on the training
    split the tuning loop's compiled program is reused instead of compiling a new one."""
    rows = [objective.defaults, np.asarray(x, np.float32)]
    rows += [rows[1]] * max(0, population - 2)
    ev = objective.evaluate(np.stack(rows), split)
    # one seed has no spread: nan (shown as "–", as in the experiment tables), not a reassuring 0
    sd = ev.per_seed.std(axis=1, ddof=1) if ev.per_seed.shape[1] > 1 else np.full(len(rows), np.nan)
    out = {}
    for i, k in enumerate(("defaults", "tuned")):
        out[k] = {"objective": float(ev.fitness[i]), "seed_sd": float(sd[i]),
                  "per_seed": [float(v) for v in ev.per_seed[i]],
                  "metrics": {m: float(v[i]) for m, v in ev.metrics.items()}}
    out["improvement"] = out["defaults"]["objective"] - out["tuned"]["objective"]
    return out


def _sd_text(sd: float) -> str:
    """A seed-to-seed sd for a comment: ``–`` when there is none (fewer than two seeds)."""
    return f"{sd:.3g}" if math.isfinite(sd) else "–"


def json_safe(v: Any) -> Any:
    """``v`` with every NaN or infinite float as None: JSON has no NaN (``json.dumps`` would write invalid JSON)."""
    if isinstance(v, float):
        return v if math.isfinite(v) else None
    if isinstance(v, dict):
        return {k: json_safe(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [json_safe(x) for x in v]
    return v


def run_tuning(config_path: str | os.PathLike, out: str | os.PathLike = "runs", quick: bool = False,
               data_dir: str | os.PathLike | None = None, progress: bool = True, resume: bool = True) -> Path:
    """Runs the tuning config at ``config_path``; returns the run folder ``OUT/NAME`` (``NAME-quick``).

    Loads and validates the config (`jaxplan.tune._config`, `ConfigError` listing every problem),
    loads the map and scenarios, splits them into the training and held-out test sets, runs the
    configured strategy for the configured generations (one compiled call per generation,
    progress on stderr, generations.csv, orbax checkpoints every ``checkpoint_every``
    generations; with ``resume`` a folder with this run's checkpoints continues from the last
    one, exactly; without it the folder's checkpoints are discarded), then writes
    summary.json (defaults vs best on train and test with the seed-to-seed spread),
    best.toml (a ``[[planners]]`` entry `jaxplan run` accepts) and convergence.png.

    best.toml holds the tuned weights with the config's own ``overrides`` (its ants, iterations, DWA settings),
    also after a ``quick`` run: a smoke run's smaller settings are how it searched, not a setting to run with.
    """
    from jaxplan.tune._config import load_tune_config, quick_tune_config

    cfg = load_tune_config(config_path, data_dir=data_dir)
    own = dict(cfg.overrides)  # before [tune.quick] replaces some of them
    if quick:
        cfg = quick_tune_config(cfg)
    objective = build_objective(cfg)
    objective.check_population(cfg.population)  # before the strategy allocates its population
    objective.check_population(2, "test")
    run_dir = confined(out, cfg.name + ("-quick" if cfg.is_quick else ""))
    with RunFolder.lock(run_dir):
        return _run_tuning(cfg, objective, run_dir, progress, resume, own)


def _best_comment(cfg: TuneConfig, evaluations: int, test: dict, own: Mapping[str, Any]) -> str:
    """The comment above best.toml's entry: where the weights come from and their held-out result; for a quick
    run, that the entry keeps the config's own settings and which smoke-run settings the search used instead."""
    out = (f"best weights of tuning run {cfg.name} ({cfg.strategy}, {evaluations} evaluations)\n"
           f"held-out test objective: tuned {test['tuned']['objective']:.6g} ± {_sd_text(test['tuned']['seed_sd'])}, "
           f"{'defaults' if cfg.kind == 'mppi' else 'paper defaults'} {test['defaults']['objective']:.6g} ± "
           f"{_sd_text(test['defaults']['seed_sd'])} "
           f"(sd over {len(cfg.test_seeds)} seed{'s' if len(cfg.test_seeds) != 1 else ''})")
    changed = {k: v for k, v in cfg.overrides.items() if k not in own or own[k] != v}
    if cfg.is_quick:
        searched = f" with {toml.literal(changed)}" if changed else ""
        out += (f"\na quick (smoke) run: the search ran{searched}; the entry keeps the config's own settings, "
                "so rerun without --quick for weights worth using")
    return out


def _run_tuning(cfg: TuneConfig, objective: Objective, run_dir: Path, progress: bool, resume: bool,
                own: Mapping[str, Any] | None = None) -> Path:
    """The search and its outputs; ``own``: the config's overrides before ``[tune.quick]`` (best.toml's)."""
    own = dict(cfg.overrides) if own is None else dict(own)
    strategy = make_strategy(cfg.strategy, cfg.population, cfg.generations, **dict(cfg.options))
    fp = hashlib.sha256(cfg.text.encode() + (b"|quick" if cfg.is_quick else b"")).hexdigest()
    atomic_write(run_dir / "config.toml", cfg.text.encode())
    t0 = time.perf_counter()
    res = tune_loop(objective, strategy, cfg.generations, run_dir, seed=cfg.seed,
                    checkpoint_every=cfg.checkpoint_every, resume=resume, progress=progress, fingerprint=fp)
    wall = time.perf_counter() - t0
    best = res.best_x
    summary = {
        "name": cfg.name, "kind": cfg.kind, "planner": cfg.planner, "strategy": cfg.strategy,
        "population": cfg.population, "generations": cfg.generations, "evaluations": res.evaluations,
        "resumed_from_generation": res.resumed_from, "n_bad": res.n_bad,
        "space": {n: [float(lo), float(hi)] for n, lo, hi in zip(objective.bounds.names, objective.bounds.low,
                                                                    objective.bounds.high, strict=True)},
        "defaults": objective.params(objective.defaults), "best": objective.params(best),
        "best_train_during_search": res.best_f,
        "train": compare(objective, best, "train", cfg.population), "test": compare(objective, best, "test"),
        "weights": dict(cfg.weights), "wall_s_this_session": wall,
    }
    atomic_write(run_dir / "summary.json", json.dumps(json_safe(summary), indent=1, allow_nan=False).encode())
    comment = _best_comment(cfg, res.evaluations, summary["test"], own)
    frag = fragment_toml(objective, best, label=f"{cfg.planner}-tuned", overrides=own,
                         pipeline=cfg.pipeline, comment=comment)
    atomic_write(run_dir / "best.toml", frag.encode())
    plot_tuning({cfg.strategy: res.rows}, run_dir / "convergence.png", title=f"{cfg.name}: {cfg.strategy}")
    return run_dir
