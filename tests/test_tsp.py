"""TSP mode: TSPLIB reading (every metric and explicit format), tour lengths, the colony solver."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from conftest import manifest
from scipy import stats

from jaxplan.aco._tsp import TourResult, _construct, candidate_lists, solve_tsp, tsp_defaults, two_opt
from jaxplan.aco._tsplib import load_tour, load_tsplib, tour_length

OPTIMA = {"eil51": 426, "berlin52": 7542}
SMALL = {"aco": dict(ants=8, iterations=5), "praco": dict(colonies=2, ants=6, iterations=5)}


@pytest.fixture(scope="module")
def eil51(tsplib):
    return load_tsplib(tsplib / "eil51.tsp")


def _write(tmp_path: Path, name: str, text: str) -> Path:
    p = tmp_path / name
    p.write_text(text.strip() + "\n")
    return p


def _coords_file(tmp_path, metric: str, points, name="pts") -> Path:
    lines = "\n".join(f"{i + 1} {x} {y}" for i, (x, y) in enumerate(points))
    return _write(tmp_path, f"{name}.tsp", f"NAME : {name}\nTYPE : TSP\nDIMENSION : {len(points)}\n"
                                           f"EDGE_WEIGHT_TYPE : {metric}\nNODE_COORD_SECTION\n{lines}\nEOF")


# ---------------------------------------------------------------------------------------------
# Reading.


@pytest.mark.parametrize("name", sorted(OPTIMA))
def test_shared_instances_and_optimal_tours(tsplib, name):
    prob = load_tsplib(tsplib / f"{name}.tsp")
    n = int(next(r["n"] for r in manifest(tsplib) if r["file"] == f"{name}.tsp"))
    assert prob.name == name and prob.n == n and prob.metric == "EUC_2D"
    assert prob.coords.shape == (n, 2) and prob.dist.shape == (n, n) and prob.dist.dtype == np.float64
    np.testing.assert_array_equal(prob.dist, prob.dist.T)
    assert (np.diag(prob.dist) == 0).all() and (prob.dist == np.round(prob.dist)).all()
    tour = load_tour(tsplib / f"{name}.opt.tour")
    assert tour.dtype == np.int64 and tour[0] == 0 and sorted(tour) == list(range(n))
    assert tour_length(prob, tour) == OPTIMA[name]
    # The same tour, reversed and rotated, has the same length.
    assert tour_length(prob, np.roll(tour[::-1], 7)) == OPTIMA[name]


def test_euc_2d_ceil_2d_and_unrounded(tmp_path):
    pts = [(0, 0), (3, 4), (1, 1), (0, 2.5)]
    d = load_tsplib(_coords_file(tmp_path, "EUC_2D", pts)).dist
    # nint: 5 -> 5, sqrt 2 = 1.41 -> 1, 2.5 -> 3 (halves round up), |(3,4)-(0,2.5)| = sqrt 11.25 = 3.35 -> 3.
    assert (d[0, 1], d[0, 2], d[0, 3], d[1, 3]) == (5, 1, 3, 3)
    c = load_tsplib(_coords_file(tmp_path, "CEIL_2D", pts)).dist
    assert (c[0, 1], c[0, 2], c[0, 3], c[1, 3]) == (5, 2, 3, 4)
    e = load_tsplib(_coords_file(tmp_path, "EUC_2D", pts), metric="EUCLIDEAN")
    assert e.metric == "EUCLIDEAN" and e.dist[0, 2] == pytest.approx(math.sqrt(2), abs=1e-15)
    assert load_tsplib(_coords_file(tmp_path, "EUC_2D", pts), metric="ceil_2d").dist[0, 2] == 2


def test_att_pseudo_euclidean(tmp_path):
    # r = sqrt((dx² + dy²) / 10): (10, 0) -> sqrt 10 = 3.16, nint 3 < r -> 4;
    # (30, 40) -> sqrt 250 = 15.81, nint 16 >= r -> 16; (10, 30) -> sqrt 100 = 10 exactly -> 10.
    d = load_tsplib(_coords_file(tmp_path, "ATT", [(0, 0), (10, 0), (30, 40), (10, 30)])).dist
    assert (d[0, 1], d[0, 2], d[0, 3]) == (4, 16, 10)


def test_geo_degrees_minutes(tmp_path):
    # On the equator an arc of Δ degrees is RRR·PI·Δ/180 km (PI = 3.141592, RRR = 6378.388) and
    # TSPLIB takes (int)(arc + 1): 1° -> 111.32 -> 112; 0.30 = 30' = 0.5° -> 55.66 -> 56;
    # -0.30 to 0.30 = 1° -> 112; 0.59 = 59' = 0.9833° -> 109.47 -> 110 (the degree part is
    # truncated: rounding 0.59 to 1° would give 1 − 41/60 of a degree and 36 km).
    d = load_tsplib(_coords_file(tmp_path, "GEO", [(0, 0), (0, 1.0), (0, 0.30), (0, -0.30), (0, 0.59), (1.0, 0)])).dist
    assert (d[0, 1], d[0, 2], d[3, 2], d[0, 4], d[0, 5]) == (112, 56, 112, 110, 112)
    assert (np.diag(d) == 0).all()


ULYSSES16 = """NAME: ulysses16.tsp
TYPE: TSP
COMMENT: Odyssey of Ulysses (Groetschel/Padberg)
DIMENSION: 16
EDGE_WEIGHT_TYPE: GEO
DISPLAY_DATA_TYPE: COORD_DISPLAY
NODE_COORD_SECTION
 1 38.24 20.42
 2 39.57 26.15
 3 40.56 25.32
 4 36.26 23.12
 5 33.48 10.54
 6 37.56 12.19
 7 38.42 13.11
 8 37.52 20.44
 9 41.23 9.10
 10 41.17 13.05
 11 36.08 -5.21
 12 38.47 15.13
 13 38.15 15.35
 14 37.51 15.17
 15 35.49 14.32
 16 39.36 19.56
 EOF
"""


def test_geo_published_optimum(tmp_path):
    """TSPLIB's ulysses16 (GEO) and its optimal tour, whose published length is 6859."""
    prob = load_tsplib(_write(tmp_path, "ulysses16.tsp", ULYSSES16))
    tour = load_tour(_write(tmp_path, "u.opt.tour", "TYPE : TOUR\nDIMENSION : 16\nTOUR_SECTION\n"
                                                    "1 14 13 12 7 6 15 5 11 9 10 16 3 2 4 8\n-1\nEOF"))
    assert prob.metric == "GEO" and tour_length(prob, tour) == 6859


MATRIX = np.array([[0, 1, 2, 3], [1, 0, 4, 5], [2, 4, 0, 6], [3, 5, 6, 0]], float)
SECTIONS = {
    "FULL_MATRIX": "9 1 2 3\n1 9 4 5\n2 4 9 6\n3 5 6 9",  # a sentinel diagonal is ignored
    "UPPER_ROW": "1 2 3\n4 5\n6",
    "LOWER_ROW": "1\n2 4\n3 5 6",
    "UPPER_DIAG_ROW": "0 1 2 3 0 4 5\n0 6 0",  # entries may run across lines freely
    "LOWER_DIAG_ROW": "0\n1 0\n2 4 0\n3 5 6 0",
    "UPPER_COL": "1\n2 4\n3 5 6",  # column-wise = the other triangle row-wise
}


@pytest.mark.parametrize("fmt", sorted(SECTIONS))
def test_explicit_formats(tmp_path, fmt):
    p = _write(tmp_path, "m.tsp", f"NAME: m\nTYPE: TSP\nDIMENSION: 4\nEDGE_WEIGHT_TYPE: EXPLICIT\n"
                                  f"EDGE_WEIGHT_FORMAT: {fmt}\nEDGE_WEIGHT_SECTION\n{SECTIONS[fmt]}\nEOF")
    prob = load_tsplib(p)
    assert prob.metric == "EXPLICIT" and prob.coords is None and prob.n == 4
    np.testing.assert_array_equal(prob.dist, MATRIX)
    assert tour_length(prob, [0, 2, 1, 3]) == 2 + 4 + 5 + 3
    with pytest.raises(ValueError, match="impossible"):
        load_tsplib(p, metric="EUC_2D")


def test_display_data_become_coords(tmp_path):
    p = _write(tmp_path, "d.tsp", "NAME: d\nTYPE: TSP\nDIMENSION: 3\nEDGE_WEIGHT_TYPE: EXPLICIT\n"
                                  "EDGE_WEIGHT_FORMAT: UPPER_ROW\nDISPLAY_DATA_TYPE: TWOD_DISPLAY\n"
                                  "EDGE_WEIGHT_SECTION\n 7 8\n 9\nDISPLAY_DATA_SECTION\n1 0 0\n2 1 0\n3 0 1\nEOF")
    prob = load_tsplib(p)
    np.testing.assert_array_equal(prob.coords, [[0, 0], [1, 0], [0, 1]])
    assert prob.dist[0, 1] == 7 and prob.dist[2, 1] == 9


HEADER = "NAME : bad\nTYPE : TSP\n"


@pytest.mark.parametrize("text, match", [
    (HEADER + "EDGE_WEIGHT_TYPE : EUC_2D\nNODE_COORD_SECTION\n1 0 0\n2 1 1\n3 2 2\nEOF", "missing DIMENSION"),
    (HEADER + "DIMENSION : 3\nEDGE_WEIGHT_TYPE : EUC_2D\nNODE_COORD_SECTION\n1 0 0\n2 1\n3 2 2\nEOF",
     "line 7: .*3 numbers"),
    (HEADER + "DIMENSION : 3\nEDGE_WEIGHT_TYPE : EUC_2D\nNODE_COORD_SECTION\n1 0 0\n2 1 1\nEOF", "missing node 3"),
    (HEADER + "DIMENSION : 3\nEDGE_WEIGHT_TYPE : EUC_2D\nNODE_COORD_SECTION\n1 0 0\n2 1 1\n2 2 2\nEOF",
     "line 8: node 2 listed twice"),
    (HEADER + "DIMENSION : 3\nEDGE_WEIGHT_TYPE : EUC_2D\nNODE_COORD_SECTION\n1 0 0\n2 1 x\n3 2 2\nEOF",
     "line 7: 'x' is not a number"),
    (HEADER + "DIMENSION : 3\nEDGE_WEIGHT_TYPE : MAN_2D\nNODE_COORD_SECTION\n1 0 0\n2 1 1\n3 2 2\nEOF",
     "line 4: unknown EDGE_WEIGHT_TYPE 'MAN_2D'"),
    (HEADER + "DIMENSION : three\nEDGE_WEIGHT_TYPE : EUC_2D\nEOF", "line 3: DIMENSION"),
    (HEADER + "DIMENSION : 3\nEDGE_WEIGHT_TYPE : EUC_2D\nEOF", "needs a NODE_COORD_SECTION"),
    (HEADER + "DIMENSION : 3\nEDGE_WEIGHT_TYPE : EXPLICIT\nEDGE_WEIGHT_FORMAT : UPPER_ROW\n"
              "EDGE_WEIGHT_SECTION\n1 2\nEOF", "needs 3 entries, found 2"),
    (HEADER + "DIMENSION : 3\nEDGE_WEIGHT_TYPE : EXPLICIT\nEDGE_WEIGHT_FORMAT : UPPER_ROW\n"
              "EDGE_WEIGHT_SECTION\n1 -2\n3\nEOF", "line 7: negative edge weight"),
    (HEADER + "DIMENSION : 2\nEDGE_WEIGHT_TYPE : EXPLICIT\nEDGE_WEIGHT_FORMAT : FULL_MATRIX\n"
              "EDGE_WEIGHT_SECTION\n0 1\n2 0\nEOF", "not symmetric"),
    (HEADER + "DIMENSION : 2\nEDGE_WEIGHT_TYPE : EXPLICIT\nEDGE_WEIGHT_FORMAT : FUNCTION\nEOF",
     "unsupported EDGE_WEIGHT_FORMAT"),
    ("NAME : a\nTYPE : ATSP\nDIMENSION : 2\nEDGE_WEIGHT_TYPE : EXPLICIT\nEOF", "line 2: TYPE 'ATSP'"),
    (HEADER + "DIMENSION : 2\nEDGE_WEIGHT_TYPE : EUC_2D\n1 0 0\nEOF", "line 5: data outside a section"),
])
def test_bad_tsplib_files(tmp_path, text, match):
    with pytest.raises(ValueError, match=match):
        load_tsplib(_write(tmp_path, "bad.tsp", text))


def test_bad_metric_and_missing_files(tmp_path, eil51):
    with pytest.raises(FileNotFoundError, match="nope.tsp"):
        load_tsplib(tmp_path / "nope.tsp")
    with pytest.raises(FileNotFoundError, match="nope.opt.tour"):
        load_tour(tmp_path / "nope.opt.tour")
    with pytest.raises(ValueError, match="unknown metric 'MANHATTAN'.*EUC_2D"):
        load_tsplib(_coords_file(tmp_path, "EUC_2D", [(0, 0), (1, 1), (2, 0)]), metric="MANHATTAN")
    for bad in ([0, 1, 1] + list(range(3, 51)), list(range(50)), np.arange(51) + 1, np.arange(51.0)):
        with pytest.raises(ValueError, match="permutation of 0..50"):
            tour_length(eil51, bad)


@pytest.mark.parametrize("section, match", [
    ("1 2 2\n-1", "line 4: the tour is not a permutation of 1..3: node 2 appears twice"),
    ("1 2\n-1", "line 3: the tour is not a permutation of 1..3: TOUR_SECTION lists 2 nodes"),
    ("1 2\n4\n-1", "line 5: .*node 4 outside 1..3"),
    ("1 2 x\n-1", "line 4: tour entry 'x'"),
])
def test_bad_tours(tmp_path, section, match):
    with pytest.raises(ValueError, match=match):
        load_tour(_write(tmp_path, "t.tour", f"TYPE : TOUR\nDIMENSION : 3\nTOUR_SECTION\n{section}\nEOF"))
    with pytest.raises(ValueError, match="no TOUR_SECTION"):
        load_tour(_write(tmp_path, "t.tour", "TYPE : TOUR\nDIMENSION : 3\nEOF"))


# ---------------------------------------------------------------------------------------------
# The solver.


def _check_result(prob, r: TourResult, iterations: int) -> None:
    assert r.tour.dtype == np.int64 and r.tour[0] == 0 and sorted(r.tour.tolist()) == list(range(prob.n))
    assert r.length == tour_length(prob, r.tour)
    assert r.history.shape == (iterations,) and r.history.dtype == np.float64
    assert (np.diff(r.history) <= 0).all() and r.history[-1] == r.length  # integer metric: exact in float32
    assert 0 <= r.info["converged_iteration"] < iterations and r.history[r.info["converged_iteration"]] == r.length
    assert r.time_s > 0 and r.info["compile_s"] >= 0


@pytest.mark.parametrize("planner", sorted(SMALL))
def test_tours_valid_deterministic_and_compiled_once(eil51, planner):
    a = solve_tsp(eil51, planner, seed=3, **SMALL[planner])
    b = solve_tsp(eil51, planner, seed=3, **SMALL[planner])
    _check_result(eil51, a, SMALL[planner]["iterations"])
    np.testing.assert_array_equal(a.tour, b.tour)
    np.testing.assert_array_equal(a.history, b.history)
    assert b.info["compile_s"] == 0.0  # cached program
    # Another seed and other numbers reuse the program too (they are traced, not static).
    c = solve_tsp(eil51, planner, seed=4, rho=0.2, beta=3.0, **SMALL[planner])
    assert c.info["compile_s"] == 0.0
    _check_result(eil51, c, SMALL[planner]["iterations"])
    assert not np.array_equal(a.history, c.history) or not np.array_equal(a.tour, c.tour)


def test_small_explicit_instance_is_solved_exactly(tmp_path):
    """A 6-city explicit instance: the colony finds the optimum found by brute force over all orders."""
    rng = np.random.default_rng(0)
    d = np.triu(rng.integers(1, 50, (6, 6)), 1).astype(float)
    d = d + d.T
    text = "\n".join(" ".join(str(int(v)) for v in row) for row in d)
    prob = load_tsplib(_write(tmp_path, "six.tsp", f"NAME: six\nTYPE: TSP\nDIMENSION: 6\nEDGE_WEIGHT_TYPE: "
                                                   f"EXPLICIT\nEDGE_WEIGHT_FORMAT: FULL_MATRIX\nEDGE_WEIGHT_SECTION\n"
                                                   f"{text}\nEOF"))
    best = min(tour_length(prob, (0,) + p) for p in itertools.permutations(range(1, 6)))
    r = solve_tsp(prob, "praco", seed=0, **SMALL["praco"])
    _check_result(prob, r, SMALL["praco"]["iterations"])
    assert r.length == best


def test_praco_quality_on_eil51(eil51):
    """A short P-RACO run (60 iterations, the paper's 5 x 35 ants) lands within 15 % of the optimum."""
    r = solve_tsp(eil51, "praco", seed=0, iterations=60)
    _check_result(eil51, r, 60)
    assert r.length <= 1.15 * OPTIMA["eil51"]


def test_two_opt_reaches_a_local_optimum(eil51):
    dist = jnp.asarray(eil51.dist, jnp.float32)
    rng = np.random.default_rng(1)
    tours = np.stack([rng.permutation(51) for _ in range(6)]).astype(np.int32)
    out = np.asarray(jax.jit(lambda t: two_opt(dist, t, 400))(jnp.asarray(tours)))
    for before, after in zip(tours, out, strict=True):
        assert sorted(after.tolist()) == list(range(51))
        assert tour_length(eil51, after) < tour_length(eil51, before)
        # No 2-opt move shortens the result.
        d, t = eil51.dist, after
        gains = [d[t[i], t[j]] + d[t[i + 1], t[(j + 1) % 51]] - d[t[i], t[i + 1]] - d[t[j], t[(j + 1) % 51]]
                 for i in range(51) for j in range(i + 2, 51) if not (i == 0 and j == 50)]
        assert min(gains) >= 0
    r = solve_tsp(eil51, "aco", seed=0, local_search="2opt", ants=8, iterations=3)
    _check_result(eil51, r, 3)


def test_construction_samples_the_pheromone_distribution():
    """The inverse-CDF draw picks city j from city i with probability w_ij / Σ w over unvisited j."""
    n, A = 6, 30000
    w = np.array([0.0, 1.0, 0.5, 0.25, 2.0, 0.05])
    weights = jnp.asarray(np.tile(w, (n, 1)), jnp.float32)  # same row for every city
    tours = np.asarray(jax.jit(lambda s: _construct(weights, s, A))(jnp.uint32(7)))
    assert (np.sort(tours, axis=1) == np.arange(n)).all()
    starts = np.bincount(tours[:, 0], minlength=n)
    assert stats.chisquare(starts).pvalue > 1e-3  # start cities uniform
    for s in range(n):
        second = tours[tours[:, 0] == s, 1]
        p = np.where(np.arange(n) == s, 0.0, w)
        seen = np.bincount(second, minlength=n)
        assert seen[p == 0].sum() == 0
        expected = p[p > 0] / p[p > 0].sum() * len(second)
        assert stats.chisquare(seen[p > 0], expected).pvalue > 1e-3


@pytest.mark.parametrize("overrides, match", [
    ({"antz": 5}, r"unknown parameter\(s\) 'antz'; did you mean 'ants'\? \(accepted: alpha, ants, beta"),
    ({"q": 1.0}, "unknown parameter.*'q'"),  # praco has no Q
    ({"ants": 0}, "ants must be a positive integer"),
    ({"colonies": 2.5}, "colonies must be a positive integer"),
    ({"iterations": True}, "iterations must be a positive integer"),
    ({"rho": float("nan")}, "'rho' must be finite"),
    ({"beta": -1.0}, "'beta' must be finite and >= 0"),
    ({"alpha": float("inf")}, "'alpha' must be finite"),
    ({"rho": 1.5}, r"rho must lie in \[0, 1\]"),
    ({"tau0": 0.0}, "'tau0' must be > 0"),
    ({"local_search": "3opt"}, "local_search must be one of"),
    ({"w_rank": "6"}, "'w_rank' must be a number"),
])
def test_bad_overrides(eil51, overrides, match):
    with pytest.raises(ValueError, match=match):
        solve_tsp(eil51, "praco", **overrides)


def test_bad_planner_seed_and_problem(eil51):
    with pytest.raises(ValueError, match=r"unknown TSP planner 'acs'; did you mean 'aco'\? \(accepted: aco, praco\)"):
        solve_tsp(eil51, "acs")
    with pytest.raises(ValueError, match=r"'iteration'; did you mean 'iterations'\?"):
        solve_tsp(eil51, "aco", iteration=3)
    with pytest.raises(ValueError, match="seed"):
        solve_tsp(eil51, "aco", seed=-1)
    with pytest.raises(ValueError, match="n >= 3"):
        solve_tsp(eil51._replace(dist=np.zeros((2, 2))), "aco")
    with pytest.raises(ValueError, match="finite, non-negative"):
        solve_tsp(eil51._replace(dist=-eil51.dist), "aco")
    assert tsp_defaults("praco")["colonies"] == 5 and tsp_defaults("aco")["rho"] == 0.5


# ---------------------------------------------------------------------------------------------
# Candidate lists (ACOTSP's -g) and the construction split over devices.


def test_candidate_lists_are_the_nearest_cities(eil51):
    dist = jnp.asarray(eil51.dist, jnp.float32)
    nn = np.asarray(candidate_lists(dist, 7))
    assert nn.shape == (51, 7) and nn.dtype == np.int32
    for i in range(51):
        assert i not in nn[i]
        # Nearest first, ties by city number; no other city is nearer than the last candidate.
        assert [(eil51.dist[i, j], j) for j in nn[i]] == sorted((eil51.dist[i, j], j) for j in nn[i])
        others = np.setdiff1d(np.arange(51), np.append(nn[i], i))
        assert eil51.dist[i, others].min() >= eil51.dist[i, nn[i][-1]]


@pytest.mark.parametrize("planner", sorted(SMALL))
def test_candidate_tours_valid_and_deterministic(eil51, planner):
    a = solve_tsp(eil51, planner, seed=5, candidates=8, **SMALL[planner])
    b = solve_tsp(eil51, planner, seed=5, candidates=8, **SMALL[planner])
    _check_result(eil51, a, SMALL[planner]["iterations"])
    np.testing.assert_array_equal(a.tour, b.tour)
    np.testing.assert_array_equal(a.history, b.history)
    assert a.info["params"]["candidates"] == 8
    # Longer than n − 1 is the full list in distance order (cut to n − 1: the same program).
    c = solve_tsp(eil51, planner, seed=5, candidates=50, **SMALL[planner])
    d = solve_tsp(eil51, planner, seed=5, candidates=500, **SMALL[planner])
    _check_result(eil51, c, SMALL[planner]["iterations"])
    np.testing.assert_array_equal(c.tour, d.tour)
    assert d.info["compile_s"] == 0.0


def test_candidate_lists_sample_the_pheromone_distribution():
    """With k candidates the second city is drawn among the start's k nearest in proportion to their weights;
    with k = n − 1 that is the full list's distribution (drawn in distance order, so not the same draws)."""
    n, A = 6, 30000
    w = np.array([0.3, 1.0, 0.5, 0.25, 2.0, 0.05])
    weights = jnp.asarray(np.tile(w, (n, 1)), jnp.float32)
    x = np.array([0.0, 1.0, 3.0, 6.0, 10.0, 15.0])
    dist = jnp.asarray(np.abs(x[:, None] - x[None, :]), jnp.float32)
    for k in (2, n - 1):
        nn = candidate_lists(dist, k)
        tours = np.asarray(jax.jit(lambda s, nn=nn: _construct(weights, s, A, None, nn))(jnp.uint32(11)))
        assert (np.sort(tours, axis=1) == np.arange(n)).all()
        for s in range(n):
            second = tours[tours[:, 0] == s, 1]
            p = np.zeros(n)
            p[np.asarray(nn[s])] = w[np.asarray(nn[s])]
            seen = np.bincount(second, minlength=n)
            assert seen[p == 0].sum() == 0
            expected = p[p > 0] / p[p > 0].sum() * len(second)
            assert stats.chisquare(seen[p > 0], expected).pvalue > 1e-3


def test_all_candidates_visited_falls_back_to_the_best_unvisited_city():
    """k = 1 makes the construction deterministic after the start: the nearest city if unvisited, else the
    unvisited city of largest weight, first in city order on ties (ACOTSP's choose_best_next)."""
    rng = np.random.default_rng(3)
    n, A = 9, 40
    pts = rng.random((n, 2))
    dist = np.sqrt(((pts[:, None] - pts[None]) ** 2).sum(-1))
    w = np.round(rng.random((n, n)), 1)  # ties on purpose
    np.fill_diagonal(w, 0.0)
    nn = candidate_lists(jnp.asarray(dist, jnp.float32), 1)
    tours = np.asarray(_construct(jnp.asarray(w, jnp.float32), jnp.uint32(2), A, None, nn))
    for t in tours:
        seen = {int(t[0])}
        for step in range(1, n):
            cur, near = int(t[step - 1]), int(nn[t[step - 1], 0])
            if near not in seen:
                want = near
            else:
                vals = [(w[cur, c], -c) for c in range(n) if c not in seen]
                want = -max(vals)[1]
            assert t[step] == want
            seen.add(want)


@pytest.mark.parametrize("k", [0, -3, 2.5, True, "20"])
def test_bad_candidates(eil51, k):
    with pytest.raises(ValueError, match="candidates must be None"):
        solve_tsp(eil51, "aco", candidates=k)


def test_default_runs_are_unchanged(eil51):
    """The full list (default) gives the tours it gave before candidate lists and device splits existed."""
    r = solve_tsp(eil51, "aco", seed=3, ants=8, iterations=5)
    assert r.length == 522.0 and r.history.tolist() == [566.0, 541.0, 522.0, 522.0, 522.0]
    r = solve_tsp(eil51, "praco", seed=0, colonies=2, ants=6, iterations=5)
    assert r.length == 517.0 and r.history.tolist() == [554.0, 554.0, 517.0, 517.0, 517.0]


def test_construction_split_over_devices_equals_one_device(tsplib):
    """3 host devices, each building a third of the ants' tours: every result equals the one-device run, bit for
    bit (full list, candidate lists, 2-opt, P-RACO's colonies); an uneven split is refused."""
    code = """
        import json
        import numpy as np, jax
        import jaxplan as jp
        from jaxplan.scale import batch_mesh
        prob = jp.load_tsplib(%r)
        out = {"devices": len(jax.devices()), "differ": []}
        for planner, over in (("aco", dict(ants=12, iterations=4)),
                              ("praco", dict(colonies=2, ants=6, iterations=3, candidates=10, local_search="2opt"))):
            a = jp.solve_tsp(prob, planner, seed=7, mesh=None, **over)
            b = jp.solve_tsp(prob, planner, seed=7, mesh=batch_mesh(), **over)
            assert a.info["devices"] == 1 and b.info["devices"] == 3
            if not (np.array_equal(a.tour, b.tour) and np.array_equal(a.history, b.history)):
                out["differ"].append(planner + str(over))
        try:
            jp.solve_tsp(prob, "aco", ants=8, iterations=2, mesh=batch_mesh())
        except ValueError as e:
            out["uneven"] = str(e)
        out["auto"] = jp.solve_tsp(prob, "aco", ants=192, iterations=1).info["devices"]
        out["auto_small"] = jp.solve_tsp(prob, "aco", ants=12, iterations=4).info["devices"]  # cached program
        print(json.dumps(out))
    """
    from test_scale import _child
    out = _child(code % str(tsplib / "eil51.tsp"), devices=3)
    assert out["devices"] == 3 and out["differ"] == []
    assert "8 ants do not split evenly over the mesh's 3 devices" in out["uneven"]
    assert out["auto"] == 3 and out["auto_small"] == 1


def test_candidate_runs_batched_over_seeds_equal_solve_tsp(eil51):
    """An experiment's TSP chunk vmaps `run_tsp` over the seeds' keys with `tsp_config`: same tours as `solve_tsp`."""
    from jaxplan.aco._tsp import TSP_STATIC_PARAMS, resolve_tsp, run_tsp, tsp_config

    p = resolve_tsp("aco", dict(ants=6, iterations=4, candidates=6))
    cfg = tsp_config("aco", p, eil51.n)
    params = {k: jnp.asarray(v, jnp.float32) for k, v in p.items() if k not in TSP_STATIC_PARAMS}
    keys = jax.random.wrap_key_data(jnp.stack([jax.random.key_data(jax.random.key(s)) for s in (2, 9)]))
    out = jax.jit(jax.vmap(lambda k: run_tsp(cfg, jnp.asarray(eil51.dist, jnp.float32), params, k)))(keys)
    for i, s in enumerate((2, 9)):
        r = solve_tsp(eil51, "aco", seed=s, ants=6, iterations=4, candidates=6)
        np.testing.assert_array_equal(np.asarray(out.history[i], np.float64), r.history)
