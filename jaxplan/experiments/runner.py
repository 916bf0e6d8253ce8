"""`run_experiment`: a config's trials as batched, checkpointed, resumable work.

The stages, one module each:

* `jaxplan.experiments.prepare`: the work plan — maps loaded, scenarios chosen, trials cut into
  chunks (one map × one planner × up to ``chunk`` scenarios × every seed), and the fingerprint
  of everything that shapes the trials;
* `jaxplan.experiments.budget`: the memory guard of every chunk and of the trials, before any work;
* `jaxplan.experiments.execute`: one compiled batch call per chunk (`jaxplan.plan_batch`,
  `jaxplan.navigate_batch`, the TSP program over the seeds) and its rows of CSV text;
* `jaxplan.experiments.trial_metrics`: host-side float64 metrics that depend on each trial only;
* `jaxplan.experiments.store`: chunks committed to the run folder through one manifest (resume
  after a kill, SIGKILL included), and ``meta.json`` with the provenance record
  (`jaxplan.core.provenance`);
* `jaxplan.experiments.progress`: the progress line;
* `jaxplan.experiments.stats`, `jaxplan.experiments.report`: summaries, tests and reports.

Run folder ``OUT/NAME/`` (``OUT/NAME-quick/`` with ``quick=True``, so a smoke run never
mixes with the real one)::

    config.toml          the config file, verbatim
    meta.json            versions (jaxplan, jax, numpy, scipy, python), git revision, devices, session start times,
                         the seeds as ranges, and the whole provenance record
    .lock                held by the process that works in the folder (a second one is refused)
    trials.csv           one row per (map, planner, scenario, seed); deterministic
    timings.csv          wall-clock times per chunk (compile and run); NOT reproducible, hence apart
    summary.csv/.md      mean ± sd per map × planner × metric, the paper's numbers in `paper_*` columns
    significance.csv     ANOVA and pairwise Welch t-tests, if the config asks
    report.md            the whole run in one page
    checkpoints/manifest.json       the commit log of finished chunks
    checkpoints/chunks/ID.csv       each finished chunk's rows
    checkpoints/chunks/ID.json      its record (fingerprint, SHA-256 of rows and arrays): rebuilds a damaged manifest
    checkpoints/arrays/ID/          each chunk's arrays (orbax): convergence histories, paths, tours, trajectories

Restarting with the same config skips every committed chunk whose rows and arrays still match their
SHA-256 (a chunk that fails is recomputed); ``trials.csv`` is the header plus the chunk files in chunk
order, each checked again as it is read, so it comes out byte-identical to an uninterrupted run's.

Where chunks run (``executor``, ``--ray``; `jaxplan.core.executor`): in this process, one after the other, or as
Ray tasks on a cluster (`chunk_payload` is the task; the loaded maps travel with the work plan). Either way this
process is the run folder's only writer: it commits each chunk as it finishes, in whatever order, and merges
``trials.csv`` in chunk order, so the file is the same bytes whatever the number of workers. ``meta.json`` records
the machines of each session (``sessions[i].executor``: kind, nodes, CPUs) and where each committed chunk ran
(``placement``: uid -> node, host, worker pid, session).
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import json
import os
import sys
from pathlib import Path

from jaxplan.core.executor import Executor, Placement, executor_from
from jaxplan.core.io import atomic_write, confined
from jaxplan.core.run_folder import Payload, RunFolder
from jaxplan.experiments import report, stats
from jaxplan.experiments.budget import check_experiment
from jaxplan.experiments.config import ConfigError, ExperimentConfig, apply_quick, load_config
from jaxplan.experiments.execute import run_unit
from jaxplan.experiments.prepare import Prepared, Unit, fingerprint, prepare, trial_columns
from jaxplan.experiments.progress import Progress
from jaxplan.experiments.store import RUN_LAYOUT, CheckpointError, write_meta

__all__ = ["run_experiment", "resolve_config", "chunk_payload"]


def resolve_config(config: ExperimentConfig | str | os.PathLike, *, quick: bool = False,
                   data_dir: str | os.PathLike | None = None, chunk: int | None = None) -> ExperimentConfig:
    """The config to run: loaded and validated in full (a path), with the quick changes and a chunk override.

    Raises:
      ConfigError: every problem of the config, or a bad ``chunk``.
    """
    cfg = config if isinstance(config, ExperimentConfig) else load_config(config, data_dir=data_dir)
    if quick and not cfg.is_quick:
        cfg = apply_quick(cfg)
    if chunk is not None:
        if not isinstance(chunk, int) or chunk < 1:
            raise ConfigError([f"chunk: must be an integer >= 1, got {chunk!r}"], "--chunk")
        cfg = cfg.replace(chunk=chunk)
    return cfg


def _note(cfg: ExperimentConfig, store: RunFolder, seen: int) -> int:
    """Prints the run folder's notes from ``seen`` on (always: they concern the data, not the progress)."""
    for line in store.notes[seen:]:
        print(f"{cfg.name}: {line}", file=sys.stderr, flush=True)
    return len(store.notes)


def chunk_payload(prep: Prepared, u: Unit) -> Payload:
    """Chunk ``u`` computed (`jaxplan.experiments.execute.run_unit`) as what the run folder commits: its rows of
    CSV text, its arrays, and its manifest fields (map, planner, kind, scenario range, trials, timings). A pure
    function of the work plan and the unit: it may run in another process, the run folder's writer commits it."""
    cfg = prep.config
    text, arrays, timing = run_unit(prep, u)
    info = {"map": prep.maps[u.m].spec.name, "planner": cfg.planners[u.p].label, "kind": cfg.planners[u.p].kind,
            "scenarios": [u.lo, u.hi], "trials": (u.hi - u.lo) * len(cfg.seeds), **timing}
    return Payload(text.encode(), arrays, info)


def _placed(payload: Payload, where: Placement) -> Payload:
    """``payload`` with where it ran in its manifest fields (``meta.json``'s ``placement`` is read from them)."""
    return Payload(payload.data, payload.arrays, {**payload.info, "node": where.node, "host": where.host,
                                                  "pid": where.pid})


def _run_chunks(prep: Prepared, store: RunFolder, progress: bool, stop_after: int | None,
                executor: Executor) -> bool:
    """Computes and commits every chunk the run folder lacks (at most ``stop_after`` of them, in run order); False if
    ``stop_after`` cut it short. Chunks are committed as they finish, in whatever order the executor yields them."""
    cfg = prep.config
    R = len(cfg.seeds)
    done_units = [u for u in prep.units if store.done(u.uid)]
    todo = [u for u in prep.units if not store.done(u.uid)]
    cut = stop_after is not None and len(todo) > stop_after
    todo = todo[:stop_after] if cut else todo
    done = sum((u.hi - u.lo) * R for u in done_units)
    bar = Progress(cfg.name, prep.trials, done, len(prep.units), progress)
    if progress and done_units:
        print(f"{cfg.name}: resuming, {len(done_units)}/{len(prep.units)} chunks already done", file=sys.stderr)

    def label(u: Unit) -> str:
        return f"{prep.maps[u.m].spec.name}/{cfg.planners[u.p].label}"

    try:
        if todo and executor.kind == "local":
            bar.start(todo[0].index + 1, label(todo[0]))
        elif todo:
            bar.bar.stage(f"{cfg.name}: {len(todo)} chunks on {executor.kind}")
        # closing(): an interrupt or a failing chunk stops the executor's remaining units at once
        with contextlib.closing(executor.run(chunk_payload, prep, todo)) as finished:
            for k, (i, payload, where) in enumerate(finished):
                u = todo[i]
                store.commit(u.uid, _placed(payload, where))
                done += (u.hi - u.lo) * R
                bar.update(done, len(done_units) + k + 1, label(u))
                if executor.kind == "local" and i + 1 < len(todo):
                    bar.start(todo[i + 1].index + 1, label(todo[i + 1]))
    finally:
        bar.close()
    return not cut


def _record_placement(run_dir: Path, prep: Prepared, store: RunFolder, cluster: dict) -> None:
    """``meta.json``: this session's machines (``sessions[-1].executor``) and where each committed chunk ran
    (``placement``, from the manifest entries, so chunks of earlier sessions keep theirs)."""
    p = run_dir / "meta.json"
    meta = json.loads(p.read_text())
    if meta.get("sessions"):
        meta["sessions"][-1]["executor"] = cluster
    meta["placement"] = {u.uid: {k: e[k] for k in ("node", "host", "pid", "session") if k in e}
                         for u in prep.units if (e := store.entries.get(u.uid)) is not None and "node" in e}
    atomic_write(p, json.dumps(meta, indent=1).encode())


def _write_results(run_dir: Path, prep: Prepared, store: RunFolder, trials: bytes) -> None:
    """trials.csv (``trials``: header + the checked chunk files in run order), timings, summaries, significance
    tests and reports."""
    cfg = prep.config
    atomic_write(run_dir / "trials.csv", trials)
    timings = [{"uid": u.uid, **store.entries[u.uid]} for u in prep.units]
    stats.write_timings(run_dir / "timings.csv", timings)
    result = stats.analyse(run_dir / "trials.csv", run_dir / "timings.csv", cfg)
    stats.write_summary(run_dir / "summary.csv", result)
    stats.write_significance(run_dir / "significance.csv", result)
    meta = json.loads((run_dir / "meta.json").read_text())
    atomic_write(run_dir / "summary.md", report.summary_markdown(result, cfg))
    atomic_write(run_dir / "report.md", report.report_markdown(result, cfg, prep, meta))


_MERGE_ATTEMPTS = 3


def run_experiment(config: ExperimentConfig | str | os.PathLike, out_dir: str | os.PathLike = "runs", *,
                   quick: bool = False, data_dir: str | os.PathLike | None = None, progress: bool = True,
                   chunk: int | None = None, stop_after: int | None = None,
                   executor: str | Executor | None = None) -> Path:
    """Runs (or resumes) an experiment and writes its run folder.

    Before any work the config is validated in full and the memory of every chunk and of the trials is
    checked (`jaxplan.experiments.budget`); the run folder is then locked against a second process
    (`jaxplan.core.run_folder.RunFolder`). On resume every committed chunk is checked against its SHA-256 and a
    chunk that fails is recomputed; a damaged manifest is rebuilt from the intact chunks
    (`jaxplan.experiments.store`). What was found is printed on stderr.

    Args:
      config: an `ExperimentConfig` or the path of a TOML config (validated in full first).
      out_dir: parent of the run folder ``NAME`` (``NAME-quick`` with ``quick``).
      quick: apply the config's ``[experiment.quick]`` changes (a smoke run).
      data_dir: where relative map paths resolve (default ``$JAXPLAN_DATA`` or ../shared/benchmarks).
      progress: print a progress line on stderr.
      chunk: scenarios per compiled call, overriding the config's ``experiment.chunk``.
      stop_after: compute at most this many chunks in this session, then return without
        the summary (for tests and for splitting a run over several jobs).
      executor: where the chunks run (`jaxplan.core.executor`): None, this process (one after the other);
        ``"auto"`` or ``"HOST:PORT"``, Ray tasks on that cluster (``--ray``; joined here and left at the end); an
        `Executor`, as it is (the caller closes it). The run folder's files are the same bytes either way.

    Returns:
      The run folder.

    Raises:
      ConfigError: the config or its data has problems (all listed; nothing was run).
      MemoryLimitError: a chunk or the trials would not fit in memory (nothing was run).
      RunFolderError: the folder holds checkpoints of a different experiment.
      FolderInUseError: another process works in the run folder.
      ClusterUnreachable: ``executor`` names a Ray cluster that cannot be reached (or Ray is not installed).
    """
    cfg = resolve_config(config, quick=quick, data_dir=data_dir, chunk=chunk)
    ex = executor_from(executor)
    try:
        return _run(cfg, out_dir, progress, stop_after, ex)
    finally:
        if ex is not executor:  # made here from None or an address: left here
            ex.close()


def _run(cfg: ExperimentConfig, out_dir: str | os.PathLike, progress: bool, stop_after: int | None,
         executor: Executor) -> Path:
    prep = prepare(cfg)
    check_experiment(prep)
    run_dir = confined(out_dir, cfg.name + ("-quick" if cfg.is_quick else ""))
    with RunFolder.open(run_dir, fingerprint(prep), RUN_LAYOUT) as store:
        store.verify([u.uid for u in prep.units])
        seen = _note(cfg, store, 0)
        started = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
        store.write("config.toml", cfg.text.encode())
        write_meta(run_dir, cfg, store.session, started)
        header = ",".join(trial_columns(cfg)) + "\n"
        cluster = executor.cluster()
        try:
            for _ in range(_MERGE_ATTEMPTS):
                if not _run_chunks(prep, store, progress, stop_after, executor):
                    return run_dir
                trials = store.merged([u.uid for u in prep.units], header.encode())
                seen = _note(cfg, store, seen)
                if trials is not None:
                    break
            else:
                raise CheckpointError(f"{run_dir}: chunk files keep changing while they are merged (another program "
                                      f"writes to checkpoints/chunks?); run the same command again when it has "
                                      f"stopped")
        finally:  # an interrupted session too: the chunks it committed say where they ran
            _record_placement(run_dir, prep, store, cluster)
        _write_results(run_dir, prep, store, trials)
    return run_dir
