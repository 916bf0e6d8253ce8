"""Deterministic map generators for the seed papers' test environments.

Each generator is a frozen dataclass of static settings; calling it with a PRNG
key (or an integer seed) returns a `Scene`: the map plus a default start and goal.
The same key gives the same scene, bit for bit.

The papers describe their maps only in figures and counts (see each class), so
the layouts below are jaxplan's reconstructions that match the published sizes,
obstacle counts and features; what they invent is written down in the docstrings.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import jax
import numpy as np
from numpy.typing import ArrayLike

from jaxplan.grid._graph import shortest_lengths
from jaxplan.grid._gridmap import GridMap, grid_from_array

__all__ = [
    "Scene",
    "as_rng",
    "WarehouseGenerator",
    "RandomMapGenerator",
    "UrbanGenerator",
    "MountainGenerator",
    "poisson_risk",
    "warehouse_chen2023",
    "warehouse_yu2020",
    "demo_warehouse",
]


class Scene(NamedTuple):
    """A generated environment.

    Attributes:
      grid: the map.
      start, goal: ``int64[2]`` default start and goal cells ``(x, y)`` (free, connected).
      dynamic_slots: ``int64[k, 2]`` free cells where moving obstacles start (may be empty).
      name: a short description (generator and size).
    """

    grid: GridMap
    start: np.ndarray
    goal: np.ndarray
    dynamic_slots: np.ndarray
    name: str


def as_rng(key: Any) -> np.random.Generator:
    """A numpy generator derived deterministically from a JAX PRNG key or an int seed."""
    if isinstance(key, (int, np.integer)):
        if key < 0:
            raise ValueError(f"seed must be >= 0, got {key}")
        return np.random.default_rng(int(key))
    try:
        data = jax.random.key_data(key) if jax.dtypes.issubdtype(key.dtype, jax.dtypes.prng_key) else key
        words = np.asarray(data, dtype=np.uint32).ravel()
    except (AttributeError, TypeError):
        raise TypeError(f"expected a jax PRNG key or an integer seed, got {type(key).__name__}") from None
    return np.random.default_rng(words.tolist())


def _connected(free: np.ndarray, a: tuple[int, ...], b: tuple[int, ...], connectivity: int = 8) -> bool:
    g = grid_from_array(free)
    return bool(np.isfinite(shortest_lengths(g, [a], [b], connectivity=connectivity)[0]))


def _cells(*pairs: ArrayLike) -> np.ndarray:
    return np.array(pairs, dtype=np.int64).reshape(-1, 2)


@dataclass(frozen=True)
class WarehouseGenerator:
    """Warehouse of rectangular shelf blocks separated by aisles (chen2023, yu2020).

    Shelves are ``shelf_depth`` x ``shelf_length`` blocks (rows x columns) placed
    on a regular lattice inside a free ``margin`` ring, with ``aisle`` free rows
    between block rows and ``cross_aisle`` free columns between block columns.
    chen2023 draws each shelf as six consecutive cells and combines two back to
    back (depth 2). The key decides which blocks are left out
    (``missing_prob``) and, when ``n_blocked`` is given, which shelf ends are
    trimmed to hit that exact count of blocked cells (yu2020's ≈200 / ≈400).
    Removing shelf cells never disconnects the aisles, so every free cell is
    reachable. Start and goal: opposite corners of the margin ring.
    """

    width: int = 20
    height: int = 20
    shelf_length: int = 6
    shelf_depth: int = 2
    aisle: int = 1
    cross_aisle: int = 2
    margin: int = 1
    missing_prob: float = 0.0
    n_blocked: int | None = None
    resolution: float = 1.0

    def __post_init__(self) -> None:
        for name in ("width", "height", "shelf_length", "shelf_depth", "aisle", "cross_aisle", "margin"):
            if getattr(self, name) < 1:
                raise ValueError(f"WarehouseGenerator.{name} must be >= 1, got {getattr(self, name)}")
        if not 0.0 <= self.missing_prob < 1.0:
            raise ValueError(f"missing_prob must be in [0, 1), got {self.missing_prob}")
        # The upper limit (the shelf cells of the layout) depends on the draw: checked in __call__.
        if self.n_blocked is not None and (not _is_int(self.n_blocked) or self.n_blocked < 0):
            raise ValueError(f"WarehouseGenerator.n_blocked must be None or an integer >= 0, got {self.n_blocked!r}")

    def blocks(self) -> list[tuple[int, int]]:
        """Top-left cells ``(x, y)`` of every shelf slot of the lattice, centred in the map."""

        def starts(size: int, block: int, gap: int) -> list[int]:
            inner = size - 2 * self.margin
            n = (inner + gap) // (block + gap)
            used = n * block + max(n - 1, 0) * gap
            first = self.margin + (inner - used) // 2
            return [first + i * (block + gap) for i in range(n)]

        ys = starts(self.height, self.shelf_depth, self.aisle)
        xs = starts(self.width, self.shelf_length, self.cross_aisle)
        return [(x, y) for y in ys for x in xs]

    def __call__(self, key: Any) -> Scene:
        rng = as_rng(key)
        free = np.ones((self.height, self.width), dtype=bool)
        # Each shelf row of each block is a segment [x0, x1) that trimming shortens from either end.
        segments: list[list[int]] = []
        for bx, by in self.blocks():
            if rng.random() < self.missing_prob:
                continue
            for r in range(self.shelf_depth):
                segments.append([by + r, bx, bx + self.shelf_length])
        total = sum(s[2] - s[1] for s in segments)
        if self.n_blocked is not None:
            if self.n_blocked > total:
                raise ValueError(
                    f"n_blocked={self.n_blocked} exceeds the {total} shelf cells this layout holds; "
                    "use narrower aisles, longer shelves or a larger map"
                )
            while total > self.n_blocked:
                live = [s for s in segments if s[2] > s[1]]
                s = live[rng.integers(len(live))]
                if rng.random() < 0.5:
                    s[1] += 1
                else:
                    s[2] -= 1
                total -= 1
        for y, x0, x1 in segments:
            free[y, x0:x1] = False
        grid = grid_from_array(free, resolution=self.resolution)
        name = f"warehouse {self.width}x{self.height}, {int((~free).sum())} shelf cells"
        return Scene(grid, _cells(0, 0)[0], _cells(self.width - 1, self.height - 1)[0], _cells(), name)


def warehouse_chen2023(key: Any = 0) -> Scene:
    """chen2023, Case 1: a 20x20 warehouse of combined shelves (two 1x6 shelves back to back)."""
    return WarehouseGenerator(20, 20, shelf_length=6, shelf_depth=2, aisle=1, cross_aisle=2)(key)


def warehouse_yu2020(key: Any = 0, size: int = 30) -> Scene:
    """yu2020: the 30x30 map with 200 blocked cells or the 35x35 map with 400."""
    if size == 30:
        return WarehouseGenerator(30, 30, shelf_length=6, shelf_depth=2, aisle=2, cross_aisle=2, n_blocked=200)(key)
    if size == 35:
        return WarehouseGenerator(35, 35, shelf_length=6, shelf_depth=2, aisle=1, cross_aisle=2, n_blocked=400)(key)
    raise ValueError(f"yu2020 uses sizes 30 and 35, got {size}")


def demo_warehouse() -> Scene:
    """The built-in 48x32 warehouse of `jaxplan demo` (fixed key: no data needed)."""
    return WarehouseGenerator(48, 32, shelf_length=8, shelf_depth=2, aisle=2, cross_aisle=3, missing_prob=0.1)(7)


@dataclass(frozen=True)
class RandomMapGenerator:
    """Uniformly random blocked cells at a given obstacle ratio (li2026 sweeps 10–40 %).

    Exactly ``round(obstacle_ratio * (W * H - 2))`` cells other than start and goal
    are blocked. The start–goal connection is guaranteed: up to ``tries`` draws are
    rejected while start and goal are disconnected; if all fail, a random
    4-connected monotone corridor from start to goal is kept free and the same
    number of obstacles is drawn among the other cells (the corridor is valid
    under 4, 8 and 16 connectivity).
    """

    width: int = 32
    height: int = 32
    obstacle_ratio: float = 0.2
    start: tuple[int, int] | None = None
    goal: tuple[int, int] | None = None
    connectivity: int = 8
    tries: int = 20
    resolution: float = 1.0

    def __post_init__(self) -> None:
        if self.width < 2 or self.height < 2:
            raise ValueError(f"random map must be at least 2x2, got {self.width}x{self.height}")
        if not 0.0 <= self.obstacle_ratio <= 0.9:
            raise ValueError(f"obstacle_ratio must be in [0, 0.9], got {self.obstacle_ratio}")

    def __call__(self, key: Any) -> Scene:
        rng = as_rng(key)
        W, H = self.width, self.height
        s = tuple(self.start) if self.start is not None else (0, 0)
        g = tuple(self.goal) if self.goal is not None else (W - 1, H - 1)
        for name, (x, y) in (("start", s), ("goal", g)):
            if not (0 <= x < W and 0 <= y < H):
                raise ValueError(f"{name} {(x, y)} lies outside the {W}x{H} map")
        if s == g:
            raise ValueError("start and goal must differ")
        n_obs = int(round(self.obstacle_ratio * (W * H - 2)))
        reserved = {s[1] * W + s[0], g[1] * W + g[0]}
        for _ in range(self.tries):
            free = self._draw(rng, n_obs, reserved)
            if _connected(free, s, g, self.connectivity):
                break
        else:
            corridor = self._corridor(rng, s, g)
            if n_obs > W * H - len(corridor):
                raise ValueError(f"obstacle_ratio {self.obstacle_ratio} leaves no room for a start-goal corridor")
            free = self._draw(rng, n_obs, reserved | corridor)
        grid = grid_from_array(free, resolution=self.resolution)
        return Scene(grid, np.array(s, np.int64), np.array(g, np.int64), _cells(),
                     f"random {W}x{H}, {self.obstacle_ratio:.0%} obstacles")

    def _draw(self, rng: np.random.Generator, n_obs: int, reserved: set[int]) -> np.ndarray:
        W, H = self.width, self.height
        candidates = np.setdiff1d(np.arange(W * H), np.fromiter(reserved, dtype=np.int64))
        free = np.ones(W * H, dtype=bool)
        free[rng.choice(candidates, size=min(n_obs, len(candidates)), replace=False)] = False
        return free.reshape(H, W)

    def _corridor(self, rng: np.random.Generator, s: tuple[int, ...], g: tuple[int, ...]) -> set[int]:
        (x, y), (gx, gy) = s, g
        sx, sy = int(np.sign(gx - x)), int(np.sign(gy - y))
        cells = {y * self.width + x}
        while (x, y) != (gx, gy):
            if x != gx and (y == gy or rng.random() < 0.5):
                x += sx
            else:
                y += sy
            cells.add(y * self.width + x)
        return cells


def _is_int(v: Any) -> bool:
    return isinstance(v, (int, np.integer)) and not isinstance(v, bool)


@dataclass(frozen=True)
class UrbanGenerator:
    """chu2024's 20x20 urban map: a street grid with right-turn cells and moving-car slots.

    Reconstruction (the paper gives only Figure 1): two-cell-wide streets on every
    sixth row and column (0–1, 6–7, 12–13, 18–19) around 4x4 building blocks
    (static obstacles). The key makes some blocks parks (free, with a hill in the
    ``height`` layer: chu2024's green cells, "the deeper the higher"); marks
    intersection cells as right-turn cells (``turn_rule = 1``, chu2024's brown
    cells) with probability ``right_turn_prob``; blocks ``n_interventions``
    street cells (the grey "random interventions"); and picks ``n_dynamic``
    street cells as starting slots of moving cars (the yellow squares). Start
    and goal are opposite corners; the draw is repeated until they connect.
    """

    park_prob: float = 0.25
    right_turn_prob: float = 0.3
    n_interventions: int = 6
    n_dynamic: int = 3
    hill_height: float = 3.0
    resolution: float = 1.0

    _SIZE, _PERIOD, _ROAD = 20, 6, 2

    @classmethod
    def _streets(cls) -> tuple[np.ndarray, np.ndarray]:
        """``(street_cell, crossing)``, each ``bool[20, 20]``: the fixed street layout."""
        street = (np.arange(cls._SIZE) % cls._PERIOD) < cls._ROAD
        return street[None, :] | street[:, None], street[None, :] & street[:, None]

    def __post_init__(self) -> None:
        for name in ("park_prob", "right_turn_prob"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(f"UrbanGenerator.{name} must be in [0, 1], got {getattr(self, name)!r}")
        street_cell, crossing = self._streets()
        # Interventions go on street cells off the crossings, never on start or goal (crossings);
        # cars start on the street cells left free, other than start and goal.
        plain = int((street_cell & ~crossing).sum())
        if not _is_int(self.n_interventions) or not 0 <= self.n_interventions <= plain:
            raise ValueError(f"UrbanGenerator.n_interventions must be an integer in [0, {plain}] (the street cells "
                             f"off the crossings), got {self.n_interventions!r}")
        slots = int(street_cell.sum()) - 2 - self.n_interventions
        if not _is_int(self.n_dynamic) or not 0 <= self.n_dynamic <= slots:
            raise ValueError(f"UrbanGenerator.n_dynamic must be an integer in [0, {slots}] (the free street cells "
                             f"other than start and goal with {self.n_interventions} interventions), got "
                             f"{self.n_dynamic!r}")

    def __call__(self, key: Any) -> Scene:
        rng = as_rng(key)
        size, period, road = self._SIZE, self._PERIOD, self._ROAD
        street_cell, crossing = self._streets()
        start, goal = (0, 0), (size - 1, size - 1)
        for _ in range(100):
            free = street_cell.copy()
            height = np.zeros((size, size), np.float32)
            for by in range(road, size, period):
                for bx in range(road, size, period):
                    if rng.random() < self.park_prob:
                        free[by : by + 4, bx : bx + 4] = True
                        yy, xx = np.mgrid[0:4, 0:4]
                        bump = np.exp(-((yy - 1.5) ** 2 + (xx - 1.5) ** 2) / 3.0)
                        height[by : by + 4, bx : bx + 4] = self.hill_height * bump
            turn = (crossing & (rng.random((size, size)) < self.right_turn_prob)).astype(np.int8)
            plain = np.flatnonzero((street_cell & ~crossing).ravel())
            plain = plain[(plain != start[1] * size + start[0]) & (plain != goal[1] * size + goal[0])]
            blocked = rng.choice(plain, size=self.n_interventions, replace=False)
            free.ravel()[blocked] = False
            if _connected(free, start, goal):
                break
        else:  # pragma: no cover - 100 failed draws would mean a broken setting
            raise RuntimeError("could not draw a connected urban map; lower n_interventions")
        candidates = np.setdiff1d(np.flatnonzero((free & street_cell).ravel()), [0, size * size - 1])
        slots = rng.choice(candidates, size=self.n_dynamic, replace=False)
        grid = grid_from_array(free, resolution=self.resolution, height=height, turn_rule=turn)
        return Scene(grid, np.array(start, np.int64), np.array(goal, np.int64),
                     np.stack([slots % size, slots // size], axis=1).astype(np.int64), "urban 20x20")


@dataclass(frozen=True)
class MountainGenerator:
    """chu2024's 30x30 mountain map: a height grid with a ridge crossed by tunnels and a bridge.

    Reconstruction (the paper gives only Figure 2 and two vehicle heights, 1.45 and
    0.5 m, of which only the lower passes five "three-dimensional" cells): terrain
    is a sum of random Gaussian hills scaled to ``[0, max_height]`` metres, cells
    above ``peak_height`` are absolute obstacles; a ridge three cells thick
    crosses the map from top to bottom at columns 14–16, blocked except for a
    tunnel (two rows x three columns = six cells with ``clearance_height`` drawn in
    ``tunnel_clearance``, so a 0.5 m vehicle passes and a 1.45 m one does not) and,
    far from the direct line, a gap open to any vehicle (the bridge deck). Start
    (1, 2) as in the paper's encounter scene; goal (28, 27).
    """

    max_height: float = 10.0
    peak_height: float = 8.5
    n_hills: int = 6
    tunnel_clearance: tuple[float, float] = (0.8, 1.2)
    resolution: float = 1.0

    def __call__(self, key: Any) -> Scene:
        rng = as_rng(key)
        n = 30
        start, goal = (1, 2), (28, 27)
        yy, xx = np.mgrid[0:n, 0:n].astype(np.float64)
        for _ in range(100):
            h = np.zeros((n, n))
            for _ in range(self.n_hills):
                cx, cy = rng.uniform(0, n, size=2)
                sigma = rng.uniform(2.0, 5.0)
                h += rng.uniform(0.5, 1.0) * np.exp(-((xx - cx) ** 2 + (yy - cy) ** 2) / (2 * sigma**2))
            h = self.max_height * h / h.max()
            free = h <= self.peak_height
            free[:, 14:17] = False
            ty = int(rng.integers(10, 19))
            clearance = np.full((n, n), np.inf, np.float32)
            free[ty : ty + 2, 14:17] = True
            clearance[ty : ty + 2, 14:17] = rng.uniform(*self.tunnel_clearance, size=(2, 3))
            gap = int(rng.choice([1, 27]))
            free[gap : gap + 2, 14:17] = True
            for c in (start, goal):
                free[c[1], c[0]] = True
            h[~free] = np.maximum(h[~free], self.peak_height)  # the ridge stands above the terrain
            tall = free & (clearance > 1.45)
            if _connected(tall, start, goal) and _connected(free, start, goal):
                break
        else:  # pragma: no cover
            raise RuntimeError("could not draw a connected mountain map")
        grid = grid_from_array(free, resolution=self.resolution, height=h.astype(np.float32),
                               clearance_height=clearance)
        return Scene(grid, np.array(start, np.int64), np.array(goal, np.int64), _cells(), "mountain 30x30")


def poisson_risk(grid: GridMap, key: Any, lam: float = 1.0) -> GridMap:
    """chen2023's "unknown factor" layer: one Poisson(λ) draw per free cell (Eq. 4).

    λ is the mean number of disturbances (manual picking, a stalled stacker, ...)
    per cell; chen2023 tries 0.01, 0.1, 1 and 10 and settles on 1. Blocked cells get 0.

    Args:
      grid: the map.
      key: JAX PRNG key or int seed.
      lam: λ >= 0.

    Returns:
      the map with its ``risk`` layer replaced.
    """
    lam = float(lam)
    if not np.isfinite(lam) or lam < 0:
        raise ValueError(f"Poisson parameter lam must be finite and >= 0, got {lam}")
    k = jax.random.key(key) if isinstance(key, (int, np.integer)) else key
    draws = np.asarray(jax.random.poisson(k, lam, shape=grid.shape), dtype=np.float32)
    return grid.replace(risk=np.where(np.asarray(grid.free), draws, 0.0))
