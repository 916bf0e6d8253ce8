"""Running a study: every method once per tuner seed at the same counted budget, judged on held-out scenarios;
resumable, and shareable by workers.

The unit of work is one method with one tuner seed (`study_run`): `tune_loop` in ``runs/<method>-s<seed>/`` (its own
checkpoints: an interrupted run resumes exactly) on the counted objective (`CountedObjective`), then the held-out
score of its best-so-far weights after each generation (held-out evaluations are not charged to the budget; one
evaluation per distinct weight vector, cached in ``heldout.json``). It returns a
`jaxplan.core.run_folder.Payload` — the run's rows as CSV, its compile seconds and best weights — which the process
that holds the study folder commits (`STUDY_LAYOUT`); the results are always read back from there, checked against
their SHA-256, so a run computed here and one computed elsewhere are handled alike.

Study folder ``OUT/NAME`` (``NAME-quick``; a `jaxplan.core.run_folder.RunFolder`)::

    config.toml                  the study config, verbatim
    runs/<method>-s<seed>/       one `tune_loop` folder per method and tuner seed (checkpoints: exact resume),
                                 with counts.json (counted evaluations and wall seconds after each generation)
    checkpoints/manifest.json    the commit log of the finished runs (the study's fingerprint, one entry per run)
    checkpoints/runs/<method>-s<seed>.csv   a finished run: per generation the counted evaluations, wall seconds,
                                 training and held-out scores of the best-so-far weights, and those weights
    heldout.json                 held-out scores by weight vector (the cache; a worker's runs keep theirs in
                                 runs/<method>-s<seed>/heldout.json, read as part of it)
    worker-*.json                a worker's session (`run_study(only=...)`, ``--only``), until the page pass takes it in
    log.csv                      method, tuner_seed, generation, evaluations (counted), train_best,
                                 heldout_best (held-out score of the best-so-far weights), wall_s, weights
    summary.json                 per method: train and held-out scores over tuner seeds, 95 % intervals, wall time
                                 (with and without XLA compilation), counted evaluations; the defaults; the verdict
                                 (`jaxplan.tune.study.judge`)
    convergence.png              held-out score against evaluations, one line per method, ± sd band over tuner seeds
    best.toml                    the best weights as a ``[[planners]]`` entry (`jaxplan.tune.fragment_toml`)
    confirm.toml                 an experiment config: defaults vs tuned on fresh scenarios and seeds (`jaxplan run`)
    page.md                      the results page (also written to ``results/NAME.md`` with ``results``)
    sessions.json                each session's wall seconds, load averages and generations run (the page's time)
    confirm.md                   with ``confirm``: the confirmation run's report (the run itself: OUT/NAME_confirm)

Workers. With ``only`` (``--only``), a process runs some methods' runs alone, each under its run folder's lock and
with its held-out scores in that folder, and commits nothing: workers with disjoint methods share one study folder
(one per core, or per machine on a shared file system). A later call without ``only`` finds their runs done
(`tune_loop` resumes them at their last generation), reads their held-out scores, commits the runs and writes the
page.

On a Ray cluster (``executor``, ``--ray``; `jaxplan.core.executor`), each run that the study folder lacks is a Ray
task (`study_task`): the worker runs it in a scratch folder of its own (the unit of resume is then the whole run, not
a generation) on the study's objective, which travels with the task (maps and scenarios loaded here), and returns
the `Payload` and the held-out scores it computed; this process commits the runs as they finish and takes the scores
into ``heldout.json``. The log is the same bytes as a local study's (its wall-time column aside).
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Callable, Iterator, Mapping, Sequence

import numpy as np

from jaxplan.core.executor import Executor, executor_from
from jaxplan.core.io import atomic_write, confined
from jaxplan.core.run_folder import Layout, Payload, RunFolder
from jaxplan.tune._base import Strategy
from jaxplan.tune._objective import Objective
from jaxplan.tune._strategies import STRATEGY_SPECS, make_strategy
from jaxplan.tune._workflow import fragment_toml, json_safe, tune_loop
from jaxplan.tune.study import judge
from jaxplan.tune.study.config import StudyConfig, load_study_config
from jaxplan.tune.study.confirm import confirm_config, run_confirmation
from jaxplan.tune.study.objective import CountedObjective, build_study_objective
from jaxplan.tune.study.page import figure, page

__all__ = ["STUDY_LAYOUT", "HELDOUT_FILE", "run_study", "study_run", "study_task", "study_fingerprint"]

STUDY_LAYOUT = Layout(table="runs", suffix=".csv", arrays="arrays", noun="run",
                      refusal="a different study (its config changed); delete that folder, pass another --out or "
                              "--no-resume (resume=False)")
"""Where a study folder keeps its finished runs (`jaxplan.core.run_folder.Layout`)."""

HELDOUT_FILE = "heldout.json"
"""A worker's run keeps the held-out scores of its best-so-far weights here, in its own folder."""

_RUN_COLUMNS = ("generation", "evaluations", "wall_s", "train_best", "heldout_best")


def study_fingerprint(cfg: StudyConfig) -> str:
    """What a study folder must hold: the config's text and whether it is the quick run."""
    return hashlib.sha256(cfg.text.encode() + f"|{cfg.is_quick}".encode()).hexdigest()


def _key(x: Any) -> str:
    return np.asarray(x, "<f4").tobytes().hex()


class _HeldOut:
    """Held-out scores by weight vector: evaluated in padded chunks of ``chunk`` rows (one compiled program),
    cached in ``path`` (JSON); the caches in ``read`` (other processes' files) are read too, never written."""

    def __init__(self, objective: Objective, path: Path, chunk: int, read: Sequence[Path] = ()) -> None:
        self.objective, self.path, self.chunk = objective, path, chunk
        self.cache: dict[str, dict] = {}
        for f in (*read, path):
            if f.is_file():
                try:
                    self.cache.update(json.loads(f.read_text()))
                except ValueError:  # a damaged cache only costs its evaluations again
                    pass
        self.seconds = 0.0

    def scores(self, xs: list[np.ndarray]) -> list[dict]:
        todo = list(dict.fromkeys(_key(x) for x in xs if _key(x) not in self.cache))
        if todo:
            t0 = time.perf_counter()
            vecs = [np.frombuffer(bytes.fromhex(k), "<f4") for k in todo]
            for i in range(0, len(vecs), self.chunk):
                part = vecs[i:i + self.chunk]
                pop = np.stack(part + [part[-1]] * (self.chunk - len(part)))
                ev = self.objective.evaluate(pop, "test")
                for j, k in enumerate(todo[i:i + len(part)]):
                    self.cache[k] = {"fitness": float(ev.fitness[j]), "per_seed": [float(v) for v in ev.per_seed[j]],
                                     "metrics": {m: float(v[j]) for m, v in ev.metrics.items()}}
            atomic_write(self.path, json.dumps(json_safe(self.cache)).encode())
            self.seconds += time.perf_counter() - t0
        return [self.cache[_key(x)] for x in xs]

    def merge(self, cache: Mapping[str, dict]) -> None:
        """Takes in scores computed elsewhere (a Ray task's) and writes the cache."""
        new = {k: v for k, v in cache.items() if k not in self.cache}
        if new:
            self.cache.update(new)
            atomic_write(self.path, json.dumps(json_safe(self.cache)).encode())


def _run_one(cfg: StudyConfig, objective: Objective, method: str, strategy: Strategy, seed: int, folder: Path,
             progress: bool, resume: bool) -> dict:
    """One method with one tuner seed: `tune_loop` on the counted objective; returns rows, counts, wall times."""
    counted = CountedObjective(objective)
    fp = hashlib.sha256(cfg.text.encode() + f"|{cfg.is_quick}|{method}|{seed}".encode()).hexdigest()
    folder.mkdir(parents=True, exist_ok=True)
    counts_path = folder / "counts.json"
    saved = json.loads(counts_path.read_text()) if (resume and counts_path.is_file()) else {"evaluations": [],
                                                                                            "wall_s": []}
    state: dict[str, Any] = {"first": None, "t": time.perf_counter()}
    evals: list[int] = []
    walls: list[float] = []

    def callback(g: int, row: dict) -> None:
        if state["first"] is None:  # the first generation of this session: the earlier ones are in `saved`
            state["first"] = g
            evals[:] = saved["evaluations"][:g - 1]
            walls[:] = saved["wall_s"][:g - 1]
            state["base_e"] = evals[-1] if evals else 0
            state["base_w"] = walls[-1] if walls else 0.0
        now = time.perf_counter()
        evals.append(state["base_e"] + counted.count)
        walls.append(state["base_w"] + now - state["t0"])
        atomic_write(counts_path, json.dumps({"evaluations": evals, "wall_s": walls}).encode())

    state["t0"] = time.perf_counter()
    res = tune_loop(counted, strategy, cfg.generations, folder, seed=seed, checkpoint_every=1, resume=resume,
                    progress=progress, fingerprint=fp, callback=callback)
    if state["first"] is None:  # every generation was already done
        evals, walls = saved["evaluations"][:cfg.generations], saved["wall_s"][:cfg.generations]
    if len(evals) != cfg.generations or evals[-1] != cfg.budget:
        raise RuntimeError(f"{folder.name}: counted {evals[-1] if evals else 0} training evaluations in "
                           f"{len(evals)} generations; the budget is {cfg.budget} in {cfg.generations}")
    return {"rows": res.rows, "evaluations": evals, "wall_s": walls, "compile_s": _compile_seconds(folder),
            "best_x": np.asarray(res.best_x), "best_f": res.best_f, "new": cfg.generations - res.resumed_from}


def _compile_seconds(run_dir: Path) -> float:
    """Seconds of XLA compilation inside a run's evaluations (`tune_loop`'s timings.csv, every generation): a
    process compiles once, in whichever run comes first, so it is taken out of the wall times compared."""
    lines = (run_dir / "timings.csv").read_text().splitlines()[1:]
    return float(sum(float(x.split(",")[2]) for x in lines if x))


def study_run(cfg: StudyConfig, objective: Objective, method: str, strategy: Strategy, seed: int, run_dir: Path,
              held_for: Callable[[Path], _HeldOut], progress: bool = False, resume: bool = True) -> Payload:
    """Method ``method`` with tuner seed ``seed``, run (or resumed) in ``run_dir`` and scored on the held-out split
    (``held_for(run_dir)``), as the `Payload` the study folder commits: per generation the counted evaluations, wall
    seconds, training and held-out scores of the best-so-far weights and those weights (CSV; floats written with
    ``repr``, so they read back to the same bits); its compile seconds, best weights and training score, and the
    generations this call computed.

    Raises:
      RuntimeError: the run did not spend exactly the study's budget.
      FolderInUseError: another process works in ``run_dir`` (a worker).
    """
    names = list(objective.bounds.names)
    with RunFolder.lock(run_dir):  # a worker may hold it (`run_study(only=...)`)
        r = _run_one(cfg, objective, method, strategy, seed, run_dir, progress, resume)
        xs = [np.array([row[n] for n in names], np.float32) for row in r["rows"]]
        heldout = [h["fitness"] for h in held_for(run_dir).scores(xs)]
    buf = io.StringIO()
    buf.write(",".join((*_RUN_COLUMNS, *names)) + "\n")
    for i, row in enumerate(r["rows"]):
        vals = [str(row["generation"]), str(r["evaluations"][i]), repr(float(r["wall_s"][i])),
                repr(float(row["best"])), repr(float(heldout[i]))] + [repr(float(row[n])) for n in names]
        buf.write(",".join(vals) + "\n")
    info = {"method": method, "tuner_seed": seed, "compile_s": float(r["compile_s"]),
            "best_x": [float(v) for v in np.asarray(r["best_x"]).ravel()], "best_f": float(r["best_f"]),
            "generations_run": int(r["new"])}
    return Payload(buf.getvalue().encode(), {}, info)


_WORKER: dict[str, Any] = {}
"""A Ray worker's study: the objective (its compiled programs) and one strategy per method, kept between the tasks
that the same worker runs, so that a worker compiles them once per study, not once per run."""


def study_task(shared: tuple[str, StudyConfig, Objective], item: tuple[str, int]) -> tuple[Payload, dict]:
    """One (method, tuner seed) run as a Ray task: `study_run` in a scratch folder of this worker (removed after),
    scored on the held-out split here. ``shared``: (the study's fingerprint, its config, its objective).

    Returns:
      The run's `Payload` and the held-out scores computed for it (weight vector key -> scores), for the study's
      ``heldout.json``.
    """
    token, cfg, objective = shared
    method, seed = item
    if _WORKER.get("token") != token:  # the first task of this study on this worker
        _WORKER.clear()
        # One device, whatever the node's JAX settings: a population split over devices may move the last bit of
        # a fitness that weights float sums (clearance, roughness), and a run must not depend on where it ran.
        _WORKER.update(token=token, objective=objective.with_mesh(None), strategies={})
    objective = _WORKER["objective"]
    strategies = _WORKER["strategies"]
    if method not in strategies:
        strategies[method] = make_strategy(method, cfg.population, cfg.generations, **cfg.options.get(method, {}))
    with tempfile.TemporaryDirectory(prefix="jaxplan-study-") as tmp:
        held = _HeldOut(objective, Path(tmp) / HELDOUT_FILE, cfg.population)
        payload = study_run(cfg, objective, method, strategies[method], seed, Path(tmp) / f"{method}-s{seed}",
                            lambda _run_dir: held, progress=False, resume=False)
    return payload, held.cache


def _result(data: bytes, info: Mapping[str, Any], names: Sequence[str], new: int) -> dict:
    """A run (``rows``, ``evaluations``, ``wall_s``, ``heldout``, ``compile_s``, ``best_x``, ``best_f``, ``new``) from
    its committed data and entry (`study_run`'s payload)."""
    lines = data.decode().splitlines()
    cols = lines[0].split(",")
    if cols != [*_RUN_COLUMNS, *names]:
        raise ValueError(f"a study run's columns are {cols}, expected {[*_RUN_COLUMNS, *names]}")
    rows, evals, walls, held = [], [], [], []
    for ln in lines[1:]:
        v = ln.split(",")
        rows.append({"generation": int(v[0]), "best": float(v[3]),
                     **{n: float(x) for n, x in zip(names, v[len(_RUN_COLUMNS):], strict=True)}})
        evals.append(int(v[1]))
        walls.append(float(v[2]))
        held.append(float(v[4]))
    return {"rows": rows, "evaluations": evals, "wall_s": walls, "heldout": held, "compile_s": float(info["compile_s"]),
            "best_x": np.asarray(info["best_x"], np.float32), "best_f": float(info["best_f"]), "new": new}


def _committed(store: RunFolder, name: str, names: Sequence[str]) -> dict:
    """Committed run ``name`` read back (checked against its SHA-256); its generations count as this session's only
    if this session computed them."""
    entry = store.entries[name]
    new = int(entry.get("generations_run", 0)) if entry.get("session") == store.session else 0
    return _result(store.data(name), entry, names, new)


def _method_runs(cfg: StudyConfig, objective: Objective, m: str, folder: Path, progress: bool, resume: bool,
                 held_for: Callable[[Path], _HeldOut], runs: dict, store: RunFolder | None
                 ) -> Iterator[tuple[int, dict]]:
    """Runs (or resumes) method ``m`` for every tuner seed into ``runs``, scoring each run's best-so-far weights
    on the held-out split with ``held_for(run_dir)``; commits each run to ``store`` (None: a worker, which commits
    nothing) and skips the runs ``store`` holds; yields ``(seed, run)`` after each."""
    names = list(objective.bounds.names)
    # One strategy serves every tuner seed: its ask and tell are then the same functions, so JAX compiles
    # them once per study instead of once per run (each compile also maps more code into the process).
    strategy = make_strategy(m, cfg.population, cfg.generations, **cfg.options.get(m, {}))
    first = cfg.tuner_seeds[0]
    for s in cfg.tuner_seeds:
        if s != first and not STRATEGY_SPECS[m].uses_key:
            # Its proposals do not depend on the key and the objective is deterministic, so this seed's run
            # would repeat the first one evaluation for evaluation: the first stands for it, wall times too.
            runs[(m, s)] = dict(runs[(m, first)], new=0, same_as_seed=first)
            continue
        name = f"{m}-s{s}"
        if store is not None and store.done(name):
            r = _committed(store, name, names)
        else:
            payload = study_run(cfg, objective, m, strategy, s, folder / "runs" / name, held_for, progress, resume)
            if store is None:
                r = _result(payload.data, payload.info, names, int(payload.info["generations_run"]))
            else:
                store.commit(name, payload)
                r = _committed(store, name, names)
        runs[(m, s)] = r
        yield s, r


def _read_sessions(folder: Path) -> list[dict]:
    """The study's earlier sessions (``sessions.json``) and its workers' (``worker-*.json``, each entry once); a
    folder from before sessions.json takes its first session from summary.json."""
    path = folder / "sessions.json"
    out: list[dict] = []
    if path.is_file():
        out = json.loads(path.read_text())
    elif (folder / "summary.json").is_file():
        old = json.loads((folder / "summary.json").read_text())
        out = [{"wall_s": old.get("wall_s_this_session", 0.0), "loadavg_start": old.get("loadavg_start"),
                "loadavg_end": old.get("loadavg_end"), "generations": None}]
    seen = {s.get("worker") for s in out}
    for f in sorted(folder.glob("worker-*.json")):
        entry = json.loads(f.read_text())
        if entry.get("worker") not in seen:
            out.append(entry)
    return out


def _session_entry(wall: float, load0: Sequence[float], generations: int) -> dict:
    """A session's wall seconds, load averages, generations run, the process's niceness and the cores it could
    use."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return {"wall_s": wall, "loadavg_start": list(load0), "loadavg_end": list(os.getloadavg()),
            "generations": generations, "nice": os.nice(0), "cores": cores}


def _sessions(store: RunFolder, earlier: list[dict], wall: float, load0: Sequence[float],
              generations: int) -> list[dict]:
    """``earlier`` sessions with this one (so far) appended (`_session_entry`), written to ``sessions.json``.
    Written after every run, so a session that is interrupted still counts the time of the runs it finished; the
    workers' files it took in are then removed (their entries live on in sessions.json)."""
    sessions = store.log_session("sessions.json", _session_entry(wall, load0, generations), earlier)
    for f in store.path.glob("worker-*.json"):
        if any(s.get("worker") == f.stem for s in earlier):
            f.unlink(missing_ok=True)
    return sessions


def _log_csv(cfg: StudyConfig, runs: Mapping[tuple[str, int], Mapping[str, Any]], names: list[str]) -> str:
    cols = ["method", "tuner_seed", "generation", "evaluations", "train_best", "heldout_best", "wall_s"] + names
    lines = [",".join(cols)]
    for (m, s), r in runs.items():
        for i, row in enumerate(r["rows"]):
            vals = [m, s, row["generation"], r["evaluations"][i], repr(float(row["best"])), repr(r["heldout"][i]),
                    f"{r['wall_s'][i]:.3f}"] + [repr(float(row[n])) for n in names]
            lines.append(",".join(map(str, vals)))
    return "\n".join(lines) + "\n"


def run_study(config_path: str | os.PathLike, out: str | os.PathLike = "runs", quick: bool = False,
              data_dir: str | os.PathLike | None = None, progress: bool = True, resume: bool = True,
              results: str | os.PathLike | None = None, confirm: bool = False,
              only: Sequence[str] | None = None, executor: str | Executor | None = None) -> Path:
    """Runs (or resumes) the study config at ``config_path``; returns its folder ``OUT/NAME`` (``NAME-quick``).

    Every method runs once per tuner seed with the same counted budget; then the log, summary, figure,
    best.toml, confirm.toml and page.md are written (module docstring). With ``results``, the page, figure,
    best.toml and confirm.toml are copied to ``results/NAME.md``, ``NAME.png``, ``NAME_best.toml`` and
    ``NAME_confirm.toml``. With ``confirm``, the confirmation experiment then runs (`jaxplan run` of confirm.toml,
    into ``OUT/NAME_confirm``) and its report becomes ``confirm.md`` (and ``results/NAME_confirm.md``).

    With ``only`` (method names), this process is a worker: it runs (or resumes) those methods' runs alone, each
    under its own run folder's lock and with its held-out scores in that folder, and writes nothing else, so
    workers with disjoint methods share one study folder (one per core or machine). A later call without
    ``only`` finds their runs done, reads their held-out scores and writes the page.

    Args:
      config_path: the study config (TOML).
      out: the parent folder of the study folder.
      quick: apply the config's ``[study.quick]`` and ``[tune.quick]`` tables (folder ``NAME-quick``).
      data_dir: where relative map paths resolve.
      progress: draw progress bars on stderr.
      resume: continue from the folder's committed runs and checkpoints; False discards them first.
      results: a folder for the page, figure, best.toml and confirm.toml (e.g. docs/results/tuning).
      confirm: then run the confirmation experiment.
      only: run only these methods' runs, as a worker.
      executor: where the runs (and the confirmation's chunks) run (`jaxplan.core.executor`): None, this process;
        ``"auto"`` or ``"HOST:PORT"``, one Ray task per run on that cluster (``--ray``); an `Executor` as it is.

    Raises:
      ValueError: ``only`` names a method the study does not run, or is combined with ``resume=False`` (a fresh
        start would delete the other workers' runs), ``confirm`` or ``executor``.
      ClusterUnreachable: ``executor`` names a Ray cluster that cannot be reached (or Ray is not installed).
      RunFolderError: the folder holds a different study's runs.
      FolderInUseError: another process works in the folder.
    """
    cfg = load_study_config(config_path, data_dir=data_dir, quick=quick)
    if only is not None:
        bad = sorted(set(only) - set(cfg.methods))
        if bad or not only:
            what = f"{', '.join(bad)} not among" if bad else "give at least one of"
            raise ValueError(f"only: {what} the study's methods ({', '.join(cfg.methods)})")
        if not resume or confirm or executor is not None:
            raise ValueError("only (a worker) resumes and runs its methods' runs alone: not with a fresh start "
                             "(it would delete the other workers' runs) or the confirmation, nor on a Ray cluster "
                             "(--ray runs every method's runs itself)")
    ex = executor_from(executor)
    try:
        return _study(cfg, out, progress, resume, results, confirm, only, data_dir, ex)
    finally:
        if ex is not executor:  # made here from None or an address: left here
            ex.close()


def _study(cfg: StudyConfig, out: str | os.PathLike, progress: bool, resume: bool, results: str | os.PathLike | None,
           confirm: bool, only: Sequence[str] | None, data_dir: str | os.PathLike | None, executor: Executor) -> Path:
    objective = build_study_objective(cfg)
    objective.check_population(cfg.population)
    objective.check_population(cfg.population, "test")
    folder = confined(out, cfg.name + ("-quick" if cfg.is_quick else ""))
    folder.mkdir(parents=True, exist_ok=True)
    if only is not None:
        _run_worker(cfg, objective, folder, [m for m in cfg.methods if m in set(only)], progress)
        return folder
    with RunFolder.lock(folder):
        if not resume:
            for p in (folder / "runs", folder / "heldout.json", folder / "sessions.json", folder / "summary.json",
                      *folder.glob("worker-*.json")):
                shutil.rmtree(p, ignore_errors=True) if p.is_dir() else p.unlink(missing_ok=True)
        with RunFolder.open(folder, study_fingerprint(cfg), STUDY_LAYOUT, fresh=not resume) as store:
            store.verify()
            _run_study(cfg, objective, store, progress, resume, results, data_dir, executor)
    if confirm:
        run_confirmation(cfg, folder, out, results, data_dir, progress,
                         executor=None if executor.kind == "local" else executor)
    return folder


def _notes(cfg: StudyConfig, store: RunFolder, seen: int) -> int:
    """Prints the study folder's notes from ``seen`` on (a rebuilt manifest, a run recomputed); returns the count."""
    for line in store.notes[seen:]:
        print(f"{cfg.name}: {line}", file=sys.stderr, flush=True)
    return len(store.notes)


def _remote_runs(cfg: StudyConfig, objective: Objective, store: RunFolder, executor: Executor, progress: bool,
                 held: _HeldOut, done: Callable[[], None]) -> None:
    """Every run the study folder lacks as a task of ``executor`` (`study_task`), committed as it finishes (any
    order); ``held`` takes in the tasks' held-out scores; ``done()`` after each commit."""
    from jaxplan.core.progress import ProgressBar

    todo = [(m, s) for m in cfg.methods for s in cfg.tuner_seeds
            if (s == cfg.tuner_seeds[0] or STRATEGY_SPECS[m].uses_key) and not store.done(f"{m}-s{s}")]
    if not todo:
        return
    bar = ProgressBar(f"{cfg.name}: {len(todo)} runs on {executor.kind}", len(todo), unit="runs", enabled=progress)
    shared = (study_fingerprint(cfg), cfg, objective)
    try:
        with contextlib.closing(executor.run(study_task, shared, todo)) as finished:
            for k, (i, (payload, scores), where) in enumerate(finished):
                m, s = todo[i]
                store.commit(f"{m}-s{s}", Payload(payload.data, payload.arrays,
                                                  {**payload.info, "node": where.node, "host": where.host,
                                                   "pid": where.pid}))
                held.merge(scores)
                bar.update(k + 1, description=f"{cfg.name}: {m}-s{s} done ({k + 1}/{len(todo)} runs)")
                done()
    finally:
        bar.close()


def _run_study(cfg: StudyConfig, objective: Objective, store: RunFolder, progress: bool, resume: bool,
               results: str | os.PathLike | None, data_dir: str | os.PathLike | None,
               executor: Executor | None = None) -> Path:
    folder = store.path
    t_start = time.perf_counter()
    load0 = os.getloadavg()
    store.write("config.toml", cfg.text.encode())
    seen = _notes(cfg, store, 0)
    held = _HeldOut(objective, folder / "heldout.json", cfg.population,
                    read=sorted(folder.glob(f"runs/*/{HELDOUT_FILE}")))
    names = list(objective.bounds.names)
    earlier = _read_sessions(folder)
    runs: dict[tuple[str, int], dict] = {}
    if executor is not None and executor.kind != "local":

        def committed() -> None:
            new = sum(int(e.get("generations_run", 0)) for e in store.entries.values()
                      if e.get("session") == store.session)
            _sessions(store, earlier, time.perf_counter() - t_start, load0, new)

        _remote_runs(cfg, objective, store, executor, progress, held, committed)
    # (after a cluster's tasks, every run is committed: this reads them back, in the order of the log's rows)
    for m in cfg.methods:
        for _ in _method_runs(cfg, objective, m, folder, progress, resume, lambda _run_dir: held, runs, store):
            _sessions(store, earlier, time.perf_counter() - t_start, load0, sum(x["new"] for x in runs.values()))
            seen = _notes(cfg, store, seen)
    counts = {m: sorted({runs[(m, s)]["evaluations"][-1] for s in cfg.tuner_seeds}) for m in cfg.methods}
    if any(c != [cfg.budget] for c in counts.values()):
        raise RuntimeError(f"unequal budgets (counted): {counts}")
    d = objective.defaults
    d_test = held.scores([d])[0]
    d_train = objective.evaluate(np.stack([d] * cfg.population), "train")  # not charged: not part of a search
    wall = time.perf_counter() - t_start
    sessions = _sessions(store, earlier, wall, load0, sum(r["new"] for r in runs.values()))
    summary = judge.summary(cfg, objective, runs, d_train, d_test, lambda x: held.scores([x])[0]["metrics"], wall,
                            held.seconds, load0)
    summary["sessions"] = sessions
    summary["wall_s_total"] = sum(x["wall_s"] for x in sessions)
    store.write("log.csv", _log_csv(cfg, runs, names).encode())
    store.write("summary.json", json.dumps(json_safe(summary), indent=1, allow_nan=False).encode())
    figure(cfg, runs, d_test["fitness"], folder / "convergence.png")
    best_m, best_s = summary["best"]["method"], summary["best"]["tuner_seed"]
    bx = runs[(best_m, best_s)]["best_x"]
    t0 = cfg.tunes[0]
    comment = (f"best weights of study {cfg.name}: {best_m}, tuner seed {best_s}, {cfg.budget} counted training "
               f"evaluations\nheld-out cost {summary['best']['heldout']:.6g}; defaults {d_test['fitness']:.6g}")
    frag = fragment_toml(objective, bx, label=f"{t0.planner.upper()} (tuned)", overrides=dict(t0.overrides),
                         pipeline=t0.pipeline, comment=comment)
    store.write("best.toml", frag.encode())
    dflt = None if t0.kind == "aco" else fragment_toml(objective, objective.defaults, label=f"{t0.planner} (defaults)",
                                                        overrides=dict(t0.overrides), pipeline=t0.pipeline)
    conf = confirm_config(cfg, frag, data_dir, dflt)
    store.write("confirm.toml", conf.encode())
    text = page(cfg, summary, frag)
    store.write("page.md", text.encode())
    if results is not None:
        res = Path(results)
        res.mkdir(parents=True, exist_ok=True)
        atomic_write(res / f"{cfg.name}.md", text.encode())
        shutil.copyfile(folder / "convergence.png", res / f"{cfg.name}.png")
        atomic_write(res / f"{cfg.name}_best.toml", frag.encode())
        atomic_write(res / f"{cfg.name}_confirm.toml", conf.encode())
    return folder


def _run_worker(cfg: StudyConfig, objective: Objective, folder: Path, methods: list[str], progress: bool) -> None:
    """`run_study` with ``only``: these methods' runs, each run's held-out scores in its own folder; nothing is
    committed (the study folder's lock is the page pass's)."""
    atomic_write(folder / "config.toml", cfg.text.encode())
    shared = [folder / "heldout.json"]
    t0, load0 = time.perf_counter(), os.getloadavg()
    me = f"worker-{os.getpid()}-{int(time.time())}"

    def held_for(run_dir: Path) -> _HeldOut:
        return _HeldOut(objective, run_dir / HELDOUT_FILE, cfg.population, read=shared)

    runs: dict[tuple[str, int], dict] = {}
    for m in methods:
        for s, r in _method_runs(cfg, objective, m, folder, progress, True, held_for, runs, None):
            entry = _session_entry(time.perf_counter() - t0, load0, sum(x["new"] for x in runs.values()))
            atomic_write(folder / f"{me}.json", json.dumps({**entry, "worker": me, "methods": methods}).encode())
            print(f"{cfg.name}: {m}-s{s} done ({r['evaluations'][-1]} counted evaluations)", file=sys.stderr,
                  flush=True)
