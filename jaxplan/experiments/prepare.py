"""The work plan of an experiment: maps loaded, scenarios chosen, trials cut into chunks — before any planning.

Maps are loaded (or generated) and their scenarios chosen first; then the trials are cut into
*chunks*: one chunk is one map × one planner × up to ``chunk`` consecutive scenarios × every
seed, and runs as ONE compiled call (`jaxplan.experiments.execute`). A TSP instance
(``[[instances]]``) is one scenario: its chunk is the instance × one ``kind = "tsp"`` planner ×
every seed. Planners run only where they apply (`jaxplan.experiments.config.applies`): grid
planners on maps, tsp planners on instances. Chunks run in a fixed order (map, planner,
scenarios), so the trials file has rows ordered by (map, planner, scenario, seed).

`fingerprint` hashes everything that shapes the trials (seeds, chunk size, maps and their files'
SHA-256, scenarios, planners, metrics): the run folder (`jaxplan.experiments.store`)
refuses a run folder written by a different experiment.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from jaxplan.core.run_folder import sha256
from jaxplan.experiments.config import METRICS, ConfigError, ExperimentConfig, MapSpec, applies
from jaxplan.scale import check_memory, table_memory

__all__ = ["ID_COLUMNS", "MapWork", "Unit", "Prepared", "sha256", "load_map_spec", "random_pairs", "spec_scenarios",
           "prepare", "trial_columns", "fingerprint"]

ID_COLUMNS = ("map", "planner", "kind", "scenario", "scen_row", "start_x", "start_y", "goal_x", "goal_y", "optimal",
              "seed")
"""The identifying columns of trials.csv, before the metric columns (``optimal``: exact octile optimum, m — for
a TSP instance the optimal tour's length, nan if unknown; ``scenario``: index among the map's chosen scenarios;
``scen_row``: row in the .scen file, −1 if generated; a TSP row leaves the start and goal cells empty)."""


@dataclass(frozen=True)
class MapWork:
    """A loaded map and its chosen scenarios.

    Attributes:
      spec: the config entry.
      grid: the `GridMap`.
      starts, goals: ``int64[S, 2]`` cells.
      optimal: ``f64[S]`` exact 8-connected octile optimum (m).
      rows: ``int64[S]`` row of each scenario in the .scen file (−1 when generated).
      digest: SHA-256 of the map (and scenario) file bytes, or of the generated grid.
      problem: a TSP instance's `TSPProblem` (then ``grid`` is None, S = 1, starts/goals are −1 and
        ``optimal`` is the optimal tour length); None for a map.
      draws: the moving discs drawn so far for this map's trials (`jaxplan.experiments.execute.obstacle_fn`),
        by (obstacle spec, team, scenario, seed): every planner of a config that shares those meets the same
        discs, so each set is drawn once per process (a draw plans routes over the map: 0.1-0.4 s on the
        MovingAI maps). Not part of equality.
    """

    spec: MapSpec
    grid: Any
    starts: np.ndarray
    goals: np.ndarray
    optimal: np.ndarray
    rows: np.ndarray
    digest: str
    problem: Any = None
    draws: dict[Any, Any] = dataclasses.field(default_factory=dict, compare=False, repr=False)


@dataclass(frozen=True)
class Unit:
    """One chunk: map ``m`` × planner ``p`` × scenarios ``lo:hi`` × every seed (``uid`` sorts in run order)."""

    index: int
    uid: str
    m: int
    p: int
    lo: int
    hi: int


@dataclass(frozen=True)
class Prepared:
    """The resolved config, its loaded maps and the chunks in run order."""

    config: ExperimentConfig
    maps: tuple[MapWork, ...]
    units: tuple[Unit, ...]

    @property
    def trials(self) -> int:
        return sum((u.hi - u.lo) * len(self.config.seeds) for u in self.units)


def load_map_spec(spec: MapSpec):
    """(grid, default start, default goal, digest) of a map entry."""
    from jaxplan.experiments.config import _generators
    from jaxplan.grid import load_map

    if spec.path is not None:
        grid = load_map(spec.path, resolution=spec.resolution, **spec.ros)
        extra = spec.scen.read_bytes() if (spec.scen is not None and spec.scenarios.source == "scen") else b""
        return grid, None, None, sha256(*_map_file_bytes(spec), extra)
    factory, is_dc = _generators()[spec.generator]
    params = {k: tuple(v) if isinstance(v, (list, tuple)) else v for k, v in spec.params.items()}
    if is_dc:
        gen = factory(**params, resolution=spec.resolution)
        _check_map_size(spec, getattr(gen, "width", None), getattr(gen, "height", None))
        scene = gen(spec.seed)
    elif spec.generator == "demo_warehouse":
        scene = factory()
    else:
        scene = factory(spec.seed, **params)
    grid = scene.grid if scene.grid.resolution == spec.resolution else scene.grid._replace(resolution=spec.resolution)
    arrays = [np.ascontiguousarray(a).tobytes() for a in (grid.free, grid.height, grid.clearance_height, grid.risk,
                                                            grid.turn_rule)]
    return grid, np.asarray(scene.start), np.asarray(scene.goal), sha256(*arrays, repr(grid.resolution).encode())


def _map_file_bytes(spec: MapSpec) -> list[bytes]:
    """The bytes a file map's grid is read from: a MovingAI file; a ROS map's YAML and image, each mask's too,
    and the mask options (so that a changed image or mask is a changed map, not a silent resume)."""
    from jaxplan.grid import is_ros_map, read_ros_yaml

    if not is_ros_map(spec.path):
        return [spec.path.read_bytes()]
    out = []
    for f in (spec.path, spec.ros.get("keepout"), spec.ros.get("speed")):
        if f is not None:
            out += [Path(f).read_bytes(), Path(read_ros_yaml(f)["image"]).read_bytes()]
    opts = {k: v for k, v in spec.ros.items() if k not in ("keepout", "speed")}
    return out + [repr(sorted(opts.items())).encode()]


_CELL_BYTES = 64
"""Bytes per cell of a generated map while it is made: the map's layers (14 bytes) and the generator's and
the exact distances' temporaries."""
_PAIR_BYTES = 1024
"""Bytes per random start-goal pair while they are drawn: four candidate pairs of cells, their distances and the
exact lengths, and the kept Python lists."""


def _check_map_size(spec: MapSpec, width, height) -> None:
    """The memory guard of a generated map's claimed size, before the generator allocates it."""
    if isinstance(width, int) and isinstance(height, int) and width > 0 and height > 0:
        check_memory(table_memory(width * height, {"map layers": _CELL_BYTES}),
                     f"map {spec.name!r}: a generated {width}x{height} map", unit="cells",
                     advice="Use a smaller map")


def load_instance(spec: MapSpec) -> MapWork:
    """A TSP instance as one scenario: the problem, its optimum (from the optimal tour, the configured length, or
    nan) and a digest of the files."""
    from jaxplan.aco import load_tour, load_tsplib, tour_length

    problem = load_tsplib(spec.tsplib)
    if spec.tour is not None:
        optimum = float(tour_length(problem, load_tour(spec.tour)))
        extra = spec.tour.read_bytes()
    else:
        optimum = math.nan if spec.optimum is None else float(spec.optimum)
        extra = repr(spec.optimum).encode()
    none = np.full((1, 2), -1, np.int64)
    return MapWork(spec, None, none, none, np.asarray([optimum], np.float64), np.full(1, -1, np.int64),
                   sha256(spec.tsplib.read_bytes(), extra), problem=problem)


def _choose(n: int, count: int | None, spread: str, seed: int) -> np.ndarray:
    """Indices of ``count`` of ``n`` filtered rows, in file order."""
    if count is None or count >= n:
        return np.arange(n)
    if spread == "first":
        return np.arange(count)
    if spread == "even":
        return np.unique(np.round(np.linspace(0, n - 1, count)).astype(np.int64))
    return np.sort(np.random.default_rng(seed).choice(n, size=count, replace=False))


def random_pairs(grid, count: int, seed: int, min_distance: float,
                  min_clearance: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``count`` connected (start, goal) pairs of free cells at least ``min_distance`` m apart (straight line),
    each cell at least ``min_clearance`` m from the nearest blocked square."""
    from jaxplan.search import shortest_lengths

    check_memory(table_memory(count, {"start-goal pairs": _PAIR_BYTES}), f"{count} random scenarios",
                 unit="scenarios", advice="Ask for fewer scenarios")
    ok_cells = np.asarray(grid.free)
    if min_clearance > 0:
        from jaxplan.grid import clearance_field

        ok_cells = ok_cells & (np.asarray(clearance_field(grid)) >= min_clearance)
    free = np.argwhere(ok_cells)[:, ::-1]  # (x, y)
    if len(free) < 2:
        raise ValueError("the map has fewer than two free cells" + (
            f" at least {min_clearance} m from obstacles" if min_clearance > 0 else ""))
    rng = np.random.default_rng(seed)
    S, G, L = [], [], []
    for _ in range(50):
        k = 4 * count
        a, b = free[rng.integers(len(free), size=k)], free[rng.integers(len(free), size=k)]
        d = np.hypot(*(a - b).T) * grid.resolution
        keep = (d >= max(min_distance, 1e-9))
        a, b = a[keep], b[keep]
        if len(a):
            lens = shortest_lengths(grid, a, b)
            ok = np.isfinite(lens)
            S += list(a[ok])
            G += list(b[ok])
            L += list(lens[ok])
        if len(S) >= count:
            break
    if len(S) < count:
        raise ValueError(f"found only {len(S)} of {count} connected start-goal pairs at least {min_distance} m apart")
    return np.asarray(S[:count], np.int64), np.asarray(G[:count], np.int64), np.asarray(L[:count], np.float64)


def spec_scenarios(spec: MapSpec, grid, start0, goal0) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(starts, goals, optimal m, scen rows) of a map, as its `ScenarioSpec` asks."""
    from jaxplan.grid import load_scenarios
    from jaxplan.search import shortest_lengths

    sc = spec.scenarios
    if sc.source == "scene":
        s, g = start0[None].astype(np.int64), goal0[None].astype(np.int64)
        opt = shortest_lengths(grid, s, g)
        if not np.isfinite(opt[0]):
            raise ValueError("the generator's start and goal are not connected")
        return s, g, opt, np.full(1, -1, np.int64)
    if sc.source == "random":
        s, g, opt = random_pairs(grid, sc.count or 10, sc.seed, sc.min_distance, sc.min_clearance)
        return s, g, opt, np.full(len(s), -1, np.int64)
    scen = load_scenarios(spec.scen, grid=grid)
    keep = np.ones(len(scen.starts), bool)
    opt_file = np.asarray(scen.optimal, np.float64) * float(grid.resolution)
    if sc.min_bucket is not None:
        keep &= scen.buckets >= sc.min_bucket
    if sc.max_bucket is not None:
        keep &= scen.buckets <= sc.max_bucket
    if sc.min_optimal is not None:
        keep &= opt_file >= sc.min_optimal
    if sc.max_optimal is not None:
        keep &= opt_file <= sc.max_optimal
    keep &= np.any(scen.starts != scen.goals, axis=1)
    rows = np.flatnonzero(keep)
    if rows.size == 0:
        raise ValueError(f"no scenario row of {spec.scen.name} passes the bucket/optimal filters")
    rows = rows[_choose(rows.size, sc.count, sc.spread, sc.seed)]
    s, g = scen.starts[rows].astype(np.int64), scen.goals[rows].astype(np.int64)
    return s, g, shortest_lengths(grid, s, g), rows.astype(np.int64)


def prepare(cfg: ExperimentConfig) -> Prepared:
    """Loads every map, chooses every scenario and cuts the chunks — before any planning.

    Raises:
      ConfigError: problems only visible with the data (an empty scenario filter,
        scenario rows that do not fit the map, too few connected random pairs), all at once.
      MemoryLimitError: a generated map or a random scenario count that would not fit in memory.
    """
    problems, maps = [], []
    for i, spec in enumerate(cfg.maps):
        try:
            if spec.is_tsp:
                maps.append(load_instance(spec))
                continue
            grid, s0, g0, digest = load_map_spec(spec)
            s, g, opt, rows = spec_scenarios(spec, grid, s0, g0)
        except (ValueError, FileNotFoundError) as e:
            problems.append(f"{spec.key or f'maps[{i}]'} ({spec.name}): {e}")
            continue
        maps.append(MapWork(spec, grid, s, g, np.asarray(opt, np.float64), rows, digest))
    if problems:
        raise ConfigError(problems, str(cfg.path or cfg.name))
    units, k = [], 0
    for mi, mw in enumerate(maps):
        for pi, pc in enumerate(cfg.planners):
            if not applies(pc, mw.spec):
                continue
            for ci, lo in enumerate(range(0, len(mw.starts), cfg.chunk)):
                hi = min(lo + cfg.chunk, len(mw.starts))
                units.append(Unit(k, f"{k:05d}-m{mi}-p{pi}-c{ci}", mi, pi, lo, hi))
                k += 1
    return Prepared(cfg, tuple(maps), tuple(units))


def trial_columns(cfg: ExperimentConfig) -> tuple[str, ...]:
    """The header of trials.csv: `ID_COLUMNS`, ``success`` (always), the configured non-timing metrics, and
    ``reason`` with navigation."""
    metrics = ("success",) + tuple(m for m in cfg.metrics if not METRICS[m].timing and m != "success")
    return ID_COLUMNS + metrics + (("reason",) if "navigate" in cfg.kinds else ())


def _plain(x: Any) -> Any:
    """JSON-able form of config values (for the fingerprint)."""
    if dataclasses.is_dataclass(x):
        return {f.name: _plain(getattr(x, f.name)) for f in dataclasses.fields(x)}
    if isinstance(x, Mapping):
        return {str(k): _plain(v) for k, v in sorted(x.items())}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, Path):
        return x.name
    if isinstance(x, float) and not math.isfinite(x):
        return repr(x)
    return x


def _spec_doc(spec: MapSpec) -> dict:
    """A map's part of the fingerprint. The instance fields, ROS mask options and draw fields are left out while
    unset (and ``key`` always: it names the config entry, it does not shape trials), so a map's fingerprint is the
    one written before instances, masks and draws."""
    doc = _plain(spec)
    doc.pop("key", None)
    for k in ("tsplib", "tour", "optimum"):
        if doc.get(k) is None:
            doc.pop(k, None)
    if not doc.get("ros"):
        doc.pop("ros", None)
    # A map's draw is in its name and key; paper_map decides only how the report compares numbers.
    for k, default in (("family", ""), ("draw", 0), ("paper_map", False)):
        if doc.get(k) == default:
            doc.pop(k, None)
    return doc


def _planner_doc(pc) -> dict:
    """A planner's part of the fingerprint; ``team`` is left out while unset, so a planner's fingerprint is the one
    written before teams (a run folder of then still resumes)."""
    doc = _plain(pc)
    if doc.get("team") is None:
        doc.pop("team", None)
    return doc


def fingerprint(prep: Prepared) -> str:
    """SHA-256 of everything that shapes trials.csv (not stats, figures or paper numbers)."""
    cfg = prep.config
    doc = {
        "seeds": list(cfg.seeds), "chunk": cfg.chunk, "columns": list(trial_columns(cfg)),
        "maps": [{"spec": _spec_doc(m.spec), "digest": m.digest} for m in prep.maps],
        "planners": [_planner_doc(pc) for pc in cfg.planners], "quick": cfg.is_quick,
    }
    return sha256(json.dumps(doc, sort_keys=True).encode())
