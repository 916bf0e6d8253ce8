"""The registry of tuning strategies: one place that maps a strategy's name to its factory.

Configs (``[tune] strategy``, checked with `option_problems`), the workflow (`make_strategy`), the
tests and the benchmarks all go through `STRATEGY_SPECS`; a new optimiser is one entry here. Each
factory builds a `Strategy` (``init/ask/tell``, `jaxplan.tune._base`) from the population size,
(where its schedule needs it) the number of generations, and keyword options whose names and
defaults are the factory's own keyword parameters (`strategy_options`).

=============  ==========================================================  ==================
name           optimiser                                                   module
=============  ==========================================================  ==================
``grid``       full-factorial grid, row-major                              `_search`
``random``     uniform samples in the box                                  `_search`
``cma_es``     CMA-ES (Hansen 2016), evosax                                `_evosax`
``snes``       separable NES (Schaul et al. 2011), evosax                  `_evosax`
``ssa``        sparrow search (Xue & Shen 2020)                            `_sparrow`
``issa``       li2026's improved sparrow search                            `_sparrow`
``reinforce``  score-function gradient of the smoothed cost, optax Adam    `_gradients`
``surrogate``  quadratic surrogate minimised with optax                    `_gradients`
=============  ==========================================================  ==================
"""

from __future__ import annotations

import difflib
import inspect
import math
from types import MappingProxyType
from typing import Any, Callable, Mapping, NamedTuple

from jaxplan.tune._base import Strategy
from jaxplan.tune._evosax import cma_es, snes
from jaxplan.tune._gradients import reinforce, surrogate
from jaxplan.tune._search import grid_search, random_search
from jaxplan.tune._sparrow import issa, ssa

__all__ = ["StrategySpec", "STRATEGY_SPECS", "STRATEGIES", "strategy_options", "option_problems", "make_strategy"]


class StrategySpec(NamedTuple):
    """A registered strategy.

    Attributes:
      name: the name configs and `make_strategy` use.
      factory: ``factory(population_size, generations, **options)`` when ``uses_generations`` (a schedule or a
        budget sized by the run), else ``factory(population_size, **options)``; returns a `Strategy`.
      uses_generations: whether the factory takes the number of generations.
      uses_key: whether its proposals depend on the PRNG key (the tuner seed). A strategy that does not (the grid)
        repeats itself evaluation for evaluation under every seed, so a study runs it once.
    """

    name: str
    factory: Callable[..., Strategy]
    uses_generations: bool
    uses_key: bool = True


STRATEGY_SPECS: Mapping[str, StrategySpec] = MappingProxyType({s.name: s for s in (
    StrategySpec("grid", grid_search, True, uses_key=False),
    StrategySpec("random", random_search, False),
    StrategySpec("cma_es", cma_es, False),
    StrategySpec("snes", snes, False),
    StrategySpec("ssa", ssa, True),
    StrategySpec("issa", issa, True),
    StrategySpec("reinforce", reinforce, False),
    StrategySpec("surrogate", surrogate, True),
)})
"""Every strategy by name, in the order configs and reports list them."""

STRATEGIES: tuple[str, ...] = tuple(STRATEGY_SPECS)
"""The strategy names (a config's ``[tune] strategy`` choices)."""

_SIZES = ("population_size", "generations")


def strategy_options(name: str) -> dict[str, Any]:
    """The options (keyword arguments besides the population and generations) that strategy ``name`` takes,
    with their defaults (the factory's own keyword parameters)."""
    spec = _spec(name)
    return {k: p.default for k, p in inspect.signature(spec.factory).parameters.items()
            if k not in _SIZES and p.default is not inspect.Parameter.empty}


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


def make_strategy(name: str, population_size: int, generations: int, **options: Any) -> Strategy:
    """A `Strategy` by name (`STRATEGIES`); ``generations`` sizes the grid, the sparrows' schedules and the
    surrogate's memory.

    Raises:
      ValueError: an unknown name or option, a population under 2, a non-positive generation count, or an
        option the strategy refuses (its own range checks).
    """
    if not isinstance(population_size, int) or population_size < 2:
        raise ValueError(f"population_size must be an integer >= 2, got {population_size!r}")
    if not isinstance(generations, int) or generations < 1:
        raise ValueError(f"generations must be a positive integer, got {generations!r}")
    spec = _spec(name)
    unknown = sorted(set(options) - set(strategy_options(name)))
    if unknown:
        raise ValueError(f"strategy {name!r} has no option(s) {', '.join(map(repr, unknown))}")
    if spec.uses_generations:
        return spec.factory(population_size, generations, **options)
    return spec.factory(population_size, **options)


def _spec(name: str) -> StrategySpec:
    spec = STRATEGY_SPECS.get(name)
    if spec is None:
        raise ValueError(f"unknown strategy {name!r}; choose from {STRATEGIES}")
    return spec
