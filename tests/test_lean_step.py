"""The lean single-robot steps: `make_stepper` and `dwa_step(full_info=False)` give `dwa_step`'s control bit for bit,
reject the same bad input with the same errors and never use another map's tables; `mppi_step`'s lean front
gives the same control and sequence as before; the one-robot programs, compiled without XLA:CPU's loop split,
give the bits of XLA's default compilation."""

from __future__ import annotations

import jax
import numpy as np
import pytest

import jaxplan as jp
from jaxplan.dwa import DWAConfig, DWAInfo, dwa_step, make_stepper, table_of
from jaxplan.dwa._core import dwa_control
from jaxplan.dwa._step import _control_only, _single, _single_control, device_config, validate_params


def _map(origin=(0.0, 0.0)):
    free = np.ones((24, 32), bool)
    free[0], free[-1], free[:, 0], free[:, -1] = False, False, False, False
    free[8:16, 12] = False  # a wall
    free[4, 20:26] = False  # and a shelf
    return jp.grid_from_array(free, resolution=0.25, origin=origin)


def _states(grid, n, seed=0):
    """``n`` random states on free cells (centres) with random headings and speeds, and sub-goals near them."""
    rng = np.random.default_rng(seed)
    ys, xs = np.nonzero(np.asarray(grid.free))
    k = rng.integers(0, len(xs), n)
    res = float(grid.resolution)
    xy = (np.stack([xs[k], ys[k]], 1) + 0.5) * res + np.asarray(grid.origin)
    st = np.column_stack([xy, rng.uniform(-np.pi, np.pi, n), rng.uniform(0, 1.2, n), rng.uniform(-2, 2, n)])
    return st, xy + rng.uniform(-3, 3, (n, 2))


def _bits(a) -> bytes:
    return np.asarray(a).tobytes()


@pytest.mark.parametrize("origin", [(0.0, 0.0), (-3.125, 7.5)])
@pytest.mark.parametrize("config", [DWAConfig(), DWAConfig(evaluator="fuzzy"), DWAConfig(evaluator="classic"),
                                    DWAConfig(clearance="bilinear", n_v=7, n_omega=11)],
                         ids=["weighted", "fuzzy", "classic", "bilinear"])
def test_stepper_and_lean_step_give_dwa_steps_control_bit_for_bit(origin, config):
    grid = _map(origin)
    step = make_stepper(grid, config)
    states, goals = _states(grid, 12)
    for st, sg in zip(states, goals, strict=True):
        u, info = dwa_step(st, sg, grid, config=config)
        lean, none = dwa_step(st, sg, grid, config=config, full_info=False)
        assert none is None
        assert _bits(step(st, sg)) == _bits(u) == _bits(lean)
        assert step(st, sg).dtype == np.float32 and step(st, sg).shape == (2,)


@pytest.mark.parametrize("origin", [(0.0, 0.0), (-3.125, 7.5)])
def test_dwa_steps_lean_front_returns_what_the_plain_program_returns(origin):
    """The single-robot front (scalar checks, configuration on the device) changes no bit of control or info."""
    grid = _map(origin)
    config = DWAConfig()
    prm = validate_params(None, config.evaluator)
    for st, sg in zip(*_states(grid, 6, seed=1), strict=True):
        u, info = dwa_step(st, sg, grid, config=config)
        local = grid.to_local(st[None])[0].astype(np.float32), grid.to_local(sg).astype(np.float32)
        u0, info0 = jax.device_get(_single(table_of(grid), config, prm, *local, None, None))
        assert _bits(u) == _bits(u0)
        for name, a, b in zip(DWAInfo._fields, info, info0, strict=True):
            b = grid.to_world(b) if name == "rollouts" else b
            assert _bits(a) == _bits(b), name
        u2, info2 = make_stepper(grid, config).info(st, sg)
        assert _bits(u2) == _bits(u) and all(_bits(a) == _bits(b) for a, b in zip(info, info2, strict=True))


@pytest.mark.parametrize("config", [DWAConfig(), DWAConfig(evaluator="fuzzy"), DWAConfig(evaluator="classic"),
                                    DWAConfig(clearance="bilinear", n_v=7, n_omega=11)],
                         ids=["weighted", "fuzzy", "classic", "bilinear"])
def test_one_robot_programs_skip_xlas_loop_split_with_the_bits_of_the_default_compilation(config):
    """`_single`/`_single_control` (behind `dwa_step` and `make_stepper`) are compiled without XLA:CPU's
    parallel task assignment (`jaxplan.core.xla`): no loop is split across threads, and control and info are
    those of a plain ``jax.jit`` (which splits the large loops when the process has several cores or devices)."""
    grid = _map((-3.125, 7.5))
    prm = validate_params(None, config.evaluator)
    table, lean, full = table_of(grid), device_config(config, True), device_config(config)
    plain_control, plain_full = jax.jit(_control_only), jax.jit(dwa_control)
    for st, sg in zip(*_states(grid, 8, seed=3), strict=True):
        local = grid.to_local(st[None])[0].astype(np.float32), grid.to_local(sg).astype(np.float32)
        assert _bits(_single_control(table, lean, prm, *local)) == _bits(plain_control(table, lean, prm, *local))
        ours = jax.device_get(_single(table, full, prm, *local, None, None))
        theirs = jax.device_get(plain_full(table, full, prm, *local, None, None))
        assert all(_bits(a) == _bits(b) for a, b in zip(jax.tree_util.tree_leaves(ours),
                                                           jax.tree_util.tree_leaves(theirs), strict=True))
    hlo = _single_control.lower(table, lean, prm, *local).compile().as_text()
    assert "outer_dimension_partitions" not in hlo


@pytest.mark.parametrize("state, subgoal", [
    ([1.0, 1.0, float("nan"), 0.5, 0.0], [3.0, 3.0]),
    ([1.0, 1.0, 0.0, 0.5, 0.0], [3.0, float("inf")]),
    ([1.0, 1.0, 0.0, 5.0, 0.0], [3.0, 3.0]),  # empty window (v)
    ([1.0, 1.0, 0.0, 0.5, 9.0], [3.0, 3.0]),  # empty window (omega)
    ([-0.2, 1.0, 0.0, 0.5, 0.0], [3.0, 3.0]),  # off the map
    ([3.1, 3.0, 0.0, 0.5, 0.0], [5.0, 3.0]),  # on the wall
    ([0.1, 1.0, 0.0, 0.5, 0.0], [3.0, 3.0]),  # on the border
    ([1.0, 1.0, 0.0, 0.5], [3.0, 3.0]),
    ([1.0, 1.0, 0.0, 0.5, 0.0], [3.0, 3.0, 0.0]),
    ("robot", [3.0, 3.0]),
])
def test_stepper_rejects_bad_input_with_dwa_steps_error(state, subgoal):
    grid = _map()
    with pytest.raises(ValueError) as want:
        dwa_step(state, subgoal, grid)
    with pytest.raises(ValueError) as lean:
        dwa_step(state, subgoal, grid, full_info=False)
    with pytest.raises(ValueError) as got:
        make_stepper(grid)(state, subgoal)
    assert str(got.value) == str(want.value) == str(lean.value)


def test_stepper_takes_one_robot_only():
    grid = _map()
    st, sg = _states(grid, 2)
    with pytest.raises(ValueError, match="one robot"):
        make_stepper(grid)(st, sg)
    u, _ = dwa_step(st, sg, grid, full_info=False)  # dwa_step takes the batch
    assert u.shape == (2, 2) and _bits(u) == _bits(dwa_step(st, sg, grid)[0])


@pytest.mark.parametrize("bad, match", [
    (dict(config=DWAConfig(d_safe=0.1)), "d_safe"),
    (dict(config=DWAConfig(n_v=0)), "n_v"),
    (dict(params={"heading": -0.1}), "must be >= 0"),
    (dict(params={"speed": 1.0}), "unknown DWA parameter"),
    (dict(grid=np.ones((4, 4), bool)), "GridMap"),
])
def test_config_params_and_map_are_checked_when_the_stepper_is_made(bad, match):
    args = dict(grid=_map(), config=None, params=None) | bad
    with pytest.raises(ValueError, match=match):
        make_stepper(args["grid"], args["config"], args["params"])


def test_each_map_gets_its_own_tables_and_the_stepper_keeps_its_map():
    grid = _map()
    st, sg = np.array([2.0, 3.0, 0.0, 1.0, 0.0]), np.array([5.0, 3.0])  # heading for the wall at x = 3 m
    step = make_stepper(grid)
    before = step(st, sg)
    open_free = np.ones_like(np.asarray(grid.free))
    open_free[0], open_free[-1], open_free[:, 0], open_free[:, -1] = False, False, False, False
    opened = grid.replace(free=open_free)
    assert not np.array_equal(np.asarray(table_of(opened).quads), np.asarray(table_of(grid).quads))
    u_open, _ = dwa_step(st, sg, opened)
    assert _bits(u_open) != _bits(before)  # another map, other tables, another control
    assert _bits(make_stepper(opened)(st, sg)) == _bits(u_open)
    assert _bits(dwa_step(st, sg, grid)[0]) == _bits(before)  # the first map's tables are still its own
    grid.free[8:16, 12] = True  # written into the map's array after the stepper was made
    assert _bits(step(st, sg)) == _bits(before)


def test_speed_limit_layer_is_part_of_the_cached_table():
    free = np.ones((16, 80), bool)
    free[0], free[-1] = False, False
    slow = np.ones(free.shape, np.float32)
    slow[:, 20:50] = 0.4
    grid = jp.grid_from_array(free, resolution=0.1, origin=(5.0, 5.0), speed_limit=slow)
    st, sg = np.array([8.0, 5.8, 0.0, 0.4 * 1.2, 0.0]), np.array([10.5, 5.8])
    assert table_of(grid).speed_limit is not None and table_of(grid) is table_of(grid)
    u = make_stepper(grid)(st, sg)
    assert u[0] <= 0.4 * 1.2 + 1e-6 and _bits(u) == _bits(dwa_step(st, sg, grid)[0])
    fast = grid._replace(speed_limit=np.ones(free.shape, np.float32))  # same free cells, another limit layer
    assert _bits(dwa_step(st, sg, fast)[0]) != _bits(u)
    assert _bits(make_stepper(fast)(st, sg)) == _bits(dwa_step(st, sg, fast)[0])


def test_stepper_repr_is_short():
    assert len(repr(make_stepper(_map()))) < 600


# ---------------------------------------------------------------------------------------------
# MPPI's front


@pytest.mark.parametrize("origin", [(0.0, 0.0), (-3.125, 7.5)])
def test_mppi_lean_front_gives_the_same_control_and_sequence(origin):
    from jaxplan.mppi import MPPIConfig, initial_sequence

    grid = _map(origin)
    (st, sg), = zip(*_states(grid, 1, seed=2), strict=True)
    held = np.asarray(initial_sequence(MPPIConfig(), np.asarray(st, np.float32)))
    u0, info0 = jp.mppi_step(st, sg, grid, sequence=held, key=jax.random.key(5))
    for key in (5, np.int64(5)):  # an int seed becomes the key inside the compiled step
        u, info = jp.mppi_step(st, sg, grid, key=key)  # no sequence: the held velocity, built in numpy
        assert _bits(u) == _bits(u0)
        for name in ("sequence", "costs", "weights", "controls", "chosen"):
            assert _bits(getattr(info, name)) == _bits(getattr(info0, name)), name
        lean, only = jp.mppi_step(st, sg, grid, key=key, full_info=False)
        assert _bits(lean) == _bits(u0) and _bits(only.sequence) == _bits(info0.sequence)
        assert only.costs is None and only.controls is None
    for key in (0, -3, 2 ** 31 - 1):
        a, ia = jp.mppi_step(st, sg, grid, sequence=info0.sequence, key=key)
        b, ib = jp.mppi_step(st, sg, grid, sequence=info0.sequence, key=jax.random.key(key))
        assert _bits(a) == _bits(b) and _bits(ia.costs) == _bits(ib.costs)


def test_mppi_one_robot_program_gives_the_bits_of_the_default_compilation():
    """`mppi_step`'s program, compiled without XLA:CPU's loop split, returns what a plain ``jax.jit`` returns."""
    from jaxplan.mppi import MPPIConfig
    from jaxplan.mppi._step import _on_device, _program
    from jaxplan.mppi._step import validate_params as mppi_params

    grid = _map()
    config = MPPIConfig()
    for full_info in (False, True):
        ours = _program(config, False, False, True, full_info)
        plain = jax.jit(ours.__wrapped__)
        for i, (st, sg) in enumerate(zip(*_states(grid, 4, seed=4), strict=True)):
            st, sg = np.asarray(st, np.float32), np.asarray(sg, np.float32)
            mean = np.broadcast_to(st[3:5], (config.steps, 2)).astype(np.float32)
            args = (table_of(grid), _on_device(mppi_params(None)), st, mean, np.int32(i), sg, sg, None, None)
            a, b = jax.device_get(ours(*args)), jax.device_get(plain(*args))
            assert all(_bits(x) == _bits(y) for x, y in zip(jax.tree_util.tree_leaves(a),
                                                             jax.tree_util.tree_leaves(b), strict=True))
