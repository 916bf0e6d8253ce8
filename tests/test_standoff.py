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
