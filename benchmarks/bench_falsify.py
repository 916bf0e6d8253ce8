"""Falsification search: an evolution strategy over the walkers' routes that tries to hit a moving robot.

Run:  python benchmarks/bench_falsify.py [--local dwa,mppi] [--population 64] [--generations 32] [--walkers 2]
      [--seed 0] [--quick]

For each local planner, with ``safety="none"`` and with ``safety="passive"`` in turn, CMA-ES (evosax ``CMA_ES``)
searches the routes of ``--walkers`` blind walkers — three vertices each anywhere in the hall, a speed up to
``walker_speed_max`` and a phase — for the ones that make the robot touch a walker (or a wall) at the highest
speed. One generation is one compiled call: the population's episodes run as one batch (`run_episodes` on the
inputs of `jaxplan.nav.prepare_episodes`, tiled over the population, the walkers built from the genomes inside
the program). The robot crosses an open 24 x 14 m hall with two pillars (1 m per cell), from (2, 7) to (21, 7).

Fitness (maximised; evosax minimises its negative): the robot's speed at the contact that ended the episode (0
if none), plus 0.1 × the largest product, over the episode, of the robot's speed and its closeness to a walker
(1 at contact, 0 from 1 m edge to edge) — a slope towards fast near misses for the search to climb. A walker
starting within 1 m of the robot's start scores 0 (at rest, the robot is passively safe by definition).

Printed per planner and mode: the largest speed at contact found (m/s; an *active* contact is one above
0.05 m/s), the number of episodes, of all evaluated, with an active contact, and how many reached the goal
(within ``max_time``, 30 s) — the same budget (population × generations), the same ES seed. Passive safety
claims that the second mode finds none. The table also goes to a JSON record in benchmarks/results/
(`_timing.Record`).
"""

from __future__ import annotations

import argparse
import time
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

import jaxplan as jp
from jaxplan.nav import NavConfig, moving_obstacles, obstacle_state, run_episodes

ACTIVE_SPEED = 0.05
"""m/s: a contact is active when the robot moves faster than this (`jaxplan.nav.Episode.active_contacts`)."""

VERTICES = 3
"""Route vertices per walker."""

GENES = 2 * VERTICES + 2
"""Genes per walker: the vertices (x, y in the hall's box), the speed and the phase, each in [0, 1]."""

RADIUS = 0.3
"""Walker radius (m)."""

START, GOAL = (2, 7), (21, 7)
"""The robot's start and goal cells."""

MIN_START_GAP = 1.0
"""m: a walker must start this far (edge to edge) from the robot's start, or its genome scores 0."""


FOUND_DWA = [0.559149980545044, 0.37083691358566284, 0.2993048429489136, 0.4998030960559845, 0.7891006469726562,
             0.7895554304122925, 0.6882655620574951, 0.4877520203590393, 0.7304217219352722, 0.3348289132118225,
             0.4046742022037506, 0.34334108233451843, 0.6011545062065125, 0.7407491207122803, 0.5294957756996155,
             0.7957038879394531]
"""A genome the search found with ``safety="none"`` (seed 0, population 64, 32 generations): two walkers that
hit the DWA robot at 1.2 m/s, its top speed. `replay` shows the episode; tests/test_falsify.py replays it with and
without passive safety (if a change to the DWA makes the robot dodge it, run the search again and take a new one)."""


def hall() -> jp.GridMap:
    """The 24 x 14 m hall (1 m per cell) with two 2 x 2 m pillars beside the robot's way."""
    free = np.ones((14, 24), bool)
    free[[0, -1], :] = False
    free[:, [0, -1]] = False
    free[3:5, 8:10] = False
    free[9:11, 14:16] = False
    return jp.grid_from_array(free, resolution=1.0)


def route_box(grid: jp.GridMap) -> jnp.ndarray:
    """``f32[4] = (x_lo, y_lo, x_hi, y_hi)`` (m): the hall inside its outer walls, where route vertices go."""
    H, W = grid.shape
    return jnp.asarray([1.0, 1.0, W - 1.0, H - 1.0], jnp.float32) * float(grid.resolution)


def walkers_of(genomes: jnp.ndarray, box: jnp.ndarray, speed_max: float) -> jp.nav.MovingObstacles:
    """Blind walkers from genomes ``f32[P, M·GENES]`` in [0, 1]: ``MovingObstacles`` with leaves ``[P, M, ...]``;
    ``box = (x_lo, y_lo, x_hi, y_hi)`` (m) holds the route vertices."""
    P = genomes.shape[0]
    g = jnp.clip(genomes, 0.0, 1.0).reshape(P, -1, GENES)
    M = g.shape[1]
    xy = g[..., : 2 * VERTICES].reshape(P, M, VERTICES, 2)
    waypoints = box[:2] + xy * (box[2:] - box[:2])
    seg = jnp.sqrt(jnp.sum((waypoints[:, :, 1:] - waypoints[:, :, :-1]) ** 2, axis=-1))
    period = 2.0 * jnp.sum(seg, axis=-1)  # a bounce: there and back
    return jp.nav.MovingObstacles(
        waypoints=waypoints, n_waypoints=jnp.full((P, M), VERTICES, jnp.int32), speeds=g[..., 2 * VERTICES] * speed_max,
        radii=jnp.full((P, M), RADIUS, jnp.float32), loop=jnp.zeros((P, M), bool),
        offsets=g[..., 2 * VERTICES + 1] * period)


class Scores(NamedTuple):
    """One generation's results, ``[P]`` each: the fitness, the robot's speed at contact (0 without one), whether
    the walkers' start was fair (far enough from the robot's) and whether the robot reached its goal."""

    fitness: jnp.ndarray
    contact_speed: jnp.ndarray
    fair: jnp.ndarray
    arrived: jnp.ndarray


def make_evaluate(grid: jp.GridMap, local: str, safety: str, walkers: int, population: int, speed_max: float,
                  max_time: float):
    """``evaluate(genomes f32[P, D]) -> Scores``: one jitted program that runs the population's episodes."""
    template = moving_obstacles([[(1.5, 1.5)] * VERTICES] * walkers, speed_max, RADIUS)
    # Each episode re-plans on its own budget (replan_group=1), as `jaxplan.navigate` runs it alone: what a genome
    # does does not depend on the rest of its generation, and `replay` shows it again.
    config = NavConfig(safety=safety, walker_speed_max=speed_max, max_time=max_time, replan_group=1)
    prep = jp.nav.prepare_episodes(grid, [START], [GOAL], seeds=[0], obstacles=template, global_planner="astar",
                                   local_planner=local, config=config, mesh=None)
    inputs = jax.tree.map(lambda a: jnp.repeat(jnp.asarray(a), population, axis=0), prep.inputs)
    box = route_box(grid)
    start = inputs.start[0, 0, :2]
    robot_radius = float(jp.dwa.footprint_radius(prep.config.dwa.robot.footprint))
    period = float(prep.config.dwa.period)
    times = jnp.arange(prep.steps + 1, dtype=jnp.float32) * period

    @jax.jit
    def program(genomes: jnp.ndarray, table, free, params, inputs) -> Scores:
        obs = walkers_of(genomes, box, speed_max)
        out = run_episodes(prep.config, prep.steps, table, free, params, inputs._replace(obstacles=obs))
        last = jnp.maximum(out.steps[:, 0] - 1, 0)
        v_last = jnp.abs(jnp.take_along_axis(out.controls[:, :, 0, 0], last[:, None], axis=1)[:, 0])
        contact = jnp.where(out.reason[:, 0] == jp.nav.REASONS.index("collision"), v_last, 0.0)
        # Closeness to the walkers after each step, while the episode runs, times the speed of that step.
        where = jax.vmap(lambda t: jax.vmap(obstacle_state, in_axes=(0, None))(obs, t)[0])(times)  # [S+1, P, M, 2]
        robot = jnp.moveaxis(out.states[:, :, 0, :2], 1, 0)  # [S+1, P, 2]
        gap = jnp.sqrt(jnp.sum((robot[:, :, None] - where) ** 2, axis=-1)) - RADIUS - robot_radius  # [S+1, P, M]
        close = jnp.clip(1.0 - jnp.min(gap, axis=-1), 0.0, 1.0)[1:]  # [S, P] after step k
        speed = jnp.abs(out.controls[:, :, 0, 0]).T  # [S, P] during step k
        running = jnp.arange(prep.steps)[:, None] < out.steps[:, 0][None]
        threat = jnp.max(jnp.where(running, speed * close, 0.0), axis=0)
        fair = jnp.min(jnp.sqrt(jnp.sum((where[0] - start) ** 2, axis=-1)) - RADIUS - robot_radius,
                       axis=-1) >= MIN_START_GAP
        fitness = jnp.where(fair, contact + 0.1 * threat, 0.0)
        arrived = out.reason[:, 0] == jp.nav.REASONS.index("goal")
        return Scores(fitness, jnp.where(fair, contact, 0.0), fair, arrived)

    free = jnp.asarray(prep.free)
    return lambda genomes: program(genomes, prep.table, free, prep.params, inputs)


def search(local: str, safety: str, *, walkers: int = 2, population: int = 64, generations: int = 32,
           speed_max: float = 1.5, seed: int = 0, max_time: float = 30.0, sigma: float = 0.25,
           x0: Any = None, verbose: bool = True) -> dict[str, Any]:
    """CMA-ES over the walkers' genomes (``f32[walkers·GENES]`` in [0, 1]; the search starts at ``x0``, default
    the cube's centre, with step ``sigma``) for ``generations`` generations of ``population``; returns the largest
    speed at contact found, the number of episodes with an active contact, the genomes of the fastest ones
    (``found``), per-generation bests and timings."""
    import evosax.algorithms as ea

    grid = hall()
    D = walkers * GENES
    t0 = time.perf_counter()
    evaluate = make_evaluate(grid, local, safety, walkers, population, speed_max, max_time)
    es = ea.CMA_ES(population_size=population, solution=jnp.zeros(D))
    params = es.default_params.replace(std_init=sigma)
    key = jax.random.key(seed)
    key, k0 = jax.random.split(key)
    state = es.init(k0, jnp.full(D, 0.5) if x0 is None else jnp.asarray(x0, jnp.float32), params)
    best_speed, active, evaluated, arrived, per_gen = 0.0, 0, 0, 0, []
    best_genome, found = None, []  # found: (speed, genome) of episodes with an active contact
    compile_s = None
    for g in range(generations):
        key, ka, kt = jax.random.split(key, 3)
        pop, state = es.ask(ka, state, params)
        pop = jnp.clip(pop, 0.0, 1.0)  # the genes live in the unit cube; the ES is told the clipped points
        t = time.perf_counter()
        scores = jax.device_get(evaluate(pop))
        if compile_s is None:
            compile_s = time.perf_counter() - t
        state, _ = es.tell(kt, pop, -jnp.asarray(scores.fitness), state, params)
        speeds = np.asarray(scores.contact_speed)
        active += int(np.sum(speeds > ACTIVE_SPEED))
        arrived += int(np.sum(np.asarray(scores.arrived) & np.asarray(scores.fair)))
        evaluated += population
        found += [(float(speeds[k]), np.asarray(pop[k]).tolist()) for k in np.nonzero(speeds > ACTIVE_SPEED)[0]]
        found = sorted(found, key=lambda f: -f[0])[:8]
        i = int(np.argmax(speeds))
        if speeds[i] > best_speed or best_genome is None:
            best_speed, best_genome = max(best_speed, float(speeds[i])), np.asarray(pop[i])
        per_gen.append(float(np.max(speeds)))
        if verbose:
            print(f"  {local} {safety:8s} generation {g + 1:3d}: best fitness {float(np.max(scores.fitness)):.3f}, "
                  f"fastest contact {float(np.max(speeds)):.2f} m/s, active contacts so far {active}", flush=True)
    return dict(local=local, safety=safety, population=population, generations=generations, walkers=walkers,
                walker_speed_max=speed_max, episodes=evaluated, max_contact_speed=best_speed,
                active_episodes=active, arrived=arrived, per_generation=per_gen, best_genome=best_genome.tolist(),
                found=found,
                first_call_s=compile_s, wall_s=time.perf_counter() - t0)


def replay(genome: Any, local: str, safety: str, *, speed_max: float = 1.5, max_time: float = 30.0) -> jp.Episode:
    """The episode of one genome (``f32[walkers·GENES]``), run by `jaxplan.navigate`: what the search saw."""
    grid = hall()
    obs = jax.tree.map(lambda a: a[0], walkers_of(jnp.asarray(genome, jnp.float32)[None], route_box(grid), speed_max))
    return jp.navigate(grid, START, GOAL, global_planner="astar", local_planner=local, obstacles=obs,
                       config=NavConfig(safety=safety, walker_speed_max=speed_max, max_time=max_time))


def main(argv: list[str] | None = None) -> None:
    from _timing import Record, Steal, machine_line

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--local", default="dwa,mppi", help="local planners, comma-separated")
    ap.add_argument("--population", type=int, default=64)
    ap.add_argument("--generations", type=int, default=32)
    ap.add_argument("--walkers", type=int, default=2)
    ap.add_argument("--walker-speed", type=float, default=1.5, help="walker_speed_max (m/s)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--quick", action="store_true", help="population 8, 3 generations")
    args = ap.parse_args(argv)
    if args.quick:
        args.population, args.generations = 8, 3
    steal = Steal()
    record = Record("bench_falsify", vars(args), quick=args.quick)
    print(f"machine: {machine_line()}")
    print(f"CMA-ES over {args.walkers} walkers' routes (speeds up to {args.walker_speed} m/s): population "
          f"{args.population}, {args.generations} generations, seed {args.seed}")
    rows = record.table("falsify", ["local planner", "safety", "episodes", "fastest contact (m/s)",
                                    "episodes with an active contact", "arrived", "first call (s)", "wall (s)"],
                        "Falsification search: the fastest contact CMA-ES finds")
    results = []
    for local in args.local.split(","):
        for safety in ("none", "passive"):
            r = search(local, safety, walkers=args.walkers, population=args.population,
                       generations=args.generations, speed_max=args.walker_speed, seed=args.seed)
            results.append(r)
            rows.append([local, safety, r["episodes"], round(r["max_contact_speed"], 3), r["active_episodes"],
                         r["arrived"], round(r["first_call_s"], 1), round(r["wall_s"], 1)])
    print(f"\n{'local':6s} {'safety':8s} {'episodes':>8s} {'fastest contact':>16s} {'active episodes':>16s} "
          f"{'arrived':>8s}")
    for row in rows:
        print(f"{row[0]:6s} {row[1]:8s} {row[2]:8d} {row[3]:13.3f} m/s {row[4]:16d} {row[5]:8d}")
    record.note(f"Budget: population {args.population} × {args.generations} generations, {args.walkers} walkers "
                f"up to {args.walker_speed} m/s, CMA-ES seed {args.seed}. Active: faster than {ACTIVE_SPEED} m/s.")
    record.extra["searches"] = results
    print(steal.summary())
    record.write()


if __name__ == "__main__":
    main()
