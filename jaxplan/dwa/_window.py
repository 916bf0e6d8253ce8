"""The dynamic window and its grid of velocity samples (cui2025 Eqs. (5)–(6), chu2024 Eq. (10)).

The window is the set of velocities reachable within one control period Δt,
intersected with the robot's limits::

    v ∈ [v_t − decel·Δt, v_t + accel·Δt] ∩ [v_min, v_max]
    ω ∈ [ω_t − alpha·Δt, ω_t + alpha·Δt] ∩ [−omega_max, omega_max]

and, for an `Ackermann` robot, per sampled v, ``|ω| <= κ·|v|`` with κ = tan(δ_max)/L.

An empty intersection means the state is already outside the limits by more than one
period of acceleration can repair. The host front rejects such states; inside
compiled code (which cannot raise) the interval collapses to the single reachable
value closest to the limits, so the robot brakes or turns back as hard as it can.
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from jaxplan.dwa._robot import Robot, curvature_limit

Num = jnp.ndarray | float
"""A traced or concrete number, or an array of them (elementwise)."""

__all__ = ["Window", "dynamic_window", "window_of", "sample_controls", "curvature_window", "clamp_controls"]


class Window(NamedTuple):
    """Velocity intervals reachable in one control period (scalars, m/s and rad/s)."""

    v_lo: jnp.ndarray
    v_hi: jnp.ndarray
    w_lo: jnp.ndarray
    w_hi: jnp.ndarray


def _interval(cur: Num, down: Num, up: Num, lo_lim: Num, hi_lim: Num) -> tuple[jnp.ndarray, jnp.ndarray]:
    lo = jnp.maximum(cur - down, lo_lim)
    hi = jnp.minimum(cur + up, hi_lim)
    # Empty: keep the reachable value nearest to the limits (brake or turn back hardest).
    only = jnp.clip(jnp.clip(cur, lo_lim, hi_lim), cur - down, cur + up)
    empty = lo > hi
    return jnp.where(empty, only, lo), jnp.where(empty, only, hi)


def dynamic_window(robot: Robot, state: jnp.ndarray, period: Num) -> Window:
    """The window of ``state [5]`` for a control period of ``period`` seconds.

    The curvature limit of an `Ackermann` robot depends on v and is applied per sample
    in `sample_controls`, not here.
    """
    return window_of(robot, state[3], state[4], period)


def window_of(robot: Robot, v: Num, w: Num, period: Num) -> Window:
    """The window reachable in ``period`` seconds from velocities ``v, w`` (scalars or elementwise arrays)."""
    v_lo, v_hi = _interval(v, robot.decel * period, robot.accel * period, robot.v_min, robot.v_max)
    w_lo, w_hi = _interval(w, robot.alpha * period, robot.alpha * period, -robot.omega_max, robot.omega_max)
    return Window(v_lo, v_hi, w_lo, w_hi)


def curvature_window(robot: Robot, v: Num, w_lo: jnp.ndarray, w_hi: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray]:
    """The yaw-rate interval ``[w_lo, w_hi]`` cut to an `Ackermann` robot's cone ``|ω| <= κ·|v|`` (elementwise).

    Where the interval and the cone do not meet, it collapses to the point of the interval nearest the cone. A
    `Unicycle` has no cone: the interval comes back as it is.
    """
    kappa = curvature_limit(robot)
    if kappa is None:
        return w_lo, w_hi
    cap = kappa * jnp.abs(v)
    lo, hi = jnp.maximum(w_lo, -cap), jnp.minimum(w_hi, cap)
    only = jnp.clip(jnp.clip((w_lo + w_hi) / 2, -cap, cap), w_lo, w_hi)
    empty = lo > hi
    return jnp.where(empty, only, lo), jnp.where(empty, only, hi)


def clamp_controls(robot: Robot, v_prev: Num, w_prev: Num, v_raw: Num, w_raw: Num,
                   period: Num) -> tuple[jnp.ndarray, jnp.ndarray]:
    """The controls reachable within one period from ``(v_prev, w_prev)`` nearest to the raw ones (elementwise).

    Speed within the window of `window_of`; yaw rate within its window, then for an `Ackermann` robot within
    ``|ω| <= κ|v|`` (`curvature_window`). An empty interval (a state already outside the limits) collapses to the
    reachable value nearest the limits, as in `dynamic_window`. ``v_raw = w_raw = 0`` is the hardest braking the
    robot can do: the MPPI's braking candidate and the passive-safety check's braking run.
    """
    win = window_of(robot, v_prev, w_prev, period)
    v = jnp.clip(v_raw, win.v_lo, win.v_hi)
    w_lo, w_hi = curvature_window(robot, v, win.w_lo, win.w_hi)
    return v, jnp.clip(w_raw, w_lo, w_hi)


def sample_controls(robot: Robot, window: Window, n_v: int, n_omega: int) -> tuple[jnp.ndarray, jnp.ndarray]:
    """The ``n_v × n_omega`` grid of samples spanning the window (end points included).

    Returns:
      ``(v [S], omega [S])`` with S = n_v·n_omega, v-major: sample ``i·n_omega + j`` has
      the i-th speed and the j-th yaw rate (a single sample per axis sits mid-interval).
      For an `Ackermann` robot the yaw-rate interval of each speed is further cut to
      ``|ω| <= κ·|v|`` (collapsing, when that leaves nothing, to the rate-reachable ω
      nearest the allowed cone).
    """
    # Grid fractions as compile-time constants (numpy), so the grid itself costs no kernel and
    # fuses into whatever consumes it.
    k = np.arange(n_v * n_omega)
    t_v = (k // n_omega) / (n_v - 1) if n_v > 1 else np.full(k.shape, 0.5)
    t_w = (k % n_omega) / (n_omega - 1) if n_omega > 1 else np.full(k.shape, 0.5)
    t_v, t_w = t_v.astype(np.float32), t_w.astype(np.float32)
    v = window.v_lo + t_v * (window.v_hi - window.v_lo)
    w_lo, w_hi = curvature_window(robot, v, window.w_lo, window.w_hi)
    return v, w_lo + t_w * (w_hi - w_lo)
