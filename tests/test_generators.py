"""Generators: deterministic, published sizes and counts, connected start and goal."""

from __future__ import annotations

import jax
import numpy as np
import pytest

import jaxplan as jp

GENERATORS = {
    "chen2023": jp.warehouse_chen2023,
    "yu2020_30": lambda k: jp.warehouse_yu2020(k, 30),
    "yu2020_35": lambda k: jp.warehouse_yu2020(k, 35),
    "random20": jp.RandomMapGenerator(32, 32, 0.2),
    "urban": jp.UrbanGenerator(),
    "mountain": jp.MountainGenerator(),
}


def _same(a: jp.Scene, b: jp.Scene) -> bool:
    la, lb = jax.tree_util.tree_leaves(a.grid), jax.tree_util.tree_leaves(b.grid)
    return all(np.array_equal(x, y) for x, y in zip(la, lb, strict=True)) and np.array_equal(a.start, b.start)


@pytest.mark.parametrize("name", sorted(GENERATORS))
def test_generators_deterministic_and_connected(name):
    gen = GENERATORS[name]
    a, b, c = gen(3), gen(3), gen(4)
    assert _same(a, b)
    assert not np.array_equal(a.grid.free, c.grid.free) or not np.array_equal(a.grid.height, c.grid.height) \
        or not np.array_equal(a.grid.turn_rule, c.grid.turn_rule) or name == "chen2023"
    r = jp.plan(a.grid, a.start, a.goal)
    assert r.success


def test_jax_keys_work_like_seeds():
    k = jax.random.key(5)
    a = jp.RandomMapGenerator(16, 16, 0.3)(k)
    b = jp.RandomMapGenerator(16, 16, 0.3)(jax.random.key(5))
    assert _same(a, b)
    with pytest.raises(TypeError, match="PRNG key or an integer seed"):
        jp.RandomMapGenerator(16, 16, 0.3)("five")


def test_yu2020_blocked_counts_are_exact():
    for key in range(3):
        assert (~jp.warehouse_yu2020(key, 30).grid.free).sum() == 200
        assert (~jp.warehouse_yu2020(key, 35).grid.free).sum() == 400
    with pytest.raises(ValueError, match="yu2020 uses sizes 30 and 35"):
        jp.warehouse_yu2020(0, 40)
    with pytest.raises(ValueError, match="exceeds the"):
        jp.WarehouseGenerator(10, 10, n_blocked=90)(0)


def test_chen2023_combined_shelves():
    g = jp.warehouse_chen2023(0).grid
    assert g.shape == (20, 20)
    blocked = ~g.free
    # Every shelf is a run of six cells, two rows deep.
    for y in np.nonzero(blocked.any(axis=1))[0]:
        runs = np.diff(np.flatnonzero(np.diff(np.r_[0, blocked[y].astype(int), 0])))[::2]
        assert (runs == 6).all()


@pytest.mark.parametrize("ratio", [0.1, 0.2, 0.3, 0.4, 0.6])
def test_random_map_ratio_exact_and_connected(ratio):
    for key in range(4):
        s = jp.RandomMapGenerator(24, 24, ratio)(key)
        assert (~s.grid.free).sum() == round(ratio * (24 * 24 - 2))
        assert jp.plan(s.grid, s.start, s.goal).success
    with pytest.raises(ValueError, match="obstacle_ratio"):
        jp.RandomMapGenerator(8, 8, 0.95)


def test_urban_layers():
    s = jp.UrbanGenerator()(1)
    g = s.grid
    idx = np.arange(20)
    street = (idx % 6) < 2
    crossing = street[None, :] & street[:, None]
    assert g.turn_rule.any() and not g.turn_rule[~crossing].any()
    assert g.free[s.dynamic_slots[:, 1], s.dynamic_slots[:, 0]].all()
    assert len(s.dynamic_slots) == 3


def test_mountain_tunnel_passes_low_vehicle_only():
    s = jp.MountainGenerator()(2)
    ch = s.grid.clearance_height
    tunnel = np.isfinite(ch) & s.grid.free
    assert tunnel.sum() >= 5 and ((ch[tunnel] > 0.5) & (ch[tunnel] < 1.45)).all()
    assert s.grid.height.max() == pytest.approx(10.0)


def test_poisson_risk_layer():
    g = jp.grid_from_array(np.ones((60, 60), bool).__and__(np.arange(60)[None, :] % 7 != 3))
    a = jp.poisson_risk(g, 0, lam=1.0)
    b = jp.poisson_risk(g, 0, lam=1.0)
    np.testing.assert_array_equal(a.risk, b.risk)
    assert (a.risk[~g.free] == 0).all()
    assert abs(a.risk[g.free].mean() - 1.0) < 0.1
    assert jp.poisson_risk(g, jax.random.key(1), lam=0.01).risk.mean() < 0.05
    with pytest.raises(ValueError, match="lam must be finite and >= 0"):
        jp.poisson_risk(g, 0, lam=-1)


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: jp.WarehouseGenerator(n_blocked=-5),
         r"WarehouseGenerator.n_blocked must be None or an integer >= 0, got -5"),
        (lambda: jp.WarehouseGenerator(n_blocked=2.5), r"n_blocked must be None or an integer >= 0, got 2.5"),
        (lambda: jp.UrbanGenerator(n_interventions=1000),
         r"UrbanGenerator.n_interventions must be an integer in \[0, 192\].*got 1000"),
        (lambda: jp.UrbanGenerator(n_interventions=-1), r"n_interventions must be an integer in \[0, 192\]"),
        (lambda: jp.UrbanGenerator(n_dynamic=-1), r"UrbanGenerator.n_dynamic must be an integer in \[0, 248\].*got -1"),
        (lambda: jp.UrbanGenerator(n_interventions=0, n_dynamic=255), r"n_dynamic must be an integer in \[0, 254\]"),
        (lambda: jp.UrbanGenerator(park_prob=1.5), r"UrbanGenerator.park_prob must be in \[0, 1\], got 1.5"),
    ],
)
def test_generator_counts_are_validated_up_front(make, match):
    # Refused when the generator is made, not with a numpy error at the first draw.
    with pytest.raises(ValueError, match=match):
        make()


def test_urban_counts_at_their_limits_draw():
    scene = jp.UrbanGenerator(n_interventions=0, n_dynamic=254)(0)
    assert len(scene.dynamic_slots) == 254
    assert jp.UrbanGenerator(n_dynamic=0)(0).dynamic_slots.shape == (0, 2)


@pytest.mark.parametrize("old,new", [("warehouse_seed003", "warehouse_chen2023"),
                                     ("warehouse_seed004", "warehouse_yu2020")])
def test_old_generator_names_warn_and_still_work(old, new):
    with pytest.warns(DeprecationWarning, match=new):
        fn = getattr(jp, old)
    assert fn is getattr(jp, new)
