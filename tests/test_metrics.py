"""Metrics of docs/guide/smoothing-and-metrics.md against hand-computed values; batching, padding, compilation,
bad input."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxplan as jp
from jaxplan import metrics as M
from jaxplan.grid._collision import collision_map
from jaxplan.metrics._front import _core, bucket

SQ2 = math.sqrt(2.0)


def open_grid(h: int = 8, w: int = 8, res: float = 1.0) -> jp.GridMap:
    return jp.grid_from_array(np.ones((h, w), bool), resolution=res)


# Jitted once per dtype and padded length (eager JAX would compile every op for every shape).
_GEOMETRY = jax.jit(M.geometry_metrics)
_BOUNDS = jax.jit(M.hausdorff_bounds, static_argnames="samples")
_CLEARANCE = jax.jit(M.vertex_clearance)
_HITS = jax.jit(M.collision_steps)
_COLLISIONS = jax.jit(M.collisions)
PAD = 32


def geometry(path, res: float = 1.0) -> dict:
    """JAX geometry metrics of one path (padded to PAD points with NaN), as Python numbers."""
    p = np.asarray(path)
    padded = np.full((PAD, 2), np.nan if p.dtype.kind == "f" else 10**6, p.dtype if p.size else np.int64)
    padded[: len(p)] = p
    return {k: v.item() for k, v in _GEOMETRY(jnp.asarray(padded), len(p), res).items()}


# --------------------------------------------------------------------------------------------
# Path geometry, hand-computed.


def test_straight_line_with_half_metre_cells():
    g = geometry([[0, 0], [1, 0], [2, 0], [3, 0]], res=0.5)
    assert g["length"] == pytest.approx(1.5)
    assert (g["turns"], g["sharp_turns"], g["smoothness"], g["max_curvature"]) == (0, 0, 1.0, 0.0)


def test_l_turn():
    # Legs of 2 and 3 cells at 0.5 m: 2.5 m; one 90° turn; the circle through the right
    # triangle (0,0), (2,0), (2,3) has the hypotenuse √13 cells as diameter: κ = 2/√13 per cell.
    g = geometry([[0, 0], [2, 0], [2, 3]], res=0.5)
    assert g["length"] == pytest.approx(2.5)
    assert (g["turns"], g["sharp_turns"]) == (1, 1)
    assert g["smoothness"] == pytest.approx(0.5)
    assert g["max_curvature"] == pytest.approx(2 / math.sqrt(13) / 0.5, rel=1e-6)


def test_zigzag_of_right_angles():
    # Three 90° turns; every triangle is right-angled at its middle point with hypotenuse 2: R = 1 cell.
    g = geometry([[0, 0], [1, 1], [2, 0], [3, 1], [4, 0]], res=2.0)
    assert g["length"] == pytest.approx(4 * SQ2 * 2.0)
    assert (g["turns"], g["sharp_turns"]) == (3, 3)
    assert g["smoothness"] == pytest.approx(0.5)
    assert g["max_curvature"] == pytest.approx(0.5, rel=1e-6)  # 1 per cell / 2 m per cell


def test_exact_45_degree_turns_are_sharp_and_gentler_ones_are_not():
    # (1,0) -> (1,1) -> (1,0): two turns of exactly 45°, both sharp (the float32 45° test is exact).
    g = geometry([[0, 0], [1, 0], [2, 1], [3, 1]])
    assert (g["turns"], g["sharp_turns"]) == (2, 2)
    assert g["smoothness"] == pytest.approx(0.75)
    # Curvature at (1,0): |cross| = 1, sides 1, √2, √5: κ = 2/√10.
    assert g["max_curvature"] == pytest.approx(2 / math.sqrt(10), rel=1e-6)
    # (1,0) -> (2,1): atan(1/2) = 26.6°, a turn but not sharp.
    g = geometry([[0, 0], [1, 0], [3, 1]])
    assert (g["turns"], g["sharp_turns"]) == (1, 0)
    assert g["smoothness"] == pytest.approx(1 - math.atan(0.5) / math.pi, rel=1e-6)


def test_circle_arc_has_menger_curvature_one_over_r():
    R, res = 5.0, 0.5
    theta = np.linspace(0.0, math.pi / 2, 7)
    arc = np.stack([10 + R * np.cos(theta), 3 + R * np.sin(theta)], axis=1)
    g = geometry(arc, res=res)
    assert g["max_curvature"] == pytest.approx(1 / (R * res), rel=1e-5)
    step = math.pi / 2 / 6
    assert g["turns"] == 5 and g["sharp_turns"] == 0
    assert g["smoothness"] == pytest.approx(1 - step / math.pi, rel=1e-6)
    assert g["length"] == pytest.approx(6 * 2 * R * math.sin(step / 2) * res, rel=1e-6)


def test_repeated_points_are_skipped():
    plain = geometry([[0, 0], [1, 0], [1, 1]])
    repeated = geometry([[0, 0], [0, 0], [1, 0], [1, 0], [1, 0], [1, 1], [1, 1]])
    assert repeated == pytest.approx(plain)
    assert M.heading_changes([[0, 0], [1, 0], [1, 0], [1, 1]]) == pytest.approx([math.pi / 2])


def test_folding_back_is_a_turn_of_pi_with_zero_curvature():
    g = geometry([[0, 0], [2, 0], [0, 0]])
    assert (g["turns"], g["sharp_turns"], g["max_curvature"]) == (1, 1, 0.0)
    assert g["smoothness"] == pytest.approx(0.0, abs=1e-7)


@pytest.mark.parametrize("path", [np.zeros((0, 2), np.int64), np.array([[3, 4]])])
def test_empty_and_one_point_paths(path):
    g = geometry(path)
    assert g == {"length": 0.0, "turns": 0, "sharp_turns": 0, "smoothness": 1.0, "max_curvature": 0.0}
    assert (M.path_length(path), M.count_turns(path), M.count_sharp_turns(path), M.smoothness(path)) == (0.0, 0, 0, 1.0)
    m = M.path_metrics(path, open_grid())
    assert (m.length, m.turns, m.smoothness, m.max_curvature) == (0.0, 0, 1.0, 0.0)
    if len(path) == 0:
        assert m.min_clearance == m.mean_clearance == m.optimality_gap == math.inf
    else:
        assert m.optimality_gap == 0.0  # start = goal
        assert m.min_clearance == m.mean_clearance == pytest.approx(3.5)  # (3, 4) on 8x8: 3.5 cells to the border


# --------------------------------------------------------------------------------------------
# The host functions evaluate the same definitions (numpy, float64).


def test_host_functions_equal_the_jax_ones_on_random_paths():
    rng = np.random.default_rng(0)
    for trial in range(40):
        L = int(rng.integers(1, PAD))
        if trial % 2:
            path = np.cumsum(rng.integers(-1, 2, size=(L, 2)), axis=0)  # integer, with repeats
        else:
            path = rng.normal(size=(L, 2)) * 5
        g = geometry(path, 0.5)
        assert M.path_length(path, 0.5) == pytest.approx(g["length"], rel=1e-6, abs=1e-6)
        assert M.count_turns(path) == g["turns"]
        assert M.count_sharp_turns(path) == g["sharp_turns"]
        assert M.smoothness(path) == pytest.approx(g["smoothness"], abs=1e-6)
        assert M.max_curvature(path, 0.5) == pytest.approx(g["max_curvature"], rel=1e-4)
        if trial < 4:  # eager: one compilation per op and shape
            h, *_, vertex = M.vertex_turns(jnp.asarray(path), L)
            np.testing.assert_allclose(M.heading_changes(path), np.asarray(h)[np.asarray(vertex)], rtol=1e-5,
                                       atol=1e-6)


def test_host_turns_match_planner_turns():
    grid = jp.demo_warehouse().grid
    scene = jp.demo_warehouse()
    res = jp.astar(grid, scene.start, scene.goal)
    assert res.turns == M.count_turns(res.path) == M.path_metrics(res.path, grid).turns


# --------------------------------------------------------------------------------------------
# Clearance.


@pytest.fixture
def pillar():
    """7x7 map at 0.5 m per cell with one blocked cell at (3, 3)."""
    free = np.ones((7, 7), bool)
    free[3, 3] = False
    return jp.grid_from_array(free, resolution=0.5)


def test_clearance_on_a_tiny_map(pillar):
    # (1,1): 1.5 cells to the border, √4.5 to the pillar; (2,2): √0.5 to the pillar's corner;
    # (3,2): 0.5 to its edge. In metres (x 0.5): 0.75, 0.3536, 0.25.
    m = M.path_metrics(np.array([[1, 1], [2, 2], [3, 2]]), pillar)
    assert m.min_clearance == pytest.approx(0.25)
    assert m.mean_clearance == pytest.approx((0.75 + 0.5 * math.sqrt(0.5) + 0.25) / 3, rel=1e-6)
    # Float vertices: (1.5, 1) is 1.5 cells from the top border; (2.9, 2) 0.5 cells above the pillar.
    cmap = collision_map(pillar)
    c = _CLEARANCE(cmap, jnp.array([[1.5, 1.0], [2.9, 2.0], [9.0, 9.0]]), 2)
    np.testing.assert_allclose(np.asarray(c), [0.75, 0.25, np.inf], rtol=1e-6)


def test_integer_and_float_vertices_give_the_same_clearance(pillar):
    cmap = collision_map(pillar)
    cells = np.stack(np.meshgrid(np.arange(7), np.arange(7)), -1).reshape(-1, 2)
    a = _CLEARANCE(cmap, jnp.asarray(cells), len(cells))
    b = _CLEARANCE(cmap, jnp.asarray(cells, jnp.float32), len(cells))
    np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=1e-6)
    assert float(jnp.min(a)) == 0.0  # the pillar itself


def _brute_clearance(free: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Distance (cells) from points to every blocked square, the outside ring included."""
    by, bx = np.nonzero(np.pad(~free, 1, constant_values=True))
    c = np.stack([bx - 1.0, by - 1.0], 1)
    d = np.maximum(np.abs(pts[:, None] - c[None]) - 0.5, 0.0)
    return np.sqrt((d ** 2).sum(-1)).min(1)


def test_float_vertex_clearance_is_exact_far_from_obstacles():
    # One blocked cell in a 21x21 map: (13.4, 12.6) is 3.5805 cells from it, beyond the JAX
    # 2-cell window, where the centre field + offset bound read 4.1012.
    free = np.ones((21, 21), bool)
    free[10, 10] = False
    grid = jp.grid_from_array(free, resolution=0.5)
    pts = np.array([[13.4, 12.6], [13.4, 13.4], [7.4, 13.4], [13.45, 7.45], [3.2, 17.9]])
    want = _brute_clearance(free, pts) * 0.5
    assert want[0] == pytest.approx(0.5 * math.hypot(13.4 - 10.5, 12.6 - 10.5))
    for p, w in zip(pts, want, strict=True):
        m = M.path_metrics(p[None], grid)
        assert m.min_clearance == m.mean_clearance == pytest.approx(w, rel=1e-6)
    rng = np.random.default_rng(5)
    free = rng.random((30, 40)) > 0.15
    pts = rng.uniform(-0.5, [39.5, 29.5], size=(300, 2))
    got = M.path_metrics(pts[:, None, :], jp.grid_from_array(free)).min_clearance
    np.testing.assert_allclose(got, _brute_clearance(free, pts), rtol=1e-6, atol=1e-7)


def test_float_path_clearance_is_measured_along_segments():
    # Line-of-sight output passes the blocked cell (4, 3) between its vertices: the segment
    # (0,2)-(4,4) comes within 0.25/√1.25 = √0.05 of the corner (3.5, 3.5); the vertices are 0.5 away.
    free = np.ones((7, 9), bool)
    free[3, 4] = False
    grid = jp.grid_from_array(free)
    m = M.path_metrics(np.array([[0.0, 2.0], [4.0, 4.0], [8.0, 4.0]]), grid)
    assert m.min_clearance == pytest.approx(math.sqrt(0.05), rel=1e-6)
    # The mean is weighted by arc length: along y = 1 of a 3x7 map the clearance is
    # min(x + 0.5, 6.5 − x, 1.5), whose integral over [0, 6] is 8; sparse and dense
    # vertices of the same line agree.
    open3 = open_grid(3, 7, res=0.5)
    for xs in ([0.0, 6.0], [0.0, 3.0, 6.0], np.linspace(0, 6, 13)):
        line = np.stack([np.asarray(xs, float), np.ones(len(xs))], 1)
        m = M.path_metrics(line, open3)
        assert m.mean_clearance == pytest.approx(0.5 * 8 / 6, rel=1e-6)
        assert m.min_clearance == pytest.approx(0.25, rel=1e-6)
    # Raw grid (integer) paths keep the per-vertex values at the cell centres.
    m = M.path_metrics(np.array([[0, 1], [3, 1], [6, 1]]), open3)
    assert m.mean_clearance == pytest.approx(0.5 * (0.5 + 1.5 + 0.5) / 3, rel=1e-6)


# --------------------------------------------------------------------------------------------
# Hausdorff.


def test_hausdorff_is_between_polylines_not_vertex_sets():
    # B has an extra vertex on A: the polylines coincide (0), the vertex sets do not (2 cells).
    a, b = jnp.array([[0, 0], [4, 0]]), jnp.array([[0, 0], [2, 0], [4, 0]])
    assert float(M.hausdorff(a, 2, b, 3)) == 0.0
    lo, hi = _BOUNDS(a, 2, b, 3, 0.5)
    assert float(lo) == float(hi) == 0.0


def test_hausdorff_of_a_line_and_a_tent():
    # B's apex (2, 3) is 3 cells from A; A's points are at most 3/√2 from B. At 0.5 m: 1.5 m.
    a = jnp.array([[0.0, 0.0], [4.0, 0.0]])
    b = jnp.array([[0.0, 1.0], [2.0, 3.0], [4.0, 1.0]])
    lo, hi = _BOUNDS(a, 2, b, 3, 0.5)
    assert float(lo) == pytest.approx(1.5) and float(hi) == pytest.approx(1.5)


def test_hausdorff_maximum_inside_a_segment():
    # A = base (0,0)-(4,0) plus a spur to (2,3); B = tent (0,1)-(2,3)-(4,1). The farthest point
    # of A from B is A's midpoint (2, 0), at 3/√2 from both arms of the tent (not a vertex);
    # every point of B is within 1.5 of A. So H = 3/√2 exactly.
    a = jnp.array([[0.0, 0.0], [4.0, 0.0], [2.0, 3.0]])
    b = jnp.array([[0.0, 1.0], [2.0, 3.0], [4.0, 1.0]])
    exact = 3 / SQ2
    lo, hi = _BOUNDS(a, 3, b, 3, 1.0, samples=8)  # samples at eighths hit the midpoint
    assert float(lo) == pytest.approx(exact, rel=1e-6)
    assert float(hi) >= exact - 1e-6 and float(hi) - float(lo) <= 4 / 8 / 2 + 1e-6
    lo1, hi1 = _BOUNDS(a, 3, b, 3, 1.0, samples=1)  # vertices only miss it, the bound does not
    assert float(lo1) == pytest.approx(1.0) and float(hi1) >= exact
    # A dense brute force agrees.
    t = np.linspace(0, 1, 4001)[:, None]
    dense = lambda p: np.concatenate([p[i] + t * (p[i + 1] - p[i]) for i in range(len(p) - 1)])  # noqa: E731
    da = np.asarray(M.point_polyline_distance(jnp.asarray(dense(np.asarray(a))), b, 3)).max()
    db = np.asarray(M.point_polyline_distance(jnp.asarray(dense(np.asarray(b))), a, 3)).max()
    assert max(da, db) == pytest.approx(exact, rel=1e-5)


def test_hausdorff_in_path_metrics_and_bad_references():
    grid = open_grid(res=0.5)
    path = np.array([[0, 0], [4, 0]])
    m = M.path_metrics(path, grid, reference=np.array([[0.0, 1.0], [2.0, 3.0], [4.0, 1.0]]))
    assert m.hausdorff == pytest.approx(1.5)
    assert M.path_metrics(path, grid).hausdorff is None
    with pytest.raises(ValueError, match="reference must have shape"):
        M.path_metrics(path, grid, reference=np.zeros((2, 2, 2)))
    with pytest.raises(ValueError, match=r"\[L, 2\] or \[B, L, 2\]"):
        M.path_metrics(path, grid, reference=np.zeros((3, 3)))
    with pytest.raises(ValueError, match="reference has NaN"):
        M.path_metrics(path, grid, reference=np.array([[0.0, np.nan], [1.0, 1.0]]))
    with pytest.raises(ValueError, match="reference has no points"):
        M.path_metrics(path, grid, reference=np.zeros((0, 2)))
    with pytest.raises(ValueError, match="reference must have shape"):
        M.path_metrics(np.stack([path, path]), grid, reference=np.zeros((3, 2, 2)))


# --------------------------------------------------------------------------------------------
# Optimality gap.


def test_optimality_gap_of_raw_grid_paths_is_automatic():
    grid = open_grid(res=0.5)
    optimal = np.array([[0, 0], [1, 1], [2, 1], [3, 1]])  # octile optimum 2 + √2 cells
    assert abs(M.path_metrics(optimal, grid).optimality_gap) < 1e-6
    detour = np.array([[0, 0], [0, 1], [1, 1], [2, 1], [3, 1]])  # 4 cells
    assert M.path_metrics(detour, grid).optimality_gap == pytest.approx(4 / (2 + SQ2) - 1, rel=1e-6)
    # Float, any-angle or 16-connected paths have no automatic optimum.
    assert M.path_metrics(optimal.astype(float), grid).optimality_gap is None
    assert M.path_metrics(np.array([[0, 0], [2, 1]]), grid).optimality_gap is None
    # Given: length 2 m against 1.6 m.
    given = M.path_metrics(np.array([[0.0, 0.0], [4.0, 0.0]]), grid, optimal=1.6)
    assert given.optimality_gap == pytest.approx(0.25)


def test_optimality_gap_rejects_bad_optimum_and_broken_paths():
    grid = open_grid()
    path = np.array([[0, 0], [1, 0]])
    for bad in (-1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match=f"optimal must be finite and >= 0 \\(metres\\), got {bad}"):
            M.path_metrics(path, grid, optimal=bad)
    with pytest.raises(ValueError, match="optimal must be a number"):
        M.path_metrics(path, grid, optimal=[1.0, 2.0])
    free = np.ones((3, 3), bool)
    free[0, 1] = free[1, 0] = False  # the diagonal (0,0)->(1,1) cuts two corners
    free[2, 0] = free[0, 2] = False
    walled = jp.grid_from_array(free)
    with pytest.raises(ValueError, match="cuts a corner"):
        M.path_metrics(np.array([[0, 0], [1, 1]]), walled)


def test_optimality_gap_rejects_illegal_moves_whose_ends_are_connected():
    # Cell (0, 1) blocked: (0,0) and (1,1) are still joined around it (√2 + ... > √2), so the
    # shortcut would read a negative gap.
    free = np.ones((4, 4), bool)
    free[1, 0] = False
    grid = jp.grid_from_array(free)
    with pytest.raises(ValueError, match=r"path step 0, \[0, 0\] -> \[1, 1\], cuts a corner of blocked cell \[0, 1\]"):
        M.path_metrics(np.array([[0, 0], [1, 1]]), grid)
    with pytest.raises(ValueError, match=r"path step 0, \[0, 0\] -> \[0, 1\], enters \[0, 1\], a blocked cell"):
        M.path_metrics(np.array([[0, 0], [0, 1], [0, 2]]), grid)
    with pytest.raises(ValueError, match=r"path 1 starts at \[0, 1\], a blocked cell"):
        M.path_metrics(np.array([[[0, 0], [1, 0]], [[0, 1], [1, 1]]]), grid)
    with pytest.raises(ValueError, match=r"path step 1, \[3, 0\] -> \[4, 0\], enters \[4, 0\], outside the map"):
        M.path_metrics(np.array([[2, 0], [3, 0], [4, 0]]), grid)
    # Padding beyond n is not checked; given an optimum, nothing is.
    ok = M.path_metrics(np.array([[[1, 0], [2, 1], [0, 1]]]), grid, n=np.array([2]))
    assert abs(ok.optimality_gap[0]) < 1e-6
    assert M.path_metrics(np.array([[0, 0], [1, 1]]), grid, optimal=2.0).optimality_gap == pytest.approx(SQ2 / 2 - 1)


# --------------------------------------------------------------------------------------------
# Batches, padding, compilation.


def _batch(rng, B=6, L=20):
    paths = np.cumsum(rng.integers(-1, 2, size=(B, L, 2)), axis=1) + 10
    n = rng.integers(0, L + 1, size=B)
    n[0], n[1] = L, 1
    return np.clip(paths, 0, 19), n


def test_batched_equals_per_path_and_padding_is_ignored():
    rng = np.random.default_rng(1)
    grid = jp.RandomMapGenerator(20, 20, 0.1)(0).grid
    paths, n = _batch(rng)
    batch = M.path_metrics(paths.astype(float), grid, n=n, reference=paths[0, :7].astype(float))
    for b in range(len(paths)):
        one = M.path_metrics(paths[b, : n[b]].astype(float), grid, reference=paths[0, :7].astype(float))
        for k, v in one._asdict().items():
            if v is None:
                assert getattr(batch, k) is None
            else:
                assert getattr(batch, k)[b] == pytest.approx(v, rel=1e-6), (k, b)
    # Garbage (NaN, huge) after n changes nothing.
    dirty = paths.astype(float)
    for b in range(len(paths)):
        dirty[b, n[b]:] = np.where(rng.random((len(paths[0]) - n[b], 2)) < 0.5, np.nan, 1e30)
    again = M.path_metrics(dirty, grid, n=n, reference=paths[0, :7].astype(float))
    for k in M.PATH_METRICS:
        if getattr(batch, k) is not None:
            np.testing.assert_array_equal(getattr(again, k), getattr(batch, k))


def test_jax_functions_vmap_and_jit_like_the_batch():
    rng = np.random.default_rng(2)
    paths, n = _batch(rng)
    p, nn = jnp.asarray(paths), jnp.asarray(n)
    direct = M.geometry_metrics(p, nn, 0.5)
    mapped = jax.jit(jax.vmap(lambda q, k: M.geometry_metrics(q, k, 0.5)))(p, nn)
    for k in direct:
        np.testing.assert_allclose(np.asarray(mapped[k]), np.asarray(direct[k]), rtol=1e-6)
    d1 = M.point_polyline_distance(p[:, :5].astype(jnp.float32), p, nn)
    d2 = jax.vmap(M.point_polyline_distance)(p[:, :5].astype(jnp.float32), p, nn)
    np.testing.assert_allclose(np.asarray(d1), np.asarray(d2))


def test_path_metrics_compiles_once_per_batch_and_length_bucket():
    grid = open_grid(16, 16)
    rng = np.random.default_rng(3)
    paths = np.clip(np.cumsum(rng.integers(-1, 2, size=(4, 16, 2)), axis=1) + 8, 0, 15)
    assert bucket(9) == bucket(16) == 16 and bucket(1) == bucket(0) == 4
    M.path_metrics(paths[:, :9], grid)
    size = _core._cache_size()
    for L in (10, 13, 16):  # same bucket, same batch: no new compilation
        M.path_metrics(paths[:, :L], grid)
        M.path_metrics(paths[:, :L].astype(np.float32), grid, n=np.full(4, L - 2))
    assert _core._cache_size() <= size + 1  # the float dtype is one more signature
    M.path_metrics(paths[:3], grid)
    assert _core._cache_size() <= size + 2


# --------------------------------------------------------------------------------------------
# Bad input at the front.


def test_path_metrics_rejects_bad_paths():
    grid = open_grid()
    with pytest.raises(ValueError, match=r"path has NaN or infinite coordinates \(point 1"):
        M.path_metrics(np.array([[0.0, 0.0], [np.nan, 1.0]]), grid)
    with pytest.raises(ValueError, match=r"path 1, point 0"):
        M.path_metrics(np.array([[[0.0, 0.0]], [[np.inf, 1.0]]]), grid)
    with pytest.raises(ValueError, match=r"shape \[L, 2\] or \[B, L, 2\]"):
        M.path_metrics(np.zeros((3, 3)), grid)
    with pytest.raises(ValueError, match="must hold numbers"):
        M.path_metrics(np.array([["a", "b"]]), grid)
    with pytest.raises(ValueError, match=r"n must lie in \[0, 2\]"):
        M.path_metrics(np.zeros((1, 2, 2)), grid, n=np.array([3]))
    with pytest.raises(ValueError, match=r"n must have shape \[2\]"):
        M.path_metrics(np.zeros((2, 2, 2)), grid, n=np.array([1]))
    # NaN beyond n is padding, not an error.
    assert M.path_metrics(np.array([[[0.0, 0.0], [np.nan, 1.0]]]), grid, n=np.array([1])).length[0] == 0.0


# --------------------------------------------------------------------------------------------
# Run metrics.


def test_converged_iteration():
    h = jnp.array([[jnp.inf, jnp.inf, 12.0, 10.2, 10.05, 10.0],    # 10.05 <= 10 * 1.01 < 10.2
                   [jnp.inf] * 6,                                   # never found a path
                   [5.0] * 6])                                      # converged at once
    np.testing.assert_array_equal(np.asarray(M.converged_iteration(h)), [4, -1, 0])
    assert int(M.converged_iteration(jnp.zeros((0,)))) == -1


def test_diversity():
    costs = jnp.array([[1.0, 3.0, 5.0, jnp.inf],   # mean 3, sample variance (4 + 0 + 4) / 2 = 4
                       [2.0, jnp.inf, jnp.inf, jnp.inf],
                       [7.0, 9.0, jnp.nan, 1.0]])  # the NaN ant is left out, the last is not valid
    valid = jnp.array([[True, True, True, False], [True, False, False, False], [True, True, True, False]])
    np.testing.assert_allclose(np.asarray(M.diversity(costs, valid)), [2.0, 0.0, SQ2], rtol=1e-6)
    # Several colonies form one population: axis (-2, -1).
    two = jnp.array([[1.0, 3.0], [5.0, 7.0]])
    assert float(M.diversity(two, jnp.ones((2, 2), bool), axis=(-2, -1))) == pytest.approx(math.sqrt(20 / 3))


def test_colony_reports_the_run_metrics():
    scene = jp.demo_warehouse()
    r = jp.plan_batch(scene.grid, [scene.start], [scene.goal], planner="aco", seeds=[0, 1], ants=8, iterations=6)
    for h, conv, div, ok in zip(r.history[0], r.converged[0], r.diversity[0], r.successes[0], strict=True):
        final = h[-1]
        assert conv == (np.flatnonzero(h <= final * 1.01)[0] if np.isfinite(final) else -1)  # within 1 %
        assert np.all(div >= 0) and np.all(div[ok < 2] == 0)


# --------------------------------------------------------------------------------------------
# Episode metrics.


def test_rmse_to_the_planned_polyline():
    # Path (0,0)-(4,0) in cells at 1 m: the segment (0.5, 0.5)-(4.5, 0.5) m. Distances 1, 0, 1, 2.
    pos = jnp.array([[0.5, 1.5], [2.5, 0.5], [4.5, -0.5], [6.5, 0.5], [99.0, 99.0]])
    path = jnp.array([[0, 0], [4, 0], [7, 7]])
    got = M.rmse(pos, path, 2, 1.0, n=4)
    assert float(got) == pytest.approx(math.sqrt((1 + 0 + 1 + 4) / 4))
    # At 0.5 m per cell the same path is (0.25, 0.25)-(2.25, 0.25) m.
    assert float(M.rmse(jnp.array([[1.25, 1.25]]), path, 2, 0.5)) == pytest.approx(1.0)
    assert float(M.rmse(pos, path, 0, 1.0)) == math.inf


def test_energy_on_a_hand_made_profile():
    model = M.EnergyModel(mass=2.0, rolling=0.1, gravity=10.0, turn=0.5)
    # Period 0: v 0->1: m|Δv|/dt·∫v = 2·1·0.5 = 1, rolling c_r·m·g·∫v = 2·0.5 = 1.
    # Period 1: v 1->1: rolling 2; ω 0->1: 0.5·0.5 = 0.25.
    # Period 2: v 1->0: 1 + 1; ω 1->-1 crosses zero: ∫|ω| = (1 + 1)/(2·2) = 0.5, so 0.25.
    v = jnp.array([0.0, 1.0, 1.0, 0.0, 5.0])
    w = jnp.array([0.0, 0.0, 1.0, -1.0, 5.0])
    assert float(M.energy(v, w, 1.0, model, n=4)) == pytest.approx(6.5)
    # Reversing from 1 to -1 m/s: m·|Δv|·∫|v| = 2·2·0.5 = 2 = m(v0² + v1²)/2.
    assert float(M.energy(jnp.array([1.0, -1.0]), jnp.zeros(2), 1.0, M.EnergyModel(mass=2.0, rolling=0.0))) == 2.0
    assert float(M.energy(jnp.array([1.0]), jnp.zeros(1), 1.0)) == 0.0
    with pytest.raises(ValueError, match="EnergyModel.mass"):
        M.EnergyModel(mass=-1.0)
    d = M.EnergyModel()
    assert d.turn == pytest.approx(d.rolling * d.mass * d.gravity * 0.2, rel=0.01)


def test_collisions_success_and_timing():
    free = np.ones((5, 5), bool)
    free[2, 2] = False  # blocked square [2, 3] x [2, 3] m at 1 m per cell
    cmap = collision_map(jp.grid_from_array(free))
    # Robot radius 0.3 m: 0.5 m from the square is free, 0.2 and 0.25 m collide.
    pos = jnp.array([[1.5, 2.5], [1.8, 2.5], [1.75, 2.5], [1.5, 2.5], [1.8, 2.5], [1.8, 2.5]])
    np.testing.assert_array_equal(np.asarray(_HITS(cmap, pos, 0.3)), [0, 1, 1, 0, 1, 1])
    assert int(_COLLISIONS(cmap, pos, 0.3)) == 2  # two contacts
    assert int(_COLLISIONS(cmap, pos, 0.3, n=4)) == 1
    # A moving disc of radius 0.2 passes 0.4 m from the robot at sample 1 (< 0.3 + 0.2).
    free_pos = jnp.array([[0.9, 1.3], [0.9, 1.3], [0.9, 1.3]])
    obs = jnp.array([[[4.0, 4.0]], [[0.9, 0.9]], [[jnp.inf, jnp.inf]]])
    hit = _HITS(cmap, free_pos, 0.3, obs, jnp.array([0.2]))
    np.testing.assert_array_equal(np.asarray(hit), [0, 1, 0])
    # Success: within 0.2 m of the goal at t = 0.4 s (sample 2 at dt 0.2), no collision, limit 1 s.
    track = jnp.array([[0.5, 0.5], [0.9, 0.5], [1.4, 0.5], [1.5, 0.5]])
    goal = jnp.array([1.5, 0.5])
    assert float(M.arrival_time(track, goal, 0.2, 0.2)) == pytest.approx(0.4)
    assert bool(M.success(track, goal, 0, tolerance=0.2, dt=0.2, time_limit=1.0))
    assert not bool(M.success(track, goal, 1, tolerance=0.2, dt=0.2, time_limit=1.0))
    assert not bool(M.success(track, goal, 0, tolerance=0.2, dt=0.2, time_limit=0.3))
    assert not bool(M.success(track, goal, 0, tolerance=0.2, dt=0.2, time_limit=1.0, n=2))
    t = M.EpisodeTiming.from_totals(0.5, 2.0, 400)
    assert t == M.EpisodeTiming(plan_time_s=0.5, step_time_s=0.005)
