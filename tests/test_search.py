"""Exact planners: published optimal lengths, path validity, independence from scipy, bad input."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from conftest import scenario_pairs
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.sparse.csgraph import dijkstra as scipy_dijkstra

import jaxplan as jp

DRAGON_AGE = {"brc202d": 2519, "den520d": 888, "ost003d": 846}
"""cui2025's three Dragon Age maps in the manifest -> rows of their .scen files (the other pairs are the small
MAPF maps)."""


def _check_scenarios(m, sc) -> int:
    """Checks every row's published optimum against `shortest_lengths`; returns the number of rows."""
    g = jp.load_map(m)
    s = jp.load_scenarios(sc, grid=g)
    got = jp.shortest_lengths(g, s.starts, s.goals)
    np.testing.assert_allclose(got, s.optimal, rtol=1e-4, err_msg=f"{sc.name}")
    return len(s)


def test_every_scenario_row_of_the_small_maps(movingai):
    pairs = scenario_pairs(movingai)
    assert sorted(m.stem for m, _ in pairs if m.stem in DRAGON_AGE) == sorted(DRAGON_AGE)
    small = [p for p in pairs if p[0].stem not in DRAGON_AGE]
    assert len(small) == 5
    for m, sc in small:
        _check_scenarios(m, sc)


@pytest.mark.parametrize("name", sorted(DRAGON_AGE))
def test_every_scenario_row_of_the_dragon_age_maps(movingai, name):
    """All rows of each of cui2025's maps (brc202d about 10 s on 2 cores, den520d and ost003d under 1 s each)."""
    assert _check_scenarios(movingai / f"{name}.map", movingai / f"{name}.map.scen") == DRAGON_AGE[name]


def _assert_valid_path(g: jp.GridMap, res: jp.PlanResult, start, goal, k: int) -> None:
    p = res.path
    assert tuple(p[0]) == tuple(start) and tuple(p[-1]) == tuple(goal)
    assert g.free[p[:, 1], p[:, 0]].all(), "path enters a blocked cell"
    table = jp.neighbour_table(g, k)
    moves = {tuple(o): j for j, o in enumerate(table.offsets)}
    W = g.width
    for a, b in zip(p[:-1], p[1:], strict=True):
        d = tuple((b - a).tolist())
        assert d in moves, f"step {d} is not a {k}-connected move"
        assert table.valid[a[1] * W + a[0], moves[d]], f"step {tuple(a)}->{tuple(b)} cuts a corner"
    np.testing.assert_allclose(jp.search.path_cost(p, g.resolution), res.length, rtol=1e-9)


def test_astar_paths_on_scenarios_are_valid_and_optimal(movingai):
    for m, sc in scenario_pairs(movingai):
        g = jp.load_map(m)
        s = jp.load_scenarios(sc)
        for i in np.linspace(0, len(s) - 1, 12).astype(int):
            r = jp.astar(g, s.starts[i], s.goals[i])
            assert r.success
            np.testing.assert_allclose(r.length, s.optimal[i], rtol=1e-4)
            _assert_valid_path(g, r, s.starts[i], s.goals[i], 8)


def _scipy_reference(free: np.ndarray, k: int, res: float) -> sp.csr_array:
    """The move graph built independently from the hand-written corner rules."""
    H, W = free.shape
    moves = [(1, 0), (0, 1), (-1, 0), (0, -1)]
    if k >= 8:
        moves += [(1, 1), (1, -1), (-1, 1), (-1, -1)]
    if k == 16:
        moves += [(a * sx, b * sy) for a, b in ((1, 2), (2, 1)) for sx in (1, -1) for sy in (1, -1)]
    rows, cols, w = [], [], []
    inside = lambda x, y: 0 <= x < W and 0 <= y < H and free[y, x]  # noqa: E731
    for y in range(H):
        for x in range(W):
            if not free[y, x]:
                continue
            for dx, dy in moves:
                sx, sy = int(np.sign(dx)), int(np.sign(dy))
                need = [(x + dx, y + dy)]
                if abs(dx) == 1 and abs(dy) == 1:
                    need += [(x + sx, y), (x, y + sy)]
                elif abs(dy) == 2:
                    need += [(x, y + sy), (x + sx, y + sy)]
                elif abs(dx) == 2:
                    need += [(x + sx, y), (x + sx, y + sy)]
                if all(inside(*c) for c in need):
                    rows.append(y * W + x)
                    cols.append((y + dy) * W + x + dx)
                    w.append(np.hypot(dx, dy) * res)
    return sp.csr_array((w, (rows, cols)), shape=(H * W, H * W))


maps = arrays(bool, st.tuples(st.integers(2, 10), st.integers(2, 10)), elements=st.booleans())


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(maps, st.sampled_from([4, 8, 16]), st.sampled_from([1.0, 0.25]), st.data())
def test_property_paths_valid_and_lengths_exact(free, k, res, data):
    cells = np.argwhere(free)[:, ::-1]
    if len(cells) < 2:
        return
    i, j = data.draw(st.lists(st.integers(0, len(cells) - 1), min_size=2, max_size=2, unique=True))
    start, goal = cells[i], cells[j]
    g = jp.grid_from_array(free, resolution=res)
    ref = scipy_dijkstra(_scipy_reference(free, k, res), indices=start[1] * free.shape[1] + start[0])
    expected = ref[goal[1] * free.shape[1] + goal[0]]
    a = jp.plan(g, start, goal, planner="astar", connectivity=k)
    d = jp.plan(g, start, goal, planner="dijkstra", connectivity=k)
    batch = jp.shortest_lengths(g, [start, goal], [goal, start], connectivity=k)
    if np.isinf(expected):
        assert not a.success and not d.success and np.isinf(a.length) and a.path.shape == (0, 2)
        assert np.isinf(batch).all()
        return
    assert a.success and d.success
    np.testing.assert_allclose([a.length, d.length, *batch], expected, rtol=1e-9)
    _assert_valid_path(g, a, start, goal, k)
    _assert_valid_path(g, d, start, goal, k)


def test_unreachable_goal_is_a_result_not_an_error():
    free = np.ones((5, 5), bool)
    free[:, 2] = False
    g = jp.grid_from_array(free)
    r = jp.plan(g, (0, 0), (4, 4))
    assert not r.success and r.length == float("inf") and r.cost == float("inf") and len(r.path) == 0
    assert np.isinf(jp.shortest_lengths(g, [[0, 0]], [[4, 4]])).all()


def test_vehicle_height_changes_the_route():
    scene = jp.MountainGenerator()(0)
    low = jp.plan(scene.grid, scene.start, scene.goal, vehicle_height=0.5)
    high = jp.plan(scene.grid, scene.start, scene.goal, vehicle_height=1.45)
    assert low.success and high.success and low.length < high.length
    ch = scene.grid.clearance_height[high.path[:, 1], high.path[:, 0]]
    assert (ch > 1.45).all()


@pytest.mark.parametrize(
    "kwargs, error",
    [
        (dict(start=(0, 0), goal=(2, 0)), r"goal \(2, 0\) is on a blocked cell"),
        (dict(start=(1, 0), goal=(0, 0)), r"start \(1, 0\) is on a blocked cell"),
        (dict(start=(9, 0), goal=(0, 0)), r"start \(9, 0\) lies outside the 3x2 map"),
        (dict(start=(0.5, 0), goal=(0, 0)), "integer cell coordinates"),
        (dict(start=(0, 0, 0), goal=(0, 0)), "must be a cell"),
        (dict(start=(0, 0), goal=(0, 1), connectivity=6), "connectivity must be one of"),
        (dict(start=(0, 0), goal=(0, 1), vehicle_height=float("nan")), "NaN"),
        (dict(start=(0, 0), goal=(0, 1), vehicle_height=-1.0), "vehicle_height must be"),
        (dict(start=(0, 0), goal=(0, 1), ants=5), "planner 'astar' has no parameter"),
        (dict(start=(0, 0), goal=(0, 1), planner="nope"), r"unknown planner 'nope' \(registered: "),
        # did-you-mean, as on the command line: a case slip and a missing letter find the real names
        (dict(start=(0, 0), goal=(0, 1), planner="IACO"), r"unknown planner 'IACO'; did you mean 'iaco'\?"),
        (dict(start=(0, 0), goal=(0, 1), planner="iaco", iteration=10),
         r"no parameter\(s\) 'iteration'; did you mean 'iterations'\?"),
        (dict(start=(0, 0), goal=(0, 1), connectivty=4), r"'connectivty'; did you mean 'connectivity'\?"),
    ],
)
def test_bad_input_names_the_problem(kwargs, error):
    g = jp.grid_from_array(np.array([[1, 0, 0], [1, 1, 1]], bool))
    kwargs = dict(kwargs)
    with pytest.raises(ValueError, match=error):
        jp.plan(g, kwargs.pop("start"), kwargs.pop("goal"), **kwargs)


def test_did_you_mean_is_one_helper_for_every_layer():
    """The Python API, the configs and the command line share `jaxplan.core.names.did_you_mean`."""
    from jaxplan.core.names import closest, did_you_mean
    from jaxplan.experiments import schema

    assert schema.did_you_mean is did_you_mean
    assert closest("IACO", ["aco", "iaco"]) == "iaco" and closest("Iteration", ["ants", "iterations"]) == "iterations"
    assert closest("zzz", ["aco", "iaco"]) is None and did_you_mean("zzz", ["aco"]) == ""
    assert did_you_mean("iaco-dwa", ["iaco_dwa", "aco_dwa"]) == "; did you mean 'iaco_dwa'?"


def test_shortest_lengths_bad_rows_are_named():
    g = jp.grid_from_array(np.array([[1, 0, 0], [1, 1, 1]], bool))
    with pytest.raises(ValueError, match=r"goals\[1\] = \(1, 0\) is on a blocked cell"):
        jp.shortest_lengths(g, [[0, 0], [0, 0]], [[2, 1], [1, 0]])
    with pytest.raises(ValueError, match="differ in shape"):
        jp.shortest_lengths(g, [[0, 0]], [[2, 1], [0, 1]])
    assert jp.shortest_lengths(g, np.zeros((0, 2)), np.zeros((0, 2))).shape == (0,)


def test_shortest_lengths_groups_shared_ends(movingai):
    g = jp.load_map(movingai / "random-64-64-20.map")
    cells = np.argwhere(g.free)[:, ::-1]
    rng = np.random.default_rng(1)
    hub = cells[5]
    others = cells[rng.choice(len(cells), 40, replace=False)]
    # The hub is the start of some rows and the goal of others: one group serves all.
    starts = np.concatenate([np.repeat(hub[None], 20, 0), others[20:]])
    goals = np.concatenate([others[:20], np.repeat(hub[None], 20, 0)])
    got = jp.shortest_lengths(g, starts, goals)
    single = [jp.astar(g, s, t).length for s, t in zip(starts, goals, strict=True)]
    np.testing.assert_allclose(got, single, rtol=1e-12)


def test_planners_registry_lists_exact_planners():
    reg = jp.planners()
    assert {"astar", "dijkstra"} <= set(reg)
    assert reg["astar"].defaults["connectivity"] == 8
