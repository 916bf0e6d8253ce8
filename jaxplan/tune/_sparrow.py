"""Sparrow search: the plain SSA (Xue & Shen 2020) and li2026's improved ISSA, as `Strategy` objects.

A population of ``P`` sparrows keeps personal-best positions ``X`` and fitness ``F``. Per
generation, ranked by fitness, the best ``pd·P`` are *producers* (leaders), the rest
*scroungers* (followers), and a random ``sd·P`` also act as *sentinels*; all three rules are
applied from the previous generation's ranking, the whole new population is evaluated in
ONE call, and each sparrow keeps its new position if it is better (the reference code's
``pX``/``pFit`` memory). This is the one-evaluation-per-generation reading of SSA; the
reference code evaluates producers, scroungers and sentinels separately.

SSA (Xue & Shen 2020, Eqs. 3–5):
  * producers: ``x ← x·exp(−i/(a·T))`` (a ~ U(0, 1]) if the alarm R2 < ST, else ``x ← x + Q·1``;
  * scroungers: rank i > P/2: ``x ← Q·exp((x_worst − x)/i²)``; else ``x ← x_P + |x − x_P|·A⁺·1``;
  * sentinels: ``x ← x_best + β·|x − x_best|`` (not the best) or
    ``x ← x + K·|x − x_worst|/(f − f_worst + ε)`` (the best).

ISSA (li2026, "Cauchy opposition-based learning, sine–cosine leaders, Lévy followers"):
  * initialisation (Eq. 5): generation 0 evaluates uniform points x; generation 1 their
    Cauchy-perturbed quasi-opposition points ``OP = c + r·(a + b − x − c)`` (c the box centre,
    r ~ U(0, 1) — Eq. 5's "rand((a + b)/2, x̃)") plus a Cauchy step ``0.1·(b − a)·tan(π(u − ½))``;
    each sparrow keeps the fitter of x and OP (standard opposition-based selection);
  * producers: sine–cosine update ``x ← λ(t)·x + r1·sin(r2)·|r3·x_best − x|`` (cos when R2 ≥ ST),
    ``r1 = 2(1 − t/T)``, ``r2 ~ U(0, 2π)``, ``r3 ~ U(0, 2)``, with the adaptive weight of Eq. 6:
    ``λ(t) = λmin + (λmax − λmin)/(λmax + λmin)·cos(t·π/T)``;
  * scroungers near the leader: Lévy flight ``x ← x_P + |x − x_P| ⊙ L`` with the Mantegna step of
    Eq. 7, ``L = s·r1·σ/|r2|^(1/ζ)``, r1, r2 ~ N(0, 1), ζ = 1.5 (the paper's scale s = 0.01 is a
    step length in its own units; here s = ``levy_scale`` = 1 multiplies the distance to the leader);
    the starving half as in SSA; sentinels as in SSA.

Coordinates. The rules act on ``y = 2z − 1 ∈ [−1, 1]^D`` (z the unit-cube position): the
multiplicative rules (``x·exp(…)``, ``λ·x``) contract towards the origin, which in raw
coordinates would be a bias towards every lower bound (a known defect of SSA); centred,
it is a contraction towards the box centre. Positions are clipped to the box, as in the
reference code. The paper gives neither λmax/λmin nor ST/PD/SD; we use the usual values
(0.9, 0.4; ST = 0.8, PD = 0.2, SD = 0.2).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from jaxplan.tune._base import Strategy, box, require_positive, sanitize, track_best
from jaxplan.tune._bounds import Bounds

__all__ = ["SparrowState", "ssa", "issa", "adaptive_weight", "levy"]


class SparrowState(NamedTuple):
    """X ``f32[P, D]`` personal-best positions (unit cube), F ``f32[P]`` their fitness (inf before
    the first tell), the box, the best point (box units) and the generation counter."""

    X: jnp.ndarray
    F: jnp.ndarray
    low: jnp.ndarray
    high: jnp.ndarray
    best_x: jnp.ndarray
    best_f: jnp.ndarray
    generation: jnp.ndarray


def adaptive_weight(t: int | jnp.ndarray, T: int, lam_max: float = 0.9, lam_min: float = 0.4) -> jnp.ndarray:
    """li2026 Eq. 6: ``λ = λmin + (λmax − λmin)/(λmax + λmin)·cos(t·π/T)``."""
    return lam_min + (lam_max - lam_min) / (lam_max + lam_min) * jnp.cos(t * math.pi / T)


def levy(key: jax.Array, shape: tuple[int, ...], zeta: float = 1.5, scale: float = 1.0) -> jnp.ndarray:
    """li2026 Eq. 7 (Mantegna's algorithm): ``scale·r1·σ/|r2|^(1/ζ)``, r1, r2 ~ N(0, 1)."""
    sigma = (math.gamma(1 + zeta) * math.sin(math.pi * zeta / 2)
             / (math.gamma((1 + zeta) / 2) * zeta * 2 ** ((zeta - 1) / 2))) ** (1 / zeta)
    k1, k2 = jax.random.split(key)
    r1, r2 = jax.random.normal(k1, shape), jax.random.normal(k2, shape)
    return scale * r1 * sigma / jnp.maximum(jnp.abs(r2), 1e-6) ** (1 / zeta)


def _init(key, bounds: Bounds, x0=None, *, P: int) -> SparrowState:
    low, high = box(bounds)
    D = bounds.dim
    best = (low + high) / 2 if x0 is None else jnp.asarray(x0, jnp.float32)
    return SparrowState(jnp.full((P, D), 0.5), jnp.full((P,), jnp.inf), low, high, best,
                        jnp.asarray(jnp.inf, jnp.float32), jnp.asarray(0, jnp.int32))


def _tell(state: SparrowState, pop, fitness) -> SparrowState:
    fitness, _ = sanitize(fitness)
    z = (pop - state.low) / (state.high - state.low)
    better = fitness < state.F  # F = inf before the first tell: everything is taken
    X = jnp.where(better[:, None], z, state.X)
    F = jnp.where(better, fitness, state.F)
    bx, bf = track_best(state.best_x, state.best_f, pop, fitness)
    return state._replace(X=X, F=F, best_x=bx, best_f=bf, generation=state.generation + 1)


def _step(key, state: SparrowState, T: int, improved: bool, pd: float, sd: float, st: float, lam_max: float,
          lam_min: float, levy_scale: float) -> jnp.ndarray:
    """The next positions (unit cube) from the ranked personal bests."""
    P, D = state.X.shape
    keys = jax.random.split(key, 12)
    t = state.generation.astype(jnp.float32)
    order = jnp.argsort(state.F)
    y = 2.0 * state.X[order] - 1.0
    f = state.F[order]
    rank = jnp.arange(1, P + 1, dtype=jnp.float32)
    n_prod = max(1, int(round(pd * P)))
    is_prod = rank <= n_prod
    y_best, y_worst, f_best, f_worst = y[0], y[-1], f[0], f[-1]
    alarm = jax.random.uniform(keys[0]) < st  # R2 < ST: no predator, wide search

    # Producers.
    if improved:
        lam = adaptive_weight(t, T, lam_max, lam_min)
        r1 = 2.0 * (1.0 - t / T)
        r2 = jax.random.uniform(keys[1], (P, D), maxval=2 * math.pi)
        r3 = jax.random.uniform(keys[2], (P, 1), maxval=2.0)
        wave = jnp.where(alarm, jnp.sin(r2), jnp.cos(r2))
        prod = lam * y + r1 * wave * jnp.abs(r3 * y_best - y)
    else:
        a = jax.random.uniform(keys[1], (P, 1), minval=1e-3, maxval=1.0)
        q = jax.random.normal(keys[2], (P, 1))
        prod = jnp.where(alarm, y * jnp.exp(-rank[:, None] / (a * T)), y + q)
    prod = jnp.clip(prod, -1.0, 1.0)
    x_p = prod[0]  # the best producer's new position

    # Scroungers.
    q = jax.random.normal(keys[3], (P, 1))
    starving = q * jnp.exp((y_worst - y) / rank[:, None] ** 2)
    if improved:
        near = x_p + jnp.abs(y - x_p) * levy(keys[4], (P, D), scale=levy_scale)
    else:
        A = jnp.where(jax.random.bernoulli(keys[4], 0.5, (P, D)), 1.0, -1.0)
        near = x_p + jnp.sum(jnp.abs(y - x_p) * A, axis=1, keepdims=True) / D  # |x − x_P|·A⁺·1, A⁺ = Aᵀ/D
    scr = jnp.where((rank > P / 2)[:, None], starving, near)
    new = jnp.where(is_prod[:, None], prod, scr)

    # Sentinels: a random sd·P of the sparrows (from the previous ranking).
    n_sent = max(1, int(round(sd * P)))
    sent = jnp.zeros(P, bool).at[jax.random.permutation(keys[5], P)[:n_sent]].set(True)
    beta = jax.random.normal(keys[6], (P, D))
    k = jax.random.uniform(keys[7], (P, 1), minval=-1.0, maxval=1.0)
    edge = y_best + beta * jnp.abs(new - y_best)
    centre = new + k * jnp.abs(new - y_worst) / ((f - f_worst)[:, None] + 1e-8)
    watch = jnp.where((f > f_best)[:, None], edge, centre)
    new = jnp.where(sent[:, None], watch, new)
    new = jnp.clip(jnp.nan_to_num(new), -1.0, 1.0)
    z = (new + 1.0) / 2.0
    return jnp.zeros_like(z).at[order].set(z)  # back to the sparrows' own slots (tell is per slot)


def _make(name: str, P: int, T: int, improved: bool, pd=0.2, sd=0.2, st=0.8, lam_max=0.9, lam_min=0.4,
          levy_scale=1.0) -> Strategy:
    for k, v in (("pd", pd), ("sd", sd), ("st", st)):
        if not 0 < v <= 1:
            raise ValueError(f"{name}: {k} must lie in (0, 1], got {v!r}")
    if not 0 < lam_min < lam_max:
        raise ValueError(f"{name}: need 0 < lam_min < lam_max, got {lam_min!r}, {lam_max!r}")
    require_positive(name, levy_scale=levy_scale)

    def init(key, bounds, x0=None):
        return _init(key, bounds, x0, P=P)

    def ask(key, state: SparrowState):
        D = state.X.shape[1]
        k0, k1, k2 = jax.random.split(key, 3)
        first = jax.random.uniform(k0, (P, D))
        if improved:
            # Eq. 5: quasi-opposition point between the centre and the opposite a + b − x, Cauchy-perturbed.
            opp = 0.5 + jax.random.uniform(k1, (P, D)) * ((1.0 - state.X) - 0.5)
            opp = jnp.clip(opp + 0.1 * jax.random.cauchy(k2, (P, D)), 0.0, 1.0)
        step = _step(key, state, T, improved, pd, sd, st, lam_max, lam_min, levy_scale)
        g = state.generation
        z = jnp.where(g == 0, first, step)
        if improved:
            z = jnp.where(g == 1, opp, z)
        return state.low + z * (state.high - state.low)

    return Strategy(name, P, init, ask, _tell)


def ssa(population_size: int, generations: int, pd: float = 0.2, sd: float = 0.2, st: float = 0.8,
        lam_max: float = 0.9, lam_min: float = 0.4, levy_scale: float = 1.0) -> Strategy:
    """The plain sparrow search (Xue & Shen 2020) over ``generations`` generations (producer share ``pd``,
    sentinel share ``sd``, alarm threshold ``st``; ``lam_*`` and ``levy_scale`` act in ISSA only)."""
    return _make("ssa", population_size, generations, False, pd, sd, st, lam_max, lam_min, levy_scale)


def issa(population_size: int, generations: int, pd: float = 0.2, sd: float = 0.2, st: float = 0.8,
         lam_max: float = 0.9, lam_min: float = 0.4, levy_scale: float = 1.0) -> Strategy:
    """li2026's improved sparrow search (see the module docstring; options as `ssa`'s, with the adaptive
    weight's ``lam_max``/``lam_min`` of Eq. 6 and the Lévy step scale)."""
    return _make("issa", population_size, generations, True, pd, sd, st, lam_max, lam_min, levy_scale)
