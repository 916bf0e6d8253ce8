"""Experiment configs: TOML files read with `tomllib` into frozen dataclasses, checked in full before any work.

A config names maps, scenarios, planners, seeds, metrics, statistics, figures and the
paper's reported numbers. `load_config` reads and validates it; every problem is
collected with its key path and one `ConfigError` lists them all, so a typo found at
the 20th planner does not cost an overnight run a restart per mistake.

Schema (every key shown; ``#`` marks defaults and alternatives)::

    metrics = ["success", "length", "optimality_gap", "smoothness", "plan_time_s"]
    # Top-level keys come before the first table in TOML. Default: every metric that
    # applies to the configured planner kinds, except the opt-in ones (accuracy, los_*).
    # Names: see `METRICS`.

    [experiment]
    name = "aco_warehouse"      # the run folder runs/NAME ([A-Za-z0-9][A-Za-z0-9_.-]*), required
    description = "ACO variants on the MovingAI warehouse"
    seeds = 30                  # a count (seeds 0..n-1, >= 1) or a list of distinct ints in [0, 2**32)
    chunk = 16                  # scenarios per compiled call (>= 1); `jaxplan run --chunk` overrides

    [experiment.quick]          # what `--quick` changes (a smoke run for CI); every key optional
    seeds = 2                   # count or list
    count = 3                   # at most this many scenarios per map
    chunk = 3
    overrides = { ants = 8, iterations = 5 }   # given to every planner that accepts the key
    nav = { max_time = 40.0 }   # NavConfig fields for every navigate planner
    planners = ["IACO"]         # only these planner labels run (default all; each pipeline compiles once)
    maps = ["wh20"]             # only these maps run (default all)

    [[maps]]                    # a MovingAI map, by path relative to the data dir (or absolute)
    name = "warehouse"          # label in tables (default: the file's stem or the generator's name)
    path = "movingai/warehouse-10-20-10-2-1.map"
    scen = "movingai/warehouse-10-20-10-2-1-random-1.scen"   # default: MAP.scen, else STEM-random-1.scen
    resolution = 1.0            # metres per cell (> 0)

    [[maps]]                    # or a generator of jaxplan.grid._generators (see `GENERATORS`)
    name = "wh20"
    generator = "warehouse"     # warehouse | random | urban | mountain | warehouse_chen2023 | warehouse_yu2020 | demo_warehouse
                                # | warehouse_chen2023_risk (params = { lam = 1.0 }: chen2023's Poisson risk layer)
    seed = 0                    # the generator's key (>= 0)
    params = { width = 20, height = 20, missing_prob = 0.1 }   # the generator's own settings
    resolution = 1.0
    scenarios = { source = "random", count = 4, seed = 1 }   # per-map keys replace [scenarios] keys

    [[instances]]               # a TSPLIB instance, for kind = "tsp" planners (no [[maps]] needed then)
    name = "eil51"              # label in tables (default: the file's stem); unique among maps and instances
    path = "tsplib/eil51.tsp"   # relative to the data dir (or absolute)
    tour = "tsplib/eil51.opt.tour"   # the optimal tour, for optimality_gap (default: STEM.opt.tour if present)
    optimum = 426.0             # or the optimal length itself (not both; neither: optimality_gap is nan)

    [scenarios]                 # default for every map
    source = "scen"             # "scen": rows of the map's .scen file (MovingAI maps only)
                                # "random": start-goal pairs drawn on the free cells (connected)
                                # "scene": the generator's own start and goal (one scenario)
    count = 20                  # scenarios per map (>= 1; default: every selected scen row, 10 random pairs)
    spread = "even"             # which filtered scen rows: "first", "even" (evenly spaced in file order), "random"
    seed = 0                    # for spread = "random" and source = "random"
    min_bucket = 0              # scen filters (inclusive)
    max_bucket = 100
    min_optimal = 0.0           # metres (the exact octile optimum on the map)
    max_optimal = 1e9
    min_distance = 5.0          # source = "random": straight-line start-goal distance in metres
    min_clearance = 0.6         # source = "random": start and goal cells this far (m) from any obstacle

    [[planners]]                # a registered global planner, `jaxplan.planners()`
    label = "IACO"              # column label (default: name); unique
    kind = "plan"
    name = "iaco"
    overrides = { ants = 20, iterations = 30 }   # checked against the planner's defaults

    [[planners]]                # a two-level navigation pipeline, `jaxplan.nav.pipelines()`
    label = "IACO-DWA"
    kind = "navigate"
    name = "iaco_dwa"
    overrides = { iterations = 20 }             # the pipeline's global planner
    nav = { max_time = 60.0, goal_tolerance = 0.5 }   # NavConfig fields (scalars)
    dwa = { n_v = 10, n_omega = 20 }            # DWAConfig fields (scalars)
    robot = { v_max = 1.2, radius = 0.25 }      # Unicycle limits; radius: its Disc footprint
    params = { heading = 0.4 }                  # DWAParams critic weights
    obstacles = { n = 3, speed = 1.0, radius = 0.25, waypoints = 4, loop = false, seed = 0, avoid_radius = 1.0 }

    [[planners]]                # a TSP ant colony (`jaxplan.solve_tsp`), run on every [[instances]] entry
    label = "P-RACO"
    kind = "tsp"
    name = "praco"              # "praco" | "aco"
    overrides = { iterations = 200, colonies = 5, ants = 35 }   # checked against `jaxplan.aco._tsp.tsp_defaults`

    [stats]
    anova = true                # one-way ANOVA across planners, per map and metric
    pairwise = true             # Welch t-tests between every pair of planners
    metrics = ["length"]        # default: every configured metric except wall-clock times
    alpha = 0.05                # marks p < alpha in the report
    correction = "holm"         # pairwise p-values adjusted by Holm's method ("holm" | "none")
    extremes = false            # also show the smallest and largest single-trial value (yu2020's Max/Min)

    [[figures]]                 # stored for `jaxplan figures`; not drawn here
    kind = "convergence"        # see `FIGURE_KINDS`
    name = "convergence_wh"     # file stem (default: kind, then kind_2, ...)
    maps = ["wh20"]             # default: all
    planners = ["IACO"]         # default: all
    band = "iqr"
    # Other kinds: box/bar (metric = ...; default the first stats metric), paths and pheromone
    # (scenario, seed; plan planners; paths also takes smoothing = "los" to draw each path after that
    # smoother beside it, yu2020 Fig. 11), trajectories and controls (scenario, seed; navigate planners:
    # executed paths among the moving discs, v and omega over time), fan (the DWA rollouts at the
    # given control steps = [..]), diversity (yu2020: sd of the ants' costs per iteration),
    # sweep (metric against x: a generator parameter name, e.g. "obstacle_ratio", or one number per map), and
    # tours (seed; tsp planners: the best tour over the instance's cities, the optimal one dashed).

    [paper]                     # the paper's numbers, shown beside ours, labelled "paper"
    source = "Cui & Liu (2025), Table 2"
    [[paper.values]]
    planner = "IACO"            # a planner label
    map = "wh20"                # optional: default every map
    length = 28.6               # metric = mean, or [mean, sd], or { mean = , sd = , min = , max = } (sd, min,
    success = [1.0, 0.0]        # max optional: a paper's Max/Min columns)

Planner kinds run where they apply: ``plan`` and ``navigate`` planners on every ``[[maps]]``
entry, ``tsp`` planners on every ``[[instances]]`` entry (`applies`); a map or instance that no
configured planner applies to is an error.

Resolved objects: `ExperimentConfig` and its parts (`MapSpec`, `ScenarioSpec`,
`PlannerConfig`, `ObstacleSpec`, `StatsSpec`, `FigureSpec`, `PaperValue`, `QuickSpec`).
Paths are absolute after loading; `ExperimentConfig.text` keeps the file's bytes for the
run folder's copy. TSP instances are `MapSpec` entries too (``tsplib`` set), after the maps in
``ExperimentConfig.maps``: tables, figures and quick filters name them like maps.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import os
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any, Callable, Mapping, Sequence

__all__ = [
    "ConfigError", "ExperimentConfig", "MapSpec", "ScenarioSpec", "PlannerConfig", "ObstacleSpec", "StatsSpec",
    "FigureSpec", "PaperValue", "QuickSpec", "Metric", "METRICS", "GENERATORS", "FIGURE_KINDS", "KINDS",
    "ACCURACY_GAP", "load_config", "parse_config", "default_data_dir", "nav_config", "apply_quick", "applies",
]


class ConfigError(ValueError):
    """A config with problems; ``problems`` lists each as ``"key.path: message"``."""

    def __init__(self, problems: list[str] | tuple[str, ...], source: str = "config"):
        self.problems = tuple(dict.fromkeys(problems))  # a shared [scenarios] problem is met once per map
        n = len(self.problems)
        head = f"{source}: {n} problem{'s' if n != 1 else ''}"
        super().__init__(head + "\n" + "\n".join(f"  - {p}" for p in self.problems))


# ---------------------------------------------------------------------------------------------
# Fixed vocabularies


@dataclass(frozen=True)
class Metric:
    """A metric a config may name.

    Attributes:
      name: column name in trials.csv / summary.csv.
      kinds: planner kinds it applies to (``"plan"``, ``"navigate"``).
      unit: for tables ("" for counts and ratios).
      description: one line (DESIGN §6).
      timing: a wall-clock time: written to timings.csv per chunk, not to trials.csv
        (it differs from run to run; trials.csv must not).
      given_success: averaged over successful trials only (e.g. the arrival time).
      rate: a 0/1 outcome whose per-seed mean is a rate.
      default: in the default metric set of a config that lists none (the opt-in metrics cost
        extra work per chunk: exact reference paths, smoothing).
    """

    name: str
    kinds: frozenset
    unit: str
    description: str
    timing: bool = False
    given_success: bool = False
    rate: bool = False
    default: bool = True


KINDS = ("plan", "navigate", "tsp")
"""Planner kinds: a grid planner (`jaxplan.plan_batch`), a navigation pipeline (`jaxplan.navigate_batch`),
a TSP ant colony on a TSPLIB instance (`jaxplan.solve_tsp`'s program, batched over seeds)."""

ACCURACY_GAP = 0.10
"""cui2025's "accuracy" (DESIGN §6): the share of trials that succeed with an optimality gap <= this."""

_P, _N, _B = frozenset({"plan"}), frozenset({"navigate"}), frozenset({"plan", "navigate"})
_T, _PT = frozenset({"tsp"}), frozenset({"plan", "tsp"})
METRICS: Mapping[str, Metric] = MappingProxyType({m.name: m for m in (
    Metric("success", _B | _T, "", "plan: goal reached; navigate: goal reached without collision in time; "
                                   "tsp: 1 (every run returns a tour)", rate=True),
    Metric("accuracy", _B, "", "cui2025: success with optimality gap <= 10 % (plan: the raw grid path against the "
                               "octile optimum; navigate: the executed path against the line-of-sight smoothed "
                               "exact path on the planning map)", rate=True, default=False),
    Metric("length", _P, "m", "path length"),
    Metric("tour_length", _T, "", "closed-tour length in the instance's metric (TSPLIB rounding)"),
    Metric("optimality_gap", _PT, "", "plan: length / exact 8-connected octile optimum - 1; tsp: tour length / "
                                      "optimal tour length - 1"),
    Metric("turns", _P, "", "path vertices with a heading change"),
    Metric("sharp_turns", _P, "", "heading changes >= 45 deg"),
    Metric("los_length", _P, "m", "path length after line-of-sight smoothing (yu2020 sec. 3.3, smoother 'los')",
           default=False),
    Metric("los_turns", _P, "", "turns after line-of-sight smoothing", default=False),
    Metric("los_length_reduction", _P, "", "1 - los_length / length (yu2020 Table 4)", default=False),
    Metric("los_turns_reduction", _P, "", "1 - los_turns / turns (nan for a straight path)", default=False),
    Metric("smoothness", _P, "", "1 - mean |heading change| / pi"),
    Metric("min_clearance", _P, "m", "smallest vertex clearance"),
    Metric("mean_clearance", _P, "m", "mean vertex clearance"),
    Metric("max_curvature", _B, "1/m", "plan: Menger curvature at path vertices; navigate: executed |omega|/v"),
    Metric("hausdorff", _B, "m", "Hausdorff distance of the global path to the exact A* path (cui2025 Fig. 9)"),
    Metric("cost", _P, "", "the planner's own objective"),
    Metric("converged_iteration", _PT, "", "plan: first iteration within 0.1 % of the final best cost; tsp: first "
                                           "iteration whose best tour is the final best (0-based)"),
    Metric("collisions", _N, "", "contacts with the map or moving discs"),
    Metric("time_s", _N, "s", "simulated time to the goal", given_success=True),
    Metric("rmse", _N, "m", "RMS distance of executed positions to the tracked path"),
    Metric("energy", _N, "J", "energy proxy (DESIGN §6)"),
    Metric("path_length", _N, "m", "executed path length"),
    Metric("recoveries", _N, "", "control steps with no feasible DWA sample"),
    Metric("replans", _N, "", "in-episode re-plans"),
    Metric("plan_time_s", _B | _T, "s", "global planning (tsp: solving) wall time per trial (chunk time / trials)",
           timing=True),
    Metric("step_time_s", _N, "s", "wall time per control step of one robot", timing=True),
)})
"""Every metric a config may name, in the column order of the outputs."""

FIGURE_KINDS: Mapping[str, frozenset] = MappingProxyType({
    "convergence": frozenset({"band", "log", "scenario"}),
    "box": frozenset({"metric"}),
    "bar": frozenset({"metric"}),
    "paths": frozenset({"scenario", "seed", "smoothing"}),
    "trajectories": frozenset({"scenario", "seed"}),
    "pheromone": frozenset({"scenario", "seed", "log"}),
    "diversity": frozenset({"band", "log", "scenario"}),
    "fan": frozenset({"scenario", "seed", "steps"}),
    "controls": frozenset({"scenario", "seed"}),
    "sweep": frozenset({"metric", "x", "xlabel"}),
    "tours": frozenset({"seed"}),
})
"""Figure kinds and the keys each accepts besides ``kind name title maps planners format``."""
_FIGURE_COMMON = frozenset({"kind", "name", "title", "maps", "planners", "format"})
_SCENARIO_FIGURE_PLANNERS: Mapping[str, tuple[str, ...]] = MappingProxyType({
    "convergence": ("plan", "tsp"), "diversity": ("plan", "tsp"), "paths": ("plan", "navigate"),
    "pheromone": ("plan",), "trajectories": ("navigate",), "controls": ("navigate",), "fan": ("navigate",),
})
"""Figure kinds with a ``scenario`` key -> the planner kinds they draw (as `figures` selects them)."""


def _generators() -> dict[str, tuple[Callable[..., Any], bool]]:
    """name -> (factory, is_dataclass). Dataclass generators take their fields as params."""
    from jaxplan.grid import _generators as G

    return {
        "warehouse": (G.WarehouseGenerator, True),
        "random": (G.RandomMapGenerator, True),
        "urban": (G.UrbanGenerator, True),
        "mountain": (G.MountainGenerator, True),
        "warehouse_chen2023": (G.warehouse_chen2023, False),
        "warehouse_yu2020": (G.warehouse_yu2020, False),
        "demo_warehouse": (G.demo_warehouse, False),
        "warehouse_chen2023_risk": (_chen2023_risk, False),
    }


def _chen2023_risk(key: int = 0, lam: float = 1.0):
    """chen2023's Case 1 map with its unknown-factor layer: Poisson(λ = ``lam``) risk per free cell (§II, Fig. 8).

    The layer's key is the map key + 1, so the shelves stay those of `warehouse_chen2023(key)` for every λ."""
    from jaxplan.grid import _generators as G

    scene = G.warehouse_chen2023(key)
    return scene._replace(grid=G.poisson_risk(scene.grid, int(key) + 1, lam=float(lam)))


GENERATORS = ("warehouse", "random", "urban", "mountain", "warehouse_chen2023", "warehouse_yu2020", "demo_warehouse",
              "warehouse_chen2023_risk")
"""Generator names a map may use (`jaxplan.grid._generators`)."""
_FUNCTION_PARAMS = {"warehouse_chen2023": (), "warehouse_yu2020": ("size",), "demo_warehouse": (),
                    "warehouse_chen2023_risk": ("lam",)}

SCENARIO_SOURCES = ("scen", "random", "scene")
SPREADS = ("first", "even", "random")
_OBSTACLE_KEYS = ("n", "speed", "radius", "waypoints", "loop", "seed", "avoid_radius")
_ROBOT_KEYS = ("v_min", "v_max", "omega_max", "accel", "decel", "alpha", "radius")
_NAME_RE = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]*\Z")


# ---------------------------------------------------------------------------------------------
# The resolved config


def _frozen(d: Mapping[str, Any] | None) -> Mapping[str, Any]:
    """A read-only mapping whose lists became tuples (TOML arrays as hashable parameter values)."""
    def fix(v):
        if isinstance(v, list):
            return tuple(fix(x) for x in v)
        if isinstance(v, dict):
            return MappingProxyType({k: fix(x) for k, x in v.items()})
        return v

    return MappingProxyType({k: fix(v) for k, v in (d or {}).items()})


@dataclass(frozen=True)
class ScenarioSpec:
    """How a map's start-goal pairs are chosen.

    Attributes:
      source: ``"scen"`` (rows of the map's scenario file), ``"random"`` (pairs of connected
        free cells) or ``"scene"`` (a generator's default start and goal).
      count: scenarios wanted (None: every selected scen row; 10 random pairs).
      spread: ``"first"``, ``"even"`` or ``"random"`` choice among the filtered scen rows.
      seed: numpy seed for ``spread="random"`` and ``source="random"``.
      min_bucket, max_bucket: inclusive scen bucket filter (None: open).
      min_optimal, max_optimal: inclusive filter on the exact optimum (m; None: open).
      min_distance: straight-line start-goal distance (m) of random pairs.
      min_clearance: random pairs only: start and goal cells at least this far (m, cell centre to the
        nearest blocked square) from obstacles, so a robot with a footprint and safety distance fits there.
    """

    source: str = "scen"
    count: int | None = None
    spread: str = "even"
    seed: int = 0
    min_bucket: int | None = None
    max_bucket: int | None = None
    min_optimal: float | None = None
    max_optimal: float | None = None
    min_distance: float = 0.0
    min_clearance: float = 0.0


@dataclass(frozen=True)
class MapSpec:
    """A map: a MovingAI file or a generator; or a TSPLIB instance (``tsplib`` set, from ``[[instances]]``).

    Attributes:
      name: label in tables.
      path: absolute ``.map`` path (None for a generator or an instance).
      scen: absolute ``.scen`` path (None if none was found or needed).
      generator: a `GENERATORS` name (None for a file).
      params: the generator's settings.
      seed: the generator's key.
      resolution: metres per cell.
      scenarios: how this map's scenarios are chosen.
      tsplib: absolute ``.tsp`` path of a TSP instance (None for a map).
      tour: absolute ``.opt.tour`` path of the instance's optimal tour, or None.
      optimum: the instance's optimal tour length as configured, or None.
      key: where it was configured (``maps[i]`` or ``instances[j]``), for error messages.
    """

    name: str
    path: Path | None
    scen: Path | None
    generator: str | None
    params: Mapping[str, Any]
    seed: int
    resolution: float
    scenarios: ScenarioSpec
    tsplib: Path | None = None
    tour: Path | None = None
    optimum: float | None = None
    key: str = ""

    @property
    def is_tsp(self) -> bool:
        return self.tsplib is not None


@dataclass(frozen=True)
class ObstacleSpec:
    """Random moving discs per episode (`jaxplan.random_obstacles`): ``n`` discs at ``speed`` m/s, ``radius`` m.

    Each (scenario, seed) trial draws its own set from ``(seed, scenario, trial seed)``;
    starts keep ``avoid_radius`` m from the robot's start and goal.
    """

    n: int = 0
    speed: float = 1.0
    radius: float = 0.25
    waypoints: int = 4
    loop: bool = False
    seed: int = 0
    avoid_radius: float = 1.0


@dataclass(frozen=True)
class PlannerConfig:
    """One configured planner (a column of the result tables).

    Attributes:
      label: unique display name.
      kind: ``"plan"`` (`jaxplan.plan_batch`), ``"navigate"`` (`jaxplan.navigate_batch`) or ``"tsp"``
        (`jaxplan.solve_tsp`'s program, all seeds in one call; runs on the ``[[instances]]``).
      name: planner name (plan), pipeline name (navigate) or TSP planner (tsp: ``"aco"``, ``"praco"``).
      overrides: planner parameters (navigate: of the pipeline's global planner).
      nav, dwa, robot, params: navigate only: NavConfig, DWAConfig and Unicycle fields and
        DWAParams weights.
      obstacles: navigate only: moving discs, or None.
    """

    label: str
    kind: str
    name: str
    overrides: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    nav: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    dwa: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    robot: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    params: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    obstacles: ObstacleSpec | None = None

    @property
    def global_planner(self) -> str:
        """The registry planner that makes the global paths (a tsp planner: its TSP planner name)."""
        if self.kind in ("plan", "tsp"):
            return self.name
        from jaxplan.nav import get_pipeline

        return get_pipeline(self.name).global_planner


@dataclass(frozen=True)
class StatsSpec:
    """Significance tests across planners, per map and metric (on per-seed means); ``extremes``: the tables
    also show the smallest and largest single-trial value (yu2020 reports Max/Min beside Avg/Sd)."""

    anova: bool = True
    pairwise: bool = False
    metrics: tuple[str, ...] = ()
    alpha: float = 0.05
    correction: str = "holm"
    extremes: bool = False


@dataclass(frozen=True)
class FigureSpec:
    """A figure for `jaxplan figures`: kind, file stem, and its parameters (validated, not drawn here)."""

    kind: str
    name: str
    params: Mapping[str, Any]


@dataclass(frozen=True)
class PaperValue:
    """A number the paper reports: ``mean`` (and ``sd``, ``min``, ``max``) of ``metric`` for a planner (on
    ``map``, or every map)."""

    planner: str
    map: str | None
    metric: str
    mean: float
    sd: float | None = None
    min: float | None = None
    max: float | None = None


@dataclass(frozen=True)
class QuickSpec:
    """What ``--quick`` changes: seeds, scenarios per map, chunk, planner overrides and NavConfig fields."""

    seeds: tuple[int, ...] | None = None
    count: int | None = None
    chunk: int | None = None
    overrides: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    nav: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    planners: tuple[str, ...] | None = None  # labels kept by --quick (default all): CI time is compile time
    maps: tuple[str, ...] | None = None  # map names kept by --quick (default all)


@dataclass(frozen=True)
class ExperimentConfig:
    """A validated experiment.

    Attributes:
      name, description: of the run (``runs/NAME``).
      seeds: ``R`` seeds; every (scenario, planner) runs with all of them.
      chunk: scenarios per compiled call.
      metrics: metric names in `METRICS` order.
      maps, planners: in config order (the order of the trials).
      stats, figures, paper_source, paper: as configured.
      quick: the ``--quick`` changes; ``is_quick`` once applied (`apply_quick`).
      text: the config file's text; path: where it was read from; data_dir: the data folder.
    """

    name: str
    description: str
    seeds: tuple[int, ...]
    chunk: int
    metrics: tuple[str, ...]
    maps: tuple[MapSpec, ...]
    planners: tuple[PlannerConfig, ...]
    stats: StatsSpec
    figures: tuple[FigureSpec, ...]
    paper_source: str
    paper: tuple[PaperValue, ...]
    quick: QuickSpec
    text: str
    path: Path | None
    data_dir: Path
    is_quick: bool = False

    def replace(self, **changes) -> "ExperimentConfig":
        return dataclasses.replace(self, **changes)

    @property
    def kinds(self) -> frozenset:
        return frozenset(p.kind for p in self.planners)


def applies(planner: PlannerConfig, site: MapSpec) -> bool:
    """Whether ``planner`` runs on ``site``: tsp planners on TSP instances, plan/navigate planners on maps."""
    return (planner.kind == "tsp") == site.is_tsp


def default_data_dir() -> Path:
    """``$JAXPLAN_DATA``, else ``shared/benchmarks`` beside the checkout (as the tests and benchmarks)."""
    env = os.environ.get("JAXPLAN_DATA")
    return Path(env) if env else Path(__file__).resolve().parents[3] / "shared" / "benchmarks"


# ---------------------------------------------------------------------------------------------
# Reading with error collection


class _Reader:
    """Collects problems while reading nested TOML tables; every check returns a usable fallback."""

    def __init__(self) -> None:
        self.problems: list[str] = []

    def bad(self, path: str, msg: str) -> None:
        self.problems.append(f"{path}: {msg}")

    def table(self, obj: Any, path: str, allowed: tuple[str, ...] | frozenset, required: tuple[str, ...] = ()) -> dict:
        """``obj`` as a dict with only ``allowed`` keys (unknown ones reported, with a close match)."""
        if obj is None:
            obj = {}
        if not isinstance(obj, dict):
            self.bad(path, f"expected a table, got {_describe(obj)}")
            return {}
        for k in obj:
            if k not in allowed:
                near = difflib.get_close_matches(k, list(allowed), n=1)
                hint = f"; did you mean {near[0]!r}?" if near else f" (expected one of: {', '.join(sorted(allowed))})"
                self.bad(_join(path, k), f"unknown key{hint}")
        for k in required:
            if k not in obj:
                self.bad(_join(path, k), "required key is missing")
        return {k: v for k, v in obj.items() if k in allowed}

    def get(self, t: dict, path: str, key: str, kind: str, default: Any = None, *, lo: float | None = None,
            hi: float | None = None, strict_lo: bool = False, choices: tuple | None = None) -> Any:
        """``t[key]`` checked against ``kind`` (``int``, ``float``, ``str``, ``bool``), bounds and choices."""
        if key not in t:
            return default
        v, p = t[key], _join(path, key)
        ok = {
            "int": isinstance(v, int) and not isinstance(v, bool),
            "float": isinstance(v, (int, float)) and not isinstance(v, bool),
            "str": isinstance(v, str),
            "bool": isinstance(v, bool),
        }[kind]
        if not ok:
            self.bad(p, f"expected {_KIND_NAMES[kind]}, got {_describe(v)}")
            return default
        if kind == "float":
            v = float(v)
            if not math.isfinite(v):
                self.bad(p, f"must be a finite number, got {v}")
                return default
        if choices is not None and v not in choices:
            near = difflib.get_close_matches(str(v), [str(c) for c in choices], n=1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            self.bad(p, f"must be one of {', '.join(map(repr, choices))}, got {v!r}{hint}")
            return default
        if lo is not None and (v < lo or (strict_lo and v == lo)):
            self.bad(p, f"must be {'>' if strict_lo else '>='} {lo:g}, got {v!r}")
            return default
        if hi is not None and v > hi:
            self.bad(p, f"must be <= {hi:g}, got {v!r}")
            return default
        return v

    def str_list(self, t: dict, path: str, key: str) -> list[str] | None:
        if key not in t:
            return None
        v = t[key]
        if not isinstance(v, list) or not all(isinstance(x, str) for x in v):
            self.bad(_join(path, key), f"expected a list of strings, got {_describe(v)}")
            return None
        return v

    def seeds(self, t: dict, path: str, key: str, default: Any = None) -> tuple[int, ...] | None:
        """A seed count ``n >= 1`` (seeds 0..n-1) or a list of distinct integers in [0, 2**32)."""
        if key not in t:
            return default
        v, p = t[key], _join(path, key)
        if isinstance(v, int) and not isinstance(v, bool):
            if v < 1:
                self.bad(p, f"must be >= 1, got {v}")
                return default
            return tuple(range(v))
        if isinstance(v, list) and v and all(isinstance(x, int) and not isinstance(x, bool) for x in v):
            bad = [x for x in v if not 0 <= x < 2**32]
            if bad:
                self.bad(p, f"seeds must lie in [0, 2**32), got {bad[0]}")
                return default
            if len(set(v)) != len(v):
                self.bad(p, "seeds must be distinct")
                return default
            return tuple(v)
        self.bad(p, f"expected a seed count (integer >= 1) or a non-empty list of integers, got {_describe(v)}")
        return default


_KIND_NAMES = {"int": "an integer", "float": "a number", "str": "a string", "bool": "true or false"}


def _describe(v: Any) -> str:
    name = {bool: "boolean", int: "integer", float: "number", str: "string", list: "array", dict: "table"}.get(
        type(v), type(v).__name__)
    text = repr(v)
    return f"{name} {text if len(text) <= 40 else text[:37] + '...'}"


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def _close(name: str, known: list[str]) -> str:
    near = difflib.get_close_matches(name, known, n=1)
    return f"; did you mean {near[0]!r}?" if near else ""


# ---------------------------------------------------------------------------------------------
# Sections


def _read_experiment(r: _Reader, raw: dict) -> dict:
    t = r.table(raw.get("experiment"), "experiment", ("name", "description", "seeds", "chunk", "quick"),
                required=("name",))
    name = r.get(t, "experiment", "name", "str", "unnamed")
    if "name" in t and isinstance(t["name"], str) and not _NAME_RE.match(t["name"]):
        r.bad("experiment.name", f"must match [A-Za-z0-9][A-Za-z0-9_.-]* (it names the run folder), got {name!r}")
    out = {
        "name": name,
        "description": r.get(t, "experiment", "description", "str", ""),
        "seeds": r.seeds(t, "experiment", "seeds", tuple(range(30))),
        "chunk": r.get(t, "experiment", "chunk", "int", 16, lo=1),
    }
    q = r.table(t.get("quick"), "experiment.quick", ("seeds", "count", "chunk", "overrides", "nav", "planners", "maps"))
    out["quick_raw"] = {
        "seeds": r.seeds(q, "experiment.quick", "seeds"),
        "count": r.get(q, "experiment.quick", "count", "int", None, lo=1),
        "chunk": r.get(q, "experiment.quick", "chunk", "int", None, lo=1),
        "overrides": r.table(q.get("overrides"), "experiment.quick.overrides", tuple(q.get("overrides") or {})),
        "nav": r.table(q.get("nav"), "experiment.quick.nav", tuple(q.get("nav") or {})),
        "planners": r.str_list(q, "experiment.quick", "planners"),
        "maps": r.str_list(q, "experiment.quick", "maps"),
    }
    return out


_SCEN_KEYS = ("source", "count", "spread", "seed", "min_bucket", "max_bucket", "min_optimal", "max_optimal",
              "min_distance", "min_clearance")


def _read_scenarios(r: _Reader, t: dict, path: str, is_file: bool) -> ScenarioSpec:
    source = r.get(t, path, "source", "str", "scen" if is_file else "random", choices=SCENARIO_SOURCES)
    if source == "scen" and not is_file:
        r.bad(_join(path, "source"), "a generated map has no scenario file; use 'random' or 'scene'")
    if source == "scene" and is_file:
        r.bad(_join(path, "source"), "'scene' is a generator's own start and goal; a MovingAI map uses 'scen' or 'random'")
    spec = ScenarioSpec(
        source=source,
        count=r.get(t, path, "count", "int", None, lo=1),
        spread=r.get(t, path, "spread", "str", "even", choices=SPREADS),
        seed=r.get(t, path, "seed", "int", 0, lo=0),
        min_bucket=r.get(t, path, "min_bucket", "int", None, lo=0),
        max_bucket=r.get(t, path, "max_bucket", "int", None, lo=0),
        min_optimal=r.get(t, path, "min_optimal", "float", None, lo=0),
        max_optimal=r.get(t, path, "max_optimal", "float", None, lo=0),
        min_distance=r.get(t, path, "min_distance", "float", 0.0, lo=0),
        min_clearance=r.get(t, path, "min_clearance", "float", 0.0, lo=0),
    )
    if spec.min_bucket is not None and spec.max_bucket is not None and spec.min_bucket > spec.max_bucket:
        r.bad(path, f"min_bucket {spec.min_bucket} > max_bucket {spec.max_bucket}")
    if spec.min_optimal is not None and spec.max_optimal is not None and spec.min_optimal > spec.max_optimal:
        r.bad(path, f"min_optimal {spec.min_optimal} > max_optimal {spec.max_optimal}")
    if source != "scen":
        for k in ("min_bucket", "max_bucket", "spread"):
            if k in t:
                r.bad(_join(path, k), f"only applies to source = 'scen', not {source!r}")
    if source != "random" and "min_clearance" in t:
        r.bad(_join(path, "min_clearance"), f"only applies to source = 'random', not {source!r}")
    if source == "scene" and spec.count not in (None, 1):
        r.bad(_join(path, "count"), "source = 'scene' gives exactly one scenario")
    return spec


def _read_maps(r: _Reader, raw: dict, data_dir: Path, required: bool = True) -> tuple[MapSpec, ...]:
    maps_raw = raw.get("maps")
    if maps_raw is None:
        if required:
            r.bad("maps", "at least one [[maps]] entry is required")
        return ()
    if not isinstance(maps_raw, list) or not maps_raw:
        r.bad("maps", f"expected one or more [[maps]] tables, got {_describe(maps_raw)}")
        return ()
    default_scen = raw.get("scenarios")
    if default_scen is not None and not isinstance(default_scen, dict):
        r.bad("scenarios", f"expected a table, got {_describe(default_scen)}")
        default_scen = None
    r.table(default_scen, "scenarios", _SCEN_KEYS)
    gens = _generators()
    out, names = [], {}
    for i, m in enumerate(maps_raw):
        p = f"maps[{i}]"
        t = r.table(m, p, ("name", "path", "scen", "generator", "params", "seed", "resolution", "scenarios"))
        if not isinstance(m, dict):
            continue
        has_path, has_gen = "path" in t, "generator" in t
        if has_path == has_gen:
            r.bad(p, "give exactly one of 'path' (a MovingAI .map) or 'generator'")
        resolution = r.get(t, p, "resolution", "float", 1.0, lo=0, strict_lo=True)
        seed = r.get(t, p, "seed", "int", 0, lo=0)
        map_path = scen_path = gen = None
        params: dict = {}
        label = None
        if has_path:
            map_path = _data_file(r, t, p, "path", data_dir, hint=True)
            for k in ("params", "seed"):
                if k in t:
                    r.bad(_join(p, k), "only applies to a generated map")
            if map_path is not None:
                label = map_path.stem
            if "scen" in t:
                scen_path = _data_file(r, t, p, "scen", data_dir)
            elif map_path is not None:
                for cand in (Path(str(map_path) + ".scen"), map_path.with_name(map_path.stem + "-random-1.scen")):
                    if cand.is_file():
                        scen_path = cand
                        break
        elif has_gen:
            if "scen" in t:
                r.bad(_join(p, "scen"), "only applies to a MovingAI map")
            gen = r.get(t, p, "generator", "str", None, choices=GENERATORS)
            params = r.table(t.get("params"), _join(p, "params"), tuple(t.get("params") or {}))
            if gen is not None:
                label = gen
                _check_generator(r, _join(p, "params"), gen, gens[gen], params, resolution)
        name = r.get(t, p, "name", "str", label or f"map{i}")
        if name in names:
            r.bad(_join(p, "name"), f"duplicate map name {name!r} (also maps[{names[name]}]); give each a unique name")
        names.setdefault(name, i)
        merged = {**(default_scen or {}), **(t.get("scenarios") or {} if isinstance(t.get("scenarios"), dict) else {})}
        if "scenarios" in t:
            r.table(t["scenarios"], _join(p, "scenarios"), _SCEN_KEYS)
        scen_p = _join(p, "scenarios") if "scenarios" in t else "scenarios"
        spec = _read_scenarios(r, {k: v for k, v in merged.items() if k in _SCEN_KEYS}, scen_p, has_path)
        if has_path and spec.source == "scen" and scen_path is None and map_path is not None and map_path.is_file():
            r.bad(_join(p, "scen"), f"no scenario file for {map_path.name} (looked for {map_path.name}.scen and "
                                    f"{map_path.stem}-random-1.scen); give 'scen' or use source = 'random'")
        out.append(MapSpec(name, map_path, scen_path, gen, _frozen(params), seed, resolution, spec, key=p))
    return tuple(out)


def _read_instances(r: _Reader, raw: dict, data_dir: Path, taken: set[str]) -> tuple[MapSpec, ...]:
    """``[[instances]]``: TSPLIB files (and their optimal tours) for the tsp planners; names unique with ``taken``."""
    raw_list = raw.get("instances")
    if raw_list is None:
        return ()
    if not isinstance(raw_list, list) or not raw_list:
        r.bad("instances", f"expected one or more [[instances]] tables, got {_describe(raw_list)}")
        return ()
    out, names = [], {}
    for i, e in enumerate(raw_list):
        p = f"instances[{i}]"
        t = r.table(e, p, ("name", "path", "tour", "optimum"), required=("path",) if isinstance(e, dict) else ())
        if not isinstance(e, dict):
            continue
        tsp = _data_file(r, t, p, "path", data_dir, hint=True)
        tour = None
        optimum = r.get(t, p, "optimum", "float", None, lo=0, strict_lo=True)
        if "tour" in t:
            tour = _data_file(r, t, p, "tour", data_dir)
            if "optimum" in t:
                r.bad(p, "give 'tour' (the optimal tour file) or 'optimum' (its length), not both")
        elif tsp is not None and optimum is None:
            cand = tsp.with_name(tsp.stem + ".opt.tour")  # TSPLIB's own naming of the optimal tours
            tour = cand if cand.is_file() else None
        name = r.get(t, p, "name", "str", tsp.stem if tsp is not None else f"instance{i}")
        if name in taken or name in names:
            r.bad(_join(p, "name"), f"duplicate name {name!r}: maps and instances share one namespace (tables, "
                                    "figures); give each a unique name")
        names.setdefault(name, i)
        out.append(MapSpec(name, None, None, None, _frozen({}), 0, 1.0, ScenarioSpec(source="scene"), tsplib=tsp,
                           tour=tour, optimum=optimum, key=p))
    return tuple(out)


def _resolve(data_dir: Path, rel: str) -> Path:
    p = Path(rel).expanduser()
    return p if p.is_absolute() else (data_dir / p)


def _data_file(r: _Reader, t: dict, p: str, key: str, data_dir: Path, hint: bool = False) -> Path | None:
    """``t[key]`` resolved against the data folder (None when absent); a missing file is reported at
    ``p.key``, with the data folder and how to set it when ``hint``."""
    rel = r.get(t, p, key, "str", None)
    if rel is None:
        return None
    f = _resolve(data_dir, rel)
    if not f.is_file():
        more = f" (data dir {data_dir}; set --data-dir or JAXPLAN_DATA)" if hint else ""
        r.bad(_join(p, key), f"file not found: {f}{more}")
    return f


def _check_generator(r: _Reader, path: str, name: str, entry: tuple, params: dict, resolution: float) -> None:
    factory, is_dc = entry
    if is_dc:
        fields = [f.name for f in dataclasses.fields(factory) if f.name != "resolution"]
        known = tuple(fields)
    else:
        known = _FUNCTION_PARAMS[name]
    ok = True
    for k in params:
        if k not in known:
            ok = False
            r.bad(_join(path, k), f"generator {name!r} has no parameter {k!r} (accepts: {', '.join(known) or 'none'})"
                                  + _close(k, list(known)))
    if "resolution" in params:
        r.bad(_join(path, "resolution"), "give the resolution as the map's own 'resolution' key")
    if not ok or not is_dc:
        if name == "warehouse_yu2020" and params.get("size", 30) not in (30, 35):
            r.bad(_join(path, "size"), f"must be 30 or 35, got {params.get('size')!r}")
        return
    try:
        fixed = {k: tuple(v) if isinstance(v, list) else v for k, v in params.items()}
        factory(**fixed, resolution=resolution)
    except (TypeError, ValueError) as e:
        r.bad(path, f"generator {name!r}: {e}")


_PLANNER_KEYS = ("label", "kind", "name", "overrides", "nav", "dwa", "robot", "params", "obstacles")


def _nav_fields() -> tuple[str, ...]:
    from jaxplan.nav import NavConfig

    return tuple(f.name for f in dataclasses.fields(NavConfig) if f.name != "dwa")


def _dwa_fields() -> tuple[str, ...]:
    from jaxplan.dwa import DWAConfig

    return tuple(f.name for f in dataclasses.fields(DWAConfig) if f.name not in ("robot", "keep_rollouts"))


def _read_planners(r: _Reader, raw: dict) -> tuple[PlannerConfig, ...]:
    import jaxplan as jp
    from jaxplan.dwa import DWAParams
    from jaxplan.registry import resolve

    pl_raw = raw.get("planners")
    if pl_raw is None:
        r.bad("planners", "at least one [[planners]] entry is required")
        return ()
    if not isinstance(pl_raw, list) or not pl_raw:
        r.bad("planners", f"expected one or more [[planners]] tables, got {_describe(pl_raw)}")
        return ()
    registry, pipes = jp.planners(), jp.pipelines()
    out, labels = [], {}
    for i, e in enumerate(pl_raw):
        p = f"planners[{i}]"
        t = r.table(e, p, _PLANNER_KEYS, required=("kind", "name") if isinstance(e, dict) else ())
        if not isinstance(e, dict):
            continue
        kind = r.get(t, p, "kind", "str", None, choices=KINDS)
        name = r.get(t, p, "name", "str", None)
        overrides = r.table(t.get("overrides"), _join(p, "overrides"), tuple(t.get("overrides") or {}))
        global_name = None
        if kind in ("plan", "tsp"):
            for k in ("nav", "dwa", "robot", "params", "obstacles"):
                if k in t:
                    r.bad(_join(p, k), "only applies to kind = 'navigate'")
        if kind == "tsp" and name is not None:
            _check_tsp(r, p, name, overrides)
        elif kind == "plan" and name is not None:
            if name not in registry:
                r.bad(_join(p, "name"), f"unknown planner {name!r} (known: {', '.join(sorted(registry))})"
                      + _close(name, list(registry)))
            else:
                global_name = name
        elif kind == "navigate" and name is not None:
            if name not in pipes:
                r.bad(_join(p, "name"), f"unknown pipeline {name!r} (known: {', '.join(sorted(pipes))})"
                      + _close(name, list(pipes)))
            else:
                global_name = pipes[name].global_planner
        if global_name is not None:
            _check_overrides(r, _join(p, "overrides"), global_name, overrides, resolve,
                             dict(pipes[name].planner_overrides) if kind == "navigate" else {})
        label = r.get(t, p, "label", "str", name or f"planner{i}")
        if label in labels:
            r.bad(_join(p, "label"), f"duplicate label {label!r} (also planners[{labels[label]}]); labels name the "
                                     "table columns, give each a unique one")
        labels.setdefault(label, i)
        nav = dwa = robot = params = {}
        obstacles = None
        if kind == "navigate":
            nav = r.table(t.get("nav"), _join(p, "nav"), _nav_fields())
            dwa = r.table(t.get("dwa"), _join(p, "dwa"), _dwa_fields())
            robot = r.table(t.get("robot"), _join(p, "robot"), _ROBOT_KEYS)
            params = r.table(t.get("params"), _join(p, "params"), DWAParams._fields)
            if "obstacles" in t:
                ot = r.table(t["obstacles"], _join(p, "obstacles"), _OBSTACLE_KEYS)
                op = _join(p, "obstacles")
                obstacles = ObstacleSpec(
                    n=r.get(ot, op, "n", "int", 0, lo=0), speed=r.get(ot, op, "speed", "float", 1.0, lo=0),
                    radius=r.get(ot, op, "radius", "float", 0.25, lo=0),
                    waypoints=r.get(ot, op, "waypoints", "int", 4, lo=1), loop=r.get(ot, op, "loop", "bool", False),
                    seed=r.get(ot, op, "seed", "int", 0, lo=0),
                    avoid_radius=r.get(ot, op, "avoid_radius", "float", 1.0, lo=0))
            if name in pipes:
                _check_nav(r, p, name, nav, dwa, robot, params)
        out.append(PlannerConfig(label, kind or "plan", name or "", _frozen(overrides), _frozen(nav), _frozen(dwa),
                                 _frozen(robot), _frozen(params), obstacles))
    return tuple(out)


def _check_tsp(r: _Reader, p: str, name: str, overrides: dict) -> None:
    """A tsp planner: its name, then unknown override names one by one, then `solve_tsp`'s own value checks."""
    from jaxplan.aco._tsp import TSP_PLANNERS, _resolve as tsp_resolve, tsp_defaults

    if name not in TSP_PLANNERS:
        r.bad(_join(p, "name"), f"unknown TSP planner {name!r} (known: {', '.join(TSP_PLANNERS)})"
              + _close(name, list(TSP_PLANNERS)))
        return
    accepted = list(tsp_defaults(name))
    unknown = [k for k in overrides if k not in accepted]
    for k in unknown:
        r.bad(_join(p, f"overrides.{k}"), f"TSP planner {name!r} has no parameter {k!r} (accepts: "
                                         f"{', '.join(sorted(accepted))})" + _close(k, accepted))
    if not unknown:
        try:
            tsp_resolve(name, {k: _tuple(v) for k, v in overrides.items()})
        except (ValueError, TypeError) as e:
            r.bad(_join(p, "overrides"), str(e))


def _check_sites(r: _Reader, maps: tuple[MapSpec, ...], planners: tuple[PlannerConfig, ...]) -> None:
    """Every map and instance has a planner that runs on it, and every planner a map or instance."""
    for m in maps:
        if planners and not any(applies(pc, m) for pc in planners):
            what = "kind = 'tsp' planner" if m.is_tsp else "plan or navigate planner"
            r.bad(m.key, f"no {what} is configured to run on {m.name!r}")
    for i, pc in enumerate(planners):
        if maps and not any(applies(pc, m) for m in maps):
            r.bad(f"planners[{i}].kind", "a kind = 'tsp' planner runs on [[instances]] entries, and there is none"
                  if pc.kind == "tsp" else f"a kind = {pc.kind!r} planner runs on [[maps]] entries, and there is none")


def _check_overrides(r: _Reader, path: str, planner: str, overrides: dict, resolve, base: dict) -> None:
    """Unknown names one by one (with a close match), then the planner's own value checks."""
    import jaxplan as jp

    accepted = list(jp.planners()[planner].defaults)
    unknown = [k for k in overrides if k not in accepted]
    for k in unknown:
        r.bad(_join(path, k), f"planner {planner!r} has no parameter {k!r} (accepts: {', '.join(sorted(accepted))})"
              + _close(k, accepted))
    if unknown:
        return
    try:
        resolve(planner, {**base, **{k: _tuple(v) for k, v in overrides.items()}})
    except (ValueError, TypeError) as e:
        r.bad(path, str(e))


def _tuple(v: Any) -> Any:
    return tuple(v) if isinstance(v, list) else v


def nav_config(planner: PlannerConfig):
    """The `NavConfig` and DWA params mapping of a navigate planner (raises ValueError/TypeError on bad values)."""
    from jaxplan.dwa import Disc
    from jaxplan.nav import NavConfig

    base = NavConfig()
    robot_kw = dict(planner.robot)
    radius = robot_kw.pop("radius", None)
    robot = base.dwa.robot
    if robot_kw or radius is not None:
        changes = dict(robot_kw)
        if radius is not None:
            changes["footprint"] = Disc(float(radius))
        robot = dataclasses.replace(robot, **changes)
    dwa = base.dwa.replace(robot=robot, **dict(planner.dwa))
    return base.replace(dwa=dwa, **dict(planner.nav)), dict(planner.params)


def _check_nav(r: _Reader, p: str, pipeline: str, nav: Mapping, dwa: Mapping, robot: Mapping,
               params: Mapping) -> None:
    problem = _nav_problem(pipeline, nav, dwa, robot, params)
    if problem is not None:
        r.bad(p, f"navigation settings: {problem}")


def _nav_problem(pipeline: str, nav: Mapping, dwa: Mapping, robot: Mapping, params: Mapping) -> str | None:
    """Why pipeline ``pipeline`` would refuse these settings, or None."""
    from jaxplan.dwa._step import validate_params
    from jaxplan.nav._front import _config
    from jaxplan.nav._pipelines import get_pipeline

    probe = PlannerConfig("probe", "navigate", pipeline, _frozen({}), _frozen(dict(nav)), _frozen(dict(dwa)),
                          _frozen(dict(robot)), _frozen(dict(params)))
    try:
        cfg, weights = nav_config(probe)
        cfg = _config(cfg, get_pipeline(pipeline), None)
        validate_params(weights or None, cfg.dwa.evaluator)
    except (ValueError, TypeError) as e:
        return str(e)
    return None


def _read_metrics(r: _Reader, raw: dict, kinds: frozenset) -> tuple[str, ...]:
    if "metrics" not in raw:
        return tuple(m for m, spec in METRICS.items() if spec.kinds & kinds and spec.default)
    v = raw["metrics"]
    if not isinstance(v, list) or not v:
        r.bad("metrics", f"expected a non-empty list of metric names, got {_describe(v)}")
        return ()
    seen = set()
    for i, m in enumerate(v):
        p = f"metrics[{i}]"
        if not isinstance(m, str):
            r.bad(p, f"expected a metric name, got {_describe(m)}")
        elif m not in METRICS:
            r.bad(p, f"unknown metric {m!r}" + _close(m, list(METRICS)) + f" (known: {', '.join(METRICS)})")
        elif m in seen:
            r.bad(p, f"metric {m!r} is listed twice")
        elif kinds and not (METRICS[m].kinds & kinds):
            r.bad(p, f"metric {m!r} applies to kind {'/'.join(sorted(METRICS[m].kinds))} planners, and the config "
                     f"has only {'/'.join(sorted(kinds))} ones")
        seen.add(m)
    return tuple(m for m in METRICS if m in seen)


def _read_stats(r: _Reader, raw: dict, metrics: tuple[str, ...]) -> StatsSpec:
    t = r.table(raw.get("stats"), "stats", ("anova", "pairwise", "metrics", "alpha", "correction", "extremes"))
    chosen = r.str_list(t, "stats", "metrics")
    if chosen is None:
        chosen = [m for m in metrics if not METRICS[m].timing]
    else:
        for i, m in enumerate(chosen):
            if m not in metrics:
                r.bad(f"stats.metrics[{i}]", f"{m!r} is not one of the configured metrics ({', '.join(metrics)})")
            elif METRICS[m].timing:
                r.bad(f"stats.metrics[{i}]", f"{m!r} is a wall-clock time, measured per chunk: no per-seed values "
                                             "to test")
    return StatsSpec(
        anova=r.get(t, "stats", "anova", "bool", "stats" in raw),
        pairwise=r.get(t, "stats", "pairwise", "bool", False),
        metrics=tuple(chosen),
        alpha=r.get(t, "stats", "alpha", "float", 0.05, lo=0, strict_lo=True, hi=1),
        correction=r.get(t, "stats", "correction", "str", "holm", choices=("holm", "none")),
        extremes=r.get(t, "stats", "extremes", "bool", False),
    )


def scenario_bound(spec: MapSpec) -> int | None:
    """How many scenarios ``spec`` has at most, when the config alone tells (None: only the data does)."""
    sc = spec.scenarios
    if spec.is_tsp or sc.source == "scene":
        return 1
    if sc.source == "random":
        return sc.count or 10  # `runner._random_pairs` finds exactly this many or fails
    return sc.count  # scen rows: count is an upper bound; the filters may keep fewer


def _check_figure_scenario(r: _Reader, p: str, name: str | None, kind: str | None, t: dict,
                           sites: Sequence[MapSpec], planners: Sequence[PlannerConfig]) -> None:
    """A figure's ``scenario`` past a map's scenarios would crash the drawing (or leave an empty panel)."""
    sc = t.get("scenario")
    if kind not in _SCENARIO_FIGURE_PLANNERS or not isinstance(sc, int) or isinstance(sc, bool):
        return
    labels = t.get("planners") if isinstance(t.get("planners"), list) else None
    named = t.get("maps") if isinstance(t.get("maps"), list) else None
    drawn = [pc for pc in planners
             if pc.kind in _SCENARIO_FIGURE_PLANNERS[kind] and (labels is None or pc.label in labels)]
    for m in sites:
        n = scenario_bound(m)
        if (named is None or m.name in named) and any(applies(pc, m) for pc in drawn) and n is not None and sc >= n:
            r.bad(_join(p, "scenario"), f"figure {name!r}: scenario {sc} is past map {m.name!r}'s {n} scenario"
                                        f"{'s' if n > 1 else ''} (0..{n - 1})")
            return


def _read_figures(r: _Reader, raw: dict, metrics: tuple, maps: set, labels: set,
                  sites: Sequence[MapSpec] = (), planners: Sequence[PlannerConfig] = ()) -> tuple[FigureSpec, ...]:
    figs = raw.get("figures", [])
    if not isinstance(figs, list):
        r.bad("figures", f"expected [[figures]] tables, got {_describe(figs)}")
        return ()
    out, names = [], set()
    for i, f in enumerate(figs):
        p = f"figures[{i}]"
        if not isinstance(f, dict):
            r.bad(p, f"expected a table, got {_describe(f)}")
            continue
        kind = r.get(f, p, "kind", "str", None, choices=tuple(FIGURE_KINDS))
        if "kind" not in f:
            r.bad(_join(p, "kind"), "required key is missing")
        allowed = _FIGURE_COMMON | (FIGURE_KINDS[kind] if kind else frozenset(f) - _FIGURE_COMMON)
        t = r.table(f, p, allowed)
        name = r.get(t, p, "name", "str", None)
        if name is None and kind:
            name, k = kind, 2
            while name in names:
                name, k = f"{kind}_{k}", k + 1
        if name in names:
            r.bad(_join(p, "name"), f"duplicate figure name {name!r}")
        names.add(name)
        if "metric" in t and t["metric"] not in metrics:
            r.bad(_join(p, "metric"), f"{t['metric']!r} is not one of the configured metrics ({', '.join(metrics)})")
        for key, known in (("maps", maps), ("planners", labels)):
            lst = r.str_list(t, p, key) or []
            for j, x in enumerate(lst):
                if x not in known:
                    r.bad(f"{p}.{key}[{j}]", f"unknown {key[:-1]} {x!r} (configured: {', '.join(sorted(known))})")
        r.get(t, p, "format", "str", None, choices=("png", "svg", "pdf"))
        r.get(t, p, "title", "str", None)
        for k in ("scenario", "seed"):
            r.get(t, p, k, "int", None, lo=0)
        _check_figure_scenario(r, p, name, kind, t, sites, planners)
        if "band" in t and t["band"] not in ("iqr", "sd", "minmax", False):
            r.bad(_join(p, "band"), f"must be 'iqr', 'sd', 'minmax' or false, got {t['band']!r}")
        r.get(t, p, "log", "bool", None)
        r.get(t, p, "xlabel", "str", None)
        if "smoothing" in t:
            from jaxplan.smooth import SMOOTHERS

            r.get(t, p, "smoothing", "str", None, choices=tuple(sorted(SMOOTHERS)))
        if kind == "sweep" and "metric" not in t:
            r.bad(_join(p, "metric"), "required key is missing")
        if "steps" in t and not (isinstance(t["steps"], list) and t["steps"]
                                 and all(isinstance(v, int) and not isinstance(v, bool) and v >= 0
                                         for v in t["steps"])):
            r.bad(_join(p, "steps"), f"expected a non-empty list of control steps >= 0, got {_describe(t['steps'])}")
        if kind == "sweep":
            x = t.get("x")
            if isinstance(x, list):
                n_maps = len(t.get("maps") or maps)
                if len(x) != n_maps or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in x):
                    r.bad(_join(p, "x"), f"expected {n_maps} numbers (one per map) or a generator parameter name")
            elif not isinstance(x, str):
                r.bad(_join(p, "x"), "required: a generator parameter name or one number per map")
        if kind:
            out.append(FigureSpec(kind, name, _frozen({k: v for k, v in t.items() if k not in ("kind", "name")})))
    return tuple(out)


def _read_paper(r: _Reader, raw: dict, metrics: tuple, maps: set, labels: set) -> tuple[str, tuple[PaperValue, ...]]:
    t = r.table(raw.get("paper"), "paper", ("source", "values"))
    source = r.get(t, "paper", "source", "str", "")
    vals = t.get("values", [])
    if not isinstance(vals, list):
        r.bad("paper.values", f"expected [[paper.values]] tables, got {_describe(vals)}")
        return source, ()
    if vals and not source:
        r.bad("paper.source", "say where the paper's numbers come from (e.g. 'cui2025, Table 2')")
    out, seen = [], set()
    for i, v in enumerate(vals):
        p = f"paper.values[{i}]"
        if not isinstance(v, dict):
            r.bad(p, f"expected a table, got {_describe(v)}")
            continue
        planner = r.get(v, p, "planner", "str", None)
        if "planner" not in v:
            r.bad(_join(p, "planner"), "required key is missing")
        elif planner is not None and planner not in labels:
            r.bad(_join(p, "planner"), f"unknown planner label {planner!r} (configured: {', '.join(sorted(labels))})"
                  + _close(planner, list(labels)))
        mp = r.get(v, p, "map", "str", None)
        if mp is not None and mp not in maps:
            r.bad(_join(p, "map"), f"unknown map {mp!r} (configured: {', '.join(sorted(maps))})")
        for k, x in v.items():
            if k in ("planner", "map"):
                continue
            kp = _join(p, k)
            if k not in METRICS:
                r.bad(kp, f"unknown metric {k!r}" + _close(k, list(METRICS)))
                continue
            if k not in metrics:
                r.bad(kp, f"metric {k!r} is not configured (metrics = [{', '.join(metrics)}])")
                continue
            num = lambda y: isinstance(y, (int, float)) and not isinstance(y, bool)  # noqa: E731
            lo = hi = None
            if num(x):
                mean, sd = float(x), None
            elif isinstance(x, list) and len(x) == 2 and all(num(y) for y in x):
                mean, sd = float(x[0]), float(x[1])
            elif isinstance(x, dict) and "mean" in x and set(x) <= {"mean", "sd", "min", "max"} and all(
                    num(y) for y in x.values()):
                # A paper's Max/Min are stored as printed, unchecked against the mean: yu2020's Table 1
                # prints an ACO average below its minimum.
                mean, sd = float(x["mean"]), (float(x["sd"]) if "sd" in x else None)
                lo, hi = (float(x["min"]) if "min" in x else None), (float(x["max"]) if "max" in x else None)
            else:
                r.bad(kp, f"expected a number, [mean, sd] or {{ mean = , sd = , min = , max = }}, got {_describe(x)}")
                continue
            if not all(math.isfinite(y) for y in (mean, lo, hi) if y is not None) or (
                    sd is not None and not (math.isfinite(sd) and sd >= 0)):
                r.bad(kp, f"mean, min and max must be finite and sd finite and >= 0, got {x!r}")
                continue
            key = (planner, mp, k)
            if key in seen:
                r.bad(kp, f"a second paper value for planner {planner!r}, map {mp!r}, metric {k!r}")
            seen.add(key)
            out.append(PaperValue(planner, mp, k, mean, sd, lo, hi))
    return source, tuple(out)


def _read_quick(r: _Reader, q: dict, planners: tuple[PlannerConfig, ...], map_names: list[str] | None = None
                ) -> QuickSpec:
    """Quick overrides: each key must be accepted by at least one planner, and valid for each that accepts it."""
    from jaxplan.aco._tsp import _resolve as tsp_resolve
    from jaxplan.nav import get_pipeline
    from jaxplan.registry import resolve

    for k, v in q["overrides"].items():
        takers = [pc for pc in planners if k in _accepted(pc)]
        if not takers and planners:
            r.bad(f"experiment.quick.overrides.{k}", "no configured planner accepts this parameter")
        for pc in takers:
            own = {k2: _tuple(v2) for k2, v2 in pc.overrides.items()}
            try:
                if pc.kind == "tsp":
                    tsp_resolve(pc.name, {**own, k: _tuple(v)})
                    continue
                base = dict(get_pipeline(pc.name).planner_overrides) if pc.kind == "navigate" else {}
                resolve(_global(pc), {**base, **own, k: _tuple(v)})
            except (ValueError, TypeError) as e:
                if _overrides_ok(pc, own):  # else the planner's own overrides are at fault, reported at them
                    r.bad(f"experiment.quick.overrides.{k}", f"for {pc.label!r}: {e}")
    if q["nav"]:
        navs = [pc for pc in planners if pc.kind == "navigate"]
        if not navs:
            r.bad("experiment.quick.nav", "no planner has kind = 'navigate'")
        fields = _nav_fields()
        for k in q["nav"]:
            if k not in fields:
                r.bad(f"experiment.quick.nav.{k}", "unknown NavConfig field" + _close(k, list(fields)))
        if all(k in fields for k in q["nav"]):
            _check_quick_nav(r, q["nav"], navs)
    labels, names = [pc.label for pc in planners], map_names
    for key, known in (("planners", labels), ("maps", names)):
        for j, x in enumerate(q.get(key) or []):
            if known is not None and x not in known:
                r.bad(f"experiment.quick.{key}[{j}]", f"unknown {key[:-1]} {x!r} (configured: {', '.join(known)})")
    return QuickSpec(q["seeds"], q["count"], q["chunk"], _frozen(q["overrides"]), _frozen(q["nav"]),
                     tuple(q["planners"]) if q.get("planners") else None, tuple(q["maps"]) if q.get("maps") else None)


def _overrides_ok(pc: PlannerConfig, overrides: Mapping) -> bool:
    """Whether planner ``pc`` accepts ``overrides`` (its own, without the quick ones)."""
    from jaxplan.aco._tsp import _resolve as tsp_resolve
    from jaxplan.nav import get_pipeline
    from jaxplan.registry import resolve

    try:
        if pc.kind == "tsp":
            tsp_resolve(pc.name, dict(overrides))
        else:
            base = dict(get_pipeline(pc.name).planner_overrides) if pc.kind == "navigate" else {}
            resolve(_global(pc), {**base, **overrides})
    except (ValueError, TypeError):
        return False
    return True


def _check_quick_nav(r: _Reader, quick_nav: Mapping, navs: Sequence[PlannerConfig]) -> None:
    """The quick nav values merged into each navigate planner's own, checked as `_check_nav` checks those: else a
    bad value surfaces only mid-run, after a chunk is committed, under no config key."""
    import jaxplan as jp

    for pc in navs:
        if pc.name not in jp.pipelines():
            continue  # reported at its planners[i].name
        own = (pc.nav, pc.dwa, pc.robot, pc.params)
        if _nav_problem(pc.name, *own) is not None:
            continue  # reported at its planners[i]; the quick values are not to blame
        found = False
        for k, v in quick_nav.items():  # one key at a time, to name it
            problem = _nav_problem(pc.name, {**dict(pc.nav), k: v}, *own[1:])
            if problem is not None:
                found = True
                r.bad(f"experiment.quick.nav.{k}", f"for {pc.label!r}: {problem}")
        problem = None if found else _nav_problem(pc.name, {**dict(pc.nav), **dict(quick_nav)}, *own[1:])
        if problem is not None:  # fine alone, not together
            r.bad("experiment.quick.nav", f"for {pc.label!r}: {problem}")


def _accepted(pc: PlannerConfig) -> tuple[str, ...]:
    """The override names planner ``pc`` accepts (none for a name that failed validation)."""
    import jaxplan as jp
    from jaxplan.aco._tsp import TSP_PLANNERS, tsp_defaults

    if pc.kind == "tsp":
        return tuple(tsp_defaults(pc.name)) if pc.name in TSP_PLANNERS else ()
    registry = jp.planners()
    g = _global(pc)
    return tuple(registry[g].defaults) if g in registry else ()


def _global(pc: PlannerConfig) -> str | None:
    import jaxplan as jp

    if pc.kind in ("plan", "tsp"):
        return pc.name
    p = jp.pipelines().get(pc.name)
    return p.global_planner if p else None


# ---------------------------------------------------------------------------------------------
# Entry points


_TOP = ("metrics", "experiment", "maps", "instances", "scenarios", "planners", "stats", "figures", "paper")


def parse_config(text: str, *, data_dir: str | os.PathLike | None = None, source: str = "config",
                 path: Path | None = None) -> ExperimentConfig:
    """Parses and validates config ``text`` (TOML).

    Args:
      text: the TOML text.
      data_dir: folder that relative map paths are resolved against (default `default_data_dir`).
      source: a name for error messages (the file path).
      path: the file it came from, if any.

    Raises:
      ConfigError: listing every problem, each with its key path.
    """
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ConfigError([f"TOML syntax: {e}"], source) from None
    ddir = Path(data_dir) if data_dir is not None else default_data_dir()
    r = _Reader()
    r.table(raw, "", _TOP)
    exp = _read_experiment(r, raw)
    maps = _read_maps(r, raw, ddir, required="instances" not in raw)
    maps = maps + _read_instances(r, raw, ddir, {m.name for m in maps})
    planners = _read_planners(r, raw)
    _check_sites(r, maps, planners)
    kinds = frozenset(p.kind for p in planners if p.kind)
    metrics = _read_metrics(r, raw, kinds)
    stats = _read_stats(r, raw, metrics)
    map_names, labels = {m.name for m in maps}, {p.label for p in planners}
    figures = _read_figures(r, raw, metrics, map_names, labels, maps, planners)
    paper_source, paper = _read_paper(r, raw, metrics, map_names, labels)
    quick = _read_quick(r, exp["quick_raw"], planners, sorted(map_names))
    if r.problems:
        raise ConfigError(r.problems, source)
    return ExperimentConfig(
        name=exp["name"], description=exp["description"], seeds=exp["seeds"], chunk=exp["chunk"], metrics=metrics,
        maps=maps, planners=planners, stats=stats, figures=figures, paper_source=paper_source, paper=paper,
        quick=quick, text=text, path=path, data_dir=ddir,
    )


def load_config(path: str | os.PathLike, *, data_dir: str | os.PathLike | None = None) -> ExperimentConfig:
    """Reads and validates the TOML config at ``path`` (see the module docstring for the schema).

    Raises:
      FileNotFoundError: no such file.
      ConfigError: listing every problem of the config, each with its key path.
    """
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"config file not found: {p}")
    return parse_config(p.read_text(encoding="utf-8"), data_dir=data_dir, source=str(p), path=p.resolve())


def apply_quick(cfg: ExperimentConfig) -> ExperimentConfig:
    """The config with its ``[experiment.quick]`` changes applied (``is_quick=True``)."""
    q = cfg.quick
    maps = tuple(dataclasses.replace(m, scenarios=dataclasses.replace(
        m.scenarios, count=min(q.count, m.scenarios.count or q.count))) for m in cfg.maps) if q.count else cfg.maps
    planners = []
    for pc in cfg.planners:
        accepted = _accepted(pc)
        extra = {k: v for k, v in q.overrides.items() if k in accepted}
        nav = {**dict(pc.nav), **dict(q.nav)} if pc.kind == "navigate" else dict(pc.nav)
        planners.append(dataclasses.replace(pc, overrides=_frozen({**dict(pc.overrides), **extra}), nav=_frozen(nav)))
    if q.planners:
        planners = [pc for pc in planners if pc.label in q.planners]
    if q.maps:
        maps = tuple(m for m in maps if m.name in q.maps)
    return cfg.replace(seeds=q.seeds or cfg.seeds, chunk=q.chunk or cfg.chunk, maps=maps, planners=tuple(planners),
                       is_quick=True)
