"""Passive motion safety: can a robot still brake to rest before any predicted contact?

From a rollout's end state the robot brakes as hard as it can (``robot.decel``) along the curvature
``κ = ω/v`` it ends on — a circular arc traversed at falling speed — and stops after ``v/decel``
seconds. The rollout is *admissible* if no point of that braking run comes closer to the map or to a
moving disc (predicted at the run's times) than the footprint radius: its end state is then not an
inevitable collision state, and if a contact happens at all the robot is at rest when it does
(passive motion safety; Fraichard 2007, Bouraine, Fraichard & Salhi 2012). Both local planners use it
as an option (`jaxplan.dwa.DWAConfig.admissible`, `jaxplan.mppi.MPPIConfig.admissible`).

Each run is checked at ``points`` times evenly spaced over its own stop (the discs predicted at those
times); between two checks the robot and a disc can close by at most ``(v + v_disc)·Δ``, so a check
counts only the clearance beyond half of that (``closing`` gives ``v_disc``, the discs' top speed): the
test is conservative, never passing a run that meets a disc between its checks. Its arc is computed with rotors (no
trigonometric calls), with the turn of each check point clipped to ±π/2 around the end heading: a
tighter spiral would be a turn in place, not a braking run.
"""

from __future__ import annotations

import math
from typing import Callable

import jax.numpy as jnp

from jaxplan.dwa._fastmath import rotor
from jaxplan.dwa._robot import Disc, Robot, footprint_offsets

__all__ = ["braking_clearance"]

_SMALL_ANGLE = 1e-4


def braking_clearance(clearance: Callable, robot: Robot, x: jnp.ndarray, y: jnp.ndarray, h: jnp.ndarray,
                      v: jnp.ndarray, w: jnp.ndarray, t0, points: int, closing=0.0) -> jnp.ndarray:
    """Minimum clearance (m) of the braking runs from end states ``[S]``, less the margin between checks; +inf for
    a robot already at rest.

    Args:
      clearance: ``clearance(x, y, t) -> m`` at points ``[S]`` and times ``t [S]`` (s after now): map and discs.
      robot: the robot model (``decel``, footprint).
      x, y: ``[S]`` end positions (m); ``h``: ``[S]`` end headings as complex units ``e^{iθ}``.
      v, w: ``[S]`` speed (m/s; reversing counts as at rest) and yaw rate (rad/s) at the end.
      t0: time (s) of the end states.
      points: check points along each run (static).
      closing: the discs' top speed (m/s), for the margin between checks.
    """
    speed = jnp.maximum(v, 0.0)
    moving = speed > 1e-3
    decel = jnp.maximum(robot.decel, 1e-6)
    t_stop = speed / decel
    step = t_stop / points
    kappa = jnp.where(moving, w / jnp.where(moving, speed, 1.0), 0.0)
    disc = isinstance(robot.footprint, Disc)
    offsets = None if disc else footprint_offsets(robot.footprint)
    best = None
    for i in range(1, points + 1):
        tau = step * i
        s = speed * tau - 0.5 * robot.decel * tau * tau  # arc length braked so far (m)
        half = jnp.clip(kappa * s / 2, -math.pi / 2, math.pi / 2)
        q = rotor(half)
        straight = jnp.abs(half) < _SMALL_ANGLE
        chord = jnp.where(straight, s, 2.0 * q.imag / jnp.where(straight, 1.0, kappa))
        p = h * q * chord
        px, py = x + p.real, y + p.imag
        when = t0 + tau
        if disc:
            c = clearance(px, py, when)
        else:
            hh = h * q * q
            c = None
            for j in range(offsets.shape[0]):
                cj = clearance(px + offsets[j] * hh.real, py + offsets[j] * hh.imag, when)
                c = cj if c is None else jnp.minimum(c, cj)
        # Between the previous check and this one the robot went at most speed_then·Δ and a disc closing·Δ.
        margin = 0.5 * (speed - robot.decel * step * (i - 1) + closing) * step
        c = jnp.where(moving, c - margin, jnp.inf)
        best = c if best is None else jnp.minimum(best, c)
    return best
