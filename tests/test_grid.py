"""GridMap validation, neighbour tables and their corner rules, distance fields."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import jaxplan as jp
from jaxplan.grid import offsets, segment_cells


def test_grid_from_array_validates_layers():
    free = np.ones((3, 4), bool)
    with pytest.raises(ValueError, match=r"layer 'height' has shape \(4, 3\), but the map is \(3, 4\)"):
        jp.grid_from_array(free, height=np.zeros((4, 3)))
    with pytest.raises(ValueError, match="layer 'risk' contains NaN"):
        jp.grid_from_array(free, risk=np.full((3, 4), np.nan))
    with pytest.raises(ValueError, match="layer 'risk' must be >= 0"):
        jp.grid_from_array(free, risk=-np.ones((3, 4)))
    with pytest.raises(ValueError, match="resolution must be a finite number"):
        jp.grid_from_array(free, resolution=0.0)
    with pytest.raises(ValueError, match="resolution must be a finite number"):
        jp.grid_from_array(free, resolution=float("nan"))
    with pytest.raises(ValueError, match="non-empty 2-D"):
        jp.grid_from_array(np.ones(3, bool))
    with pytest.raises(ValueError, match="turn_rule"):
        jp.grid_from_array(free, turn_rule=np.full((3, 4), 2))


def test_grid_from_array_refuses_infinite_height_and_risk():
    # One inf makes every cost through the cell inf (opt_ant then fails silently).
    free = np.ones((3, 4), bool)
    h = np.zeros((3, 4))
    h[1, 2] = np.inf
    with pytest.raises(ValueError, match=r"layer 'height' must be finite, got inf at cell \(2, 1\)"):
        jp.grid_from_array(free, height=h)
    with pytest.raises(ValueError, match=r"layer 'height' must be finite, got -inf"):
        jp.grid_from_array(free, height=-h)
    with pytest.raises(ValueError, match=r"layer 'height' must be finite, got 1e\+39"):  # inf in float32
        jp.grid_from_array(free, height=np.where(np.isinf(h), 1e39, 0.0))
    with pytest.raises(ValueError, match=r"layer 'risk' must be finite, got inf at cell \(2, 1\)"):
        jp.grid_from_array(free, risk=h)
    # A roof-less cell is documented as +inf headroom.
    g = jp.grid_from_array(free, clearance_height=h)
    assert g.clearance_height[1, 2] == np.inf
    with pytest.raises(ValueError, match=r"layer 'height' must be finite"):
        g.replace(height=h)


def test_gridmap_is_a_pytree_and_maps_cells():
    import jax

    g = jp.grid_from_array(np.ones((3, 4), bool), resolution=0.5)
    leaves = jax.tree_util.tree_leaves(g)
    assert len(leaves) == 6
    np.testing.assert_array_equal(g.flat_index([[3, 2], [0, 1]]), [11, 4])
    np.testing.assert_array_equal(g.cell_of([11, 4]), [[3, 2], [0, 1]])
    np.testing.assert_allclose(g.centre([1, 2]), [0.75, 1.25])


def test_offsets_sorted_and_counted():
    for k in (4, 8, 16):
        o = offsets(k)
        assert len(o) == k and len({tuple(m) for m in o}) == k
        ang = np.arctan2(o[:, 1], o[:, 0]) % (2 * np.pi)
        assert np.all(np.diff(ang) > 0)
    with pytest.raises(ValueError, match="connectivity must be one of"):
        offsets(6)


def test_segment_cells_rules():
    assert segment_cells(1, 0) == ()
    assert set(segment_cells(1, 1)) == {(1, 0), (0, 1)}
    assert set(segment_cells(-1, 1)) == {(-1, 0), (0, 1)}
    assert set(segment_cells(1, 2)) == {(0, 1), (1, 1)}
    assert set(segment_cells(2, 1)) == {(1, 0), (1, 1)}
    assert set(segment_cells(-2, -1)) == {(-1, 0), (-1, -1)}


def _expected_crossed(dx: int, dy: int) -> list[tuple[int, int]]:
    """The corner rules of docs/guide/maps-and-scenarios.md, written out by hand (independent of segment_cells)."""
    sx, sy = int(np.sign(dx)), int(np.sign(dy))
    if abs(dx) == 1 and abs(dy) == 1:
        return [(sx, 0), (0, sy)]
    if abs(dy) == 2:
        return [(0, sy), (sx, sy)]
    if abs(dx) == 2:
        return [(sx, 0), (sx, sy)]
    return []


@settings(max_examples=60, deadline=None)
@given(arrays(bool, st.tuples(st.integers(1, 7), st.integers(1, 7))), st.sampled_from([4, 8, 16]))
def test_neighbour_table_matches_hand_rules(free, k):
    g = jp.grid_from_array(free, resolution=0.5)
    t = jp.neighbour_table(g, k)
    H, W = free.shape
    for c in range(H * W):
        x, y = c % W, c // W
        for j, (dx, dy) in enumerate(t.offsets):
            nx, ny = x + dx, y + dy
            ok = free[y, x] and 0 <= nx < W and 0 <= ny < H and free[ny, nx]
            for cx, cy in _expected_crossed(int(dx), int(dy)):
                ok = ok and 0 <= x + cx < W and 0 <= y + cy < H and free[y + cy, x + cx]
            assert t.valid[c, j] == ok
            assert t.index[c, j] == (ny * W + nx if ok else c)
    np.testing.assert_allclose(t.step, 0.5 * np.hypot(t.offsets[:, 0], t.offsets[:, 1]), rtol=1e-6)


def test_vehicle_height_blocks_low_tunnels():
    free = np.ones((1, 3), bool)
    g = jp.grid_from_array(free, clearance_height=np.array([[np.inf, 1.0, np.inf]]))
    assert jp.passable(g, 0.5).all()
    np.testing.assert_array_equal(jp.passable(g, 1.0), [[True, False, True]])
    with pytest.raises(ValueError, match="vehicle_height"):
        jp.passable(g, float("nan"))


def test_clearance_field_hand_values():
    free = np.ones((7, 7), bool)
    free[3, 3] = False
    c = jp.clearance_field(jp.grid_from_array(free, resolution=0.1), border_is_obstacle=False)
    assert c[3, 3] == 0
    np.testing.assert_allclose(c[3, 4], 0.05, rtol=1e-6)  # edge neighbour: half a cell
    np.testing.assert_allclose(c[4, 4], 0.1 * math.sqrt(0.5), rtol=1e-6)  # corner neighbour
    np.testing.assert_allclose(c[3, 5], 0.15, rtol=1e-6)
    np.testing.assert_allclose(c[4, 5], 0.1 * math.hypot(1.5, 0.5), rtol=1e-6)
    np.testing.assert_allclose(c[5, 5], 0.1 * math.hypot(1.5, 1.5), rtol=1e-6)
    # With the border as obstacle the corner cell is half a cell from the outside.
    cb = jp.clearance_field(jp.grid_from_array(free, resolution=0.1))
    np.testing.assert_allclose(cb[0, 0], 0.05, rtol=1e-6)


@settings(max_examples=40, deadline=None)
@given(arrays(bool, st.tuples(st.integers(1, 9), st.integers(1, 9))))
def test_clearance_field_equals_brute_force_point_to_square(free):
    H, W = free.shape
    c = jp.clearance_field(jp.grid_from_array(free, resolution=2.0))
    pad = np.pad(~free, 1, constant_values=True)
    by, bx = np.nonzero(pad)
    for y in range(H):
        for x in range(W):
            # centre (x + 1.5, y + 1.5) in padded coordinates; squares [bx, bx + 1] x [by, by + 1]
            dx = np.maximum(np.maximum(bx - (x + 1.5), (x + 1.5) - (bx + 1)), 0)
            dy = np.maximum(np.maximum(by - (y + 1.5), (y + 1.5) - (by + 1)), 0)
            np.testing.assert_allclose(c[y, x], 2.0 * np.hypot(dx, dy).min(), rtol=1e-5, atol=1e-6)


def test_goal_distance_field_agrees_with_shortest_lengths(movingai):
    g = jp.load_map(movingai / "room-64-64-8.map")
    free_cells = np.argwhere(g.free)[:, ::-1]
    goal = free_cells[100]
    field = jp.goal_distance_field(g, goal)
    starts = free_cells[::37]
    exact = jp.shortest_lengths(g, starts, np.repeat(goal[None], len(starts), 0))
    np.testing.assert_allclose(field[starts[:, 1], starts[:, 0]], exact, rtol=1e-6)
    assert np.isinf(field[~g.free]).all()
    assert field[goal[1], goal[0]] == 0
