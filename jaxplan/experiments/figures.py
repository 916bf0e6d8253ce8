"""`draw_figures`: every ``[[figures]]`` entry of a run folder's config, as PNG and SVG, with an index page.

A run folder (`jaxplan.experiments.run_experiment`) holds what the figures need: ``config.toml``
(the config verbatim; ``meta.json`` says whether it ran with ``--quick``), ``trials.csv``
and, per chunk, orbax arrays (plan chunks: ``history``, ``diversity``, ``paths``,
``n_cells``; navigate chunks: ``states``, ``steps``, ``plans``, ``n_plan``). The maps and
scenarios are rebuilt from the config (`prepare`: deterministic, no planning). Two kinds
recompute a little, deterministically, and say so in their captions: ``pheromone``
re-plans the one (scenario, seed) with ``keep_pheromone=True`` (the runner does not keep
``[C, K]`` pheromone tables per trial), and ``fan`` evaluates `jaxplan.dwa_step` at the
stored robot states (the episode keeps no rollouts). The moving discs of a trajectory
plot are redrawn from the runner's own per-trial obstacle seeds.

Kinds (keys besides ``kind name title maps planners format``):

    convergence  best cost per iteration, median and band over seeds, at ``scenario`` (plan planners; tsp
                 planners: best tour length per iteration on each instance)
    diversity    yu2020's diversity (sd of the ants' path costs) per iteration, same layout
    box          per-seed means of ``metric`` per planner (box plot), one panel per map
    bar          mean ± sd over seeds of ``metric`` per planner, the paper's value beside ours, hatched
    sweep        ``metric`` against ``x`` (a generator parameter, e.g. ``obstacle_ratio``, or one number
                 per map): mean ± sd over seeds per planner, the paper's values as open markers
    paths        global paths over the map at (``scenario``, ``seed``) (plan and navigate planners);
                 ``smoothing`` (a `jaxplan.smoothing` smoother, e.g. "los") adds each path after it, dashed
    pheromone    final pheromone per cell of each colony planner at (``scenario``, ``seed``)
    trajectories executed robot paths with the moving discs' tracks (navigate planners)
    controls     v (m/s) and omega (rad/s) against time (navigate planners), chu2024 Figs 8/11
    fan          DWA rollouts (feasible blue, infeasible red, chosen black) at control ``steps``
    tours        best tour of each tsp planner at ``seed`` over the instance's cities, the optimal tour dashed

Output: ``OUT/RUN/STEM.png`` and ``.svg`` (``format`` = one of png/svg/pdf writes only that),
``OUT/RUN/index.md`` (one section per figure with its caption), and ``OUT/index.md``
listing every run's index found under ``OUT``; every file is written atomically
(`jaxplan.core.io`), and STEM (a `jaxplan.core.io.SAFE_NAME`) stays inside ``OUT/RUN``.
``OUT`` defaults to a ``figures`` folder beside the run folder (`default_figures_root`: ``runs/figures``
for ``runs/NAME``), which is not tracked: the committed ``figures/`` of the repository are rewritten only on
purpose, by `jaxplan reproduce` (or an explicit ``OUT``).

A figure that needs the arrays of a chunk that are missing, damaged (checked against the SHA-256
the runner stored) or not computed yet is not drawn: it is listed with the chunk and what to do
(``jaxplan run CONFIG`` recomputes it). With ``partial=True`` (``jaxplan figures --partial``) it is
drawn without them and labelled partial: in the figure, its caption and the index.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

from jaxplan.core.io import atomic_write, confined
from jaxplan.core.progress import ProgressBar
from jaxplan.experiments import plots
from jaxplan.experiments.config import FigureSpec
from jaxplan.experiments.figure_kinds import DRAW
from jaxplan.experiments.run_data import MissingArrays, RunData, load_run

__all__ = ["Drawn", "RunData", "load_run", "draw_figures", "default_figures_root", "write_index", "DRAW"]

plt = plots.plt  # the Agg backend is chosen in plots


@dataclass(frozen=True)
class Drawn:
    """One written figure: its stem, files (relative to the run's figure folder) and caption; ``partial`` says
    which chunks' arrays it lacks (empty for a complete figure)."""

    name: str
    kind: str
    files: tuple[str, ...]
    caption: str
    partial: str = ""


# ---------------------------------------------------------------------------------------------
# The front door


def write_index(out: Path, run_name: str, title: str, drawn: Sequence[Drawn], problems: Sequence[str]) -> Path:
    """Writes ``out/run_name/index.md`` and refreshes ``out/index.md`` (a list of every run's index)."""
    d = out / run_name
    lines = [f"# Figures: {run_name}", "", title, ""]
    for f in drawn:
        lines += [f"## {f.name} ({f.kind}{', PARTIAL' if f.partial else ''})", "", f"![{f.name}]({f.files[0]})", "",
                  f.caption, "",
                  "Files: " + ", ".join(f"[{x}]({x})" for x in f.files), ""]
    if problems:
        lines += ["## Not drawn", ""] + [f"- {p}" for p in problems] + [""]
    atomic_write(d / "index.md", "\n".join(lines))
    runs = sorted(p.parent.name for p in out.glob("*/index.md"))
    top = ["# Figures", "", "One page per run folder (`jaxplan figures RUN`).", ""]
    top += [f"- [{r}]({r}/index.md)" for r in runs]
    extra = sorted(p.name for ext in ("png", "gif") for p in out.glob(f"*.{ext}"))  # e.g. jaxplan demo's
    if extra:
        top += ["", "Other figures:", ""] + [f"- [{x}]({x})" for x in extra]
    atomic_write(out / "index.md", "\n".join(top) + "\n")
    return d / "index.md"


def _draw_one(run: RunData, spec: FigureSpec, d: Path) -> Drawn:
    """Draws and saves one figure into ``d`` (labelled partial if it lacks some chunks' arrays)."""
    before = set(plt.get_fignums())
    run.figure_missing = {}
    try:
        fig, caption = DRAW[spec.kind](run, spec)
    except Exception:
        for num in set(plt.get_fignums()) - before:  # a half-drawn figure would stay open for the whole batch
            plt.close(num)
        raise
    partial = "; ".join(run.figure_missing.values())
    if partial:
        n = len(run.figure_missing)
        fig.text(0.01, 0.005, f"PARTIAL: drawn without the arrays of {n} chunk{'s' * (n != 1)} (see index.md)",
                 color="red", fontsize=8, ha="left", va="bottom")
        caption = f"PARTIAL: drawn without {partial}. {caption}"
    try:
        fmts = [spec.params["format"]] if spec.params.get("format") else ["png", "svg"]
        files = []
        for ext in fmts:
            plots.save_figure(fig, str(confined(d, spec.name, f".{ext}")))
            files.append(f"{spec.name}.{ext}")
    finally:
        plt.close(fig)
    return Drawn(spec.name, spec.kind, tuple(files), caption, partial)


def default_figures_root(run_dir: str | os.PathLike) -> Path:
    """Where a run's figures go unless told: ``figures/`` beside the run folder (``runs/NAME`` -> ``runs/figures``,
    so ``runs/figures/NAME/``). Beside the run, because the run folder's parent is output already (``runs/`` is
    not tracked), and never the repository's committed ``figures/``, which only `jaxplan reproduce` rewrites.
    Relative to the working folder when it lies inside it (so messages name ``runs/figures``)."""
    root = Path(run_dir).resolve().parent / "figures"
    try:
        return root.relative_to(Path.cwd().resolve())
    except ValueError:
        return root


def draw_figures(run_dir: str | os.PathLike, out: str | os.PathLike | None = None, *,
                 data_dir: str | os.PathLike | None = None, strict: bool = False,
                 partial: bool = False, progress: bool = False) -> tuple[list[Drawn], list[str]]:
    """Draws every ``[[figures]]`` entry of a run folder's config.

    Args:
      run_dir: a folder written by `run_experiment`.
      out: figure root; files go to ``out/RUN/`` (RUN = the run folder's name); default `default_figures_root`.
      data_dir: where the config's relative map paths resolve (as for `run_experiment`).
      strict: raise on the first figure that cannot be drawn (default: list it, whatever the error, and go on).
      partial: draw a figure whose chunks' arrays are partly missing or damaged, labelled partial
        (default: list it as not drawn, naming the chunk).
      progress: a bar over the figures on stderr (`jaxplan.core.progress`: only on a terminal).

    Returns:
      (the figures written, the problems of those not drawn — one line each).

    Raises:
      FileNotFoundError: not a run folder, or nothing finished in it.
    """
    run = load_run(run_dir, data_dir, partial=partial)
    run_name = Path(run_dir).resolve().name
    out = default_figures_root(run_dir) if out is None else Path(out)
    d = out / run_name
    d.mkdir(parents=True, exist_ok=True)
    drawn, problems = [], []
    figures = run.config.figures
    with ProgressBar(f"{run_name}: figures", len(figures), unit="figures", enabled=progress) as bar:
        for k, spec in enumerate(figures):
            bar.update(k, description=f"{run_name}: {spec.name} ({spec.kind})")
            try:
                drawn.append(_draw_one(run, spec, d))
            except Exception as e:  # noqa: BLE001 - one figure's failure (even a bug) must not cost the others
                if strict:
                    raise
                known = isinstance(e, (ValueError, KeyError, FileNotFoundError, MissingArrays))
                problems.append(f"{spec.name} ({spec.kind}): {e if known else f'{type(e).__name__}: {e}'}")
        bar.update(len(figures), description=f"{run_name}: figures")
    write_index(out, run_name, run.config.description or run.config.name, drawn, problems)
    return drawn, problems
