"""Path post-processing (docs/guide/planners.md): line-of-sight pruning, key nodes, arc fillets, Bezier corners,
B-splines.

Each smoother is a pure JAX function ``f(cmap, points [L, 2], n, ..., radius) -> Smoothed``
on one padded path in cell coordinates, to be ``vmap``-ed over a batch; `smooth` is
the host front (metres, validation, compiled-function reuse). Every result is
checked against the map with the exact segment test of `jaxplan.grid._collision`
and falls back to the unsmoothed path where it would collide.

``jaxplan.smooth`` is the function `smooth`; this subpackage is ``jaxplan.smoothing`` (the previous release
called it ``jaxplan.smooth``: ``from jaxplan.smooth import ...`` still works for one release, with a
`DeprecationWarning`).
"""

from jaxplan.smoothing._bspline import bspline
from jaxplan.smoothing._corners import bezier_corners, fillet
from jaxplan.smoothing._front import SMOOTHERS, smooth
from jaxplan.smoothing._prune import key_nodes, los_prune
from jaxplan.smoothing._result import Smoothed, compact, drop_repeats

__all__ = ["SMOOTHERS", "Smoothed", "bezier_corners", "bspline", "compact", "drop_repeats",
           "fillet", "key_nodes", "los_prune", "smooth"]
