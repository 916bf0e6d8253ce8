"""benchmarks/bench_mppi.py at tiny sizes: the problem's map and cost, the checks, the timing and the table."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from conftest import load_benchmark


@pytest.fixture(scope="module")
def bench():
    return load_benchmark("bench_mppi")


def test_map_has_the_papers_obstacles(bench):
    table = bench.paper_table()
    xs = jnp.asarray([x + s / 2 for x, _, s in bench.OBSTACLES], jnp.float32)
    ys = jnp.asarray([y + s / 2 for _, y, s in bench.OBSTACLES], jnp.float32)
    assert np.all(np.asarray(bench.static_clearance(table, xs, ys, "bilinear")) == 0.0)
    # The start is 4.2 m from the nearest obstacle corner (4, 6) and about 1 m from the map's edge.
    c = float(bench.static_clearance(table, jnp.float32(1.0), jnp.float32(1.0), "bilinear"))
    assert 0.9 <= c <= 1.2


def test_point_cost_charges_goal_distance_and_obstacle_margin(bench):
    table = bench.paper_table()
    far = float(bench.point_cost(table, jnp.float32(1.0), jnp.float32(1.0)))
    assert far == pytest.approx(5.0 * math.hypot(9.0, 9.0), rel=1e-5)  # no obstacle within 0.1 m
    x, y = jnp.float32(8.2), jnp.float32(8.0 - 0.05)  # 5 cm below the obstacle at (8, 8)
    near = float(bench.point_cost(table, x, y))
    goal_part = 5.0 * math.hypot(10.0 - 8.2, 10.0 - 7.95)
    assert near - goal_part == pytest.approx(20.0 * 0.05, abs=0.15)


def test_jaxplan_weights_reproduce_the_problems_cost(bench):
    """jaxplan's own cost of its sampled sequences equals the cost jax_mppi is given, and its first step turns
    towards the goal and lowers the cost (the checks, at K = 64, without jax_mppi)."""
    c = bench.checks(None, samples=64, loop_steps=10)
    assert c["cost"]["ok"], c["cost"]
    assert c["cost"]["spread"] > 10.0  # the sequences differ: the comparison has something to compare
    assert c["first"]["ok"], c["first"]
    assert c["loop"]["jaxplan_distance"] < c["loop"]["start_distance"]
    rows = bench.check_rows(c)  # the record's table: one cell per column, the verdicts as booleans
    assert all(len(r) == 5 for r in rows) and rows[0][-1] is True and rows[1][-1] is True


def test_quoted_table_is_rectangular_and_says_quoted(bench):
    columns, rows = bench.quoted_rows()
    assert "quoted" in columns[0] and all(len(r) == len(columns) for r in rows)
    nav2 = next(r for r in rows if r[0].startswith("Nav2") and "13900K" in r[0])
    assert nav2[columns.index("K = 2,048")] == 6.742  # the published table's ROS 2 figure at 2,048 samples


def test_time_programs_and_table(bench):
    def bad(x):
        raise ValueError("no")

    rows = bench.time_programs([(lambda x: x * 2.0, (jnp.ones(4),)), (bad, (jnp.ones(4),)),
                                (lambda x: x + 1.0, (jnp.ones(4),))], repeats=3, budget_s=0.0, max_repeats=3)
    for row in (rows[0], rows[2]):
        assert row["n"] == 3 and len(row["runs_ms"]) == 3
        assert row["ms_min"] <= row["ms"] <= row["ms_max"] and row["compile_s"] > 0
    assert rows[1]["error"].startswith("ValueError") and "ms" not in rows[1]
    results = [dict(impl="jaxplan", samples=128, robots=1, ms=2.0), dict(impl="jax_mppi", samples=128, robots=1,
                                                                          ms=3.0),
               dict(impl="jaxplan", samples=128, robots=4, error="OOM")]
    rows = bench.speed_rows(results, 4)
    assert rows == [[128, 2.0, 3.0, 1.5, None, None, None]]
    assert "| 128 | 2.00 | 3.00 | 1.50 | — | — | — |" in bench.markdown(bench.speed_columns(4, "vmap"), rows)


def test_jaxplan_program_batches_robots_alike_under_vmap_and_map(bench):
    table = bench.paper_table()
    states = bench.start_states(3)
    assert np.all(states[0] == np.asarray(bench.START, np.float32))
    args = bench.jaxplan_args(table, states, 3)
    u, mean = jax.jit(bench.jaxplan_program(16, 3, "vmap"))(*args)
    assert u.shape == (3, 2) and mean.shape == (3, bench.STEPS, 2)
    assert np.all(np.asarray(u[:, 0]) >= bench.V_MIN - 1e-6) and np.all(np.asarray(u[:, 0]) <= bench.V_MAX + 1e-6)
    assert np.all(np.abs(np.asarray(u[:, 1])) <= bench.OMEGA_MAX + 1e-6)
    u_map, mean_map = jax.jit(bench.jaxplan_program(16, 3, "map"))(*args)
    np.testing.assert_allclose(np.asarray(u_map), np.asarray(u), atol=1e-4)
    np.testing.assert_allclose(np.asarray(mean_map), np.asarray(mean), atol=1e-4)


def test_jax_mppi_runs_the_same_problem(bench):
    jm = pytest.importorskip("jax_mppi")
    table = bench.paper_table()
    states = bench.start_states(2)
    fn, args = bench.jax_mppi_setup(jm, 16, states, 2, table)
    u, state = jax.jit(fn)(*args)
    assert u.shape == (2, 2) and state.U.shape == (2, bench.STEPS, 2)
    assert np.all(np.asarray(u[:, 0]) <= bench.V_MAX + 1e-6) and np.all(np.abs(np.asarray(u[:, 1])) <= 0.5 + 1e-6)
