"""Exact point/segment clearance against blocked cells, checked against brute force over every square."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxplan as jp
from jaxplan.core.geometry import point_square_distance
from jaxplan.grid import TOUCH, collision_map, point_clearance, segment_clearance, segment_free


@pytest.fixture(scope="module")
def scene():
    rng = np.random.default_rng(3)
    free = rng.random((30, 34)) > 0.06
    grid = jp.grid_from_array(free, resolution=0.5)
    ys, xs = np.nonzero(~np.pad(free, 6, constant_values=False))
    squares = np.stack([xs - 6, ys - 6], 1).astype(np.float64)  # border ring included
    return grid, collision_map(grid), squares


def _brute_point(p, squares):
    d = np.maximum(np.abs(squares - p) - 0.5, 0.0)
    return np.min(np.hypot(d[:, 0], d[:, 1]))


def _brute_segment(p, q, squares):
    """Dense sampling (1e-3 cells) of the segment: an upper bound within 5e-4 of the truth."""
    s = p + np.linspace(0, 1, int(np.hypot(*(q - p)) / 1e-3) + 2)[:, None] * (q - p)
    near = squares[np.max(np.abs(squares - (p + q) / 2), 1) <= np.hypot(*(q - p)) / 2 + 3]
    if not len(near):
        return np.inf
    d = np.maximum(np.abs(s[:, None] - near[None]) - 0.5, 0.0)
    return np.min(np.hypot(d[..., 0], d[..., 1]))


def test_point_square_distance_by_hand():
    d = point_square_distance(jnp.array([[0.0, 0.0], [1.0, 0.0], [2.0, 2.0], [0.2, 0.3]]), jnp.zeros(2))
    np.testing.assert_allclose(d, [0.0, 0.5, np.hypot(1.5, 1.5), 0.0], atol=1e-6)


def test_point_clearance_exact_near_and_at_centres(scene):
    grid, cmap, squares = scene
    rng = np.random.default_rng(0)
    pts = rng.uniform(-0.5, [33.5, 29.5], (400, 2))
    pts[:100] = np.round(pts[:100])
    got = np.asarray(jax.jit(lambda x: point_clearance(cmap, x))(pts))
    want = np.array([_brute_point(p, squares) for p in pts])
    assert np.all(got >= want - 1e-5)  # never optimistic
    np.testing.assert_allclose(got[:100], want[:100], atol=1e-5)  # exact at cell centres
    near = want <= 2.0
    np.testing.assert_allclose(got[near], want[near], atol=1e-5)  # exact within the window
    assert np.all(got - want <= np.sqrt(2) + 1e-5)


@pytest.mark.parametrize("radius", [0.0, 0.3, 1.2])
def test_segment_decision_matches_brute_force(scene, radius):
    grid, cmap, squares = scene
    rng = np.random.default_rng(1)
    p = rng.uniform(0, [33, 29], (150, 2))
    q = np.clip(p + rng.normal(0, 5, (150, 2)), -0.4, [33.4, 29.4])
    got = np.asarray(jax.jit(jax.vmap(lambda a, b: segment_free(cmap, a, b, radius)))(p, q))
    clear = np.asarray(jax.jit(jax.vmap(lambda a, b: segment_clearance(cmap, a, b, radius)))(p, q))
    want = np.array([_brute_segment(a, b, squares) for a, b in zip(p, q, strict=True)])
    thr = max(radius, TOUCH)
    decided = np.abs(want - thr) > 1e-3  # sampling brute force is only good to 5e-4
    assert np.array_equal(got[decided], (want >= thr)[decided])
    assert np.all(clear >= want - 1e-3)
    assert 0.1 < np.mean(got) < 0.9  # both outcomes occur


def test_touching_a_corner_is_a_collision():
    grid = jp.grid_from_array(np.array([[True, False], [True, True]]))
    cmap = collision_map(grid)
    # (0,0) -> (1,1) passes exactly through the corner of blocked cell (1,0): the grid forbids it too.
    assert not bool(segment_free(cmap, jnp.array([0.0, 0.0]), jnp.array([1.0, 1.0])))
    assert bool(segment_free(cmap, jnp.array([0.0, 0.0]), jnp.array([0.0, 1.0])))
    assert bool(segment_free(cmap, jnp.array([0.0, 0.0]), jnp.array([0.0, 1.0]), 0.5))  # clearance == radius
    assert not bool(segment_free(cmap, jnp.array([0.0, 0.0]), jnp.array([0.0, 1.0]), 0.51))
