"""Sampling planners (RRT*, MRBS-RRT*) and key-node-guided A*: validity, reproducibility, bad input."""

from __future__ import annotations

import inspect
import math

import jax
import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from numba import njit
from scipy.sparse.csgraph import dijkstra

import jaxplan as jp
from jaxplan.grid._collision import cached_collision_map, polyline_free
from jaxplan.metrics._host import heading_changes
from jaxplan.search import _sampling as S
from jaxplan.search._kng import astar_kng
from jaxplan.search._sampling import mrbs_rrt, rrt_star

SAMPLERS = ("rrt_star", "mrbs_rrt")
_PAD = 256


@pytest.fixture(scope="module")
def random32() -> jp.GridMap:
    """A 32x32 map with 20 % random blocks (fixed seed), resolution 0.5 m."""
    free = np.random.default_rng(3).random((32, 32)) > 0.2
    free[2, 2] = free[29, 29] = True
    return jp.grid_from_array(free, resolution=0.5)


@pytest.fixture(scope="module")
def corridor() -> jp.GridMap:
    """Two 8x8 rooms joined by a 1-cell corridor (row 4, columns 8-13), resolution 1 m."""
    free = np.zeros((10, 22), bool)
    free[1:9, 0:8] = True
    free[1:9, 14:22] = True
    free[4, 8:14] = True
    return jp.grid_from_array(free)


_free_fn = jax.jit(polyline_free, static_argnums=3)


def _segments_free(grid: jp.GridMap, pts: np.ndarray, radius_cells: float) -> np.ndarray:
    """``bool[L-1]`` under the JAX exact segment test (float32), padded to one compiled shape."""
    assert len(pts) <= _PAD
    padded = np.concatenate([pts, np.repeat(pts[-1:], _PAD - len(pts), axis=0)]).astype(np.float32)
    ok = _free_fn(cached_collision_map(grid), padded, np.int32(len(pts)), float(radius_cells))
    return np.asarray(ok)[: len(pts) - 1]


@njit(cache=True)
def _crosses(blocked, px, py, qx, qy):
    """Whether segment p–q enters the open interior of a blocked square (touching is allowed)."""
    H, W = blocked.shape
    h = 0.5 - 1e-9
    for y in range(max(int(math.floor(min(py, qy))), 0), min(int(math.ceil(max(py, qy))), H - 1) + 1):
        for x in range(max(int(math.floor(min(px, qx))), 0), min(int(math.ceil(max(px, qx))), W - 1) + 1):
            if not blocked[y, x]:
                continue
            lo, hi = 0.0, 1.0
            ok = True
            for a, d, c in ((px, qx - px, float(x)), (py, qy - py, float(y))):
                if d == 0.0:
                    ok = ok and abs(a - c) < h
                else:
                    t1, t2 = (c - h - a) / d, (c + h - a) / d
                    lo, hi = max(lo, min(t1, t2)), min(hi, max(t1, t2))
            if ok and lo < hi:
                return True
    return False


@njit(cache=True)
def _visibility(blocked, nodes):
    n = nodes.shape[0]
    w = np.zeros((n, n))
    for i in range(n):
        for j in range(i + 1, n):
            if not _crosses(blocked, nodes[i, 0], nodes[i, 1], nodes[j, 0], nodes[j, 1]):
                w[i, j] = math.hypot(nodes[i, 0] - nodes[j, 0], nodes[i, 1] - nodes[j, 1]) + 1e-300
    return w


def any_angle_optimum(grid: jp.GridMap, start, goal) -> float:
    """Shortest any-angle length (m) when paths may touch blocked squares: a lower bound for
    any collision-free polyline. Visibility graph over the corners where a taut path can
    bend (one blocked cell of four, or two diagonal ones); segments between points of the
    map rectangle stay inside it, so the border needs no squares."""
    free = np.asarray(grid.free, bool)
    pad = np.pad(~free, 1, constant_values=True)
    a, b, c, d = pad[1:, 1:], pad[1:, :-1], pad[:-1, 1:], pad[:-1, :-1]  # around corner (x + ½, y + ½)
    nb = a.astype(int) + b + c + d
    cy, cx = np.nonzero((nb == 1) | ((nb == 2) & ((a & d) | (b & c))))
    nodes = np.concatenate([[start, goal], np.stack([cx - 0.5, cy - 0.5], 1)]).astype(float)
    w = _visibility(~free, nodes)
    return float(dijkstra(sp.csr_array(w), directed=False, indices=0)[1]) * float(grid.resolution)


def _assert_grid_path(grid: jp.GridMap, p: np.ndarray, start, goal) -> None:
    assert p.dtype == np.int64 and p.ndim == 2 and p.shape[1] == 2
    assert tuple(p[0]) == tuple(start) and tuple(p[-1]) == tuple(goal)
    assert grid.free[p[:, 1], p[:, 0]].all(), "grid path enters a blocked cell"
    d = np.diff(p, axis=0)
    assert np.all(np.abs(d).max(axis=1) == 1), "grid path steps are not 8-connected moves"
    diag = np.flatnonzero(np.all(np.abs(d) == 1, axis=1))
    a, b = p[diag], p[diag + 1]
    assert grid.free[a[:, 1], b[:, 0]].all() and grid.free[b[:, 1], a[:, 0]].all(), "grid path cuts a corner"


def _point_polyline(c: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Distance of points ``c [N, 2]`` to the polyline ``pts [L, 2]``."""
    if len(pts) == 1:
        return np.linalg.norm(c - pts[0], axis=1)
    p, q = pts[:-1][None], pts[1:][None]
    d = q - p
    dd = np.maximum((d * d).sum(-1), 1e-30)
    t = np.clip(((c[:, None] - p) * d).sum(-1) / dd, 0, 1)
    return np.linalg.norm(c[:, None] - (p + t[..., None] * d), axis=-1).min(axis=1)


def _assert_rrt_result(grid: jp.GridMap, r: jp.PlanResult, start, goal, robot_radius: float = 0.0) -> None:
    res = grid.resolution
    assert r.success, r.info
    pts = r.info["points"]
    assert pts.dtype == np.float64 and pts.ndim == 2 and pts.shape[1] == 2
    np.testing.assert_array_equal(pts[0], start)
    np.testing.assert_array_equal(pts[-1], goal)
    assert _segments_free(grid, pts, robot_radius / res).all(), "a polyline segment collides"
    _assert_grid_path(grid, r.path, start, goal)
    # The grid path follows the polyline: each of its cells is one the polyline passes through.
    assert _point_polyline(r.path.astype(float), pts).max() <= math.sqrt(2) / 2 + 1e-9
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    assert np.isclose(r.length, seg.sum() * res) and r.cost == r.length
    assert r.length >= np.linalg.norm(np.subtract(goal, start)) * res - 1e-9
    assert r.length >= any_angle_optimum(grid, start, goal) - 1e-9
    assert np.isclose(r.info["grid_length"], jp.search.path_cost(r.path, res))
    h = r.history
    assert np.all(np.diff(h[np.isfinite(h)]) <= 1e-9), "best cost increased"
    assert np.isclose(h[-1], r.length)
    assert r.turns == jp.metrics._host.count_turns(pts)


# --- validity -------------------------------------------------------------------------------


@pytest.mark.parametrize("planner", SAMPLERS)
@pytest.mark.parametrize("robot_radius", [0.0, 0.1])
def test_paths_are_collision_free_and_consistent(random32, planner, robot_radius):
    start, goal = (2, 2), (29, 29)
    r = jp.plan(random32, start, goal, planner=planner, seed=1, iterations=2000, robot_radius=robot_radius)
    assert r.planner == planner and len(r.history) == 2000
    _assert_rrt_result(random32, r, start, goal, robot_radius)
    assert r.length <= 1.2 * any_angle_optimum(random32, start, goal)  # 2,000 iterations: within 5-10 %


@pytest.mark.parametrize("planner", SAMPLERS)
def test_room_map_with_pocket(room, planner):
    grid, starts, goals = room
    for s, g in zip(starts, goals, strict=True):
        r = jp.plan(grid, s, g, planner=planner, seed=0, iterations=1500)
        _assert_rrt_result(grid, r, s, g)


def test_radius_keeps_clearance_through_a_corridor(corridor):
    start, goal = (2, 4), (19, 4)
    r = rrt_star(corridor, start, goal, seed=0, iterations=2000, robot_radius=0.3)
    _assert_rrt_result(corridor, r, start, goal, robot_radius=0.3)
    # Inside the 1-cell corridor the only way through keeps within 0.2 of its centre line.
    pts = r.info["points"]
    inside = (pts[:, 0] > 8.5) & (pts[:, 0] < 12.5)
    assert inside.any() and np.all(np.abs(pts[inside, 1] - 4) <= 0.2)


def test_rrt_star_near_optimal_on_an_open_map():
    grid = jp.grid_from_array(np.ones((32, 32), bool))
    start, goal = (1, 3), (30, 25)
    r = rrt_star(grid, start, goal, seed=0, iterations=3000)
    _assert_rrt_result(grid, r, start, goal)
    euclid = math.dist(start, goal)
    assert any_angle_optimum(grid, start, goal) == pytest.approx(euclid)
    assert euclid <= r.length <= 1.05 * euclid  # the straight line is the any-angle optimum
    assert r.length <= jp.astar(grid, start, goal).length


def test_scenario_rows_of_a_movingai_map(movingai):
    grid = jp.load_map(movingai / "random-32-32-20.map")
    scen = jp.load_scenarios(movingai / "random-32-32-20-random-1.scen", grid=grid)
    for i in (120, 400):
        for planner in SAMPLERS:
            r = jp.plan(grid, scen.starts[i], scen.goals[i], planner=planner, seed=0)
            _assert_rrt_result(grid, r, scen.starts[i], scen.goals[i])
            assert r.length <= 1.15 * any_angle_optimum(grid, scen.starts[i], scen.goals[i])
            assert r.length <= 1.1 * scen.optimal[i]  # any-angle paths are mostly shorter than octile ones


def test_start_equals_goal(random32):
    r = rrt_star(random32, (2, 2), (2, 2), iterations=10)
    assert r.success and r.length == 0.0
    np.testing.assert_array_equal(r.path, [[2, 2]])
    np.testing.assert_array_equal(r.info["points"], [[2.0, 2.0]])


def test_history_finds_then_improves(random32):
    r = mrbs_rrt(random32, (2, 2), (29, 29), seed=4, iterations=2000)
    first = r.info["first_solution"]
    assert 0 <= first < 2000 and np.all(np.isinf(r.history[:first])) and np.isfinite(r.history[first])
    assert r.history[-1] <= r.history[first]


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31 - 1), density=st.floats(0.0, 0.4), planner=st.sampled_from(SAMPLERS))
def test_random_maps_give_valid_paths_or_reasons(seed, density, planner):
    rng = np.random.default_rng(seed)
    free = rng.random((12, 12)) >= density
    cells = np.argwhere(free)[:, ::-1]
    if len(cells) < 2:
        return
    start, goal = cells[rng.choice(len(cells), 2, replace=False)]
    grid = jp.grid_from_array(free)
    r = jp.plan(grid, start, goal, planner=planner, seed=seed, iterations=600)
    if not jp.astar(grid, start, goal).success:
        assert not r.success and "component" in r.info["reason"]
        return
    if not r.success:
        assert "budget" in r.info["reason"]
        return
    pts = r.info["points"]
    assert all(S.segment_clear(grid, a, b) for a, b in zip(pts[:-1], pts[1:], strict=True))
    _assert_grid_path(grid, r.path, start, goal)
    assert r.length >= any_angle_optimum(grid, start, goal) - 1e-9


# --- reproducibility ------------------------------------------------------------------------


@pytest.mark.parametrize("planner", SAMPLERS)
def test_same_seed_same_result_other_seed_differs(random32, planner):
    a, b, c = (jp.plan(random32, (2, 2), (29, 29), planner=planner, seed=s, iterations=800) for s in (7, 7, 8))
    np.testing.assert_array_equal(a.info["points"], b.info["points"])
    np.testing.assert_array_equal(a.path, b.path)
    np.testing.assert_array_equal(a.history, b.history)
    assert a.length == b.length
    assert a.info["points"].shape != c.info["points"].shape or not np.array_equal(a.info["points"], c.info["points"])


# --- failures -------------------------------------------------------------------------------


@pytest.mark.parametrize("planner", SAMPLERS)
def test_unreachable_goal_is_a_failed_result(planner):
    free = np.ones((10, 10), bool)
    free[:, 5] = False
    r = jp.plan(jp.grid_from_array(free), (1, 1), (8, 8), planner=planner)
    assert not r.success and r.length == math.inf and r.path.shape == (0, 2)
    assert "component" in r.info["reason"]


def test_diagonal_gap_is_not_a_passage():
    # Two free cells touching only at a corner: the continuous free space is disconnected there.
    free = np.array([[1, 1, 0, 0], [1, 1, 0, 0], [0, 0, 1, 1], [0, 0, 1, 1]], bool)
    r = rrt_star(jp.grid_from_array(free), (0, 0), (3, 3))
    assert not r.success and "component" in r.info["reason"]


def test_budget_exhausted_is_a_failed_result(corridor):
    r = rrt_star(corridor, (2, 4), (19, 4), iterations=5)
    assert not r.success and "budget" in r.info["reason"] and len(r.history) == 5
    # A robot wider than the corridor never gets through either.
    r = mrbs_rrt(corridor, (2, 4), (19, 4), iterations=300, robot_radius=0.6)
    assert not r.success and "budget" in r.info["reason"]


# --- bad input ------------------------------------------------------------------------------


@pytest.mark.parametrize("planner", SAMPLERS)
@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(start=(10, 2)), "blocked"),
        (dict(goal=(40, 4)), "outside"),
        (dict(step=float("nan")), "NaN"),
        (dict(step=-1.0), "step"),
        (dict(radius=0.0), "radius"),
        (dict(goal_bias=float("nan")), "NaN"),
        (dict(goal_bias=1.0), "goal_bias"),
        (dict(robot_radius=-0.1), "robot_radius"),
        (dict(robot_radius=float("inf")), "robot_radius"),
        (dict(iterations=0), "iterations"),
        (dict(iterations=2.5), "iterations"),
        (dict(start=(0, 1), robot_radius=0.7), "closer than robot_radius"),
        (dict(bogus=1), "no parameter"),
    ],
)
def test_bad_input_raises(corridor, planner, kwargs, match):
    kw = {"start": (2, 4), "goal": (19, 4), **kwargs}
    with pytest.raises(ValueError, match=match):
        jp.plan(corridor, kw.pop("start"), kw.pop("goal"), planner=planner, **kw)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(p_start=0.5), "sum to 1"),
        (dict(p_norm=0.0), "sum to 1"),
        (dict(p_obs=-0.2, p_norm=0.9), "p_obs"),
        (dict(p_end=float("nan")), "NaN"),
        (dict(obs_band=-1.0), "obs_band"),
    ],
)
def test_bad_region_probabilities(corridor, kwargs, match):
    with pytest.raises(ValueError, match=match):
        jp.plan(corridor, (2, 4), (19, 4), planner="mrbs_rrt", **kwargs)
    with pytest.raises(ValueError, match=match):
        mrbs_rrt(corridor, (2, 4), (19, 4), **kwargs)  # direct calls validate too


def test_registry_defaults_match_signatures():
    for name, fn in (("rrt_star", rrt_star), ("mrbs_rrt", mrbs_rrt), ("astar_kng", astar_kng)):
        spec = jp.planners()[name]
        sig = {k: p.default for k, p in inspect.signature(fn).parameters.items() if p.kind is p.KEYWORD_ONLY}
        assert dict(spec.defaults) == sig, name
    assert jp.search.rrt_star is rrt_star and jp.search.mrbs_rrt is mrbs_rrt and jp.search.astar_kng is astar_kng


# --- MRBS sampler ---------------------------------------------------------------------------


def test_mrbs_samples_land_in_their_regions_with_the_configured_frequencies(random32):
    probs = S.region_probabilities(0.05, 0.1, 0.2, 0.3, 0.4)
    np.testing.assert_allclose(probs, [0.05, 0.095, 0.19, 0.285, 0.38])
    regions = S.sampling_regions(random32, (2, 2), (29, 29), probs, robot_radius=0.0, obs_band=0.5)
    n = 40_000
    pts, reg = S.mrbs_sample(regions, np.random.default_rng(0).random((n, 4)), r_start=4.0, r_end=2.5)
    freq = np.bincount(reg, minlength=5) / n
    sigma = np.sqrt(probs * (1 - probs) / n)
    assert np.all(np.abs(freq - probs) < 5 * sigma), (freq, probs)
    assert np.all(pts[reg == 0] == [29, 29])
    ds = np.linalg.norm(pts[reg == 1] - [2, 2], axis=1)
    de = np.linalg.norm(pts[reg == 2] - [29, 29], axis=1)
    assert ds.max() <= 4.0 and de.max() <= 2.5
    # Uniform over the disc's area: half the samples within radius / sqrt(2).
    assert abs(np.mean(ds <= 4.0 / math.sqrt(2)) - 0.5) < 0.03
    field = jp.clearance_field(random32) / random32.resolution  # cells
    cells = np.rint(pts).astype(int)
    obs, norm = cells[reg == 3], cells[reg == 4]
    assert random32.free[obs[:, 1], obs[:, 0]].all() and random32.free[norm[:, 1], norm[:, 0]].all()
    assert field[obs[:, 1], obs[:, 0]].max() <= 0.5 / 0.5 + 1e-6  # obs_band 0.5 m = 1 cell
    assert field[norm[:, 1], norm[:, 0]].mean() > field[obs[:, 1], obs[:, 0]].mean() + 0.05
    # The uniform region is the start's component and nothing else.
    comp = S._components(np.asarray(random32.free))
    assert np.all(comp[norm[:, 1], norm[:, 0]] == comp[2, 2])


def test_mrbs_sample_rejects_bad_uniforms(random32):
    regions = S.sampling_regions(random32, (2, 2), (29, 29), S.region_probabilities(0, 0, 0, 0, 1))
    with pytest.raises(ValueError, match="uniforms"):
        S.mrbs_sample(regions, np.zeros((5, 3)), 1.0, 1.0)


@pytest.mark.parametrize("region", ["p_start", "p_end", "p_obs", "p_norm"])
def test_mrbs_with_one_region_only(random32, region):
    ps = {"p_start": 0.0, "p_end": 0.0, "p_obs": 0.0, "p_norm": 0.0, region: 1.0}
    r = mrbs_rrt(random32, (2, 2), (29, 29), seed=0, iterations=3000, **ps)
    if region in ("p_obs", "p_norm"):  # these cover the free space and so find the goal
        _assert_rrt_result(random32, r, (2, 2), (29, 29))
    else:  # the discs alone need not reach past the obstacles; a failure is a result
        assert r.success or "budget" in r.info["reason"]


# --- kernels --------------------------------------------------------------------------------


def test_nearest_bins_agree_with_brute_force():
    rng = np.random.default_rng(0)
    W = H = 40
    size = 3.0
    nbx, nby = int(W / size) + 1, int(H / size) + 1
    pts = rng.uniform(-0.5, 39.5, (300, 2))
    head = np.full(nbx * nby, -1, np.int64)
    nxt = np.full(300, -1, np.int64)
    for k, (x, y) in enumerate(pts):
        b = S._bin(y, size, nby) * nbx + S._bin(x, size, nbx)
        nxt[k], head[b] = head[b], k
    for q in rng.uniform(-10, 50, (500, 2)):  # also outside the map (disc samples may be)
        k, d2 = S._nearest(head, nxt, nbx, nby, size, pts[:, 0], pts[:, 1], q[0], q[1])
        assert np.isclose(d2, ((pts - q) ** 2).sum(1).min())


def test_segment_test_agrees_with_the_jax_test(random32):
    rng = np.random.default_rng(1)
    p = rng.uniform(-0.5, 31.5, (120, 2))
    q = p + rng.normal(0, 3, (120, 2))
    zigzag = np.stack([p, q], axis=1).reshape(-1, 2)  # segments p0-q0, q0-p1, p1-q1, ...: test the even ones
    for radius_m in (0.0, 0.1):
        ours = np.array([S.segment_clear(random32, a, b, radius_m) for a, b in zip(p, q, strict=True)])
        theirs = _segments_free(random32, zigzag, radius_m / random32.resolution)[0::2]
        np.testing.assert_array_equal(ours, theirs)
        assert 10 < ours.sum() < len(ours) - 10


def test_polyline_cells_follow_the_polyline_and_refuse_collisions():
    grid = jp.grid_from_array(np.ones((6, 8), bool))
    cells = S.polyline_cells(grid, [[0, 0], [5.2, 3.1], [7, 5], [1, 5]])
    _assert_grid_path(grid, cells, (0, 0), (1, 5))
    free = np.ones((6, 8), bool)
    free[2, 3] = False
    with pytest.raises(ValueError, match="not collision-free"):
        S.polyline_cells(jp.grid_from_array(free), [[0, 2], [7, 2]])


# --- key-node-guided A* -----------------------------------------------------------------------


def _local_turns_deg(p: np.ndarray) -> np.ndarray:
    a, b = np.diff(p[:-1], axis=0).astype(float), np.diff(p[1:], axis=0).astype(float)
    cos = (a * b).sum(1) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1))
    return np.degrees(np.arccos(np.clip(cos, -1, 1)))


def _assert_kng(grid: jp.GridMap, r: jp.PlanResult, start, goal, threshold: float = 20.0) -> None:
    assert r.success and r.planner == "astar_kng"
    gp, kn = r.info["grid_path"], r.path
    assert kn.dtype == np.int64 and tuple(kn[0]) == tuple(start) and tuple(kn[-1]) == tuple(goal)
    idx = [int(np.flatnonzero((gp == c).all(1))[0]) for c in kn]
    assert idx == sorted(idx) and len(set(idx)) == len(idx), "key nodes are not a subsequence of the A* path"
    if len(kn) > 1:
        assert _segments_free(grid, kn.astype(float), 0.0).all(), "a key-node segment is not line-of-sight free"
    kept = set(idx)
    turns = _local_turns_deg(gp) if len(gp) >= 3 else np.zeros(0)
    for j in np.flatnonzero(turns >= threshold - 1e-9) + 1:
        assert j in kept, f"vertex {gp[j]} turns by {turns[j - 1]:.1f} deg but was dropped"
    assert np.isclose(r.length, jp.search.path_cost(kn, grid.resolution))
    assert np.linalg.norm(np.subtract(goal, start)) * grid.resolution - 1e-9 <= r.length <= r.info["grid_length"] + 1e-9


def test_kng_keeps_turning_vertices_and_line_of_sight(room):
    grid, starts, goals = room
    for s, g in zip(starts, goals, strict=True):
        r = jp.plan(grid, s, g, planner="astar_kng")
        _assert_kng(grid, r, s, g)
        np.testing.assert_array_equal(r.info["grid_path"], jp.astar(grid, s, g).path)
        assert r.turns == jp.metrics._host.count_turns(r.path)
        assert np.all(heading_changes(r.path) >= np.radians(20) - 1e-9) or r.info["fallback"]


@pytest.mark.slow
def test_kng_matches_the_jax_key_node_smoother(room):
    """The numba key-node pass equals `jp.smooth(..., "key_nodes")` (about 10 s: JAX compiles)."""
    grid, starts, goals = room
    for s, g in zip(starts, goals, strict=True):
        r = astar_kng(grid, s, g)
        ref = jp.smooth(r.info["grid_path"], grid, "key_nodes", threshold=20.0)
        np.testing.assert_array_equal(r.path, ref.points)
        assert r.info["removed"] == ref.removed and r.info["fallback"] == bool(ref.fallbacks)


@pytest.mark.parametrize("connectivity", [8, 16])
def test_kng_on_movingai_rows(movingai, connectivity):
    grid = jp.load_map(movingai / "maze-32-32-2.map")
    scen = jp.load_scenarios(movingai / "maze-32-32-2-random-1.scen", grid=grid)
    for i in (5, 150, 300):
        r = astar_kng(grid, scen.starts[i], scen.goals[i], connectivity=connectivity)
        _assert_kng(grid, r, scen.starts[i], scen.goals[i])


def test_kng_threshold_trades_nodes_for_turns(random32):
    few = astar_kng(random32, (2, 2), (29, 29), threshold_deg=60.0)
    many = astar_kng(random32, (2, 2), (29, 29), threshold_deg=20.0)
    _assert_kng(random32, few, (2, 2), (29, 29), threshold=60.0)
    assert len(few.path) <= len(many.path) <= len(many.info["grid_path"])


def test_kng_straight_corridor_is_two_nodes(corridor):
    r = astar_kng(corridor, (0, 4), (21, 4))
    np.testing.assert_array_equal(r.path, [[0, 4], [21, 4]])
    assert r.length == 21.0 and r.turns == 0 and r.info["removed"] == 20


def test_kng_respects_vehicle_height():
    free = np.ones((5, 9), bool)
    free[2, 1:8] = False
    low = np.full((5, 9), np.inf, np.float32)
    free[2, 4] = True
    low[2, 4] = 0.3  # a gap in the wall, too low for the vehicle
    grid = jp.grid_from_array(free, clearance_height=low)
    r = astar_kng(grid, (4, 0), (4, 4), vehicle_height=0.5)
    assert r.success and r.length > 4.0  # around the wall, not through the gap
    sight = grid.replace(free=jp.passable(grid, 0.5))
    _assert_kng(sight, r, (4, 0), (4, 4))
    through = astar_kng(grid, (4, 0), (4, 4))
    assert through.length == 4.0


def test_kng_failures_and_bad_input(corridor):
    free = np.ones((6, 6), bool)
    free[:, 3] = False
    r = jp.plan(jp.grid_from_array(free), (0, 0), (5, 5), planner="astar_kng")
    assert not r.success and r.path.shape == (0, 2) and "reachable" in r.info["reason"]
    for kw, match in [(dict(threshold_deg=0.0), "threshold_deg"), (dict(threshold_deg=float("nan")), "NaN"),
                      (dict(threshold_deg=200.0), "threshold_deg"), (dict(connectivity=6), "onnectivity"),
                      (dict(vehicle_height=-1.0), "vehicle_height")]:
        with pytest.raises(ValueError, match=match):
            jp.plan(corridor, (0, 4), (21, 4), planner="astar_kng", **kw)
    with pytest.raises(ValueError, match="blocked"):
        astar_kng(corridor, (0, 0), (21, 4))


def test_float64_accepted_segments_pass_float32_segment_free_on_wide_maps():
    # Segments grazing the corner (499.5, 19.5) of a blocked cell on a 600-wide map, from
    # 1.2e-5 cells out (float32 coordinates there are 6e-5 apart) to just beyond the margin.
    from jaxplan.grid._collision import collision_map, segment_free

    free = np.ones((40, 600), bool)
    free[20, 500] = False
    grid = jp.grid_from_array(free)
    check = jax.jit(jax.vmap(lambda p, q: segment_free(collision_map(grid), p, q, 0.0)))
    rng = np.random.default_rng(1)
    N = 4000
    ang = rng.uniform(0.2, 1.3, N)
    d = np.stack([np.cos(ang), -np.sin(ang)], 1)
    away = np.stack([-d[:, 1], d[:, 0]], 1)
    away *= np.sign(away @ np.array([-1.0, -1.0]))[:, None]  # towards the outside of the square
    off = np.concatenate([rng.uniform(1.2e-5, 4e-5, N // 2), rng.uniform(3e-4, 6e-4, N - N // 2)])
    c = np.array([499.5, 19.5]) + off[:, None] * away
    p, q = c - d * rng.uniform(2, 8, N)[:, None], c + d * rng.uniform(2, 8, N)[:, None]
    accepted = np.array([S.segment_clear(grid, a, b) for a, b in zip(p, q, strict=True)])
    ok32 = np.asarray(check(p.astype(np.float32), q.astype(np.float32)))
    assert accepted.sum() > N // 4  # the margin is not so wide that it rejects everything
    assert not np.any(accepted & ~ok32), np.flatnonzero(accepted & ~ok32)[:5]
