"""Cosine/sine and arctangent as short polynomials, because XLA's CPU versions are not vectorised.

On the CPU backend ``jnp.sin``, ``jnp.cos`` and ``jnp.arctan2`` cost 10–40 ns per element
(scalar library calls), against under 1 ns for a multiply-add: a step's 800 samples
would spend more time in the three of them than in the whole dynamic window. These two
functions are elementwise polynomials that XLA fuses and vectorises, accurate to about
float32 rounding on the ranges the planner needs, and differentiable.
"""

from __future__ import annotations

import math

import jax.numpy as jnp
from jax import lax

__all__ = ["rotor", "abs_angle", "MAX_ROTOR_ANGLE"]

MAX_ROTOR_ANGLE = math.pi / 2
"""`rotor` is accurate for |angle| up to this (the planner validates ω_max·dt/2 against it)."""

_HALVINGS = 2  # angle / 4 <= π/8 before the Taylor series; squared back twice


def rotor(angle: jnp.ndarray) -> jnp.ndarray:
    """``e^{i·angle}`` (complex64) for |angle| <= `MAX_ROTOR_ANGLE`, to about 2e-7.

    Taylor series to the 10th/11th power at angle/4 (|angle/4| <= 0.393, truncation below
    1e-13), two squarings back to the full angle, and a renormalisation to unit length (so
    the rotor neither grows nor shrinks under the rollouts' repeated multiplication).
    Written with complex products so that XLA keeps it in one fused kernel.
    """
    x = angle * (1.0 / 2**_HALVINGS)
    x2 = x * x
    c = 1.0 + x2 * (-1 / 2 + x2 * (1 / 24 + x2 * (-1 / 720 + x2 * (1 / 40320 + x2 * (-1 / 3628800)))))
    s = x * (1.0 + x2 * (-1 / 6 + x2 * (1 / 120 + x2 * (-1 / 5040 + x2 * (1 / 362880 + x2 * (-1 / 39916800))))))
    z = lax.complex(c, s)
    for _ in range(_HALVINGS):
        z = z * z
    return z * lax.rsqrt(jnp.real(z * jnp.conj(z))).astype(z.dtype)


def abs_angle(cross: jnp.ndarray, dot: jnp.ndarray) -> jnp.ndarray:
    """``|atan2(cross, dot)|`` in [0, π]: the angle between two vectors from their cross and dot products.

    Cephes' single-precision arctangent (range reduction to [0, tan(π/8)], a degree-9 odd
    polynomial; about 1e-7 relative) on min/max of |cross| and |dot|, then the octant
    fix-ups. Returns 0 for (0, 0); the gradient there is 0 rather than NaN.
    """
    y, x = jnp.abs(cross), jnp.abs(dot)
    hi, lo = jnp.maximum(x, y), jnp.minimum(x, y)
    r = lo / jnp.where(hi > 0, hi, 1.0)  # in [0, 1]
    big = r > 0.41421356  # tan(π/8): reduce with atan(r) = π/4 + atan((r − 1)/(r + 1))
    z = jnp.where(big, (r - 1.0) / (r + 1.0), r)
    z2 = z * z
    p = ((((8.05374449538e-2 * z2 - 1.38776856032e-1) * z2 + 1.99777106478e-1) * z2 - 3.33329491539e-1) * z2 * z
         + z)
    a = jnp.where(big, math.pi / 4 + p, p)  # atan(lo / hi) in [0, π/4]
    a = jnp.where(y > x, math.pi / 2 - a, a)  # atan(y / x) in [0, π/2]
    return jnp.where(dot < 0, math.pi - a, a)
