"""Static episodes always arrive: a robot that stops progressing re-plans from where it stands, its new path
beginning at the centre of its cell when the straight way on does not keep d_safe (docs/guide/navigation.md)."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxplan as jp
from jaxplan.dwa import clearance_table, static_clearance
from jaxplan.grid._collision import collision_map
from jaxplan.nav import NavConfig
from jaxplan.nav._episode import run_episodes
from jaxplan.nav._front import prepare_episodes
from jaxplan.nav._state import REASONS
from jaxplan.nav._tracking import way_clear

_run = jax.jit(run_episodes, static_argnums=(0, 1))


def _two_rooms() -> jp.GridMap:
    """Two rooms joined by a door one cell wide at cell (4, 4); the goal room above (y 1-3), the robot's below."""
    free = np.zeros((10, 10), bool)
    free[1:4, 1:9] = True
    free[5:9, 1:9] = True
    free[4, 4] = True
    return jp.grid_from_array(free, resolution=1.0)


def test_the_way_to_a_paths_first_vertex_is_checked_end_to_end():
    grid = _two_rooms()
    table = clearance_table(collision_map(grid))
    clear = jax.jit(lambda a, b: way_clear(a, b, 0.3, lambda x, y: static_clearance(table, x, y, "hybrid"), whole=True))
    beside_the_door, goal = jnp.asarray([4.9, 5.29]), jnp.asarray([4.5, 2.5])
    assert not bool(clear(beside_the_door, goal))  # grazes the door's right jamb, 0.1 m from the robot's centre
    assert bool(clear(jnp.asarray([4.5, 5.5]), goal))  # from the cell's centre: through the door's middle
    # A corner farther than the first 3.2 m is seen too: a long leg is also checked at 64 points end to end.
    free = np.ones((3, 20), bool)
    free[0, :] = free[2, :] = False
    free[1, 12:] = False
    free[0, 12:] = True  # the corridor steps up one row at x = 12
    table = clearance_table(collision_map(jp.grid_from_array(free, resolution=1.0)))
    far = jax.jit(lambda a, b: way_clear(a, b, 0.3, lambda x, y: static_clearance(table, x, y, "hybrid"), whole=True))
    assert not bool(far(jnp.asarray([1.5, 1.5]), jnp.asarray([18.5, 0.5])))


@pytest.mark.parametrize("local", ["dwa", "mppi"])
def test_a_robot_stalled_beside_a_door_replans_via_its_cells_centre(local):
    # room-64-64-8, start (15, 52), goal (33, 6), seed 2 (the DWA): the robot came to a stop 0.4 m right of the
    # centre of the door before the goal, facing the goal. The straight way on grazed the door's jamb, so every
    # rollout but standing broke d_safe; each re-plan from its cell gave the same straight path (the cell is in
    # line with the door), and it stood from 146 s to the 180 s time limit (MPPI stood the same way here). Here
    # the same stance on a small map, the goal 2.8 m away beyond the door.
    grid = _two_rooms()
    p = prepare_episodes(grid, [[4, 5]], [[4, 2]], pipeline=f"astar_kng_{local}", config=NavConfig(max_time=30.0))
    x, y = 4.9, 5.29
    goal = np.array([4.5, 2.5], np.float32)
    start = np.array([x, y, math.atan2(goal[1] - y, goal[0] - x), 0.0, 0.0], np.float32)
    inputs = p.inputs._replace(start=jnp.broadcast_to(jnp.asarray(start), p.inputs.start.shape),
                               waypoints=jnp.broadcast_to(jnp.asarray(goal), p.inputs.waypoints.shape),
                               n_waypoints=jnp.ones_like(p.inputs.n_waypoints),
                               time_limit=jnp.full_like(p.inputs.time_limit, 30.0))
    out = _run(p.config, p.steps, p.table, jnp.asarray(p.free), p.params, inputs)
    assert REASONS[int(out.reason[0, 0])] == "goal" and int(out.collisions[0, 0]) == 0
    xy = np.asarray(out.states[0, : int(out.steps[0, 0]) + 1, 0, :2])
    # It stood until the stall watch fired (4 s), re-planned, went by its cell's centre and through the door.
    assert np.linalg.norm(xy[15] - xy[0]) < 0.05 and int(out.replans[0, 0]) >= 1
    assert np.linalg.norm(xy - [4.5, 5.5], axis=1).min() < 0.3
    assert np.abs(xy[xy[:, 1] < 5.0, 0] - 4.5).max() < 0.2  # through the door's middle


@pytest.mark.slow
@pytest.mark.parametrize("local", ["dwa", "mppi"])
def test_the_room_row_that_stood_at_a_door_arrives(movingai, local):
    grid = jp.load_map(movingai / "room-64-64-8.map", resolution=1.0)
    ep = jp.navigate(grid, (15, 52), (33, 6), global_planner="iaco", local_planner=local, seed=2)
    assert ep.success and ep.collisions == 0, ep.reason
