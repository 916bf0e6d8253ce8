"""Validation of MPPI configs and parameters, and the host front `mppi_step` for scripts that step one robot.

`mppi_control` is pure and cannot raise; everything a user hands in is checked here first, with a
`ValueError` naming the problem. `mppi_step` is the one-robot front (like `jaxplan.dwa.dwa_step`): it
validates, looks up the map's clearance table (cached per map), and runs one compiled step; the caller
keeps the returned sequence and passes it back as the next call's ``sequence`` (it is shifted here).

Per call the front does only what the call needs: a configuration is checked once (the last 64 are
kept), the weights go to the device once per value, an integer seed becomes a PRNG key inside the
compiled step (the same key as ``jax.random.key(seed)``), and with ``full_info=False`` the step
returns the control and the sequence alone.
"""

from __future__ import annotations

import math
from typing import Any, Mapping

import jax
import jax.numpy as jnp
import numpy as np
from numpy.typing import ArrayLike

from jaxplan.core.cache import lru_cache
from jaxplan.core.xla import one_thread_options
from jaxplan.dwa import (
    CLEARANCE_MODES,
    SAFETY_MODES,
    DWAConfig,
    as_obstacles,
    check_safety,
    obstacles_to_local,
    table_of,
    with_brake_periods,
)
from jaxplan.dwa import validate_config as validate_dwa_config
from jaxplan.grid import GridMap
from jaxplan.mppi._config import MPPIConfig, MPPIParams, default_params
from jaxplan.mppi._core import MPPIInfo, fixed_rows, mppi_control, shift

__all__ = ["validate_config", "validate_params", "mppi_step"]


def validate_config(config: MPPIConfig) -> MPPIConfig:
    """Checks an `MPPIConfig` and its robot; raises ValueError naming the first problem. Returns ``config``."""
    if not isinstance(config, MPPIConfig):
        raise ValueError(f"config must be an MPPIConfig, got {type(config).__name__}")
    try:
        hash(config)
    except TypeError:  # array-valued fields: check every time
        _check_config(config)
    else:
        _checked_config(config)  # each valid configuration is checked once (the last 64 are kept)
    return config


def _check_config(config: MPPIConfig) -> None:
    # The robot, period and d_safe are the DWA's checks (one robot model for both local planners).
    validate_dwa_config(DWAConfig(robot=config.robot, period=config.period, d_safe=config.d_safe))
    for name in ("samples", "steps", "substeps", "iterations", "brake_points"):
        v = getattr(config, name)
        if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or v < 1:
            raise ValueError(f"MPPIConfig.{name} must be a positive integer, got {v!r}")
    if config.samples < fixed_rows(config) + 1:
        raise ValueError(f"MPPIConfig.samples must be >= {fixed_rows(config) + 1} ({fixed_rows(config)} fixed "
                         f"candidates and at least one noisy sequence), got {config.samples}")
    for name in ("d_clip", "disc_clip", "path_clip", "goal_radius"):
        v = getattr(config, name)
        if not (isinstance(v, (int, float, np.floating)) and math.isfinite(v) and v > 0):
            raise ValueError(f"MPPIConfig.{name} must be a finite number > 0, got {v!r}")
    if config.clearance not in CLEARANCE_MODES:
        raise ValueError(f"unknown clearance mode {config.clearance!r}; choose from {CLEARANCE_MODES}")
    for name in ("escape", "keep_rollouts"):
        if not isinstance(getattr(config, name), bool):
            raise ValueError(f"MPPIConfig.{name} must be True or False, got {getattr(config, name)!r}")
    if config.safety not in SAFETY_MODES:
        raise ValueError(f"MPPIConfig.safety must be one of {SAFETY_MODES}, got {config.safety!r}")
    check_safety(config, "MPPIConfig")


_checked_config = lru_cache(maxsize=64)(_check_config)
_defaults = lru_cache(maxsize=1)(default_params)


def validate_params(params: MPPIParams | Mapping[str, float] | None) -> MPPIParams:
    """`MPPIParams` from None (the defaults), a mapping of overrides or `MPPIParams`; every value checked."""
    if params is None:
        return _defaults()
    if isinstance(params, Mapping):
        return default_params(**params)
    if not isinstance(params, MPPIParams):
        raise ValueError(f"params must be MPPIParams, a dict of overrides or None, got {type(params).__name__}")
    values = {}
    for name, x in params._asdict().items():
        a = np.asarray(x, dtype=np.float64)
        if a.shape != ():
            raise ValueError(f"params.{name} must be a scalar, got shape {a.shape}")
        values[name] = float(a)
    return default_params(**values)


@lru_cache(maxsize=16)
def _program(config: MPPIConfig, with_obstacles: bool, with_path: bool, seeded: bool = False,
             full_info: bool = True):
    """The compiled step. ``seeded``: ``key`` is an int32 seed, made a key inside (as ``jax.random.key(seed)``
    would outside: the same key data); ``full_info=False``: only the control and the new sequence come back."""

    def step(table, params, state, mean, key, subgoal, goal, obstacles, path):
        k = jax.random.key(key) if seeded else key
        u, info = mppi_control(table, config, params, state, shift(mean), k, subgoal, goal,
                               obstacles if with_obstacles else None, path if with_path else None)
        return (u, info) if full_info else (u, info.sequence)

    # One robot's step, called from Python: compiled without XLA:CPU's loop splitting (`jaxplan.core.xla`).
    return jax.jit(step, compiler_options=one_thread_options())


@lru_cache(maxsize=64)
def _params_on_device(key: tuple[bytes, ...]) -> MPPIParams:
    return jax.device_put(MPPIParams(*(np.frombuffer(b, np.float32)[0] for b in key)))


def _on_device(params: MPPIParams) -> MPPIParams:
    """Validated float32 weights as device arrays, one per distinct value (keyed by their bits)."""
    return _params_on_device(tuple(np.float32(x).tobytes() for x in params))


_INT32 = (-(2 ** 31), 2 ** 31)


def mppi_step(state: ArrayLike, subgoal: ArrayLike, grid: GridMap, *, obstacles: Any = None,
              params: MPPIParams | Mapping[str, float] | None = None, config: MPPIConfig | None = None,
              path: ArrayLike | None = None, full_info: bool = True, sequence: ArrayLike | None = None,
              key: Any = 0, goal: ArrayLike | None = None) -> tuple[np.ndarray, MPPIInfo]:
    """One MPPI step for one robot from Python (the signature of `jaxplan.dwa_step`, then MPPI's own keywords).

    Args:
      state: ``[5]`` (x, y, θ, v, ω) in m, rad, m/s, rad/s.
      subgoal: ``[2]`` (m) the point to head for now.
      grid: the map.
      obstacles: moving discs as for `jaxplan.dwa.dwa_step` (`DiscObstacles` or (positions, velocities, radii)).
      params: `MPPIParams` or a dict of overrides of the defaults.
      config: `MPPIConfig` (default: `MPPIConfig()`).
      path: ``[L, 2]`` (m) the stretch of the global path ahead, or None.
      full_info: False returns an `MPPIInfo` holding the new ``sequence`` only (the other fields None): the
        same control and sequence, bit for bit, without copying the samples' record.
      sequence: the previous call's ``info.sequence`` ``[T, 2]`` (warm start; shifted here), or None.
      key: an int seed or a JAX PRNG key for this step's noise (same key, same control).
      goal: ``[2]`` (m) the goal (default: the sub-goal).

    Returns:
      ``(control (v, ω) as numpy f32[2], MPPIInfo)``.
    """
    config = with_brake_periods(validate_config(MPPIConfig() if config is None else config))
    p = validate_params(params)
    state = np.asarray(state, np.float32)
    if state.shape != (5,) or not np.all(np.isfinite(state)):
        raise ValueError(f"state must be 5 finite numbers (x, y, theta, v, omega), got {state.tolist()}")
    sub = np.asarray(subgoal, np.float32)
    if sub.shape != (2,) or not np.all(np.isfinite(sub)):
        raise ValueError(f"subgoal must be 2 finite numbers (m), got {np.asarray(subgoal).tolist()}")
    g = sub if goal is None else np.asarray(goal, np.float32)
    if g.shape != (2,) or not np.all(np.isfinite(g)):
        raise ValueError(f"goal must be 2 finite numbers (m), got {np.asarray(goal).tolist()}")
    if sequence is None:
        # `_program` shifts its input: a held-velocity sequence shifts to itself. `initial_sequence` in numpy
        # (a copy of two float32 numbers: the same bits without a device call).
        mean = np.broadcast_to(state[3:5], (config.steps, 2)).astype(np.float32)
    else:
        mean = np.asarray(sequence, np.float32)
        if mean.shape != (config.steps, 2) or not np.all(np.isfinite(mean)):
            raise ValueError(f"sequence must be the previous step's [{config.steps}, 2] finite sequence, "
                             f"got shape {mean.shape}")
    obs = as_obstacles(obstacles, None)
    pa = None if path is None else np.asarray(path, np.float32)
    if pa is not None and (pa.ndim != 2 or pa.shape[1] != 2 or pa.shape[0] < 1 or not np.all(np.isfinite(pa))):
        raise ValueError(f"path must be [L, 2] finite points (m), got shape {pa.shape}")
    seeded = isinstance(key, (int, np.integer)) and not isinstance(key, bool) and _INT32[0] <= key < _INT32[1]
    if seeded:
        k = np.int32(key)
    else:
        k = jax.random.key(int(key)) if isinstance(key, (int, np.integer)) else key
    if grid.has_origin:  # world -> the map's frame, where the tables are; rollout points go back below
        state, sub, g = (grid.to_local(a).astype(np.float32) for a in (state, sub, g))
        obs = obstacles_to_local(obs, grid)
        pa = None if pa is None else grid.to_local(pa).astype(np.float32)
    fn = _program(config, obs is not None, pa is not None, seeded, full_info)
    u, info = fn(table_of(grid), _on_device(p), state, mean, k, sub, g, obs, pa)
    if not full_info:
        return np.asarray(u), MPPIInfo(info, *(None,) * (len(MPPIInfo._fields) - 1))
    if grid.has_origin and info.points is not None:
        info = info._replace(points=jnp.asarray(grid.to_world(np.asarray(info.points))))
    return np.asarray(u), info
