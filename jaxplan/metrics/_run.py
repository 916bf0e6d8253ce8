"""Run metrics of an iterative planner (DESIGN §6): convergence iteration and colony diversity.

Both are pure functions over the trailing axis, with any leading batch axes, and are what
the colony engine (`jaxplan.aco._colony`) reports per run.

Example:
  >>> import jax.numpy as jnp
  >>> from jaxplan.metrics import converged_iteration, diversity
  >>> int(converged_iteration(jnp.array([jnp.inf, 12.0, 10.005, 10.0])))
  2
  >>> float(diversity(jnp.array([1.0, 3.0, jnp.inf]), jnp.array([True, True, False])))
  1.4142135381698608
"""

from __future__ import annotations

import jax.numpy as jnp

__all__ = ["CONVERGED_RTOL", "converged_iteration", "diversity"]

CONVERGED_RTOL = 1e-3
"""A run has converged at the first iteration whose best cost is within 0.1 % of its final best."""


def converged_iteration(history: jnp.ndarray) -> jnp.ndarray:
    """``int32[...]`` first iteration whose best cost is within 0.1 % of the final best.

    Args:
      history: ``[..., I]`` best-so-far cost after each iteration (``+inf`` before the
        first success), so the final best is ``history[..., -1]``.

    Returns:
      The first ``i`` with ``history[i] <= final + 1e-3·|final|``; ``-1`` when the run never
      found a path (the final best is ``inf`` or NaN) and for an empty history (``I == 0``).
    """
    history = jnp.asarray(history)
    if history.shape[-1] == 0:
        return jnp.full(history.shape[:-1], -1, jnp.int32)
    final = history[..., -1]
    within = history <= (final + CONVERGED_RTOL * jnp.abs(final))[..., None]
    return jnp.where(jnp.isfinite(final), jnp.argmax(within, axis=-1), -1).astype(jnp.int32)


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
