"""The colony engine and the papers' ACO planners: valid paths, exact sampling, determinism, bad input."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import stats

import jaxplan as jp
from jaxplan.aco import COLONIES, draw, hash_uniform
from jaxplan.aco._context import goal_tables
from jaxplan.aco._planners import cached_map_tables, compiled, seed_keys, split_params
from jaxplan.registry import resolve

PLANNERS = sorted(COLONIES)
SMALL = dict(ants=16, iterations=6)



def _assert_path_valid(grid, path, start, goal, connectivity):
    assert tuple(path[0]) == tuple(start) and tuple(path[-1]) == tuple(goal)
    assert grid.free[path[:, 1], path[:, 0]].all()
    table = jp.neighbour_table(grid, connectivity)
    moves = {tuple(o): j for j, o in enumerate(table.offsets)}
    for a, b in zip(path[:-1], path[1:], strict=True):
        d = tuple((b - a).tolist())
        assert d in moves and table.valid[a[1] * grid.width + a[0], moves[d]], f"bad step {tuple(a)}->{tuple(b)}"
    assert len({tuple(c) for c in path.tolist()}) == len(path), "path revisits a cell"


@pytest.mark.parametrize("planner", PLANNERS)
def test_batched_paths_are_valid_and_deterministic(room, planner):
    grid, starts, goals = room
    extra = {"vehicle_height": None} if planner == "opt_ant" else {}
    if planner == "praco":
        extra["colonies"] = 2
    a = jp.plan_batch(grid, starts, goals, planner=planner, seeds=[0, 1], **SMALL, **extra)
    b = jp.plan_batch(grid, starts, goals, planner=planner, seeds=[0, 1], **SMALL, **extra)
    for field in ("paths", "length", "cost", "history", "success", "converged"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
    assert a.success.shape == (3, 2) and a.history.shape == (3, 2, SMALL["iterations"])
    conn = jp.planners()[planner].defaults["connectivity"]
    exact = jp.shortest_lengths(grid, starts, goals, connectivity=conn)
    for i in range(3):
        for r in range(2):
            res = a.result(i, r)
            if not res.success:
                continue
            _assert_path_valid(grid, res.path, starts[i], goals[i], conn)
            np.testing.assert_allclose(res.length, jp.search.path_cost(res.path, grid.resolution), rtol=1e-5)
            assert res.length >= exact[i] - 1e-4
            assert res.turns == jp.metrics.count_turns(res.path)
            h = res.history
            assert np.all(np.diff(h[np.isfinite(h)]) <= 1e-6), "best-so-far cost must not increase"
            np.testing.assert_allclose(h[-1], res.cost, rtol=1e-6)
    assert a.success.mean() >= 0.5
    # plan() is the same program with one scenario and one seed: identical result.
    single = jp.plan(grid, starts[1], goals[1], planner=planner, seed=1, **SMALL, **extra)
    np.testing.assert_array_equal(single.path, a.result(1, 1).path)
    assert single.info["compile_s"] == 0 or single.success == a.success[1, 1]


def test_first_move_frequencies_match_transition_probabilities():
    """20,000 draws of the sampler against the exact probabilities w / Σw (chi-square)."""
    w = np.array([0.0, 0.5, 2.0, 1e-3, 1.0, 0.0, 3.0, 0.25], np.float32)
    n = 20000
    p = jnp.broadcast_to(jnp.asarray(w), (n, 8))
    nb = jnp.broadcast_to(jnp.arange(8) + 100, (n, 8))
    u = hash_uniform(jnp.uint32(12345), jnp.int32(0), jnp.arange(n))
    k, target, any_move = draw(p, nb, u)
    k = np.asarray(k)
    assert np.asarray(any_move).all() and np.array_equal(np.asarray(target), k + 100)
    counts = np.bincount(k, minlength=8)
    assert counts[0] == 0 and counts[5] == 0, "zero-weight moves must never be drawn"
    expected = w / w.sum() * n
    keep = expected > 0
    chi2 = ((counts[keep] - expected[keep]) ** 2 / expected[keep]).sum()
    assert stats.chi2.sf(chi2, keep.sum() - 1) > 1e-3, (counts, expected)


def test_walk_first_moves_follow_pheromone_and_heuristic():
    """First moves of real ants from one cell match τ^α·η^β normalised over the allowed moves."""
    grid = jp.grid_from_array(np.ones((9, 9), bool))
    start, goal = np.array([[4, 4]]), np.array([[8, 6]])
    spec, p = resolve("aco", dict(ants=4000, iterations=1, max_steps=1, beta=2.0))
    cfg, params, conn, vh = split_params(grid, p)
    tables = cached_map_tables(grid, conn, vh)
    gt = goal_tables(grid, start, goal, conn, vh)
    from jaxplan.aco._walk import move_lut, walk

    c = 4 * 9 + 4
    d = np.linalg.norm(np.asarray(tables.xy)[np.asarray(tables.index[c])] - np.asarray(tables.xy)[gt.goal[0]], axis=1)
    w = (1.0 / np.maximum(d, 0.5)) ** 2
    table = jnp.zeros((81, 8)).at[c].set(jnp.asarray(w / w.max(), jnp.float32))
    A = 4000
    z = jnp.zeros(A, jnp.int32)
    ants = walk(jnp.where(tables.valid, tables.index, -1), table, z + c, z + gt.goal[0], z, z,
                jnp.full(A, 7, jnp.uint32), jnp.arange(A), None, max_steps=1, width=9,
                lut=move_lut(tables.offsets), dead_end="die")
    first = np.asarray(ants.moves[:, 0])
    counts = np.bincount(first, minlength=8)
    expected = w / w.sum() * A
    chi2 = ((counts - expected) ** 2 / expected).sum()
    assert stats.chi2.sf(chi2, 7) > 1e-3, (counts, expected)


def test_unreachable_goal_fails_cleanly_without_nan():
    free = np.ones((6, 6), bool)
    free[:, 3] = False
    grid = jp.grid_from_array(free)
    for planner in ("aco", "praco"):
        extra = {"colonies": 2} if planner == "praco" else {}
        r = jp.plan_batch(grid, [[0, 0]], [[5, 5]], planner=planner, seeds=[0, 1], **SMALL, **extra)
        assert not r.success.any() and np.isinf(r.length).all()
        assert not np.isnan(r.history).any() and not np.isnan(r.diversity).any()
        assert (r.successes == 0).all()


def test_pheromone_stays_finite_and_inside_bounds():
    scene = jp.UrbanGenerator()(0)
    spec, p = resolve("opt_ant", dict(ants=16, iterations=8))
    cfg, params, conn, vh = split_params(scene.grid, p)
    cfg = type(cfg)(**{**cfg.__dict__, "keep_pheromone": True})
    tables = cached_map_tables(scene.grid, conn, vh)
    gt = goal_tables(scene.grid, [scene.start], [scene.goal], conn, vh)
    keys = seed_keys([0])
    fn, _ = compiled(COLONIES["opt_ant"], cfg, tables, gt, params, keys)
    out = fn(tables, gt, params, keys)
    tau = np.asarray(out.tau)
    assert np.isfinite(tau).all()
    assert tau.min() >= 10.0 - 1e-4 and tau.max() <= 40.0 + 1e-4
    assert bool(out.success[0, 0])


def test_second_call_with_other_seed_does_not_recompile(room):
    grid, starts, goals = room
    jp.plan(grid, starts[0], goals[0], planner="aco", seed=0, **SMALL)
    again = jp.plan(grid, starts[0], goals[0], planner="aco", seed=5, **SMALL)
    assert again.info["compile_s"] == 0.0


@pytest.mark.parametrize(
    "overrides, message",
    [
        (dict(alpha=float("nan")), "NaN"),
        (dict(beta=-1.0), "'beta' must be >= 0"),
        (dict(q=float("inf")), "'q' must be finite"),
        (dict(ants=0), "ants must be a positive integer"),
        (dict(rho=1.5), "'rho' must lie in"),
        (dict(heuristic="manhattan"), "heuristic must be one of"),
        (dict(dead_end="jump"), "dead_end must be one of"),
        (dict(gamma=1.0), "has no parameter"),
    ],
)
def test_bad_parameters_name_the_problem(room, overrides, message):
    grid, starts, goals = room
    with pytest.raises(ValueError, match=message):
        jp.plan(grid, starts[0], goals[0], planner="aco", **overrides)


def test_bad_cells_name_the_problem(room):
    grid, starts, goals = room
    with pytest.raises(ValueError, match="equals the goal"):
        jp.plan(grid, starts[0], starts[0], planner="iaco")
    with pytest.raises(ValueError, match=r"start \(2, 3\) is on a blocked cell"):
        jp.plan(grid, (2, 3), goals[0], planner="iaco")
    with pytest.raises(ValueError, match=r"goals\[0\] = \(2, 3\) is on a blocked cell"):
        jp.plan_batch(grid, starts[:1], [[2, 3]], planner="iaco")
    with pytest.raises(ValueError, match="seeds must"):
        jp.plan_batch(grid, starts[:1], goals[:1], planner="iaco", seeds=[])


def test_geodesic_heuristic_finds_the_optimum_on_a_maze(movingai):
    grid = jp.load_map(movingai / "maze-32-32-2.map")
    scen = jp.load_scenarios(movingai / "maze-32-32-2-random-1.scen")
    rows = np.nonzero((scen.optimal > 10) & (scen.optimal < 40))[0][:4]
    r = jp.plan_batch(grid, scen.starts[rows], scen.goals[rows], planner="iaco", seeds=[0],
                      heuristic="geodesic", ants=32, iterations=10)
    assert r.success.all()
    gap = r.length[:, 0] / scen.optimal[rows] - 1
    assert (gap < 0.10).all(), gap


def test_compacting_the_walking_ants_changes_no_result(monkeypatch):
    """With >= 512 ants the walk continues with the walking quarter once the rest stopped."""
    import jaxplan.aco._walk as W

    scene = jp.RandomMapGenerator(24, 24, 0.3)(2)
    grid = scene.grid
    spec, p = resolve("aco", dict(ants=512, iterations=1))
    cfg, params, conn, vh = split_params(grid, p)
    tables = cached_map_tables(grid, conn, vh)
    gt = goal_tables(grid, [scene.start], [scene.goal], conn, vh)
    h = np.linalg.norm(np.asarray(tables.xy) - np.asarray(tables.xy)[int(gt.goal[0])], axis=1)
    w = np.where(np.asarray(tables.valid), (1.0 / np.maximum(h, 0.5))[np.asarray(tables.index)] ** 7, 0.0)
    table = jnp.asarray(w / np.maximum(w.max(axis=1, keepdims=True), 1e-30), jnp.float32)
    A = 512
    z = jnp.zeros(A, jnp.int32)
    outs = []
    for threshold in (10**9, 512):
        monkeypatch.setattr(W, "COMPACT_MIN_ANTS", threshold)
        for dead_end in ("die", "retreat"):
            outs.append(W.walk(jnp.where(tables.valid, tables.index, -1), table, z + gt.start[0], z + gt.goal[0], z, z,
                               jnp.full(A, 11, jnp.uint32), jnp.arange(A), None, max_steps=cfg.max_steps,
                               width=grid.width, lut=W.move_lut(tables.offsets), dead_end=dead_end))
    for plain, compact in zip(outs[:2], outs[2:], strict=True):
        for field in ("cells", "n", "status", "ant_steps"):
            np.testing.assert_array_equal(getattr(plain, field), getattr(compact, field))
    assert (np.asarray(outs[0].status) != 1).sum() > 3 * A // 4, "the case must actually compact"


def test_seed_keys_equal_jax_random_key():
    from jaxplan.aco._planners import seed_keys

    seeds = [0, 1, 7, 2**32 - 1]
    expected = jax.vmap(jax.random.key)(jnp.asarray(seeds, jnp.uint32))
    np.testing.assert_array_equal(jax.random.key_data(seed_keys(seeds)), jax.random.key_data(expected))
    with pytest.raises(ValueError, match="below 2\\*\\*32"):
        seed_keys([2**32])


def test_praco_with_one_colony_exchanges_with_no_one():
    # One colony has no ring neighbour: its exchange deposits must not come back to itself.
    from jaxplan.grid._neighbours import offsets

    free = np.ones((6, 7), bool)
    free[2:4, 2:5] = False
    grid = jp.grid_from_array(free)
    for backend in ("jax", "numba"):
        r = jp.plan(grid, (0, 0), (6, 5), planner="praco", seed=0, colonies=1, ants=1, iterations=1,
                    keep_pheromone=True, update_backend=backend)
        index = {tuple(o): k for k, o in enumerate(offsets(8))}
        steps = zip(r.path[:-1], r.path[1:], strict=True)
        edges = [(int(y0 * 7 + x0), index[(x1 - x0, y1 - y0)]) for (x0, y0), (x1, y1) in steps]
        tau = r.info["tau"][0]
        # rho_res 0.7 of the initial 1.0, plus the own colony's (w − 1 = 5) and best-so-far (w = 6) deposits, 1/Z each.
        np.testing.assert_allclose([tau[c, k] for c, k in edges], 0.7 + 11.0 / r.cost, rtol=1e-5)


def test_opt_ant_initial_pheromone_stays_bounded_below_the_datum():
    # chu2024's −σ·H/H_max term: terrain below zero must not divide by a floored maximum.
    from jaxplan.aco import _rules as R
    from jaxplan.aco._context import map_tables

    params = {"c_init": jnp.float32(20.0), "sigma": jnp.float32(0.125)}
    h = np.linspace(-101.0, -100.0, 36, dtype=np.float32).reshape(6, 6)
    tau0 = np.asarray(R.init_opt_ant(map_tables(jp.grid_from_array(np.ones((6, 6), bool), height=h), 16), params))
    assert np.all(tau0 <= 20.0 + 1.0 + 0.125 + 1e-5) and np.all(tau0 >= 20.0 - 0.125 - 1e-5)
    # Heights >= 0 keep the published form: the highest cell loses exactly σ.
    h = np.linspace(0.0, 1.0, 36, dtype=np.float32).reshape(6, 6)
    t = map_tables(jp.grid_from_array(np.ones((6, 6), bool), height=h), 16)
    inner = 20.0 + 1.0 / (1.0 + np.asarray(t.n_blocked)) - 0.125 * np.asarray(t.height)
    expect = np.where(np.asarray(t.boundary), 20.0, inner)
    np.testing.assert_allclose(np.asarray(R.init_opt_ant(t, params)), expect, rtol=1e-6)


def test_an_empty_batch_is_an_empty_result():
    # A host past the end of a multi-host sweep's scenarios gets none (jaxplan.scale.host_share).
    grid = jp.grid_from_array(np.ones((6, 6), bool))
    b = jp.plan_batch(grid, np.zeros((0, 2), int), np.zeros((0, 2), int), planner="aco", seeds=[0, 1],
                      iterations=3, mesh=None)
    assert b.paths.shape[:2] == (0, 2) and b.success.shape == (0, 2) and b.history.shape == (0, 2, 3)


@pytest.mark.parametrize("overrides, match", [
    (dict(planner="iaco", lambdas=(0.0, 0.0, 0.0)), "lambdas must have a weight > 0"),
    (dict(planner="aco", max_steps=True), "max_steps"),
    (dict(planner="praco", w_rank=0.5), "w_rank"),
    (dict(planner="praco", n_exchange=0), "n_exchange"),
])
def test_counts_and_weights_that_make_no_sense_are_refused(overrides, match):
    grid = jp.grid_from_array(np.ones((6, 6), bool))
    with pytest.raises(ValueError, match=match):
        jp.plan(grid, (0, 0), (5, 5), **overrides)


@pytest.mark.parametrize("dead_end", ["die", "alert", "retreat"])
def test_praco_takes_every_dead_end_rule(dead_end):
    # docs/guide/planners.md: every ACO planner takes the three rules; the dead-corner penalty needs retreats only.
    free = np.ones((6, 7), bool)
    free[2:4, 2:5] = False
    r = jp.plan(jp.grid_from_array(free), (0, 0), (6, 5), planner="praco", dead_end=dead_end, ants=4, iterations=3)
    assert r.success


def test_aco_retreats_by_default_where_dying_ants_fail():
    """aco's default dead-end rule is "retreat" (issue 43): in a pocket facing the goal, a lone ant that dies
    there fails most runs; the default reaches the goal in every run, the same runs as an explicit "retreat"."""
    assert resolve("aco", {})[1]["dead_end"] == "retreat"
    free = np.ones((11, 15), bool)
    free[2:9, 9] = False  # the pocket's back wall, between the start (left) and the goal (right)
    free[2, 5:10] = False
    free[8, 5:10] = False
    grid = jp.grid_from_array(free)
    runs = {de: jp.plan_batch(grid, [(1, 5)], [(13, 5)], planner="aco", seeds=range(32), ants=1, iterations=1,
                              **({} if de is None else {"dead_end": de})) for de in (None, "retreat", "die")}
    assert np.asarray(runs[None].success).all()
    np.testing.assert_array_equal(runs[None].length, runs["retreat"].length)
    assert np.asarray(runs["die"].success).mean() < 0.6  # measured 10 of 32


def test_every_config_names_the_dead_end_rule_of_its_ant_system():
    """A config entry that runs `aco` (as a planner or as a pipeline's global planner) says which dead-end rule
    it uses: the default changed once (issue 43), and a result must not change with a default."""
    import tomllib
    from pathlib import Path

    from jaxplan.nav import pipelines

    via_aco = {n for n, p in pipelines().items() if p.global_planner == "aco"}
    unnamed = []
    for path in sorted((Path(__file__).resolve().parents[1] / "configs").glob("*.toml")):
        for pc in tomllib.loads(path.read_text()).get("planners", []):
            runs_aco = (pc.get("kind") == "plan" and pc.get("name") == "aco") or (
                pc.get("kind") == "navigate" and pc.get("name") in via_aco)
            if runs_aco and "dead_end" not in pc.get("overrides", {}):
                unnamed.append(f"{path.name}: {pc.get('label')}")
    assert not unnamed, unnamed
