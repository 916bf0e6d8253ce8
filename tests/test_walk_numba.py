"""The numba walk backend: bit-identical to the JAX walk, for every preset, rule and batch shape."""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from numba import njit

import jaxplan as jp
from jaxplan.aco import COLONIES, _walk_ffi, hash_uniform
from jaxplan.aco import _rules as R
from jaxplan.aco import _walk_numba as WN
from jaxplan.aco import _walk_numba_intrinsics as WI
from jaxplan.aco._colony import RunConfig, run_batch
from jaxplan.aco._context import goal_tables, map_tables
from jaxplan.aco._planners import seed_keys, split_params
from jaxplan.aco._walk import GOAL, move_lut, walk
from jaxplan.aco._walk_numba_kernels import MODES, NO_HOOK, walk_all
from jaxplan.registry import resolve

PLANNERS = sorted(COLONIES)
SMALL = dict(ants=16, iterations=6)
RESULT_FIELDS = ("paths", "n_cells", "length", "cost", "turns", "success", "converged", "history", "diversity",
                 "successes")



def _assert_same(a, b, fields=RESULT_FIELDS):
    for f in fields:
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f), err_msg=f)


def _assert_same_walk(ref, out, fields):
    """Walk outputs field by field; paths only on their valid slots (cells up to n, moves below n)."""
    n = np.asarray(ref.n)
    np.testing.assert_array_equal(np.asarray(out.n), n, err_msg="n")
    L = np.asarray(ref.moves).shape[1]
    for field in fields:
        r, o = getattr(ref, field), getattr(out, field)
        assert (r is None) == (o is None), field
        if r is None or field == "n":
            continue
        r, o = np.asarray(r), np.asarray(o)
        if field in ("cells", "moves"):
            valid = np.arange(r.shape[1])[None, :] <= n[:, None] - (field == "moves")
            r, o = np.where(valid, r, 0), np.where(valid, o, 0)
            assert r.shape[1] == L + (field == "cells")
        np.testing.assert_array_equal(o, r, err_msg=field)


@njit
def _exp_many(x, out):
    for i in range(x.size):
        out[i] = WI.exp_xla(x[i])


def test_exp_is_xlas_bit_for_bit():
    """The hook's exponential against `jnp.exp` on 2^22 float32 in [-90, 0] (every one of them
    was checked once: no difference), including the range XLA flushes to zero."""
    rng = np.random.default_rng(0)
    lo, hi = np.float32(-90.0).view(np.uint32), np.float32(-0.0).view(np.uint32)
    x = np.concatenate([rng.integers(hi, lo, 1 << 22, dtype=np.uint32).view(np.float32),
                        np.linspace(-88.0, -86.0, 4001, dtype=np.float32),
                        np.array([0.0, -0.0, -np.inf, -1e-30, -87.8, -87.33655], np.float32)])
    out = np.empty_like(x)
    _exp_many(x, out)
    np.testing.assert_array_equal(out.view(np.uint32), np.asarray(jax.jit(jnp.exp)(x)).view(np.uint32))


@njit
def _uniforms(seed, t, ant, out):
    for i in range(out.size):
        out[i] = WI.uniform(seed[i], t[i], ant[i])


def test_uniforms_are_hash_uniform():
    rng = np.random.default_rng(1)
    n = 100_000
    seed = rng.integers(0, 2**32, n, dtype=np.uint32)
    t = rng.integers(0, 5000, n).astype(np.int32)
    ant = rng.integers(0, 10**6, n).astype(np.int32)
    out = np.empty(n, np.float32)
    _uniforms(seed, t, ant, out)
    np.testing.assert_array_equal(out, np.asarray(hash_uniform(jnp.asarray(seed), jnp.asarray(t), jnp.asarray(ant))))


def _walk_inputs(grid, B: int, S: int, m: int, seed: int):
    """Random pheromone-like tables for B runs x S colonies x m ants on ``grid``."""
    tables = map_tables(grid, 8)
    C, K = tables.index.shape
    rng = np.random.default_rng(seed)
    free = np.flatnonzero(np.asarray(grid.free).ravel())
    cells = rng.choice(free, size=(B, 2), replace=False) if B * 2 <= free.size else rng.choice(free, size=(B, 2))
    w = rng.random((B * S * C, K)).astype(np.float32) ** 4
    w[rng.random(w.shape) < 0.1] = 0.0  # some zero weights: allowed moves drawn only through the floor
    valid = np.tile(np.asarray(tables.valid), (B * S, 1))
    table = np.where(valid, w, 0.0).astype(np.float32)
    A = B * S * m
    run_of = np.repeat(np.arange(B), S * m)
    colony_of = np.tile(np.repeat(np.arange(S), m), B)
    return dict(
        tables=tables,
        nbr=jnp.where(tables.valid, tables.index, -1), table=jnp.asarray(table),
        start=jnp.asarray(cells[run_of, 0], jnp.int32), goal=jnp.asarray(cells[run_of, 1], jnp.int32),
        row0=jnp.asarray((run_of * S + colony_of) * C, jnp.int32), cell0=jnp.asarray(run_of * C, jnp.int32),
        seed=jnp.asarray(rng.integers(0, 2**32, B, dtype=np.uint32)[run_of]),
        local=jnp.asarray(np.tile(np.arange(S * m), B), jnp.int32),
        alert=jnp.asarray(rng.random(B * C) < 0.05), A=A, C=C, K=K,
    )


@pytest.mark.parametrize("dead_end, penalise",
                         [("die", False), ("retreat", False), ("retreat", True), ("alert", False)])
@pytest.mark.parametrize("ants", [24, 200])  # 2 runs x 2 colonies x ants: 200 gives 800 ants, compacted in JAX
def test_walk_equals_jax_walk_field_by_field(dead_end, penalise, ants):
    scene = jp.RandomMapGenerator(20, 18, 0.25)(3)
    B, S = 2, 2
    d = _walk_inputs(scene.grid, B, S, ants, seed=ants)
    alert = d["alert"] if dead_end == "alert" else None
    kw = dict(max_steps=120, width=scene.grid.width, lut=move_lut(d["tables"].offsets), dead_end=dead_end,
              penalty_size=B * S * d["C"] * d["K"] if penalise else 0)
    args = (d["nbr"], d["table"], d["start"], d["goal"], d["row0"], d["cell0"], d["seed"], d["local"], alert)
    ref = jax.jit(functools.partial(walk, **kw))(*args)
    out = jax.jit(functools.partial(WN.walk, **kw))(*args)
    _assert_same_walk(ref, out, [f for f in ref._fields if f != "stats"])
    status = np.asarray(ref.status)
    assert len(np.unique(status)) >= 2, "the case should mix goal, dead-end and step-limit ants"
    if dead_end == "alert":
        assert np.asarray(ref.marks).any()
    if penalise:
        assert np.asarray(ref.penalty).sum() > 0


@pytest.mark.parametrize("ants", [1, 5, 23])  # 2 runs x 2 colonies: fewer ants than lanes, and a partial last round
@pytest.mark.parametrize("n_chunks", [1, 2, 3])
def test_lane_walk_equals_jax_walk_for_any_ant_and_chunk_count(ants, n_chunks):
    """The 8-connected walk steps `LANES` ants at once per chunk: idle lanes, lanes that take the chunk's
    next ant and chunk counts that do not divide the ants change no path, count or penalty."""
    scene = jp.RandomMapGenerator(20, 18, 0.25)(3)
    B, S = 2, 2
    d = _walk_inputs(scene.grid, B, S, ants, seed=ants)
    L, C, K, A = 120, d["C"], d["K"], d["A"]
    lut = move_lut(d["tables"].offsets)
    kw = dict(max_steps=L, width=scene.grid.width, lut=lut, dead_end="retreat", penalty_size=B * S * C * K)
    ref = jax.jit(functools.partial(walk, **kw))(d["nbr"], d["table"], d["start"], d["goal"], d["row0"], d["cell0"],
                                                 d["seed"], d["local"], None)
    i32 = lambda x: np.ascontiguousarray(np.asarray(x), np.int32)  # noqa: E731
    cells, moves = np.zeros((A, L + 1), np.int32), np.zeros((A, L), np.int8)
    per_ant, stats = np.zeros((3, A), np.int32), np.zeros((WN.N_STATS, A), np.float32)
    penalty, marks = np.zeros(B * S * C * K, np.float32), np.zeros(1, np.bool_)
    walk_all(i32(d["nbr"]), np.asarray(d["table"]), np.zeros((2, 1, K), np.float32), np.zeros((K + 1) * K, np.int32),
             np.zeros(K, np.int32), np.zeros(1, np.bool_), i32(d["start"]), i32(d["goal"]), i32(d["row0"]),
             i32(d["cell0"]), np.asarray(d["seed"]), i32(d["local"]), np.zeros(1, np.bool_),
             np.asarray(WN.move_bits(d["nbr"])), L, scene.grid.width, i32(lut), MODES["retreat"], NO_HOOK, True,
             n_chunks, np.ones(K + K * K, np.float32), np.ones((3, C), np.float32), cells, moves, per_ant[0],
             per_ant[1], per_ant[2], penalty, marks, stats)
    out = ref._replace(cells=cells, moves=moves, n=per_ant[0], status=per_ant[1], ant_steps=per_ant[2],
                       penalty=penalty)
    _assert_same_walk(ref, out, ["cells", "moves", "status", "ant_steps", "penalty"])
    assert np.asarray(ref.penalty).sum() > 0


@pytest.mark.parametrize("dead_end", ["die", "retreat", "alert"])
def test_walk_with_opt_ant_hook_equals_jax_walk(dead_end):
    """chu2024's hook (heights, right-turn cells, goal priority, geodesic inf distances)."""
    scene = jp.UrbanGenerator(right_turn_prob=0.8)(1)
    grid = scene.grid
    _, p = resolve("opt_ant", dict(vehicle_height=None, connectivity=8))
    _, params, _, _ = split_params(grid, p)
    tables = map_tables(grid, 8)
    C, K = tables.index.shape
    B, S, m = 2, 1, 300
    rng = np.random.default_rng(7)
    free = np.flatnonzero(np.asarray(grid.free).ravel())
    goals = rng.choice(free, B)
    h_cell = jnp.asarray(np.stack([
        jp.search.distance_from(grid, (int(g) % grid.width, int(g) // grid.width), 8).ravel() for g in goals
    ]), jnp.float32)  # inf where unreachable
    tau = jnp.asarray(rng.uniform(10, 40, (B, S, C, K)), jnp.float32)
    logits = jnp.where(tables.valid, params["alpha"] * jnp.log(tau), -jnp.inf)
    run_of = np.repeat(np.arange(B), S * m)
    starts = rng.choice(free, B)
    args = (jnp.where(tables.valid, tables.index, -1), logits.reshape(B * S * C, K),
            jnp.asarray(starts[run_of], jnp.int32), jnp.asarray(goals[run_of], jnp.int32),
            jnp.asarray(run_of * S * C, jnp.int32), jnp.asarray(run_of * C, jnp.int32),
            jnp.asarray(rng.integers(0, 2**32, B, dtype=np.uint32)[run_of]),
            jnp.asarray(np.tile(np.arange(m), B), jnp.int32),
            jnp.asarray(rng.random(B * C) < 0.03) if dead_end == "alert" else None)
    kw = dict(max_steps=150, width=grid.width, lut=move_lut(tables.offsets), dead_end=dead_end)
    hook = functools.partial(R.hook_opt_ant, tables, params, h_cell.reshape(B * C))
    ref = jax.jit(functools.partial(walk, **kw, hook=hook))(*args)
    ht = WN.HookTables(R.hook_opt_ant_logits(tables, params, h_cell, logits), tables.right_turn, tables.turn_rule)
    out = jax.jit(functools.partial(WN.walk, **kw, hook=ht))(*args)
    _assert_same_walk(ref, out, ("cells", "moves", "n", "status", "ant_steps", "loop_steps", "slots", "marks"))
    assert (np.asarray(ref.status) == 1).mean() > 0.2


def _both(grid, starts, goals, planner, seeds, **kw):
    return [jp.plan_batch(grid, starts, goals, planner=planner, seeds=seeds, walk_backend=b, **kw)
            for b in ("jax", "numba")]


@pytest.mark.parametrize("planner", PLANNERS)
# The presets' default rule runs by default; the others are slow (~8 s each): every rule is also
# compared step by step at the walk level above.
@pytest.mark.parametrize("dead_end", [pytest.param("die", marks=pytest.mark.slow), "retreat",
                                      pytest.param("alert", marks=pytest.mark.slow)])
def test_every_preset_and_dead_end_rule_gives_identical_results(room, planner, dead_end):
    grid, starts, goals = room
    extra = {"vehicle_height": None} if planner == "opt_ant" else {}
    if planner == "praco":
        extra["colonies"] = 2
        if dead_end != "retreat":
            pytest.skip("praco's dead-corner penalty needs dead_end='retreat'")
    a, b = _both(grid, starts, goals, planner, [0, 1], dead_end=dead_end, **SMALL, **extra)
    _assert_same(a, b)
    assert a.success.mean() >= 0.5


@pytest.mark.parametrize("planner, scene, extra", [
    ("opt_ant", jp.UrbanGenerator(right_turn_prob=0.6), dict(vehicle_height=None)),  # right-hand rule, heights
    ("opt_ant", jp.MountainGenerator(), dict(connectivity=16)),  # 16 moves, tunnels vs vehicle height
    ("iaco", jp.RandomMapGenerator(24, 24, 0.3), dict(heuristic="geodesic")),
    ("risk_aco", jp.RandomMapGenerator(24, 24, 0.2), dict(ants=40)),
    ("praco", jp.RandomMapGenerator(24, 24, 0.3), dict(colonies=3, ants=12)),
])
def test_presets_on_the_seed_maps_give_identical_results(planner, scene, extra):
    s = scene(2)
    kw = {**dict(ants=24, iterations=5), **extra}
    a, b = _both(s.grid, [s.start], [s.goal], planner, [0, 3], **kw)
    _assert_same(a, b)


def test_numba_backend_same_seed_same_result_and_auto_picks_it(room):
    grid, starts, goals = room
    runs = [jp.plan_batch(grid, starts, goals, planner="iaco", seeds=[4], walk_backend=b, **SMALL)
            for b in ("numba", "numba", "auto")]
    _assert_same(runs[0], runs[1])
    _assert_same(runs[0], runs[2])
    assert WN.resolve_backend("auto") == ("numba" if jax.default_backend() == "cpu" else "jax")


def test_unreachable_goal_fails_cleanly_without_nan_in_numba():
    free = np.ones((6, 6), bool)
    free[:, 3] = False
    grid = jp.grid_from_array(free)
    for planner in ("iaco", "opt_ant"):  # aco and praco: tests/test_aco.py (default backend "auto")
        extra = {"vehicle_height": None} if planner == "opt_ant" else {}
        r = jp.plan_batch(grid, [[0, 0]], [[5, 5]], planner=planner, seeds=[0, 1], walk_backend="numba", **SMALL,
                          **extra)
        assert not r.success.any() and np.isinf(r.length).all()
        assert not np.isnan(r.history).any() and not np.isnan(r.diversity).any()
        assert (r.successes == 0).all()


def test_walk_refuses_move_bits_of_another_grid():
    scene = jp.RandomMapGenerator(20, 18, 0.25)(3)
    d = _walk_inputs(scene.grid, 1, 1, 8, seed=5)
    args = (d["nbr"], d["table"], d["start"], d["goal"], d["row0"], d["cell0"], d["seed"], d["local"], None)
    kw = dict(max_steps=50, width=scene.grid.width, lut=move_lut(d["tables"].offsets), dead_end="die")
    with pytest.raises(ValueError, match="bits must be move_bits"):
        WN.walk(*args, **kw, bits=WN.move_bits(d["nbr"])[:-1])


@pytest.mark.parametrize("dead_end", ["die", "retreat"])
def test_nan_move_weights_stop_the_ant_as_in_the_jax_walk(dead_end):
    """A cell whose weights are NaN (β = 0 with a geodesic heuristic where the goal is unreachable
    gives 0·log 0) leaves the ant stuck there in both walks; the two-ant walk must not move blind."""
    scene = jp.RandomMapGenerator(20, 18, 0.25)(3)
    d = _walk_inputs(scene.grid, 1, 1, 64, seed=5)
    table = np.asarray(d["table"]).copy()
    nan_cells = np.random.default_rng(0).random(d["C"]) < 0.15
    table[nan_cells] = np.where(np.asarray(d["tables"].valid)[nan_cells], np.nan, 0.0)
    kw = dict(max_steps=120, width=scene.grid.width, lut=move_lut(d["tables"].offsets), dead_end=dead_end)
    args = (d["nbr"], jnp.asarray(table), d["start"], d["goal"], d["row0"], d["cell0"], d["seed"], d["local"], None)
    ref = jax.jit(functools.partial(walk, **kw))(*args)
    out = jax.jit(functools.partial(WN.walk, **kw))(*args)
    _assert_same_walk(ref, out, ["cells", "moves", "status", "ant_steps"])
    n = np.asarray(ref.n)
    last = np.asarray(ref.cells)[np.arange(n.size), n]
    assert nan_cells[last].any(), "some ant should have stopped on a NaN cell"


def test_vmap_over_params_matches_per_element_runs(room):
    """Tuning vmaps a run over parameter values: the callback then walks each element in turn."""
    grid, starts, goals = room
    _, p = resolve("iaco", dict(SMALL))
    cfg, params, conn, vh = split_params(grid, p)
    tables = map_tables(grid, conn, vh)
    gt = goal_tables(grid, starts[:2], goals[:2], conn, vh)
    keys = seed_keys([0, 1])
    betas = jnp.asarray([2.0, 5.0, 7.0], jnp.float32)
    outs = {}
    for backend in ("jax", "numba"):
        c = RunConfig(**{**cfg.__dict__, "walk_backend": backend})
        fn = jax.jit(jax.vmap(lambda b, c=c: run_batch(COLONIES["iaco"], c, tables, gt, {**params, "beta": b}, keys)))
        outs[backend] = fn(betas)
    for field in ("cells", "n", "cost", "history", "ant_steps", "loop_steps", "slots"):
        np.testing.assert_array_equal(np.asarray(getattr(outs["numba"], field)),
                                      np.asarray(getattr(outs["jax"], field)))
    c = RunConfig(**{**cfg.__dict__, "walk_backend": "numba"})
    single = jax.jit(lambda b: run_batch(COLONIES["iaco"], c, tables, gt, {**params, "beta": b}, keys))(betas[1])
    np.testing.assert_array_equal(np.asarray(single.cells), np.asarray(outs["numba"].cells[1]))


def test_walk_backend_is_validated(room):
    grid, starts, goals = room
    with pytest.raises(ValueError, match="walk_backend must be one of"):
        jp.plan(grid, starts[0], goals[0], planner="aco", walk_backend="cuda")
    with pytest.raises(ValueError, match="walk_backend must be one of"):
        RunConfig(colonies=1, ants=2, iterations=1, max_steps=4, width=4, walk_backend="gpu")
    with pytest.raises(ValueError, match="planner 'iaco': update_backend must be one of"):
        jp.plan(grid, starts[0], goals[0], planner="iaco", update_backend="numpy")


def test_jax_backends_compile_no_native_call_and_reach_the_same_paths(room):
    # The demo's setting: no numba at all. Statistics may differ in the last bits from the native
    # update (another summation order); on this map the runs take the same paths.
    from jaxplan.aco._context import goal_tables
    from jaxplan.aco._planners import COLONIES, cached_map_tables, compiled, seed_keys, split_params
    from jaxplan.registry import resolve

    grid, starts, goals = room
    over = dict(ants=16, iterations=6, walk_backend="jax")
    for update, native in (("jax", False), ("numba", True)):
        cfg, params, conn, vh = split_params(grid, resolve("iaco", {**over, "update_backend": update})[1])
        fn, _ = compiled(COLONIES["iaco"], cfg, cached_map_tables(grid, conn, vh),
                         goal_tables(grid, starts[:2], goals[:2], conn, vh), params, seed_keys([3]))
        assert ("jaxplan_aco_deposit" in fn.as_text()) == native, update
        assert "jaxplan_aco_walk" not in fn.as_text()
    runs = [jp.plan_batch(grid, starts[:2], goals[:2], planner="iaco", seeds=[3], **over, update_backend=u)
            for u in ("jax", "numba")]
    np.testing.assert_array_equal(runs[0].paths, runs[1].paths)
    np.testing.assert_allclose(runs[0].cost, runs[1].cost, rtol=1e-6)
    assert runs[0].success.all()


def _random_paths(seed: int = 5, A: int = 300, ants_per_colony: int = 50):
    """Paths walked in JAX on a random map, with the tables the statistics and deposits read."""
    scene = jp.RandomMapGenerator(20, 18, 0.25)(3)
    B, S = 1, 2
    d = _walk_inputs(scene.grid, B, S, ants_per_colony, seed=seed)
    kw = dict(max_steps=120, width=scene.grid.width, lut=move_lut(d["tables"].offsets), dead_end="retreat")
    ants = jax.jit(functools.partial(walk, **kw))(d["nbr"], d["table"], d["start"], d["goal"], d["row0"], d["cell0"],
                                                  d["seed"], d["local"], None)
    return scene, d, kw, ants


def test_native_path_stats_match_the_array_version_and_the_walks():
    scene, d, kw, ants = _random_paths()
    tables = d["tables"]
    rng = np.random.default_rng(0)
    # Non-trivial risk and height layers, so every statistic is exercised.
    tables = tables._replace(risk=jnp.asarray(rng.random(d["C"]), jnp.float32),
                             height=jnp.asarray(rng.random(d["C"]) * 3, jnp.float32))
    st = WN.stat_tables(tables)
    native = np.asarray(jax.jit(WN.path_stats)(st, ants.cells, ants.moves, ants.n))
    ref = R.path_stats(tables, ants)
    for i, field in enumerate(R.PathStats._fields):
        exact = field in ("turns", "cells")
        np.testing.assert_allclose(native[i], np.asarray(getattr(ref, field)), rtol=0 if exact else 2e-5,
                                   atol=0 if exact else 1e-5, err_msg=field)
    # The numba walk sums the same statistics in its kernel: the same bits as the separate call.
    out = jax.jit(functools.partial(WN.walk, **kw, stats=st))(d["nbr"], d["table"], d["start"], d["goal"], d["row0"],
                                                                d["cell0"], d["seed"], d["local"], None)
    # ... for the ants at the goal; the others have no cost, and the walk leaves their statistics zero.
    at_goal = np.asarray(out.status) == GOAL
    assert 0 < at_goal.mean() < 1
    np.testing.assert_array_equal(np.asarray(out.stats)[:, at_goal], native[:, at_goal])
    np.testing.assert_array_equal(np.asarray(out.stats)[:, ~at_goal], 0.0)
    assert (np.asarray(ants.n) > 1).mean() > 0.5


def test_native_deposit_equals_xla_scatter_add():
    """The deposit kernel adds the same amounts in the same order as XLA's scatter-add."""
    from jaxplan.aco._colony import _scatter_paths

    scene, d, kw, ants = _random_paths(A=300)
    C, K = d["C"], d["K"]
    S, m = 2, 50
    rng = np.random.default_rng(1)
    tau = jnp.asarray(rng.random(S * C * K) * 3, jnp.float32)
    own = jnp.asarray(np.where(rng.random(S * m) < 0.5, rng.random(S * m) * 100, 0.0), jnp.float32)
    nbr = jnp.asarray(np.where(rng.random(S * m) < 0.3, rng.random(S * m) * 50, 0.0), jnp.float32)
    colony = jnp.repeat(jnp.arange(S), m)
    nxt = (colony + 1) % S
    best = jnp.asarray([3, 70])
    bs_cells, bs_moves, bs_n = ants.cells[best], ants.moves[best], ants.n[best]
    bs_amt = jnp.asarray([[5.0, 7.0], [1.5, 0.0]], jnp.float32)
    moves32 = ants.moves.astype(jnp.int32)
    ref = _scatter_paths(tau, colony, ants.cells, moves32, ants.n, own, K, C * K)
    ref = _scatter_paths(ref, nxt, ants.cells, moves32, ants.n, nbr, K, C * K)
    ref = _scatter_paths(ref, jnp.arange(S), bs_cells, bs_moves.astype(jnp.int32), bs_n, bs_amt[0], K, C * K)
    ref = _scatter_paths(ref, (jnp.arange(S) + 1) % S, bs_cells, bs_moves.astype(jnp.int32), bs_n, bs_amt[1], K, C * K)
    out = jax.jit(WN.deposit, static_argnums=(3, 4))(
        tau, (ants.cells, ants.moves, ants.n, jnp.stack([own, nbr]), jnp.stack([colony, nxt])),
        (bs_cells, bs_moves, bs_n, bs_amt, jnp.stack([jnp.arange(S), (jnp.arange(S) + 1) % S])), C, K)
    np.testing.assert_array_equal(np.asarray(out), np.asarray(ref))
    assert not np.array_equal(np.asarray(out), np.asarray(tau))


@pytest.mark.parametrize("planner", ["iaco", "praco"])
def test_update_backends_agree(room, planner):
    """The array-operation update (other devices) against the native one: the same first iteration
    (walks and counts; costs to float32 rounding of the summed statistics). praco's cost (length +
    turns) often ties between different paths, and the two updates, summing lengths in another
    order, can break such ties differently: its best path and pheromone are not compared."""
    grid, starts, goals = room
    _, p = resolve(planner, dict(ants=16, iterations=1, **({"colonies": 2} if planner == "praco" else {})))
    cfg, params, conn, vh = split_params(grid, p)
    tables = map_tables(grid, conn, vh)
    gt = goal_tables(grid, starts, goals, conn, vh)
    keys = seed_keys([0, 1])
    outs = {}
    for backend in ("jax", "numba"):
        c = RunConfig(**{**cfg.__dict__, "update_backend": backend, "keep_pheromone": True})
        program = jax.jit(lambda t, g, pr, k, c=c: run_batch(COLONIES[planner], c, t, g, pr, k))
        outs[backend] = program(tables, gt, params, keys)
    a, b = outs["jax"], outs["numba"]
    exact = ("success", "successes", "ant_steps") + (("cells", "n") if planner != "praco" else ())
    for field in exact:
        np.testing.assert_array_equal(np.asarray(getattr(a, field)), np.asarray(getattr(b, field)))
    for field in ("cost", "length") + (("tau",) if planner != "praco" else ()):
        np.testing.assert_allclose(np.asarray(getattr(a, field)), np.asarray(getattr(b, field)), rtol=1e-5)
    assert np.asarray(a.success).any()


def test_native_dead_corner_penalty_matches_power():
    """yu2020's penalty in the deposit kernel: τ·(1 − λ_p)^count where an edge was retreated over."""
    rng = np.random.default_rng(2)
    T, K = 800, 8
    tau = jnp.asarray(rng.random(T) * 5, jnp.float32)
    counts = jnp.asarray(np.where(rng.random(T) < 0.2, rng.integers(1, 40, T), 0), jnp.float32)
    keep = jnp.float32(0.7)
    empty = (jnp.zeros((1, 3), jnp.int32), jnp.zeros((1, 2), jnp.int8), jnp.zeros((1,), jnp.int32),
             jnp.zeros((2, 1), jnp.float32), jnp.zeros((2, 1), jnp.int32))
    out = jax.jit(WN.deposit, static_argnums=(3, 4))(tau, empty, empty, T // K, K, counts, keep)
    np.testing.assert_allclose(np.asarray(out), np.asarray(tau * jnp.power(keep, counts)), rtol=2e-6)
    np.testing.assert_array_equal(np.asarray(out)[np.asarray(counts) == 0], np.asarray(tau)[np.asarray(counts) == 0])


def test_cached_handlers_are_keyed_on_every_native_source():
    """numba's on-disk cache checks only a function's own file, yet a cached handler holds the code of every
    kernel it calls; so the handlers close over a hash of all native modules (a closure is in numba's key)."""
    from pathlib import Path

    package = Path(_walk_ffi.__file__).parent
    native = {p.name for p in package.glob("_walk_numba_*.py")} | {"_walk.py", "_walk_ffi.py"}
    assert native == set(_walk_ffi._NATIVE_MODULES)
    fp = _walk_ffi.source_fingerprint()
    assert 0 <= fp < 2**63 and fp == _walk_ffi.source_fingerprint()
    for handler in _walk_ffi._handlers(fp).values():
        assert [c.cell_contents for c in handler.__closure__] == [fp]
