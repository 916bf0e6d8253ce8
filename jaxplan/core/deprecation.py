"""Arguments of the previous release's signatures, accepted for one release with a `DeprecationWarning`.

`keyword_only` lets a function whose trailing parameters became keyword-only still take them by position, in
their old order, and says which keyword form to write instead::

    @keyword_only("global_planner", "local_planner", "seed", "obstacles")
    def navigate(grid, start, goal, *, pipeline=None, global_planner=None, ...): ...

    navigate(grid, start, goal, "astar")   # works, warns: use global_planner="astar"

The wrapped function keeps its new signature for `inspect.signature` and type checkers (``__wrapped__``).
"""

from __future__ import annotations

import functools
import inspect
import warnings
from typing import Any, Callable, ParamSpec, TypeVar

__all__ = ["keyword_only", "warn_deprecated"]

_P = ParamSpec("_P")
_R = TypeVar("_R")


def warn_deprecated(message: str, stacklevel: int = 3) -> None:
    """A `DeprecationWarning` with ``message``, attributed to the caller of the function that calls this one."""
    warnings.warn(message, DeprecationWarning, stacklevel=stacklevel)


def keyword_only(*old_positional: str) -> Callable[[Callable[_P, _R]], Callable[_P, _R]]:
    """A decorator: ``fn``'s keyword-only parameters ``old_positional`` (the previous release's positional
    parameters after the ones that stay positional, in their old order) are still accepted by position, with a
    `DeprecationWarning` naming the keyword form.

    Args:
      *old_positional: names of keyword-only parameters of ``fn``, in the order they used to take by position.

    Returns:
      The decorator. Too many positional arguments, or one given both by position and by keyword, raise
      ``TypeError`` as a plain call would.
    """

    def decorate(fn: Callable[_P, _R]) -> Callable[_P, _R]:
        params = inspect.signature(fn).parameters
        kept = sum(p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) for p in params.values())
        missing = [n for n in old_positional if n not in params or params[n].kind is not params[n].KEYWORD_ONLY]
        if missing:
            raise TypeError(f"{fn.__qualname__}: {missing} are not keyword-only parameters")

        @functools.wraps(fn)
        def wrapper(*args: Any, **kwargs: Any) -> _R:
            if len(args) > kept:
                extra = args[kept:]
                if len(extra) > len(old_positional):
                    raise TypeError(f"{fn.__name__}() takes {kept} positional arguments but {len(args)} were given")
                moved = dict(zip(old_positional, extra, strict=False))
                twice = sorted(set(moved) & set(kwargs))
                if twice:
                    raise TypeError(f"{fn.__name__}() got multiple values for argument {twice[0]!r}")
                keywords = ", ".join(f"{k}=..." for k in moved)
                warn_deprecated(f"{fn.__name__}(): passing {', '.join(moved)} by position is deprecated and will be "
                                f"an error in the next release; pass {keywords} by keyword")
                kwargs.update(moved)
                args = args[:kept]
            return fn(*args, **kwargs)

        return wrapper  # type: ignore[return-value]

    return decorate
