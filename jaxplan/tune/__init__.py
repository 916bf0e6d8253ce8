"""Tuning the planners' weights (DESIGN §7): objectives over scenario batches, gradient-free and differentiable optimisers."""

from jaxplan.tune._bounds import Bounds, clip, from_unit, make_bounds, reflect, to_unit
from jaxplan.tune._strategies import STRATEGIES, Strategy, cma_es, grid_search, make_strategy, random_search, sanitize, snes
from jaxplan.tune._sparrow import SparrowState, adaptive_weight, issa, levy, ssa

__all__ = [
    "Bounds", "clip", "from_unit", "make_bounds", "reflect", "to_unit",
    "STRATEGIES", "Strategy", "cma_es", "grid_search", "make_strategy", "random_search", "sanitize", "snes",
    "SparrowState", "adaptive_weight", "issa", "levy", "ssa",
]
