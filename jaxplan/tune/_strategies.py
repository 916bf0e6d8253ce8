"""Optimisers behind one interface: grid, random, CMA-ES / SNES (evosax), SSA, ISSA (and, from
`jaxplan.tune._gradients`, the score-function and surrogate routes).

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
Boundary repair: the evolution strategies reflect (`reflect`) and are told the repaired
points ("Lamarckian" repair: the update sees the points that were evaluated); the sparrow
searches clip, as the SSA reference code does.

evosax (0.3.2 installs cleanly beside jax 0.10.2; it pulls flax, dotmap, rich, treescope)
provides CMA-ES (Hansen 2016, "The CMA Evolution Strategy: A Tutorial") and SNES (Schaul
et al. 2011); they are wrapped, not re-implemented.
"""

from __future__ import annotations

import difflib
import inspect
import math
from typing import Any, Callable, Mapping, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxplan.tune._bounds import Bounds, clip, from_unit, reflect, to_unit

__all__ = ["Strategy", "sanitize", "grid_search", "random_search", "cma_es", "snes", "STRATEGIES", "make_strategy"]


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


def _track_best(best_x, best_f, pop, fitness):
    i = jnp.argmin(fitness)
    # a point with a NaN coordinate is never the best, even when sanitize gave every member the same worst value
    better = (fitness[i] < best_f) & jnp.all(jnp.isfinite(pop[i]))
    return jnp.where(better, pop[i], best_x), jnp.where(better, fitness[i], best_f)


def _box(bounds: Bounds):
    return jnp.asarray(bounds.low, jnp.float32), jnp.asarray(bounds.high, jnp.float32)


def _unit(state, x):
    return (x - state.low) / (state.high - state.low)


def _box_of(state, z):
    return state.low + z * (state.high - state.low)


# ---------------------------------------------------------------------------------------------
# Grid and random search


class SearchState(NamedTuple):
    """Grid and random search: nothing evolves but the best point and the generation counter."""

    low: jnp.ndarray
    high: jnp.ndarray
    best_x: jnp.ndarray
    best_f: jnp.ndarray
    generation: jnp.ndarray


def _search_init(key, bounds: Bounds, x0=None) -> SearchState:
    low, high = _box(bounds)
    x = (low + high) / 2 if x0 is None else jnp.asarray(x0, jnp.float32)
    return SearchState(low, high, x, jnp.asarray(jnp.inf, jnp.float32), jnp.asarray(0, jnp.int32))


def _search_tell(state: SearchState, pop, fitness) -> SearchState:
    fitness, _ = sanitize(fitness)
    bx, bf = _track_best(state.best_x, state.best_f, pop, fitness)
    return state._replace(best_x=bx, best_f=bf, generation=state.generation + 1)


def random_search(population_size: int) -> Strategy:
    """Uniform samples in the box, ``population_size`` per generation."""

    def ask(key, state):
        z = jax.random.uniform(key, (population_size, state.low.shape[0]))
        return _box_of(state, z)

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
        return _box_of(state, axis[idx])

    return Strategy("grid", population_size, _search_init, ask, _search_tell)


# ---------------------------------------------------------------------------------------------
# evosax evolution strategies


class ESState(NamedTuple):
    """An evosax strategy's state plus the box, the best point and a key for its ``tell``."""

    es: Any
    low: jnp.ndarray
    high: jnp.ndarray
    best_x: jnp.ndarray
    best_f: jnp.ndarray
    generation: jnp.ndarray
    key: jax.Array


def require_positive(who: str, *, strict: bool = True, **values: float) -> None:
    """ValueError naming the first of ``values`` that is not a finite number > 0 (>= 0 unless ``strict``)."""
    for k, v in values.items():
        bad = isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0 or (
            strict and v == 0)
        if bad:
            raise ValueError(f"{who}: option {k!r} must be a finite number {'>' if strict else '>='} 0, got {v!r}")


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
        low, high = _box(bounds)
        es, params = es_of(bounds.dim)
        mean = jnp.full(bounds.dim, 0.5) if x0 is None else jnp.clip((jnp.asarray(x0) - low) / (high - low), 0, 1)
        k1, k2 = jax.random.split(key)
        return ESState(es.init(k1, mean, params), low, high, low + mean * (high - low),
                       jnp.asarray(jnp.inf, jnp.float32), jnp.asarray(0, jnp.int32), k2)

    def ask(key, state: ESState):
        es, params = es_of(state.low.shape[0])
        z, _ = es.ask(key, state.es, params)
        return _box_of(state, reflect(z))

    def tell(state: ESState, pop, fitness) -> ESState:
        es, params = es_of(state.low.shape[0])
        fitness, _ = sanitize(fitness)
        key = jax.random.fold_in(state.key, state.generation)
        es_state, _ = es.tell(key, _unit(state, pop), fitness, state.es, params)
        bx, bf = _track_best(state.best_x, state.best_f, pop, fitness)
        return state._replace(es=es_state, best_x=bx, best_f=bf, generation=state.generation + 1)

    return Strategy(name, population_size, init, ask, tell)


def cma_es(population_size: int, sigma: float = 0.3) -> Strategy:
    """CMA-ES (evosax ``CMA_ES``) in the unit cube, initial step ``sigma`` (unit-cube units)."""
    return _evosax("cma_es", "CMA_ES", population_size, sigma)


def snes(population_size: int, sigma: float = 0.3) -> Strategy:
    """Separable natural evolution strategy (evosax ``SNES``) in the unit cube."""
    return _evosax("snes", "SNES", population_size, sigma)


def _sparrows():
    from jaxplan.tune import _sparrow

    return _sparrow


STRATEGIES = ("grid", "random", "cma_es", "snes", "ssa", "issa", "reinforce", "surrogate")


def strategy_options(name: str) -> dict[str, Any]:
    """The options (keyword arguments besides the population and generations) that strategy ``name`` takes,
    with their defaults."""
    from jaxplan.tune import _gradients

    fn = {"cma_es": cma_es, "snes": snes, "ssa": _sparrows()._make, "issa": _sparrows()._make,
          "reinforce": _gradients.reinforce, "surrogate": _gradients.surrogate}.get(name)
    if fn is None:  # grid and random search have none
        return {}
    sizes = {"name", "population_size", "generations", "P", "T", "improved"}
    return {k: p.default for k, p in inspect.signature(fn).parameters.items()
            if k not in sizes and p.default is not inspect.Parameter.empty}


def option_problems(name: str, options: Mapping[str, Any], population_size: int = 2,
                    generations: int = 1) -> list[tuple[str | None, str]]:
    """``(option or None, problem)`` for every option of ``options`` that strategy ``name`` would refuse or
    misuse: unknown names, values that are not finite real numbers (integers where the default is one), and
    the strategy's own range checks (e.g. sigma > 0). Empty when ``make_strategy`` accepts them."""
    accepted = strategy_options(name)
    problems: list[tuple[str | None, str]] = []
    for k, v in options.items():
        if k not in accepted:
            near = difflib.get_close_matches(k, list(accepted), n=1)
            takes = f"it takes {', '.join(sorted(accepted))}" if accepted else "it takes none"
            problems.append((k, f"strategy {name!r} has no option {k!r} ({takes})"
                                + (f"; did you mean {near[0]!r}?" if near else "")))
        elif isinstance(v, bool) or not isinstance(v, (int, float)):
            problems.append((k, f"expected a number, got {v!r}"))
        elif not math.isfinite(v):
            problems.append((k, f"must be a finite number, got {v!r}"))
        elif isinstance(accepted[k], int) and not isinstance(v, int):
            problems.append((k, f"expected an integer, got {v!r}"))
    if not problems:  # the ranges live with each strategy: build it once to apply them
        try:
            make_strategy(name, population_size, generations, **options)
        except ValueError as e:
            problems.append((None, str(e)))
    return problems


def make_strategy(name: str, population_size: int, generations: int, **options) -> Strategy:
    """A `Strategy` by name (``STRATEGIES``); ``generations`` sizes the grid and the sparrows' schedules."""
    if not isinstance(population_size, int) or population_size < 2:
        raise ValueError(f"population_size must be an integer >= 2, got {population_size!r}")
    if not isinstance(generations, int) or generations < 1:
        raise ValueError(f"generations must be a positive integer, got {generations!r}")
    if name == "grid":
        return grid_search(population_size, generations)
    if name == "random":
        return random_search(population_size)
    if name == "cma_es":
        return cma_es(population_size, **options)
    if name == "snes":
        return snes(population_size, **options)
    if name == "ssa":
        return _sparrows().ssa(population_size, generations, **options)
    if name == "issa":
        return _sparrows().issa(population_size, generations, **options)
    if name == "reinforce":
        from jaxplan.tune._gradients import reinforce

        return reinforce(population_size, **options)
    if name == "surrogate":
        from jaxplan.tune._gradients import surrogate

        return surrogate(population_size, generations, **options)
    raise ValueError(f"unknown strategy {name!r}; choose from {STRATEGIES}")
