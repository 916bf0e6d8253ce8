"""The experiment config's schema: its vocabularies, its TOML tables declared once, and the resolved dataclasses.

Each key is a `jaxplan.experiments.schema.setting` on a dataclass field (its type, default, bounds or choices and
one-line doc). `ExperimentFile` is the top level; the tables under it are `ExperimentTable` (``[experiment]``),
`QuickSpec` (``[experiment.quick]``, whose settings declare the quick overlay), `MapTable` (``[[maps]]``),
`InstanceTable` (``[[instances]]``), `ScenarioSpec` (``[scenarios]``), `PlannerConfig` (``[[planners]]``),
`ObstacleSpec`, `TeamSpec`, `StatsSpec` (``[stats]``), `FigureTable` (``[[figures]]``) and `PaperTable`
(``[paper]``). Resolved objects: `ExperimentConfig` and its parts (`MapSpec`, `ScenarioSpec`, `PlannerConfig`,
`ObstacleSpec`, `StatsSpec`, `FigureSpec`, `PaperValue`, `QuickSpec`).

`jaxplan.experiments.config` reads a file against these declarations (and re-exports every name here);
`jaxplan.experiments.config_checks` holds the checks that need more than one key.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any, Callable, Mapping

from jaxplan.core.io import SAFE_NAME
from jaxplan.experiments.metric_catalogue import METRICS
from jaxplan.experiments.schema import Setting, declaration, frozen, setting, settings

__all__ = [
    "KINDS", "DRAW_SEP", "FIGURE_KIND_NAMES", "SCENARIO_FIGURE_PLANNERS", "map_generators", "GENERATORS",
    "DEPRECATED_GENERATORS", "GENERATOR_PARAMS", "SCENARIO_SOURCES", "SPREADS", "ROBOT_KEYS", "ROBOT_MODELS",
    "RUN_NAME", "BANDS", "ScenarioSpec", "ObstacleSpec", "TeamSpec", "PlannerConfig", "StatsSpec", "QuickSpec",
    "MapSpec", "FigureSpec", "PaperValue", "ExperimentConfig", "ExperimentTable", "MapTable", "InstanceTable",
    "FigureTable", "FIGURE_KINDS", "PaperValueTable", "PaperTable", "ExperimentFile", "applies",
]


KINDS = ("plan", "navigate", "tsp")
"""Planner kinds: a grid planner (`jaxplan.plan_batch`), a navigation pipeline (`jaxplan.navigate_batch`),
a TSP ant colony on a TSPLIB instance (`jaxplan.solve_tsp`'s program, batched over seeds)."""

DRAW_SEP = "~"
"""Separates a generated map's name from its draw index in the name of draw d > 0 (``warehouse20m~3``)."""

FIGURE_KIND_NAMES = ("convergence", "box", "bar", "paths", "trajectories", "pheromone", "diversity", "fan", "controls",
                     "sweep", "tours")
"""The figure kinds of ``[[figures]]`` (drawn by `jaxplan.experiments.figure_kinds`)."""
SCENARIO_FIGURE_PLANNERS: Mapping[str, tuple[str, ...]] = MappingProxyType({
    "convergence": ("plan", "tsp"), "diversity": ("plan", "tsp"), "paths": ("plan", "navigate"),
    "pheromone": ("plan",), "trajectories": ("navigate",), "controls": ("navigate",), "fan": ("navigate",),
})
"""Figure kinds with a ``scenario`` key -> the planner kinds they draw (as `figures` selects them)."""


def map_generators() -> dict[str, tuple[Callable[..., Any], bool]]:
    """name -> (factory, is_dataclass). Dataclass generators take their fields as params."""
    from jaxplan import grid as G

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
    from jaxplan.grid import poisson_risk, warehouse_chen2023

    scene = warehouse_chen2023(key)
    return scene._replace(grid=poisson_risk(scene.grid, int(key) + 1, lam=float(lam)))


GENERATORS = ("warehouse", "random", "urban", "mountain", "warehouse_chen2023", "warehouse_yu2020", "demo_warehouse",
              "warehouse_chen2023_risk")
"""Generator names a map may use (the generators of `jaxplan.grid`)."""
DEPRECATED_GENERATORS: Mapping[str, str] = MappingProxyType({
    "warehouse_seed003": "warehouse_chen2023", "warehouse_seed004": "warehouse_yu2020",
    "warehouse_seed003_risk": "warehouse_chen2023_risk"})
"""Generator names of the previous release (papers by internal number) -> their new names; accepted with a
`DeprecationWarning` for one release."""
GENERATOR_PARAMS = {"warehouse_chen2023": (), "warehouse_yu2020": ("size",), "demo_warehouse": (),
                    "warehouse_chen2023_risk": ("lam",)}
"""The parameters of the generators that are functions (a dataclass generator takes its fields)."""

SCENARIO_SOURCES = ("scen", "random", "scene")
SPREADS = ("first", "even", "random")
ROBOT_KEYS = ("model", "v_min", "v_max", "omega_max", "accel", "decel", "alpha", "wheelbase", "steer_max", "radius")
"""The ``robot`` keys of a navigate planner: ``model`` (one of `ROBOT_MODELS`), the model's limits
(`jaxplan.dwa.Unicycle`, or `jaxplan.dwa.Ackermann` with ``wheelbase`` and ``steer_max``), and ``radius`` for a `Disc`
footprint (default: the model's own footprint)."""
ROBOT_MODELS = ("unicycle", "ackermann")
"""``robot.model`` of a navigate planner: a differential drive (cui2025) or li2026's car-like robot."""
RUN_NAME = SAFE_NAME
"""What an experiment's or tuning run's name (and a figure's name) must match: it names the run folder (the
figure's files), which must stay inside the output folder (`jaxplan.core.io.SAFE_NAME`)."""
BANDS = ("iqr", "sd", "minmax")
"""The spread bands of convergence and diversity figures (or ``false``: none)."""


def _nav_fields() -> tuple[str, ...]:
    from jaxplan.nav import NavConfig

    return tuple(f.name for f in dataclasses.fields(NavConfig) if f.name != "dwa")


def _dwa_fields() -> tuple[str, ...]:
    from jaxplan.dwa import DWAConfig

    return tuple(f.name for f in dataclasses.fields(DWAConfig) if f.name not in ("robot", "keep_rollouts"))


def _mppi_fields() -> tuple[str, ...]:
    from jaxplan.mppi import MPPIConfig

    # The robot, period and d_safe of an episode are its DWA config's (one robot model per episode).
    return tuple(f.name for f in dataclasses.fields(MPPIConfig)
                 if f.name not in ("robot", "period", "d_safe", "keep_rollouts"))


def _dwa_weights() -> tuple[str, ...]:
    from jaxplan.dwa import DWAParams
    from jaxplan.mppi import MPPIParams

    # A DWA pipeline's critic weights, or an MPPI pipeline's (checked against its local planner).
    return DWAParams._fields + tuple(k for k in MPPIParams._fields if k not in DWAParams._fields)


def _smoothers() -> tuple[str, ...]:
    from jaxplan.smoothing import SMOOTHERS

    return tuple(sorted(SMOOTHERS))


# ---------------------------------------------------------------------------------------------
# The schema and the resolved config


@dataclass(frozen=True)
class ScenarioSpec:
    """How a map's start-goal pairs are chosen: ``[scenarios]`` for every map; a map's own ``scenarios``
    keys replace these."""

    source: str = setting("str", "scen", "'scen': rows of the map's .scen file (MovingAI maps); 'random': pairs "
                          "of connected free cells; 'scene': the generator's own start and goal (one scenario)",
                          choices=SCENARIO_SOURCES,
                          default_text="`\"scen\"` for a MovingAI map, `\"random\"` for a generator")
    count: int | None = setting("int", None, "scenarios per map (scen rows: at most this many)", ge=1,
                                default_text="every selected scen row; 10 random pairs")
    spread: str = setting("str", "even", "scen rows: which of the filtered rows (the first ones, evenly spaced in "
                          "file order, or a random choice)", choices=SPREADS)
    seed: int = setting("int", 0, "numpy seed of spread = 'random' and source = 'random'", ge=0)
    min_bucket: int | None = setting("int", None, "scen rows: smallest bucket kept (inclusive)", ge=0)
    max_bucket: int | None = setting("int", None, "scen rows: largest bucket kept (inclusive)", ge=0)
    min_optimal: float | None = setting("float", None, "scen rows: smallest exact octile optimum kept (m)", ge=0)
    max_optimal: float | None = setting("float", None, "scen rows: largest exact octile optimum kept (m)", ge=0)
    min_distance: float = setting("float", 0.0, "random pairs: straight-line start-goal distance at least this (m)",
                                  ge=0)
    min_clearance: float = setting("float", 0.0, "random pairs: start and goal cells at least this far (m, cell "
                                   "centre to the nearest blocked square) from obstacles, so that a robot with a "
                                   "footprint and safety distance fits there", ge=0)


@dataclass(frozen=True)
class ObstacleSpec:
    """Random moving discs per episode (`jaxplan.random_obstacles`): each (scenario, seed) trial draws its own
    set from ``(seed, scenario, trial seed)``."""

    n: int = setting("int", 0, "discs per episode", ge=0)
    speed: float = setting("float", 1.0, "their speed (m/s)", ge=0)
    radius: float = setting("float", 0.25, "their radius (m)", ge=0)
    waypoints: int = setting("int", 4, "random cells per route (1 stands still)", ge=1)
    loop: bool = setting("bool", False, "routes loop (else the discs bounce back along them)")
    seed: int = setting("int", 0, "mixed into every trial's draw", ge=0)
    avoid_radius: float = setting("float", 1.0, "disc starts keep this far (m, to the disc's edge) from the robot's "
                                  "start and goal", ge=0)
    behavior: str = setting("str", "blind", "'blind': on their routes regardless of the robot; 'social': the same "
                            "routes, avoiding robots, each other and walls (social force model)",
                            choices=("blind", "social"))


@dataclass(frozen=True)
class TeamSpec:
    """A team of robots sharing one episode (`jaxplan.navigate_multi`; li2026 Table 3's multi-robot cooperation
    mode). Robot 0 takes the scenario's start and goal; robots 1.. draw theirs per scenario from
    ``(seed, map, scenario)`` (the same teams for every planner), as the map's random scenarios are drawn: connected
    pairs at least ``min_distance`` apart, cells ``min_clearance`` from obstacles (the map's `ScenarioSpec`). A trial's
    row holds team metrics (`jaxplan.experiments.team`): success = every robot arrived, ``arrived`` = the share that
    did, counts, energy and path length summed over the robots, time_s the makespan, max_curvature the largest."""

    robots: int = setting("int", doc="robots per episode (robot 0: the scenario's own start and goal)", required=True,
                          ge=2)
    spacing: float = setting("float", 2.0, "every start and goal of the team at least this far (m) from its "
                             "teammates' starts and goals (more than two footprint radii)", ge=0)
    seed: int = setting("int", 0, "mixed into every team's draw", ge=0)


@dataclass(frozen=True)
class PlannerConfig:
    """A planner to compare: a column of the result tables. ``kind = "plan"``: a registered grid planner
    (`jaxplan.plan_batch`); ``"navigate"``: a two-level pipeline (`jaxplan.navigate_batch`); ``"tsp"``: a TSP
    ant colony (`jaxplan.solve_tsp`'s program, all seeds in one call), run on the ``[[instances]]``."""

    label: str = setting("str", doc="unique column label", default_text="the name")
    kind: str = setting("str", doc="plan, navigate or tsp (see above)", required=True, choices=KINDS)
    name: str = setting("str", doc="a planner (plan: `jaxplan.planners()`), pipeline (navigate: "
                        "`jaxplan.nav.pipelines()`) or TSP planner (tsp: aco, praco)", required=True)
    overrides: Mapping[str, Any] = setting("table", doc="planner parameters, checked against the planner's "
                                           "defaults (navigate: the pipeline's global planner)")
    nav: Mapping[str, Any] = setting("table", doc="navigate: `NavConfig` fields (scalars)", keys=_nav_fields)
    dwa: Mapping[str, Any] = setting("table", doc="navigate: `DWAConfig` fields (scalars)", keys=_dwa_fields)
    robot: Mapping[str, Any] = setting("table", doc="navigate: model ('unicycle' or 'ackermann', li2026) and its "
                                       "limits (`Unicycle`, `Ackermann`); radius: a `Disc` footprint (m)",
                                       keys=ROBOT_KEYS)
    params: Mapping[str, Any] = setting("table", doc="navigate: the local planner's weights (`DWAParams`, or "
                                        "`MPPIParams` for an MPPI pipeline)", keys=_dwa_weights)
    obstacles: ObstacleSpec | None = setting("section", None, "navigate: random moving discs per episode",
                                             section=ObstacleSpec)
    mppi: Mapping[str, Any] = setting("table", doc="navigate: `MPPIConfig` fields (scalars) of an MPPI pipeline",
                                      keys=_mppi_fields)
    team: TeamSpec | None = setting("section", None, "navigate: a team of robots in one shared episode (one trial "
                                    "= one team episode, team metrics)", section=TeamSpec)

    @property
    def global_planner(self) -> str:
        """The registry planner that makes the global paths (a tsp planner: its TSP planner name)."""
        if self.kind in ("plan", "tsp"):
            return self.name
        from jaxplan.nav import get_pipeline

        return get_pipeline(self.name).global_planner


@dataclass(frozen=True)
class StatsSpec:
    """Significance tests across planners, per map and metric (on per-seed means)."""

    anova: bool = setting("bool", True, "one-way ANOVA across planners",
                          default_text="true when a `[stats]` table is given, else false")
    pairwise: bool = setting("bool", False, "Welch t-tests between every pair of planners")
    metrics: tuple[str, ...] = setting("strings", (), "the metrics tested (configured ones)",
                                       default_text="every configured metric except wall-clock times")
    alpha: float = setting("float", 0.05, "significance level: p < alpha is marked in the report", gt=0, le=1)
    correction: str = setting("str", "holm", "pairwise p-values adjusted by Holm's method, or not",
                              choices=("holm", "none"))
    extremes: bool = setting("bool", False, "the tables also show the smallest and largest single-trial value "
                             "(yu2020 reports Max/Min beside Avg/Sd)")


@dataclass(frozen=True)
class QuickSpec:
    """What ``--quick`` changes: a smoke run for CI (every key optional)."""

    seeds: tuple[int, ...] | None = setting("seeds", None, "the seeds of the quick run: a count or a list",
                                            overlay="set")
    count: int | None = setting("int", None, "at most this many scenarios per map", ge=1,
                                overlay="cap maps[].scenarios.count")
    chunk: int | None = setting("int", None, "scenarios per compiled call", ge=1, overlay="set")
    overrides: Mapping[str, Any] = setting("table", doc="planner parameters, given to every planner that accepts "
                                           "the key", overlay="merge planners[].overrides")
    nav: Mapping[str, Any] = setting("table", doc="`NavConfig` fields for every navigate planner",
                                     overlay="merge planners[].nav")
    planners: tuple[str, ...] | None = setting("strings", None, "only these planner labels run (CI time is "
                                               "compile time: each pipeline compiles once)", default_text="all",
                                               overlay="keep planners[].label")
    maps: tuple[str, ...] | None = setting("strings", None, "only these maps run", default_text="all",
                                           overlay="keep maps[].name")


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
      resolution: metres per cell; None for a ROS map (``.yaml``) without one: it keeps its own (the loaded
        grid's ``resolution`` is the value used).
      scenarios: how this map's scenarios are chosen.
      tsplib: absolute ``.tsp`` path of a TSP instance (None for a map).
      tour: absolute ``.opt.tour`` path of the instance's optimal tour, or None.
      optimum: the instance's optimal tour length as configured, or None.
      key: where it was configured (``maps[i]`` or ``instances[j]``), for error messages.
      ros: a ROS map's `jaxplan.grid.load_ros_map` options (``keepout``, ``speed`` as absolute paths,
        ``speed_filter``, ``top_speed``, ``unknown``); empty for any other map.
      family: the configured map's name when this site is one of its ``draws`` (draw 0 keeps the name, draw
        ``d`` is ``NAME~d`` with generator key ``seed + d``); draw: that draw's index.
      paper_map: the paper's own published map or instance (absolute numbers are comparable there).
    """

    name: str
    path: Path | None
    scen: Path | None
    generator: str | None
    params: Mapping[str, Any]
    seed: int
    resolution: float | None
    scenarios: ScenarioSpec
    tsplib: Path | None = None
    tour: Path | None = None
    optimum: float | None = None
    key: str = ""
    ros: Mapping[str, Any] = dataclasses.field(default_factory=lambda: frozen({}))
    family: str = ""
    draw: int = 0
    paper_map: bool = False

    @property
    def is_tsp(self) -> bool:
        return self.tsplib is not None

    @property
    def map_family(self) -> str:
        """The configured map this site is a draw of (its own name for a map with one draw)."""
        return self.family or self.name


@dataclass(frozen=True)
class FigureSpec:
    """A figure for `jaxplan figures`: kind, file stem, and its parameters (validated, not drawn here)."""

    kind: str
    name: str
    params: Mapping[str, Any]


@dataclass(frozen=True)
class PaperValue:
    """A number the paper reports: ``mean`` (and ``sd``, ``min``, ``max``) of ``metric`` for a planner (on
    ``map``, or every map), over ``n`` runs as the paper states them (None: not stated)."""

    planner: str
    map: str | None
    metric: str
    mean: float
    sd: float | None = None
    min: float | None = None
    max: float | None = None
    n: int | None = None


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


# TOML tables without a resolved object of their own: declarations of keys only.


@declaration
class ExperimentTable:
    """The run: its name, seeds and chunking, and what ``--quick`` changes."""

    name: str = setting("str", None, "the run folder runs/NAME", required=True, pattern=RUN_NAME,
                        hint="it names the run folder")
    description: str = setting("str", "", "one line for the report")
    seeds: Any = setting("seeds", 30, "a count n (seeds 0..n-1) or a list of distinct integers in [0, 2**32); "
                         "every (scenario, planner) runs with all of them")
    chunk: int = setting("int", 16, "scenarios per compiled call; `jaxplan run --chunk` overrides", ge=1)
    quick: Any = setting("section", None, "what `--quick` changes", section=QuickSpec)


@declaration
class MapTable:
    """A map for the plan and navigate planners: a MovingAI file (``path``) or a generator (``generator``),
    exactly one of them."""

    name: str = setting("str", None, "label in tables and figures; unique among maps and instances",
                        default_text="the file's stem or the generator's name")
    path: str = setting("str", None, "a MovingAI .map file or a ROS map_server map's .yaml, relative to the data "
                        "folder (`--data-dir`, `$JAXPLAN_DATA`) or absolute")
    scen: str = setting("str", None, "its .scen file (MovingAI maps only)",
                        default_text="MAP.scen, else STEM-random-1.scen beside the map")
    generator: str = setting("str", None, "a map generator of `jaxplan.grid`", choices=GENERATORS,
                             aliases=DEPRECATED_GENERATORS)
    params: Mapping[str, Any] = setting("table", doc="the generator's own settings: a dataclass generator's fields; "
                                        "warehouse_yu2020: size (30 or 35); warehouse_chen2023_risk: lam (chen2023's "
                                        "Poisson risk rate)")
    seed: int = setting("int", 0, "the generator's key (generated maps only)", ge=0)
    draws: int = setting("int", 1, "generated maps: independent draws with keys seed, seed + 1, ...; draw d > 0 "
                         "runs as its own map NAME~d, and the report treats the draws as the unit of replication "
                         "(intervals over per-draw means), so a difference that belongs to one map draw is not "
                         "taken for the planner's", ge=1)
    paper_map: bool = setting("bool", False, "the paper's own map, as published: only on such a map (or instance) "
                              "are absolute numbers (lengths, turns, iterations, collisions) compared with the "
                              "paper's; a generated map is never one")
    resolution: float = setting("float", None, "metres per cell; a ROS map is resampled to it (a coarse cell is "
                                "blocked if any fine cell it overlaps is)", gt=0,
                                default_text="1.0 for a MovingAI or generated map; a ROS map's own")
    scenarios: Any = setting("section", None, "this map's scenario keys, replacing those of `[scenarios]`",
                             section=ScenarioSpec)
    keepout: str = setting("str", None, "a ROS map's Nav2 keep-out mask (.yaml), relative to the data folder or "
                           "absolute: its occupied cells become blocked")
    speed_mask: str = setting("str", None, "a ROS map's Nav2 speed mask (.yaml): the map's speed limits, which the "
                              "navigation episodes obey")
    speed_filter: Any = setting("custom", None, "the speed mask's filter `[type, base, multiplier]` (Nav2's "
                                "CostmapFilterInfo): type 1 is percent of the top speed, type 2 metres per second "
                                "(then give `top_speed`)", default_text="[1, 100.0, -1.0], Nav2's tutorial",
                                json={"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3},
                                type_text="array of 3 numbers")
    top_speed: float = setting("float", None, "the robot's top speed in m/s, for a type 2 (absolute) speed mask",
                               gt=0)
    unknown: str = setting("str", None, "a ROS map's unknown cells", choices=("blocked", "free"),
                           default_text="blocked")


@declaration
class InstanceTable:
    """A TSPLIB instance for the tsp planners (no ``[[maps]]`` needed then)."""

    name: str = setting("str", None, "label in tables; unique among maps and instances",
                        default_text="the file's stem")
    path: str = setting("str", None, "a TSPLIB .tsp file, relative to the data folder or absolute", required=True)
    tour: str = setting("str", None, "its optimal tour, for optimality_gap",
                        default_text="STEM.opt.tour beside it, if present")
    optimum: float = setting("float", None, "or the optimal tour length itself (not both; neither: optimality_gap "
                             "is nan)", gt=0)


@declaration
class FigureTable:
    """A figure for `jaxplan figures`: stored with the run, not drawn by `jaxplan run`. Its kind decides which
    further keys it takes."""

    kind: str = setting("str", None, "convergence, diversity (yu2020: sd of the ants' costs): best cost per "
                        "iteration; box, bar: a metric per planner; sweep: a metric against x; paths, pheromone, "
                        "trajectories, controls (v and omega over time), fan (the DWA rollouts): one trial; tours: "
                        "the best tour over the instance's cities", required=True, choices=FIGURE_KIND_NAMES)
    name: str = setting("str", None, "file stem; unique", default_text="the kind, then kind_2, ...", pattern=RUN_NAME,
                        hint="it names the figure's files, inside the figure folder")
    title: str = setting("str", None, "the figure's title", default_text="one made from the kind")
    maps: tuple[str, ...] = setting("strings", None, "only these maps (names)", default_text="all")
    planners: tuple[str, ...] = setting("strings", None, "only these planners (labels)", default_text="all")
    format: str = setting("str", None, "file format", choices=("png", "svg", "pdf"), default_text="png and svg")
    band: Any = setting("custom", None, "the spread around the median: interquartile range, ±1 sd (around the "
                        "mean), min-max, or none (false)", default_text='`"iqr"`', choices=BANDS + (False,),
                        type_text="string or false", json={"enum": [*BANDS, False]},
                        when=("kind", ("convergence", "diversity")))
    log: bool = setting("bool", None, "logarithmic scale (pheromone: of the colours)",
                        default_text="false; pheromone: true", when=("kind", ("convergence", "pheromone", "diversity")))
    scenario: int = setting("int", None, "the scenario drawn (index among the map's chosen scenarios)", ge=0,
                            default_text="`0`", when=("kind", ("convergence", "paths", "trajectories", "pheromone",
                                                              "diversity", "fan", "controls")))
    seed: int = setting("int", None, "the trial seed drawn (one of the run's seeds)", ge=0,
                        default_text="the first seed",
                        when=("kind", ("paths", "trajectories", "pheromone", "fan", "controls", "tours")))
    metric: str = setting("str", None, "a configured metric (sweep: required)", default_text="the first stats metric",
                          when=("kind", ("box", "bar", "sweep")))
    smoothing: str = setting("str", None, "also draw each path after this smoother (yu2020 Fig. 11)",
                             choices=_smoothers, when=("kind", ("paths",)))
    steps: Any = setting("custom", None, "the control steps whose rollouts are drawn", default_text="mid-episode",
                         type_text="list of integers >= 0",
                         json={"type": "array", "minItems": 1, "items": {"type": "integer", "minimum": 0}},
                         when=("kind", ("fan",)))
    x: Any = setting("custom", None, "the x axis: a generator parameter name (e.g. \"obstacle_ratio\") or one number "
                     "per map", required=False, type_text="string or list of numbers",
                     json={"oneOf": [{"type": "string"}, {"type": "array", "items": {"type": "number"}}]},
                     default_text="**required**", when=("kind", ("sweep",)))
    xlabel: str = setting("str", None, "the x axis label", default_text="x", when=("kind", ("sweep",)))


FIGURE_KINDS: Mapping[str, frozenset] = MappingProxyType({
    kind: frozenset(s.name for s in settings(FigureTable) if s.when is not None and kind in s.when[1])
    for kind in FIGURE_KIND_NAMES})
"""Figure kinds and the keys each accepts besides ``kind name title maps planners format`` (from `FigureTable`)."""


@declaration
class PaperValueTable:
    """One number the paper reports, for a planner (on one map, or every map)."""

    planner: str = setting("str", None, "a planner label", required=True)
    map: str = setting("str", None, "a map name", default_text="every map")
    n: int = setting("int", None, "the runs behind this value's mean and sd, as the paper states them (1: a "
                     "single run)", ge=1, default_text="`[paper] n`")
    schema_extra = Setting(
        "custom", name="metric", doc="a configured metric's value: mean, [mean, sd] or { mean, sd, min, max } (sd, "
        "min and max optional: a paper's Max/Min columns, stored as printed)", type_text="number, [mean, sd] or table",
        keys=tuple(METRICS), json={"oneOf": [
            {"type": "number"}, {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2},
            {"type": "object", "required": ["mean"], "additionalProperties": False,
             "properties": {k: {"type": "number"} for k in ("mean", "sd", "min", "max")}}]})


@declaration
class PaperTable:
    """The paper's numbers, shown beside ours and labelled "paper"."""

    source: str = setting("str", "", "where they come from (e.g. \"cui2025, Table 2\"); required with values")
    n: int = setting("int", None, "the runs behind each mean and sd, as the paper states them (1: each value is "
                     "a single run); decides the verdict rule of its cells", ge=1,
                     default_text="not stated: a value with an sd is judged by a prediction interval")
    values: Any = setting("tables", None, "the numbers", section=PaperValueTable)


@declaration
class ExperimentFile:
    """An experiment config (`jaxplan run CONFIG`). Top-level keys come before the first table in TOML."""

    metrics: tuple[str, ...] = setting(
        "strings", None, "the metrics recorded (stored in `METRICS` order)", choices=tuple(METRICS), nonempty=True,
        default_text="every metric that applies to the configured planner kinds except the opt-in ones ("
                     + ", ".join(m for m, spec in METRICS.items() if not spec.default) + ")")
    experiment: Any = setting("section", None, "the run", section=ExperimentTable, required=True)
    maps: Any = setting("tables", None, "MovingAI maps or generators, for plan and navigate planners",
                        section=MapTable, nonempty=True, default_text="required unless `[[instances]]` are given")
    instances: Any = setting("tables", None, "TSPLIB instances, for tsp planners", section=InstanceTable,
                             nonempty=True)
    scenarios: Any = setting("section", None, "the scenarios of every map", section=ScenarioSpec)
    planners: Any = setting("tables", None, "the planners compared, in table order", section=PlannerConfig,
                            required=True, nonempty=True)
    stats: Any = setting("section", None, "significance tests", section=StatsSpec)
    figures: Any = setting("tables", None, "figures for `jaxplan figures`", section=FigureTable)
    paper: Any = setting("section", None, "the paper's reported numbers", section=PaperTable)
    schema_json = {"anyOf": [{"required": ["maps"]}, {"required": ["instances"]}]}


def applies(planner: PlannerConfig, site: MapSpec) -> bool:
    """Whether ``planner`` runs on ``site``: tsp planners on TSP instances, plan/navigate planners on maps."""
    return (planner.kind == "tsp") == site.is_tsp
