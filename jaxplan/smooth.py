"""The previous release's name of the subpackage `jaxplan.smoothing`, kept for one release.

``from jaxplan.smooth import smooth, Smoothed, ...`` still works, with a `DeprecationWarning`; import from
`jaxplan.smoothing` instead (or call ``jaxplan.smooth``, the function). Importing this module binds it to
``jaxplan.smooth`` (the import system sets a module's parent attribute), so the module is callable and calls
`jaxplan.smoothing.smooth`: ``jaxplan.smooth(path, grid)`` works either way. Private modules
(``jaxplan.smooth._front``) are not kept.
"""

from __future__ import annotations

import sys
import types
import warnings
from typing import Any

from jaxplan.smoothing import (
    SMOOTHERS,
    Smoothed,
    bezier_corners,
    bspline,
    compact,
    drop_repeats,
    fillet,
    key_nodes,
    los_prune,
    smooth,
)

__all__ = ["SMOOTHERS", "Smoothed", "bezier_corners", "bspline", "compact", "drop_repeats", "fillet", "key_nodes",
           "los_prune", "smooth"]

__wrapped__ = smooth  # inspect.signature(jaxplan.smooth) is the function's, whichever object the name holds

warnings.warn("the subpackage jaxplan.smooth is now jaxplan.smoothing: import from jaxplan.smoothing (jaxplan.smooth "
              "is the function); the old import path will be removed in the next release", DeprecationWarning,
              stacklevel=2)


class _CallableModule(types.ModuleType):
    """This module, callable as `jaxplan.smoothing.smooth`."""

    def __call__(self, *args: Any, **kwargs: Any) -> Smoothed:
        return smooth(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
