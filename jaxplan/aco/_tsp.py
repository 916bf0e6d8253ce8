"""TSP mode of the ACO engine: Ant System and P-RACO on a complete graph (docs/guide/planners.md).

A run is one compiled program: `lax.scan` over iterations; inside, all ants of all
sub-colonies build their tours together in a `lax.scan` over the n − 1 construction steps
(tabu as ``bool[A, n]``: n is small here), then the pheromone update reuses the grid
engine's deposit rules (`jaxplan.aco._rules`):

* ``aco`` — Ant System (Dorigo, Maniezzo & Colorni 1996): τ0 = 1, η = 1/d, every ant lays
  Q/L on its tour, τ ← (1 − ρ)·τ + Σ Δτ. Classic AS values: α = 1, β = 5, ρ = 0.5, Q = 100,
  50 ants, 200 iterations.
* ``praco`` — yu2020 (P-RACO), Eq. 8 (choice), Eq. 9 (evaporation), Eq. 10 (deposit): S
  sub-colonies of m ants on a ring. In each colony the w − 1 best ants lay (w − r)/L_r and
  the colony's best-so-far w/L_bs (`deposit_ranked`); colony s also passes its n − 1 best
  ants ((n − q)/L_q) and its best-so-far (n/L_nbs) to colony (s + 1) mod S
  (`deposit_neighbour`). Defaults are the paper's TSP settings: S = 5, m = 35,
  200 iterations; w = 6, n = 3, ρ = 0.3, α = 1, β = 5 (the paper gives no values for these).

Both: pheromone ``f32[S, n, n]`` is symmetric (every deposit goes on both directions),
floored at `TAU_FLOOR`; each ant starts at a uniformly drawn city; the next city is drawn by
inverse CDF with one uniform per ant and step (`hash_uniform`, seeded per iteration from
the run's key with `jax.random.bits`, as in the grid engine). Optional
``local_search="2opt"`` improves every ant's tour with best-improvement 2-opt before the
update (an addition: the paper does not use local search). It is off by default because the
colonies do not need it: without it praco's tours are already close to the optimum on the
TSPLIB instances (``benchmarks/bench_tsp.py``); with it the runs reach the optimum at many
times the run time.

Candidate lists (``candidates=k``, off by default) restrict each choice to the k nearest cities of
the current city that are still unvisited, falling back to the best unvisited city when all k are
visited: ACOTSP's ``-g k`` (Stützle's reference C code for Dorigo & Stützle's *Ant Colony
Optimization*, 2004). That is a change of algorithm, not of speed alone: the papers' settings use
the full list. Large colonies can be split over several host devices (``mesh``; each device builds
its share of the tours), which leaves every result unchanged, bit for bit.

Example::

    import jaxplan as jp
    tsp = jp.load_tsplib("eil51.tsp")
    res = jp.solve_tsp(tsp, planner="praco", seed=0, iterations=100)
    res.tour, res.length          # int64[51] starting at city 0, 426 <= length
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh
from jax.sharding import PartitionSpec as P

from jaxplan.aco import _rules as R
from jaxplan.aco._tsplib import TSPProblem, tour_length
from jaxplan.aco._walk import hash_uniform
from jaxplan.core.cache import Built, memoize
from jaxplan.core.names import did_you_mean
from jaxplan.scale import BATCH_AXIS, Knob, auto_mesh, batch_mesh, check_memory, tsp_memory

__all__ = ["TSP_MIN_ANTS_PER_DEVICE", "TSP_PLANNERS", "TSP_STATIC_PARAMS", "TSPConfig", "TSPOutput", "TourResult",
           "candidate_lists", "resolve_tsp", "run_tsp", "solve_tsp", "tsp_config", "tsp_defaults"]

# The deposit rules of each TSP planner (summed with `R.combine`).
TSP_PLANNERS: dict[str, tuple] = {
    "aco": (R.deposit_inverse,),
    "praco": (R.deposit_ranked, R.deposit_neighbour),
}
_DEFAULTS: dict[str, dict[str, Any]] = {
    "aco": {"ants": 50, "iterations": 200, "alpha": 1.0, "beta": 5.0, "rho": 0.5, "q": 100.0, "tau0": 1.0,
            "local_search": None, "candidates": None},
    "praco": {"colonies": 5, "ants": 35, "iterations": 200, "alpha": 1.0, "beta": 5.0, "rho": 0.3, "w_rank": 6.0,
              "n_exchange": 3.0, "tau0": 1.0, "local_search": None, "candidates": None},
}
TSP_STATIC_PARAMS = ("colonies", "ants", "iterations", "local_search", "candidates")
"""TSP parameters that shape the compiled program; the rest are traced."""
_LOCAL_SEARCH = (None, "2opt")


def tsp_defaults(planner: str) -> dict[str, Any]:
    """A copy of the defaults of TSP planner ``planner`` (``"aco"`` or ``"praco"``)."""
    if planner not in _DEFAULTS:
        raise ValueError(f"unknown TSP planner {planner!r}{did_you_mean(str(planner), _DEFAULTS)} "
                         f"(accepted: {', '.join(_DEFAULTS)})")
    return dict(_DEFAULTS[planner])


@dataclass(frozen=True)
class TSPConfig:
    """Static sizes and switches of a TSP run (changing one recompiles).

    planner: ``"aco"`` or ``"praco"`` (selects the deposit rules); colonies: S; ants: m per
    colony; iterations: I; local_search: None or ``"2opt"``; candidates: None (every unvisited city
    is a choice, the papers' rule) or k, the length of ACOTSP's candidate lists (``-g k``, a change
    of algorithm: see `_construct`).
    """

    planner: str
    colonies: int
    ants: int
    iterations: int
    local_search: str | None = None
    candidates: int | None = None


class TSPOutput(NamedTuple):
    """What `run_tsp` returns (device arrays).

    tour ``i32[n]`` the best tour found (any rotation); length ``f32`` its length;
    history ``f32[I]`` best length so far after each iteration.
    """

    tour: jnp.ndarray
    length: jnp.ndarray
    history: jnp.ndarray


class TourResult(NamedTuple):
    """A solved TSP instance.

    Attributes:
      tour: ``int64[n]`` city order, 0-based, starting at city 0.
      length: closed-tour length (float64 on the host, in the problem's metric).
      history: ``f64[iterations]`` best length so far after each iteration (summed in float32 on
        the device: exact for integer distances, last digits may differ from ``length`` otherwise).
      time_s: run time in seconds, compilation excluded.
      info: ``compile_s`` (0 when the program was cached), ``converged_iteration`` (first
        iteration whose best equals the final best), ``planner`` and the resolved ``params``.
    """

    tour: np.ndarray
    length: float
    history: np.ndarray
    time_s: float
    info: dict[str, Any]


def candidate_lists(dist: jnp.ndarray, k: int) -> jnp.ndarray:
    """``i32[n, k]`` the k nearest other cities of every city, nearest first (ties: lower city number).

    ACOTSP's ``nn_list`` (`compute_nn_lists` in ACOTSP 1.03's ``utilities.c``/``TSP.c``): the candidate
    lists of its ``-g`` option. ``dist`` is ``f32[n, n]``; ``1 <= k <= n - 1``.
    """
    n = dist.shape[0]
    # A city is never its own candidate: its diagonal sorts last.
    key = jnp.where(jnp.eye(n, dtype=bool), jnp.inf, dist)
    return jnp.argsort(key, axis=1, stable=True)[:, :k].astype(jnp.int32)


def _construct(weights: jnp.ndarray, seed: jnp.ndarray, m: int, ant: jnp.ndarray | None = None,
               nn: jnp.ndarray | None = None) -> jnp.ndarray:
    """Builds the tours of the ants ``ant`` (all ants by default) at once.

    Args:
      weights: ``f32[S * n, n]`` move weights τ^α·η^β of each colony's city rows, row-normalised.
      seed: ``u32`` the iteration's seed; ant ``a`` uses uniform ``hash_uniform(seed, t, a)`` at step t
        (t = 0 draws its start city).
      m: ants per colony (ant ``a`` belongs to colony ``a // m``).
      ant: ``i32[B]`` the (global) numbers of the ants to build, e.g. one device's share of a sharded
        colony; None: all ``S * m`` ants. An ant's tour depends only on its own number, not on ``B``.
      nn: None (the full list: every unvisited city is a choice, the papers' rule) or ``i32[n, k]``
        candidate lists (`candidate_lists`): ACOTSP's ``-g k`` rule, a change of algorithm. The next
        city is drawn among the unvisited candidates of the current city in proportion to their
        weights; when all k are visited, the ant takes the unvisited city of largest weight (first in
        city order on ties) — ``neighbour_choose_and_move_to_next`` and ``choose_best_next`` in ACOTSP
        1.03's ``ants.c``; a draw that float32 rounding pushes onto a visited candidate takes the best
        unvisited candidate (its ``neighbour_choose_best_next``).

    Returns:
      ``i32[B, n]`` tours (city order).
    """
    n = weights.shape[1]
    if ant is None:
        ant = jnp.arange(weights.shape[0] // n * m)
    row0 = (ant // m) * n
    cities = jnp.arange(n, dtype=jnp.int32)
    width = n if nn is None else nn.shape[1]
    slots = jnp.arange(width, dtype=jnp.int32)
    # Prefix sums as a product with a triangular matrix: on a CPU, XLA's cumsum over a minor axis
    # of 51 costs several times more than this small matmul (and argmax more than a count).
    upper = (slots[:, None] <= slots[None, :]).astype(jnp.float32)
    start = jnp.minimum(hash_uniform(seed, jnp.uint32(0), ant) * n, n - 1).astype(jnp.int32)
    # A minimum-normal floor keeps unvisited cities drawable when all their weights underflowed.
    tiny = jnp.finfo(jnp.float32).tiny
    flat = weights.reshape(-1)

    def best_unvisited(pos, visited):
        """The unvisited city of largest weight, first in city order on ties (ACOTSP's choose_best_next)."""
        w = jnp.where(visited, -1.0, weights[row0 + pos])
        return jnp.min(jnp.where(w == jnp.max(w, axis=1, keepdims=True), cities, n), axis=1).astype(jnp.int32)

    def best_candidate(p, choice):
        """The unvisited candidate of largest weight, first in list order on ties (ACOTSP's
        neighbour_choose_best_next, for a draw that rounding pushed past the last candidate)."""
        first = jnp.min(jnp.where(p == jnp.max(p, axis=1, keepdims=True), slots, width), axis=1)
        return jnp.take_along_axis(choice, first[:, None], axis=1)[:, 0]

    def step(carry, t):
        pos, visited = carry
        if nn is None:
            choice, taken = cities, visited
            p = jnp.where(visited, 0.0, weights[row0 + pos] + tiny)  # [B, n]
        else:
            choice = nn[pos]  # [B, k] the current city's candidates
            taken = jnp.take_along_axis(visited, choice, axis=1)
            p = jnp.where(taken, 0.0, flat[(row0 + pos)[:, None] * n + choice] + tiny)
        cum = jnp.matmul(p, upper, precision=jax.lax.Precision.HIGHEST)  # full f32 on accelerators too
        threshold = (hash_uniform(seed, t, ant) * cum[:, -1])[:, None]
        # Inverse CDF: the first slot whose cumulative weight exceeds u·Σp. With monotone prefix
        # sums that slot has p > 0, so it is unvisited; u < 1 keeps u·Σp below Σp.
        slot = jnp.minimum(jnp.sum(cum <= threshold, axis=1, dtype=jnp.int32), width - 1)
        # Guard for prefix sums that are not monotone in float32 (the matmul's summation order is
        # XLA's choice), and with candidate lists for ants whose candidates are all visited (Σp = 0):
        # such an ant takes another unvisited city. Costs nothing unless hit.
        bad = jnp.take_along_axis(taken, slot[:, None], axis=1)[:, 0]
        nxt = jnp.take_along_axis(choice, slot[:, None], axis=1)[:, 0] if nn is not None else slot
        if nn is None:  # the highest-numbered unvisited city (as before candidate lists existed)
            other = lambda: jnp.max(jnp.where(visited, -1, cities), axis=1)  # noqa: E731
        else:  # ACOTSP: the best unvisited city if all candidates are visited (common), else the best candidate (rare)
            rounded = bad & (cum[:, -1] > 0)
            other = lambda: jax.lax.cond(  # noqa: E731
                jnp.any(rounded), lambda: jnp.where(rounded, best_candidate(p, choice), best_unvisited(pos, visited)),
                lambda: best_unvisited(pos, visited))
        nxt = jax.lax.cond(jnp.any(bad), lambda: jnp.where(bad, other(), nxt), lambda: nxt)
        return (nxt, visited | (cities[None, :] == nxt[:, None])), nxt

    visited0 = cities[None, :] == start[:, None]
    _, path = jax.lax.scan(step, (start, visited0), jnp.arange(1, n, dtype=jnp.uint32))
    return jnp.concatenate([start[:, None], path.T], axis=1)


def _lengths(dist: jnp.ndarray, tours: jnp.ndarray) -> jnp.ndarray:
    """``f32[P]`` closed-tour lengths of ``tours [P, n]``."""
    return jnp.sum(dist[tours, jnp.roll(tours, -1, axis=1)], axis=1)


def two_opt(dist: jnp.ndarray, tours: jnp.ndarray, max_passes: int) -> jnp.ndarray:
    """Best-improvement 2-opt of every tour at once, until no tour improves (or ``max_passes``).

    Each pass evaluates all ``n (n − 3) / 2`` moves of every tour as one ``[P, n, n]`` array:
    with ``D[i, j] = d(t_i, t_j)`` (the distance matrix in tour order), removing edges
    (t_i, t_i+1), (t_j, t_j+1) and adding (t_i, t_j), (t_i+1, t_j+1) changes the length by
    ``D[i, j] + D[i+1, j+1] − D[i, i+1] − D[j, j+1]``; the best move (if it shortens the tour)
    reverses positions i+1..j.

    Args:
      dist: ``f32[n, n]``; tours: ``i32[P, n]``; max_passes: static cap on passes.

    Returns:
      ``i32[P, n]`` improved tours.
    """
    n = tours.shape[1]
    i = jnp.arange(n)
    allowed = (i[None, :] > i[:, None] + 1) & ~((i[:, None] == 0) & (i[None, :] == n - 1))
    # Float32 sums of four distances carry rounding noise; smaller "gains" are not moves.
    eps = 1e-5 * jnp.max(dist)

    flat_dist = dist.reshape(-1)
    move = jnp.arange(n * n, dtype=jnp.int32)

    def body(carry):
        tours, k, _ = carry
        D = flat_dist[tours[:, :, None] * n + tours[:, None, :]]  # [P, n, n]
        D1 = jnp.roll(D, -1, axis=(1, 2))  # D1[i, j] = D[i+1, j+1]
        edge = dist[tours, jnp.roll(tours, -1, axis=1)]  # [P, n]: d(t_i, t_i+1)
        delta = jnp.where(allowed, D + D1 - edge[:, :, None] - edge[:, None, :], jnp.inf).reshape(-1, n * n)
        # min, then the first index attaining it: two plain reductions (argmin is slow on a CPU).
        best = jnp.min(delta, axis=1)
        flat = jnp.min(jnp.where(delta == best[:, None], move, n * n), axis=1)
        better = best < -eps
        a, b = (flat // n)[:, None], (flat % n)[:, None]
        inside = (i[None, :] > a) & (i[None, :] <= b) & better[:, None]
        tours = jnp.take_along_axis(tours, jnp.where(inside, a + b + 1 - i[None, :], i[None, :]), axis=1)
        return tours, k + 1, jnp.any(better)

    tours, _, _ = jax.lax.while_loop(lambda c: (c[1] < max_passes) & c[2], body, (tours, 0, jnp.bool_(True)))
    return tours


def run_tsp(cfg: TSPConfig, dist: jnp.ndarray, params: dict, key: jax.Array, shards: int = 1) -> TSPOutput:
    """One TSP run: ``cfg.iterations`` iterations of ``cfg.colonies × cfg.ants`` ants.

    Pure and jittable with ``cfg`` static. With ``shards > 1`` it must run inside `jax.shard_map` over
    a mesh with axis `jaxplan.scale.BATCH_AXIS` of that many devices, every argument and the output
    replicated: each device builds (and 2-opts) its ``1 / shards`` of the ants' tours, the tours are
    gathered, and every device does the rest (lengths, update) on all of them. An ant's tour depends
    only on its number, and the update sees the same tours in the same order, so the result is the
    single-device one, bit for bit.

    Args:
      cfg: static configuration.
      dist: ``f32[n, n]`` symmetric distances.
      params: dict of ``f32`` scalars (``alpha``, ``beta``, ``rho``, ``tau0``, and the deposit
        rules' ``q`` or ``w_rank``/``n_exchange``).
      key: the run's PRNG key.
      shards: devices the ants are split over (a static divisor of ``S * m``).

    Returns:
      `TSPOutput`.
    """
    S, m, I = cfg.colonies, cfg.ants, cfg.iterations
    if (S * m) % shards:
        raise ValueError(f"{S * m} ants do not split evenly over {shards} devices")
    B = S * m // shards  # ants per device
    cand = None if cfg.candidates is None else candidate_lists(dist, cfg.candidates)
    n = dist.shape[0]
    nn = n * n
    eye = jnp.eye(n, dtype=bool)
    # η = 1/d; coincident cities (d = 0) get a finite, very attractive η instead of inf.
    d_floor = 1e-6 * jnp.maximum(jnp.max(dist), 1e-30)
    log_eta = jnp.where(eye, -jnp.inf, -jnp.log(jnp.maximum(dist, d_floor)))
    colony_of = jnp.repeat(jnp.arange(S), m)  # [A]
    nxt = (jnp.arange(S) + 1) % S  # ring: colony s passes to colony s + 1
    deposits = TSP_PLANNERS[cfg.planner]

    def iteration(state, seed):
        tau, bs_tour, bs_len = state
        # Weights in log space, normalised per row (max 1): τ^α·η^β neither overflows nor needs exp in the steps.
        logits = params["alpha"] * jnp.log(jnp.maximum(tau, R.TAU_FLOOR)) + params["beta"] * log_eta
        weights = jnp.exp(logits - jnp.max(logits, axis=2, keepdims=True))
        ant = jnp.arange(B) if shards == 1 else jax.lax.axis_index(BATCH_AXIS) * B + jnp.arange(B)
        tours = _construct(weights.reshape(S * n, n), seed, m, ant, cand)
        if cfg.local_search == "2opt":
            tours = two_opt(dist, tours, max_passes=4 * n)
        if shards > 1:
            tours = jax.lax.all_gather(tours, BATCH_AXIS, tiled=True)  # [S * m, n] in ant order
        lengths = _lengths(dist, tours).reshape(S, m)
        best = jnp.argmin(lengths, axis=1)
        it_len = lengths[jnp.arange(S), best]
        better = it_len < bs_len
        bs_tour = jnp.where(better[:, None], tours[jnp.arange(S) * m + best], bs_tour)
        bs_len = jnp.where(better, it_len, bs_len)
        # Eq. 10 (or Q/L): amounts for own ants, ants passed on, and best-so-far tours.
        dep = R.without_exchange(R.combine(deposits, lengths, bs_len, params), S)
        parts = [(tours, colony_of, dep.own), (tours, nxt[colony_of], dep.nbr),
                 (bs_tour, jnp.arange(S), dep.bs_own), (bs_tour, nxt, dep.bs_nbr)]
        parts = [(t, c, a.ravel()) for t, c, a in parts if a is not None]
        t_all = jnp.concatenate([p[0] for p in parts])
        idx = jnp.concatenate([p[1] for p in parts])[:, None] * nn + t_all * n + jnp.roll(t_all, -1, axis=1)
        amount = jnp.concatenate([p[2] for p in parts])
        delta = jnp.zeros(S * nn, jnp.float32).at[idx.ravel()].add(jnp.repeat(amount, n)).reshape(S, n, n)
        # One scatter for one direction, then the transpose: the pheromone stays symmetric.
        tau = R.bound_floor((1.0 - params["rho"]) * tau + delta + jnp.swapaxes(delta, 1, 2), params)
        return (tau, bs_tour, bs_len), jnp.min(bs_len)

    state0 = (
        jnp.full((S, n, n), 1.0, jnp.float32) * params["tau0"],
        jnp.zeros((S, n), jnp.int32),
        jnp.full((S,), jnp.inf, jnp.float32),
    )
    # One u32 seed per iteration, drawn from the run's key in a single threefry call (cheaper to
    # compile than splitting I keys); the step uniforms are hashed from it.
    seeds = jax.random.bits(key, (I,), jnp.uint32)
    (_, bs_tour, bs_len), history = jax.lax.scan(iteration, state0, seeds)
    b = jnp.argmin(bs_len)
    return TSPOutput(bs_tour[b], bs_len[b], history)


def _compiled(cfg: TSPConfig, dist: jnp.ndarray, params: dict, key: jax.Array,
              mesh: Mesh | None = None) -> tuple[Any, float]:
    """The compiled run for these static sizes, and the seconds spent compiling it now (0 if cached): programs
    are kept by (config, n, parameter names, mesh), so a call's time_s excludes its one-off compilation.
    With a ``mesh``, the ants are split over its devices (`run_tsp`'s ``shards``)."""
    return _program(cfg, dist, params, key, mesh).take()


@memoize(maxsize=16, key=lambda cfg, dist, params, key, mesh: (cfg, dist.shape, tuple(sorted(params)), mesh))
def _program(cfg: TSPConfig, dist: jnp.ndarray, params: dict, key: jax.Array, mesh: Mesh | None) -> Built:
    if mesh is None:
        body = lambda d, p, k: run_tsp(cfg, d, p, k)  # noqa: E731
    else:
        # check_vma=False: the gathered tours are the same on every device, which the varying-axes
        # check cannot see through all_gather inside the scan.
        body = jax.shard_map(lambda d, p, k: run_tsp(cfg, d, p, k, shards=mesh.devices.size), mesh=mesh,
                             in_specs=(P(), P(), P()), out_specs=P(), check_vma=False)
    return Built.timed(lambda: jax.jit(body).lower(dist, params, key).compile())


def tsp_config(planner: str, p: dict[str, Any], n: int) -> TSPConfig:
    """The static configuration of a run of ``planner`` with resolved parameters ``p`` (`resolve_tsp`) on ``n``
    cities (a candidate list longer than n − 1 is the full list in distance order: it is cut to n − 1)."""
    k = None if p["candidates"] is None else min(int(p["candidates"]), n - 1)
    return TSPConfig(planner, int(p.get("colonies", 1)), int(p["ants"]), int(p["iterations"]), p["local_search"], k)


def resolve_tsp(planner: str, overrides: dict[str, Any]) -> dict[str, Any]:
    """The parameters of TSP planner ``planner``: its defaults with ``overrides`` applied, checked (``ValueError``)."""
    p = tsp_defaults(planner)
    unknown = sorted(set(overrides) - set(p))
    if unknown:
        named = "; ".join(f"{k!r}{did_you_mean(str(k), p)}" for k in unknown)
        raise ValueError(f"TSP planner {planner!r}: unknown parameter(s) {named} (accepted: {', '.join(sorted(p))})")
    p.update(overrides)
    for k in ("colonies", "ants", "iterations"):
        if k in p and (not isinstance(p[k], (int, np.integer)) or isinstance(p[k], bool) or p[k] < 1):
            raise ValueError(f"TSP planner {planner!r}: {k} must be a positive integer, got {p[k]!r}")
    k = p["candidates"]
    if k is not None and (not isinstance(k, (int, np.integer)) or isinstance(k, bool) or k < 1):
        raise ValueError(f"TSP planner {planner!r}: candidates must be None (the full list) or a positive integer, "
                         f"got {k!r}")
    if p["local_search"] not in _LOCAL_SEARCH:
        raise ValueError(f"TSP planner {planner!r}: local_search must be one of {_LOCAL_SEARCH}, "
                         f"got {p['local_search']!r}")
    for k, v in p.items():
        if k in TSP_STATIC_PARAMS:
            continue
        try:  # a Python or numpy number, or a 0-d array (e.g. a jax scalar from a tuning loop)
            x = None if isinstance(v, (bool, str)) or np.ndim(v) != 0 else float(v)
        except TypeError:
            x = None
        if x is None:
            raise ValueError(f"TSP planner {planner!r}: parameter {k!r} must be a number, got {v!r}")
        if not math.isfinite(x) or x < 0:
            raise ValueError(f"TSP planner {planner!r}: parameter {k!r} must be finite and >= 0, got {v!r}")
    if p["rho"] > 1:
        raise ValueError(f"TSP planner {planner!r}: rho must lie in [0, 1], got {p['rho']!r}")
    for k in ("q", "tau0"):
        if k in p and not p[k] > 0:
            raise ValueError(f"TSP planner {planner!r}: parameter {k!r} must be > 0, got {p[k]!r}")
    return p




TSP_MIN_ANTS_PER_DEVICE = 64
"""``mesh="auto"`` splits a TSP colony only if every device builds at least this many ants' tours: each
iteration then gathers the tours from the devices, which costs more than it saves for small colonies."""


def _ant_mesh(mesh: Any, ants: int) -> Mesh | None:
    """The mesh `solve_tsp` splits ``ants`` over (see its ``mesh``); ``ValueError`` if they do not split evenly."""
    if isinstance(mesh, str) and mesh == "auto":
        local = jax.local_devices()
        d = len(local)
        return batch_mesh(local) if d > 1 and ants % d == 0 and ants >= TSP_MIN_ANTS_PER_DEVICE * d else None
    mesh = auto_mesh(mesh, ants)  # None, or a checked Mesh (a bad value raises)
    if mesh is not None and ants % mesh.devices.size:
        raise ValueError(f"{ants} ants do not split evenly over the mesh's {mesh.devices.size} devices")
    return mesh


def solve_tsp(problem: TSPProblem, planner: str = "praco", seed: int = 0, *, mesh: Mesh | str | None = "auto",
              **overrides: Any) -> TourResult:
    """Solves a symmetric TSP with an ant colony.

    Args:
      problem: a `TSPProblem` (``dist f64[n, n]``, n >= 3), e.g. from `load_tsplib`.
      planner: ``"praco"`` (yu2020, default) or ``"aco"`` (Ant System); see the module docstring.
      seed: integer in [0, 2**32); the same seed gives the same result, bit for bit.
      mesh: ``"auto"`` (default), None or a `jax.sharding.Mesh` (`jaxplan.scale.batch_mesh`): the
        devices the ants' tour construction is split over. ``"auto"`` uses every local device when
        there are several (`jaxplan.use_host_devices`), the ants split evenly over them and each gets
        at least `TSP_MIN_ANTS_PER_DEVICE`; else one device. The result does not depend on it, bit for
        bit (`run_tsp`); only the time does.
      **overrides: ``ants`` (per colony), ``iterations``, ``alpha``, ``beta``, ``rho``, ``tau0``,
        ``local_search`` (None or ``"2opt"``), ``candidates`` (None: the full list, the papers' rule;
        k: ACOTSP's candidate lists of the k nearest cities, a change of algorithm, see `_construct`;
        k >= n − 1 is the full list drawn in distance order, the same distribution but not the same
        draws), and ``q`` (aco) or ``colonies``, ``w_rank``, ``n_exchange`` (praco). `tsp_defaults`
        lists them with their defaults.

    Returns:
      `TourResult`.

    Raises:
      ValueError: unknown planner or parameter, a parameter that is NaN, infinite, negative or
        out of range, zero ants, a bad ``candidates``, a bad seed, a mesh the ants do not split
        evenly over, or a distance matrix that is not a finite, non-negative ``[n, n]`` array with n >= 3.
    """
    if planner not in TSP_PLANNERS:
        raise ValueError(f"unknown TSP planner {planner!r}{did_you_mean(str(planner), TSP_PLANNERS)} "
                         f"(accepted: {', '.join(TSP_PLANNERS)})")
    p = resolve_tsp(planner, overrides)
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or not 0 <= seed < 2**32:
        raise ValueError(f"seed must be an integer in [0, 2**32), got {seed!r}")
    d = np.asarray(problem.dist, np.float64)
    if d.ndim != 2 or d.shape[0] != d.shape[1] or d.shape[0] < 3:
        raise ValueError(f"problem.dist must be a square [n, n] matrix with n >= 3, got shape {d.shape}")
    if not np.all(np.isfinite(d)) or np.any(d < 0):
        raise ValueError("problem.dist must hold finite, non-negative distances")
    cfg = tsp_config(planner, p, d.shape[0])
    mesh = _ant_mesh(mesh, cfg.colonies * cfg.ants)
    est = lambda ants: tsp_memory(d.shape[0], cfg.colonies, ants, cfg.iterations, 1,  # noqa: E731
                                  local_search=cfg.local_search == "2opt")
    check_memory(est(cfg.ants), f"TSP planner {planner!r} with {cfg.colonies * cfg.ants} ants on {d.shape[0]} cities",
                 unit="runs", knob=Knob("ants" if cfg.colonies == 1 else "ants per colony", cfg.ants, est))
    params = {k: jnp.asarray(v, jnp.float32) for k, v in p.items() if k not in TSP_STATIC_PARAMS}
    dist = jnp.asarray(d, jnp.float32)
    key = jax.random.key(int(seed))
    fn, compile_s = _compiled(cfg, dist, params, key, mesh)
    t0 = time.perf_counter()
    out = jax.block_until_ready(fn(dist, params, key))
    time_s = time.perf_counter() - t0
    tour = np.asarray(out.tour, np.int64)
    tour = np.roll(tour, -int(np.flatnonzero(tour == 0)[0]))
    history = np.asarray(out.history, np.float64)
    return TourResult(
        tour=tour,
        length=tour_length(problem, tour),  # float64 on the host (the device sums in float32)
        history=history,
        time_s=time_s,
        info={"compile_s": compile_s, "converged_iteration": int(np.argmax(history <= history[-1])),
              "planner": planner, "params": p, "devices": 1 if mesh is None else mesh.devices.size},
    )
