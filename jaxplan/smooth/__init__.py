"""Path post-processing (docs/guide/planners.md): line-of-sight pruning, key nodes, arc fillets, Bezier corners,
B-splines.

Each smoother is a pure JAX function ``f(cmap, points [L, 2], n, ..., radius) -> Smoothed``
on one padded path in cell coordinates, to be ``vmap``-ed over a batch; `smooth` is
the host front (metres, validation, compiled-function reuse). Every result is
checked against the map with the exact segment test of `jaxplan.grid._collision`
and falls back to the unsmoothed path where it would collide.
"""

from jaxplan.smooth._bspline import bspline
from jaxplan.smooth._corners import bezier_corners, fillet
from jaxplan.smooth._front import SMOOTHERS, smooth
from jaxplan.smooth._prune import key_nodes, los_prune
from jaxplan.smooth._result import Smoothed, compact, drop_repeats

__all__ = ["SMOOTHERS", "Smoothed", "bezier_corners", "bspline", "compact", "drop_repeats",
           "fillet", "key_nodes", "los_prune", "smooth"]
