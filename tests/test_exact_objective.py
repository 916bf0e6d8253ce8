"""Each colony's own optimum (`jaxplan.search.exact_objective`): brute force over every simple path, the colonies'
own costs, and the property that no colony beats it."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import jaxplan as jp
from jaxplan.aco import COLONIES
from jaxplan.search import OBJECTIVE_PLANNERS, exact_objective, exact_objectives, path_objective, path_objectives

# ---------------------------------------------------------------------------------------------
# An independent reference: every simple path enumerated, each cost written out as docs/guide/planners.md defines it.


def _offsets(conn: int) -> list[tuple[int, int]]:
    return [tuple(o) for o in jp.grid.offsets(conn).tolist()]


def _allowed(free: np.ndarray, x: int, y: int, dx: int, dy: int) -> bool:
    """The move rule of docs/guide/maps-and-scenarios.md, written out: target free and inside; a diagonal needs both
    orthogonal cells; a knight move the two cells its segment crosses."""
    H, W = free.shape
    tx, ty = x + dx, y + dy
    if not (0 <= tx < W and 0 <= ty < H and free[ty, tx]):
        return False
    if abs(dx) == 1 and abs(dy) == 1:
        return bool(free[y, x + dx] and free[y + dy, x])
    if abs(dx) == 2:  # (±2, ±1): crosses (x + dx/2, y) and (x + dx/2, y + dy)
        return bool(free[y, x + dx // 2] and free[y + dy, x + dx // 2])
    if abs(dy) == 2:
        return bool(free[y + dy // 2, x] and free[y + dy // 2, x + dx])
    return True


def _simple_paths(free: np.ndarray, start, goal, conn: int, rule=None):
    """Every simple path start → goal (lists of cells); ``rule(cell, prev_move, moves) -> moves`` filters moves."""
    offs = _offsets(conn)
    out = []

    def rec(path, seen, prev):
        x, y = path[-1]
        moves = [k for k, (dx, dy) in enumerate(offs) if _allowed(free, x, y, dx, dy)]
        if rule is not None:
            moves = rule((x, y), prev, moves)
        for k in moves:
            nxt = (x + offs[k][0], y + offs[k][1])
            if nxt in seen:
                continue
            if nxt == goal:
                out.append(path + [nxt])
                continue
            seen.add(nxt)
            rec(path + [nxt], seen, k)
            seen.discard(nxt)

    rec([tuple(start)], {tuple(start)}, -1)
    return out


def _reference_cost(path, grid, planner, p) -> float:
    """The planner's cost of ``path`` from its definition (docs/guide/planners.md), in float64."""
    res = float(grid.resolution)
    steps = [(b[0] - a[0], b[1] - a[1]) for a, b in zip(path[:-1], path[1:], strict=True)]
    L = sum(math.hypot(*s) for s in steps) * res
    heads = [math.atan2(s[1], s[0]) for s in steps]
    changes = [abs((h1 - h0 + math.pi) % (2 * math.pi) - math.pi) for h0, h1 in zip(heads[:-1], heads[1:], strict=True)]
    turns = sum(1 for a, b in zip(steps[:-1], steps[1:], strict=True) if a != b)
    if planner in ("aco", "astar"):
        return L
    if planner == "praco":
        return p["omega1"] * L + p["omega2"] * turns
    if planner == "risk_aco":
        risk = sum(float(grid.risk[y, x]) for x, y in path)
        return p["u"] * L + p["v"] * risk + p["w"] * turns
    if planner == "opt_ant":
        return p["a"] * L + p["b"] * turns
    if planner == "iaco":
        lam = p["lambdas"]
        clear = np.maximum(jp.grid.clearance_field(grid), 0.5 * res).astype(np.float32)
        l0 = math.hypot(path[0][0] - path[-1][0], path[0][1] - path[-1][1]) * res
        inv_d = sum(1.0 / float(clear[y, x]) for x, y in path)
        return lam[0] * L / l0 + lam[1] * sum(changes) / math.pi + lam[2] * inv_d
    raise AssertionError(planner)


def _maps():
    """Small maps with a few obstacles (True = free), start and goal."""
    a = np.ones((4, 4), bool)
    a[1, 1] = a[2, 2] = False
    b = np.ones((5, 5), bool)
    b[1, 1:4] = False
    b[3, 2] = False
    b[2, 4] = False
    c = np.ones((5, 5), bool)
    c[0, 2] = c[1, 2] = c[3, 1] = c[3, 3] = c[4, 3] = False
    return [(a, (0, 0), (3, 3)), (a, (3, 0), (0, 3)), (b, (0, 0), (4, 4)), (b, (4, 0), (0, 4)), (c, (0, 0), (4, 0))]


SETTINGS = [
    ("aco", {}),
    ("iaco", {}),
    ("iaco", {"lambdas": (0.1, 0.8, 0.1)}),
    ("iaco", {"lambdas": (0.2, 0.1, 0.7)}),
    ("risk_aco", {}),
    ("risk_aco", {"u": 1.0, "v": 5.0, "w": 2.0}),
    ("opt_ant", {"connectivity": 8}),
    ("opt_ant", {"connectivity": 8, "a": 1.0, "b": 0.3}),
    ("praco", {}),
    ("praco", {"omega2": 3.0}),
    ("astar", {}),
]


def _grid(free, planner, seed=0):
    risk = np.random.default_rng(seed).poisson(1.0, free.shape).astype(np.float32) if planner == "risk_aco" else None
    return jp.grid_from_array(free, resolution=0.5, risk=risk)


def _cheapest_by_enumeration(grid, s, g, planner, p, rule=None):
    free = np.asarray(grid.free)
    paths = _simple_paths(free, s, g, int(p.get("connectivity", 8)), rule)
    assert paths, "the test map must connect start and goal"
    costs = [_reference_cost(q, grid, planner, p) for q in paths]
    return min(costs), len(paths)


@pytest.mark.parametrize("planner,over", SETTINGS, ids=[f"{p}-{i}" for i, (p, _) in enumerate(SETTINGS)])
def test_exact_objective_equals_brute_force(planner, over):
    p = {**jp.registry.registered()[planner].defaults, **over}
    for free, s, g in _maps():
        grid = _grid(free, planner)
        rule = _goal_first(g) if planner == "opt_ant" else None
        best, n_paths = _cheapest_by_enumeration(grid, s, g, planner, p, rule)
        r = exact_objective(grid, s, g, planner=planner, **over)
        assert r.success and r.cost == pytest.approx(best, rel=1e-12), (planner, over, s, g, n_paths)
        # The returned path attains the optimum, by the reference and by path_objective.
        path = [tuple(c) for c in r.path.tolist()]
        assert path[0] == s and path[-1] == g and len(set(path)) == len(path)
        assert _reference_cost(path, grid, planner, p) == pytest.approx(r.cost, rel=1e-12)
        assert path_objective(r.path, grid, planner, **over) == pytest.approx(r.cost, rel=1e-12)


def _goal_first(goal, conn: int = 8):
    """chu2024's hook: an adjacent goal is always taken."""
    offs = _offsets(conn)

    def rule(cell, prev, moves):
        at = [k for k in moves if (cell[0] + offs[k][0], cell[1] + offs[k][1]) == tuple(goal)]
        return at or moves

    return rule


def test_opt_ant_sixteen_directions_and_right_hand_rule_by_brute_force():
    """opt_ant at its default 16 directions on 4x4 maps, and with right-turn cells (8 directions, 5x5): the
    rule forces the quarter turn right of the incoming move where the map allows it; an adjacent goal wins."""
    p = dict(jp.registry.registered()["opt_ant"].defaults)
    for free, s, g in _maps()[:2]:
        grid = jp.grid_from_array(free, resolution=0.5)
        best, n = _cheapest_by_enumeration(grid, s, g, "opt_ant", p, _goal_first(g, 16))
        assert n >= 10
        assert exact_objective(grid, s, g, planner="opt_ant").cost == pytest.approx(best, rel=1e-12)
    free = np.ones((5, 5), bool)
    free[2, 2] = False
    turn = np.zeros((5, 5), np.int8)
    turn[0, 2] = turn[2, 0] = turn[4, 2] = 1
    grid = jp.grid_from_array(free, resolution=1.0, turn_rule=turn)
    offs = _offsets(8)
    K = len(offs)
    for s, g in (((0, 0), (4, 4)), ((4, 0), (0, 4)), ((0, 2), (4, 2))):

        def rule(cell, prev, moves, g=g):
            at = [k for k in moves if (cell[0] + offs[k][0], cell[1] + offs[k][1]) == tuple(g)]
            if at:
                return at
            right = (prev + K // 4) % K
            if prev >= 0 and turn[cell[1], cell[0]] and right in moves:
                return [right]
            return moves

        over = {"connectivity": 8, "b": 3.0}
        best, _ = _cheapest_by_enumeration(grid, s, g, "opt_ant", {**p, **over}, rule)
        r = exact_objective(grid, s, g, planner="opt_ant", **over)
        assert r.cost == pytest.approx(best, rel=1e-12)
        unruled, _ = _cheapest_by_enumeration(grid, s, g, "opt_ant", {**p, **over}, _goal_first(g))
        assert r.cost >= unruled - 1e-12


def test_every_colony_is_covered_or_refused():
    """Every colony in the registry has an exact objective; the planners whose cost is no sum are refused."""
    assert set(COLONIES) <= set(OBJECTIVE_PLANNERS)
    grid = jp.grid_from_array(np.ones((4, 4), bool))
    for name in ("astar_kng", "rrt_star", "mrbs_rrt"):
        with pytest.raises(ValueError, match="not a sum over grid moves|not over grid moves"):
            exact_objective(grid, (0, 0), (3, 3), planner=name)
    with pytest.raises(ValueError, match="unknown planner|no exact objective"):
        exact_objective(grid, (0, 0), (3, 3), planner="nope")


def test_opt_ant_height_term_is_refused_on_height_maps():
    height = np.zeros((4, 4), np.float32)
    height[1, 2] = 2.0
    grid = jp.grid_from_array(np.ones((4, 4), bool), height=height)
    with pytest.raises(ValueError, match="mean square deviation"):
        exact_objective(grid, (0, 0), (3, 3), planner="opt_ant")
    # c = 0: the exact minimum of a·L + b·R, a lower bound of the colony's full cost.
    r = exact_objective(grid, (0, 0), (3, 3), planner="opt_ant", c=0.0)
    assert r.success and r.cost == pytest.approx(3 * math.sqrt(2))
    flat = jp.grid_from_array(np.ones((4, 4), bool), height=np.full((4, 4), 1.5, np.float32))
    assert exact_objective(flat, (0, 0), (3, 3), planner="opt_ant").cost == pytest.approx(3 * math.sqrt(2))


def test_bad_input_and_unreachable():
    free = np.ones((4, 4), bool)
    free[:, 2] = False
    grid = jp.grid_from_array(free)
    r = exact_objective(grid, (0, 0), (3, 3), planner="praco")
    assert not r.success and r.cost == math.inf and len(r.path) == 0
    assert exact_objectives(grid, [(0, 0), (0, 0)], [(3, 3), (1, 3)], planner="praco")[0] == math.inf
    with pytest.raises(ValueError, match="equals the goal"):
        exact_objective(grid, (0, 0), (0, 0), planner="iaco")
    with pytest.raises(ValueError, match="start"):
        exact_objective(grid, (2, 0), (0, 3), planner="iaco")
    with pytest.raises(ValueError, match="no parameter"):
        exact_objective(grid, (0, 0), (1, 3), planner="iaco", lambda1=2.0)
    with pytest.raises(ValueError, match="not a 8-connected move"):
        path_objective(np.array([[0, 0], [0, 2]]), grid, "aco")
    with pytest.raises(ValueError, match="not allowed on the map"):
        path_objective(np.array([[1, 0], [2, 0]]), grid, "aco")


def test_batch_equals_single_and_ignores_colony_only_parameters():
    free = np.ones((12, 14), bool)
    free[3:9, 5] = False
    free[6, 2:10] = False
    grid = jp.grid_from_array(free, resolution=0.25, risk=np.random.default_rng(1).poisson(1.0, (12, 14)))
    starts = np.array([(0, 0), (13, 11), (2, 10), (12, 1)])
    goals = np.array([(13, 11), (0, 0), (11, 2), (1, 9)])
    for planner in OBJECTIVE_PLANNERS:
        over = {"ants": 7} if planner in COLONIES else {}
        batch = exact_objectives(grid, starts, goals, planner=planner, **over)
        single = [exact_objective(grid, s, g, planner=planner).cost for s, g in zip(starts, goals, strict=True)]
        np.testing.assert_allclose(batch, single, rtol=1e-12)
        # Lengths: the length objectives equal the octile optimum (16 directions: shorter or equal).
        if planner in ("aco", "astar", "dijkstra"):
            np.testing.assert_allclose(batch, jp.shortest_lengths(grid, starts, goals), rtol=1e-12)


@pytest.mark.parametrize("planner", sorted(COLONIES))
def test_path_objective_is_the_colonys_own_cost(planner):
    """`path_objective` of a colony's best path equals the cost the colony reports (float32, ~1e-6)."""
    free = np.ones((10, 12), bool)
    free[2:8, 4] = False
    free[5, 6:11] = False
    risk = np.random.default_rng(2).poisson(1.0, free.shape)
    grid = jp.grid_from_array(free, resolution=0.5, risk=risk)
    over = {"ants": 16, "iterations": 8}
    batch = jp.plan_batch(grid, [(0, 0), (11, 9)], [(11, 9), (0, 9)], planner=planner, seeds=range(2), **over)
    assert batch.success.all()
    cost = path_objectives(batch.paths.reshape(4, -1, 2), batch.n_cells.reshape(-1), grid, planner, **over)
    np.testing.assert_allclose(cost, batch.cost.reshape(-1), rtol=2e-6)


def _property_maps():
    rng = np.random.default_rng(7)
    out = []
    while len(out) < 3:
        free = rng.random((14, 16)) > 0.25
        free[0, 0] = free[-1, -1] = free[0, -1] = free[-1, 0] = True
        grid = jp.grid_from_array(free, resolution=1.0, risk=rng.poisson(1.0, free.shape))
        ok = jp.shortest_lengths(grid, [(0, 0), (15, 0)], [(15, 13), (0, 13)])
        if np.isfinite(ok).all():
            out.append(grid)
    return out


@pytest.mark.parametrize("planner", sorted(COLONIES))
def test_no_colony_beats_its_own_optimum(planner):
    """Property: on random maps, every colony's best cost (its own float32 number and the float64 cost of its
    path) is at least `exact_objective`'s, for several seeds and parameter settings."""
    starts, goals = np.array([(0, 0), (15, 0)]), np.array([(15, 13), (0, 13)])
    settings = [{}, {"heuristic": "geodesic"}]
    if planner == "iaco":
        settings.append({"lambdas": (0.2, 0.2, 0.6)})
    if planner in ("praco", "risk_aco", "opt_ant"):
        settings.append({"connectivity": 16 if planner == "opt_ant" else 8, **({"omega2": 5.0} if planner == "praco"
                                                                               else {})})
    for grid in _property_maps():
        for over in settings:
            over = {"ants": 12, "iterations": 6, **over}
            opt = exact_objectives(grid, starts, goals, planner=planner, **over)
            b = jp.plan_batch(grid, starts, goals, planner=planner, seeds=range(3), **over)
            own = np.where(b.success, b.cost, np.inf)
            assert (own >= opt[:, None] * (1 - 2e-6)).all(), (planner, over, own, opt)
            P = b.paths.shape[2]
            ok = b.success.reshape(-1)
            cost = path_objectives(b.paths.reshape(-1, P, 2)[ok], b.n_cells.reshape(-1)[ok], grid, planner, **over)
            assert (cost >= np.repeat(opt, 3)[ok] - 1e-9).all()


def test_path_metrics_objective_gap_is_opt_in():
    free = np.ones((6, 7), bool)
    free[1:5, 3] = False
    grid = jp.grid_from_array(free, resolution=0.5)
    path = np.array([[0, 0], [1, 0], [2, 0], [3, 0], [4, 0], [5, 1], [6, 2], [6, 3]])
    plain = jp.metrics.path_metrics(path, grid)
    assert plain.objective_gap is None
    assert [f.name for f in dataclasses.fields(plain)] == [*jp.metrics.PATH_METRICS, "objective_gap"]
    best = exact_objective(grid, (0, 0), (6, 3), planner="praco", omega2=2.0)
    cost = path_objective(path, grid, "praco", omega2=2.0)
    m = jp.metrics.path_metrics(path, grid, cost=cost, objective_optimum=best.cost)
    assert dataclasses.replace(m, objective_gap=None) == plain  # the existing metrics unchanged
    assert m.objective_gap == pytest.approx(cost / best.cost - 1) and m.objective_gap >= 0
    batch = jp.metrics.path_metrics(np.stack([path, path]), grid, cost=[cost, best.cost], objective_optimum=best.cost)
    assert batch.objective_gap[1] == 0.0
    with pytest.raises(ValueError, match="go together"):
        jp.metrics.path_metrics(path, grid, cost=cost)


OBJ_RUN = """
metrics = ["success", "length", "optimality_gap", "objective_gap"]
[experiment]
name = "objgap"
seeds = 2
[[maps]]
name = "r"
generator = "random"
seed = 1
params = { width = 20, height = 16, obstacle_ratio = 0.2 }
scenarios = { source = "random", count = 3, seed = 3, min_distance = 10.0 }
[[planners]]
label = "A*"
kind = "plan"
name = "astar"
[[planners]]
label = "IACO"
kind = "plan"
name = "iaco"
overrides = { ants = 8, iterations = 4 }
[[planners]]
label = "KNG"
kind = "plan"
name = "astar_kng"
"""


def test_trials_gain_an_objective_gap_column(tmp_path):
    import csv

    from jaxplan.experiments import run_experiment

    cfg = tmp_path / "o.toml"
    cfg.write_text(OBJ_RUN)
    with open(run_experiment(cfg, tmp_path / "run", progress=False) / "trials.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    by = {}
    for r in rows:
        by.setdefault(r["planner"], []).append(r)
    assert set(by) == {"A*", "IACO", "KNG"}, set(by)
    assert all(float(r["objective_gap"]) == pytest.approx(0.0, abs=1e-12) for r in by["A*"])
    assert all(r["objective_gap"] == "nan" for r in by["KNG"])  # a polyline: no sum over grid moves
    gaps = [float(r["objective_gap"]) for r in by["IACO"] if r["success"] == "1"]
    assert gaps and min(gaps) >= -1e-12
