"""The search box: named, validated bounds, and the maps between the box and the unit cube.

Every optimiser of `jaxplan.tune` searches a box ``low <= x <= high`` (``D`` dimensions,
one per scalar weight; a vector weight such as IACO's ``lambdas`` contributes one
dimension per component, named ``lambdas[0]``, ``lambdas[1]``, …). Positivity is a
property of the box: a weight that must stay positive gets ``low > 0`` (or ``low = 0`` if
zero is allowed), and no optimiser ever returns a point outside the box.

Internally the strategies work in the unit cube ``z ∈ [0, 1]^D`` (``x = low + z·(high − low)``),
so one step size means the same thing in every dimension. Points leaving the cube are
brought back by reflection (`reflect`, the default of the evolution strategies: it keeps
the sampling distribution's shape near a bound instead of piling mass on the face) or by
clipping (`clip`, what the sparrow searches' reference code does).
"""

from __future__ import annotations

import math
from typing import Mapping, NamedTuple, Sequence

import jax.numpy as jnp
import numpy as np
from numpy.typing import ArrayLike

__all__ = ["Bounds", "make_bounds", "to_unit", "from_unit", "reflect", "clip"]


class Bounds(NamedTuple):
    """A validated box.

    Attributes:
      low, high: ``f32[D]`` with ``low < high`` and both finite.
      names: ``D`` names, one per dimension (``"alpha"``, ``"lambdas[0]"``, …).
    """

    low: np.ndarray
    high: np.ndarray
    names: tuple[str, ...]

    @property
    def dim(self) -> int:
        return len(self.names)

    def contains(self, x: ArrayLike) -> np.ndarray:
        """``bool[...]``: every coordinate of ``x [..., D]`` lies in the box."""
        x = np.asarray(x)
        return np.all((x >= self.low) & (x <= self.high), axis=-1)


def make_bounds(space: Mapping[str, Sequence] | Sequence[tuple[str, float, float]]) -> Bounds:
    """Builds and validates a box.

    Args:
      space: ``{name: (low, high)}`` for scalars, ``{name: [(low, high), …]}`` for vector
        weights (one pair per component), or a sequence of ``(name, low, high)`` triples.

    Returns:
      `Bounds`.

    Raises:
      ValueError: naming the parameter, if a bound is not a finite number or ``low >= high``,
        or if the space is empty.
    """
    rows: list[tuple[str, float, float]] = []
    items = space.items() if isinstance(space, Mapping) else [(n, (lo, hi)) for n, lo, hi in space]
    for name, b in items:
        pairs = list(b)
        if len(pairs) == 2 and all(np.ndim(v) == 0 for v in pairs):
            rows.append((str(name), pairs[0], pairs[1]))
        else:
            for i, pair in enumerate(pairs):
                if np.ndim(pair) != 1 or len(pair) != 2:
                    raise ValueError(f"bounds of {name}[{i}]: expected a (low, high) pair, got {pair!r}")
                rows.append((f"{name}[{i}]", pair[0], pair[1]))
    if not rows:
        raise ValueError("the search space is empty: give at least one parameter with (low, high) bounds")
    for name, lo, hi in rows:
        for what, v in (("low", lo), ("high", hi)):
            if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) or not math.isfinite(v):
                raise ValueError(f"bounds of {name!r}: {what} must be a finite number, got {v!r}")
        if not lo < hi:
            raise ValueError(f"bounds of {name!r}: need low < high, got low={lo!r}, high={hi!r}")
    names = tuple(r[0] for r in rows)
    if len(set(names)) != len(names):
        raise ValueError(f"duplicate parameter names in the search space: {names}")
    return Bounds(np.array([r[1] for r in rows], np.float32), np.array([r[2] for r in rows], np.float32), names)


def to_unit(bounds: Bounds, x: jnp.ndarray) -> jnp.ndarray:
    """``x [..., D]`` in the box → ``z`` in the unit cube."""
    return (x - bounds.low) / (bounds.high - bounds.low)


def from_unit(bounds: Bounds, z: jnp.ndarray) -> jnp.ndarray:
    """``z [..., D]`` in the unit cube → ``x`` in the box (no repair: repair first)."""
    return bounds.low + z * (bounds.high - bounds.low)


def reflect(z: jnp.ndarray) -> jnp.ndarray:
    """Folds ``z`` back into ``[0, 1]`` by mirror reflection at the faces (periodic with period 2)."""
    m = jnp.mod(z, 2.0)
    return jnp.where(m > 1.0, 2.0 - m, m)


def clip(z: jnp.ndarray) -> jnp.ndarray:
    """Projects ``z`` onto ``[0, 1]``."""
    return jnp.clip(z, 0.0, 1.0)
