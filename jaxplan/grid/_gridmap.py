"""The `GridMap` pytree: an occupancy grid with the extra layers the seed papers use.

Conventions (docs/guide/maps-and-scenarios.md#conventions): cells are ``(x, y)`` = (column, row), row 0 at the top;
flat index ``i = y * W + x``; the centre of cell ``(x, y)`` lies at
``origin + ((x + 0.5) * res, (y + 0.5) * res)`` metres, with ``origin`` ``(0, 0)`` unless the map
says otherwise (a ROS map's YAML does: see `jaxplan.grid.load_ros_map`).

The origin is a translation: every planner, rollout and metric computes in the map's own frame
(metres from the corner of cell ``(0, 0)``), which differs from the world frame by ``origin`` only,
so no result depends on it. It is added where metres leave the library (`GridMap.centre`,
`GridMap.to_world`, episodes' trajectories and waypoints, `dwa_step`/`mppi_step` rollouts) and
subtracted where they enter (`GridMap.cell_at`, `GridMap.to_local`, obstacle routes, DWA/MPPI states).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import numpy as np
from numpy.typing import ArrayLike

__all__ = ["GridMap", "grid_from_array", "passable", "check_cell", "check_cells"]

ZERO_ORIGIN = (0.0, 0.0)


class GridMap(NamedTuple):
    """An occupancy grid and its terrain layers. A pytree: the layers and the resolution are leaves (and
    ``speed_limit`` when there is one); ``origin`` is static data (it never enters a computation, see the
    module docstring), so a map without a speed limit has the same six leaves as before either existed.

    Attributes:
      free: ``bool[H, W]``, True where a robot may stand.
      height: ``f32[H, W]`` terrain height in metres (chu2024's mountain map), 0 by default.
      clearance_height: ``f32[H, W]`` the headroom of a tunnel or bridge cell in metres;
        a vehicle passes only if it is lower than this. ``+inf`` (no roof) by default.
      risk: ``f32[H, W]`` intensity of chen2023's "unknown factors" (>= 0), 0 by default.
      turn_rule: ``i8[H, W]`` 0 = no rule, 1 = right turn required (chu2024's urban map).
      resolution: metres per cell (a scalar leaf, so maps of several resolutions can be batched).
      origin: ``(x, y)`` world coordinates in metres of the outer corner of cell ``(0, 0)``
        (``(0, 0)`` by default; a ROS map's ``origin``). Two float leaves.
      speed_limit: ``None`` (no limit, the default) or ``f32[H, W]`` in ``(0, 1]``: the fraction of the
        robot's top speed allowed in each cell (a Nav2 speed filter mask, `jaxplan.grid.load_ros_map`);
        the DWA and MPPI windows cap their top speed at the value of the robot's cell.

    Example:
      >>> import numpy as np, jaxplan as jp
      >>> g = jp.grid_from_array(np.ones((3, 4), bool), resolution=0.5)
      >>> g.shape, g.n_cells
      ((3, 4), 12)
    """

    free: np.ndarray
    height: np.ndarray
    clearance_height: np.ndarray
    risk: np.ndarray
    turn_rule: np.ndarray
    resolution: float
    origin: tuple[float, float] = ZERO_ORIGIN
    speed_limit: np.ndarray | None = None

    @property
    def shape(self) -> tuple[int, int]:
        """``(H, W)``: rows, columns."""
        return tuple(self.free.shape)  # type: ignore[return-value]

    @property
    def width(self) -> int:
        return int(self.free.shape[1])

    @property
    def height_cells(self) -> int:
        return int(self.free.shape[0])

    @property
    def n_cells(self) -> int:
        return int(self.free.shape[0] * self.free.shape[1])

    def flat_index(self, cells: ArrayLike) -> np.ndarray:
        """``int[..., 2]`` cells ``(x, y)`` -> ``int[...]`` flat indices ``y * W + x``."""
        c = np.asarray(cells)
        return c[..., 1] * self.width + c[..., 0]

    def cell_of(self, flat: ArrayLike) -> np.ndarray:
        """``int[...]`` flat indices -> ``int[..., 2]`` cells ``(x, y)``."""
        f = np.asarray(flat)
        return np.stack([f % self.width, f // self.width], axis=-1)

    @property
    def has_origin(self) -> bool:
        """True if the origin is not ``(0, 0)`` (world and map frame differ)."""
        return tuple(float(v) for v in self.origin) != ZERO_ORIGIN

    def centre(self, cells: ArrayLike) -> np.ndarray:
        """``int[..., 2]`` cells -> ``f64[..., 2]`` world coordinates of their centres (m), origin included."""
        return self.to_world((np.asarray(cells, dtype=np.float64) + 0.5) * float(self.resolution))

    def cell_at(self, points: ArrayLike) -> np.ndarray:
        """``f[..., 2]`` world points (m) -> ``int64[..., 2]`` cells ``(x, y)`` that contain them.

        ``floor((p - origin) / res)``; a point outside the map gives a cell outside it (check with
        `check_cells`), a point on a cell edge belongs to the cell above/right of it.
        """
        p = np.asarray(points, dtype=np.float64) - np.asarray(self.origin, np.float64)
        return np.floor(p / float(self.resolution)).astype(np.int64)

    def to_world(self, local: ArrayLike) -> np.ndarray:
        """``f[..., 2+]`` points in the map's frame (m from the corner of cell (0, 0)) -> world frame: adds
        ``origin`` to the first two columns (``(x, y, theta, ...)`` rows keep their other columns). With the
        default origin the input comes back unchanged (the same bits)."""
        a = np.asarray(local)
        if not self.has_origin:
            return a
        out = np.array(a, dtype=np.result_type(a.dtype, np.float32), copy=True)
        o = np.asarray(self.origin, np.float64).astype(out.dtype)
        out[..., 0] += o[0]  # column by column: a broadcast over the last axis's first two entries is 10x slower
        out[..., 1] += o[1]
        return out

    def to_local(self, world: ArrayLike) -> np.ndarray:
        """The inverse of `to_world`: subtracts ``origin`` from the first two columns."""
        a = np.asarray(world)
        if not self.has_origin:
            return a
        out = np.array(a, dtype=np.result_type(a.dtype, np.float32), copy=True)
        o = np.asarray(self.origin, np.float64).astype(out.dtype)
        out[..., 0] -= o[0]
        out[..., 1] -= o[1]
        return out

    def replace(self, **fields: Any) -> "GridMap":
        """A copy with some layers replaced (validated like `grid_from_array`)."""
        d = self._asdict()
        d.update(fields)
        return grid_from_array(
            d["free"],
            resolution=d["resolution"],
            height=d["height"],
            clearance_height=d["clearance_height"],
            risk=d["risk"],
            turn_rule=d["turn_rule"],
            origin=d["origin"],
            speed_limit=d["speed_limit"],
        )


def _flatten(g: GridMap) -> tuple[tuple, tuple[float, float]]:
    return (g.free, g.height, g.clearance_height, g.risk, g.turn_rule, g.resolution, g.speed_limit), g.origin


def _unflatten(origin: tuple[float, float], leaves: tuple) -> GridMap:
    free, height, clearance_height, risk, turn_rule, resolution, speed_limit = leaves
    return GridMap(free, height, clearance_height, risk, turn_rule, resolution, origin=origin, speed_limit=speed_limit)


jax.tree_util.register_pytree_node(GridMap, _flatten, _unflatten)


def _layer(name: str, value: ArrayLike | None, shape: tuple[int, int], dtype: type, default: float,
           finite: bool = False) -> np.ndarray:
    """The layer as ``dtype[H, W]``; with ``finite``, ±inf is refused too (checked after the cast,
    so a float64 value beyond float32's range is caught as the inf it becomes)."""
    if value is None:
        return np.full(shape, default, dtype=dtype)
    arr = np.asarray(value)
    if arr.shape != shape:
        raise ValueError(f"layer '{name}' has shape {arr.shape}, but the map is {shape} (rows, columns)")
    if np.issubdtype(dtype, np.floating) and np.isnan(arr.astype(np.float64)).any():
        raise ValueError(f"layer '{name}' contains NaN")
    with np.errstate(over="ignore"):  # an overflow becomes inf, reported below or documented (headroom)
        out: np.ndarray = arr.astype(dtype)
    if finite and np.issubdtype(dtype, np.floating) and not np.isfinite(out).all():
        y, x = np.argwhere(~np.isfinite(out))[0]
        raise ValueError(f"layer '{name}' must be finite, got {float(arr[y, x])} at cell ({x}, {y})")
    return out


def grid_from_array(
    free: ArrayLike,
    resolution: float = 1.0,
    height: ArrayLike | None = None,
    risk: ArrayLike | None = None,
    clearance_height: ArrayLike | None = None,
    turn_rule: ArrayLike | None = None,
    origin: ArrayLike = ZERO_ORIGIN,
    speed_limit: ArrayLike | None = None,
) -> GridMap:
    """Builds a validated `GridMap` from a boolean occupancy array.

    Args:
      free: ``bool[H, W]`` (row y, column x), True where passable.
      resolution: metres per cell, finite and > 0.
      height, risk, clearance_height, turn_rule: optional ``[H, W]`` layers (see `GridMap`);
        height and risk finite, clearance_height ``+inf`` where there is no roof.
      origin: ``(x, y)`` world metres of the outer corner of cell ``(0, 0)`` (finite).
      speed_limit: optional ``[H, W]`` fraction of the top speed allowed per cell, in ``(0, 1]``.

    Raises:
      ValueError: naming the layer, for a wrong shape, NaN, an infinite height or risk,
        a negative risk or clearance height, a turn rule other than 0/1, a speed limit outside
        ``(0, 1]`` or an origin that is not two finite numbers.

    Returns:
      A `GridMap` holding numpy arrays (convert with ``jax.numpy.asarray`` inside programs).
    """
    f = np.asarray(free)
    if f.ndim != 2 or f.shape[0] < 1 or f.shape[1] < 1:
        raise ValueError(f"free must be a non-empty 2-D array [H, W], got shape {f.shape}")
    if f.dtype != np.bool_:
        if not np.isin(f, (0, 1)).all():
            raise ValueError("free must be boolean (or 0/1): True where passable")
        f = f.astype(bool)
    res = float(resolution)
    if not np.isfinite(res) or res <= 0:
        raise ValueError(f"resolution must be a finite number of metres per cell > 0, got {resolution!r}")
    shape = f.shape
    # Costs add height differences and risk: one inf makes every path through it cost inf.
    r = _layer("risk", risk, shape, np.float32, 0.0, finite=True)
    if (r < 0).any():
        raise ValueError("layer 'risk' must be >= 0")
    ch = _layer("clearance_height", clearance_height, shape, np.float32, np.inf)
    if (ch < 0).any():
        raise ValueError("layer 'clearance_height' must be >= 0")
    tr = _layer("turn_rule", turn_rule, shape, np.int8, 0)
    if not np.isin(tr, (0, 1)).all():
        raise ValueError("layer 'turn_rule' must hold 0 (none) or 1 (right turn required)")
    try:
        o = tuple(float(v) for v in np.asarray(origin, dtype=np.float64).reshape(-1))
    except (TypeError, ValueError):
        raise ValueError(f"origin must be two numbers (x, y) in metres, got {origin!r}") from None
    if len(o) != 2 or not all(np.isfinite(o)):
        raise ValueError(f"origin must be two finite numbers (x, y) in metres, got {origin!r}")
    o = (o[0] + 0.0, o[1] + 0.0)  # -0.0 -> 0.0: the origin (0, 0) has one spelling
    sl = None
    if speed_limit is not None:
        sl = _layer("speed_limit", speed_limit, shape, np.float32, 1.0, finite=True)
        if not ((sl > 0) & (sl <= 1)).all():
            raise ValueError("layer 'speed_limit' must hold fractions of the top speed in (0, 1]")
    return GridMap(
        free=f.copy(),
        height=_layer("height", height, shape, np.float32, 0.0, finite=True),
        clearance_height=ch,
        risk=r,
        turn_rule=tr,
        resolution=res,
        origin=o,
        speed_limit=sl,
    )


def passable(grid: GridMap, vehicle_height: float | None = None) -> np.ndarray:
    """``bool[H, W]``: free cells, less tunnel/bridge cells too low for the vehicle.

    A cell with ``clearance_height <= vehicle_height`` is blocked (docs/guide/planners.md, opt_ant).
    """
    free = np.asarray(grid.free, dtype=bool)
    if vehicle_height is None:
        return free
    vh = float(vehicle_height)
    if not np.isfinite(vh) or vh < 0:
        raise ValueError(f"vehicle_height must be a finite height >= 0 in metres, got {vehicle_height!r}")
    return free & (np.asarray(grid.clearance_height) > vh)


def check_cell(grid: GridMap, cell: ArrayLike, what: str, free: np.ndarray | None = None) -> tuple[int, int]:
    """Validates one ``(x, y)`` cell: integral, inside the map and passable. Returns it as ints."""
    c = np.asarray(cell)
    if c.shape != (2,):
        raise ValueError(f"{what} must be a cell (x, y), got shape {c.shape}")
    if not np.all(np.isfinite(c.astype(np.float64))) or not np.all(np.asarray(c, np.float64) == np.round(c)):
        raise ValueError(f"{what} must hold integer cell coordinates (x, y), got {c.tolist()}")
    x, y = int(c[0]), int(c[1])
    H, W = grid.shape
    if not (0 <= x < W and 0 <= y < H):
        raise ValueError(f"{what} {(x, y)} lies outside the {W}x{H} map (x in [0, {W}), y in [0, {H}))")
    ok = np.asarray(grid.free) if free is None else free
    if not ok[y, x]:
        raise ValueError(f"{what} {(x, y)} is on a blocked cell")
    return x, y


def check_cells(grid: GridMap, cells: ArrayLike, what: str, free: np.ndarray | None = None) -> np.ndarray:
    """Validates ``int[N, 2]`` cells at once; the error names the first bad row."""
    c = np.asarray(cells)
    if c.ndim != 2 or c.shape[1] != 2:
        raise ValueError(f"{what} must be an array of cells [N, 2] (x, y), got shape {c.shape}")
    cf = c.astype(np.float64)
    bad = ~np.isfinite(cf).all(axis=1) | (cf != np.round(cf)).any(axis=1)
    if bad.any():
        i = int(np.argmax(bad))
        raise ValueError(f"{what}[{i}] must hold integer cell coordinates, got {c[i].tolist()}")
    ci = c.astype(np.int64)
    H, W = grid.shape
    out = (ci[:, 0] < 0) | (ci[:, 0] >= W) | (ci[:, 1] < 0) | (ci[:, 1] >= H)
    if out.any():
        i = int(np.argmax(out))
        raise ValueError(f"{what}[{i}] = {tuple(ci[i].tolist())} lies outside the {W}x{H} map")
    ok = np.asarray(grid.free) if free is None else free
    blocked = ~ok[ci[:, 1], ci[:, 0]]
    if blocked.any():
        i = int(np.argmax(blocked))
        raise ValueError(f"{what}[{i}] = {tuple(ci[i].tolist())} is on a blocked cell")
    return ci


def check_pair(grid: GridMap, start: ArrayLike, goal: ArrayLike,
               free: np.ndarray | None = None) -> tuple[tuple[int, int], tuple[int, int]]:
    """Validates one start/goal pair: each a valid cell (`check_cell`), and different. Returns them as ints."""
    s = check_cell(grid, start, "start", free)
    g = check_cell(grid, goal, "goal", free)
    if s == g:
        raise ValueError(f"start {s} equals the goal; nothing to plan")
    return s, g


def check_pairs(grid: GridMap, starts: ArrayLike, goals: ArrayLike, free: np.ndarray | None = None, *,
                distinct: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Validates ``int[N, 2]`` starts and goals (`check_cells` each) of one shape and, with ``distinct``, no start
    equal to its goal; the error names the first bad row. Returns them as ``int64[N, 2]``."""
    s = check_cells(grid, starts, "starts", free)
    g = check_cells(grid, goals, "goals", free)
    if s.shape != g.shape:
        raise ValueError(f"starts and goals differ in shape: {s.shape} vs {g.shape}")
    same = (s == g).all(axis=1)
    if distinct and same.any():
        i = int(np.argmax(same))
        raise ValueError(f"scenario {i}: start {tuple(s[i].tolist())} equals the goal; nothing to plan")
    return s, g
