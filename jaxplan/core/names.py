"""The one did-you-mean of jaxplan: the closest known name to a mistyped one, for every error that rejects a name.

The command line, the experiment and tuning configs and the Python API (`jaxplan.plan`, `jaxplan.navigate`,
planner parameters) all end their "unknown name" errors with `did_you_mean`, so a typo reads the same
wherever it is made. This module imports nothing from jaxplan.
"""

from __future__ import annotations

import difflib
from typing import Iterable

__all__ = ["did_you_mean", "closest"]


def closest(name: str, known: Iterable[str]) -> str | None:
    """The name of ``known`` closest to ``name``, or None when none is close.

    A name that differs only in case (``"IACO"`` for ``"iaco"``) is found first; otherwise `difflib`'s ratio,
    compared case-blind (``"Iterations"`` and ``"iteration"`` both find ``"iterations"``), must reach 0.6.
    """
    known = [str(k) for k in known]
    folded = {k.casefold(): k for k in reversed(known)}  # the first spelling wins a case-blind tie
    key = str(name).casefold()
    if key in folded:
        return folded[key]
    near = difflib.get_close_matches(key, list(folded), n=1)
    return folded[near[0]] if near else None


def did_you_mean(name: str, known: Iterable[str]) -> str:
    """``"; did you mean 'x'?"`` for the closest of ``known`` to ``name`` (`closest`), else ``""``."""
    near = closest(name, known)
    return f"; did you mean {near!r}?" if near is not None else ""
