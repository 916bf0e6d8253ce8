"""Grid and random search as `Strategy` objects: the baselines every other optimiser is compared with."""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from jaxplan.tune._base import Strategy, box, box_of, sanitize, track_best
from jaxplan.tune._bounds import Bounds

__all__ = ["SearchState", "random_search", "grid_search"]


class SearchState(NamedTuple):
    """Grid and random search: nothing evolves but the best point and the generation counter."""

    low: jnp.ndarray
    high: jnp.ndarray
    best_x: jnp.ndarray
    best_f: jnp.ndarray
    generation: jnp.ndarray


def _search_init(key, bounds: Bounds, x0=None) -> SearchState:
    low, high = box(bounds)
    x = (low + high) / 2 if x0 is None else jnp.asarray(x0, jnp.float32)
    return SearchState(low, high, x, jnp.asarray(jnp.inf, jnp.float32), jnp.asarray(0, jnp.int32))


def _search_tell(state: SearchState, pop, fitness) -> SearchState:
    fitness, _ = sanitize(fitness)
    bx, bf = track_best(state.best_x, state.best_f, pop, fitness)
    return state._replace(best_x=bx, best_f=bf, generation=state.generation + 1)


def random_search(population_size: int) -> Strategy:
    """Uniform samples in the box, ``population_size`` per generation."""

    def ask(key, state):
        z = jax.random.uniform(key, (population_size, state.low.shape[0]))
        return box_of(state, z)

    return Strategy("random", population_size, _search_init, ask, _search_tell)


def grid_search(population_size: int, generations: int) -> Strategy:
    """A full-factorial grid with ``n = floor((P·G)^(1/D))`` points per axis (end points included),
    visited in row-major order, ``P`` points per generation; once the ``n^D`` points are used
    up the visit wraps round (the evaluation budget is the same as the other strategies').
    ``n = 1`` is the box centre."""

    def ask(key, state):
        D = state.low.shape[0]
        n = max(1, int(math.floor((population_size * generations) ** (1.0 / D) + 1e-9)))
        axis = jnp.linspace(0.0, 1.0, n) if n > 1 else jnp.array([0.5])
        k = (state.generation * population_size + jnp.arange(population_size)) % (n ** D)
        idx = jnp.stack(jnp.unravel_index(k, (n,) * D), axis=-1)
        return box_of(state, axis[idx])

    return Strategy("grid", population_size, _search_init, ask, _search_tell)
