"""Gaussian sampling noise for MPPI, cheap enough for every control step of every robot.

`jax.random.normal` runs threefry and an inverse error function per element: on a CPU that costs
more than a third of an MPPI step. Here each element's uniform is a counter-based integer hash
(lowbias32, as `jaxplan.aco.hash_uniform`) of its index and a 32-bit seed taken from the step's PRNG
key, and the uniform is mapped to a standard normal through a 4,096-entry inverse-CDF table with
linear interpolation between entries. The result is N(0, 1) up to the table's resolution, with the
tails cut at the table's last quantile (±3.6σ): exploration noise, not a statistical sample.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
from jax.scipy.special import ndtri

__all__ = ["gaussian", "TABLE_SIZE"]

TABLE_SIZE = 4096


@functools.cache
def _table() -> np.ndarray:
    """``f32[TABLE_SIZE + 1]`` standard-normal quantiles at the midpoints of the table's cells.

    Built on first use, not at import: computing it starts JAX's backend, which importing a config
    reader must not do (it would allocate the backend under a caller's memory limit).
    """
    with jax.ensure_compile_time_eval():
        q = ndtri((np.arange(TABLE_SIZE + 1, dtype=np.float64) + 0.5) / (TABLE_SIZE + 1))
    return np.asarray(q, np.float32)


def _mix(x: jnp.ndarray) -> jnp.ndarray:
    """lowbias32: a bijective integer hash with good avalanche."""
    x = x ^ (x >> 16)
    x = x * jnp.uint32(0x7FEB352D)
    x = x ^ (x >> 15)
    x = x * jnp.uint32(0x846CA68B)
    return x ^ (x >> 16)


def _seed(key: jax.Array) -> jnp.ndarray:
    """A well-mixed 32-bit seed from the key's data (two keys' element streams then overlap only by chance)."""
    data = jax.random.key_data(key).reshape(-1).astype(jnp.uint32)
    return _mix(data[0] ^ _mix(data[-1] + jnp.uint32(0x9E3779B9)))


def gaussian(key: jax.Array, shape: tuple[int, ...]) -> jnp.ndarray:
    """``f32[shape]`` standard normal noise from ``key`` (same key, same noise)."""
    n = int(np.prod(shape))
    x = _mix(_mix(jnp.arange(n, dtype=jnp.uint32) + _seed(key)))
    i = (x >> 20).astype(jnp.int32)  # 12 bits: the table entry
    frac = ((x >> 8) & jnp.uint32(0xFFF)).astype(jnp.float32) * jnp.float32(1.0 / 4096)  # the next 12
    table = jnp.asarray(_table())
    lo = table[i]
    return (lo + frac * (table[i + 1] - lo)).reshape(shape)
