"""Walkers that see and lose sight of their route go back the way they came instead of standing against a wall.

The social force model steers a walker straight at its route's next vertex; pushed off its route behind a wall,
it used to stand against that wall for good (a local minimum of the model, in up to 11 % of 180 s episodes on the
MovingAI maps). These tests pin the trail that takes it back: a walker placed behind a wall, and the maze
episodes whose walkers stood still."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxplan as jp
from jaxplan.dwa._clearance import clearance_table, static_clearance
from jaxplan.grid._collision import collision_map
from jaxplan.nav import moving_obstacles
from jaxplan.nav._moving import obstacle_state, route_target
from jaxplan.nav._social import TRAIL, VERTEX_RADIUS, SocialForce, advance_walkers, initial_walkers

FAR = jnp.full((1, 2), -100.0)  # no robot near: the walkers alone


def _simulate(grid: jp.GridMap, obs, state, periods: int) -> np.ndarray:
    """Positions ``[..., periods, M, 2]`` of the walkers ``obs`` from ``state`` (leading batch axes on both, or
    none), period 0.2 s, no robot."""
    table = clearance_table(collision_map(grid))

    def wall(x, y):
        return static_clearance(table, x, y, "hybrid")

    def run(o, s0):
        def step(w, _):
            w, _ = advance_walkers(SocialForce(), w, o.waypoints, o.n_waypoints, o.speeds, o.radii, o.loop,
                                   o.reactive, FAR, jnp.zeros((1, 2)), 0.3, wall, 0.2)
            return w, w.pos

        return jax.lax.scan(step, s0, None, length=periods)[1]

    for _ in range(obs.radii.ndim - 1):
        run = jax.vmap(run)
    return np.asarray(jax.jit(run)(obs, state))


def _start(obs):
    pos, vel = obstacle_state(obs, 0.0)
    target, forward = route_target(obs, 0.0)
    return initial_walkers(pos, vel, target, forward)


@pytest.fixture(scope="module")
def two_corridors() -> jp.GridMap:
    # Corridor A (row 1) and corridor B (row 3), 1 m wide, joined at x = 1 only.
    free = np.zeros((5, 10), bool)
    free[1, 1:9] = free[3, 1:9] = free[2, 1] = True
    return jp.grid_from_array(free, resolution=1.0)


def test_a_walker_behind_a_wall_goes_back_to_where_it_took_up_its_vertex(two_corridors):
    # Route along corridor A; the walker heads for its far end but stands in corridor B below it, where the
    # straight way up meets the wall. It took the vertex up at the route's start (its trail's one breadcrumb).
    obs = moving_obstacles([[[1.5, 1.5], [8.5, 1.5]]], speeds=1.0, radii=0.25, reactive=True)
    s = _start(obs)
    s = s._replace(pos=jnp.asarray([[6.5, 3.5]]), vel=jnp.zeros((1, 2)), target=jnp.asarray([1], jnp.int32),
                   step=jnp.asarray([1], jnp.int32), trail=jnp.broadcast_to(jnp.asarray([1.5, 1.5]), (1, TRAIL, 2)),
                   depth=jnp.asarray([1], jnp.int32))
    path = _simulate(two_corridors, obs, s, periods=150)[:, 0]  # 30 s
    cells = np.floor(path).astype(int)
    assert np.asarray(two_corridors.free)[cells[:, 1], cells[:, 0]].all()  # never inside a wall
    assert path[:, 1].min() < 2.0  # through the gap into corridor A
    assert np.hypot(*(path - [8.5, 1.5]).T).min() < VERTEX_RADIUS + 0.1  # and on to the vertex it was after


# maze-32-32-2 walkers that stood against a wall until the end of a 180 s episode before the trail: bench_nav's
# set-up (5 walkers at 1.0 m/s, radius 0.25 m, kept 3 m from the scenario's start and goal), (scenario row, seed).
STOOD = [(156, 0), (199, 0), (319, 0), (0, 1), (151, 1), (224, 1)]


def test_maze_walkers_that_stood_against_a_wall_keep_walking(movingai):
    grid = jp.load_map(movingai / "maze-32-32-2.map", resolution=1.0)
    scen = jp.load_scenarios(movingai / "maze-32-32-2-random-1.scen")
    ok = np.nonzero(scen.optimal <= 80.0)[0]
    sel = ok[np.unique(np.linspace(0, len(ok) - 1, 50).round().astype(int))]
    sets = []
    for row, seed in STOOD:
        e = int(np.nonzero(sel == row)[0][0])
        avoid = (np.stack([scen.starts[row], scen.goals[row]]) + 0.5) * grid.resolution
        sets.append(jp.random_obstacles(grid, n=5, speed=1.0, radius=0.25, seed=10_000 * seed + e, avoid=avoid,
                                        avoid_radius=3.0, behavior="social"))
    K = max(o.waypoints.shape[1] for o in sets)  # one program: routes padded with their last vertex
    sets = [o._replace(waypoints=jnp.concatenate(
        [o.waypoints, jnp.repeat(o.waypoints[:, -1:], K - o.waypoints.shape[1], axis=1)], axis=1)) for o in sets]
    obs = jax.tree_util.tree_map(lambda *x: jnp.stack(x), *sets)
    path = _simulate(grid, obs, jax.vmap(_start)(obs), periods=900)  # [6, 900, 5, 2]: 180 s
    # Metres walked over the last 50 s [6, 5]: a walker standing against a wall (or jittering in place) walks none.
    walked = np.linalg.norm(np.diff(path[:, -250:], axis=1), axis=-1).sum(axis=1)
    assert (walked > 10.0).all(), {STOOD[i]: walked[i].round(1).tolist() for i in range(len(STOOD))}


def test_a_new_trail_starts_at_the_vertex_just_reached(two_corridors):
    # 0.2 m short of its vertex (8.5, 1.5), the walker moves on to the next (back to 1.5, 1.5: a bounce) within the
    # period; its new trail is the vertex itself (in sight of the next one), not the spot where it stood.
    obs = moving_obstacles([[[1.5, 1.5], [8.5, 1.5]]], speeds=1.0, radii=0.25, reactive=True)
    s = _start(obs)._replace(pos=jnp.asarray([[8.3, 1.5]]), vel=jnp.asarray([[1.0, 0.0]]),
                             target=jnp.asarray([1], jnp.int32), step=jnp.asarray([1], jnp.int32))
    table = clearance_table(collision_map(two_corridors))
    new, _ = advance_walkers(SocialForce(), s, obs.waypoints, obs.n_waypoints, obs.speeds, obs.radii, obs.loop,
                             obs.reactive, FAR, jnp.zeros((1, 2)), 0.3,
                             lambda x, y: static_clearance(table, x, y, "hybrid"), 0.2)
    assert int(new.target[0]) == 0 and int(new.depth[0]) == 1
    np.testing.assert_allclose(np.asarray(new.trail[0, 0]), [8.5, 1.5])
