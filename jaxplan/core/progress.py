"""Progress bars of long calls on stderr: a bar with elapsed time and time left, or a spinner for a stage of
unknown length (compiling), drawn only on a terminal.

Why a module at the bottom of the import graph: the command line (`run`, `reproduce`, `tune`, `figures`, `demo`,
`bench`) and the batched library calls (`jaxplan.plan_batch(..., progress=True)`, `navigate_batch`) share one
bar, and the library calls sit below `jaxplan.experiments`.

Rules, the same everywhere:
  * A bar is drawn only when it is asked for (``enabled``), stderr is a terminal and ``$JAXPLAN_PROGRESS`` is not
    ``0``/``off``: piped or redirected output (logs, CI, tests) carries no bar and no control characters, and the
    command's own output (stdout, the files it writes) is the same with or without one.
  * With rich installed (it comes with evosax, a dependency) the bar is rich's: spinner, description, bar,
    ``done/total``, elapsed, time left. Without it, one rewritten ``\\r`` line with the same fields.
  * A stage of unknown length (``total=None``: compiling, one compiled call) shows a spinner and the elapsed time;
    rich's display refreshes from its own thread, so the spinner turns while JAX compiles in the main thread.
  * Time left is rich's estimate from the recent rate (or, without rich, elapsed / done × left since the bar
    began, so chunks resumed from a checkpoint do not count as fast).
"""

from __future__ import annotations

import math
import os
import sys
import time
from typing import Any, TextIO

__all__ = ["clock", "progress_wanted", "ProgressBar"]

_LIVE: list["ProgressBar"] = []
"""The bar drawn now, if any: one bar at a time, so a bar inside a bar (a batched call inside a run's chunk, with
``progress=True``) draws nothing and the outer one keeps the screen."""

_KEEP: Any = object()
"""Sentinel of `ProgressBar.update`: leave the total as it is (None means a spinner)."""


def clock(s: float) -> str:
    """Seconds as ``H:MM:SS``."""
    s = int(round(s))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


def progress_wanted(enabled: bool = True, stream: TextIO | None = None) -> bool:
    """Whether to draw a bar: asked for, ``stream`` (default stderr) a terminal, and ``$JAXPLAN_PROGRESS`` not
    ``0``/``off``/``no``/``false``."""
    if not enabled or os.environ.get("JAXPLAN_PROGRESS", "").strip().lower() in ("0", "off", "no", "false"):
        return False
    stream = sys.stderr if stream is None else stream
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # a closed or minimal stream
        return False


def _rich_progress(stream: TextIO) -> Any:
    """A started `rich.progress.Progress` on ``stream``, None without rich, False when another rich display is
    live (rich draws one at a time)."""
    try:
        from rich.console import Console
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            SpinnerColumn,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )
        from rich.table import Column
    except ImportError:
        return None
    console = Console(file=stream, force_terminal=True)
    # stdout is redirected above the bar only when it shares the terminal; piped stdout must keep its bytes.
    same_screen = getattr(sys.stdout, "isatty", lambda: False)()
    fixed = lambda: Column(no_wrap=True)  # noqa: E731
    p = Progress(SpinnerColumn(table_column=fixed()), TextColumn("{task.description}", table_column=fixed()),
                 BarColumn(bar_width=16, table_column=fixed()), MofNCompleteColumn(table_column=fixed()),
                 TextColumn("{task.fields[unit]}", table_column=fixed()), TimeElapsedColumn(table_column=fixed()),
                 TextColumn("left", table_column=fixed()), TimeRemainingColumn(table_column=fixed()),
                 console=console, redirect_stdout=same_screen, redirect_stderr=stream is sys.stderr,
                 refresh_per_second=8)
    try:
        p.start()
    except Exception:  # noqa: BLE001 - rich's LiveError: another bar is live (a bar inside a bar draws nothing)
        return False
    return p


class ProgressBar:
    """One bar on stderr (drawn only where `progress_wanted`); every method is a no-op when it is not drawn.

    Args:
      description: what runs (``"cui2025_table2"``; `stage` changes it).
      total: units of work (trials, generations, figures), or None for a spinner (a stage of unknown length).
      done: units already done (resumed from a checkpoint): shown, but not counted in the rate.
      unit: the units' name after ``done/total`` (``"trials"``).
      enabled: False draws nothing (``--no-progress``, ``progress=False``).
      stream: where to draw (default stderr; for tests).

    Use as a context manager, or call `close` (a finished bar stays on screen, so its time remains readable).
    """

    def __init__(self, description: str, total: int | None = None, *, done: int = 0, unit: str = "",
                 enabled: bool = True, stream: TextIO | None = None):
        self.stream = sys.stderr if stream is None else stream
        self.active = progress_wanted(enabled, self.stream) and not _LIVE
        self.description, self.total, self.done, self.unit = description, total, done, unit
        self.start_done, self.t0 = done, time.perf_counter()
        self._rich = _rich_progress(self.stream) if self.active else None
        if self._rich is False:  # another rich display is live: it keeps the screen
            self._rich, self.active = None, False
        if self.active:
            _LIVE.append(self)
        self._task = None
        if self._rich is not None:
            self._task = self._rich.add_task(self._fit(description), total=total, completed=done, unit=unit)
        self._draw()

    @property
    def rich(self) -> bool:
        """Whether rich draws the bar."""
        return self._rich is not None

    def stage(self, description: str, total: Any = _KEEP, *, unit: str | None = None) -> None:
        """Names what runs now (``"compiling"``, ``"chunk 3/8 den520d/iaco"``); ``total`` None turns the bar into
        a spinner, a number back into a bar."""
        self.update(description=description, total=total, unit=unit)

    def update(self, done: int | None = None, *, advance: int = 0, description: str | None = None,
               total: Any = _KEEP, unit: str | None = None) -> None:
        """Sets ``done`` (or adds ``advance``), and optionally the description, total and unit."""
        if not self.active:
            return
        if done is not None:
            self.done = done
        self.done += advance
        if description is not None:
            self.description = description
        if total is not _KEEP:
            self.total = total
        if unit is not None:
            self.unit = unit
        if self._rich is not None:
            fields = {} if unit is None else {"unit": unit}
            kw = {} if total is _KEEP else {"total": total}
            self._rich.update(self._task, completed=self.done, description=self._fit(self.description), **kw,
                              **fields)
        self._draw()

    def _fit(self, text: str) -> str:
        """``text`` cut (with an ellipsis) so that the counts and times keep their room on a narrow terminal."""
        if self._rich is None:
            return text
        counts = 2 * len(str(self.total or 0)) + 1  # "done/total"
        room = max(12, self._rich.console.width - 44 - counts - len(self.unit))
        return text if len(text) <= room else text[: room - 1] + "…"

    def left_s(self) -> float:
        """Estimated seconds left (nan before the first unit done in this session, or for a spinner)."""
        if self._rich is not None:
            task = self._rich.tasks[0]
            return float("nan") if task.time_remaining is None else float(task.time_remaining)
        new = self.done - self.start_done
        if not self.total or new <= 0:
            return float("nan")
        return (time.perf_counter() - self.t0) / new * max(self.total - self.done, 0)

    def _draw(self) -> None:
        if not self.active or self._rich is not None:
            return
        el = time.perf_counter() - self.t0
        if self.total is None:
            msg = f"{self.description} | elapsed {clock(el)}"
        else:
            frac = self.done / max(self.total, 1)
            bar = "#" * int(frac * 20)
            left = self.left_s()
            msg = (f"{self.description} [{bar:<20}] {self.done}/{self.total} {self.unit} | elapsed {clock(el)} | "
                   f"left ~{clock(left) if math.isfinite(left) else '?'}")
        print("\r" + msg.ljust(100), end="", file=self.stream, flush=True)

    def close(self) -> None:
        """Leaves the finished bar on screen and stops drawing."""
        if not self.active:
            return
        self.active = False
        if self in _LIVE:
            _LIVE.remove(self)
        if self._rich is not None:
            self._rich.refresh()
            self._rich.stop()
        else:
            print(file=self.stream, flush=True)

    def __enter__(self) -> "ProgressBar":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
