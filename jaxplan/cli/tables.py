"""Plain-text tables for the terminal: `jaxplan plan` and `jaxplan demo` print one row per metric, one column
per planner or pipeline (the Markdown tables of run reports are `jaxplan.experiments.report`'s)."""

from __future__ import annotations

from typing import Any, Sequence

__all__ = ["text_table", "PATH_ROWS", "path_column"]


def text_table(columns: Sequence[tuple[str, list[str]]], labels: Sequence[str], title: str) -> str:
    """A boxed text table under ``title``: one row per label, one column per ``(header, values)``.

    Args:
      columns: ``(header, values)`` pairs; ``values[i]`` is the cell of row ``labels[i]``.
      labels: the row labels (first column, left-aligned; the value columns are right-aligned).
      title: the line above the table.
    """
    heads = ["metric"] + [h for h, _ in columns]
    rows = [[lab] + [vals[i] for _, vals in columns] for i, lab in enumerate(labels)]
    widths = [max(len(r[j]) for r in rows + [heads]) for j in range(len(heads))]
    line = "+" + "+".join("-" * (w + 2) for w in widths) + "+"

    def fmt(r):
        cells = (c.ljust(w) if j == 0 else c.rjust(w) for j, (c, w) in enumerate(zip(r, widths, strict=True)))
        return "| " + " | ".join(cells) + " |"

    return "\n".join([title, line, fmt(heads), line] + [fmt(r) for r in rows] + [line])


PATH_ROWS = (
    "success", "length (m)", "cells on path", "turns", "sharp turns (>= 45 deg)", "smoothness",
    "min clearance (m)", "mean clearance (m)", "planning time (ms)",
)
"""The rows of `path_column`: `jaxplan plan`'s table."""


def path_column(res: Any, grid: Any) -> list[str]:
    """The `PATH_ROWS` cells of one `PlanResult` ``res`` on ``grid`` (docs/guide/smoothing-and-metrics.md; time in
    ms)."""
    from jaxplan.metrics import path_metrics

    # The table shows no gap: the planner's own length as `optimal` skips a second exact search.
    if res.success:
        m = path_metrics(res.path, grid, optimal=res.length)
        sharp, smoothness, low, mean = m.sharp_turns, m.smoothness, m.min_clearance, m.mean_clearance
    else:
        sharp, smoothness, low, mean = 0, 1.0, float("nan"), float("nan")
    return [
        str(res.success), f"{res.length:.3f}", str(len(res.path)), str(res.turns), str(sharp), f"{smoothness:.3f}",
        f"{low:.3f}", f"{mean:.3f}", f"{res.time_s * 1e3:.2f}",
    ]
