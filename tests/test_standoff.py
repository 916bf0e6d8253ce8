"""Standoffs: a robot and a walker that sees it, facing each other in a corridor two cells wide, get past each
other without contact and the robot arrives, whichever side of the corridor the walker keeps to — for both local
planners."""

from __future__ import annotations

import numpy as np
import pytest

import jaxplan as jp
from jaxplan.nav import NavConfig, moving_obstacles

LENGTH = 16  # cells of 1 m; the corridor is rows 3-4, y in [3, 5] m


@pytest.fixture(scope="module")
def corridor() -> jp.GridMap:
    free = np.zeros((8, LENGTH), bool)
    free[3:5, :] = True
    return jp.grid_from_array(free, resolution=1.0)


@pytest.mark.parametrize("local", ["dwa", "mppi"])
@pytest.mark.parametrize("lane", [3.5, 4.0, 4.5])
def test_a_robot_and_a_walker_facing_each_other_in_a_corridor_pass(corridor, local, lane):
    # The walker starts 2 m along a route down the corridor's length (x 15.5 -> 0.5) in the lane `lane` (m):
    # the robot's own lane (3.5), the middle, or the other lane; it sees the robot (social force) but keeps to
    # its route, so someone must give way in a corridor where two fit side by side only just.
    walker = moving_obstacles([[[LENGTH - 0.5, lane], [0.5, lane]]], speeds=1.0, radii=0.25, reactive=True,
                              offsets=[2.0])
    ep = jp.navigate(corridor, (1, 3), (LENGTH - 2, 3), pipeline=f"astar_kng_{local}", obstacles=walker,
                     config=NavConfig(max_time=40.0), time_limit=40.0)
    assert ep.success and ep.reason == "goal" and ep.collisions == 0, ep.reason
    robot, other = ep.trajectory[:, :2], ep.obstacle_positions[:, 0]
    n = min(len(robot), len(other))
    gap = np.hypot(*(other[:n] - robot[:n]).T)
    assert gap.min() > 0.25 + 0.25  # the robot's disc and the walker's never overlapped
    # They swapped ends: the walker began ahead of the robot and was behind it at some point.
    assert other[0, 0] > robot[0, 0] and np.any(other[:n, 0] < robot[:n, 0] - 0.5)


# maze-32-32-2 scenario rows where `iaco_dwa` with passive safety at its guaranteed bound (the walkers' route speed
# × 1.3 = 1.3 m/s) ran out of time among 5 walkers that see, most in a standoff: a walker standing within the
# robot's reach freezes a passively safe robot, and the walker waits for the robot (bench_nav's 100-episode batch,
# its walkers for each row). In this 28-episode batch (both seeds of each row) the guaranteed bound times out on
# 12 episodes (measured, not asserted).
STOOD_PASSIVE = [0, 22, 37, 52, 84, 116, 130, 151, 156, 176, 192, 231, 298, 325]


@pytest.mark.slow
def test_passive_dwa_at_a_stated_walker_bound_gets_through_the_maze_standoffs(movingai):
    # At a bound of 0.8 m/s the robot may move away from a walker standing close (in one period that walker can
    # reach less far than the robot moves), so both get on; the walkers that see close in on a robot near them far
    # slower than they walk, so no active contact follows — measured here, not guaranteed (docs/decisions.md).
    grid = jp.load_map(movingai / "maze-32-32-2.map", resolution=1.0)
    scen = jp.load_scenarios(movingai / "maze-32-32-2-random-1.scen")
    ok = np.nonzero(scen.optimal <= 80.0)[0]
    sel = ok[np.unique(np.linspace(0, len(ok) - 1, 50).round().astype(int))]  # bench_nav's 50 rows
    rows = np.asarray(STOOD_PASSIVE)
    S, G = scen.starts[rows], scen.goals[rows]

    def walkers(i: int, seed: int):  # bench_nav's walkers for row rows[i]: seeded by its place among the 50
        e = int(np.nonzero(sel == rows[i])[0][0])
        avoid = (np.stack([S[i], G[i]]) + 0.5) * grid.resolution
        return jp.random_obstacles(grid, n=5, speed=1.0, radius=0.25, seed=10_000 * seed + e, avoid=avoid,
                                   avoid_radius=3.0, behavior="social")

    b = jp.navigate_batch(grid, S, G, pipeline="iaco_dwa", seeds=[0, 1], obstacles=walkers,
                          config=NavConfig(safety="passive", walker_speed_max=0.8))
    assert b.feasible.all()
    failed = np.nonzero(~b.success[..., 0])
    assert b.success.all(), {(int(rows[e]), s): str(b.reason[e, s, 0]) for e, s in zip(*failed, strict=True)}
    assert int(b.active_contacts.sum()) == 0
