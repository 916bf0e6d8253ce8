"""Sharp-turn count used by the smoothers' guard (placeholder until jaxplan.metrics has the JAX form)."""

from __future__ import annotations

import jax.numpy as jnp

SHARP = jnp.pi / 4


def sharp_turn_count(points: jnp.ndarray, n: jnp.ndarray) -> jnp.ndarray:
    from jaxplan.smooth._result import drop_repeats

    p, m = drop_repeats(points, n)
    d = p[1:] - p[:-1]
    ang = jnp.arctan2(d[:, 1], d[:, 0])
    dh = jnp.abs((ang[1:] - ang[:-1] + jnp.pi) % (2 * jnp.pi) - jnp.pi)
    valid = jnp.arange(dh.shape[0]) < m - 2
    return jnp.sum(valid & (dh >= SHARP - 1e-6))
