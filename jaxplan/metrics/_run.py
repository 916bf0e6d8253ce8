"""Run metrics of an iterative planner: convergence iteration (three definitions) and colony diversity.

All are pure functions over the trailing (iteration) axis, with any leading batch axes. The colony
engine (`jaxplan.aco._colony`) reports `converged_iteration` and `diversity` per run; the others are
computed on the host from the same best-so-far history (`jaxplan.experiments.execute`).

Convergence, as each paper defines it:

* `converged_iteration` — the general definition: the first iteration (0-based) whose best cost is
  within 1 % (`CONVERGED_RTOL`) of the run's final best; ``rtol=CONVERGED_RTOL_STRICT`` (0.1 %) gives
  the sensitivity row ``converged_iteration_strict``.
* `turning_point` — chu2024 (Tables 3 and 5, "iterative stabilization times"): "The curve's stationary
  values' turning points in Figure 7 are selected as the stable points for iteration times." The
  iteration (counted from 1) at which the curve reaches the value it keeps to the end.
* `optimum_iteration` — yu2020 (Tables 1-3, "the number of iterations"): the generation in which the
  run's optimal solution is found ("the optimal solution can be obtained as soon as the third
  generation"; "the shortest time to search for the optimal solution is eight iterations"), counted
  from 1 as the paper counts generations.

On a best-so-far history (never rising) `turning_point` and `optimum_iteration` coincide; they
differ on a curve that may rise again (an iteration-best curve), where the turning point is the start
of the final flat stretch and the optimum iteration the first time the final value is reached.

Example:
  >>> import jax.numpy as jnp
  >>> from jaxplan.metrics import converged_iteration, diversity, optimum_iteration
  >>> h = jnp.array([jnp.inf, 12.0, 10.05, 10.0])
  >>> int(converged_iteration(h)), int(converged_iteration(h, rtol=1e-3)), int(optimum_iteration(h))
  (2, 3, 4)
  >>> float(diversity(jnp.array([1.0, 3.0, jnp.inf]), jnp.array([True, True, False])))
  1.4142135381698608
"""

from __future__ import annotations

import jax.numpy as jnp

__all__ = ["CONVERGED_RTOL", "CONVERGED_RTOL_STRICT", "converged_iteration", "diversity", "optimum_iteration",
           "turning_point"]

CONVERGED_RTOL = 1e-2
"""A run has converged at the first iteration whose best cost is within 1 % of its final best."""

CONVERGED_RTOL_STRICT = 1e-3
"""The sensitivity row's tolerance (``converged_iteration_strict``): within 0.1 % of the final best."""


def _never(history: jnp.ndarray) -> jnp.ndarray:
    """``int32[...]`` all −1: the answer for an empty history (``I == 0``)."""
    return jnp.full(history.shape[:-1], -1, jnp.int32)


def converged_iteration(history: jnp.ndarray, rtol: float = CONVERGED_RTOL) -> jnp.ndarray:
    """``int32[...]`` first iteration (0-based) whose best cost is within ``rtol`` of the final best.

    Args:
      history: ``[..., I]`` best-so-far cost after each iteration (``+inf`` before the
        first success), so the final best is ``history[..., -1]``.
      rtol: relative tolerance: `CONVERGED_RTOL` (1 %, the general definition) or
        `CONVERGED_RTOL_STRICT` (0.1 %, the sensitivity row).

    Returns:
      The first ``i`` with ``history[i] <= final + rtol·|final|``; ``-1`` when the run never
      found a path (the final best is ``inf`` or NaN) and for an empty history (``I == 0``).
    """
    history = jnp.asarray(history)
    if history.shape[-1] == 0:
        return _never(history)
    final = history[..., -1]
    within = history <= (final + rtol * jnp.abs(final))[..., None]
    return jnp.where(jnp.isfinite(final), jnp.argmax(within, axis=-1), -1).astype(jnp.int32)


def optimum_iteration(history: jnp.ndarray) -> jnp.ndarray:
    """``int32[...]`` yu2020's "number of iterations": the iteration, counted from 1, in which the final best is
    first reached (no tolerance: the run's optimal solution itself).

    Args:
      history: ``[..., I]`` best-so-far cost after each iteration (``+inf`` before the first success).

    Returns:
      ``1 +`` the first ``i`` with ``history[i] <= history[-1]``; ``-1`` when the run never found a path
      (final best ``inf`` or NaN) and for an empty history.
    """
    history = jnp.asarray(history)
    if history.shape[-1] == 0:
        return _never(history)
    final = history[..., -1]
    first = jnp.argmax(history <= final[..., None], axis=-1) + 1
    return jnp.where(jnp.isfinite(final), first, -1).astype(jnp.int32)


def turning_point(curve: jnp.ndarray) -> jnp.ndarray:
    """``int32[...]`` chu2024's turning point: the iteration, counted from 1, from which the curve stays at its
    final (stationary) value to the last iteration.

    Args:
      curve: ``[..., I]`` a cost per iteration: the best-so-far history (then this equals
        `optimum_iteration`) or any curve that may rise again, such as an iteration-best cost.

    Returns:
      ``1 +`` the smallest ``i`` with ``curve[j] == curve[-1]`` for every ``j >= i``; ``-1`` when the
      final value is ``inf`` or NaN (no path) and for an empty curve.
    """
    curve = jnp.asarray(curve)
    if curve.shape[-1] == 0:
        return _never(curve)
    final = curve[..., -1]
    at_final = curve == final[..., None]
    # A suffix flag: iteration i stays at the final value when it and every later one do.
    stays = jnp.flip(jnp.cumprod(jnp.flip(at_final, axis=-1), axis=-1), axis=-1).astype(bool)
    first = jnp.argmax(stays, axis=-1) + 1
    return jnp.where(jnp.isfinite(final), first, -1).astype(jnp.int32)


def diversity(costs: jnp.ndarray, valid: jnp.ndarray, axis: int | tuple[int, ...] | None = -1) -> jnp.ndarray:
    """Sample standard deviation (ddof 1) of the path costs of the ants that reached the goal.

    Args:
      costs: ``[..., A]`` each ant's path cost in one iteration.
      valid: ``bool[..., A]`` the ant reached the goal (same shape as ``costs``); an ant
        whose cost is not finite is left out as well, so a failed ant may carry any cost
        (``inf`` by convention, and then ``valid = isfinite(costs)`` will do).
      axis: the ant axis, or axes (e.g. ``(-2, -1)`` for ``[..., colonies, ants]``: all
        sub-colonies' ants form one population), or None for all axes.

    Returns:
      ``[...]`` the standard deviation over the counted ants (yu2020's population
      diversity); 0 when fewer than two ants count — one path or none shows no spread,
      and 0 keeps per-iteration curves free of NaN.
    """
    costs = jnp.asarray(costs)
    use = jnp.asarray(valid) & jnp.isfinite(costs)
    count = jnp.sum(use, axis=axis)
    mean = jnp.sum(jnp.where(use, costs, 0.0), axis=axis) / jnp.maximum(count, 1)
    centred = costs - (mean if axis is None else jnp.expand_dims(mean, axis))
    var = jnp.sum(jnp.where(use, centred**2, 0.0), axis=axis) / jnp.maximum(count - 1, 1)
    return jnp.where(count >= 2, jnp.sqrt(var), 0.0)
