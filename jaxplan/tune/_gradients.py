"""Differentiable tuning routes with optax: relaxed DWA, score-function (REINFORCE) gradients, surrogates.

(a) `relaxed_dwa`: the DWA's argmax over rollout scores replaced by ``softmax(score / T)``
    (`DWAConfig(selection="softmax")`, `jaxplan.dwa._core`), so a whole episode batch —
    a `lax.scan` of DWA steps, `jaxplan.tune._objective.dwa_episodes` — is a smooth
    function of the critic weights; `relaxed_dwa_loss` is differentiated with `jax.grad`
    and minimised with an optax optimiser while the temperature follows a schedule
    (exponential decay from ``t0`` to ``t1``: smooth early, close to the argmax DWA late).
    The weights stay in the box through ``x = low + (high − low)·sigmoid(u)``.

(b) `reinforce`: the score-function gradient of the *expected* ACO cost. An ACO run is not
    differentiable (the ants' choices are discrete and walked natively), so the weights are
    drawn from a search distribution ``x ~ N(μ, diag σ²)`` (unit-cube coordinates) and
    ``∇_μ E[f(x)] = E[(f(x) − b)·(x − μ)/σ²]`` (Williams 1992; PGPE, Sehnke et al. 2010) is
    estimated from a population with the leave-one-out mean as baseline ``b`` (independent
    of the sample it multiplies, so the estimator stays unbiased; `score_function_grad`).
    optax (Adam) then moves μ. It is a `Strategy`, so it shares the workflow and budget.
    The gradient is that of the cost smoothed by the search distribution, not of the ants'
    own choice probabilities (the numba walk does not return their log-probabilities).

(c) `surrogate`: fit a small differentiable model — a quadratic in the unit-cube
    coordinates with all cross terms, by ridge regression (closed form; refitted on every
    evaluation so far) — and minimise it with optax (Adam, projected onto the box) from
    ``P`` starts to propose the next population; generation 0 is uniform random. Also a
    `Strategy`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import optax

from jaxplan.tune._base import Strategy, box, require_positive, sanitize, track_best
from jaxplan.tune._bounds import Bounds, reflect

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from jaxplan.tune._objective import Objective

__all__ = ["score_function_grad", "reinforce", "surrogate", "relaxed_dwa_loss", "relaxed_dwa", "RelaxedResult",
           "quadratic_features"]


# ---------------------------------------------------------------------------------------------
# (b) score-function gradient


def score_function_grad(fitness: jnp.ndarray, eps: jnp.ndarray, sigma: float | jnp.ndarray) -> jnp.ndarray:
    """Unbiased estimate ``f32[D]`` of ``∇_μ E_{x ~ N(μ, σ²)}[f(x)]`` from samples ``x_i = μ + σ·ε_i``.

    Args:
      fitness: ``f32[P]`` costs ``f(x_i)``, P >= 2.
      eps: ``f32[P, D]`` the standard normal draws ``ε_i``.
      sigma: ``f32[]`` or ``f32[D]``.

    ``(1/P)·Σ (f_i − b_i)·ε_i/σ`` with the leave-one-out baseline ``b_i = mean_{j≠i} f_j``:
    ``b_i`` is independent of ``ε_i`` and E[ε_i] = 0, so the baseline changes the variance only.
    """
    P = fitness.shape[0]
    b = (jnp.sum(fitness) - fitness) / (P - 1)
    return jnp.mean((fitness - b)[:, None] * eps, axis=0) / sigma


class ReinforceState(NamedTuple):
    """μ ``f32[D]`` (unit cube), σ, the optax state, the last draws ``eps [P, D]``, box, best, generation."""

    mu: jnp.ndarray
    opt: Any
    eps: jnp.ndarray
    low: jnp.ndarray
    high: jnp.ndarray
    best_x: jnp.ndarray
    best_f: jnp.ndarray
    generation: jnp.ndarray


def reinforce(population_size: int, sigma: float = 0.1, learning_rate: float = 0.05) -> Strategy:
    """Score-function gradient descent on μ (see the module docstring); σ fixed (unit-cube units).

    ``ask`` draws ``x = reflect(μ + σ·ε)``; ``tell`` estimates the gradient from the raw draws
    and applies ``optax.adam(learning_rate)`` with μ clipped to the cube. Fitness is
    standardised (divided by its std) before the estimate: the step then does not depend on
    the cost's units (a positive rescaling of f leaves the gradient's direction unbiased)."""
    require_positive("reinforce", sigma=sigma, learning_rate=learning_rate)
    opt = optax.adam(learning_rate)

    def init(key, bounds: Bounds, x0=None):
        low, high = box(bounds)
        mu = jnp.full(bounds.dim, 0.5) if x0 is None else jnp.clip((jnp.asarray(x0) - low) / (high - low), 0, 1)
        return ReinforceState(mu, opt.init(mu), jnp.zeros((population_size, bounds.dim)), low, high,
                              low + mu * (high - low), jnp.asarray(jnp.inf, jnp.float32), jnp.asarray(0, jnp.int32))

    def ask(key, state):
        eps = jax.random.normal(key, (population_size, state.mu.shape[0]))
        return state.low + reflect(state.mu + sigma * eps) * (state.high - state.low)

    def tell(state, pop, fitness):
        fitness, _ = sanitize(fitness)
        # ask is pure, so recover the draws from the points: exact unless reflection folded them.
        z = (pop - state.low) / (state.high - state.low)
        eps = (z - state.mu) / sigma
        f = fitness / (jnp.std(fitness) + 1e-12)
        g = score_function_grad(f, eps, sigma)
        upd, o = opt.update(g, state.opt, state.mu)
        mu = jnp.clip(optax.apply_updates(state.mu, upd), 0.0, 1.0)
        bx, bf = track_best(state.best_x, state.best_f, pop, fitness)
        return state._replace(mu=mu, opt=o, eps=eps, best_x=bx, best_f=bf, generation=state.generation + 1)

    return Strategy("reinforce", population_size, init, ask, tell)


# ---------------------------------------------------------------------------------------------
# (c) surrogate


def quadratic_features(z: jnp.ndarray) -> jnp.ndarray:
    """``[..., 1 + D + D(D+1)/2]``: 1, z, and the products z_i·z_j (i <= j)."""
    D = z.shape[-1]
    i, j = np.triu_indices(D)
    c = z - 0.5  # centred: better conditioned
    return jnp.concatenate([jnp.ones(z.shape[:-1] + (1,)), c, c[..., i] * c[..., j]], axis=-1)


class SurrogateState(NamedTuple):
    """Every evaluation so far: Z ``f32[capacity, D]`` (unit cube), F ``[capacity]``, n used; box, best, generation."""

    Z: jnp.ndarray
    F: jnp.ndarray
    n: jnp.ndarray
    low: jnp.ndarray
    high: jnp.ndarray
    best_x: jnp.ndarray
    best_f: jnp.ndarray
    generation: jnp.ndarray


def surrogate(population_size: int, generations: int, ridge: float = 1e-3, steps: int = 100,
              learning_rate: float = 0.05, jitter: float = 0.05) -> Strategy:
    """Quadratic-surrogate search (see the module docstring): ``steps`` Adam steps on the fitted
    model from the best ``P/2`` points seen and ``P/2`` uniform starts, then a ``jitter`` (unit cube)
    Gaussian perturbation so that the proposals stay diverse."""
    require_positive("surrogate", ridge=ridge, steps=steps, learning_rate=learning_rate)  # ridge 0: singular fits
    require_positive("surrogate", strict=True, jitter=jitter)
    cap = population_size * generations
    opt = optax.adam(learning_rate)

    def init(key, bounds: Bounds, x0=None):
        low, high = box(bounds)
        D = bounds.dim
        best = (low + high) / 2 if x0 is None else jnp.asarray(x0, jnp.float32)
        return SurrogateState(jnp.zeros((cap, D)), jnp.zeros(cap), jnp.asarray(0, jnp.int32), low, high, best,
                              jnp.asarray(jnp.inf, jnp.float32), jnp.asarray(0, jnp.int32))

    def fit(state):
        w = (jnp.arange(cap) < state.n).astype(jnp.float32)
        X = quadratic_features(state.Z)
        mean = jnp.sum(w * state.F) / jnp.maximum(jnp.sum(w), 1.0)
        scale = jnp.sqrt(jnp.sum(w * (state.F - mean) ** 2) / jnp.maximum(jnp.sum(w), 1.0)) + 1e-9
        y = (state.F - mean) / scale
        A = (X * w[:, None]).T @ X + ridge * jnp.eye(X.shape[1])
        return jnp.linalg.solve(A, (X * w[:, None]).T @ y)

    def ask(key, state):
        P, D = population_size, state.Z.shape[1]
        k0, k1, k2 = jax.random.split(key, 3)
        uniform = jax.random.uniform(k0, (P, D))
        coef = fit(state)
        model = lambda z: quadratic_features(z) @ coef  # noqa: E731
        valid = jnp.arange(cap) < state.n
        top = state.Z[jnp.argsort(jnp.where(valid, state.F, jnp.inf))[: P // 2]]
        starts = jnp.concatenate([top, jax.random.uniform(k1, (P - P // 2, D))])

        def descend(z):
            def body(_, carry):
                z, o = carry
                g = jax.grad(model)(z)
                u, o = opt.update(g, o, z)
                return jnp.clip(optax.apply_updates(z, u), 0.0, 1.0), o

            return jax.lax.fori_loop(0, steps, body, (z, opt.init(z)))[0]

        z = jax.vmap(descend)(starts)
        z = reflect(z + jitter * jax.random.normal(k2, z.shape))
        z = jnp.where(state.n == 0, uniform, z)
        return state.low + z * (state.high - state.low)

    def tell(state, pop, fitness):
        fitness, _ = sanitize(fitness)
        z = (pop - state.low) / (state.high - state.low)
        idx = (state.n + jnp.arange(population_size)) % cap
        bx, bf = track_best(state.best_x, state.best_f, pop, fitness)
        return state._replace(Z=state.Z.at[idx].set(z), F=state.F.at[idx].set(fitness),
                              n=jnp.minimum(state.n + population_size, cap), best_x=bx, best_f=bf,
                              generation=state.generation + 1)

    return Strategy("surrogate", population_size, init, ask, tell)


# ---------------------------------------------------------------------------------------------
# (a) relaxed DWA


def relaxed_dwa_loss(objective: Objective, split: str = "train", collision_weight: float = 10.0) -> Callable:
    """The smooth episode loss ``loss(x f32[D], temperature) -> f32[]`` of a DWA `Objective`.

    Softmax selection at ``temperature``; per episode, the mean over control steps of the
    distance to the goal divided by the initial distance (a smooth time-to-goal: a robot that
    arrives sooner has a smaller area under its distance curve), plus ``collision_weight`` ×
    the mean squared clearance deficit ``max(0, d_safe − c)²/d_safe²`` while it moves.
    Averaged over the split's scenarios × seeds. Differentiable in ``x`` through `lax.scan`.
    """
    from jaxplan.dwa import DWAParams
    from jaxplan.tune._objective import _scatter, dwa_episodes

    d = objective._dwa
    config = d["config"].replace(selection="softmax")
    ep = d["episodes"][split]
    d0 = jnp.sqrt(jnp.sum((ep.start[:, :2] - ep.goal) ** 2, axis=-1))
    safe = float(config.d_safe)

    def loss(x, temperature):
        p = DWAParams(**{**_scatter(d["base"], d["slots"], x), "temperature": jnp.asarray(temperature, jnp.float32)})
        tr = dwa_episodes(d["table"], config, p, ep, d["steps"], d["tolerance"])
        progress = jnp.mean(tr.dist, axis=-1) / d0
        deficit = jnp.mean(tr.moving * jnp.maximum(0.0, safe - tr.clearance) ** 2, axis=-1) / safe ** 2
        return jnp.mean(progress + collision_weight * deficit)

    return loss


class RelaxedResult(NamedTuple):
    """x ``f32[K + 1, D]`` iterates (box units), loss ``[K]``, temperature ``[K]``, grad_norm ``[K]``."""

    x: np.ndarray
    loss: np.ndarray
    temperature: np.ndarray
    grad_norm: np.ndarray


def relaxed_dwa(objective: Objective, steps: int, x0: ArrayLike | None = None, learning_rate: float = 0.1,
                t0: float = 0.5, t1: float = 0.02, split: str = "train",
                optimizer: optax.GradientTransformation | None = None) -> RelaxedResult:
    """Minimises `relaxed_dwa_loss` with optax over ``steps`` gradient steps.

    The temperature decays exponentially from ``t0`` to ``t1`` (``optax.exponential_decay``);
    the weights are ``x = low + (high − low)·sigmoid(u)`` and optax (default Adam) updates u.
    Each step is one compiled call (loss and gradient over the whole split).
    """
    if steps < 1:
        raise ValueError(f"relaxed_dwa: steps must be >= 1, got {steps!r}")
    if not (t0 > 0 and t1 > 0):
        raise ValueError(f"relaxed_dwa: temperatures must be > 0, got t0={t0!r}, t1={t1!r}")
    b = objective.bounds
    low, high = jnp.asarray(b.low), jnp.asarray(b.high)
    loss = relaxed_dwa_loss(objective, split)
    schedule = optax.exponential_decay(t0, transition_steps=max(steps - 1, 1), decay_rate=t1 / t0)
    opt = optimizer or optax.adam(learning_rate)
    x0 = jnp.asarray(objective.defaults if x0 is None else x0, jnp.float32)
    z0 = jnp.clip((x0 - low) / (high - low), 1e-3, 1 - 1e-3)
    u = jnp.log(z0) - jnp.log1p(-z0)
    to_x = lambda u: low + (high - low) * jax.nn.sigmoid(u)  # noqa: E731

    @jax.jit
    def step(u, o, t):
        val, g = jax.value_and_grad(lambda u: loss(to_x(u), t))(u)
        g = jnp.nan_to_num(g)  # a step with a non-finite gradient (never seen) must not destroy u
        upd, o = opt.update(g, o, u)
        return optax.apply_updates(u, upd), o, val, jnp.linalg.norm(g)

    o = opt.init(u)
    xs, ls, ts, gs = [np.asarray(to_x(u))], [], [], []
    for k in range(steps):
        t = float(schedule(k))
        u, o, val, gn = step(u, o, jnp.asarray(t, jnp.float32))
        xs.append(np.asarray(to_x(u)))
        ls.append(float(val))
        ts.append(t)
        gs.append(float(gn))
    return RelaxedResult(np.stack(xs), np.asarray(ls), np.asarray(ts), np.asarray(gs))
