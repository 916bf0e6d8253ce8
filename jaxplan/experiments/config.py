"""Experiment configs: TOML files read with `tomllib` into frozen dataclasses, checked in full before any work.

A config names maps, scenarios, planners, seeds, metrics, statistics, figures and the paper's reported
numbers. `load_config` reads and validates it; every problem is collected with its key path and one
`ConfigError` lists them all, so a typo found at the 20th planner does not cost an overnight run a restart
per mistake.

The schema is declared once, below: each key is a `jaxplan.experiments.schema.setting` on a dataclass
field (its type, default, bounds or choices and one-line doc). `ExperimentFile` is the top level; the
tables under it are `ExperimentTable` (``[experiment]``), `QuickSpec` (``[experiment.quick]``), `MapTable`
(``[[maps]]``), `InstanceTable` (``[[instances]]``), `ScenarioSpec` (``[scenarios]``), `PlannerConfig`
(``[[planners]]``), `ObstacleSpec`, `StatsSpec` (``[stats]``), `FigureTable` (``[[figures]]``) and
`PaperTable` (``[paper]``). The reference page ``docs/guide/config.md`` and the editors' JSON Schema
``configs/schema/experiment.schema.json`` are generated from them (``python -m jaxplan.config_reference``);
``configs/`` holds complete examples.

Planner kinds run where they apply: ``plan`` and ``navigate`` planners on every ``[[maps]]`` entry,
``tsp`` planners on every ``[[instances]]`` entry (`applies`); a map or instance that no configured
planner applies to is an error.

Resolved objects: `ExperimentConfig` and its parts (`MapSpec`, `ScenarioSpec`, `PlannerConfig`,
`ObstacleSpec`, `StatsSpec`, `FigureSpec`, `PaperValue`, `QuickSpec`). Paths are absolute after loading;
`ExperimentConfig.text` keeps the file's bytes for the run folder's copy. TSP instances are `MapSpec`
entries too (``tsplib`` set), after the maps in ``ExperimentConfig.maps``: tables, figures and quick
filters name them like maps.
"""

from __future__ import annotations

import dataclasses
import math
import os
import tomllib
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any, Callable, Mapping, Sequence

from jaxplan.core.io import SAFE_NAME
from jaxplan.experiments.schema import (
    ConfigError,
    Reader,
    Setting,
    declaration,
    describe,
    did_you_mean,
    frozen,
    join,
    setting,
    setting_of,
    settings,
)

__all__ = [
    "ConfigError", "ExperimentConfig", "MapSpec", "ScenarioSpec", "PlannerConfig", "ObstacleSpec", "TeamSpec",
    "StatsSpec", "FigureSpec", "PaperValue", "QuickSpec", "Metric", "METRICS", "GENERATORS", "DEPRECATED_GENERATORS",
    "FIGURE_KINDS", "KINDS", "ACCURACY_GAP", "SCENARIO_SOURCES", "SPREADS", "ROBOT_KEYS", "ROBOT_MODELS", "RUN_NAME",
    "ExperimentFile",
    "ExperimentTable", "MapTable", "InstanceTable", "FigureTable", "PaperTable", "PaperValueTable", "load_config",
    "parse_config", "read_config_text", "default_data_dir", "nav_config", "apply_quick", "applies", "read_maps",
    "scenario_bound",
]


# ---------------------------------------------------------------------------------------------
# Fixed vocabularies


@dataclass(frozen=True)
class Metric:
    """A metric a config may name.

    Attributes:
      name: column name in trials.csv / summary.csv.
      kinds: planner kinds it applies to (``"plan"``, ``"navigate"``).
      unit: for tables ("" for counts and ratios).
      description: one line (docs/guide/smoothing-and-metrics.md).
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

DRAW_SEP = "~"
"""Separates a generated map's name from its draw index in the name of draw d > 0 (``warehouse20m~3``)."""

ACCURACY_GAP = 0.10
"""cui2025's "accuracy" (docs/guide/smoothing-and-metrics.md): the share of trials that succeed with an optimality gap
<= this."""

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
    Metric("objective_gap", _P, "", "the planner's own cost of its path / the exact minimum of that cost - 1 "
                                    "(jaxplan.search.exact_objective; nan for planners whose cost is no sum over "
                                    "moves and turns)", default=False),
    Metric("turns", _P, "", "path vertices with a heading change"),
    Metric("sharp_turns", _P, "", "heading changes >= 45 deg"),
    Metric("los_length", _P, "m", "path length after line-of-sight smoothing (yu2020 sec. 3.3, smoother 'los')",
           default=False),
    Metric("los_turns", _P, "", "turns after line-of-sight smoothing", default=False),
    Metric("los_length_reduction", _P, "", "1 - los_length / length (yu2020 Table 4)", default=False),
    Metric("los_turns_reduction", _P, "", "1 - los_turns / turns (nan for a straight path)", default=False),
    Metric("smoothness", _B, "", "1 - mean |heading change| / pi over the path's vertices (navigate: the executed "
           "path resampled every cell length)"),
    Metric("min_clearance", _P, "m", "smallest vertex clearance"),
    Metric("mean_clearance", _B, "m", "mean vertex clearance (navigate: of the executed path resampled every cell "
           "length; cui2025 Table 1's average obstacle distance)"),
    Metric("max_curvature", _B, "1/m", "plan: Menger curvature at path vertices; navigate: executed |omega|/v"),
    Metric("hausdorff", _B, "m", "Hausdorff distance of the global path to the exact A* path (cui2025 Fig. 9)"),
    Metric("cost", _P, "", "the planner's own objective"),
    Metric("converged_iteration", _PT, "", "first iteration (0-based) whose best cost (tsp: tour length) is within "
                                           "1 % of the run's final best: the general definition"),
    Metric("converged_iteration_strict", _PT, "", "as converged_iteration within 0.1 % of the final best: the "
                                                  "sensitivity row of the convergence iteration", default=False),
    Metric("turning_point", _PT, "", "chu2024's iterative stabilization: the iteration (counted from 1) from which "
                                     "the best cost stays at its final value", default=False),
    Metric("optimum_iteration", _PT, "", "yu2020's number of iterations: the generation (counted from 1) in which "
                                         "the run's final best is first found", default=False),
    Metric("collisions", _N, "", "contacts with the map or moving discs (a team: with other robots too, summed "
                                 "over its robots)"),
    Metric("arrived", _N, "", "share of the robots at their goals without collision in time (one robot: success; "
                              "a team: its robots that succeeded / robots)", default=False),
    Metric("robot_contacts", _N, "", "robot-robot contacts of a team, each pair's contact once (0 for one robot)",
           default=False),
    Metric("active_contacts", _N, "", "contacts begun while the robot moved faster than 0.05 m/s", default=False),
    Metric("passive_contacts", _N, "", "contacts begun with the robot at rest", default=False),
    Metric("time_s", _N, "s", "simulated time to the goal", given_success=True),
    Metric("rmse", _N, "m", "RMS distance of executed positions to the tracked path"),
    Metric("energy", _N, "J", "energy proxy (docs/guide/smoothing-and-metrics.md)"),
    Metric("path_length", _N, "m", "executed path length"),
    Metric("recoveries", _N, "", "control steps with no feasible DWA sample"),
    Metric("replans", _N, "", "in-episode re-plans"),
    Metric("plan_time_s", _B | _T, "s", "global planning (tsp: solving) wall time per trial (chunk time / trials)",
           timing=True),
    Metric("step_time_s", _N, "s", "wall time per control step of one robot", timing=True),
)})
"""Every metric a config may name, in the column order of the outputs."""

FIGURE_KIND_NAMES = ("convergence", "box", "bar", "paths", "trajectories", "pheromone", "diversity", "fan", "controls",
                     "sweep", "tours")
_SCENARIO_FIGURE_PLANNERS: Mapping[str, tuple[str, ...]] = MappingProxyType({
    "convergence": ("plan", "tsp"), "diversity": ("plan", "tsp"), "paths": ("plan", "navigate"),
    "pheromone": ("plan",), "trajectories": ("navigate",), "controls": ("navigate",), "fan": ("navigate",),
})
"""Figure kinds with a ``scenario`` key -> the planner kinds they draw (as `figures` selects them)."""


def _generators() -> dict[str, tuple[Callable[..., Any], bool]]:
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
_FUNCTION_PARAMS = {"warehouse_chen2023": (), "warehouse_yu2020": ("size",), "demo_warehouse": (),
                    "warehouse_chen2023_risk": ("lam",)}

GENERATORS = ("warehouse", "random", "urban", "mountain", "warehouse_chen2023", "warehouse_yu2020", "demo_warehouse",
              "warehouse_chen2023_risk")
"""Generator names a map may use (the generators of `jaxplan.grid`)."""
DEPRECATED_GENERATORS: Mapping[str, str] = MappingProxyType({
    "warehouse_seed003": "warehouse_chen2023", "warehouse_seed004": "warehouse_yu2020",
    "warehouse_seed003_risk": "warehouse_chen2023_risk"})
"""Generator names of the previous release (papers by internal number) -> their new names; accepted with a
`DeprecationWarning` for one release."""
_FUNCTION_PARAMS = {"warehouse_chen2023": (), "warehouse_yu2020": ("size",), "demo_warehouse": (),
                    "warehouse_chen2023_risk": ("lam",)}

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
    from jaxplan.smooth import SMOOTHERS

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

    seeds: tuple[int, ...] | None = setting("seeds", None, "the seeds of the quick run: a count or a list")
    count: int | None = setting("int", None, "at most this many scenarios per map", ge=1)
    chunk: int | None = setting("int", None, "scenarios per compiled call", ge=1)
    overrides: Mapping[str, Any] = setting("table", doc="planner parameters, given to every planner that accepts "
                                           "the key")
    nav: Mapping[str, Any] = setting("table", doc="`NavConfig` fields for every navigate planner")
    planners: tuple[str, ...] | None = setting("strings", None, "only these planner labels run (CI time is "
                                               "compile time: each pipeline compiles once)", default_text="all")
    maps: tuple[str, ...] | None = setting("strings", None, "only these maps run", default_text="all")


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


def default_data_dir() -> Path:
    """``$JAXPLAN_DATA``, else ``shared/benchmarks`` beside the checkout (as the tests and benchmarks)."""
    env = os.environ.get("JAXPLAN_DATA")
    return Path(env) if env else Path(__file__).resolve().parents[3] / "shared" / "benchmarks"


# ---------------------------------------------------------------------------------------------
# Sections


def _read_experiment(r: Reader, raw: dict) -> dict:
    exp = r.section(raw.get("experiment"), "experiment", ExperimentTable, defaults={"name": "unnamed"})
    exp["quick_raw"] = r.section(exp.get("quick"), "experiment.quick", QuickSpec)
    return exp


def _read_scenarios(r: Reader, t: dict, path: str, is_file: bool) -> ScenarioSpec:
    spec = ScenarioSpec(**r.section(t, path, ScenarioSpec, defaults={"source": "scen" if is_file else "random"}))
    source = spec.source
    if source == "scen" and not is_file:
        r.bad(join(path, "source"), "a generated map has no scenario file; use 'random' or 'scene'")
    if source == "scene" and is_file:
        r.bad(join(path, "source"),
              "'scene' is a generator's own start and goal; a MovingAI map uses 'scen' or 'random'")
    if spec.min_bucket is not None and spec.max_bucket is not None and spec.min_bucket > spec.max_bucket:
        r.bad(path, f"min_bucket {spec.min_bucket} > max_bucket {spec.max_bucket}")
    if spec.min_optimal is not None and spec.max_optimal is not None and spec.min_optimal > spec.max_optimal:
        r.bad(path, f"min_optimal {spec.min_optimal} > max_optimal {spec.max_optimal}")
    if source != "scen":
        for k in ("min_bucket", "max_bucket", "spread"):
            if k in t:
                r.bad(join(path, k), f"only applies to source = 'scen', not {source!r}")
    if source != "random" and "min_clearance" in t:
        r.bad(join(path, "min_clearance"), f"only applies to source = 'random', not {source!r}")
    if source == "scene" and spec.count not in (None, 1):
        r.bad(join(path, "count"), "source = 'scene' gives exactly one scenario")
    return spec


def read_maps(r: Reader, raw: Mapping[str, Any], data_dir: Path, required: bool = True) -> tuple[MapSpec, ...]:
    """The ``[[maps]]`` entries of parsed config ``raw`` (with its ``[scenarios]``) as `MapSpec`s, problems
    reported to ``r``; relative paths resolved against ``data_dir``. Experiment and tuning configs share it."""
    entries = list(r.entries(raw, "maps", required=required))
    if not entries:
        return ()
    scen_keys = [s.name for s in settings(ScenarioSpec)]
    default_scen = raw.get("scenarios")
    if default_scen is not None and not isinstance(default_scen, dict):
        r.bad("scenarios", f"expected a table, got {describe(default_scen)}")
        default_scen = None
    r.table(default_scen, "scenarios", scen_keys)
    gens = _generators()
    from jaxplan.grid import is_ros_map

    out, names = [], {}
    for i, (p, m) in enumerate(entries):
        t = r.section(m, p, MapTable, skip=("name", "path", "scen", "generator", "params", "keepout", "speed_mask",
                                            "speed_filter"))
        if not isinstance(m, dict):
            continue
        has_path, has_gen = "path" in m, "generator" in m
        if has_path == has_gen:
            r.bad(p, "give exactly one of 'path' (a MovingAI .map) or 'generator'")
        resolution, seed = t["resolution"], t["seed"]
        if resolution is None and not (has_path and isinstance(m["path"], str) and is_ros_map(m["path"])):
            resolution = 1.0  # a MovingAI or generated map's default; a ROS map keeps its own (None)
        map_path = scen_path = gen = None
        params: dict = {}
        label = None
        if has_path:
            map_path = _data_file(r, m, p, setting_of(MapTable, "path"), data_dir, hint=True)
            for k in ("params", "seed"):
                if k in m:
                    r.bad(join(p, k), "only applies to a generated map")
            if map_path is not None:
                label = map_path.stem
            if "scen" in m:
                scen_path = _data_file(r, m, p, setting_of(MapTable, "scen"), data_dir)
            elif map_path is not None:
                for cand in (Path(str(map_path) + ".scen"), map_path.with_name(map_path.stem + "-random-1.scen")):
                    if cand.is_file():
                        scen_path = cand
                        break
        elif has_gen:
            if "scen" in m:
                r.bad(join(p, "scen"), "only applies to a MovingAI map")
            gen = r.value(m, p, setting_of(MapTable, "generator"))
            params = r.value(m, p, setting_of(MapTable, "params"))
            if gen is not None:
                label = gen
                _check_generator(r, join(p, "params"), gen, gens[gen], params, resolution)
        name = r.value(m, p, setting_of(MapTable, "name"), label or f"map{i}")
        if name in names:
            r.bad(join(p, "name"), f"duplicate map name {name!r} (also maps[{names[name]}]); give each a unique name")
        names.setdefault(name, i)
        own = m.get("scenarios")
        merged = {**(default_scen or {}), **(own if isinstance(own, dict) else {})}
        if "scenarios" in m:
            r.table(own, join(p, "scenarios"), scen_keys)
        scen_p = join(p, "scenarios") if "scenarios" in m else "scenarios"
        spec = _read_scenarios(r, {k: v for k, v in merged.items() if k in scen_keys}, scen_p, has_path)
        if has_path and spec.source == "scen" and scen_path is None and map_path is not None and map_path.is_file():
            r.bad(join(p, "scen"), f"no scenario file for {map_path.name} (looked for {map_path.name}.scen and "
                                   f"{map_path.stem}-random-1.scen); give 'scen' or use source = 'random'")
        ros = _read_ros_options(r, m, p, t, data_dir, has_path and map_path is not None and is_ros_map(map_path))
        draws, paper_map = t["draws"], bool(t["paper_map"])
        if draws and draws > 1 and not has_gen:
            r.bad(join(p, "draws"), "only a generated map has draws (a file is one map)")
            draws = 1
        if paper_map and has_gen:
            r.bad(join(p, "paper_map"), "a generated map is never the paper's own map (it stands in for one)")
        for d in range(draws or 1):
            site = name if d == 0 else f"{name}{DRAW_SEP}{d}"
            if d and site in names:
                r.bad(join(p, "name"), f"draw {d} of map {name!r} would be named {site!r}, which is taken")
            if d:
                names.setdefault(site, i)
            out.append(MapSpec(site, map_path, scen_path, gen, frozen(params), seed + d, resolution, spec, key=p,
                               ros=frozen(ros), family=name if (draws or 1) > 1 else "", draw=d,
                               paper_map=paper_map))
    return tuple(out)


def _read_instances(r: Reader, raw: dict, data_dir: Path, taken: set[str]) -> tuple[MapSpec, ...]:
    """``[[instances]]``: TSPLIB files (and their optimal tours) for the tsp planners; names unique with ``taken``."""
    out, names = [], {}
    for i, (p, e) in enumerate(r.entries(raw, "instances")):
        t = r.section(e, p, InstanceTable, skip=("name", "path", "tour"))
        if not isinstance(e, dict):
            continue
        tsp = _data_file(r, e, p, setting_of(InstanceTable, "path"), data_dir, hint=True)
        tour = None
        optimum = t["optimum"]
        if "tour" in e:
            tour = _data_file(r, e, p, setting_of(InstanceTable, "tour"), data_dir)
            if "optimum" in e:
                r.bad(p, "give 'tour' (the optimal tour file) or 'optimum' (its length), not both")
        elif tsp is not None and optimum is None:
            cand = tsp.with_name(tsp.stem + ".opt.tour")  # TSPLIB's own naming of the optimal tours
            tour = cand if cand.is_file() else None
        name = r.value(e, p, setting_of(InstanceTable, "name"), tsp.stem if tsp is not None else f"instance{i}")
        if name in taken or name in names:
            r.bad(join(p, "name"), f"duplicate name {name!r}: maps and instances share one namespace (tables, "
                                   "figures); give each a unique name")
        names.setdefault(name, i)
        out.append(MapSpec(name, None, None, None, frozen({}), 0, 1.0, ScenarioSpec(source="scene"), tsplib=tsp,
                           tour=tour, optimum=optimum, key=p))
    return tuple(out)


def _resolve(data_dir: Path, rel: str) -> Path:
    p = Path(rel).expanduser()
    return p if p.is_absolute() else (data_dir / p)


_ROS_KEYS = ("keepout", "speed_mask", "speed_filter", "top_speed", "unknown")


def _read_ros_options(r: Reader, m: dict, p: str, t: Mapping[str, Any], data_dir: Path, is_ros: bool) -> dict:
    """A ROS map entry's mask options as `load_ros_map` keywords; any of them on another map is a problem."""
    given = [k for k in _ROS_KEYS if k in m]
    if not is_ros:
        for k in given:
            r.bad(join(p, k), "only applies to a ROS map_server map (a .yaml path)")
        return {}
    out: dict[str, Any] = {}
    for key, kw in (("keepout", "keepout"), ("speed_mask", "speed")):
        f = _data_file(r, m, p, setting_of(MapTable, key), data_dir)
        if f is not None:
            out[kw] = f
    if t["unknown"] is not None:
        out["unknown"] = t["unknown"]
    if "speed_filter" in m:
        f = m["speed_filter"]
        ok = (isinstance(f, list) and len(f) == 3 and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                          and math.isfinite(v) for v in f) and f[0] in (1, 2))
        if not ok:
            r.bad(join(p, "speed_filter"), f"expected [type, base, multiplier] with type 1 (percent) or 2 (m/s) and "
                                           f"finite numbers, got {describe(f)}")
        else:
            out["speed_filter"] = (int(f[0]), float(f[1]), float(f[2]))
    if t["top_speed"] is not None:
        out["top_speed"] = t["top_speed"]
    if "speed" not in out:
        for k in ("speed_filter", "top_speed"):
            if k in m:
                r.bad(join(p, k), "only applies with a speed_mask")
    elif out.get("speed_filter", (1,))[0] == 2 and "top_speed" not in out:
        r.bad(join(p, "top_speed"), "a type 2 speed mask gives metres per second: give the robot's top speed")
    return out


def _data_file(r: Reader, t: dict, p: str, s: Setting, data_dir: Path, hint: bool = False) -> Path | None:
    """``t[s.name]`` resolved against the data folder (None when absent); a missing file is reported at
    ``p.key``, with the data folder and how to set it when ``hint``."""
    rel = r.value(t, p, s)
    if rel is None:
        return None
    f = _resolve(data_dir, rel)
    if not f.is_file():
        more = f" (data dir {data_dir}; set --data-dir or JAXPLAN_DATA)" if hint else ""
        r.bad(join(p, s.name), f"file not found: {f}{more}")
    return f


def _check_generator(r: Reader, path: str, name: str, entry: tuple, params: dict, resolution: float) -> None:
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
            r.bad(join(path, k), f"generator {name!r} has no parameter {k!r} (accepts: {', '.join(known) or 'none'})"
                                 + did_you_mean(k, list(known)))
    if "resolution" in params:
        r.bad(join(path, "resolution"), "give the resolution as the map's own 'resolution' key")
    if not ok or not is_dc:
        if name == "warehouse_yu2020" and params.get("size", 30) not in (30, 35):
            r.bad(join(path, "size"), f"must be 30 or 35, got {params.get('size')!r}")
        return
    try:
        fixed = {k: tuple(v) if isinstance(v, list) else v for k, v in params.items()}
        factory(**fixed, resolution=resolution)
    except (TypeError, ValueError) as e:
        r.bad(path, f"generator {name!r}: {e}")


_NAVIGATE_ONLY = ("nav", "dwa", "robot", "params", "obstacles", "team")
_TEAM_REFUSED = ("hausdorff", "accuracy", "smoothness", "mean_clearance")
"""Metrics of one robot's global path against the scenario's exact path: a team trial has N paths, so none."""


def _read_planners(r: Reader, raw: dict) -> tuple[PlannerConfig, ...]:
    from jaxplan.nav import pipelines
    from jaxplan.planning import planners
    from jaxplan.registry import resolve

    entries = list(r.entries(raw, "planners", required=True))
    if not entries:
        return ()
    registry, pipes = planners(), pipelines()
    out, labels = [], {}
    for i, (p, e) in enumerate(entries):
        t = r.section(e, p, PlannerConfig, skip=("label",) + _NAVIGATE_ONLY)
        if not isinstance(e, dict):
            continue
        kind, name, overrides = t["kind"], t["name"], t["overrides"]
        global_name = None
        if kind in ("plan", "tsp"):
            for k in _NAVIGATE_ONLY:
                if k in e:
                    r.bad(join(p, k), "only applies to kind = 'navigate'")
        if kind == "tsp" and name is not None:
            _check_tsp(r, p, name, overrides)
        elif kind == "plan" and name is not None:
            if name not in registry:
                r.bad(join(p, "name"), f"unknown planner {name!r} (known: {', '.join(sorted(registry))})"
                      + did_you_mean(name, list(registry)))
            else:
                global_name = name
        elif kind == "navigate" and name is not None:
            if name not in pipes:
                r.bad(join(p, "name"), f"unknown pipeline {name!r} (known: {', '.join(sorted(pipes))})"
                      + did_you_mean(name, list(pipes)))
            else:
                global_name = pipes[name].global_planner
        if global_name is not None:
            _check_overrides(r, join(p, "overrides"), global_name, overrides, resolve,
                             dict(pipes[name].planner_overrides) if kind == "navigate" else {})
        label = r.value(e, p, setting_of(PlannerConfig, "label"), name or f"planner{i}")
        if label in labels:
            r.bad(join(p, "label"), f"duplicate label {label!r} (also planners[{labels[label]}]); labels name the "
                                    "table columns, give each a unique one")
        labels.setdefault(label, i)
        nav = dwa = robot = params = mppi = {}
        obstacles = team = None
        if kind == "navigate":
            nav, dwa, robot, params, mppi = (r.value(e, p, setting_of(PlannerConfig, k))
                                             for k in ("nav", "dwa", "robot", "params", "mppi"))
            if "obstacles" in e:
                obstacles = ObstacleSpec(**r.section(e["obstacles"], join(p, "obstacles"), ObstacleSpec))
            if "team" in e:
                t_team = r.section(e["team"], join(p, "team"), TeamSpec)
                team = TeamSpec(**t_team) if t_team.get("robots") is not None else None
            _check_robot(r, join(p, "robot"), robot)
            if name in pipes:
                _check_nav(r, p, name, nav, dwa, robot, params, mppi)
                if team is not None:
                    _check_team(r, join(p, "team"), name, nav, dwa, robot, params, mppi, team)
        out.append(PlannerConfig(label, kind or "plan", name or "", frozen(overrides), frozen(nav), frozen(dwa),
                                 frozen(robot), frozen(params), obstacles, frozen(mppi), team))
    return tuple(out)


def _check_tsp(r: Reader, p: str, name: str, overrides: dict) -> None:
    """A tsp planner: its name, then unknown override names one by one, then `solve_tsp`'s own value checks."""
    from jaxplan.aco import TSP_PLANNERS, tsp_defaults
    from jaxplan.aco import resolve_tsp as tsp_resolve

    if name not in TSP_PLANNERS:
        r.bad(join(p, "name"), f"unknown TSP planner {name!r} (known: {', '.join(TSP_PLANNERS)})"
              + did_you_mean(name, list(TSP_PLANNERS)))
        return
    accepted = list(tsp_defaults(name))
    unknown = [k for k in overrides if k not in accepted]
    for k in unknown:
        r.bad(join(p, f"overrides.{k}"), f"TSP planner {name!r} has no parameter {k!r} (accepts: "
                                         f"{', '.join(sorted(accepted))})" + did_you_mean(k, accepted))
    if not unknown:
        try:
            tsp_resolve(name, {k: _tuple(v) for k, v in overrides.items()})
        except (ValueError, TypeError) as e:
            r.bad(join(p, "overrides"), str(e))


def _check_sites(r: Reader, maps: tuple[MapSpec, ...], planners: tuple[PlannerConfig, ...]) -> None:
    """Every map and instance has a planner that runs on it, and every planner a map or instance."""
    for m in maps:
        if planners and not any(applies(pc, m) for pc in planners):
            what = "kind = 'tsp' planner" if m.is_tsp else "plan or navigate planner"
            r.bad(m.key, f"no {what} is configured to run on {m.name!r}")
    for i, pc in enumerate(planners):
        if maps and not any(applies(pc, m) for m in maps):
            r.bad(f"planners[{i}].kind", "a kind = 'tsp' planner runs on [[instances]] entries, and there is none"
                  if pc.kind == "tsp" else f"a kind = {pc.kind!r} planner runs on [[maps]] entries, and there is none")


def _check_overrides(r: Reader, path: str, planner: str, overrides: dict, resolve, base: dict) -> None:
    """Unknown names one by one (with a close match), then the planner's own value checks."""
    from jaxplan.planning import planners

    accepted = list(planners()[planner].defaults)
    unknown = [k for k in overrides if k not in accepted]
    for k in unknown:
        r.bad(join(path, k), f"planner {planner!r} has no parameter {k!r} (accepts: {', '.join(sorted(accepted))})"
              + did_you_mean(k, accepted))
    if unknown:
        return
    try:
        resolve(planner, {**base, **{k: _tuple(v) for k, v in overrides.items()}})
    except (ValueError, TypeError) as e:
        r.bad(path, str(e))


def _tuple(v: Any) -> Any:
    return tuple(v) if isinstance(v, list) else v


def _check_robot(r: Reader, path: str, robot: Mapping) -> None:
    """``robot.model`` is a known model, and only an Ackermann robot has a wheelbase and a steering limit."""
    model = robot.get("model", "unicycle")
    if model not in ROBOT_MODELS:
        r.bad(join(path, "model"), f"unknown robot model {model!r} (known: {', '.join(ROBOT_MODELS)})"
              + did_you_mean(str(model), list(ROBOT_MODELS)))
    elif model != "ackermann":
        for k in ("wheelbase", "steer_max"):
            if k in robot:
                r.bad(join(path, k), f"only applies to model = 'ackermann' (this robot is a {model!r})")


def _check_team(r: Reader, path: str, pipeline: str, nav: Mapping, dwa: Mapping, robot: Mapping, params: Mapping,
                mppi: Mapping, team: TeamSpec) -> None:
    """A team's spacing keeps teammates apart by more than two footprint radii (`jaxplan.navigate_multi` refuses
    robots overlapping at their starts or sharing a goal)."""
    from jaxplan.dwa import footprint_radius

    if _nav_problem(pipeline, nav, dwa, robot, params, mppi) is not None:
        return  # reported by _check_nav
    probe = PlannerConfig("probe", "navigate", pipeline, robot=frozen(dict(robot)), dwa=frozen(dict(dwa)),
                          nav=frozen(dict(nav)))
    rad = float(footprint_radius(nav_config(probe)[0].dwa.robot.footprint))
    if team.spacing <= 2 * rad:
        r.bad(join(path, "spacing"), f"{team.spacing:g} m does not keep teammates apart: it must exceed two footprint "
                                     f"radii ({2 * rad:.4g} m)")


def nav_config(planner: PlannerConfig):
    """The `NavConfig` and DWA params mapping of a navigate planner (raises ValueError/TypeError on bad values).

    ``robot.model = "ackermann"`` starts from `jaxplan.dwa.Ackermann`'s defaults (li2026's car-like robot, its
    rectangular footprint) instead of the `NavConfig` default `Unicycle`; the other ``robot`` keys replace fields."""
    from jaxplan.dwa import Ackermann, Disc
    from jaxplan.nav import NavConfig

    base = NavConfig()
    robot_kw = dict(planner.robot)
    radius = robot_kw.pop("radius", None)
    model = robot_kw.pop("model", "unicycle")
    if model not in ROBOT_MODELS:
        raise ValueError(f"unknown robot model {model!r} (known: {', '.join(ROBOT_MODELS)})")
    robot = Ackermann() if model == "ackermann" else base.dwa.robot
    if robot_kw or radius is not None:
        changes = dict(robot_kw)
        if radius is not None:
            changes["footprint"] = Disc(float(radius))
        robot = dataclasses.replace(robot, **changes)
    dwa = base.dwa.replace(robot=robot, **dict(planner.dwa))
    mppi = base.mppi.replace(**dict(planner.mppi))
    return base.replace(dwa=dwa, mppi=mppi, **dict(planner.nav)), dict(planner.params)


def _check_nav(r: Reader, p: str, pipeline: str, nav: Mapping, dwa: Mapping, robot: Mapping,
               params: Mapping, mppi: Mapping | None = None) -> None:
    problem = _nav_problem(pipeline, nav, dwa, robot, params, mppi or {})
    if problem is not None:
        r.bad(p, f"navigation settings: {problem}")


def _nav_problem(pipeline: str, nav: Mapping, dwa: Mapping, robot: Mapping, params: Mapping,
                 mppi: Mapping | None = None) -> str | None:
    """Why pipeline ``pipeline`` would refuse these settings, or None."""
    from jaxplan.dwa import validate_params
    from jaxplan.mppi import validate_params as validate_mppi_params
    from jaxplan.nav import get_pipeline, resolve_config

    probe = PlannerConfig("probe", "navigate", pipeline, overrides=frozen({}), nav=frozen(dict(nav)),
                          dwa=frozen(dict(dwa)), robot=frozen(dict(robot)), params=frozen(dict(params)),
                          mppi=frozen(dict(mppi or {})))
    try:
        cfg, weights = nav_config(probe)
        cfg = resolve_config(cfg, get_pipeline(pipeline), None)
        if cfg.local == "mppi":
            validate_mppi_params(weights or None)
        else:
            validate_params(weights or None, cfg.dwa.evaluator)
    except (ValueError, TypeError) as e:
        return str(e)
    return None


def _check_team_metrics(r: Reader, planners: tuple[PlannerConfig, ...], metrics: tuple[str, ...]) -> None:
    """A team planner has no single global path to compare with the scenario's exact one."""
    refused = [m for m in metrics if m in _TEAM_REFUSED]
    for i, pc in enumerate(planners):
        if pc.team is not None and refused:
            r.bad(f"planners[{i}].team", f"metrics {', '.join(map(repr, refused))} compare one robot's path with the "
                                         "scenario's exact path and are not defined for a team: drop them")


def _read_metrics(r: Reader, raw: dict, kinds: frozenset) -> tuple[str, ...]:
    if "metrics" not in raw:
        return tuple(m for m, spec in METRICS.items() if spec.kinds & kinds and spec.default)
    v = raw["metrics"]
    if not isinstance(v, list) or not v:
        r.bad("metrics", f"expected a non-empty list of metric names, got {describe(v)}")
        return ()
    seen = set()
    for i, m in enumerate(v):
        p = f"metrics[{i}]"
        if not isinstance(m, str):
            r.bad(p, f"expected a metric name, got {describe(m)}")
        elif m not in METRICS:
            r.bad(p, f"unknown metric {m!r}" + did_you_mean(m, list(METRICS)) + f" (known: {', '.join(METRICS)})")
        elif m in seen:
            r.bad(p, f"metric {m!r} is listed twice")
        elif kinds and not (METRICS[m].kinds & kinds):
            r.bad(p, f"metric {m!r} applies to kind {'/'.join(sorted(METRICS[m].kinds))} planners, and the config "
                     f"has only {'/'.join(sorted(kinds))} ones")
        seen.add(m)
    return tuple(m for m in METRICS if m in seen)


def _read_stats(r: Reader, raw: dict, metrics: tuple[str, ...]) -> StatsSpec:
    t = r.section(raw.get("stats"), "stats", StatsSpec, defaults={"anova": "stats" in raw, "metrics": None})
    chosen = t["metrics"]
    if chosen is None:
        chosen = [m for m in metrics if not METRICS[m].timing]
    else:
        for i, m in enumerate(chosen):
            if m not in metrics:
                r.bad(f"stats.metrics[{i}]", f"{m!r} is not one of the configured metrics ({', '.join(metrics)})")
            elif METRICS[m].timing:
                r.bad(f"stats.metrics[{i}]", f"{m!r} is a wall-clock time, measured per chunk: no per-seed values "
                                             "to test")
    return StatsSpec(**{**t, "metrics": tuple(chosen)})


def scenario_bound(spec: MapSpec) -> int | None:
    """How many scenarios ``spec`` has at most, when the config alone tells (None: only the data does)."""
    sc = spec.scenarios
    if spec.is_tsp or sc.source == "scene":
        return 1
    if sc.source == "random":
        return sc.count or 10  # `runner._random_pairs` finds exactly this many or fails
    return sc.count  # scen rows: count is an upper bound; the filters may keep fewer


def _check_figure_scenario(r: Reader, p: str, name: str | None, kind: str | None, t: dict,
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
            r.bad(join(p, "scenario"), f"figure {name!r}: scenario {sc} is past map {m.name!r}'s {n} scenario"
                                        f"{'s' if n > 1 else ''} (0..{n - 1})")
            return


def _read_figures(r: Reader, raw: dict, metrics: tuple, maps: set, labels: set,
                  sites: Sequence[MapSpec] = (), planners: Sequence[PlannerConfig] = ()) -> tuple[FigureSpec, ...]:
    out, names = [], set()
    for p, f in r.entries(raw, "figures", nonempty=False):
        t = r.section(f, p, FigureTable)
        if not isinstance(f, dict):
            continue
        kind, name = t["kind"], t["name"]
        if name is None and kind:
            name, k = kind, 2
            while name in names:
                name, k = f"{kind}_{k}", k + 1
        if name in names:
            r.bad(join(p, "name"), f"duplicate figure name {name!r}")
        names.add(name)
        if t["metric"] is not None and t["metric"] not in metrics:
            r.bad(join(p, "metric"), f"{t['metric']!r} is not one of the configured metrics ({', '.join(metrics)})")
        for key, known in (("maps", maps), ("planners", labels)):
            for j, x in enumerate(t[key] or []):
                if x not in known:
                    r.bad(f"{p}.{key}[{j}]", f"unknown {key[:-1]} {x!r} (configured: {', '.join(sorted(known))})")
        _check_figure_scenario(r, p, name, kind, f, sites, planners)
        if "band" in t and not (t["band"] is False or (isinstance(t["band"], str) and t["band"] in BANDS)):
            r.bad(join(p, "band"), f"must be {', '.join(map(repr, BANDS))} or false, got {t['band']!r}")
        if kind == "sweep" and "metric" not in f:
            r.bad(join(p, "metric"), "required key is missing")
        if "steps" in t and not (isinstance(t["steps"], list) and t["steps"]
                                 and all(isinstance(v, int) and not isinstance(v, bool) and v >= 0
                                         for v in t["steps"])):
            r.bad(join(p, "steps"), f"expected a non-empty list of control steps >= 0, got {describe(t['steps'])}")
        if kind == "sweep":
            x = t.get("x")
            if isinstance(x, list):
                n_maps = len(t["maps"] or maps)
                if len(x) != n_maps or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in x):
                    r.bad(join(p, "x"), f"expected {n_maps} numbers (one per map) or a generator parameter name")
            elif not isinstance(x, str):
                r.bad(join(p, "x"), "required: a generator parameter name or one number per map")
        if kind:
            out.append(FigureSpec(kind, name, frozen({k: v for k, v in f.items() if k not in ("kind", "name")})))
    return tuple(out)


def _read_paper(r: Reader, raw: dict, metrics: tuple, maps: set, labels: set) -> tuple[str, tuple[PaperValue, ...]]:
    t = r.section(raw.get("paper"), "paper", PaperTable)
    source = t["source"]
    vals = list(r.entries(t, "values", "paper", nonempty=False))
    if vals and not source:
        r.bad("paper.source", "say where the paper's numbers come from (e.g. 'cui2025, Table 2')")
    out, seen = [], set()
    for p, v in vals:
        planner_map = r.section(v, p, PaperValueTable)
        if not isinstance(v, dict):
            continue
        planner, mp, n_runs = planner_map["planner"], planner_map["map"], planner_map["n"]
        if n_runs is None:
            n_runs = t["n"]
        if planner is not None and planner not in labels:
            r.bad(join(p, "planner"), f"unknown planner label {planner!r} (configured: {', '.join(sorted(labels))})"
                  + did_you_mean(planner, list(labels)))
        if mp is not None and mp not in maps:
            r.bad(join(p, "map"), f"unknown map {mp!r} (configured: {', '.join(sorted(maps))})")
        for k, x in v.items():
            if k in planner_map:
                continue
            kp = join(p, k)
            if k not in METRICS:
                r.bad(kp, f"unknown metric {k!r}" + did_you_mean(k, list(METRICS)))
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
                r.bad(kp, f"expected a number, [mean, sd] or {{ mean = , sd = , min = , max = }}, got {describe(x)}")
                continue
            if not all(math.isfinite(y) for y in (mean, lo, hi) if y is not None) or (
                    sd is not None and not (math.isfinite(sd) and sd >= 0)):
                r.bad(kp, f"mean, min and max must be finite and sd finite and >= 0, got {x!r}")
                continue
            key = (planner, mp, k)
            if key in seen:
                r.bad(kp, f"a second paper value for planner {planner!r}, map {mp!r}, metric {k!r}")
            seen.add(key)
            out.append(PaperValue(planner, mp, k, mean, sd, lo, hi, n_runs))
    return source, tuple(out)


def _read_quick(r: Reader, q: dict, planners: tuple[PlannerConfig, ...], map_names: list[str] | None = None
                ) -> QuickSpec:
    """Quick overrides: each key must be accepted by at least one planner, and valid for each that accepts it."""
    from jaxplan.aco import resolve_tsp as tsp_resolve
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
                r.bad(f"experiment.quick.nav.{k}", "unknown NavConfig field" + did_you_mean(k, list(fields)))
        if all(k in fields for k in q["nav"]):
            _check_quick_nav(r, q["nav"], navs)
    labels, names = [pc.label for pc in planners], map_names
    for key, known in (("planners", labels), ("maps", names)):
        for j, x in enumerate(q.get(key) or []):
            if known is not None and x not in known:
                r.bad(f"experiment.quick.{key}[{j}]", f"unknown {key[:-1]} {x!r} (configured: {', '.join(known)})")
    return QuickSpec(q["seeds"], q["count"], q["chunk"], frozen(q["overrides"]), frozen(q["nav"]),
                     tuple(q["planners"]) if q.get("planners") else None, tuple(q["maps"]) if q.get("maps") else None)


def _overrides_ok(pc: PlannerConfig, overrides: Mapping) -> bool:
    """Whether planner ``pc`` accepts ``overrides`` (its own, without the quick ones)."""
    from jaxplan.aco import resolve_tsp as tsp_resolve
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


def _check_quick_nav(r: Reader, quick_nav: Mapping, navs: Sequence[PlannerConfig]) -> None:
    """The quick nav values merged into each navigate planner's own, checked as `_check_nav` checks those: else a
    bad value surfaces only mid-run, after a chunk is committed, under no config key."""
    from jaxplan.nav import pipelines

    for pc in navs:
        if pc.name not in pipelines():
            continue  # reported at its planners[i].name
        own = (pc.nav, pc.dwa, pc.robot, pc.params, pc.mppi)
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
    from jaxplan.aco import TSP_PLANNERS, tsp_defaults
    from jaxplan.planning import planners

    if pc.kind == "tsp":
        return tuple(tsp_defaults(pc.name)) if pc.name in TSP_PLANNERS else ()
    registry = planners()
    g = _global(pc)
    return tuple(registry[g].defaults) if g in registry else ()


def _global(pc: PlannerConfig) -> str | None:
    from jaxplan.nav import pipelines

    if pc.kind in ("plan", "tsp"):
        return pc.name
    p = pipelines().get(pc.name)
    return p.global_planner if p else None


# ---------------------------------------------------------------------------------------------
# Entry points


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
    r = Reader()
    r.section(raw, "", ExperimentFile, skip=("metrics",))
    exp = _read_experiment(r, raw)
    maps = read_maps(r, raw, ddir, required="instances" not in raw)
    maps = maps + _read_instances(r, raw, ddir, {m.name for m in maps})
    planners = _read_planners(r, raw)
    _check_sites(r, maps, planners)
    kinds = frozenset(p.kind for p in planners if p.kind)
    metrics = _read_metrics(r, raw, kinds)
    _check_team_metrics(r, planners, metrics)
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
    """Reads and validates the TOML config at ``path`` (schema: `ExperimentFile`, docs/guide/config.md).

    Raises:
      FileNotFoundError: no such file.
      ConfigError: listing every problem of the config, each with its key path.
    """
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"config file not found: {p}")
    return parse_config(read_config_text(p), data_dir=data_dir, source=str(p), path=p.resolve())


def read_config_text(p: Path) -> str:
    """The UTF-8 text of config file ``p``; a file that is not text is a `ConfigError` that quotes none of it."""
    try:
        return p.read_bytes().decode("utf-8")
    except UnicodeDecodeError as e:
        raise ConfigError([f"not a TOML config: not UTF-8 text (undecodable byte at offset {e.start})"],
                          str(p)) from None


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
        planners.append(dataclasses.replace(pc, overrides=frozen({**dict(pc.overrides), **extra}), nav=frozen(nav)))
    if q.planners:
        planners = [pc for pc in planners if pc.label in q.planners]
    if q.maps:
        maps = tuple(m for m in maps if m.name in q.maps)
    maps = tuple(m for m in maps if m.draw == 0)  # a smoke run checks the pipeline, not the map-to-map variance
    return cfg.replace(seeds=q.seeds or cfg.seeds, chunk=q.chunk or cfg.chunk, maps=maps, planners=tuple(planners),
                       is_quick=True)
