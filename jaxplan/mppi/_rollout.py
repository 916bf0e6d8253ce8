"""Rollouts of K control sequences through the robot model, with the per-point critic sums.

A sequence holds one (v, ω) per control period, as a navigation episode applies it. Each raw
(noisy) control is first clamped to what the robot can do from the previous one — the dynamic
window of one period (``|Δv|`` within accel/decel·period, ``|Δω|`` within alpha·period, the
speed and yaw-rate limits, and for an `Ackermann` robot ``|ω| <= κ|v|``) — so every rollout is
a motion the robot can execute, and the clamped sequences are what MPPI averages. Within a
period the robot moves on the exact arc of its (v, ω) (no Euler error), evaluated at
``substeps`` points per period with rotors (``e^{iφ}`` as polynomials: XLA's CPU sine and cosine
are scalar library calls).

Per point the loop keeps only running sums over the K sequences — the minimum clearance (to the
map alone too, for the flee fallback), the obstacle, goal, prefer-forward and constraint critic
sums, and the path-align sum at the end of every period — so no ``[K, T]`` array of points is
stored unless asked for. The critics themselves (`jaxplan.mppi._critics`) are small pure
functions of the point values; this module only sums them.

Predicted-contact safety (``MPPIConfig.safety = "predicted"``): from a sequence's end state the robot
brakes as hard as it can (decel) along the curvature it ends on; the sequence is admissible if no point
of that braking run (checked at ``brake_points`` times against the map and the discs predicted at those
times) comes closer than the footprint radius — the end state is then not an inevitable collision state
*if the discs move as predicted* (`jaxplan.dwa.braking_clearance`, shared with the DWA's option). The
guarantee against any walker of bounded speed is ``safety="passive"``, checked by the step
(`jaxplan.mppi._core`, `jaxplan.dwa.passive_slack`).
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp
from jax import lax

from jaxplan.dwa import (
    Disc,
    braking_clearance,
    clamp_controls,
    footprint_offsets,
    footprint_radius,
    rotor,
)
from jaxplan.mppi import _critics as C

__all__ = ["Sequences", "rollout"]

ClearanceFn = Callable[[jnp.ndarray, jnp.ndarray, jnp.ndarray], tuple[jnp.ndarray, jnp.ndarray]]
"""``clearance(x, y, t) -> (map, discs)``: metres from points ``x, y [K]`` to the map and to the moving discs
predicted at time ``t`` (s; +inf without discs)."""

_SMALL_ANGLE = 1e-4


class Sequences(NamedTuple):
    """The rollouts of K sequences (a pytree).

    Attributes:
      controls: ``f32[K, T, 2]`` the clamped (v, ω) of every sequence (what the robot would do).
      clearance: ``f32[K]`` minimum clearance (m) over the T·substeps points (map and discs).
      static: ``f32[K]`` the same minimum from the map alone.
      terms: `jaxplan.mppi._critics.Terms` the per-point critic means ``f32[K]`` and the end pose.
      admissible: ``bool[K]`` the braking run from the end state is free of predicted contacts (all True unless
        ``safety="predicted"``; the passive check is the step's, `jaxplan.mppi._core`).
      points: ``f32[K, T·substeps, 3]`` every point (x, y, θ), or None when not kept.
    """

    controls: jnp.ndarray
    clearance: jnp.ndarray
    static: jnp.ndarray
    terms: C.Terms
    admissible: jnp.ndarray
    points: jnp.ndarray | None


def _footprint_clearance(clearance: ClearanceFn, footprint, x, y, h, t):
    """``(map, discs)`` clearance (m) of the footprint at points ``x, y [K]`` with heading ``h`` (complex)."""
    if isinstance(footprint, Disc):
        return clearance(x, y, t)
    offsets = footprint_offsets(footprint)
    best = None
    for j in range(offsets.shape[0]):
        c = clearance(x + offsets[j] * h.real, y + offsets[j] * h.imag, t)
        best = c if best is None else jax.tree.map(jnp.minimum, best, c)
    return best


def rollout(config, state: jnp.ndarray, raw: jnp.ndarray, clearance: ClearanceFn, ctx: C.Context,
            finish: jnp.ndarray | None = None, inflate: Callable[[jnp.ndarray], jnp.ndarray] | None = None,
            closing=0.0) -> Sequences:
    """Rolls out K raw control sequences from ``state`` and sums their critics.

    Args:
      config: `MPPIConfig` (robot, period, substeps, …).
      state: ``f32[5]`` (x, y, θ, v, ω).
      raw: ``f32[K, T, 2]`` raw (noisy) controls; clamped here step by step.
      clearance: ``clearance(x, y, t) -> (map, discs)`` (m) at points ``[K]``, ``t`` s after now.
      ctx: `jaxplan.mppi._critics.Context` (sub-goal, goal, local path, reach).
      finish: ``f32[3]`` (x, y, radius) the goal region where the robot's run ends, or None: points
        after a sequence enters it do not count towards its clearance (as the DWA's ``finish``).
      inflate: ``inflate(t) -> m``: how much farther than their predicted edge the discs are kept at time
        ``t`` (feasibility and the dynamic critic; the braking check uses the bare prediction), or None.
      closing: the discs' top speed (m/s), for the braking check's margin between its check points.
    """
    robot = config.robot
    K, T = raw.shape[0], raw.shape[1]
    J = config.substeps
    P = config.period
    ds = P / J
    dtype = raw.dtype
    zero = raw[:, 0, 0] * 0.0  # derived from the inputs: a carry that varies like its updates (shard_map)
    h0 = lax.complex(jnp.cos(state[2]) + zero, jnp.sin(state[2]) + zero)
    inf = zero + jnp.inf
    init = dict(x=state[0] + zero, y=state[1] + zero, h=h0, v=state[3] + zero, w=state[4] + zero,
                clear=inf, static=inf, inside=zero > 0.0, sums=C.zero_sums(zero))

    def body(carry, xs):
        t, v_raw, w_raw = xs
        v, w = clamp_controls(robot, carry["v"], carry["w"], v_raw, w_raw, P)
        phi = w * (ds / 2)
        small = jnp.abs(phi) < _SMALL_ANGLE
        q = rotor(phi)
        arc_scale = v * ds / jnp.where(small, 1.0, phi)
        x0, y0, h = carry["x"], carry["y"], carry["h"]
        clear, static, inside, sums = carry["clear"], carry["static"], carry["inside"], carry["sums"]
        qj = None
        pts = []
        for j in range(1, J + 1):
            qj = q if qj is None else qj * q
            arc = jnp.where(small, v * (j * ds), arc_scale * qj.imag)
            p = h * qj * arc
            x, y = x0 + p.real, y0 + p.imag
            hj = h * qj * qj
            tj = (t * J + j).astype(dtype) * ds
            c_map, c_dyn = _footprint_clearance(clearance, robot.footprint, x, y, hj, tj)
            if inflate is not None:
                c_dyn = c_dyn - inflate(tj)
            if finish is not None:
                c_map = jnp.where(inside, jnp.inf, c_map)
                c_dyn = jnp.where(inside, jnp.inf, c_dyn)
                dx, dy = x - finish[0], y - finish[1]
                inside = inside | (dx * dx + dy * dy <= finish[2] * finish[2])
            clear, static = jnp.minimum(clear, jnp.minimum(c_map, c_dyn)), jnp.minimum(static, c_map)
            sums = C.add_point(sums, config, ctx, x, y, c_map, c_dyn)
            if config.keep_rollouts:
                pts.append(jnp.stack([x, y, jnp.angle(hj)], axis=-1))
        h = h * qj * qj
        h = h * lax.rsqrt(jnp.real(h * jnp.conj(h))).astype(h.dtype)  # keep it a unit rotor
        sums = C.add_control(sums, config, ctx, x, y, v, w, v_raw, w_raw)
        carry = dict(x=x, y=y, h=h, v=v, w=w, clear=clear, static=static, inside=inside, sums=sums)
        out = (v, w, jnp.stack(pts, axis=1) if config.keep_rollouts else None)
        return carry, out

    xs = (jnp.arange(T, dtype=jnp.int32), jnp.swapaxes(raw[..., 0], 0, 1), jnp.swapaxes(raw[..., 1], 0, 1))
    carry, (v_seq, w_seq, pts) = lax.scan(body, init, xs)
    controls = jnp.stack([jnp.swapaxes(v_seq, 0, 1), jnp.swapaxes(w_seq, 0, 1)], axis=-1)  # [K, T, 2]
    end = C.End(carry["x"], carry["y"], carry["h"], carry["v"], carry["w"])
    terms = C.finish_terms(carry["sums"], config, ctx, end, T)
    if config.safety == "predicted":
        brake = braking_clearance(lambda x, y, t: jnp.minimum(*clearance(x, y, t)), robot, end.x, end.y, end.h,
                                  end.v, end.w, T * P, config.brake_points, closing)
        admissible = brake >= footprint_radius(robot.footprint)
    else:
        admissible = zero == 0.0
    points = None
    if config.keep_rollouts:
        points = jnp.swapaxes(pts, 0, 1).reshape(K, T * J, 3)
    return Sequences(controls, carry["clear"], carry["static"], terms, admissible, points)
