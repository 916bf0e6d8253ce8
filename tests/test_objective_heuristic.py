"""The colonies' ``heuristic="objective"``: the exact own cost-to-go behind it, and colonies that follow it."""

from __future__ import annotations

import numpy as np
import pytest

import jaxplan as jp
from jaxplan.aco import COLONIES, aco_defaults, goal_tables, plan_memory
from jaxplan.aco._objective import objective_tables
from jaxplan.grid import neighbour_table, passable, state_cost_to_go
from jaxplan.search import exact_objective, objective_cost_to_go, objective_terms

CASES = [
    ("aco", {}),
    ("iaco", {}),
    ("iaco", {"connectivity": 16, "lambdas": (0.2, 0.6, 0.2)}),
    ("risk_aco", {}),
    ("risk_aco", {"u": 1.0, "v": 5.0, "w": 2.0}),
    ("praco", {"omega2": 3.0}),
    ("praco", {"connectivity": 4}),
    ("opt_ant", {"vehicle_height": None}),
    ("opt_ant", {"vehicle_height": None, "connectivity": 8, "b": 2.0}),
]


def _grid(seed: int = 0, shape=(7, 8), turn_rule: bool = False):
    rng = np.random.default_rng(seed)
    free = rng.random(shape) > 0.25
    risk = rng.poisson(1.0, shape).astype(np.float32)
    turn = (rng.random(shape) < 0.15).astype(np.int8) if turn_rule else None
    return jp.grid_from_array(free, resolution=0.5, risk=risk, turn_rule=turn)


def _optimum_from(grid, h, terms, s, g):
    """``cell[s] + min_k (w_len·step[k] + cell[v] + h[v, k])`` over the moves the planner allows from s."""
    nb = neighbour_table(grid, terms.connectivity, terms.vehicle_height)
    W = grid.width
    si, gi = s[1] * W + s[0], g[1] * W + g[0]
    ks = [k for k in range(nb.index.shape[1]) if nb.valid[si, k]]
    if terms.goal_first and any(nb.index[si, k] == gi for k in ks):
        ks = [k for k in ks if nb.index[si, k] == gi]
    step = np.hypot(*nb.offsets.T.astype(np.float64)) * float(grid.resolution)
    return min((terms.cell[si] + terms.w_len[0] * step[k] + terms.cell[nb.index[si, k]] + h[nb.index[si, k], k]
                for k in ks), default=np.inf)


@pytest.mark.parametrize("planner,weights", CASES)
@pytest.mark.parametrize("turn_rule", [False, True])
def test_cost_to_go_gives_the_exact_optimum_from_every_cell(planner, weights, turn_rule):
    if turn_rule and planner != "opt_ant":
        pytest.skip("right-turn cells are opt_ant's rule only")
    grid = _grid(1, turn_rule=turn_rule)
    ok = passable(grid, weights.get("vehicle_height", aco_defaults(planner)["vehicle_height"]))
    cells = np.argwhere(ok)[:, ::-1]
    g = cells[len(cells) // 2]
    for s in cells:
        if (s == g).all():
            continue
        h = objective_cost_to_go(grid, [s], [g], planner, **weights)[0]  # iaco's L0 depends on the start
        terms = objective_terms(grid, [s], [g], planner, **weights)
        want = exact_objective(grid, s, g, planner, **weights).cost
        got = _optimum_from(grid, h, terms, s, g)
        assert got == pytest.approx(want, rel=1e-12, abs=1e-12) or (np.isinf(got) and np.isinf(want)), (s, g)


def test_cost_to_go_is_zero_on_the_goal_and_inf_where_it_cannot_be_reached():
    free = np.ones((4, 6), bool)
    free[:, 3] = False  # two halves
    grid = jp.grid_from_array(free)
    h = state_cost_to_go(grid, [[0, 0]])[0]
    assert (h[0] == 0).all()
    assert np.isinf(h[5]).all() and np.isfinite(h[1]).any()
    with pytest.raises(ValueError, match="w_turn"):
        state_cost_to_go(grid, [[0, 0]], w_turn=-1.0)


def test_the_colony_weights_are_the_papers_costs():
    """`cost_weights` (read by the colonies' heuristic and by the exact search alike) against each cost written out:
    iaco λ1·L/L0 + λ2·Σ|θ|/π + λ3·Σ 1/clearance, risk_aco u·L + v·risk + w·turns, praco ω1·L + ω2·turns."""
    from jaxplan.aco import cost_weights

    grid = _grid(2, turn_rule=True)
    ok = np.argwhere(passable(grid, None))[:, ::-1]
    s, g = ok[:3], ok[-3:]
    res = float(grid.resolution)
    iaco = cost_weights("iaco", grid, s, g, {**aco_defaults("iaco"), "lambdas": (0.2, 0.6, 0.2)})
    l0 = np.hypot(*(s - g).T.astype(float)) * res
    np.testing.assert_allclose(iaco.w_len, 0.2 / l0, rtol=1e-15)
    assert iaco.w_angle == pytest.approx(0.6 / np.pi) and iaco.w_turn == 0.0
    clear = np.maximum(jp.clearance_field(grid), 0.5 * res).ravel()
    free = passable(grid, None).ravel()
    np.testing.assert_allclose(iaco.cell[free], 0.2 / clear[free], rtol=1e-6)
    assert (iaco.cell[~free] == 0).all()
    risk = cost_weights("risk_aco", grid, s, g, {**aco_defaults("risk_aco"), "u": 1.0, "v": 5.0, "w": 2.0})
    assert (risk.w_len == 1.0).all() and risk.w_turn == 2.0 and risk.w_angle == 0.0
    np.testing.assert_array_equal(risk.cell[free], 5.0 * np.asarray(grid.risk).ravel()[free])
    praco = cost_weights("praco", grid, s, g, {**aco_defaults("praco"), "omega2": 3.0})
    assert (praco.w_len == 1.0).all() and praco.w_turn == 3.0 and not praco.cell.any() and not praco.goal_first
    opt = cost_weights("opt_ant", grid, s, g, {**aco_defaults("opt_ant"), "vehicle_height": None, "b": 2.0})
    assert opt.goal_first and opt.w_turn == 2.0
    np.testing.assert_array_equal(opt.turn_rule, np.asarray(grid.turn_rule).ravel() == 1)
    terms = objective_terms(grid, s, g, "iaco", lambdas=(0.2, 0.6, 0.2))  # the exact search reads the same weights
    np.testing.assert_array_equal(terms.w_len, iaco.w_len)
    with pytest.raises(ValueError, match=r"exact_objective: planner .risk_aco. gives cell \(\d+, \d+\) the path cost"):
        cost_weights("risk_aco", grid, s, g, {**aco_defaults("risk_aco"), "v": -1.0}, what="exact_objective")


def test_objective_tables_turn_variants():
    grid = _grid(3)
    ok = np.argwhere(passable(grid, None))[:, ::-1]
    for planner, V in (("aco", 1), ("praco", 2), ("risk_aco", 2), ("iaco", 5)):
        ot = objective_tables(planner, grid, ok[:1], ok[-1:], aco_defaults(planner) | {"vehicle_height": None})
        assert ot.turn_cost.shape == (1, V) and ot.turn_cost[0, 0] == 0
        K = 8
        v = ot.variant[0].reshape(K + 1, K)
        assert (v[0] == 0).all() and (np.diag(v[1:]) == 0).all()  # no turn from the start or when going straight
        assert ot.move_cost.shape == (1, grid.n_cells, K)


@pytest.mark.parametrize("planner,weights", [c for c in CASES if c[1].get("connectivity") != 4] + [
    ("praco", {"connectivity": 4})])
def test_a_colony_with_a_huge_beta_finds_its_own_optimum(planner, weights):
    grid = _grid(4, shape=(9, 11), turn_rule=planner == "opt_ant")
    ok = np.argwhere(passable(grid, weights.get("vehicle_height", None)))[:, ::-1]
    starts, goals = ok[[0, 3]], ok[[-1, -5]]
    opt = jp.search.exact_objectives(grid, starts, goals, planner=planner, **weights)
    for backend in ("numba", "jax"):
        r = jp.plan_batch(grid, starts, goals, planner=planner, seeds=range(2), heuristic="objective", beta=60.0,
                          ants=4, iterations=3, walk_backend=backend, **weights)
        assert r.success.all()
        P = r.paths.shape[2]
        cost = jp.search.path_objectives(r.paths.reshape(-1, P, 2), r.n_cells.reshape(-1), grid, planner, **weights)
        np.testing.assert_allclose(cost.reshape(2, 2), np.broadcast_to(opt[:, None], (2, 2)), rtol=1e-9)
        if backend == "numba":
            first = r
        else:  # both walks draw the same moves
            np.testing.assert_array_equal(r.paths, first.paths)
            np.testing.assert_array_equal(r.cost, first.cost)


def test_a_bad_heuristic_name_is_refused_with_the_choices():
    grid = _grid(5)
    ok = np.argwhere(passable(grid, None))[:, ::-1]
    for planner in COLONIES:
        with pytest.raises(ValueError, match=r"heuristic must be one of \('euclidean', 'geodesic', 'objective'\)"):
            jp.plan_batch(grid, ok[:1], ok[-1:], planner=planner, heuristic="objectve")


def test_defaults_build_no_objective_tables_and_the_memory_estimate_counts_them():
    grid = _grid(6)
    ok = np.argwhere(passable(grid, None))[:, ::-1]
    gt = goal_tables(grid, ok[:2], ok[-2:])
    assert gt.move_cost is None and gt.turn_cost is None and gt.variant is None
    base = plan_memory(grid, "iaco", 10)
    obj = plan_memory(grid, "iaco", 10, heuristic="objective")
    assert "objective cost-to-go" in obj.parts and "objective cost-to-go" not in base.parts
    C, K = grid.n_cells, 8
    assert obj.parts["objective cost-to-go"] == 10 * C * K * (8 + 4) + 5 * 10 * C * K * 4
    assert obj.total > base.total
