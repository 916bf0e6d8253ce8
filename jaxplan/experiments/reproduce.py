"""`reproduce`: every reproduction config (``configs/<paper>_<table>.toml``) run, then its figures drawn.

One process runs them all in file-name order, so compiled programs that two configs share
(the same planner on maps of the same shape) are built once. Each config's run folder is
``OUT/NAME`` (``OUT/NAME-quick`` with ``quick``), resumable as any run; its figures go to
``FIGURES/NAME[-quick]/`` with an index page, and ``FIGURES/index.md`` lists them all. With ``results``
(``docs/results``; `jaxplan.experiments.results`) each config's results page, the paper's numbers beside
ours with a verdict, goes to ``RESULTS/<paper>/<table>[-quick].md`` and ``RESULTS/index[-quick].md``
lists them with their verdict counts.

A config beyond the papers, the navigation frontier (``configs/navigation.toml``;
`jaxplan.experiments.frontier.is_frontier`), is not among the default configs (its full run alone takes
1-2 hours): ``--pattern 'navigation.toml'`` runs it, and its figures (one per map) and its page
``RESULTS/navigation[-quick].md`` are written by `jaxplan.experiments.frontier.write_frontier` in place of a
paper table's; the index lists it under "Beyond the papers".
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

from jaxplan.core.executor import Executor, executor_from

__all__ = ["Reproduced", "reproduction_configs", "reproduce", "describe_error"]


@dataclass(frozen=True)
class Reproduced:
    """One config's outcome: run folder, wall times (s) of the run and of its figures, figure problems."""

    config: Path
    run_dir: Path | None
    run_s: float
    figures_s: float
    figures: int
    problems: tuple[str, ...]
    error: str | None = None
    page: Path | None = None


def reproduction_configs(config_dir: str | os.PathLike = "configs", pattern: str | None = None) -> list[Path]:
    """The reproduction configs in ``config_dir`` (sorted by name): files ``<paper>_*.toml`` for every paper key of
    `jaxplan.papers.PAPERS`, or those matching the glob ``pattern`` if one is given.

    Raises:
      FileNotFoundError: no such folder, or no config matches.
    """
    d = Path(config_dir)
    if not d.is_dir():
        raise FileNotFoundError(f"config folder {d} not found (pass --configs)")
    from jaxplan.papers import PAPERS

    if pattern is None:
        found = sorted(p for key in PAPERS for p in d.glob(f"{key}_*.toml"))
    else:
        found = sorted(d.glob(pattern))
    if not found:
        raise FileNotFoundError(f"no config matches {d / (pattern or '<paper>_*.toml')}")
    return found


def reproduce(configs: Sequence[str | os.PathLike], out: str | os.PathLike = "runs",
              figures: str | os.PathLike = "figures", *, quick: bool = False,
              data_dir: str | os.PathLike | None = None, progress: bool = True,
              results: str | os.PathLike | None = None, notes: str | os.PathLike | None = None,
              executor: str | Executor | None = None) -> list[Reproduced]:
    """Runs each config (resuming finished chunks) and draws its figures; one failing config does not stop the rest.

    With ``results``, also writes each config's results page and the index (`jaxplan.experiments.results`;
    ``notes``: the hand-written notes file, default ``<config folder>/results/notes.toml``; the claims and
    margins are read from ``claims.toml`` beside it, `jaxplan.experiments.claims`). Studies that are
    not experiment configs (li2026's optimiser comparison, `jaxplan.studies.benchmark_functions`) are run by
    ``jaxplan reproduce``, which then rewrites the index (`jaxplan.experiments.results.write_index_page`).

    ``executor`` (``--ray``): where every config's chunks run, as `jaxplan.experiments.run_experiment` takes it; an
    address is joined once, before the first config (an unreachable cluster raises `ClusterUnreachable` then), and
    left at the end.

    Returns:
      One `Reproduced` per config, in order (``error`` set when the run, or drawing its figures at all,
      failed; ``problems`` lists single figures not drawn).
    """
    from jaxplan.experiments.claims import load_claims
    from jaxplan.experiments.results import load_notes, write_index_page

    t_start = time.perf_counter()
    configs = [Path(c) for c in configs]
    if results is not None and notes is None and configs:
        notes = configs[0].parent / "results" / "notes.toml"
    the_notes = load_notes(notes) if results is not None else None
    the_claims = load_claims(Path(notes).with_name("claims.toml") if notes is not None else None)
    ex = executor_from(executor)
    try:
        done = _reproduce(configs, out, figures, quick, data_dir, progress, results, the_notes, the_claims, ex)
    finally:
        if ex is not executor:
            ex.close()
    if results is not None and any(r.page is not None for r in done):
        write_index_page(results, the_notes, the_claims, quick=quick, wall_s=time.perf_counter() - t_start,
                         figures_dir=figures)
    return done


def _reproduce(configs: list[Path], out: str | os.PathLike, figures: str | os.PathLike, quick: bool,
               data_dir: str | os.PathLike | None, progress: bool, results: str | os.PathLike | None, the_notes,
               the_claims, executor: Executor) -> list[Reproduced]:
    from jaxplan.experiments.figures import draw_figures, write_index
    from jaxplan.experiments.frontier import write_frontier
    from jaxplan.experiments.results import write_table_page
    from jaxplan.experiments.runner import run_experiment

    done = []
    for cfg in configs:
        t0 = time.perf_counter()
        try:
            run_dir = run_experiment(cfg, out, quick=quick, data_dir=data_dir, progress=progress, executor=executor)
        except Exception as e:  # noqa: BLE001 - reported in the outcome; the next config still runs
            done.append(Reproduced(cfg, None, time.perf_counter() - t0, 0.0, 0, (), describe_error(e)))
            continue
        t1 = time.perf_counter()
        try:
            drawn, problems = draw_figures(run_dir, figures, data_dir=data_dir, progress=progress)
        except Exception as e:  # noqa: BLE001 - as above: the run folder stands, its figures failed
            done.append(Reproduced(cfg, run_dir, t1 - t0, time.perf_counter() - t1, 0, (),
                                   f"figures: {describe_error(e)}"))
            continue
        page = None
        if _is_frontier(run_dir):
            try:
                page, mine = write_frontier(run_dir, results, figures, data_dir=data_dir)
            except Exception as e:  # noqa: BLE001 - as above: the run folder stands
                done.append(Reproduced(cfg, run_dir, t1 - t0, time.perf_counter() - t1, len(drawn), tuple(problems),
                                       f"frontier page: {describe_error(e)}"))
                continue
            drawn = [*drawn, *mine]
            name = Path(run_dir).resolve().name
            write_index(Path(figures), name, f"{name}: the navigation frontier", drawn, problems)
        elif results is not None:
            try:
                page = write_table_page(run_dir, results, the_notes, the_claims, figures_dir=figures, drawn=drawn,
                                        data_dir=data_dir)
            except Exception as e:  # noqa: BLE001 - as above: the run and its figures stand
                done.append(Reproduced(cfg, run_dir, t1 - t0, time.perf_counter() - t1, len(drawn), tuple(problems),
                                       f"results page: {describe_error(e)}"))
                continue
        done.append(Reproduced(cfg, run_dir, t1 - t0, time.perf_counter() - t1, len(drawn), tuple(problems),
                               page=page))
    return done


def _is_frontier(run_dir: Path) -> bool:
    """Whether a run folder holds a frontier config's run (its config's name, `frontier.is_frontier`)."""
    import tomllib

    from jaxplan.experiments.config import read_config_text
    from jaxplan.experiments.frontier import is_frontier

    path = Path(run_dir) / "config.toml"
    if not path.is_file():  # a run that stopped before it wrote its config: not a frontier page to draw
        return False
    doc = tomllib.loads(read_config_text(path))
    return is_frontier(str(doc.get("experiment", {}).get("name", "")))


def describe_error(e: Exception) -> str:
    """The message of an expected failure (bad config, data, run folder); the type too for anything else."""
    from jaxplan.experiments.config import ConfigError
    from jaxplan.experiments.store import RunFolderError

    return str(e) if isinstance(e, (ConfigError, RunFolderError, ValueError, FileNotFoundError)) \
        else f"{type(e).__name__}: {e}"
