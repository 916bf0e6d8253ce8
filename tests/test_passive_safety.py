"""Passive motion safety (``safety="passive"``): the check is sound against a fine simulation of the manoeuvre and of
walkers at their speed bound, braking stays safe from one step to the next, both local planners only ever apply a
checked control or the brake, and adversarial walkers — head-on, from behind and faster, turning into the robot's
way at the last moment — touch a passive robot only at rest, while they do hit a robot without the check."""

from __future__ import annotations

import warnings

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxplan as jp
from jaxplan.dwa import (
    FLOAT_SLACK,
    Ackermann,
    Disc,
    DiscObstacles,
    DWAConfig,
    Unicycle,
    advance,
    brake,
    clamp_controls,
    clearance_table,
    dwa_step,
    footprint_offsets,
    footprint_radius,
    passive_slack,
    sample_controls,
    static_clearance,
    window_of,
)
from jaxplan.grid import collision_map
from jaxplan.mppi import MPPIConfig, initial_sequence, mppi_control
from jaxplan.mppi import default_params as mppi_params
from jaxplan.nav import NavConfig, moving_obstacles

PERIOD = 0.2
PERIODS = 30  # braking periods checked: enough for both robots below


def _hall() -> jp.GridMap:
    """A 20 x 12 m hall at 0.5 m per cell with a pillar, so that the map part of the check matters too."""
    free = np.ones((24, 40), bool)
    free[10:14, 20:24] = False
    return jp.grid_from_array(free, resolution=0.5)


@pytest.fixture(scope="module")
def hall():
    grid = _hall()
    return grid, clearance_table(collision_map(grid))


def _fine_clearance(table, robot, state, v, w, walkers, radii, speed, periods=PERIODS, sub=40):
    """The true room (m) of each manoeuvre ``[S]`` — one period at (v, w), then `clamp_controls` braking — against
    the map (exact lookup) and the walkers' reachable sets, sampled ``sub`` times per period on the exact arcs
    (`advance`), over the times the robot moves; +inf for one that never moves."""
    fp = robot.footprint
    offsets = np.zeros(1) if isinstance(fp, Disc) else np.asarray(footprint_offsets(fp))
    reach_o = float(np.max(np.abs(offsets)))
    R = float(footprint_radius(fp))
    S = v.shape[0]
    pose = jnp.broadcast_to(jnp.asarray(state, jnp.float32), (S, 5))
    vk, wk = jnp.asarray(v), jnp.asarray(w)
    best = np.full(S, np.inf)
    taus = jnp.linspace(0.0, PERIOD, sub + 1)
    for k in range(periods + 1):
        if k > 0:
            vk, wk = clamp_controls(robot, vk, wk, jnp.zeros_like(vk), jnp.zeros_like(wk), PERIOD)
        u = jnp.stack([vk, wk], axis=-1)
        poses = jax.vmap(lambda tau, p=pose, u=u: advance(p, u, tau))(taus)  # [sub + 1, S, 5]
        moving = np.asarray((jnp.abs(vk) + reach_o * jnp.abs(wk)) > 0)
        for o in offsets:
            cx = poses[..., 0] + o * jnp.cos(poses[..., 2])
            cy = poses[..., 1] + o * jnp.sin(poses[..., 2])
            c = np.asarray(static_clearance(table, cx, cy, "exact"))
            if walkers is not None:
                t = (k * PERIOD + taus)[:, None, None]
                d = jnp.sqrt((cx[..., None] - walkers[:, 0]) ** 2 + (cy[..., None] - walkers[:, 1]) ** 2)
                c = np.minimum(c, np.asarray(jnp.min(d - radii - speed * t, axis=-1)))
            best = np.where(moving, np.minimum(best, c.min(axis=0) - R), best)
        pose = poses[-1]
    return best


@pytest.mark.parametrize("robot", [Unicycle(), Ackermann()], ids=["unicycle", "ackermann"])
def test_the_check_is_sound_and_not_vacuous(hall, robot):
    """Every control the check passes keeps its room in a simulation 20 times finer; among the samples of random
    states near walkers, some pass and some do not, and most controls with 0.3 m of true room pass."""
    grid, table = hall
    rng = np.random.default_rng(7)
    check = jax.jit(lambda st, v, w, wp, wr: passive_slack(table, "hybrid", robot, st, v, w, PERIOD,
                                                           DiscObstacles(wp, jnp.zeros_like(wp), wr), 1.0, PERIODS))
    passed = failed = roomy = roomy_passed = 0
    for _ in range(6):
        while True:
            xy = rng.uniform([1.5, 1.5], [18.5, 10.5])
            if float(static_clearance(table, jnp.float32(xy[0]), jnp.float32(xy[1]), "exact")) > 0.8:
                break
        state = np.array([*xy, rng.uniform(-np.pi, np.pi), rng.uniform(0.0, float(robot.v_max)),
                          rng.uniform(-0.5, 0.5)], np.float32)
        walkers = (xy + rng.uniform(-4.0, 4.0, (3, 2))).astype(np.float32)
        radii = np.full(3, 0.3, np.float32)
        v, w = sample_controls(robot, window_of(robot, state[3], state[4], PERIOD), 8, 9)
        slack = np.asarray(check(jnp.asarray(state), v, w, jnp.asarray(walkers), jnp.asarray(radii)))
        true = _fine_clearance(table, robot, state, v, w, jnp.asarray(walkers), jnp.asarray(radii), 1.0)
        ok = slack >= 0
        assert np.all(true[ok] >= -1e-4), (state, true[ok].min())
        passed += int(ok.sum())
        failed += int((~ok).sum())
        roomy += int((true >= 0.3).sum())
        roomy_passed += int((ok & (true >= 0.3)).sum())
    assert passed > 0 and failed > 0
    assert roomy_passed >= 0.8 * roomy


def test_braking_stays_safe_from_one_step_to_the_next(hall):
    """After an admissible control, the brake from where the robot then is keeps the same room, whatever the
    walkers did meanwhile at their speed bound (here: each walked straight at the robot)."""
    _, table = hall
    robot = Unicycle()
    V = 1.0
    check = jax.jit(lambda st, v, w, wp: passive_slack(table, "hybrid", robot, st, v, w, PERIOD,
                                                       DiscObstacles(wp, jnp.zeros_like(wp), jnp.full(2, 0.3)), V,
                                                       PERIODS))
    state = jnp.array([3.0, 3.0, 0.3, 0.8, 0.2], jnp.float32)
    walkers = jnp.array([[9.0, 4.0], [5.0, 8.0]], jnp.float32)
    v, w = sample_controls(robot, window_of(robot, state[3], state[4], PERIOD), 10, 11)
    slack = check(state, v, w, walkers)
    ok = np.nonzero(np.asarray(slack) >= 0)[0]
    assert ok.size > 0
    for i in ok[:: max(1, ok.size // 8)]:
        u = jnp.stack([v[i], w[i]])
        after = advance(state, u, PERIOD)
        toward = after[:2] - walkers
        moved = walkers + V * PERIOD * toward / jnp.linalg.norm(toward, axis=-1, keepdims=True)
        b = brake(robot, after, PERIOD)
        assert np.allclose(np.asarray(b), np.asarray(clamp_controls(robot, u[0], u[1], 0.0, 0.0, PERIOD)))
        again = float(check(after, b[None, 0], b[None, 1], moved)[0])
        assert again >= float(slack[i]) - FLOAT_SLACK, (i, float(slack[i]), again)


def test_the_dwa_applies_a_checked_sample_or_brakes(hall):
    grid, table = hall
    config = DWAConfig(safety="passive", walker_speed_max=1.0, n_v=8, n_omega=11)
    state = np.array([3.0, 3.0, 0.0, 1.0, 0.0], np.float32)
    # A walker standing 2.2 m ahead could reach every manoeuvre: nothing passes, and the robot brakes, while
    # the plain DWA, which expects it to stay there, drives round it.
    near = DiscObstacles(np.array([[5.5, 3.0]]), np.array([[0.0, 0.0]]), np.array([0.3]))
    u, info = dwa_step(state, [15.0, 3.0], grid, obstacles=near, config=config)
    assert not info.feasible.any() and bool(info.recovery)
    assert np.allclose(u, np.asarray(brake(config.robot, jnp.asarray(state), PERIOD)))
    plain, plain_info = dwa_step(state, [15.0, 3.0], grid, obstacles=near, config=config.replace(safety="none"))
    assert plain_info.feasible.any() and plain[0] > u[0]
    # One far away: the robot drives on, with a control that passes.
    far = DiscObstacles(np.array([[3.0, 10.5]]), np.array([[0.0, 0.0]]), np.array([0.3]))
    u, info = dwa_step(state, [15.0, 3.0], grid, obstacles=far, config=config)
    slack = passive_slack(table, "hybrid", config.robot, jnp.asarray(state), jnp.asarray(u[None, 0]),
                          jnp.asarray(u[None, 1]), PERIOD, far, 1.0, PERIODS)
    assert info.feasible.any() and float(slack[0]) >= 0 and u[0] > 0.9


def test_mppi_applies_a_checked_control_or_brakes(hall):
    _, table = hall
    cfg = MPPIConfig(safety="passive", walker_speed_max=1.0, samples=64)
    params = mppi_params()
    state = jnp.array([3.0, 3.0, 0.0, 1.0, 0.0], jnp.float32)
    step = jax.jit(lambda s, obs: mppi_control(table, cfg, params, s, initial_sequence(cfg, s), jax.random.key(1),
                                               jnp.array([15.0, 3.0]), obstacles=obs))
    near = DiscObstacles(jnp.array([[5.5, 3.0]]), jnp.array([[-1.0, 0.0]]), jnp.array([0.3]))
    far = DiscObstacles(jnp.array([[3.0, 10.5]]), jnp.zeros((1, 2)), jnp.array([0.3]))
    u, info = step(state, near)
    assert not np.asarray(info.admissible).any()
    assert np.allclose(np.asarray(u), np.asarray(brake(cfg.robot, state, PERIOD)))
    u, info = step(state, far)
    slack = passive_slack(table, "hybrid", cfg.robot, state, u[None, 0], u[None, 1], PERIOD, far, 1.0, PERIODS)
    assert np.asarray(info.admissible).any() and float(slack[0]) >= 0 and float(u[0]) > 0.9
    w = np.asarray(info.weights)
    assert np.all(w[~np.asarray(info.admissible)] == 0.0)


# ---------------------------------------------------------------------------------------------
# Adversarial walkers in navigation episodes


def _arena() -> jp.GridMap:
    """Two one-cell corridors and an open hall, 1 m per cell."""
    free = np.zeros((24, 40), bool)
    free[2, 1:39] = True  # head-on
    free[6, 1:39] = True  # from behind, faster than the robot
    free[10:23, 1:39] = True  # turning into the robot's way
    return jp.grid_from_array(free, resolution=1.0)


ADVERSARIES = [
    # A walker walking straight at the robot down a one-cell corridor.
    ("head-on", (3, 2), (36, 2), [[(36.5, 2.5), (1.5, 2.5)]], 1.0, 16.0),
    # Walkers faster than the robot (1.2 m/s) coming up behind it.
    ("from behind 1.5", (5, 6), (36, 6), [[(1.5, 6.5), (38.5, 6.5)]], 1.5, 0.0),
    ("from behind 2.0", (5, 6), (36, 6), [[(1.5, 6.5), (38.5, 6.5)]], 2.0, 0.0),
    # A walker passing 1.25 m beside the robot's way, who turns across it at the last moment (three timings).
    *[(f"turning {off}", (3, 16), (36, 16), [[(30.5, 17.75), (14.5, 17.75), (14.5, 12.5)]], 1.5, off)
      for off in (0.5, 1.5, 2.0)],
]


@pytest.fixture(scope="module")
def adversarial_runs():
    grid = _arena()
    starts = np.array([a[1] for a in ADVERSARIES])
    goals = np.array([a[2] for a in ADVERSARIES])
    obstacles = [[moving_obstacles(a[3], a[4], 0.3, offsets=a[5])] for a in ADVERSARIES]
    runs = {}
    for local in ("dwa", "mppi"):
        for safety in ("none", "passive"):  # the fronts' keyword sets NavConfig.safety
            runs[local, safety] = jp.navigate_batch(grid, starts, goals, seeds=[0], obstacles=obstacles,
                                                    global_planner="astar", local_planner=local,
                                                    config=NavConfig(max_time=20.0), safety=safety)
    return runs


@pytest.mark.parametrize("local", ["dwa", "mppi"])
def test_adversarial_walkers_touch_a_passive_robot_only_at_rest(adversarial_runs, local):
    plain, safe = adversarial_runs[local, "none"], adversarial_runs[local, "passive"]
    active = {a[0]: plain.episode(i, 0, 0).active_contacts for i, a in enumerate(ADVERSARIES)}
    assert sum(active.values()) >= 2, active  # the adversaries do hit a robot that does not check
    for i, a in enumerate(ADVERSARIES):
        e = safe.episode(i, 0, 0)
        assert e.active_contacts == 0, (a[0], e.reason, e.controls[-3:])
        if e.reason == "collision":  # the walker came to the robot: it was standing
            assert abs(float(e.controls[-1, 0])) <= 0.05, (a[0], e.controls[-3:])


# ---------------------------------------------------------------------------------------------
# Options and their checks


def test_safety_options_and_their_defaults():
    assert DWAConfig().safety == MPPIConfig().safety == "none" and NavConfig().safety is None
    with pytest.raises(ValueError, match="unknown safety"):
        jp.nav.resolve_config(NavConfig(safety="paranoid"), jp.nav.get_pipeline("iaco_dwa"), None)
    with pytest.raises(ValueError, match="follow"):
        jp.nav.resolve_config(NavConfig(safety="passive"), jp.nav.get_pipeline("iaco_dwa"), "follow")
    with pytest.raises(ValueError, match="walker_speed_max"):
        jp.nav.resolve_config(NavConfig(walker_speed_max=-1.0), jp.nav.get_pipeline("iaco_dwa"), None)
    cfg = jp.nav.resolve_config(NavConfig(safety="passive", walker_speed_max=1.5), jp.nav.get_pipeline("iaco_mppi"),
                                None)
    assert cfg.dwa.safety == cfg.mppi.safety == "passive"
    assert cfg.dwa.walker_speed_max == cfg.mppi.walker_speed_max == 1.5
    assert cfg.dwa.brake_periods == cfg.mppi.brake_periods == 13  # 1.2 m/s at 0.5 m/s² in 0.2 s periods, + 1
    grid = _hall()
    with pytest.raises(ValueError, match="safety"):
        dwa_step([3.0, 3.0, 0.0, 0.0, 0.0], [9.0, 3.0], grid, config=DWAConfig(safety="maybe"))
    with pytest.raises(ValueError, match="walker_speed_max"):
        jp.mppi_step([3.0, 3.0, 0.0, 0.0, 0.0], [9.0, 3.0], grid, config=MPPIConfig(walker_speed_max=float("nan")))


def test_the_old_admissible_option_still_works_with_a_warning():
    with pytest.warns(DeprecationWarning, match="safety='predicted'"):
        old = DWAConfig(admissible=True)
    assert old == DWAConfig(safety="predicted") and old.admissible is None
    with pytest.warns(DeprecationWarning):
        assert MPPIConfig().replace(admissible=True).safety == "predicted"
    with pytest.warns(DeprecationWarning):
        assert MPPIConfig(admissible=False) == MPPIConfig()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        DWAConfig(safety="passive").replace(n_v=5)  # no warning without the old field


def test_dwa_step_takes_obstacles_and_params_by_position_with_a_warning():
    grid = _hall()
    state, sub = [3.0, 3.0, 0.0, 0.5, 0.0], [9.0, 3.0]
    obs = (np.array([[6.0, 3.5]]), np.array([[-0.5, 0.0]]), np.array([0.3]))
    new, _ = dwa_step(state, sub, grid, obstacles=obs, params={"heading": 0.5})
    with pytest.warns(DeprecationWarning, match="by keyword"):
        old, _ = dwa_step(state, sub, grid, obs, {"heading": 0.5})
    assert np.array_equal(old, new)
    with pytest.raises(TypeError, match="multiple values"):
        dwa_step(state, sub, grid, obs, obstacles=obs)
