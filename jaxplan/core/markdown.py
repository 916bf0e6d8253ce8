"""The one Markdown toolkit of the page writers: numbers, "mean ± sd" cells, intervals, tables, links, headings.

Every generated page (a run's summary.md and report.md, the results pages, a tuning study's page, the config
reference) builds its cells and tables here, so that a number, a missing value and a table look the same on
every page::

    from jaxplan.core import markdown as md

    md.table(["planner", "length (m)"], [["A*", md.pm(41.2, 0.0)], ["ACO", md.pm(43.01, 1.2)]])
    # | planner | length (m) |
    # | --- | ---: |
    # | A* | 41.2 ± 0 |
    # | ACO | 43.01 ± 1.2 |

Pure functions from numbers and strings to text; no file is written here (`jaxplan.core.io.atomic_write` does).
"""

from __future__ import annotations

import math
import re
from typing import Callable, Iterable, Sequence

__all__ = ["MISSING", "fmt", "pm", "interval", "cell", "table", "link", "image", "heading", "slug"]

MISSING = "–"
"""What a cell shows for a value that is not known (None or NaN)."""


def _missing(x: float | None) -> bool:
    return x is None or (isinstance(x, float) and math.isnan(x))


def fmt(x: float | None, digits: int = 4) -> str:
    """A number for a table: ``digits`` significant digits (``%g``), `MISSING` for None or NaN, ``∞``/``−∞``."""
    if _missing(x):
        return MISSING
    if isinstance(x, float) and math.isinf(x):
        return "∞" if x > 0 else "−∞"
    return f"{x:.{digits}g}"


def pm(mean: float | None, sd: float | None, num: Callable[[float], str] = fmt,
       sd_num: Callable[[float], str] | None = None) -> str:
    """``"mean ± sd"``; the mean alone when the sd is unknown (None, NaN or infinite); `MISSING` when the mean is.

    Args:
      mean: the mean (a float or None).
      sd: the standard deviation (a float or None).
      num: how the mean is written (default `fmt`).
      sd_num: how the sd is written (default ``num``), e.g. with the mean as the scale below which an sd is rounding
        noise.
    """
    if _missing(mean):
        return MISSING
    if sd is None or not math.isfinite(sd):
        return num(mean)
    return f"{num(mean)} ± {(sd_num or num)(sd)}"


def interval(lo: float | None, hi: float | None, num: Callable[[float], str] = fmt) -> str:
    """``"[lo, hi]"``, or `MISSING` unless both ends are finite numbers."""
    if lo is None or hi is None or not (math.isfinite(lo) and math.isfinite(hi)):
        return MISSING
    return f"[{num(lo)}, {num(hi)}]"


def cell(text: str) -> str:
    """``text`` safe inside a table cell: ``|`` escaped, line breaks as spaces (GitHub-flavoured Markdown)."""
    return str(text).replace("|", "\\|").replace("\r\n", " ").replace("\n", " ")


def table(head: Sequence[str], rows: Iterable[Sequence[str]], *, text: int = 1, last_text: bool = False,
          align: str | None = None) -> str:
    """A Markdown table (no trailing newline).

    Args:
      head: the column headers.
      rows: the cells of each row, as text (made safe with `cell`).
      text: the first ``text`` columns are left-aligned (labels), the rest right-aligned (numbers).
      last_text: the last column is left-aligned too (a verdict, a note).
      align: one letter per column, ``l`` (left) or ``r`` (right), instead of ``text`` and ``last_text``.
    """
    if align is None:
        align = "l" * text + "r" * (len(head) - text)
        if last_text and head:
            align = align[:-1] + "l"
    if len(align) != len(head) or set(align) - {"l", "r"}:
        raise ValueError(f"align needs one of 'l' or 'r' per column ({len(head)}), got {align!r}")
    marks = ["---" if a == "l" else "---:" for a in align]
    lines = ["| " + " | ".join(cell(h) for h in head) + " |", "| " + " | ".join(marks) + " |"]
    for r in rows:
        if len(r) != len(head):
            raise ValueError(f"a row has {len(r)} cells, the table {len(head)} columns: {list(r)!r}")
        lines.append("| " + " | ".join(cell(c) for c in r) + " |")
    return "\n".join(lines)


def link(text: str, target: str) -> str:
    """``[text](target)``."""
    return f"[{text}]({target})"


def image(alt: str, path: str) -> str:
    """``![alt](path)`` (``path`` relative to the page, with forward slashes)."""
    return f"![{alt}]({path})"


def heading(text: str, level: int = 2) -> str:
    """``## text`` at ``level`` (1..6)."""
    if not 1 <= level <= 6:
        raise ValueError(f"a Markdown heading level is 1..6, got {level}")
    return f"{'#' * level} {text}"


def slug(text: str) -> str:
    """The anchor GitHub (and MkDocs' toc with its GitHub slugs) gives a heading ``text``."""
    return re.sub(r"[^a-z0-9 _-]", "", text.lower()).replace(" ", "-")
