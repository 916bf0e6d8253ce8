"""Smoothers: hand-computed corners, and properties on random maps checked by brute force."""

from __future__ import annotations

import math

import numpy as np
import pytest

import jaxplan as jp
from jaxplan.metrics import count_sharp_turns, path_length
from jaxplan.smoothing import smooth


def _blocked_squares(grid) -> np.ndarray:
    """Centres (x, y) of every blocked square, including a ring of border cells."""
    free = np.pad(np.asarray(grid.free), 2, constant_values=False)
    ys, xs = np.nonzero(~free)
    return np.stack([xs - 2, ys - 2], axis=1).astype(np.float64)


def _segment_meets_square(p, q, c) -> bool:
    """Liang–Barsky clip of segment p–q against the closed unit square centred at c (float64)."""
    t0, t1 = 0.0, 1.0
    d = q - p
    for k in range(2):
        lo, hi = c[k] - 0.5, c[k] + 0.5
        if d[k] == 0:
            if p[k] < lo or p[k] > hi:
                return False
            continue
        a, b = (lo - p[k]) / d[k], (hi - p[k]) / d[k]
        t0, t1 = max(t0, min(a, b)), min(t1, max(a, b))
        if t0 > t1:
            return False
    return True


def assert_clear(grid, pts: np.ndarray, radius_cells: float = 0.0) -> None:
    """No segment touches a blocked square; with a radius, dense samples keep that distance."""
    sq = _blocked_squares(grid)
    pts = np.asarray(pts, np.float64)
    for p, q in zip(pts[:-1], pts[1:], strict=True):
        near = sq[np.max(np.abs(sq - (p + q) / 2), axis=1) <= np.hypot(*(q - p)) / 2 + 1.0 + radius_cells]
        for c in near:
            assert not _segment_meets_square(p, q, c), f"segment {p}->{q} meets blocked cell {c}"
        if radius_cells > 0 and len(near):
            s = p + np.linspace(0, 1, int(np.hypot(*(q - p)) / 0.01) + 2)[:, None] * (q - p)
            d = np.maximum(np.abs(s[:, None, :] - near[None]) - 0.5, 0)
            assert np.min(np.hypot(d[..., 0], d[..., 1])) >= radius_cells - 1e-4


def _random_cases(seed: int, n_maps: int = 3, per_map: int = 6):
    """Random 16x16 maps (25 % blocked) with A* paths between random connected cells."""
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(n_maps):
        free = rng.random((16, 16)) > 0.25
        grid = jp.grid_from_array(free, resolution=0.5)
        cells = np.argwhere(free)[:, ::-1]
        paths = []
        while len(paths) < per_map:
            s, g = cells[rng.integers(len(cells), size=2)]
            r = jp.astar(grid, s, g)
            if r.success and len(r.path) >= 3:
                paths.append(r.path)
        cases.append((grid, paths))
    return cases


def _pad(paths):
    L = max(len(p) for p in paths)
    return (np.stack([np.concatenate([p, np.repeat(p[-1:], L - len(p), 0)]) for p in paths]).astype(np.float32),
            np.array([len(p) for p in paths]))


@pytest.fixture(scope="module")
def cases():
    return _random_cases(0)


METHODS = ["los", "key_nodes", ("los", "fillet"), ("los", "bezier"), "bspline"]


@pytest.mark.parametrize("method", METHODS, ids=str)
def test_random_maps_clear_shorter_no_new_sharp_turns(cases, method):
    for grid, paths in cases:
        pts, n = _pad(paths)
        out = smooth(pts, grid, method, n=n)
        assert np.all(out.input_free)
        for i, raw in enumerate(paths):
            got = out.points[i, : out.n[i]]
            np.testing.assert_allclose(got[0], raw[0], atol=1e-5)
            np.testing.assert_allclose(got[-1], raw[-1], atol=1e-5)
            assert_clear(grid, got)
            assert count_sharp_turns(got) <= count_sharp_turns(raw)
            # Every smoother here cuts corners inside a free polyline: never longer.
            assert path_length(got) <= path_length(raw) + 1e-4
            if method in ("los", "key_nodes"):  # vertices are a subset, in order
                idx = [int(np.flatnonzero(np.all(raw == v, axis=1))[0]) for v in got]
                assert idx == sorted(idx)


def test_los_with_inflation_keeps_radius(cases):
    grid, paths = cases[1]
    radius_m = 0.4 * 0.5  # 0.4 cells: raw grid paths keep 0.5 cells from walls
    pts, n = _pad(paths)
    out = smooth(pts, grid, ("los", "fillet"), n=n, radius=radius_m)
    for i in range(len(paths)):
        assert_clear(grid, out.points[i, : out.n[i]], radius_cells=0.4)


def test_batch_equals_single(cases):
    grid, paths = cases[2]
    pts, n = _pad(paths)
    batch = smooth(pts, grid, "los", n=n)
    for i, p in enumerate(paths[:3]):
        one = smooth(p, grid, "los")
        np.testing.assert_allclose(one.points, batch.points[i, : batch.n[i]], atol=1e-5)
        assert one.removed == batch.removed[i]


def _open(h=12, w=12, res=0.5, blocked=()):
    free = np.ones((h, w), bool)
    for x, y in blocked:
        free[y, x] = False
    return jp.grid_from_array(free, resolution=res)


L_PATH = np.array([[1, 1], [8, 1], [8, 8]], np.float32)


def test_fillet_hand_computed_arc():
    grid = _open()
    out = smooth(L_PATH, grid, "fillet", radius_max=1.0)  # 1 m = 2 cells at 0.5 m per cell
    R, K = 2.0, 9
    assert out.removed == 1 and out.fallbacks == 0
    assert out.max_curvature == pytest.approx(1.0 / (R * 0.5))
    arc = out.points[1:-1]
    assert len(arc) == K
    np.testing.assert_allclose(arc[0], [6, 1], atol=1e-5)  # tangent points t = R·tan(45°) = 2
    np.testing.assert_allclose(arc[-1], [8, 3], atol=1e-5)
    np.testing.assert_allclose(np.hypot(*(arc - [6, 3]).T), R, atol=1e-5)  # on the circle around (6, 3)
    chords = 2 * R * math.sin(math.pi / 4 / (K - 1))
    assert path_length(out.points) == pytest.approx(5 + 5 + (K - 1) * chords, abs=1e-4)


def test_fillet_shrinks_around_an_obstacle_in_the_corner():
    grid = _open(blocked=[(7, 2)])  # inside the corner: the R=2 arc crosses it, R=1 does not
    out = smooth(L_PATH, grid, "fillet", radius_max=1.0)
    assert out.fallbacks == 0 and out.removed == 1
    assert out.max_curvature == pytest.approx(1.0 / (1.0 * 0.5))
    assert_clear(grid, out.points)


def test_bezier_hand_computed_midpoint():
    grid = _open()
    out = smooth(L_PATH, grid, "bezier", cut_max=1.0, kappa=0.5, samples=9)
    c0, c3, v = np.array([6, 1.0]), np.array([8, 3.0]), np.array([8, 1.0])
    c1, c2 = c0 + 0.5 * (v - c0), c3 + 0.5 * (v - c3)
    mid = (c0 + 3 * c1 + 3 * c2 + c3) / 8
    np.testing.assert_allclose(out.points[1 + 4], mid, atol=1e-5)
    assert 0 < out.max_curvature < np.inf


def test_bspline_pins_vertex_next_to_obstacle():
    free_out = smooth(L_PATH, _open(), "bspline")
    assert free_out.fallbacks == 0 and free_out.removed == 1
    grid = _open(blocked=[(7, 2)])
    out = smooth(L_PATH, grid, "bspline")
    assert_clear(grid, out.points)
    assert out.fallbacks == 1 and out.removed == 0  # the corner is pinned: the curve passes through it
    assert np.any(np.all(np.isclose(out.points, [8, 1]), axis=1))


def test_key_nodes_threshold():
    grid = _open(20, 20, res=1.0)
    # Measured from the last key node: (4,1) turns by 18.4° (dropped at 20°), then (7,2) by
    # 45° − 9.46° = 35.5° (kept), then (9,4) by 0°.
    p = np.array([[1, 1], [4, 1], [7, 2], [9, 4], [11, 6]], np.float32)
    out = smooth(p, grid, "key_nodes")
    np.testing.assert_allclose(out.points, [[1, 1], [7, 2], [11, 6]])
    out = smooth(p, grid, "key_nodes", threshold=10.0)
    np.testing.assert_allclose(out.points, [[1, 1], [4, 1], [7, 2], [11, 6]])


def test_short_paths_unchanged():
    grid = _open()
    for p in (L_PATH[:1], L_PATH[:2]):
        for m in ("los", "fillet"):
            out = smooth(p, grid, m)
            np.testing.assert_allclose(out.points, p)
            assert out.n == len(p)
        out = smooth(p, grid, "bspline")  # samples the straight segment
        np.testing.assert_allclose(out.points[[0, -1]], p[[0, -1]], atol=1e-6)
        assert np.allclose(out.points[:, 1], 1.0) and np.all(np.diff(out.points[:, 0]) > 0)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(path=np.zeros((0, 2))), "empty"),
        (dict(path=np.array([[1.0, 1.0], [np.nan, 2.0]])), "NaN"),
        (dict(path=np.array([[1.0, 1.0], [30.0, 2.0]])), "leaves"),
        (dict(path=L_PATH, method="nope"), "unknown smoother"),
        (dict(path=L_PATH, method="los", spacing=1.0), "not taken"),
        (dict(path=L_PATH, method="fillet", radius_max=-1.0), "radius_max"),
        (dict(path=L_PATH, radius=float("nan")), "radius"),
        (dict(path=L_PATH[None], n=[5]), "n must"),
        (dict(path=L_PATH, method=[]), r"method must name at least one smoother, got \[\]"),
        (dict(path=L_PATH, method=()), "method must name at least one smoother"),
        (dict(path=L_PATH, method="bezier", kappa=5.0), r"bezier'?: kappa must lie in \(0, 1\], got 5.0"),
        (dict(path=L_PATH, method="bezier", kappa=1.0001), "kappa must lie in"),
        (dict(path=L_PATH, method="bezier", kappa=0.0), "kappa must be a finite positive"),
    ],
)
def test_bad_input(kwargs, match):
    kwargs.setdefault("method", "los")
    path = kwargs.pop("path")
    with pytest.raises(ValueError, match=match):
        smooth(path, _open(), **kwargs)


@pytest.mark.parametrize("method", ["fillet", "bezier"])
def test_repeated_corner_vertex_is_still_curved(method):
    grid = _open()
    plain = smooth(L_PATH, grid, method)
    for i in (1, 0, 2):  # the corner, and the ends, repeated
        repeated = np.insert(L_PATH, i, L_PATH[i], axis=0)
        out = smooth(repeated, grid, method)
        assert (out.removed, out.fallbacks) == (1, 0), i
        np.testing.assert_allclose(out.points, plain.points, atol=1e-6)
        assert count_sharp_turns(out.points) == 0


def test_bezier_kappa_one_stays_inside_the_corner():
    out = smooth(L_PATH, _open(), "bezier", kappa=1.0)
    assert out.points[:, 0].max() <= 8 + 1e-5 and out.points[:, 1].min() >= 1 - 1e-5


def test_blocked_input_is_returned_unchanged():
    grid = _open(blocked=[(4, 1)])
    out = smooth(L_PATH, grid, ("los", "fillet"))
    assert not out.input_free
    np.testing.assert_allclose(out.points, L_PATH)
