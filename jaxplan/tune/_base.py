"""The `Strategy` interface of every tuning optimiser, and the helpers their states share.

Every optimiser is a `Strategy`: a NamedTuple of three pure functions closed over static
hyperparameters (the optax/evosax pattern)::

    state = strategy.init(key, bounds, x0=None)      # bounds: `Bounds` (D dims); x0: optional start f32[D]
    pop   = strategy.ask(key, state)                  # f32[P, D], every row inside the box
    state = strategy.tell(state, pop, fitness)        # fitness f32[P], lower is better

All three are jittable (the strategy itself is static). States are NamedTuple pytrees
with at least ``best_x f32[D]``, ``best_f f32[]``, ``generation i32[]``, ``low``/``high``,
so the workflow checkpoints any of them with orbax and reads the best point uniformly.
Fitness values that are NaN or ±inf (a failing configuration) are replaced by the worst
value (`sanitize`) before any update: they rank last, never poison a mean.

Strategies work in the unit cube (`jaxplan.tune._bounds`); `ask` maps back to the box.
The optimisers themselves: `_search` (grid, random), `_evosax` (CMA-ES, SNES), `_sparrow`
(SSA, ISSA), `_gradients` (score-function, surrogate); `_strategies` names them.
"""

from __future__ import annotations

import math
from typing import Any, Callable, NamedTuple

import jax
import jax.numpy as jnp

from jaxplan.tune._bounds import Bounds

__all__ = ["Strategy", "WORST_PAD", "sanitize", "track_best", "box", "unit_of", "box_of", "require_positive"]


class Strategy(NamedTuple):
    """An optimiser: ``init(key, bounds, x0=None) -> state``, ``ask(key, state) -> f32[P, D]``,
    ``tell(state, population, fitness) -> state`` (minimisation)."""

    name: str
    population_size: int
    init: Callable[..., Any]
    ask: Callable[[jax.Array, Any], jnp.ndarray]
    tell: Callable[[Any, jnp.ndarray, jnp.ndarray], Any]


WORST_PAD = 1.0
"""A non-finite fitness becomes (worst finite fitness of the batch) + ``WORST_PAD`` (or 1e30 if none is finite)."""


def sanitize(fitness: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray]:
    """``(fitness with NaN/±inf replaced by the worst value, number replaced i32)``.

    ``-inf`` counts as a failure too: an objective that claims to be infinitely good is a bug,
    and ranking it first would steer every strategy towards it.
    """
    fitness = jnp.asarray(fitness, jnp.float32)
    ok = jnp.isfinite(fitness)
    worst = jnp.where(jnp.any(ok), jnp.max(jnp.where(ok, fitness, -jnp.inf)) + WORST_PAD, 1e30)
    return jnp.where(ok, fitness, worst), jnp.sum(~ok).astype(jnp.int32)


def track_best(best_x: jnp.ndarray, best_f: jnp.ndarray, pop: jnp.ndarray,
               fitness: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray]:
    """The new ``(best_x, best_f)`` after a generation ``pop f32[P, D]`` with sanitised ``fitness f32[P]``."""
    i = jnp.argmin(fitness)
    # a point with a NaN coordinate is never the best, even when sanitize gave every member the same worst value
    better = (fitness[i] < best_f) & jnp.all(jnp.isfinite(pop[i]))
    return jnp.where(better, pop[i], best_x), jnp.where(better, fitness[i], best_f)


def box(bounds: Bounds) -> tuple[jnp.ndarray, jnp.ndarray]:
    """``(low, high)`` of the box as ``f32[D]`` arrays."""
    return jnp.asarray(bounds.low, jnp.float32), jnp.asarray(bounds.high, jnp.float32)


def unit_of(state: Any, x: jnp.ndarray) -> jnp.ndarray:
    """Box points ``x`` of a state with ``low``/``high`` -> unit-cube coordinates."""
    return (x - state.low) / (state.high - state.low)


def box_of(state: Any, z: jnp.ndarray) -> jnp.ndarray:
    """Unit-cube points ``z`` -> box points of a state with ``low``/``high``."""
    return state.low + z * (state.high - state.low)


def require_positive(who: str, *, strict: bool = True, **values: float) -> None:
    """ValueError naming the first of ``values`` that is not a finite number > 0 (>= 0 unless ``strict``)."""
    for k, v in values.items():
        bad = isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0 or (
            strict and v == 0)
        if bad:
            raise ValueError(f"{who}: option {k!r} must be a finite number {'>' if strict else '>='} 0, got {v!r}")
