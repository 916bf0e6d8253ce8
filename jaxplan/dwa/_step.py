"""`dwa_step`: the host front of the local planner (validation, map tables, compiled-function reuse).

The compiled core (`jaxplan.dwa._core.dwa_control`) cannot raise, so everything a
user can get wrong is checked here first, in numpy, with an error that names the
problem. The map's `ClearanceTable` is built once per map object and kept; the step
itself is jitted once per configuration (the static fields of `DWAConfig`, the array
shapes and the number of moving discs) — limits, distances and weights are traced, so
changing them does not recompile.

Per call the front does only what that call needs: a configuration is checked and copied to
the device once (the last 64 are kept), one robot's state is checked with scalar arithmetic,
and with ``full_info=False`` the program returns the control alone (no rollouts computed, no
info record copied to numpy). A script that steps one robot on a fixed map can go further with
`jaxplan.dwa.make_stepper`, which does the per-map and per-robot work once.
"""

from __future__ import annotations

import math
from typing import Any, Mapping

import jax
import jax.numpy as jnp
import numpy as np
from numpy.typing import ArrayLike

from jaxplan.core.cache import lru_cache, memoize
from jaxplan.core.deprecation import keyword_only
from jaxplan.core.xla import one_thread_options
from jaxplan.dwa._clearance import ClearanceTable, DiscObstacles, clearance_table
from jaxplan.dwa._config import (
    CLEARANCE_MODES,
    EVALUATORS,
    RECOVERIES,
    SAFETY_MODES,
    SELECTIONS,
    DWAConfig,
    DWAParams,
    default_params,
)
from jaxplan.dwa._core import DWAInfo, dwa_control, dwa_control_batch
from jaxplan.dwa._fastmath import MAX_ROTOR_ANGLE
from jaxplan.dwa._passive import with_brake_periods
from jaxplan.dwa._robot import Ackermann, Disc, Rectangle, Unicycle, footprint_radius
from jaxplan.grid import GridMap, collision_map

__all__ = ["dwa_step", "table_of", "validate_config", "validate_params", "as_obstacles", "obstacles_to_local",
           "check_safety"]

CHUNK = 128
"""Robots per vectorised chunk of a batched step (see `dwa_control_batch`)."""

# One robot's step is compiled without XLA:CPU's loop splitting (`jaxplan.core.xla`): called from Python, the
# split loops wake a sleeping thread per call, which costs more than they save; the kernels and bits are the same.
_single = jax.jit(dwa_control, compiler_options=one_thread_options())
_batch = jax.jit(dwa_control_batch, static_argnames=("chunk",))


def _control_only(table, config, params, state, subgoal, obstacles=None, path=None):
    return dwa_control(table, config, params, state, subgoal, obstacles, path)[0]


def _control_only_batch(table, config, params, states, subgoals, obstacles=None, path=None, *, chunk):
    return dwa_control_batch(table, config, params, states, subgoals, obstacles, path, chunk=chunk)[0]


# The control alone: XLA drops the info record's outputs; the control's bits are those of `_single`/`_batch`
# (tests/test_dwa_stepper.py compares them).
_single_control = jax.jit(_control_only, compiler_options=one_thread_options())
_batch_control = jax.jit(_control_only_batch, static_argnames=("chunk",))


@lru_cache(maxsize=64)
def on_device(config: DWAConfig, lean: bool = False) -> DWAConfig:
    """``config`` with its traced fields as device arrays (``lean``: with ``keep_rollouts=False``), one per
    configuration: a call then hands over buffers instead of converting eleven Python floats."""
    return jax.device_put(config.replace(keep_rollouts=False) if lean else config)


@lru_cache(maxsize=64)
def _params_on_device(key: tuple[bytes, ...]) -> DWAParams:
    return jax.device_put(DWAParams(*(np.frombuffer(b, np.float32)[0] for b in key)))


def params_on_device(params: DWAParams) -> DWAParams:
    """Validated float32 ``params`` as device arrays, one per distinct value (keyed by the bits, so -0.0 and
    0.0 stay apart)."""
    return _params_on_device(tuple(np.float32(x).tobytes() for x in params))


def table_of(grid: GridMap) -> ClearanceTable:
    """The `ClearanceTable` of ``grid``, built once per map object (a few maps are kept); with the grid's
    speed limit layer if it has one (copied to the device once, with the table).

    A map's layers are taken as they are when its table is built: change a map with
    `GridMap.replace` (a new map, new arrays), not by writing into its arrays."""
    return _table(grid)[1]


# Keyed by the identity of the free-cell and speed-limit arrays, as `dwa_step` calls this on every step (a content
# digest of a 512x512 map costs 0.25 ms); the value holds those arrays, so their ids cannot be reused while the
# entry lives.
@memoize(maxsize=8, key=lambda grid: (id(grid.free), id(grid.speed_limit), float(grid.resolution)))
def _table(grid: GridMap) -> tuple[Any, ClearanceTable]:
    table = clearance_table(collision_map(grid))
    if grid.speed_limit is not None:
        table = table._replace(speed_limit=jnp.asarray(grid.speed_limit, jnp.float32))
    return (grid.free, grid.speed_limit), table


def _number(name: str, x: Any, *, positive: bool = False, nonneg: bool = False) -> float:
    try:
        f = float(x)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {x!r}") from None
    if not math.isfinite(f):
        raise ValueError(f"{name} must be finite, got {f}")
    if positive and f <= 0:
        raise ValueError(f"{name} must be > 0, got {f}")
    if nonneg and f < 0:
        raise ValueError(f"{name} must be >= 0, got {f}")
    return f


def validate_config(config: DWAConfig) -> DWAConfig:
    """Checks a `DWAConfig` and its robot; raises ValueError naming the first problem. Returns ``config``."""
    if not isinstance(config, DWAConfig):
        raise ValueError(f"config must be a DWAConfig, got {type(config).__name__}")
    try:
        hash(config)
    except TypeError:  # traced or array-valued fields: validate every time
        _check_config(config)
    else:
        _checked_config(config)  # each valid configuration is checked once (the last 64 are kept)
    return config


def _check_config(config: DWAConfig) -> None:
    r = config.robot
    if not isinstance(r, (Unicycle, Ackermann)):
        raise ValueError(f"config.robot must be a Unicycle or an Ackermann, got {type(r).__name__}")
    name = type(r).__name__
    v_min = _number(f"{name}.v_min", r.v_min)
    v_max = _number(f"{name}.v_max", r.v_max, positive=True)
    if v_min >= v_max:
        raise ValueError(f"empty velocity range: {name}.v_min ({v_min}) must be below v_max ({v_max})")
    for field in ("omega_max", "accel", "decel", "alpha"):
        _number(f"{name}.{field}", getattr(r, field), positive=True)
    if isinstance(r, Ackermann):
        _number(f"{name}.wheelbase", r.wheelbase, positive=True)
        steer = _number(f"{name}.steer_max", r.steer_max, positive=True)
        if steer >= math.pi / 2:
            raise ValueError(f"{name}.steer_max must be below π/2 rad, got {steer}")
    fp = r.footprint
    if isinstance(fp, Disc):
        _number("footprint radius", fp.radius, positive=True)
    elif isinstance(fp, Rectangle):
        _number("footprint length", fp.length, positive=True)
        _number("footprint width", fp.width, positive=True)
        if not isinstance(fp.circles, (int, np.integer)) or fp.circles < 1:
            raise ValueError(f"footprint circles must be a positive integer, got {fp.circles!r}")
    else:
        raise ValueError(f"footprint must be a Disc or a Rectangle, got {type(fp).__name__}")
    _number("config.period", config.period, positive=True)
    d_safe = _number("config.d_safe", config.d_safe, positive=True)
    rad = float(footprint_radius(fp))
    if d_safe < rad:
        raise ValueError(f"config.d_safe ({d_safe} m) is below the footprint radius ({rad:.4g} m): "
                         "feasible rollouts could collide")
    d_clip = _number("config.d_clip", config.d_clip, positive=True)
    if d_clip <= d_safe:
        raise ValueError(f"config.d_clip ({d_clip} m) must exceed d_safe ({d_safe} m)")
    _number("config.path_clip", config.path_clip, positive=True)
    for field in ("n_v", "n_omega", "unroll", "n_omega_straight", "brake_points"):
        n = getattr(config, field)
        if not isinstance(n, (int, np.integer)) or isinstance(n, bool) or n < 1:
            raise ValueError(f"config.{field} must be a positive integer, got {n!r}")
    horizon = _number("config.horizon", config.horizon, positive=True)
    dt = _number("config.dt", config.dt, positive=True)
    if abs(horizon / dt - round(horizon / dt)) > 1e-6 * max(1.0, horizon / dt):
        raise ValueError(f"config.horizon ({horizon} s) must be a whole number of steps dt ({dt} s)")
    if not isinstance(config.straighten, tuple):
        raise ValueError(f"config.straighten must be a tuple of fractions of the horizon, got {config.straighten!r}")
    steps = int(round(horizon / dt))
    for f in config.straighten:
        f = _number("config.straighten fraction", f)
        if not 1 <= round(f * steps) <= steps - 1:
            raise ValueError(f"config.straighten fraction {f} turns for {round(f * steps)} of the {steps} rollout "
                             "points: it must leave at least one point on each part")
    if float(r.omega_max) * dt > 2 * MAX_ROTOR_ANGLE:
        raise ValueError(f"{name}.omega_max · config.dt = {float(r.omega_max) * dt:.3g} rad: a sample may turn at most "
                         f"π rad per rollout step (shorten dt)")
    for field, choices in (("evaluator", EVALUATORS), ("clearance", CLEARANCE_MODES), ("selection", SELECTIONS),
                            ("recovery", RECOVERIES), ("safety", SAFETY_MODES)):
        if getattr(config, field) not in choices:
            raise ValueError(f"config.{field} must be one of {choices}, got {getattr(config, field)!r}")
    check_safety(config, "config")


def check_safety(config: Any, name: str) -> None:
    """Checks the passive-safety fields shared by `DWAConfig` and `jaxplan.mppi.MPPIConfig` (``name`` prefixes the
    error): ``walker_speed_max`` None or a finite number >= 0, ``brake_periods`` None or a positive integer."""
    if config.walker_speed_max is not None:
        _number(f"{name}.walker_speed_max", config.walker_speed_max, nonneg=True)
    n = config.brake_periods
    if n is not None and (not isinstance(n, (int, np.integer)) or isinstance(n, bool) or n < 1):
        raise ValueError(f"{name}.brake_periods must be None or a positive integer, got {n!r}")


_checked_config = lru_cache(maxsize=64)(_check_config)
_defaults = lru_cache(maxsize=None)(default_params)  # one `DWAParams` object per evaluator


def validate_params(params: DWAParams | Mapping[str, float] | None, evaluator: str) -> DWAParams:
    """`DWAParams` from None (the evaluator's defaults), a mapping of overrides or `DWAParams`; checked."""
    if params is None:
        return _defaults(evaluator)
    if isinstance(params, Mapping):
        return validate_params(default_params(evaluator, **params), evaluator)
    if not isinstance(params, DWAParams):
        raise ValueError(f"params must be DWAParams, a dict of overrides or None, got {type(params).__name__}")
    values = {}
    for name, x in params._asdict().items():
        a = np.asarray(x, dtype=np.float64)
        if a.shape != ():
            raise ValueError(f"params.{name} must be a scalar, got shape {a.shape}")
        if np.isnan(a):
            raise ValueError(f"params.{name} is NaN")
        if not np.isfinite(a):
            raise ValueError(f"params.{name} must be finite, got {float(a)}")
        if name == "temperature" and a <= 0:
            raise ValueError(f"params.temperature must be > 0, got {float(a)}")
        if a < 0:
            raise ValueError(f"params.{name} is a weight and must be >= 0, got {float(a)}")
        values[name] = np.float32(a)
    return DWAParams(**values)


def as_obstacles(obstacles: Any, batch: int | None) -> DiscObstacles | None:
    """Validated float32 `DiscObstacles` (shared ``[M, ...]`` or per robot ``[B, M, ...]``) from
    `DiscObstacles` or a ``(positions, velocities, radii)`` tuple; None passes through."""
    if obstacles is None:
        return None
    track = obstacles.track if isinstance(obstacles, DiscObstacles) else None
    try:
        pos, vel, rad = obstacles[:3] if isinstance(obstacles, DiscObstacles) else obstacles
    except (TypeError, ValueError):
        raise ValueError("obstacles must be DiscObstacles or a (positions, velocities, radii) tuple") from None
    pos = np.asarray(pos, np.float64)
    vel = np.asarray(vel, np.float64)
    rad = np.asarray(rad, np.float64)
    per_robot = rad.ndim == 2
    lead = (batch,) if per_robot else ()
    if per_robot and batch is None:
        raise ValueError("per-robot obstacles [B, M, ...] need a batch of states [B, 5]")
    if rad.ndim not in (1, 2) or (per_robot and rad.shape[0] != batch):
        raise ValueError(f"obstacle radii must be [M] or [B, M] with B = {batch}, got shape {rad.shape}")
    M = rad.shape[-1]
    for name, a in (("positions", pos), ("velocities", vel)):
        if a.shape != lead + (M, 2):
            raise ValueError(f"obstacle {name} must have shape {lead + (M, 2)} to match radii {rad.shape}, "
                             f"got {a.shape}")
        if not np.isfinite(a).all():
            raise ValueError(f"obstacle {name} contain NaN or infinite values")
    if not np.isfinite(rad).all() or (rad < 0).any():
        raise ValueError("obstacle radii must be finite and >= 0")
    if track is not None:
        track = np.asarray(track, np.float64)
        if track.ndim != len(lead) + 3 or track.shape[:len(lead) + 1] != lead + (M,) or track.shape[-1] != 2 \
                or track.shape[-2] < 1:
            raise ValueError(f"obstacle track must have shape {lead + (M,)} + (K, 2) with K >= 1, got {track.shape}")
        if not np.isfinite(track).all():
            raise ValueError("obstacle track contains NaN or infinite values")
        track = track.astype(np.float32)
    return DiscObstacles(*(a.astype(np.float32) for a in (pos, vel, rad)), track=track)


def _check_window(config: DWAConfig, states: np.ndarray) -> None:
    r = config.robot
    v, w = states[:, 3], states[:, 4]
    P = float(config.period)
    v_lo = np.maximum(v - float(r.decel) * P, float(r.v_min))
    v_hi = np.minimum(v + float(r.accel) * P, float(r.v_max))
    w_lo = np.maximum(w - float(r.alpha) * P, -float(r.omega_max))
    w_hi = np.minimum(w + float(r.alpha) * P, float(r.omega_max))
    for lo, hi, what, x, lims in ((v_lo, v_hi, "v", v, (r.v_min, r.v_max)),
                                  (w_lo, w_hi, "omega", w, (-r.omega_max, r.omega_max))):
        bad = lo > hi
        if bad.any():
            i = int(np.argmax(bad))
            raise ValueError(f"empty dynamic window: state[{i}] has {what} = {x[i]:.4g}, which one control period "
                             f"({P} s) of acceleration cannot bring into [{float(lims[0]):.4g}, {float(lims[1]):.4g}]")


def _check_on_free_cells(grid: GridMap, states: np.ndarray, single: bool) -> None:
    """Raises if a robot's centre is off the map or on a blocked cell: no rollout can then be
    judged (the clearance is 0 everywhere around it, and the escape rule would pass them all)."""
    H, W = grid.shape
    cell = np.floor(states[:, :2] / float(grid.resolution)).astype(np.int64)  # (x, y) = (column, row)
    inside = (cell[:, 0] >= 0) & (cell[:, 0] < W) & (cell[:, 1] >= 0) & (cell[:, 1] < H)
    free = np.asarray(grid.free)
    ok = inside.copy()
    ok[inside] = free[cell[inside, 1], cell[inside, 0]]
    if not ok.all():
        i = int(np.argmin(ok))
        where = "outside the map" if not inside[i] else f"on the blocked cell {cell[i].tolist()}"
        x, y = grid.to_world(states[i, :2])  # the world coordinates the caller gave
        raise ValueError(f"state{'' if single else f'[{i}]'} puts the robot {where} "
                         f"(x, y = {x:.4g}, {y:.4g} m)")


def device_config(config: DWAConfig, lean: bool = False) -> DWAConfig:
    """`on_device` for a hashable (validated) configuration; a configuration with array fields as it is."""
    try:
        return on_device(config, lean)
    except TypeError:  # unhashable: array-valued fields
        return config.replace(keep_rollouts=False) if lean else config


def one_robot(state: ArrayLike, subgoal: ArrayLike, grid: GridMap, config: DWAConfig
              ) -> tuple[np.ndarray, np.ndarray] | None:
    """One robot's ``f32[5]`` state and ``f32[2]`` sub-goal in the map's frame, checked with scalar arithmetic
    (a few microseconds), or None when they are not one robot's or a check fails: `dwa_step`'s general path
    then raises the error that names the problem. The same float64 operations as that path, so the same bits."""
    st = np.asarray(state, dtype=np.float64)
    sg = np.asarray(subgoal, dtype=np.float64)
    if st.shape != (5,) or sg.shape != (2,):
        return None
    x, y, th, v, w = st.tolist()
    gx, gy = sg.tolist()
    if not all(map(math.isfinite, (x, y, th, v, w, gx, gy))):
        return None
    r, P = config.robot, float(config.period)
    if max(v - float(r.decel) * P, float(r.v_min)) > min(v + float(r.accel) * P, float(r.v_max)) or \
            max(w - float(r.alpha) * P, -float(r.omega_max)) > min(w + float(r.alpha) * P, float(r.omega_max)):
        return None
    if grid.has_origin:
        ox, oy = (float(o) for o in grid.origin)
        x, y, gx, gy = x - ox, y - oy, gx - ox, gy - oy
    res = float(grid.resolution)
    cx, cy = math.floor(x / res), math.floor(y / res)
    H, W = grid.shape
    if not (0 <= cx < W and 0 <= cy < H and grid.free[cy, cx]):
        return None
    return np.array([x, y, th, v, w], np.float32), np.array([gx, gy], np.float32)


@keyword_only("obstacles", "params")
def dwa_step(state: ArrayLike, subgoal: ArrayLike, grid: GridMap, *, obstacles: Any = None,
             params: DWAParams | Mapping[str, float] | None = None, config: DWAConfig | None = None,
             path: ArrayLike | None = None, full_info: bool = True) -> tuple[np.ndarray, DWAInfo | None]:
    """One Dynamic Window Approach step for one robot or a batch (docs/guide/navigation.md).

    The signature is `jaxplan.mppi_step`'s: ``(state, subgoal, grid, *, obstacles, params, config, path,
    full_info)``. ``obstacles`` and ``params`` given by position (the old form) still work, with a
    `DeprecationWarning`.

    Args:
      state: ``[5]`` = (x, y, theta, v, omega) in m, rad, m/s, rad/s, or ``[B, 5]``.
      subgoal: ``[2]`` (m), or ``[B, 2]``: the point the robot heads for (a key node of
        the global path).
      grid: the map (`GridMap`); its clearance tables are built on the first call and kept.
      obstacles: moving discs: `DiscObstacles` or ``(positions [M, 2] m, velocities
        [M, 2] m/s, radii [M] m)``, shared by all robots, or ``[B, M, ...]`` per robot
        (``M`` may be 0); predicted at constant velocity over the horizon, or along
        ``DiscObstacles.track`` (``[M, K, 2]`` centres every ``config.dt``) if given.
      params: `DWAParams`, a dict of overrides of the evaluator's defaults
        (e.g. ``{"heading": 0.5}``), or None for the defaults.
      config: `DWAConfig` (robot, window, horizon, evaluator, clearance mode, selection);
        default `DWAConfig()` — cui2025's robot and weighted evaluator.
      path: the global path ``[L, 2]`` (m) for the path critic, or ``[B, L, 2]``.
      full_info: False returns ``(control, None)``: the step computes no rollouts to keep
        and copies no info record (the same control, bit for bit). For one robot stepped in a
        loop on a fixed map, `make_stepper` is leaner still.

    Returns:
      ``(control, info)``: ``control`` ``[2]`` = (v, omega) for the next control period
      (``[B, 2]`` for a batch) and a `DWAInfo` of numpy arrays (leading ``B`` axis for a
      batch): scores ``[S]``, rollouts ``[S, T, 3]``, feasible ``[S]``, chosen index, …
      (None with ``full_info=False``).

    Raises:
      ValueError: non-finite or mis-shaped state, sub-goal, obstacles or path; an
        invalid robot or config (non-positive limits, v_min >= v_max, d_safe below the
        footprint radius, …); negative, NaN or infinite weights; an empty dynamic window; a
        robot centred off the map or on a blocked cell.

    Example:
      >>> import numpy as np, jaxplan as jp
      >>> grid = jp.grid_from_array(np.ones((20, 20), bool), resolution=0.5)
      >>> u, info = jp.dwa_step([2.0, 5.0, 0.0, 0.5, 0.0], [8.0, 5.0], grid)
      >>> u.shape, info.rollouts.shape, bool(info.feasible[info.chosen])
      ((2,), (800, 20, 3), True)
    """
    config = with_brake_periods(validate_config(DWAConfig() if config is None else config))
    prm = validate_params(params, config.evaluator)
    if obstacles is None and path is None and isinstance(grid, GridMap):
        robot = one_robot(state, subgoal, grid, config)
        if robot is not None:  # one robot, all checks passed: the lean path
            table, prm_dev = table_of(grid), params_on_device(prm)
            if not full_info:
                return np.asarray(_single_control(table, device_config(config, True), prm_dev, *robot)), None
            return _numpy_info(_single(table, device_config(config), prm_dev, *robot, None, None), grid)
    st = np.asarray(state, dtype=np.float64)
    single = st.ndim == 1
    if st.shape[-1:] != (5,) or st.ndim not in (1, 2) or st.shape[0] == 0:
        raise ValueError(f"state must be [5] (x, y, theta, v, omega) or [B, 5], got shape {st.shape}")
    st2 = st[None] if single else st
    if not np.isfinite(st2).all():
        i = int(np.argmax(~np.isfinite(st2).all(axis=1)))
        raise ValueError(f"state{'' if single else f'[{i}]'} has NaN or infinite values: {st2[i].tolist()}")
    B = st2.shape[0]
    sg = np.asarray(subgoal, dtype=np.float64)
    if sg.shape != ((2,) if single else (B, 2)):
        raise ValueError(f"subgoal must have shape {(2,) if single else (B, 2)} to match the state, got {sg.shape}")
    if not np.isfinite(sg).all():
        raise ValueError("subgoal has NaN or infinite values")
    _check_window(config, st2)
    obs = as_obstacles(obstacles, None if single else B)
    pa = None
    if path is not None:
        pa = np.asarray(path, dtype=np.float64)
        want = 2 if single or pa.ndim == 2 else 3
        if pa.ndim != want or pa.shape[-1] != 2 or pa.shape[-2] < 1 or (pa.ndim == 3 and pa.shape[0] != B):
            raise ValueError(f"path must be [L, 2] (m) or [B, L, 2] with B = {B}, got shape {pa.shape}")
        if not np.isfinite(pa).all():
            raise ValueError("path has NaN or infinite values")
        pa = pa.astype(np.float32)
    if not isinstance(grid, GridMap):
        raise ValueError(f"grid must be a GridMap, got {type(grid).__name__}")
    if grid.has_origin:  # world -> the map's frame, where the tables are; rollouts go back below
        st2, sg = grid.to_local(st2), grid.to_local(sg)
        st = st2[0] if single else st2
        obs, pa = obstacles_to_local(obs, grid), None if pa is None else grid.to_local(pa)
    _check_on_free_cells(grid, st2, single)
    table = table_of(grid)
    if not full_info:
        config = config.replace(keep_rollouts=False)
    single_fn, batch_fn = (_single, _batch) if full_info else (_single_control, _batch_control)
    if single:
        out = single_fn(table, config, prm, st.astype(np.float32), sg.astype(np.float32), obs, pa)
    else:
        # Pad the batch to whole chunks: one compilation per bucket, no remainder trace.
        Bp = B if B <= CHUNK else -(-B // CHUNK) * CHUNK

        def pad(a):
            return np.concatenate([a, np.repeat(a[-1:], Bp - B, axis=0)]) if Bp > B else a

        if obs is not None and obs.radii.ndim == 2:
            obs = DiscObstacles(*(None if a is None else pad(a) for a in obs))
        if pa is not None and pa.ndim == 3:
            pa = pad(pa)
        out = batch_fn(table, config, prm, pad(st2).astype(np.float32), pad(sg).astype(np.float32), obs, pa,
                       chunk=CHUNK)
        if Bp > B:
            out = jax.tree_util.tree_map(lambda a: a[:B], out)
    if not full_info:
        return np.asarray(out), None
    return _numpy_info(out, grid)


def _numpy_info(out: tuple[Any, DWAInfo], grid: GridMap) -> tuple[np.ndarray, DWAInfo]:
    """The control and info of a step as numpy arrays, rollouts in the world frame."""
    u, info = jax.device_get(out)
    info = DWAInfo(*(None if a is None else np.asarray(a) for a in info))
    if grid.has_origin and info.rollouts is not None:
        info = info._replace(rollouts=grid.to_world(info.rollouts))
    return np.asarray(u), info


def obstacles_to_local(obs: DiscObstacles | None, grid: GridMap) -> DiscObstacles | None:
    """Disc obstacles given in world coordinates, moved into ``grid``'s frame (its origin subtracted)."""
    if obs is None or not grid.has_origin:
        return obs
    return obs._replace(positions=grid.to_local(obs.positions).astype(np.float32),
                        track=None if obs.track is None else grid.to_local(obs.track).astype(np.float32))
