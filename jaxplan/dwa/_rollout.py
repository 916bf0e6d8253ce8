"""Rollouts: every velocity sample followed for the horizon at once, with its running clearance.

Each sample holds its (v, ω) for the whole horizon (the classic DWA assumption; the
dynamic window already bounds how far it is from the current velocity), so the robot
moves along an exact circular arc. After ``k`` steps of ``dt`` (``t_k = k·dt``) it has
turned ``2kφ`` with ``φ = ω·dt/2`` and its displacement is the chord

    p_k − p_0 = v·t_k·sinc(kφ)·e^{i(θ_0 + kφ)} = (v·dt/φ)·sin(kφ)·e^{iθ_0}·e^{ikφ}

(complex notation, ``x + iy``). The rotor ``q_k = e^{ikφ}`` advances by one complex
multiplication per step — the angle-addition recurrence for cos and sin, four multiplies
and two adds instead of two transcendental calls — and gives both the heading and
``sin(kφ) = Im q_k``, so no error accumulates in the position (there is no Euler
integration; rounding in the recurrence grows by about one ulp per step, 1e-6 relative
after 20 steps in float32).

The step rotor ``e^{iφ}`` itself is a polynomial (`jaxplan.dwa._fastmath.rotor`; XLA's
CPU sine and cosine are scalar calls). The loop over the T steps is a `lax.fori_loop`
(a `lax.scan` when poses are kept) whose body is elementwise over the S samples and
carries only the rotor and the running minimum clearance — two kernels per iteration on
a CPU, ``unroll`` steps per iteration — and the S·T trajectory points are never stored
unless asked for (``keep=True`` stores ``[S, T, 3]`` poses for plotting the fan of
trajectories, cui2025's Figure 4).
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp
from jax import lax

from jaxplan.dwa._fastmath import rotor
from jaxplan.dwa._robot import Disc, Footprint, footprint_offsets

__all__ = ["Rollouts", "rollout"]

ClearanceFn = Callable[[jnp.ndarray, jnp.ndarray, jnp.ndarray], jnp.ndarray]


class Rollouts(NamedTuple):
    """The rollouts of S samples (a pytree).

    Attributes:
      end: ``f32[S, 3]`` pose (x, y, theta) at the horizon (m, m, rad; theta unwrapped).
      end_dir: ``f32[S, 2]`` (cos theta, sin theta) of the end heading, from the rotor
        (so critics need no trigonometry).
      clearance: ``f32[S]`` minimum clearance (m) of the footprint over the T trajectory
        points (the current pose, which no sample can change, is not included).
      poses: ``f32[S, T, 3]`` every trajectory point, or None when not kept.
      static: ``f32[S]`` the same minimum from the map alone (``split=True``), or None.
    """

    end: jnp.ndarray
    end_dir: jnp.ndarray
    clearance: jnp.ndarray
    poses: jnp.ndarray
    static: jnp.ndarray | None = None


def rollout(state: jnp.ndarray, v: jnp.ndarray, w: jnp.ndarray, clearance: ClearanceFn, footprint: Footprint,
            steps: int, dt: float, keep: bool = False, unroll: int = 1,
            finish: jnp.ndarray | None = None, split: bool = False, turn_steps: jnp.ndarray | None = None) -> Rollouts:
    """Rolls out S constant-velocity samples from ``state`` and tracks their clearance.

    Args:
      state: ``[5]`` (x, y, theta, v, omega); only the pose is used.
      v, w: ``[S]`` sampled linear (m/s) and angular (rad/s) velocities.
      clearance: ``clearance(x, y, t) -> [S]`` metres at points ``x, y [S]`` and time ``t``
        (s after the current state): static map plus predicted moving discs.
      footprint: `Disc` (one lookup per point at the centre) or `Rectangle` (one per
        covering disc, centres placed along the heading at that point).
      steps: T, trajectory points per rollout (static).
      dt: seconds between points (static).
      keep: also return every pose ``[S, T, 3]`` (static).
      unroll: steps per loop iteration (static; `lax.scan`'s ``unroll``). On a CPU every
        iteration launches a few kernels, which for one robot costs more than the arithmetic.
      finish: ``f32[3]`` (x, y, radius): the disc where the robot's run ends (its goal region),
        or None. A rollout's points after its first point inside the disc do not count towards
        its clearance: the robot stops there, and a constant-velocity rollout that runs on
        past a goal at the end of a dead end would otherwise hit the end wall.
      split: ``clearance`` returns ``(map, moving discs)`` separately (static); both minima are
        kept, and `Rollouts.static` holds the map's.
      turn_steps: ``f32[S]`` or None: sample i turns at its ω for its first ``turn_steps[i]``
        points and then drives straight on at v (`DWAConfig.straighten`); ``T + 1`` or None
        turns for the whole horizon. The rotor then stops advancing, so the position stays
        exact: ``p_k = p_0 + e^{iθ0}·q·(v·dt·sin(k'φ)/φ + v·dt·(k − k')·q)`` with
        ``k' = min(k, turn_steps)`` and ``q = e^{ik'φ}``.
    """
    x0, y0, th0 = state[0], state[1], state[2]
    dtype = v.dtype
    phi = w * (dt / 2)
    small = jnp.abs(phi) < 1e-4  # then sin(kφ)/φ = k·(1 − (kφ)²/6) differs from k by < 1e-6
    rot = rotor(phi)  # e^{iφ}; |φ| <= π/2 (validated); a polynomial, see _fastmath
    arc_scale = v * dt / jnp.where(small, 1.0, phi)
    e0 = lax.complex(jnp.cos(th0), jnp.sin(th0))  # e^{iθ0}
    disc = isinstance(footprint, Disc)
    if not disc:
        offsets = footprint_offsets(footprint)

    def pose(q, k):
        """Position ``x, y [S]`` after ``k`` steps, ``q = e^{ikφ}``."""
        if turn_steps is None:
            arc = jnp.where(small, v * (k * dt), arc_scale * q.imag)  # v·dt·sin(kφ)/φ
            p = e0 * q * arc
            return x0 + p.real, y0 + p.imag
        kk = jnp.minimum(k, turn_steps)
        arc = jnp.where(small, v * (kk * dt), arc_scale * q.imag)
        p = e0 * q * (arc + v * dt * jnp.maximum(k - turn_steps, 0.0) * q)
        return x0 + p.real, y0 + p.imag

    def point(q, k):
        """Pose and footprint clearance of the k-th point (k counts from 1), ``q = e^{ikφ}``."""
        kf = k.astype(dtype)
        x, y = pose(q, kf)
        t = kf * dt
        if disc:
            return x, y, t, clearance(x, y, t)
        h = e0 * q * q  # e^{i(θ0 + 2kφ)}: the heading at this point
        clr = None
        for j in range(offsets.shape[0]):
            cj = clearance(x + offsets[j] * h.real, y + offsets[j] * h.imag, t)
            clr = cj if clr is None else jax.tree.map(jnp.minimum, clr, cj)
        return x, y, t, clr

    # Both initial carries derive from the inputs (not constants), so that the loop also
    # works inside shard_map, where a carry must vary along the sharded axes like its update.
    init = (rot, (v * 0.0 + jnp.inf,) * 2 if split else v * 0.0 + jnp.inf)
    if finish is not None:
        init = init + ((v * 0.0) > 0.0,)  # inside the finish disc yet: False (and NaN-proof)

    def track(carry, x, y, clr):
        """The carry after a point: running minimum clearance (and whether the finish was reached)."""
        if split:  # (combined, map)
            clr = (jnp.minimum(clr[0], clr[1]), clr[0])
        if finish is None:
            return (jax.tree.map(jnp.minimum, carry[1], clr),)
        inside = carry[2]
        m = jax.tree.map(lambda a, b: jnp.minimum(a, jnp.where(inside, jnp.inf, b)), carry[1], clr)
        dx, dy = x - finish[0], y - finish[1]
        return m, inside | (dx * dx + dy * dy <= finish[2] * finish[2])

    def advance(q, k):
        """The rotor of point ``k + 2`` from that of point ``k + 1``: frozen once a sample stops turning."""
        return q * rot if turn_steps is None else jnp.where(k + 2 <= turn_steps, q * rot, q)

    if keep:
        def body(carry, k):
            q = carry[0]  # q = e^{i(k+1)φ}: the rotor of this step's point
            x, y, t, clr = point(q, k + 1)
            th = th0 + w * (t if turn_steps is None else jnp.minimum(t, turn_steps * dt))
            return (advance(q, k),) + track(carry, x, y, clr), jnp.stack([x, y, th], axis=-1)

        carry, poses = lax.scan(body, init, jnp.arange(steps, dtype=jnp.int32), unroll=unroll)
        poses = jnp.swapaxes(poses, 0, 1)
    else:
        def body(k, carry):  # the loop counter itself gives k: no per-step index kernel
            q = carry[0]
            x, y, _, clr = point(q, k + 1)
            return (advance(q, k),) + track(carry, x, y, clr)

        carry = lax.fori_loop(0, steps, body, init, unroll=unroll)
        poses = None
    q, m = carry[0], carry[1]
    m, m_static = m if split else (m, None)
    if turn_steps is None:
        q = q * jnp.conj(rot)  # undo the last advance: e^{iTφ}
        turned = steps * dt
    else:
        q = jnp.where(steps + 1 <= turn_steps, q * jnp.conj(rot), q)
        turned = jnp.minimum(steps, turn_steps) * dt
    x, y = pose(q, jnp.asarray(steps, dtype))
    end = jnp.stack([x, y, th0 + w * turned], axis=-1)
    h = e0 * q * q  # e^{i(θ0 + 2Tφ)}
    return Rollouts(end, jnp.stack([h.real, h.imag], axis=-1), m, poses, m_static)
