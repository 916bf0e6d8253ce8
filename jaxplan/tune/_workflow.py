"""The tuning workflow: progress, a CSV log per generation, orbax checkpoints, exact resume, best weights, figure.

`tune_loop` runs one `Strategy` on one `Objective` for G generations. Generation g draws
its key as ``fold_in(key(seed), g)`` — a function of (seed, g) only — so a run that is
killed and resumed from its last checkpoint replays exactly the generations an
uninterrupted run would (same populations, same fitness bits, same final state).

Run folder ``OUT/NAME`` (``OUT/NAME-quick`` for quick runs)::

    config.toml               the config, verbatim (run_tuning)
    generations.csv           one row per generation: evaluations so far, best so far, the
                              generation's best / mean (finite values) / worst finite, how many
                              fitness values were NaN/inf (counted, then treated as the worst),
                              and the best-so-far weights by name; deterministic (no wall times)
    timings.csv               wall-clock seconds of each generation's compiled evaluation
    checkpoints/manifest.json the commit log: fingerprint, last checkpointed generation, the rows so far, and the
                              SHA-256 of each kept checkpoint's state
    checkpoints/gen_NNNNN/    the strategy state after generation NNNNN (orbax), every k generations (the last two
                              are kept)
    .lock                     held by the process that works in the folder (`jaxplan.core.io.folder_lock`)
    summary.json              defaults vs best weights on the train and held-out test sets, the
                              seed-to-seed spread (sd over seeds of the per-seed mean cost; null with
                              one seed), NaN count; strict JSON (a NaN or inf number is written null)
    best.toml                 the best weights as a [[planners]] entry for `jaxplan run`, with the config's own
                              overrides (never a quick run's smaller ants or iterations)
    convergence.png           best-so-far and generation mean against evaluations

A checkpoint commits in two steps — orbax writes the state, then the manifest (temporary
file, fsync, rename: `jaxplan.core.io.atomic_write`) names it — so a process
killed at any instant leaves at worst a state the manifest does not name, and the resume
recomputes those generations. A resume checks the state it reads against the SHA-256 the manifest
holds; a checkpoint that is missing, truncated or changed is skipped for the newest intact one
before it (the generations after it are recomputed, to the same bits), and a damaged manifest
starts the run afresh — a note on stderr says which. Before anything, `run_tuning` checks that a
generation's population fits in memory (`Objective.check_population`) and locks the run folder
against a second process.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import shutil
import sys
import time
from pathlib import Path
from typing import Any, Callable, Mapping

import jax
import jax.numpy as jnp
import numpy as np

from jaxplan.core.io import atomic_write, confined, folder_lock
from jaxplan.core.progress import ProgressBar
from jaxplan.experiments import CheckpointError, RunFolderError
from jaxplan.tune._base import Strategy, sanitize
from jaxplan.tune._objective import Objective, Split
from jaxplan.tune._strategies import make_strategy

__all__ = ["tune_loop", "run_tuning", "TuneResult", "fragment_toml", "plot_tuning"]

MANIFEST = "manifest.json"


class TuneResult(dict):
    """``{"state", "rows", "best_x", "best_f", "n_bad", "evaluations", "resumed_from"}`` of a `tune_loop`."""


def _columns(names) -> list[str]:
    return ["generation", "evaluations", "best", "gen_best", "gen_mean", "gen_worst", "n_bad"] + list(names)


def _csv(rows: list[dict], names) -> bytes:
    cols = _columns(names)
    buf = io.StringIO()
    buf.write(",".join(cols) + "\n")
    for r in rows:
        buf.write(",".join(repr(r[c]) if isinstance(r[c], float) else str(r[c]) for c in cols) + "\n")
    return buf.getvalue().encode()


def _state_digest(data: dict) -> str:
    """SHA-256 of a stored state's leaves (names, dtypes, shapes and bytes)."""
    h = hashlib.sha256()
    for k in sorted(data):
        a = np.ascontiguousarray(np.asarray(data[k]))
        h.update(f"{k}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _save_state(path: Path, state) -> str:
    """Saves ``state`` with orbax; returns its `_state_digest`."""
    import orbax.checkpoint as ocp

    leaves = jax.tree_util.tree_leaves(state)
    data = {}
    for i, a in enumerate(leaves):
        a = jnp.asarray(a)
        if jnp.issubdtype(a.dtype, jax.dtypes.prng_key):
            a = jax.random.key_data(a)  # typed keys are stored as their raw data
        data[f"leaf_{i:04d}"] = np.asarray(a)
    try:
        ocp.PyTreeCheckpointer().save(path.resolve(), data, force=True)
    except OSError:
        raise
    except Exception as e:  # noqa: BLE001 - orbax's and tensorstore's own errors: one clear message
        raise CheckpointError(f"cannot save the tuning checkpoint {path.resolve()}: {type(e).__name__}; check the "
                              f"disk, then run the same command to resume") from e
    return _state_digest(data)


def _load_state(path: Path, template, digest: str | None = None):
    """The state saved at ``path`` (checked against ``digest`` when given).

    Raises:
      ValueError: the checkpoint is missing, unreadable, of another shape or fails its digest.
    """
    import orbax.checkpoint as ocp

    if not path.is_dir():
        raise ValueError("missing")
    try:
        data = ocp.PyTreeCheckpointer().restore(path.resolve())
    except Exception as e:  # noqa: BLE001 - orbax's, tensorstore's and JSON errors of a damaged checkpoint
        raise ValueError(f"unreadable ({type(e).__name__})") from None
    if digest is not None and _state_digest(data) != digest:
        raise ValueError("fails its SHA-256 check")
    leaves, treedef = jax.tree_util.tree_flatten(template)
    if set(data) != {f"leaf_{i:04d}" for i in range(len(leaves))}:
        raise ValueError("holds another state")
    out = []
    for i, t in enumerate(leaves):
        a = np.asarray(data[f"leaf_{i:04d}"])
        t = jnp.asarray(t)
        out.append(jax.random.wrap_key_data(a) if jnp.issubdtype(t.dtype, jax.dtypes.prng_key)
                   else jnp.asarray(a, t.dtype))
    return jax.tree_util.tree_unflatten(treedef, out)


class _Progress:
    """The tuning bar: generations done of ``total``, the best fitness so far, elapsed and time left
    (`jaxplan.core.progress`; drawn only on a terminal). The first generation includes compiling the objective."""

    def __init__(self, name: str, total: int, enabled: bool, done: int = 0):
        self.name = name
        self.bar = ProgressBar(f"{name}: generation {done + 1} (compiling)", total, done=done, unit="generations",
                               enabled=enabled)

    def update(self, row: dict, eval_s: float) -> None:
        bad = f", {row['n_bad']} NaN/inf" if row["n_bad"] else ""
        text = f"{self.name}: best {row['best']:.5g} (mean {row['gen_mean']:.4g}{bad})"
        self.bar.update(row["generation"], description=text)

    def close(self) -> None:
        self.bar.close()


def tune_loop(objective: Objective, strategy: Strategy, generations: int, run_dir: str | Path, *, seed: int = 0,
              checkpoint_every: int = 2, resume: bool = True, progress: bool = True, fingerprint: str = "",
              x0: Any = "defaults", callback: Callable[[int, dict], None] | None = None) -> TuneResult:
    """Runs ``generations`` generations of ``strategy`` on the training split of ``objective``.

    Args:
      objective: the `Objective` (each generation's population is one compiled call).
      strategy: a `Strategy`.
      generations: G >= 1.
      run_dir: the folder for generations.csv, timings.csv and checkpoints/.
      seed: PRNG seed; generation g uses ``fold_in(key(seed), g)``.
      checkpoint_every: k >= 1; a checkpoint after every k-th generation and after the last.
      resume: continue from the folder's last checkpoint (same fingerprint) instead of starting over.
      fingerprint: identifies the run; a folder holding another run's checkpoints is refused.
      x0: the strategies' starting point: ``"defaults"`` (the paper's weights), None (box centre) or ``f32[D]``.
      callback: ``callback(generation, row)`` after each generation (before its checkpoint).

    Returns:
      `TuneResult`.

    Raises:
      RunFolderError: the folder holds a different run's checkpoints (and ``resume`` is True).
    """
    if not isinstance(generations, int) or generations < 1:
        raise ValueError(f"generations must be a positive integer, got {generations!r}")
    if not isinstance(checkpoint_every, int) or checkpoint_every < 1:
        raise ValueError(f"checkpoint_every must be a positive integer, got {checkpoint_every!r}")
    run_dir = Path(run_dir)
    ck = run_dir / "checkpoints"
    b = objective.bounds
    fp = hashlib.sha256(f"{fingerprint}|{strategy.name}|{strategy.population_size}|{generations}|{seed}|"
                        f"{b.names}|{b.low.tolist()}|{b.high.tolist()}".encode()).hexdigest()
    root = jax.random.key(seed)
    start = x0 if not (isinstance(x0, str) and x0 == "defaults") else objective.defaults
    state = strategy.init(jax.random.fold_in(root, 2**31 - 1), b, start)
    rows: list[dict] = []
    times: list[str] = []
    g0 = 0
    manifest_path = ck / MANIFEST
    digests: dict[str, str] = {}
    man = _read_tune_manifest(manifest_path, run_dir) if resume else None
    if man is not None:
        if man.get("fingerprint") != fp:
            raise RunFolderError(f"{run_dir} holds the checkpoints of a different tuning run (config, strategy, "
                                 "space or seed changed); delete that folder, pass another out folder or resume=False")
        state, g0 = _resume_state(ck, man, state, run_dir.name)
        rows = man["rows"][:g0]
        times = man.get("times", [])[:g0]
        digests = {k: v for k, v in man.get("digests", {}).items() if int(k) <= g0}
    elif ck.exists():
        shutil.rmtree(ck)
    for p in ck.glob("*.orbax-checkpoint-tmp*") if ck.exists() else ():
        shutil.rmtree(p, ignore_errors=True)
    ck.mkdir(parents=True, exist_ok=True)
    ask, tell = jax.jit(strategy.ask), jax.jit(strategy.tell)
    prog = _Progress(run_dir.name, generations, progress, g0)
    P = strategy.population_size
    n_bad_total = sum(r["n_bad"] for r in rows)

    def commit(g: int) -> None:
        digests[str(g)] = _save_state(ck / f"gen_{g:05d}", state)
        for k in [k for k in digests if int(k) < g - checkpoint_every]:
            del digests[k]
        man = {"fingerprint": fp, "generation": g, "rows": rows, "times": times, "digests": digests}
        atomic_write(manifest_path, json.dumps(man, indent=1).encode())
        for old in ck.glob("gen_*"):  # keep the last two checkpoints
            if old.is_dir() and old.name[4:].isdigit() and int(old.name[4:]) < g - checkpoint_every:
                shutil.rmtree(old, ignore_errors=True)

    try:
        for g in range(g0, generations):
            pop = ask(jax.random.fold_in(root, g), state)
            ev = objective.evaluate(pop, "train")
            fit, n_bad = sanitize(jnp.asarray(ev.fitness))
            state = tell(state, pop, jnp.asarray(ev.fitness))
            raw = np.asarray(ev.fitness, np.float64)
            finite = raw[np.isfinite(raw)]
            n_bad_total += int(n_bad)
            bx = np.asarray(state.best_x, np.float64)
            row = {"generation": g + 1, "evaluations": (g + 1) * P, "best": float(state.best_f),
                   "gen_best": float(finite.min()) if finite.size else math.nan,
                   "gen_mean": float(finite.mean()) if finite.size else math.nan,
                   "gen_worst": float(finite.max()) if finite.size else math.nan, "n_bad": int(n_bad),
                   **{n: float(v) for n, v in zip(b.names, bx, strict=True)}}
            rows.append(row)
            times.append(f"{g + 1},{ev.time_s!r},{ev.compile_s!r}")
            atomic_write(run_dir / "generations.csv", _csv(rows, b.names))
            atomic_write(run_dir / "timings.csv", ("generation,eval_s,compile_s\n" + "\n".join(times) + "\n").encode())
            prog.update(row, ev.time_s)
            if callback is not None:
                callback(g + 1, row)
            if (g + 1) % checkpoint_every == 0 or g + 1 == generations:
                commit(g + 1)
    finally:
        prog.close()
    return TuneResult(state=state, rows=rows, best_x=np.asarray(state.best_x), best_f=float(state.best_f),
                      n_bad=n_bad_total, evaluations=generations * P, resumed_from=g0)


def _note(name: str, text: str) -> None:
    print(f"{name}: {text}", file=sys.stderr, flush=True)


def _read_tune_manifest(path: Path, run_dir: Path) -> dict | None:
    """The tuning manifest, or None when there is none or it is damaged (then the run starts afresh, noted)."""
    if not path.is_file():
        return None
    try:
        man = json.loads(path.read_bytes().decode("utf-8"))
        ok = isinstance(man, dict) and isinstance(man.get("generation"), int) and isinstance(man.get("rows"), list) \
            and isinstance(man.get("fingerprint"), str) and len(man["rows"]) >= man["generation"] >= 0
    except (OSError, ValueError):
        ok = False
    if not ok:
        _note(run_dir.name, f"{path} is damaged: starting afresh (the generations come out the same)")
        return None
    return man


def _resume_state(ck: Path, man: dict, template, name: str):
    """(state, generation) of the newest intact checkpoint at or before the manifest's generation (a missing,
    unreadable or changed one is skipped, with a note); (template, 0) if none is intact."""
    g0 = int(man["generation"])
    if g0 == 0:
        return template, 0
    digests = man.get("digests", {})
    found = sorted((int(p.name[4:]) for p in ck.glob("gen_*") if p.name[4:].isdigit() and int(p.name[4:]) <= g0),
                   reverse=True)
    for g in [g0] + [g for g in found if g != g0]:
        try:
            return _load_state(ck / f"gen_{g:05d}", template, digests.get(str(g))), g
        except ValueError as e:
            _note(name, f"checkpoint gen_{g:05d} is {e}; falling back to an earlier one")
    _note(name, "no intact checkpoint: starting from generation 0")
    return template, 0


# ---------------------------------------------------------------------------------------------
# Outputs


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return repr(float(v))
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {v!r} to TOML")


def _inline(d: dict) -> str:
    return "{ " + ", ".join(f"{k} = {_toml_value(v)}" for k, v in d.items()) + " }"


def fragment_toml(objective: Objective, x, *, label: str, overrides: dict | None = None, pipeline: str | None = None,
                  comment: str = "") -> str:
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
        return (f"{head}[[planners]]\nlabel = {_toml_value(label)}\nkind = \"plan\"\n"
                f"name = {_toml_value(objective.planner)}\noverrides = {_inline(ov)}\n")
    # a navigation objective (`nav_objective`) names its local planner and pipeline
    local = "mppi" if objective.kind == "mppi" or getattr(objective, "local", "") == "mppi" else "dwa"
    pipeline = pipeline or getattr(objective, "pipeline", "") or f"astar_kng_{local}"
    body = (f"{head}[[planners]]\nlabel = {_toml_value(label)}\nkind = \"navigate\"\n"
            f"name = {_toml_value(pipeline)}\nparams = {_inline(p)}\n")
    if overrides:
        body += f"{local} = {_inline(dict(overrides))}\n"
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


def _splits(cfg, grid, starts, goals, optimal) -> tuple[Split, Split]:
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


def _nav_objective(cfg) -> Objective:
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


def build_objective(cfg) -> Objective:
    """The `Objective` of a `TuneConfig` (map loaded, scenarios chosen and split)."""
    from jaxplan.experiments import load_map_spec, spec_scenarios
    from jaxplan.tune._objective import aco_objective, dwa_objective, mppi_objective

    if cfg.kind == "nav":
        return _nav_objective(cfg)
    grid, s0, g0, _ = load_map_spec(cfg.map)
    starts, goals, optimal, _ = spec_scenarios(cfg.map, grid, s0, g0)
    train, test = _splits(cfg, grid, starts, goals, optimal)
    space = {k: (list(v) if isinstance(v, list) else tuple(v)) for k, v in cfg.space.items()}
    if cfg.kind == "aco":
        return aco_objective(grid, train, test, cfg.planner, space, dict(cfg.weights), dict(cfg.overrides),
                             name=cfg.name)
    if cfg.kind == "mppi":
        return mppi_objective(grid, train, test, space, dict(cfg.weights), dict(cfg.overrides), max_time=cfg.max_time,
                              n_discs=cfg.discs, name=cfg.name)
    return dwa_objective(grid, train, test, cfg.planner, space, dict(cfg.weights), dict(cfg.overrides),
                         max_time=cfg.max_time, n_discs=cfg.discs, name=cfg.name)


def compare(objective: Objective, x, split: str, population: int = 2) -> dict:
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


def _json_safe(v: Any) -> Any:
    """``v`` with every NaN or infinite float as None: JSON has no NaN (``json.dumps`` would write invalid JSON)."""
    if isinstance(v, float):
        return v if math.isfinite(v) else None
    if isinstance(v, dict):
        return {k: _json_safe(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_json_safe(x) for x in v]
    return v


def run_tuning(config_path, out="runs", quick: bool = False, data_dir=None, progress: bool = True,
               resume: bool = True) -> Path:
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
    from jaxplan.tune._config import apply_tune_quick, load_tune_config

    cfg = load_tune_config(config_path, data_dir=data_dir)
    own = dict(cfg.overrides)  # before [tune.quick] replaces some of them
    if quick:
        cfg = apply_tune_quick(cfg)
    objective = build_objective(cfg)
    objective.check_population(cfg.population)  # before the strategy allocates its population
    objective.check_population(2, "test")
    run_dir = confined(out, cfg.name + ("-quick" if cfg.is_quick else ""))
    run_dir.mkdir(parents=True, exist_ok=True)
    with folder_lock(run_dir):
        return _run_tuning(cfg, objective, run_dir, progress, resume, own)


def _best_comment(cfg, evaluations: int, test: dict, own: Mapping[str, Any]) -> str:
    """The comment above best.toml's entry: where the weights come from and their held-out result; for a quick
    run, that the entry keeps the config's own settings and which smoke-run settings the search used instead."""
    out = (f"best weights of tuning run {cfg.name} ({cfg.strategy}, {evaluations} evaluations)\n"
           f"held-out test objective: tuned {test['tuned']['objective']:.6g} ± {_sd_text(test['tuned']['seed_sd'])}, "
           f"{'defaults' if cfg.kind == 'mppi' else 'paper defaults'} {test['defaults']['objective']:.6g} ± "
           f"{_sd_text(test['defaults']['seed_sd'])} "
           f"(sd over {len(cfg.test_seeds)} seed{'s' if len(cfg.test_seeds) != 1 else ''})")
    changed = {k: v for k, v in cfg.overrides.items() if k not in own or own[k] != v}
    if cfg.is_quick:
        searched = f" with {_inline(changed)}" if changed else ""
        out += (f"\na quick (smoke) run: the search ran{searched}; the entry keeps the config's own settings, "
                "so rerun without --quick for weights worth using")
    return out


def _run_tuning(cfg, objective: Objective, run_dir: Path, progress: bool, resume: bool,
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
    best = res["best_x"]
    summary = {
        "name": cfg.name, "kind": cfg.kind, "planner": cfg.planner, "strategy": cfg.strategy,
        "population": cfg.population, "generations": cfg.generations, "evaluations": res["evaluations"],
        "resumed_from_generation": res["resumed_from"], "n_bad": res["n_bad"],
        "space": {n: [float(lo), float(hi)] for n, lo, hi in zip(objective.bounds.names, objective.bounds.low,
                                                                    objective.bounds.high, strict=True)},
        "defaults": objective.params(objective.defaults), "best": objective.params(best),
        "best_train_during_search": res["best_f"],
        "train": compare(objective, best, "train", cfg.population), "test": compare(objective, best, "test"),
        "weights": dict(cfg.weights), "wall_s_this_session": wall,
    }
    atomic_write(run_dir / "summary.json", json.dumps(_json_safe(summary), indent=1, allow_nan=False).encode())
    comment = _best_comment(cfg, res["evaluations"], summary["test"], own)
    frag = fragment_toml(objective, best, label=f"{cfg.planner}-tuned", overrides=own,
                         pipeline=cfg.pipeline, comment=comment)
    atomic_write(run_dir / "best.toml", frag.encode())
    plot_tuning({cfg.strategy: res["rows"]}, run_dir / "convergence.png", title=f"{cfg.name}: {cfg.strategy}")
    return run_dir
