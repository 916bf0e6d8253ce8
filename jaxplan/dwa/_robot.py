"""Robot models for the local planner: kinematic limits, footprints and the motion model.

Two models share one state layout, ``[5] = (x, y, theta, v, omega)`` in m, rad, m/s,
rad/s (docs/guide/navigation.md), and one motion model (a unicycle: ``ẋ = v cos θ``, ``ẏ = v sin θ``,
``θ̇ = ω``):

* `Unicycle` — a differential-drive robot; defaults from cui2025 (§4.1: v ≤ 1.2 m/s,
  |ω| ≤ 2.0 rad/s, |a| ≤ 0.5 m/s², the 0.25 m disc, angular acceleration
  3.0 rad/s²). It can turn on the spot.
* `Ackermann` — li2026's warehouse robot (Table 1: "Ackerman steering", 1.5 m/s,
  0.3 m/s²). A bicycle model about the rear axle has exactly the unicycle's kinematics
  with ``ω = v·tan(δ)/L``, so it differs only in which ``(v, ω)`` it can command: the
  steering limit bounds the curvature, ``|ω| <= |v|·tan(δ_max)/L``, and it cannot turn
  in place. li2026 gives no geometry; wheelbase 0.5 m, steering limit 0.6 rad
  (a 0.73 m minimum turning radius, well inside its 2 m aisles) and a 0.8 × 0.5 m body
  are our choices.

Models and footprints are frozen dataclasses registered as pytrees: their numbers are
leaves (traced under ``jit``, so changing a limit does not recompile and a batch of
robots with different limits can be ``vmap``-ped), while the model class and the
number of covering circles are static.

Footprints: a `Disc` (docs/guide/navigation.md) or a `Rectangle` covered by ``circles`` equal discs
along its length (the usual conservative approximation: each disc covers a
``length/circles × width`` slice, so the union contains the rectangle). Clearance is
measured from the covering discs' centres; a footprint collides when a centre's
clearance is below `footprint_radius`.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Union

import jax
import jax.numpy as jnp

__all__ = [
    "Disc", "Rectangle", "Footprint", "Unicycle", "Ackermann", "Robot", "footprint_radius",
    "footprint_offsets", "advance", "curvature_limit",
]


def _pytree(data: tuple[str, ...], meta: tuple[str, ...] = ()):
    def wrap(cls):
        return jax.tree_util.register_dataclass(cls, data_fields=list(data), meta_fields=list(meta))

    return wrap


@_pytree(("radius",))
@dataclasses.dataclass(frozen=True)
class Disc:
    """A disc footprint of ``radius`` metres centred on the robot's reference point."""

    radius: float = 0.25


@_pytree(("length", "width"), ("circles",))
@dataclasses.dataclass(frozen=True)
class Rectangle:
    """A ``length × width`` (m) rectangle centred on the reference point, long side along the heading.

    Covered by ``circles`` (static) equal discs centred on the long axis; more circles fit
    the rectangle more tightly and cost one clearance lookup each per trajectory point.
    """

    length: float = 0.8
    width: float = 0.5
    circles: int = 3


Footprint = Union[Disc, Rectangle]


def footprint_radius(fp: Footprint):
    """Radius (m) of the footprint's covering discs (the disc's own radius for a `Disc`)."""
    if isinstance(fp, Disc):
        return fp.radius
    half_slice = fp.length / (2 * fp.circles)
    return (half_slice**2 + (fp.width / 2) ** 2) ** 0.5


def footprint_offsets(fp: Footprint) -> tuple[float, ...] | jnp.ndarray:
    """Forward offsets (m, body frame) of the covering discs' centres: ``[K]``."""
    if isinstance(fp, Disc):
        return jnp.zeros(1)
    k = jnp.arange(fp.circles, dtype=jnp.float32)
    return (k + 0.5) * (fp.length / fp.circles) - fp.length / 2


@_pytree(("v_min", "v_max", "omega_max", "accel", "decel", "alpha", "footprint"))
@dataclasses.dataclass(frozen=True)
class Unicycle:
    """Differential drive (cui2025 defaults).

    Attributes:
      v_min, v_max: linear velocity limits (m/s); ``v_min < 0`` allows reversing.
      omega_max: angular velocity limit (rad/s), symmetric: ``|ω| <= omega_max``.
      accel, decel: largest increase / decrease of ``v`` per second (m/s², both >= 0;
        cui2025's ``a_acc`` and ``a_dec`` of Eq. (6), equal by default).
      alpha: largest change of ``ω`` per second (rad/s², cui2025's ``α_acc = α_dec``).
      footprint: `Disc` or `Rectangle`.
    """

    v_min: float = 0.0
    v_max: float = 1.2
    omega_max: float = 2.0
    accel: float = 0.5
    decel: float = 0.5
    alpha: float = 3.0
    footprint: Footprint = Disc(0.25)


@_pytree(("v_min", "v_max", "omega_max", "accel", "decel", "alpha", "wheelbase", "steer_max", "footprint"))
@dataclasses.dataclass(frozen=True)
class Ackermann:
    """Car-like robot (li2026's "Ackerman steering": 1.5 m/s, 0.3 m/s²).

    Attributes as `Unicycle`, plus ``wheelbase`` L (m) and ``steer_max`` δ_max (rad, in
    (0, π/2)): commands satisfy ``|ω| <= |v|·tan(δ_max)/L`` as well as the yaw-rate and
    acceleration limits. Steering is assumed fast against the control period (no
    steering-rate limit beyond ``alpha``).
    """

    v_min: float = 0.0
    v_max: float = 1.5
    omega_max: float = 2.0
    accel: float = 0.3
    decel: float = 0.3
    alpha: float = 3.0
    wheelbase: float = 0.5
    steer_max: float = 0.6
    footprint: Footprint = Rectangle(0.8, 0.5, 3)


Robot = Union[Unicycle, Ackermann]


def curvature_limit(robot: Robot):
    """Largest |ω/v| (1/m) the robot can command: ``tan(δ_max)/L`` for `Ackermann`, None for `Unicycle`."""
    if isinstance(robot, Ackermann):
        return jnp.tan(robot.steer_max) / robot.wheelbase
    return None


def advance(state: jnp.ndarray, control: jnp.ndarray, dt) -> jnp.ndarray:
    """Moves the robot for ``dt`` seconds under a constant control: the exact arc, no Euler error.

    Args:
      state: ``[..., 5]`` (x, y, theta, v, omega).
      control: ``[..., 2]`` (v, omega) held for the whole interval (the new velocities).
      dt: seconds.

    Returns:
      ``[..., 5]``: the pose at ``t + dt`` (theta wrapped to [-π, π)) and the control as
      the new velocities.

    For a constant (v, ω) the chord of the arc is ``v·dt·sinc(ω·dt/2)`` long and points
    along the mid-interval heading ``θ + ω·dt/2``; this is exact for any ω (the straight
    line is the limit ω → 0, where ``jnp.sinc`` is smooth).
    """
    state = jnp.asarray(state)
    control = jnp.asarray(control, state.dtype)
    x, y, th = state[..., 0], state[..., 1], state[..., 2]
    v, w = control[..., 0], control[..., 1]
    chord = v * dt * jnp.sinc(w * dt / (2 * math.pi))  # jnp.sinc(x) = sin(πx)/(πx)
    mid = th + w * dt / 2
    th2 = th + w * dt
    th2 = jnp.mod(th2 + math.pi, 2 * math.pi) - math.pi
    return jnp.stack([x + chord * jnp.cos(mid), y + chord * jnp.sin(mid), th2, v, w], axis=-1)
