"""Navigation beyond DWA: MPPI episodes, walkers that see, active and passive contacts."""

from __future__ import annotations

import numpy as np
import pytest

import jaxplan as jp
from jaxplan.dwa import Unicycle
from jaxplan.mppi import MPPIConfig
from jaxplan.nav import NavConfig, moving_obstacles

OPEN = jp.grid_from_array(np.ones((9, 24), bool), resolution=1.0)


@pytest.fixture(scope="module")
def warehouse():
    return jp.WarehouseGenerator(20, 14, shelf_length=4, shelf_depth=2, aisle=2, cross_aisle=2)(3)


def test_mppi_episode_arrives_within_the_robots_limits(warehouse):
    grid = warehouse.grid
    cfg = NavConfig(mppi=MPPIConfig(samples=96))
    ep = jp.navigate(grid, warehouse.start, warehouse.goal, pipeline="astar_kng_mppi", config=cfg)
    assert ep.success, ep.reason
    r = cfg.dwa.robot
    u = ep.controls
    v, w = u[:, 0], u[:, 1]
    period = cfg.dwa.period
    assert np.all((v >= r.v_min - 1e-5) & (v <= r.v_max + 1e-5)) and np.all(np.abs(w) <= r.omega_max + 1e-5)
    dv, dw = np.diff(np.concatenate([[0.0], v])), np.diff(np.concatenate([[0.0], w]))
    assert np.all(dv <= r.accel * period + 1e-4) and np.all(dv >= -r.decel * period - 1e-4)
    assert np.all(np.abs(dw) <= r.alpha * period + 1e-4)
    assert ep.collisions == 0 and ep.active_contacts == 0 and ep.passive_contacts == 0


def test_mppi_params_are_checked():
    with pytest.raises(ValueError, match="DWAParams but the local planner is 'mppi'"):
        jp.navigate(OPEN, (1, 4), (20, 4), global_planner="astar", local_planner="mppi", params=jp.DWAParams(
            *(np.float32(x) for x in (0.4, 0.3, 0.3, 0.0, 0.0, 0.05))))
    with pytest.raises(ValueError, match="unknown MPPI parameter"):
        jp.navigate(OPEN, (1, 4), (20, 4), global_planner="astar", local_planner="mppi", params={"heading": 1.0})
    assert {"iaco_mppi", "astar_kng_mppi"} <= set(jp.pipelines())


def test_a_contact_is_active_when_the_robot_moves_and_passive_at_rest():
    """Pure path following avoids nothing: driving into a parked disc is an active contact; standing (a robot too
    slow to count as moving) while a disc walks into it, a passive one."""
    cfg = NavConfig(stop_on_collision=False, replan=False, local="follow", max_time=20.0)
    parked = moving_obstacles([[[8.5, 4.5]]], speeds=0.0, radii=0.3)
    ep = jp.navigate(OPEN, (2, 4), (16, 4), global_planner="astar", config=cfg, obstacles=parked, time_limit=20.0)
    assert ep.active_contacts >= 1 and ep.passive_contacts == 0 and ep.collisions == ep.active_contacts

    slow = cfg.replace(dwa=cfg.dwa.replace(robot=Unicycle(v_max=0.04)))
    walker = moving_obstacles([[[14.5, 4.5], [1.5, 4.5]]], speeds=1.0, radii=0.25)
    ep = jp.navigate(OPEN, (5, 4), (20, 4), global_planner="astar", config=slow, obstacles=walker, time_limit=20.0)
    assert ep.passive_contacts >= 1 and ep.active_contacts == 0 and ep.collisions == ep.passive_contacts


def test_walkers_that_see_keep_apart_from_each_other_and_the_robot():
    """Two walkers meeting head-on in a 3 m wide hall, with a nearly standing robot on their line: with the social
    force model they pass each other and the robot; blind, the same routes overlap."""
    hall = jp.grid_from_array(np.pad(np.ones((3, 30), bool), ((1, 1), (0, 0))), resolution=1.0)
    routes = [[[2.5, 2.5], [27.5, 2.5]], [[27.5, 2.5], [2.5, 2.5]]]
    slow = NavConfig(stop_on_collision=False, replan=False, local="follow", max_time=30.0).replace(
        dwa=NavConfig().dwa.replace(robot=Unicycle(v_max=0.04)))
    gaps = {}
    for social in (False, True):
        obs = moving_obstacles(routes, speeds=1.0, radii=0.25, offsets=[0.0, 0.0], reactive=social or None)
        ep = jp.navigate(hall, (22, 2), (22, 1), global_planner="astar", config=slow, obstacles=obs, time_limit=30.0)
        op = ep.obstacle_positions  # [T + 1, 2, 2]
        walker_gap = np.hypot(*(op[:, 0] - op[:, 1]).T).min()
        robot_gap = np.hypot(*(op - ep.trajectory[:, None, :2]).transpose(2, 0, 1)).min()
        gaps[social] = (walker_gap, robot_gap, ep.collisions)
    walker_gap, robot_gap, contacts = gaps[True]
    assert walker_gap >= 0.5 - 0.03 and robot_gap >= 0.5 - 0.03 and contacts == 0, gaps
    assert gaps[False][0] < 0.4 and gaps[False][2] >= 1, gaps  # blind: they walk through each other and the robot


def test_random_walkers_behaviors():
    scene = jp.demo_warehouse()
    blind = jp.random_obstacles(scene, n=3, seed=4)
    social = jp.random_obstacles(scene, n=3, seed=4, behavior="social")
    assert blind.reactive is None and bool(np.all(np.asarray(social.reactive)))
    np.testing.assert_array_equal(np.asarray(blind.waypoints), np.asarray(social.waypoints))  # the same routes
    with pytest.raises(ValueError, match="walker behavior"):
        jp.random_obstacles(scene, n=3, seed=4, behavior="polite")


def test_a_navigation_batch_too_big_for_memory_is_refused_before_any_work(monkeypatch):
    monkeypatch.setenv("JAXPLAN_MEMORY_LIMIT", "200M")
    starts = np.tile([[1, 4]], (3000, 1))
    goals = np.tile([[20, 4]], (3000, 1))
    with pytest.raises(jp.scale.MemoryLimitError, match="robot episodes"):
        jp.navigate_batch(OPEN, starts, goals, global_planner="astar", seeds=range(2))


def test_mppi_weights_are_tunable_and_the_best_round_trips_into_a_run(tmp_path):
    """`jaxplan tune` on a kind = "mppi" config: a smoke run writes a best.toml whose [[planners]] entry an
    experiment config accepts (an MPPI pipeline with MPPI params)."""
    from pathlib import Path

    from jaxplan.experiments.config import parse_config
    from jaxplan.tune import run_tuning

    root = Path(__file__).resolve().parents[1]
    run = run_tuning(root / "configs" / "tune_mppi.toml", out=tmp_path, quick=True, progress=False)
    best = (run / "best.toml").read_text()
    assert 'name = "astar_kng_mppi"' in best and "temperature" in best
    cfg = parse_config('[experiment]\nname = "x"\nseeds = 1\n[[maps]]\nname = "m"\ngenerator = "warehouse"\n'
                       'params = { width = 14, height = 10 }\n[scenarios]\nsource = "random"\ncount = 1\n' + best)
    pc = cfg.planners[0]
    assert pc.name == "astar_kng_mppi" and "temperature" in pc.params and dict(pc.mppi) == {"samples": 96}


def test_an_mppi_config_with_dwa_weights_is_refused():
    from jaxplan.experiments.config import ConfigError, parse_config

    text = ('[experiment]\nname = "x"\nseeds = 1\n[[maps]]\nname = "m"\ngenerator = "warehouse"\n'
            'params = { width = 14, height = 10 }\n[scenarios]\nsource = "random"\ncount = 1\n'
            '[[planners]]\nkind = "navigate"\nname = "iaco_mppi"\nparams = { heading = 0.4 }\n'
            'obstacles = { n = 2, behavior = "social" }\n')
    with pytest.raises(ConfigError, match="unknown MPPI parameter"):
        parse_config(text)
    ok = parse_config(text.replace("heading = 0.4", "dynamic = 2.0"))
    assert ok.planners[0].obstacles.behavior == "social"


def test_a_robot_gives_way_to_a_walker_that_sees_in_a_bottleneck():
    """A robot and a walker that sees meet head-on in a 1 m wide bottleneck between two halls: each waits for the
    other until the time limit (the social force model stops the walker 0.4 m before the robot, and the robot finds
    every way forward through it), unless the robot gives way: then it backs out into the hall, the walker comes
    through, and the robot goes on and arrives."""
    free = np.zeros((7, 24), bool)
    free[1:6, 0:9] = free[1:6, 15:24] = True
    free[3, 9:15] = True
    grid = jp.grid_from_array(free, resolution=1.0)
    walker = moving_obstacles([[[22.5, 3.5], [0.5, 3.5]]], speeds=1.0, radii=0.25, reactive=True, offsets=[2.0])
    base = NavConfig(mppi=MPPIConfig(samples=128), max_time=60.0)
    runs = {}
    for give_way in (False, True):
        runs[give_way] = jp.navigate(grid, (2, 3), (22, 3), pipeline="astar_kng_mppi",
                                     config=base.replace(give_way=give_way), obstacles=walker, time_limit=60.0)
    assert runs[False].reason == "time limit" and runs[False].collisions == 0
    ep = runs[True]
    assert ep.success and ep.collisions == 0, (ep.reason, ep.collisions)
    op = ep.obstacle_positions[:, 0]
    assert np.any(op[:, 0] < ep.trajectory[:, 0] - 1.0)  # the walker came through to the robot's side
    assert np.hypot(*(op - ep.trajectory[:, :2]).T).min() >= 0.5 - 0.03  # and never touched it


def test_the_yield_point_steps_aside_or_backs_away():
    """In a 3 m hall a robot facing a walker steps to the side of the walker's line; in a 1 m corridor, where there
    is no side, it backs away from the walker along it. Either point has room to stand."""
    from jaxplan.dwa import clearance_table, static_clearance
    from jaxplan.grid import collision_map
    from jaxplan.nav._give_way import STAND_ROOM, yield_point

    d_safe = 0.3
    for rows, lateral in ((3, True), (1, False)):
        grid = jp.grid_from_array(np.pad(np.ones((rows, 16), bool), ((1, 1), (0, 0))), resolution=1.0)
        table = clearance_table(collision_map(grid))
        y = 1.0 + rows / 2
        pos, walker = np.array([8.0, y], np.float32), np.array([9.2, y], np.float32)
        point, found = yield_point(pos, walker, walker[None], np.array([0.25], np.float32),
                                   lambda x, yy, t=table: static_clearance(t, x, yy, "hybrid"), d_safe)
        point = np.asarray(point)
        assert bool(found)
        assert float(static_clearance(table, point[:1], point[1:])[0]) >= d_safe + STAND_ROOM - 1e-6
        if lateral:
            assert abs(point[1] - y) >= 0.5 and point[0] <= pos[0] + 0.2, point
        else:
            assert abs(point[1] - y) < 1e-3 and point[0] <= pos[0] - 1.5, point


def test_creep_distance_defaults_and_checks():
    assert NavConfig(local="mppi").creep_reach == 2.0
    assert NavConfig(local="dwa").creep_reach == np.inf and NavConfig().creep_reach == np.inf
    assert NavConfig(local="dwa", creep_distance=3.0).creep_reach == 3.0
    with pytest.raises(ValueError, match="creep_distance"):
        jp.navigate(OPEN, (1, 4), (20, 4), pipeline="astar_kng_mppi", config=NavConfig(creep_distance=-1.0))


@pytest.mark.slow
def test_a_creeping_mppi_robot_is_released_once_it_comes_closer(movingai):
    """Warehouse row 1 (seed 0): the robot stops 1 m short of a corner waypoint, turns towards the next one behind
    a shelf and stalls; held to the creep speed along its re-planned path's long first leg it arrives after about
    three minutes, released once 2 m closer to its goal in little more than the optimal time."""
    grid = jp.load_map(movingai / "warehouse-10-20-10-2-1.map", resolution=1.0)
    scen = jp.load_scenarios(movingai / "warehouse-10-20-10-2-1-random-1.scen", grid)
    row = int(np.nonzero(scen.optimal <= 80)[0][0])
    times = {}
    for reach in (None, np.inf):
        b = jp.navigate_batch(grid, scen.starts[row:row + 1], scen.goals[row:row + 1], pipeline="iaco_mppi",
                              seeds=[0], config=NavConfig(creep_distance=reach))
        assert b.success[0, 0, 0], b.reason[0, 0, 0]
        times[reach] = float(b.time_s[0, 0, 0])
    assert times[None] < 1.2 * scen.optimal[row] < 1.2 * 80 < times[np.inf], times
