"""Moving obstacles: the arc-length model and padding (`jaxplan.nav._moving`), the generators (`_traffic`)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import jaxplan as jp
from jaxplan.dwa._clearance import DiscObstacles, disc_clearance
from jaxplan.grid._collision import cached_collision_map, segment_free
from jaxplan.nav._moving import (
    FAR,
    MovingObstacles,
    concat_obstacles,
    discs_at,
    moving_obstacles,
    no_obstacles,
    obstacle_state,
    pad_obstacles,
    route_lengths,
    stack_obstacles,
    trajectories,
)
from jaxplan.nav._traffic import crossing_traffic, head_on, random_obstacles

# A bounce, zero-length segments, a single vertex, a loop with a closing segment, a zero-length loop.
ROUTES = [
    [[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]],
    [[1.0, 1.0], [1.0, 1.0], [2.0, 1.0], [2.0, 1.0], [2.0, 3.0]],
    [[5.0, 5.0]],
    [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]],
    [[4.0, 1.0], [4.0, 1.0]],
]
SPEEDS = [1.0, 0.7, 1.0, 1.5, 2.0]
LOOPS = [False, False, False, True, True]
OFFSETS = [0.5, -1.0, 0.0, 3.0, 1.0]
STILL = [2, 4]  # single vertex; zero-length route

# Compiled once for the module: eager dispatch of every small op would dominate the run time.
state = jax.jit(obstacle_state)
traj = jax.jit(trajectories)
_SEGMENTS = 64  # segments per compiled exact check (routes are padded with zero-length segments)


@jax.jit
def _segments_free(cmap, p, q, radius):
    return jax.vmap(lambda a, b: segment_free(cmap, a, b, radius, reach=4.0))(p, q)


@pytest.fixture(scope="module")
def obs() -> MovingObstacles:
    return moving_obstacles(ROUTES, SPEEDS, 0.3, loop=LOOPS, offsets=OFFSETS)


# ----------------------------------------------------------------------------- references


def unfolded(route, loop: bool) -> np.ndarray:
    """One period as a polyline: the route then back (bounce), or the route then its first vertex (loop)."""
    r = np.asarray(route, np.float64)
    return np.concatenate([r, r[:1]]) if loop else np.concatenate([r, r[-2::-1]])


def ref_position(route, loop: bool, s: float) -> np.ndarray:
    """Position after ``s`` metres of travel, by walking the unfolded polyline (float64)."""
    pts = unfolded(route, loop)
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    period = seg.sum()
    if period == 0:
        return pts[0]
    u = s % period
    for a, b, length in zip(pts[:-1], pts[1:], seg, strict=True):
        if u <= length and length > 0:
            return a + (b - a) * (u / length)
        u -= length
    return pts[-1]


def vertex_arcs(route, loop: bool) -> np.ndarray:
    """Arc lengths (within one period) at which the unfolded polyline has a vertex."""
    pts = unfolded(route, loop)
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])


def distance_to_polyline(x: np.ndarray, pts: np.ndarray) -> float:
    pts = np.asarray(pts, np.float64)
    if len(pts) == 1:
        return float(np.linalg.norm(x - pts[0]))
    a, b = pts[:-1], pts[1:]
    d = b - a
    dd = np.maximum((d * d).sum(1), 1e-300)
    t = np.clip(((x - a) * d).sum(1) / dd, 0, 1)
    return float(np.linalg.norm(a + t[:, None] * d - x, axis=1).min())


def blocked_squares(grid) -> np.ndarray:
    """Centres (cell coordinates) of the blocked cells plus a blocked ring around the map."""
    free = np.pad(np.asarray(grid.free, bool), 1, constant_values=False)
    ys, xs = np.nonzero(~free)
    return np.stack([xs - 1, ys - 1], axis=1).astype(np.float64)


def min_square_distance(points: np.ndarray, squares: np.ndarray) -> np.ndarray:
    """Exact distance from points ``[N, 2]`` (cells) to the nearest of the unit squares."""
    d = np.maximum(np.abs(points[:, None, :] - squares[None]) - 0.5, 0.0)
    return np.sqrt((d * d).sum(-1)).min(1)


def assert_collision_free(grid, obs: MovingObstacles, n_times: int = 400) -> None:
    """Every route segment passes the exact segment test, and the sampled discs never overlap a blocked square."""
    res = float(grid.resolution)
    cmap = cached_collision_map(grid)
    wp, n, radii = np.asarray(obs.waypoints), np.asarray(obs.n_waypoints), np.asarray(obs.radii)
    for i in range(obs.count):
        r = float(radii[i]) / res
        assert r <= 4.0
        cells = wp[i, : n[i]] / res - 0.5
        p, q = cells[:-1], cells[1:]
        if len(p) == 0:  # standing still: the point itself
            p, q = cells, cells
        assert len(p) <= _SEGMENTS
        p = np.concatenate([p, np.repeat(p[-1:], _SEGMENTS - len(p), axis=0)])
        q = np.concatenate([q, np.repeat(q[-1:], _SEGMENTS - len(q), axis=0)])
        # 1e-4 cells of slack: clearance exactly equal to the radius is allowed (docs/guide/navigation.md),
        # and the route has been rounded to float32 metres.
        ok = np.asarray(_segments_free(cmap, jnp.asarray(p, jnp.float32), jnp.asarray(q, jnp.float32),
                                       jnp.float32(max(r - 1e-4, 0.0))))
        assert ok.all(), (i, np.flatnonzero(~ok))
    period = 2.0 * float(np.max(np.asarray(route_lengths(obs)))) / max(float(np.min(np.asarray(obs.speeds))), 1e-3)
    times = np.linspace(0.0, period, n_times)
    pos = np.asarray(traj(obs, jnp.asarray(times, jnp.float32))) / res - 0.5  # [T, M, 2] cells
    squares = blocked_squares(grid)
    for i in range(obs.count):
        gap = min_square_distance(pos[:, i], squares)
        assert gap.min() >= radii[i] / res - 1e-4, (i, gap.min())


def astar_world(grid, start, goal) -> np.ndarray:
    res = jp.astar(grid, start, goal)
    assert res.success
    return (np.asarray(res.path, np.float64) + 0.5) * grid.resolution


# ----------------------------------------------------------------------------- the model


def test_fields_shapes_and_dtypes(obs):
    assert obs.waypoints.shape == (5, 5, 2) and obs.waypoints.dtype == jnp.float32
    assert obs.n_waypoints.tolist() == [3, 5, 1, 4, 2] and obs.n_waypoints.dtype == jnp.int32
    assert obs.loop.dtype == jnp.bool_ and obs.count == 5
    # Padded by repeating the last valid vertex.
    np.testing.assert_array_equal(np.asarray(obs.waypoints[2]), np.full((5, 2), 5.0))
    np.testing.assert_allclose(np.asarray(route_lengths(obs)), [7.0, 3.0, 0.0, 8.0, 0.0], atol=1e-6)


def test_arc_length_matches_reference_including_bounce_and_loop_wraparound(obs):
    times = np.concatenate([np.linspace(-6.0, 30.0, 361), [0.0, 2.5, 6.5, 13.5]])  # several periods, both ways
    pos = np.asarray(traj(obs, times))
    for i, route in enumerate(ROUTES):
        for t, p in zip(times, pos[:, i], strict=True):
            want = ref_position(route, LOOPS[i], OFFSETS[i] + SPEEDS[i] * t)
            np.testing.assert_allclose(p, want, atol=2e-5, err_msg=f"obstacle {i} at t={t}")


@settings(max_examples=40, deadline=None)
@given(
    pts=st.lists(st.tuples(st.integers(-3, 3), st.integers(-3, 3)), min_size=1, max_size=5),
    speed=st.floats(0.0, 3.0), offset=st.floats(-20.0, 20.0), loop=st.booleans(),
    times=st.lists(st.floats(-10.0, 10.0), min_size=1, max_size=4),
)
def test_random_routes_match_the_reference(pts, speed, offset, loop, times):
    # Integer vertices make repeated vertices (zero-length segments) and exact vertex hits common.
    route = np.asarray(pts, np.float64) * 0.5
    o = pad_obstacles(moving_obstacles([route], speed, 0.1, loop=loop, offsets=offset), 1, 5)  # one compiled shape
    for t in times:
        p, v = state(o, t)
        want = ref_position(route, loop, np.float32(offset) + np.float32(speed) * np.float32(t))
        np.testing.assert_allclose(np.asarray(p[0]), want, atol=1e-4)
        speed_now = np.linalg.norm(np.asarray(v[0]))
        moving = speed > 0 and np.linalg.norm(np.diff(unfolded(route, loop), axis=0), axis=1).sum() > 0
        assert speed_now == pytest.approx(np.float32(speed) if moving else 0.0, abs=1e-5)


def test_positions_lie_on_the_route(obs):
    pos = np.asarray(traj(obs, np.linspace(0.0, 20.0, 201)))
    for i, route in enumerate(ROUTES):
        pts = np.concatenate([route, route[:1]]) if LOOPS[i] else np.asarray(route)
        assert max(distance_to_polyline(p, pts) for p in pos[:, i]) < 1e-5


def test_velocity_is_the_derivative_of_position_with_speed_magnitude(obs):
    h = 1e-2
    for t in np.linspace(0.05, 12.0, 60):
        p_plus, _ = state(obs, t + h)
        p_minus, _ = state(obs, t - h)
        _, v = state(obs, t)
        fd = (np.asarray(p_plus) - np.asarray(p_minus)) / (2 * h)
        for i, route in enumerate(ROUTES):
            if i in STILL:
                continue
            arcs = vertex_arcs(route, LOOPS[i])
            period = arcs[-1]
            s = (OFFSETS[i] + SPEEDS[i] * t) % period
            if np.min(np.abs(arcs - s)) < 2 * h * SPEEDS[i]:
                continue  # a vertex inside the difference stencil
            np.testing.assert_allclose(np.asarray(v[i]), fd[i], atol=2e-3, err_msg=f"obstacle {i} at t={t}")
            assert abs(np.linalg.norm(np.asarray(v[i])) - SPEEDS[i]) < 1e-5
    # Forward-mode derivative agrees with the reported velocity as well.
    dpos = jax.jacfwd(lambda t: state(obs, t)[0])(1.3)
    np.testing.assert_allclose(np.asarray(dpos), np.asarray(state(obs, 1.3)[1]), atol=1e-5)


def test_still_obstacles_stay_put(obs):
    for t in (-3.0, 0.0, 0.7, 11.0):
        p, v = state(obs, t)
        for i in STILL:
            np.testing.assert_array_equal(np.asarray(p[i]), np.asarray(ROUTES[i][0]))
            np.testing.assert_array_equal(np.asarray(v[i]), [0.0, 0.0])
    zero = moving_obstacles(ROUTES, 0.0, 0.3, loop=LOOPS, offsets=OFFSETS)
    p0, v0 = state(zero, 0.0)
    p1, v1 = state(zero, 9.0)
    np.testing.assert_array_equal(np.asarray(p0), np.asarray(p1))
    assert not np.any(np.asarray(v1))


def test_no_nan_values_or_gradients_at_vertices_and_zero_length_segments(obs):
    def total(t):
        p, v = state(obs, t)
        return jnp.sum(p) + jnp.sum(v)

    # Times at which some obstacle sits exactly on a vertex (including repeated vertices).
    times = [0.0, -1.0]
    for i, route in enumerate(ROUTES):
        if i in STILL:
            continue
        for a in vertex_arcs(route, LOOPS[i]):
            times.append((a - OFFSETS[i]) / SPEEDS[i])
    grad = jax.grad(total)
    for t in times:
        p, v = state(obs, t)
        assert np.isfinite(np.asarray(p)).all() and np.isfinite(np.asarray(v)).all()
        g = float(grad(jnp.float32(t)))
        assert np.isfinite(g), t
    # Gradients with respect to the route itself are finite too (guarded square roots).
    gw = jax.grad(lambda w: jnp.sum(state(obs._replace(waypoints=w), 0.4)[0]))(obs.waypoints)
    assert np.isfinite(np.asarray(gw)).all()


def test_jit_and_vmap_agree_with_eager_and_trace_once(obs):
    times = jnp.linspace(-2.0, 9.0, 23)
    eager = np.stack([np.asarray(obstacle_state(obs, t)[0]) for t in times])
    traces = []

    def f(o, t):
        traces.append(1)
        return obstacle_state(o, t)

    jf = jax.jit(f)
    for k in range(5):
        np.testing.assert_allclose(np.asarray(jf(obs, times[k])[0]), eager[k], atol=1e-6)
    assert len(traces) == 1
    np.testing.assert_allclose(np.asarray(jax.vmap(lambda t: obstacle_state(obs, t)[0])(times)), eager, atol=1e-6)
    np.testing.assert_allclose(np.asarray(jax.jit(trajectories)(obs, times)), eager, atol=1e-6)


def test_batch_of_obstacle_sets_vmap_and_leading_axes(obs):
    other = moving_obstacles([[[0, 0], [0, 6]], [[1, 1], [4, 5], [7, 1]]], [1.0, 1.5], [0.2, 0.4], loop=[False, True])
    sets = [obs, other, no_obstacles(0)]
    batch = stack_obstacles(sets)
    assert batch.waypoints.shape == (3, 5, 5, 2) and batch.radii.shape == (3, 5)
    for t in (0.0, 1.7, 8.2):
        leading = state(batch, t)  # leading batch axis handled directly
        mapped = jax.vmap(lambda o, t=t: state(o, t))(batch)
        jitted = jax.jit(jax.vmap(obstacle_state, in_axes=(0, None)))(batch, t)
        for b, o in enumerate(sets):
            p, v = state(o, t)
            m = o.count
            for got in (leading, mapped, jitted):
                np.testing.assert_allclose(np.asarray(got[0][b, :m]), np.asarray(p), atol=1e-6)
                np.testing.assert_allclose(np.asarray(got[1][b, :m]), np.asarray(v), atol=1e-6)
    paths = traj(batch, jnp.arange(4.0))
    assert paths.shape == (4, 3, 5, 2)


def test_discs_at_is_the_state_snapshot(obs):
    d = discs_at(obs, 2.3)
    p, v = state(obs, 2.3)
    assert isinstance(d, DiscObstacles)
    np.testing.assert_array_equal(np.asarray(d.positions), np.asarray(p))
    np.testing.assert_array_equal(np.asarray(d.velocities), np.asarray(v))
    np.testing.assert_allclose(np.asarray(d.radii), 0.3)
    assert jax.jit(discs_at)(obs, 2.3).positions.shape == (5, 2)


# ----------------------------------------------------------------------------- padding


def test_padding_slots_are_far_apart_and_still(obs):
    empty = no_obstacles(0)
    assert empty.waypoints.shape == (0, 1, 2) and discs_at(empty, 1.0).positions.shape == (0, 2)
    padded = pad_obstacles(obs, 9, 7)
    assert padded.waypoints.shape == (9, 7, 2)
    for t in (0.0, 3.3, 50.0):
        p, v = state(padded, t)
        p0, v0 = state(obs, t)
        np.testing.assert_allclose(np.asarray(p[:5]), np.asarray(p0), atol=1e-6)
        np.testing.assert_allclose(np.asarray(v[:5]), np.asarray(v0), atol=1e-6)
        pad = np.asarray(p[5:])
        assert (pad > 0.5 * FAR).all()  # nowhere near any map
        assert not np.any(np.asarray(v[5:]))
        gaps = np.linalg.norm(pad[:, None] - pad[None], axis=-1) + np.eye(len(pad)) * 1e9
        assert gaps.min() >= 1.0  # never on top of each other
    assert not np.any(np.asarray(padded.radii[5:])) and not np.any(np.asarray(padded.speeds[5:]))
    # Concatenating two padded sets re-parks the padding so that no two slots coincide.
    both = concat_obstacles(pad_obstacles(obs, 7), no_obstacles(3))
    far = np.asarray(state(both, 0.0)[0][5:])
    assert len({tuple(x) for x in far.tolist()}) == 5
    # The DWA's clearance ignores padding: same clearance with and without it.
    x, y = jnp.array([0.5, 2.0, 3.0]), jnp.array([0.5, 1.0, 2.0])
    clearance = jax.jit(lambda o: disc_clearance(discs_at(o, 1.0), x, y, 0.4))
    np.testing.assert_allclose(np.asarray(clearance(padded)), np.asarray(clearance(obs)), atol=1e-6)
    with pytest.raises(ValueError, match="cannot pad"):
        pad_obstacles(obs, 3)


# ----------------------------------------------------------------------------- validation


@pytest.mark.parametrize("kwargs, message", [
    (dict(routes=[[[0, 0]], [[1, 1]], [[0, 0, 0]]]), "obstacle 2: route must have shape"),
    (dict(routes=[[[0, 0]], [[1, 1]], np.zeros((0, 2))]), "obstacle 2: route must have shape"),
    (dict(routes=[[[0, 0]], [[1, 1]], [[0, 0], [np.nan, 1]]]), "obstacle 2: route contains a non-finite"),
    (dict(routes=[[[0, 0]], [[1, 1]], [[2e6, 0]]]), "obstacle 2: route coordinates"),
    (dict(speeds=[1.0, -1.0, 1.0]), "obstacle 1: speed must be >= 0"),
    (dict(speeds=[1.0, 1.0, np.inf]), "obstacle 2: speed must be finite"),
    (dict(radii=[0.1, 0.2, -0.3]), "obstacle 2: radius must be >= 0"),
    (dict(offsets=[0.0, np.nan, 0.0]), "obstacle 1: offset must be finite"),
    (dict(speeds=[1.0, 1.0]), "one entry per obstacle"),
    (dict(loop=[True, False]), "one entry per obstacle"),
])
def test_bad_input_names_the_obstacle(kwargs, message):
    args = dict(routes=[[[0, 0], [1, 0]], [[1, 1]], [[2, 2], [3, 3]]], speeds=1.0, radii=0.25)
    args.update(kwargs)
    with pytest.raises(ValueError, match=message):
        moving_obstacles(**args)


# ----------------------------------------------------------------------------- generators


@pytest.fixture(scope="module")
def maze():
    """A 14x10 map at 0.5 m per cell: walls, a one-cell corridor and an open room."""
    free = np.ones((10, 14), bool)
    free[4, 0:10] = False
    free[0:3, 6] = False
    free[6:10, 4] = False
    free[7, 9:14] = False
    return jp.grid_from_array(free, resolution=0.5)


@pytest.mark.parametrize("loop", [False, True])
def test_random_obstacles_are_reproducible_and_collision_free(maze, loop):
    a = random_obstacles(maze, n=4, speed=[1.0, 1.5, 1.0, 1.5], radius=0.25, seed=3, loop=loop)
    b = random_obstacles(maze, n=4, speed=[1.0, 1.5, 1.0, 1.5], radius=0.25, seed=3, loop=loop)
    c = random_obstacles(maze, n=4, speed=[1.0, 1.5, 1.0, 1.5], radius=0.25, seed=4, loop=loop)
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y))
    assert not np.array_equal(np.asarray(a.waypoints), np.asarray(c.waypoints))
    assert a.count == 4 and bool(jnp.all(a.loop == loop))
    np.testing.assert_allclose(np.asarray(a.speeds), [1.0, 1.5, 1.0, 1.5])
    assert assert_collision_free(maze, a) is None
    if loop:  # a loop route comes back to where it started, so its closing segment is empty
        for i in range(a.count):
            k = int(a.n_waypoints[i])
            np.testing.assert_array_equal(np.asarray(a.waypoints[i, 0]), np.asarray(a.waypoints[i, k - 1]))


def test_random_obstacles_inflate_for_a_large_radius(maze):
    obs = random_obstacles(maze, n=3, radius=0.4, seed=1)  # 0.8 cells: cells next to walls are out
    assert_collision_free(maze, obs)


def test_random_obstacles_honour_avoid(maze):
    avoid = np.array([[0.75, 0.75], [6.25, 4.25], [3.0, 3.0]])
    for seed in range(3):
        obs = random_obstacles(maze, n=5, radius=0.25, seed=seed, avoid=avoid, avoid_radius=1.0)
        start = np.asarray(state(obs, 0.0)[0])
        gaps = np.linalg.norm(start[:, None] - avoid[None], axis=-1)
        assert gaps.min() >= 1.0 + 0.25 - 1e-5


def test_random_obstacles_raise_without_room(maze):
    with pytest.raises(ValueError, match="no free cell"):
        random_obstacles(maze, n=2, radius=5.0, seed=0)
    with pytest.raises(ValueError, match="avoid"):
        random_obstacles(maze, n=2, seed=0, avoid=[[3.5, 2.5]], avoid_radius=50.0)
    with pytest.raises(ValueError, match="no free cell"):
        random_obstacles(jp.grid_from_array(np.zeros((4, 4), bool)), n=1, seed=0)
    with pytest.raises(ValueError, match="seed"):
        random_obstacles(maze, seed=-1)
    with pytest.raises(ValueError, match="obstacle 1: speed"):
        random_obstacles(maze, n=2, speed=[1.0, -2.0])
    assert random_obstacles(maze, n=0).count == 0


def test_random_obstacles_on_the_demo_warehouse():
    scene = jp.demo_warehouse()  # a Scene; its .grid is the map
    obs = random_obstacles(scene, n=5, speed=1.5, radius=0.25, seed=0,
                           avoid=np.stack([scene.grid.centre(scene.start), scene.grid.centre(scene.goal)]))
    assert obs.count == 5 and int(obs.n_waypoints.min()) >= 2
    assert_collision_free(scene.grid, obs, n_times=200)


def test_random_obstacles_on_a_movingai_warehouse(movingai):
    grid = jp.load_map(movingai / "warehouse-10-20-10-2-1.map", resolution=1.0)
    obs = random_obstacles(grid, n=5, speed=1.0, radius=0.25, seed=0)
    again = random_obstacles(grid, n=5, speed=1.0, radius=0.25, seed=0)
    np.testing.assert_array_equal(np.asarray(obs.waypoints), np.asarray(again.waypoints))
    assert_collision_free(grid, obs, n_times=200)


def _segment_intersection(p, q, a, b):
    """Parameter along ``a``–``b`` where it crosses ``p``–``q`` (None if they do not meet)."""
    d1, d2 = q - p, b - a
    den = d1[0] * d2[1] - d1[1] * d2[0]
    if abs(den) < 1e-12:
        return None
    w = a - p
    s = (w[0] * d2[1] - w[1] * d2[0]) / den
    u = (w[0] * d1[1] - w[1] * d1[0]) / den
    return u if (-1e-6 <= s <= 1 + 1e-6 and -1e-6 <= u <= 1 + 1e-6) else None


@pytest.mark.parametrize("jitter", [0.0, 0.25])
def test_crossing_traffic_crosses_the_path_on_time(maze, jitter):
    path = astar_world(maze, (0, 0), (13, 9))
    speed = 1.2
    obs = crossing_traffic(maze, path, n=3, speed=speed, radius=0.25, seed=2, jitter=jitter)
    again = crossing_traffic(maze, path, n=3, speed=speed, radius=0.25, seed=2, jitter=jitter)
    for x, y in zip(obs, again, strict=True):
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y))
    assert obs.count == 3 and not bool(jnp.any(obs.loop))
    assert_collision_free(maze, obs)
    cum = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
    crossings = []
    for i in range(3):
        a, b = np.asarray(obs.waypoints[i, :2], np.float64)
        assert int(obs.n_waypoints[i]) == 2 and np.linalg.norm(b - a) > 0
        hits = [(k, _segment_intersection(a, b, path[k], path[k + 1])) for k in range(len(path) - 1)]
        hits = [(k, u) for k, u in hits if u is not None]
        assert hits, f"obstacle {i} does not cross the path"
        k, u = hits[0]
        tangent = (path[k + 1] - path[k]) / np.linalg.norm(path[k + 1] - path[k])
        assert abs(np.dot((b - a) / np.linalg.norm(b - a), tangent)) < 1e-5  # perpendicular
        s = cum[k] + u * (cum[k + 1] - cum[k])
        crossings.append(s)
        # The robot (at the obstacles' speed, from path[0] at t = 0) and the obstacle meet there.
        meet = path[k] + u * (path[k + 1] - path[k])
        at = np.asarray(state(obs, s / speed)[0][i])
        assert np.linalg.norm(at - meet) <= speed * jitter + 1e-4
    assert np.all(np.diff(crossings) > 0)  # spread along the path, in order


def test_crossing_traffic_bad_input(maze):
    path = astar_world(maze, (0, 0), (13, 9))
    with pytest.raises(ValueError, match="path"):
        crossing_traffic(maze, path[:1])
    with pytest.raises(ValueError, match="non-finite"):
        crossing_traffic(maze, np.full((3, 2), np.nan))
    with pytest.raises(ValueError, match="span"):
        crossing_traffic(maze, path, span=0.0)
    with pytest.raises(ValueError, match="fits nowhere"):
        crossing_traffic(maze, path, n=1, radius=2.0)


def test_head_on_starts_at_the_goal_and_heads_for_the_start(maze):
    path = astar_world(maze, (0, 0), (13, 9))
    length = float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())
    obs = head_on(path, speed=1.0, radius=0.3)
    assert obs.count == 1 and not bool(obs.loop[0]) and float(obs.radii[0]) == pytest.approx(0.3)
    times = np.linspace(0.0, length, 50)
    pos = np.asarray(traj(obs, times))[:, 0]
    np.testing.assert_allclose(pos[0], path[-1], atol=1e-5)
    np.testing.assert_allclose(pos[-1], path[0], atol=1e-4)
    for t, p in zip(times, pos, strict=True):  # along the path, from the goal end, at the given speed
        np.testing.assert_allclose(p, ref_position(path[::-1], False, t), atol=1e-4)
    v = np.asarray(state(obs, 0.1)[1][0])
    np.testing.assert_allclose(v, (path[-2] - path[-1]) / np.linalg.norm(path[-2] - path[-1]), atol=1e-5)
    late = head_on(path, speed=1.0, radius=0.3, delay=2.0)
    np.testing.assert_allclose(np.asarray(state(late, 2.0)[0][0]), path[-1], atol=1e-5)
    np.testing.assert_allclose(np.asarray(state(late, 5.0)[0][0]), np.asarray(state(obs, 3.0)[0][0]),
                               atol=1e-5)
    with pytest.raises(ValueError, match="obstacle 0: speed"):
        head_on(path, speed=-1.0)
