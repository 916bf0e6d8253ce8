"""benchmarks/bench_falsify.py at a tiny budget: genomes make walkers within bounds, an adversary the search found
hits a robot without passive safety and not one with it, and the search itself runs with one compiled call per
generation and finds no active contact in passive mode."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest
from conftest import load_benchmark


@pytest.fixture(scope="module")
def bench():
    return load_benchmark("bench_falsify")


def test_genomes_make_walkers_in_the_hall_no_faster_than_the_bound(bench):
    grid = bench.hall()
    box = bench.route_box(grid)
    genomes = jnp.asarray(np.random.default_rng(0).uniform(-0.5, 1.5, (5, 3 * bench.GENES)), jnp.float32)
    obs = bench.walkers_of(genomes, box, 1.5)
    assert obs.waypoints.shape == (5, 3, bench.VERTICES, 2) and obs.speeds.shape == (5, 3)
    wp = np.asarray(obs.waypoints)
    assert np.all(wp >= np.asarray(box[:2]) - 1e-6) and np.all(wp <= np.asarray(box[2:]) + 1e-6)
    assert np.all((np.asarray(obs.speeds) >= 0) & (np.asarray(obs.speeds) <= 1.5))
    assert np.asarray(obs.speeds).max() == pytest.approx(1.5)  # genes outside [0, 1] are clipped to the bound


def test_the_found_adversary_hits_only_a_robot_without_passive_safety(bench):
    plain = bench.replay(bench.FOUND_DWA, "dwa", "none")
    assert plain.reason == "collision" and plain.active_contacts == 1
    assert abs(float(plain.controls[-1, 0])) > 1.0  # at speed
    safe = bench.replay(bench.FOUND_DWA, "dwa", "passive")
    assert safe.active_contacts == 0
    if safe.reason == "collision":
        assert abs(float(safe.controls[-1, 0])) <= bench.ACTIVE_SPEED


def test_a_tiny_search_finds_no_active_contact_in_passive_mode(bench):
    r = bench.search("dwa", "passive", population=4, generations=2, max_time=15.0, x0=bench.FOUND_DWA, sigma=0.05,
                     verbose=False)
    assert r["episodes"] == 8 and len(r["per_generation"]) == 2
    assert r["active_episodes"] == 0 and r["max_contact_speed"] <= bench.ACTIVE_SPEED and r["found"] == []
