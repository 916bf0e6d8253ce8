"""CMA-ES and SNES from evosax, wrapped as `Strategy` objects in the unit cube.

evosax provides CMA-ES (Hansen 2016, "The CMA Evolution Strategy: A Tutorial") and SNES (Schaul
et al. 2011); they are wrapped, not re-implemented. Boundary repair: the evolution strategies
reflect (`reflect`) and are told the repaired points ("Lamarckian" repair: the update sees the
points that were evaluated).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxplan.tune._base import Strategy, box, box_of, require_positive, sanitize, track_best, unit_of
from jaxplan.tune._bounds import Bounds, reflect

__all__ = ["ESState", "cma_es", "snes"]


class ESState(NamedTuple):
    """An evosax strategy's state plus the box, the best point and a key for its ``tell``."""

    es: Any
    low: jnp.ndarray
    high: jnp.ndarray
    best_x: jnp.ndarray
    best_f: jnp.ndarray
    generation: jnp.ndarray
    key: jax.Array


def _evosax(name: str, cls_name: str, population_size: int, sigma: float, **kwargs) -> Strategy:
    require_positive(name, sigma=sigma)  # a NaN or negative step would run to the end on NaN points
    cache: dict[int, Any] = {}

    def es_of(D: int):
        # The evosax object is static configuration (population size, a template solution); evosax is imported
        # here, not above, so that building a strategy to check a config's options costs no import.
        if D not in cache:
            import evosax.algorithms as ea

            es = getattr(ea, cls_name)(population_size=population_size, solution=jnp.zeros(D), **kwargs)
            cache[D] = (es, es.default_params.replace(std_init=sigma))
        return cache[D]

    def init(key, bounds: Bounds, x0=None) -> ESState:
        low, high = box(bounds)
        es, params = es_of(bounds.dim)
        mean = jnp.full(bounds.dim, 0.5) if x0 is None else jnp.clip((jnp.asarray(x0) - low) / (high - low), 0, 1)
        k1, k2 = jax.random.split(key)
        return ESState(es.init(k1, mean, params), low, high, low + mean * (high - low),
                       jnp.asarray(jnp.inf, jnp.float32), jnp.asarray(0, jnp.int32), k2)

    def ask(key, state: ESState):
        es, params = es_of(state.low.shape[0])
        z, _ = es.ask(key, state.es, params)
        return box_of(state, reflect(z))

    def tell(state: ESState, pop, fitness) -> ESState:
        es, params = es_of(state.low.shape[0])
        fitness, _ = sanitize(fitness)
        key = jax.random.fold_in(state.key, state.generation)
        es_state, _ = es.tell(key, unit_of(state, pop), fitness, state.es, params)
        bx, bf = track_best(state.best_x, state.best_f, pop, fitness)
        return state._replace(es=es_state, best_x=bx, best_f=bf, generation=state.generation + 1)

    return Strategy(name, population_size, init, ask, tell)


def cma_es(population_size: int, sigma: float = 0.3) -> Strategy:
    """CMA-ES (evosax ``CMA_ES``) in the unit cube, initial step ``sigma`` (unit-cube units)."""
    return _evosax("cma_es", "CMA_ES", population_size, sigma)


def snes(population_size: int, sigma: float = 0.3) -> Strategy:
    """Separable natural evolution strategy (evosax ``SNES``) in the unit cube."""
    return _evosax("snes", "SNES", population_size, sigma)

