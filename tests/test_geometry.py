"""jaxplan.core.geometry: the JAX, numpy and numba twins of the point/segment-to-square distances agree."""

import jax
import jax.numpy as jnp
import numba
import numpy as np
import pytest

from jaxplan.core import geometry as G


def _segments(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Random segments and squares, with the special cases mixed in: axis-parallel and degenerate
    segments, half-cell lattice points (touching corners and faces)."""
    rng = np.random.default_rng(seed)
    p, q = rng.uniform(-4, 4, (n, 2)), rng.uniform(-4, 4, (n, 2))
    c = rng.integers(-5, 6, (n, 2)).astype(np.float64)
    k = rng.random(n)
    q[k < 0.1, 0] = p[k < 0.1, 0]
    q[(k >= 0.1) & (k < 0.2), 1] = p[(k >= 0.1) & (k < 0.2), 1]
    lattice = (k >= 0.3) & (k < 0.6)
    p[lattice], q[lattice] = np.round(p[lattice] * 2) / 2, np.round(q[lattice] * 2) / 2
    q[k >= 0.95] = p[k >= 0.95]
    return p, q, c


@numba.njit
def _nb_all(p, q, c):
    out = np.empty((len(p), 3))
    for i in range(len(p)):
        out[i, 0] = G.segment_square_distance_nb(p[i, 0], p[i, 1], q[i, 0], q[i, 1], c[i, 0], c[i, 1])
        out[i, 1] = G.point_square_distance_nb(p[i, 0], p[i, 1], c[i, 0], c[i, 1])
        out[i, 2] = G.point_segment_distance_nb(c[i, 0], c[i, 1], p[i, 0], p[i, 1], q[i, 0], q[i, 1])
    return out


def test_by_hand():
    np.testing.assert_array_equal(G.point_square_distance_np(np.array([[0.0, 0.0], [2.0, 0.0], [2.5, 2.5]]),
                                                             np.zeros(2)), [0.0, 1.5, np.hypot(2.0, 2.0)])
    assert G.point_segment_distance_np(np.array([1.0, 1.0]), np.zeros(2), np.array([2.0, 0.0])) == 1.0
    assert G.point_segment_distance_np(np.array([3.0, 0.0]), np.zeros(2), np.zeros(2)) == 3.0  # degenerate
    # A segment through the square, one touching its corner, one passing above it, one beside it.
    p = np.array([[-2.0, 0.0], [-1.0, 1.0], [-2.0, 1.5], [0.75, -3.0]])
    q = np.array([[2.0, 0.0], [1.0, -1.0], [2.0, 1.5], [0.75, 3.0]])
    np.testing.assert_allclose(G.segment_square_distance_np(p, q, np.zeros((4, 2))), [0.0, 0.0, 1.0, 0.25])


def test_numpy_and_numba_twins_agree_bit_for_bit():
    p, q, c = _segments(20_000)
    nb = _nb_all(p, q, c)
    np.testing.assert_array_equal(nb[:, 0], G.segment_square_distance_np(p, q, c))
    np.testing.assert_array_equal(nb[:, 1], G.point_square_distance_np(p, c))
    np.testing.assert_array_equal(nb[:, 2], G.point_segment_distance_np(c, p, q))


def test_jax_twin_agrees_with_numpy_in_float32():
    p, q, c = (a.astype(np.float32) for a in _segments(20_000, seed=1))
    got = np.asarray(jax.jit(G.segment_square_distance)(jnp.asarray(p), jnp.asarray(q), jnp.asarray(c)))
    want = G.segment_square_distance_np(p.astype(np.float64), q.astype(np.float64), c.astype(np.float64))
    np.testing.assert_allclose(got, want, rtol=0, atol=2e-6)
    np.testing.assert_array_equal(got == 0, want == 0)  # the slab test decides the same contacts
    # numpy in float32 runs the very same operations: same numbers as the JAX twin.
    np.testing.assert_allclose(G.segment_square_distance_np(p, q, c), got, rtol=0, atol=1e-6)
    np.testing.assert_allclose(np.asarray(jax.jit(G.point_square_distance)(p, c)), G.point_square_distance_np(p, c),
                               rtol=0, atol=1e-6)


@pytest.mark.parametrize("shape", [(2,), (7, 2), (3, 5, 2)])
def test_broadcasting(shape):
    rng = np.random.default_rng(2)
    p = rng.uniform(-3, 3, shape)
    q = rng.uniform(-3, 3, shape)
    c = np.zeros(2)
    assert G.segment_square_distance_np(p, q, c).shape == shape[:-1]
    assert np.asarray(G.segment_square_distance(p, q, c)).shape == shape[:-1]
