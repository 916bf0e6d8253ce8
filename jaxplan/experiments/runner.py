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
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import sys
from pathlib import Path

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


def _run_chunks(prep: Prepared, store: RunFolder, progress: bool, stop_after: int | None) -> bool:
    """Computes and commits every chunk the run folder lacks, in run order; False if ``stop_after`` cut it short."""
    cfg = prep.config
    R = len(cfg.seeds)
    done_units = [u for u in prep.units if store.done(u.uid)]
    done = sum((u.hi - u.lo) * R for u in done_units)
    bar = Progress(cfg.name, prep.trials, done, len(prep.units), progress)
    if progress and done_units:
        print(f"{cfg.name}: resuming, {len(done_units)}/{len(prep.units)} chunks already done", file=sys.stderr)
    computed = 0
    try:
        for u in prep.units:
            if store.done(u.uid):
                continue
            if stop_after is not None and computed >= stop_after:
                return False
            label = f"{prep.maps[u.m].spec.name}/{cfg.planners[u.p].label}"
            bar.start(u.index + 1, label)
            store.commit(u.uid, chunk_payload(prep, u))
            computed += 1
            done += (u.hi - u.lo) * R
            bar.update(done, u.index + 1, label)
    finally:
        bar.close()
    return True


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
                   chunk: int | None = None, stop_after: int | None = None) -> Path:
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

    Returns:
      The run folder.

    Raises:
      ConfigError: the config or its data has problems (all listed; nothing was run).
      MemoryLimitError: a chunk or the trials would not fit in memory (nothing was run).
      RunFolderError: the folder holds checkpoints of a different experiment.
      FolderInUseError: another process works in the run folder.
    """
    cfg = resolve_config(config, quick=quick, data_dir=data_dir, chunk=chunk)
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
        for _ in range(_MERGE_ATTEMPTS):
            if not _run_chunks(prep, store, progress, stop_after):
                return run_dir
            trials = store.merged([u.uid for u in prep.units], header.encode())
            seen = _note(cfg, store, seen)
            if trials is not None:
                break
        else:
            raise CheckpointError(f"{run_dir}: chunk files keep changing while they are merged (another program "
                                  f"writes to checkpoints/chunks?); run the same command again when it has stopped")
        _write_results(run_dir, prep, store, trials)
    return run_dir
