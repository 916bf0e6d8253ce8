"""MPPI local planner: limits, warm start, critics against hand computation, walls, passive safety, gradients."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxplan as jp
from jaxplan.dwa import Ackermann, DiscObstacles, Unicycle, clearance_table
from jaxplan.grid import collision_map
from jaxplan.mppi import (
    BRAKE_ROW,
    MEAN_ROW,
    MPPIConfig,
    clamp_controls,
    default_params,
    fixed_rows,
    initial_sequence,
    mppi_control,
    shift,
)
from jaxplan.mppi import _core as mppi_core
from jaxplan.mppi import _critics as C

CFG = MPPIConfig(samples=128)
PARAMS = default_params()


def _corridor(length: int = 20) -> jp.GridMap:
    free = np.ones((7, length), bool)
    free[0, :] = free[-1, :] = False
    return jp.grid_from_array(free, resolution=1.0)


@pytest.fixture(scope="module")
def corridor():
    grid = _corridor()
    return grid, clearance_table(collision_map(grid))


@pytest.fixture(scope="module")
def step(corridor):
    _, table = corridor

    @jax.jit
    def f(config, params, state, mean, key, subgoal, obstacles=None):
        return mppi_control(table, config, params, state, mean, key, subgoal, obstacles=obstacles)

    return f


def test_control_stays_within_the_robots_limits_and_window(step):
    for robot in (Unicycle(), Ackermann(footprint=jp.dwa.Disc(0.25))):
        cfg = CFG.replace(robot=robot)
        rng = np.random.default_rng(0)
        for i in range(6):
            state = jnp.array([3.0 + i, 3.5, rng.uniform(-1, 1), rng.uniform(0, robot.v_max), rng.uniform(-1, 1)],
                              jnp.float32)
            mean = jnp.asarray(rng.normal(0, 2, (cfg.steps, 2)), jnp.float32)  # far outside the limits
            u, info = step(cfg, PARAMS, state, mean, jax.random.key(i), jnp.array([18.0, 3.5]))
            v, w = float(u[0]), float(u[1])
            p = cfg.period
            assert robot.v_min - 1e-6 <= v <= robot.v_max + 1e-6
            assert float(state[3]) - robot.decel * p - 1e-5 <= v <= float(state[3]) + robot.accel * p + 1e-5
            assert abs(w) <= robot.omega_max + 1e-6
            assert abs(w - float(state[4])) <= robot.alpha * p + 1e-5
            if isinstance(robot, Ackermann):
                kappa = math.tan(robot.steer_max) / robot.wheelbase
                assert abs(w) <= kappa * abs(v) + 1e-5
            # every clamped sequence is executable period by period
            ctrl = np.asarray(info.controls)
            dv = np.diff(np.concatenate([np.full((ctrl.shape[0], 1), float(state[3])), ctrl[..., 0]], axis=1))
            assert np.all(dv <= robot.accel * p + 1e-5) and np.all(dv >= -robot.decel * p - 1e-5)


def test_clamp_controls_by_hand():
    robot = Unicycle()
    v, w = clamp_controls(robot, jnp.float32(0.5), jnp.float32(0.0), jnp.float32(2.0), jnp.float32(-5.0), 0.2)
    assert float(v) == pytest.approx(0.6) and float(w) == pytest.approx(-0.6)
    v, w = clamp_controls(robot, jnp.float32(0.05), jnp.float32(0.0), jnp.float32(-1.0), jnp.float32(0.1), 0.2)
    assert float(v) == pytest.approx(0.0) and float(w) == pytest.approx(0.1)


def test_warm_start_shifts_the_sequence():
    seq = jnp.arange(10 * 2, dtype=jnp.float32).reshape(10, 2)
    out = shift(seq)
    np.testing.assert_array_equal(out[:-1], seq[1:])
    np.testing.assert_array_equal(out[-1], seq[-1])
    state = jnp.array([1.0, 2.0, 0.3, 0.4, -0.2])
    np.testing.assert_array_equal(initial_sequence(CFG, state), np.tile([0.4, -0.2], (CFG.steps, 1)).astype(np.float32))


def test_warm_start_is_the_last_solution(step):
    """With zero noise every sample is the mean: the new mean is the clamped warm start, and shifting it feeds the
    next step."""
    params = default_params(noise_v=1e-6, noise_omega=1e-6)
    state = jnp.array([3.0, 3.5, 0.0, 0.5, 0.0], jnp.float32)
    mean = jnp.tile(jnp.array([0.6, 0.1], jnp.float32), (CFG.steps, 1))
    u, info = step(CFG, params, state, mean, jax.random.key(0), jnp.array([18.0, 3.5]))
    np.testing.assert_allclose(info.controls[MEAN_ROW], info.sequence, atol=1e-3)  # the brake row weighs ~1e-3
    np.testing.assert_allclose(u, [0.6, 0.1], atol=1e-3)


def test_critics_against_hand_computation():
    # obstacle and dynamic: 1 - min(c, clip)/clip
    np.testing.assert_allclose(C.obstacle(jnp.array([0.1, 0.5, 2.0, -1.0]), 0.5), [0.8, 0.0, 0.0, 1.0], atol=1e-7)
    np.testing.assert_allclose(C.dynamic(jnp.array([0.25, 1.0]), 1.0), [0.75, 0.0], atol=1e-7)
    # path distance to the polyline (0,0)-(4,0)-(4,4)
    path = jnp.array([[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [9.0, 9.0]])
    d = C.path_distance(jnp.array([2.0, 5.0, 6.0]), jnp.array([1.0, 2.0, -1.0]), path, jnp.asarray(3))
    np.testing.assert_allclose(d, [1.0, 1.0, math.hypot(2.0, 1.0)], rtol=1e-6)
    np.testing.assert_allclose(C.path_align(jnp.array([2.0]), jnp.array([3.0]), path, jnp.asarray(3), 1.0), [1.0])
    np.testing.assert_allclose(C.path_align(jnp.array([2.0]), jnp.array([3.0]), path, jnp.asarray(0), 1.0), [0.0])
    # path follow: (|p - g| - |p0 - g| + reach) / (2 reach), clipped to [0, 1]
    pf = C.path_follow(jnp.array([0.0, 0.0, 0.0]), jnp.array([4.0, 1.0, 9.0]), jnp.array([0.0, 0.0]),
                       jnp.array([0.0, 3.0]), 2.0)
    np.testing.assert_allclose(pf, [(4 - 3 + 2) / 4, (1 - 3 + 2) / 4, 1.0], rtol=1e-6)
    # goal: min(|p - goal|, r)/r
    np.testing.assert_allclose(C.goal(jnp.array([1.0, 5.0]), jnp.array([0.0, 0.0]), jnp.zeros(2), 2.0), [0.5, 1.0])
    # goal heading: facing +x, sub-goal straight up -> 90 deg -> 0.5; straight ahead -> 0; behind -> 1
    h = jnp.exp(1j * jnp.zeros(3)).astype(jnp.complex64)
    gh = C.goal_heading(jnp.zeros(3), jnp.zeros(3), h, jnp.array([0.0, 1.0]))
    np.testing.assert_allclose(gh, [0.5] * 3, atol=1e-6)
    np.testing.assert_allclose(C.goal_heading(jnp.zeros(1), jnp.zeros(1), h[:1], jnp.array([-1.0, 0.0])), [1.0],
                               atol=1e-6)
    # prefer forward, constraint
    np.testing.assert_allclose(C.prefer_forward(jnp.array([-0.6, 0.3]), 1.2), [0.5, 0.0])
    robot = Unicycle()  # accel 0.5, alpha 3: reach 0.1 m/s and 0.6 rad/s per 0.2 s period
    c = C.constraint(jnp.array([0.6]), jnp.array([0.0]), jnp.array([0.65]), jnp.array([0.3]), robot, 0.2)
    np.testing.assert_allclose(c, [0.5 * (0.05 / 0.1 + 0.3 / 0.6)], rtol=1e-5)


def test_cost_is_the_weighted_sum():
    from jaxplan.mppi import CRITICS

    terms = C.Terms(*(jnp.array([0.1 * (i + 1)]) for i in range(len(CRITICS))), end=None)
    w = default_params()
    expect = sum(float(getattr(w, k)) * 0.1 * (i + 1) for i, k in enumerate(CRITICS))
    np.testing.assert_allclose(C.cost(terms, w), [expect], rtol=1e-6)


def test_a_robot_facing_a_wall_stops():
    free = np.ones((9, 9), bool)
    free[:, 6] = False  # a wall across the way, the sub-goal behind it
    grid = jp.grid_from_array(free, resolution=1.0)
    table = clearance_table(collision_map(grid))
    state = jnp.array([2.5, 4.5, 0.0, 0.8, 0.0], jnp.float32)
    goal = jnp.array([8.5, 4.5])
    f = jax.jit(lambda s, m, k: mppi_control(table, CFG, PARAMS, s, m, k, goal))
    mean = initial_sequence(CFG, state)
    for i in range(60):
        u, info = f(state, mean, jax.random.key(i))
        state = jp.dwa.advance(state, u, CFG.period)
        mean = shift(info.sequence)
        clear = float(jp.dwa.static_clearance(table, state[0:1], state[1:2])[0])
        assert clear >= 0.25, (i, np.asarray(state))
    assert abs(float(state[3])) < 0.05


def test_admissible_never_chooses_a_sequence_that_cannot_stop(corridor):
    """A disc parked 2 m ahead of a fast robot: with the admissibility option every sequence with weight is one
    whose braking run from its end stays clear, and the robot brakes."""
    _, table = corridor
    cfg = CFG.replace(safety="predicted", d_safe=0.3)
    disc = DiscObstacles(jnp.array([[8.0, 3.5]]), jnp.zeros((1, 2)), jnp.array([0.25]))
    state = jnp.array([4.5, 3.5, 0.0, 1.2, 0.0], jnp.float32)
    u, info = jax.jit(lambda s: mppi_control(table, cfg, PARAMS, s, initial_sequence(cfg, s), jax.random.key(3),
                                             jnp.array([18.0, 3.5]), obstacles=disc))(state)
    w = np.asarray(info.weights)
    adm = np.asarray(info.admissible)
    assert np.all(w[~adm] == 0.0)
    assert adm[BRAKE_ROW]
    # check the chosen sequences by brute force: roll each out and brake from its end
    for k in np.nonzero(w > 1e-3)[0]:
        s = np.asarray(state, np.float64)
        for v, om in np.asarray(info.controls[k]):
            for _ in range(20):
                s = np.asarray(jp.dwa.advance(jnp.asarray(s), jnp.array([v, om]), cfg.period / 20), np.float64)
        v = max(float(s[3]), 0.0)
        kappa = float(s[4]) / v if v > 1e-3 else 0.0
        t, dt = 0.0, 0.01
        while v > 0:
            v2 = max(v - 0.5 * dt, 0.0)
            s = np.asarray(jp.dwa.advance(jnp.asarray(s), jnp.array([v2, kappa * v2]), dt), np.float64)
            v, t = v2, t + dt
            assert math.hypot(s[0] - 8.0, s[1] - 3.5) - 0.25 >= 0.25 - 0.02, (k, t)
    assert float(u[0]) < float(state[3])


def test_admissible_with_a_walker_coming_head_on(corridor):
    """A disc walking at the robot down the corridor: every sequence with weight can brake to rest, from its end,
    before the disc's predicted path reaches it (brute force), and the robot slows down."""
    from test_dwa import _brakes_clear

    _, table = corridor
    cfg = CFG.replace(safety="predicted")
    disc_xy, disc_vel = np.array([12.0, 3.5]), np.array([-1.0, 0.0])
    disc = DiscObstacles(jnp.asarray([disc_xy], jnp.float32), jnp.asarray([disc_vel], jnp.float32),
                         jnp.array([0.25]))
    state = jnp.array([4.0, 3.5, 0.0, 1.0, 0.0], jnp.float32)
    u, info = mppi_control(table, cfg, PARAMS, state, initial_sequence(cfg, state), jax.random.key(5),
                           jnp.array([18.0, 3.5]), obstacles=disc)
    w = np.asarray(info.weights)
    for k in np.nonzero(w > 1e-4)[0]:
        s = np.asarray(state, np.float64)
        for v, om in np.asarray(info.controls[k]):
            s = np.asarray(jp.dwa.advance(jnp.asarray(s), jnp.array([v, om]), cfg.period), np.float64)
        assert _brakes_clear(s[:3], max(float(s[3]), 0.0), float(s[4]), cfg.robot.decel, disc_xy, disc_vel, 0.25,
                             0.25, cfg.horizon), k
    assert np.all(w[~np.asarray(info.admissible)] == 0.0)


def test_an_empty_way_drives_at_speed(step):
    state = jnp.array([2.0, 3.5, 0.0, 0.0, 0.0], jnp.float32)
    mean = initial_sequence(CFG, state)
    for i in range(15):
        u, info = step(CFG, PARAMS, state, mean, jax.random.key(i), jnp.array([18.0, 3.5]))
        state = jp.dwa.advance(state, u, CFG.period)
        mean = shift(info.sequence)
    assert float(state[3]) > 0.8 and abs(float(state[1]) - 3.5) < 0.5


def test_same_key_same_control(step):
    state = jnp.array([3.0, 3.5, 0.2, 0.5, 0.1], jnp.float32)
    a = step(CFG, PARAMS, state, initial_sequence(CFG, state), jax.random.key(7), jnp.array([18.0, 3.5]))[0]
    b = step(CFG, PARAMS, state, initial_sequence(CFG, state), jax.random.key(7), jnp.array([18.0, 3.5]))[0]
    np.testing.assert_array_equal(a, b)


def test_differentiable_through_the_softmax(corridor):
    _, table = corridor
    state = jnp.array([3.0, 3.0, 0.3, 0.5, 0.0], jnp.float32)

    def loss(params):
        u, _ = mppi_control(table, CFG, params, state, initial_sequence(CFG, state), jax.random.key(1),
                            jnp.array([18.0, 3.5]))
        return u[1] ** 2 + (u[0] - 1.0) ** 2

    g = jax.grad(loss)(jax.tree.map(jnp.asarray, PARAMS))
    leaves = jax.tree.leaves(g)
    assert all(np.isfinite(np.asarray(x)).all() for x in leaves)
    assert any(float(jnp.abs(x)) > 0 for x in (g.temperature, g.path_follow, g.goal_heading))


def test_bad_parameters_are_refused():
    with pytest.raises(ValueError, match="temperature"):
        default_params(temperature=0.0)
    with pytest.raises(ValueError, match="obstacle"):
        default_params(obstacle=float("nan"))
    with pytest.raises(ValueError, match="unknown MPPI parameter"):
        default_params(heading=1.0)


def test_noise_is_standard_normal_and_keyed():
    from jaxplan.mppi._noise import gaussian

    z = np.asarray(gaussian(jax.random.key(3), (200_000,)), np.float64)
    assert abs(z.mean()) < 0.01 and abs(z.std() - 1.0) < 0.01 and abs(np.mean(z ** 4) - 3.0) < 0.1
    a = np.asarray(gaussian(jax.random.key(3), (4096,)))
    b = np.asarray(gaussian(jax.random.key(4), (4096,)))
    np.testing.assert_array_equal(a, np.asarray(gaussian(jax.random.key(3), (4096,))))
    assert abs(np.corrcoef(a, b)[0, 1]) < 0.05 and len(set(a.tolist()) & set(b.tolist())) < 10


def _drive_from_the_wall(corridor, steps: int = 40) -> tuple[float, float]:
    """A robot at rest 0.31 m from the corridor's wall, facing it, its sub-goal along the corridor: ``(distance
    made along the corridor, least clearance)`` after ``steps`` MPPI steps."""
    _, table = corridor
    state = jnp.array([3.0, 1.31, -1.2, 0.0, 0.0], jnp.float32)
    goal = jnp.array([15.5, 1.5])
    f = jax.jit(lambda s, m, k: mppi_control(table, CFG, PARAMS, s, m, k, goal))
    mean = initial_sequence(CFG, state)
    least = np.inf
    for i in range(steps):
        u, info = f(state, mean, jax.random.key(i))
        state = jp.dwa.advance(state, u, CFG.period)
        mean = shift(info.sequence)
        least = min(least, float(jp.dwa.static_clearance(table, state[0:1], state[1:2])[0]))
    return float(state[0]) - 3.0, least


def test_a_robot_at_rest_facing_a_wall_turns_in_place_and_drives_on(corridor, monkeypatch):
    """Every sequence that drives first would bring the robot inside d_safe; the turn-in-place candidate (row
    `TURN_ROW`) turns it towards the sub-goal, and then it drives. Without the candidate it stands."""
    made, least = _drive_from_the_wall(corridor)
    assert made >= 2.0 and least >= CFG.d_safe - 1e-3, (made, least)
    assert fixed_rows(CFG) == 3 and fixed_rows(CFG.replace(robot=Ackermann())) == 2
    monkeypatch.setattr(mppi_core, "fixed_rows", lambda config: 2)
    made, _ = _drive_from_the_wall(corridor)
    assert made < 0.5, made
