"""Dynamic Window Approach: window and limits, safety, closed loop, fuzzy evaluation, batching, errors, gradients."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxplan as jp
from jaxplan.dwa import (
    Ackermann,
    DiscObstacles,
    DWAConfig,
    DWAParams,
    Rectangle,
    Unicycle,
    _fuzzy,
    advance,
    clearance_table,
    default_params,
    dwa_control,
    dwa_step,
    input_memberships,
    rule_table,
    static_clearance,
)
from jaxplan.dwa._fuzzy import fuzzy_evaluate
from jaxplan.grid._collision import collision_map


def _brute_clearance(points_m, free, res):
    """Exact distance (m) from world points to the nearest blocked square (outside counts), by brute force."""
    pad = 3
    ys, xs = np.nonzero(~np.pad(free, pad, constant_values=False))
    squares = np.stack([xs - pad, ys - pad], 1).astype(np.float64)
    p = np.asarray(points_m, np.float64).reshape(-1, 2) / res - 0.5
    out = np.empty(len(p))
    for i in range(0, len(p), 2048):  # chunks keep the [points, squares] temporaries small
        d = np.maximum(np.abs(p[i:i + 2048, None, :] - squares[None]) - 0.5, 0.0)
        out[i:i + 2048] = np.min(np.hypot(d[..., 0], d[..., 1]), axis=1)
    return out.reshape(np.shape(points_m)[:-1]) * res


@pytest.fixture(scope="module")
def clutter():
    """A 24x24 map at 0.5 m per cell with scattered blocked cells and a wall."""
    rng = np.random.default_rng(7)
    free = rng.random((24, 24)) > 0.08
    free[4:20, 15] = False
    free[10:14, 2:6] = True
    return jp.grid_from_array(free, resolution=0.5)


def _states(rng, n, grid, robot):
    """Random states on free cells with speeds inside the limits."""
    free = np.argwhere(np.asarray(grid.free))  # (y, x)
    pick = free[rng.integers(0, len(free), n)]
    res = grid.resolution
    xy = (pick[:, ::-1] + 0.5 + rng.uniform(-0.3, 0.3, (n, 2))) * res
    th = rng.uniform(-math.pi, math.pi, n)
    v = rng.uniform(robot.v_min, robot.v_max, n)
    w = rng.uniform(-robot.omega_max, robot.omega_max, n)
    if isinstance(robot, Ackermann):
        w = np.clip(w, -np.abs(v) * math.tan(robot.steer_max) / robot.wheelbase,
                    np.abs(v) * math.tan(robot.steer_max) / robot.wheelbase)
    goals = rng.uniform(0, np.array(grid.shape[::-1]) * res, (n, 2))
    return np.column_stack([xy, th, v, w]), goals


CONFIGS = [
    DWAConfig(),
    DWAConfig(evaluator="fuzzy", selection="softmax"),
    DWAConfig(evaluator="classic"),
    DWAConfig(robot=Ackermann(), n_v=8, n_omega=12),
]


@pytest.mark.parametrize("config", CONFIGS, ids=["weighted", "fuzzy-softmax", "classic", "ackermann"])
def test_control_stays_in_window_and_limits(clutter, config):
    rng = np.random.default_rng(0)
    r = config.robot
    states, goals = _states(rng, 40, clutter, r)
    u, info = dwa_step(states, goals, clutter, config=config)
    P, tol = config.period, 1e-5
    v, w = u[:, 0], u[:, 1]
    assert np.all(v >= r.v_min - tol) and np.all(v <= r.v_max + tol)
    assert np.all(np.abs(w) <= r.omega_max + tol)
    assert np.all(v >= states[:, 3] - r.decel * P - tol) and np.all(v <= states[:, 3] + r.accel * P + tol)
    assert np.all(np.abs(w - states[:, 4]) <= r.alpha * P + tol)
    lo, hi = info.window[:, 0], info.window[:, 1]
    assert np.all((v >= lo - tol) & (v <= hi + tol))
    assert np.all((w >= info.window[:, 2] - tol) & (w <= info.window[:, 3] + tol))
    # Every sample lies in the window too.
    s = info.samples
    assert np.all((s[..., 0] >= lo[:, None] - tol) & (s[..., 0] <= hi[:, None] + tol))
    if isinstance(r, Ackermann):
        kappa = math.tan(r.steer_max) / r.wheelbase
        assert np.all(np.abs(s[..., 1]) <= kappa * np.abs(s[..., 0]) + 1e-4)
        assert np.all(np.abs(w) <= kappa * np.abs(v) + 1e-4)
    assert info.scores.shape == (40, config.samples)
    assert info.rollouts.shape == (40, config.samples, config.steps, 3)


@pytest.mark.parametrize("res", [0.5, 1.0])
def test_chosen_rollout_keeps_d_safe_when_one_is_feasible(res):
    rng = np.random.default_rng(1)
    free = rng.random((20, 20)) > 0.08
    grid = jp.grid_from_array(free, resolution=res)
    config = DWAConfig()
    states, goals = _states(rng, 64, grid, config.robot)
    u, info = dwa_step(states, goals, grid, config=config)
    rows = np.arange(64)
    ok = ~info.recovery
    assert ok.sum() >= 20  # enough cases where something was feasible
    chosen = info.rollouts[rows[ok], info.chosen[ok]]  # [n, T, 3]
    exact = _brute_clearance(chosen[..., :2], free, res)
    # A robot already inside d_safe may escape: its rollout must not get closer than it is now.
    now = _brute_clearance(states[rows[ok], None, :2], free, res)[:, 0]
    assert np.all(exact.min(axis=1) >= np.minimum(config.d_safe, now) - 1e-4)
    assert np.any(now >= config.d_safe) and np.all(exact.min(axis=1)[now >= config.d_safe] >= config.d_safe - 1e-4)
    # The planner's own clearance of every rollout agrees with brute force (hybrid: exact below 1.5 cells).
    want = _brute_clearance(info.rollouts[:3, ..., :2], free, res).min(axis=-1)  # [3, S]
    got = info.clearance[:3]
    near = want < 1.5 * res
    np.testing.assert_allclose(got[near], want[near], atol=2e-5)
    # Infeasible samples exist and are never chosen.
    assert (~info.feasible).any()
    assert np.all(info.feasible[rows[ok], info.chosen[ok]])


def test_moving_disc_rollouts_are_checked_at_predicted_positions():
    grid = jp.grid_from_array(np.ones((20, 40), bool), resolution=0.5)
    state = np.array([2.0, 5.0, 0.0, 1.0, 0.0])
    # A disc coming head-on at 1 m/s: straight fast rollouts meet it within the horizon.
    obs = DiscObstacles(np.array([[5.5, 5.0]]), np.array([[-1.0, 0.0]]), np.array([0.3]))
    u, info = dwa_step(state, [18.0, 5.0], grid, obstacles=obs)
    t = (np.arange(20) + 1) * 0.1
    centre = np.array([5.5, 5.0]) + t[:, None] * np.array([-1.0, 0.0])
    gap = np.linalg.norm(info.rollouts[..., :2] - centre[None], axis=-1) - 0.3  # [S, T]
    static = _brute_clearance(info.rollouts[..., :2], np.ones((20, 40), bool), 0.5)
    want = np.minimum(gap, static).min(axis=1)
    np.testing.assert_allclose(info.clearance, want, atol=1e-4)
    assert not info.recovery and info.feasible[info.chosen]
    assert (~info.feasible).sum() > 100  # the disc rules out a good part of the fan
    # Without the disc the robot would drive straight at full speed; with it, it turns away.
    u0, _ = dwa_step(state, [18.0, 5.0], grid)
    assert abs(u0[1]) < 0.2 and abs(u[1]) > 0.2


def test_a_disc_track_replaces_the_constant_velocity_prediction():
    grid = jp.grid_from_array(np.ones((20, 40), bool), resolution=0.5)
    state = np.array([2.0, 5.0, 0.0, 1.0, 0.0])
    pos, vel, rad = np.array([[4.0, 7.0]]), np.array([[1.0, 0.0]]), np.array([0.3])
    # Constant velocity, the disc passes 2 m to the left of the robot's lane; along its track it
    # turns after 0.5 s and crosses the lane. Samples 0 .. 20 of the track every dt = 0.1 s.
    t = np.arange(21) * 0.1
    turn = np.where(t[:, None] <= 0.5, pos + t[:, None] * vel,
                    pos + 0.5 * vel + (t[:, None] - 0.5) * np.array([[0.0, -1.0]]))
    _, cv = dwa_step(state, [18.0, 5.0], grid, obstacles=DiscObstacles(pos, vel, rad))
    _, tr = dwa_step(state, [18.0, 5.0], grid, obstacles=DiscObstacles(pos, vel, rad, turn[None]))
    static = _brute_clearance(tr.rollouts[..., :2], np.ones((20, 40), bool), 0.5)
    gap = np.linalg.norm(tr.rollouts[..., :2] - turn[None, 1:], axis=-1) - 0.3  # rollout point k at t = k·dt
    np.testing.assert_allclose(tr.clearance, np.minimum(gap, static).min(axis=1), atol=1e-4)
    assert (~tr.feasible).sum() > (~cv.feasible).sum() + 50  # the turn rules out straight-ahead samples
    # A track that is the constant-velocity prediction changes nothing.
    _, same = dwa_step(state, [18.0, 5.0], grid, obstacles=DiscObstacles(pos, vel, rad, (pos + t[:, None] * vel)[None]))
    np.testing.assert_allclose(same.clearance, cv.clearance, atol=1e-5)
    assert same.chosen == cv.chosen
    with pytest.raises(ValueError, match="track must have shape"):
        dwa_step(state, [18.0, 5.0], grid, obstacles=DiscObstacles(pos, vel, rad, turn))
    with pytest.raises(ValueError, match="track contains NaN"):
        dwa_step(state, [18.0, 5.0], grid, obstacles=DiscObstacles(pos, vel, rad, np.full((1, 21, 2), np.nan)))


def test_straighten_samples_turn_then_drive_straight_on():
    grid = jp.grid_from_array(np.ones((20, 40), bool), resolution=0.5)
    state = np.array([2.0, 5.0, 0.3, 1.0, 0.5])
    plain = DWAConfig()
    config = DWAConfig(straighten=(0.25, 0.5), n_omega_straight=10)
    assert config.samples == 800 + 2 * 20 * 10 and config.turn_steps() == (5, 10)
    _, base = dwa_step(state, [18.0, 5.0], grid, config=plain)
    u, info = dwa_step(state, [18.0, 5.0], grid, config=config)
    assert info.samples.shape == (1200, 2) and info.rollouts.shape == (1200, 20, 3)
    np.testing.assert_array_equal(info.samples[:800], base.samples)  # the plain grid comes first, unchanged
    np.testing.assert_allclose(info.rollouts[:800], base.rollouts, atol=1e-5)
    t = (np.arange(20) + 1) * 0.1
    for j, k1 in ((800 + 57, 5), (800 + 200 + 131, 10)):
        v, w = info.samples[j]
        th = state[2] + w * np.minimum(t, k1 * 0.1)
        # Exact: arc for the first k1 points, then straight on along the heading reached.
        chord = v * np.minimum(t, k1 * 0.1) * np.sinc(w * np.minimum(t, k1 * 0.1) / (2 * np.pi))
        mid = state[2] + w * np.minimum(t, k1 * 0.1) / 2
        x = state[0] + chord * np.cos(mid) + v * np.maximum(t - k1 * 0.1, 0) * np.cos(th)
        y = state[1] + chord * np.sin(mid) + v * np.maximum(t - k1 * 0.1, 0) * np.sin(th)
        np.testing.assert_allclose(info.rollouts[j], np.stack([x, y, th], 1), atol=2e-5)
    # The end pose the critics score (no rollouts kept) is the last point.
    lean = config.replace(keep_rollouts=False)
    u2, info2 = dwa_step(state, [18.0, 5.0], grid, config=lean)
    np.testing.assert_allclose(u2, u, atol=1e-6)
    np.testing.assert_allclose(info2.scores, info.scores, atol=1e-5)
    w_lo, w_hi = info.window[2:]
    assert w_lo - 1e-6 <= u[1] <= w_hi + 1e-6
    for bad, match in (((0.01,), "at least one point"), ((1.0,), "at least one point"), ([0.5], "tuple")):
        with pytest.raises(ValueError, match=match):
            dwa_step(state, [18.0, 5.0], grid, config=DWAConfig(straighten=bad))
    with pytest.raises(ValueError, match="n_omega_straight"):
        dwa_step(state, [18.0, 5.0], grid, config=DWAConfig(straighten=(0.5,), n_omega_straight=0))


def test_robot_facing_a_wall_in_a_corridor_stops_without_colliding():
    free = np.zeros((7, 30), bool)
    free[2:5, 1:20] = True  # a corridor 3 cells (1.5 m) wide, closed at x = 20 cells
    grid = jp.grid_from_array(free, resolution=0.5)
    config = DWAConfig(keep_rollouts=False)
    state = np.array([1.5, 1.75, 0.0, 1.0, 0.0])  # centre line, 1 m/s towards the wall
    goal = np.array([14.0, 1.75])  # behind the wall
    xs, speeds, recoveries = [], [], 0
    for _ in range(80):
        u, info = dwa_step(state, goal, grid, config=config)
        for k in range(1, 5):  # check the executed arc, not only the sampled states
            xs.append(np.asarray(advance(state, u, 0.05 * k))[:2])
        state = np.asarray(advance(state, u, config.period))
        speeds.append(state[3])
        recoveries += bool(info.recovery)
    clear = _brute_clearance(np.array(xs), free, 0.5)
    assert clear.min() >= 0.25  # never closer than the robot radius: no collision
    assert clear.min() >= 0.3 - 0.01  # and (between the checked points, up to a chord's sag) it kept d_safe
    assert max(np.abs(speeds[-10:])) < 0.02  # it came to rest ...
    assert 7.0 < state[0] < 10.0 - 0.3  # ... after driving down the corridor, short of the wall face (x = 10 m)


def test_classic_stuck_rule_turns_a_robot_at_rest():
    free = np.ones((9, 9), bool)
    free[3:6, 5] = False  # a wall whose face is at x = 2.5 m
    grid = jp.grid_from_array(free, resolution=0.5)
    # At rest, facing the wall 0.32 m away: every forward sample ends inside the 0.3 m margin,
    # so the best sample stands still and PythonRobotics' rule turns the robot instead.
    state = np.array([2.18, 2.25, 0.0, 0.0, 0.0])
    config = DWAConfig(evaluator="classic", n_v=5, n_omega=9)
    u, info = dwa_step(state, [3.75, 2.25], grid, config=config)
    assert info.stuck and not info.recovery
    assert info.samples[info.chosen, 0] == 0.0
    assert u[0] == 0.0 and u[1] == pytest.approx(info.window[2]) and u[1] == pytest.approx(-0.6)
    _, weighted = dwa_step(state, [3.75, 2.25], grid, config=DWAConfig(n_v=5, n_omega=9))
    assert not weighted.stuck  # the rule belongs to the classic preset only


def test_recovery_when_nothing_is_feasible():
    free = np.ones((10, 10), bool)
    free[4, 5] = False
    grid = jp.grid_from_array(free, resolution=0.5)
    # 0.2 m from the blocked cell's face: every rollout starts inside the 0.3 m margin.
    state = np.array([2.3, 2.25, 0.0, 0.4, 0.0])
    u, info = dwa_step(state, [4.0, 0.5], grid)  # sub-goal ahead and to the right (y down is +y)
    assert info.recovery and info.chosen == -1 and not info.feasible.any()
    assert u[0] == pytest.approx(max(0.0, 0.4 - 0.5 * 0.2))  # braking as hard as allowed
    # The sub-goal is at negative cross product (to the right): turn right as hard as allowed.
    assert u[1] == pytest.approx(-3.0 * 0.2)


def test_fuzzy_memberships_and_output_by_hand(monkeypatch):
    e, s, c = jnp.array([0.25]), jnp.array([0.8]), jnp.array([0.475])  # 45° off, 80 % speed, 0.475 m
    mh, ms, mc = (np.asarray(m)[:, 0] for m in input_memberships(e, s, c, 0.3, 1.0))
    np.testing.assert_allclose(mh, [0.5, 0.5, 0.0], atol=1e-6)  # small, medium, large
    np.testing.assert_allclose(ms, [0.0, 0.4, 0.6], atol=1e-6)  # slow, medium, fast
    np.testing.assert_allclose(mc, [0.5, 0.5, 0.0], atol=1e-6)  # close, safe, far (0.3, 0.65, 1.0 m)
    p = default_params("fuzzy")
    z = np.asarray(rule_table(p))
    # Table of the module docstring (heading small row): close 0.2/0.275/0.35, safe 0.55/0.7/0.85, far 0.7/0.85/1.
    np.testing.assert_allclose(z[0], [[0.2, 0.55, 0.7], [0.275, 0.7, 0.85], [0.35, 0.85, 1.0]], atol=1e-6)
    np.testing.assert_allclose(z[2, 2], [0.15, 0.225, 0.3], atol=1e-6)  # heading large, fast
    # Eight rules fire: 0.1·(0.275 + 0.7 + 0.175 + 0.5) + 0.15·(0.35 + 0.85 + 0.25 + 0.65) = 0.48.
    out = fuzzy_evaluate(e, s, c, p, 0.3, 1.0)
    np.testing.assert_allclose(out, [0.48], atol=1e-6)
    # Corners: small/fast/far is rated 1; large/fast/far is cut to half of 0.6.
    out = fuzzy_evaluate(jnp.array([0.0, 1.0]), jnp.array([1.0, 1.0]), jnp.array([1.5, 1.5]), p, 0.3, 1.0)
    np.testing.assert_allclose(out, [1.0, 0.3], atol=1e-6)
    # Without the veto the rule base is the weighted sum of the linearly interpolated levels.
    rng = np.random.default_rng(5)
    e, s, c = (jnp.asarray(rng.uniform(lo, hi, 50), jnp.float32) for lo, hi in ((0, 1), (0, 1), (0, 1.4)))
    monkeypatch.setattr(_fuzzy, "VETO", 1.0)
    linear = (0.4 * (1 - e) + 0.3 * s + 0.3 * jnp.clip((c - 0.3) / 0.7, 0, 1)) / 1.0
    np.testing.assert_allclose(fuzzy_evaluate(e, s, c, p, 0.3, 1.0), linear, atol=1e-6)
    # Membership degrees of every input sum to one (Ruspini partitions), also outside the breakpoints.
    x = jnp.linspace(-0.5, 1.5, 41)
    for m in input_memberships(x, x, x, 0.3, 1.0):
        np.testing.assert_allclose(np.sum(m, axis=0), 1.0, atol=1e-6)
        assert np.all(np.asarray(m) >= -1e-7)


def test_batched_equals_per_robot(clutter):
    rng = np.random.default_rng(2)
    config = DWAConfig(evaluator="fuzzy")
    states, goals = _states(rng, 6, clutter, config.robot)
    obs = DiscObstacles(np.array([[3.0, 3.0], [8.0, 6.0]]), np.array([[0.5, 0.0], [0.0, -0.5]]), np.array([0.3, 0.4]))
    u, info = dwa_step(states, goals, clutter, obstacles=obs, config=config)
    for i in range(6):
        ui, ii = dwa_step(states[i], goals[i], clutter, obstacles=obs, config=config)
        np.testing.assert_allclose(ui, u[i], atol=1e-5)
        assert ii.chosen == info.chosen[i] and ii.recovery == info.recovery[i]
        np.testing.assert_allclose(ii.scores, info.scores[i], rtol=1e-5, atol=1e-5)
        np.testing.assert_array_equal(ii.feasible, info.feasible[i])
    # Per-robot obstacles [B, M, ...]: each robot sees its own discs (e.g. the other robots).
    per = DiscObstacles(states[None, :, :2].repeat(6, 0), np.zeros((6, 6, 2)), np.full((6, 6), 0.25))
    per = jax.tree.map(lambda a: np.delete(a.reshape(36, -1), np.arange(6) * 7, axis=0).reshape((6, 5) + a.shape[2:]),
                       per)  # drop each robot itself
    u, info = dwa_step(states, goals, clutter, obstacles=per, config=config)
    for i in (0, 3):
        ui, ii = dwa_step(states[i], goals[i], clutter, obstacles=jax.tree.map(lambda a, i=i: a[i], per), config=config)
        np.testing.assert_allclose(ui, u[i], atol=1e-5)
        np.testing.assert_allclose(ii.clearance, info.clearance[i], atol=1e-5)


def test_same_input_same_output(clutter):
    rng = np.random.default_rng(3)
    states, goals = _states(rng, 5, clutter, Unicycle())
    a = dwa_step(states, goals, clutter)
    b = dwa_step(states, goals, clutter)
    np.testing.assert_array_equal(a[0], b[0])
    for x, y in zip(a[1], b[1], strict=True):
        np.testing.assert_array_equal(x, y)


def test_hybrid_clearance_exact_near_obstacles_and_close_beyond():
    rng = np.random.default_rng(4)
    free = rng.random((18, 22)) > 0.2
    grid = jp.grid_from_array(free, resolution=0.5)
    table = clearance_table(collision_map(grid))
    pts = rng.uniform(-0.6, [11.6, 9.6], (3000, 2))
    want = _brute_clearance(pts, free, 0.5)
    got = {m: np.asarray(jax.jit(lambda t, x, m=m: static_clearance(t, x[:, 0], x[:, 1], m))(table, pts))
           for m in ("hybrid", "bilinear", "exact")}
    near = want < 1.5 * 0.5
    np.testing.assert_allclose(got["hybrid"][near], want[near], atol=2e-5)
    assert np.all(got["hybrid"] - want <= 0.09 * 0.5)  # beyond 1.5 cells: interpolation, ≤ 0.083 cells high
    exact_range = want <= 2 * 0.5
    np.testing.assert_allclose(got["exact"][exact_range], want[exact_range], atol=2e-5)
    assert np.max(got["bilinear"] - want) > 0.05  # the plain interpolation over-estimates at corners


def test_rollouts_follow_the_motion_model():
    grid = jp.grid_from_array(np.ones((30, 30), bool), resolution=0.5)
    state = np.array([7.0, 7.0, 0.3, 0.6, -0.5])
    u, info = dwa_step(state, [12.0, 9.0], grid)
    for i in (0, 123, 517, 799):
        v, w = info.samples[i]
        s = state.copy()
        for k in range(20):
            s = np.asarray(advance(s, np.array([v, w]), 0.1))
            np.testing.assert_allclose(info.rollouts[i, k, :2], s[:2], atol=2e-5)
        assert abs(math.remainder(info.rollouts[i, -1, 2] - s[2], 2 * math.pi)) < 1e-5


def test_rectangle_footprint_sees_its_corners():
    free = np.ones((12, 12), bool)
    free[:, 6] = False  # a wall at x in [3.0, 3.5] m
    grid = jp.grid_from_array(free, resolution=0.5)
    # Facing the wall, centre 0.6 m from it: a 0.25 m disc keeps 0.6 m, a 1.0 m long body only 0.1 m.
    state = np.array([2.4, 3.0, 0.0, 0.0, 0.0])
    disc = dwa_step(state, [1.0, 3.0], grid, config=DWAConfig(n_v=3, n_omega=5))[1]
    rect_robot = Unicycle(footprint=Rectangle(1.0, 0.4, 4))
    cfg = DWAConfig(robot=rect_robot, n_v=3, n_omega=5, d_safe=0.32, escape=False)
    rect = dwa_step(state, [1.0, 3.0], grid, config=cfg)[1]
    assert disc.feasible.any() and not disc.recovery
    assert disc.clearance.max() > 0.55
    # The rectangle's covering discs (radius 0.236 m) sit up to 0.375 m ahead: clearance ≈ 0.6 − 0.375.
    assert rect.clearance.max() < 0.6 - 0.375 + 0.005
    assert not rect.feasible.any() and rect.recovery
    # With the escape rule the robot, already inside d_safe, may keep or gain clearance, never lose it.
    esc = dwa_step(state, [1.0, 3.0], grid, config=cfg.replace(escape=True))[1]
    assert esc.feasible.any() and not esc.recovery
    assert esc.clearance[esc.chosen] >= 0.6 - 0.375 - 0.005


def test_path_critic_pulls_towards_the_global_path():
    grid = jp.grid_from_array(np.ones((20, 30), bool), resolution=0.5)
    state = np.array([3.0, 5.0, 0.0, 0.6, 0.0])
    path = np.array([[2.0, 6.5], [12.0, 6.5], [12.0, 6.5]])  # 1.5 m to the side (+y); last point repeated
    base, _ = dwa_step(state, [12.0, 5.0], grid)
    pulled, info = dwa_step(state, [12.0, 5.0], grid, params={"path": 1.0}, path=path)
    assert pulled[1] > base[1] + 0.1  # turns towards +y, the side of the path
    end = info.rollouts[np.arange(800), -1, :2]
    d = np.abs(end[:, 1] - 6.5)  # distance of each end point to the (horizontal) path
    assert d[info.chosen] <= np.percentile(d[info.feasible], 10)


@pytest.mark.parametrize("bad, match", [
    (dict(state=[np.nan, 0, 0, 0, 0]), "NaN or infinite"),
    (dict(state=[1, 1, 0, 0]), r"state must be \[5\]"),
    (dict(subgoal=[np.inf, 1.0]), "subgoal"),
    (dict(config=DWAConfig(robot=Unicycle(accel=-0.5))), "accel must be > 0"),
    (dict(config=DWAConfig(robot=Unicycle(v_min=1.0, v_max=0.5))), "v_min"),
    (dict(config=DWAConfig(robot=Unicycle(omega_max=float("nan")))), "omega_max must be finite"),
    (dict(config=DWAConfig(d_safe=0.1)), "d_safe"),
    (dict(config=DWAConfig(n_v=0)), "n_v"),
    (dict(config=DWAConfig(evaluator="best")), "evaluator"),
    (dict(config=DWAConfig(horizon=1.05, dt=0.1)), "whole number"),
    (dict(config=DWAConfig(robot=Unicycle(omega_max=40.0))), "at most π"),
    (dict(params={"heading": -0.1}), "must be >= 0"),
    (dict(params={"velocity": float("nan")}), "NaN"),
    (dict(params={"temperature": 0.0}), "temperature"),
    (dict(params={"speed": 1.0}), "unknown DWA parameter"),
    (dict(state=[1, 1, 0, 5.0, 0]), "empty dynamic window"),
    (dict(state=[1, 1, 0, 0.5, 9.0]), "empty dynamic window"),
    (dict(obstacles=(np.zeros((2, 2)), np.zeros((2, 2)), np.array([0.3, -1.0]))), "radii"),
    (dict(obstacles=(np.zeros((2, 2)), np.zeros((3, 2)), np.array([0.3, 0.3]))), "velocities"),
    (dict(path=np.zeros((4, 3))), "path"),
    (dict(state=[-0.2, 1.0, 0.0, 0.5, 0.0]), "outside the map"),
    (dict(state=[[1.0, 1.0, 0.0, 0.5, 0.0], [1.0, 9.0, 0.0, 0.5, 0.0]], subgoal=[[3.0, 3.0]] * 2),
     r"state\[1\].*outside"),
])
def test_bad_input_is_a_clear_error(bad, match):
    grid = jp.grid_from_array(np.ones((8, 8), bool), resolution=0.5)
    args = dict(state=[1.0, 1.0, 0.0, 0.5, 0.0], subgoal=[3.0, 3.0], params=None, config=None, obstacles=None,
                path=None)
    args.update(bad)
    with pytest.raises(ValueError, match=match):
        dwa_step(args["state"], args["subgoal"], grid, obstacles=args["obstacles"], params=args["params"],
                 config=args["config"], path=args["path"])


def test_softmax_episode_is_differentiable_in_the_weights():
    free = np.ones((16, 16), bool)
    free[5:11, 8] = False
    grid = jp.grid_from_array(free, resolution=0.5)
    table = clearance_table(collision_map(grid))
    config = DWAConfig(selection="softmax", keep_rollouts=False, n_v=6, n_omega=9, horizon=1.0, unroll=1)
    goal = jnp.array([7.0, 4.0])

    def loss(params):
        def step(state, _):
            u, _ = dwa_control(table, config, params, state, goal)
            return advance(state, u, config.period), None
        final, _ = jax.lax.scan(step, jnp.array([1.0, 4.0, 0.0, 0.0, 0.0]), None, length=6)
        return jnp.sum((final[:2] - goal) ** 2)

    p = default_params("weighted")
    p = DWAParams(*(jnp.asarray(x) for x in p))
    g = jax.jit(jax.grad(loss))(p)
    weights = np.array([g.heading, g.velocity, g.clearance, g.goal, g.temperature])
    assert np.all(np.isfinite(weights)), weights
    assert np.all(np.abs(weights[:3]) > 0), weights


def test_core_traces_once_per_configuration(clutter):
    table = clearance_table(collision_map(clutter))
    traces = []

    @jax.jit
    def step(config, params, state):
        traces.append(1)
        return dwa_control(table, config, params, state, jnp.array([5.0, 5.0]))[0]

    cfg = DWAConfig(keep_rollouts=False, n_v=4, n_omega=6)
    s = jnp.array([2.0, 2.0, 0.0, 0.3, 0.0])
    step(cfg, default_params(), s)
    step(cfg.replace(d_safe=0.35, robot=Unicycle(v_max=1.0)), default_params(heading=0.9), s + 0.1)
    assert len(traces) == 1  # limits, distances and weights are traced
    step(cfg.replace(n_v=5), default_params(), s)
    assert len(traces) == 2  # sample counts are static


def test_rollouts_are_checked_only_until_they_enter_the_finish_disc():
    free = np.zeros((7, 30), bool)
    free[2:5, 1:20] = True  # a corridor 1.5 m wide, closed at x = 10 m
    grid = jp.grid_from_array(free, resolution=0.5)
    table = clearance_table(collision_map(grid))
    config = DWAConfig(keep_rollouts=True)
    state = jnp.asarray([8.0, 1.75, 0.0, 1.0, 0.0])  # 1 m/s towards the end wall, 2 m away
    goal = jnp.asarray([9.0, 1.75])
    control = jax.jit(dwa_control)
    _, plain = control(table, config, default_params(), state, goal)
    finish = jnp.asarray([9.0, 1.75, 0.5])
    _, ended = control(table, config, default_params(), state, goal, None, None, finish)
    samples = np.asarray(ended.samples)
    straight = np.argmin(np.abs(samples[:, 1]) - samples[:, 0])  # the fastest sample with the least turn
    assert abs(samples[straight, 1]) < 0.06 and samples[straight, 0] > 0.9
    assert not plain.feasible[straight]  # run on for 2 s, it reaches the end wall ...
    assert ended.feasible[straight]  # ... but the robot stops in the goal disc, 1 m short of it
    pts = np.asarray(ended.rollouts[straight, :, :2])
    inside = np.hypot(*(pts - [9.0, 1.75]).T) <= 0.5
    first = int(np.argmax(inside))
    assert inside.any() and first < len(pts) - 1
    want = _brute_clearance(pts[:first + 1], free, 0.5).min()  # up to and including the first point inside
    assert float(ended.clearance[straight]) == pytest.approx(want, abs=2e-3)
    assert float(plain.clearance[straight]) < 0.3
    np.testing.assert_array_equal(np.asarray(plain.samples), samples)
    # Batched: a finish disc per robot (the second robot's is far away: no effect).
    from jaxplan.dwa import dwa_control_batch
    states = jnp.stack([state, state])
    finishes = jnp.stack([finish, jnp.asarray([1.0, 1.75, 0.5])])
    _, both = jax.jit(dwa_control_batch)(table, config, default_params(), states, jnp.stack([goal, goal]),
                                         finish=finishes)
    np.testing.assert_array_equal(np.asarray(both.clearance[0]), np.asarray(ended.clearance))
    np.testing.assert_array_equal(np.asarray(both.clearance[1]), np.asarray(plain.clearance))


def test_flee_keeps_off_the_map_when_it_can():
    from jaxplan.dwa._core import _flee
    from jaxplan.dwa._rollout import Rollouts

    def ro(clearance, static):
        return Rollouts(None, None, jnp.asarray(clearance), None, None if static is None else jnp.asarray(static))

    # Sample 1 keeps the most clearance from anything but runs within d_safe of a wall: take 0.
    assert int(_flee(ro([0.2, 0.28, 0.1], [0.5, 0.1, 0.4]), 0.3)) == 0
    # No sample keeps d_safe from the map: the most clearance from anything.
    assert int(_flee(ro([0.2, 0.28, 0.1], [0.2, 0.1, 0.25]), 0.3)) == 1
    assert int(_flee(ro([0.2, 0.28, 0.1], None), 0.3)) == 1  # no discs: nothing is split


def test_flee_rollouts_split_the_clearance_without_changing_it(clutter):
    # With discs and recovery="flee" the rollouts keep the map's minimum apart; the combined
    # clearance, feasibility and choice are those of the unsplit rollouts.
    rng = np.random.default_rng(3)
    table = clearance_table(collision_map(clutter))
    discs = DiscObstacles(jnp.asarray(rng.uniform(2, 10, (3, 2)), jnp.float32),
                          jnp.asarray(rng.normal(0, 1, (3, 2)), jnp.float32), jnp.full(3, 0.3, jnp.float32))
    control = jax.jit(dwa_control)
    states, goals = _states(rng, 4, clutter, Unicycle())
    for robot in (Unicycle(), Unicycle(footprint=Rectangle(0.6, 0.4))):
        cfg = DWAConfig(keep_rollouts=False, robot=robot, n_v=6, n_omega=9)
        for state, goal in zip(jnp.asarray(states, jnp.float32), jnp.asarray(goals, jnp.float32), strict=True):
            a = control(table, cfg, default_params(), state, goal, discs)[1]
            b = control(table, cfg.replace(recovery="flee"), default_params(), state, goal, discs)[1]
            np.testing.assert_array_equal(b.clearance, a.clearance)
            np.testing.assert_array_equal(b.feasible, a.feasible)
            assert int(b.chosen) == int(a.chosen)


def test_a_robot_on_a_blocked_cell_is_an_error():
    # Its clearance is 0 all round, and the escape rule would then call every rollout feasible.
    free = np.ones((12, 12), bool)
    free[5, 5] = False
    grid = jp.grid_from_array(free, resolution=1.0)
    with pytest.raises(ValueError, match=r"blocked cell \[5, 5\]"):
        dwa_step([5.5, 5.5, 0.0, 0.3, 0.0], [9.0, 9.0], grid)
    dwa_step([4.5, 5.5, 0.0, 0.3, 0.0], [9.0, 9.0], grid)  # the next cell is fine


def test_an_ackermann_robot_never_turns_tighter_than_it_can():
    kappa = lambda r: np.tan(r.steer_max) / r.wheelbase  # noqa: E731
    # The classic stuck-escape rule at rest facing a wall: a car cannot turn on the spot.
    free = np.ones((10, 10), bool)
    free[:, 6:] = False
    grid = jp.grid_from_array(free, resolution=1.0)
    car = Ackermann()
    u, info = dwa_step([6.0 - 0.267 - 0.36, 5.0, 0.0, 0.0, 0.0], [5.9, 5.0], grid,
                       config=DWAConfig(robot=car, evaluator="classic"))
    assert info.stuck and abs(u[1]) <= kappa(car) * abs(u[0]) + 1e-6
    # Softmax blends of forward and reverse samples: |ω| <= κ|v| is not convex across v = 0.
    open_ = jp.grid_from_array(np.ones((20, 20), bool), resolution=1.0)
    car = Ackermann(v_min=-0.5)
    for temperature in (0.05, 0.2, 1.0):
        u, info = dwa_step([10.0, 10.0, 0.0, 0.0, 0.0], [10.0, 14.0], open_,
                           config=DWAConfig(robot=car, selection="softmax", n_v=5, n_omega=9),
                           params={"temperature": temperature, "velocity": 0.0})
        assert abs(u[1]) <= kappa(car) * abs(u[0]) + 1e-6, (temperature, u)
        assert info.window[2] - 1e-6 <= u[1] <= info.window[3] + 1e-6


def _brakes_clear(start, v, w, decel, disc_xy, disc_vel, disc_r, robot_r, t0, dt=0.005):
    """Brute force: brake from ``start`` (x, y, θ) at speed ``v`` along the curvature ``w/v``; True if the robot
    stops before its edge meets the disc (constant-velocity prediction from time ``t0``)."""
    x, y, th = map(float, start)
    kappa = w / v if v > 1e-3 else 0.0
    t = 0.0
    while v > 0:
        v2 = max(v - decel * dt, 0.0)
        ds = 0.5 * (v + v2) * dt
        x, y, th = x + ds * math.cos(th + kappa * ds / 2), y + ds * math.sin(th + kappa * ds / 2), th + kappa * ds
        v, t = v2, t + dt
        cx, cy = disc_xy + disc_vel * (t0 + t)
        if math.hypot(x - cx, y - cy) - disc_r < robot_r - 0.02:  # 2 cm: the check's discrete sampling
            return False
    return True


def test_admissible_samples_can_brake_before_a_predicted_contact():
    """A disc coming head-on down an open hall: with ``safety="predicted"`` every feasible sample — the chosen one
    included — can still brake to rest before the disc's predicted path reaches it; without, some cannot."""
    grid = jp.grid_from_array(np.ones((12, 30), bool), resolution=1.0)
    disc_xy, disc_vel = np.array([11.5, 6.0]), np.array([-1.5, 0.0])
    obs = DiscObstacles(jnp.asarray([disc_xy], jnp.float32), jnp.asarray([disc_vel], jnp.float32),
                        jnp.asarray([0.25], jnp.float32))
    state = np.array([5.0, 6.0, 0.0, 1.0, 0.0], np.float32)
    seen = {}
    for admissible in (False, True):
        config = DWAConfig(n_v=6, n_omega=9, safety="predicted" if admissible else "none")
        u, info = dwa_step(state, np.array([28.0, 6.0]), grid, obstacles=obs, config=config)
        r = config.robot
        ends = np.asarray(info.rollouts)[:, -1]
        samples = np.asarray(info.samples)
        ok = [_brakes_clear(ends[k], float(samples[k, 0]), float(samples[k, 1]), r.decel, disc_xy, disc_vel, 0.25,
                            0.25, config.horizon) for k in range(len(samples))]
        feasible = np.asarray(info.feasible)
        seen[admissible] = (feasible, np.asarray(ok))
        if admissible:
            assert feasible.any() and np.all(np.asarray(ok)[feasible])
            assert int(info.chosen) < 0 or ok[int(info.chosen)]
    feasible, ok = seen[False]
    assert np.any(feasible & ~ok), "the plain DWA keeps samples that cannot stop in time: the option must matter"
