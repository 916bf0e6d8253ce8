"""Experiment configs: TOML files read with `tomllib` into frozen dataclasses, checked in full before any work.

A config names maps, scenarios, planners, seeds, metrics, statistics, figures and the paper's reported
numbers. `load_config` reads and validates it; every problem is collected with its key path and one
`ConfigError` lists them all, so a typo found at the 20th planner does not cost an overnight run a restart
per mistake. `apply_quick` turns it into its ``--quick`` smoke run.

Three modules share the work, and this one re-exports the public names of the other two:

* `jaxplan.experiments.config_schema`: the schema, declared once (each key a
  `jaxplan.experiments.schema.setting` on a dataclass field: its type, default, bounds or choices and one-line
  doc), and the resolved dataclasses (`ExperimentConfig`, `MapSpec`, `PlannerConfig`, ...);
* `jaxplan.experiments.config_checks`: the checks that need more than one key, a registry or a planner;
* this module: the readers of each table and the entry points (`parse_config`, `load_config`, `apply_quick`).

The metrics a config may name are `jaxplan.experiments.metric_catalogue.METRICS`. The reference page
``docs/guide/config.md`` and the editors' JSON Schema ``configs/schema/experiment.schema.json`` are generated from
the schema (``python -m jaxplan.config_reference``); ``configs/`` holds complete examples.

Planner kinds run where they apply: ``plan`` and ``navigate`` planners on every ``[[maps]]`` entry,
``tsp`` planners on every ``[[instances]]`` entry (`applies`); a map or instance that no configured
planner applies to is an error.

Paths are absolute after loading; `ExperimentConfig.text` keeps the file's bytes for the run folder's copy. TSP
instances are `MapSpec` entries too (``tsplib`` set), after the maps in ``ExperimentConfig.maps``: tables,
figures and quick filters name them like maps.
"""

from __future__ import annotations

import math
import os
import tomllib
from pathlib import Path
from typing import Any, Mapping, Sequence

from jaxplan.experiments.config_checks import (
    accepted_overrides,
    check_figure_scenario,
    check_generator,
    check_nav,
    check_overrides,
    check_quick_nav,
    check_quick_overrides,
    check_robot,
    check_sites,
    check_team,
    check_team_metrics,
    check_tsp,
    nav_config,
    scenario_bound,
)
from jaxplan.experiments.config_schema import (
    BANDS,
    DEPRECATED_GENERATORS,
    DRAW_SEP,
    FIGURE_KINDS,
    GENERATORS,
    KINDS,
    ROBOT_KEYS,
    ROBOT_MODELS,
    RUN_NAME,
    SCENARIO_SOURCES,
    SPREADS,
    ExperimentConfig,
    ExperimentFile,
    ExperimentTable,
    FigureSpec,
    FigureTable,
    InstanceTable,
    MapSpec,
    MapTable,
    ObstacleSpec,
    PaperTable,
    PaperValue,
    PaperValueTable,
    PlannerConfig,
    QuickSpec,
    ScenarioSpec,
    StatsSpec,
    TeamSpec,
    applies,
    map_generators,
)
from jaxplan.experiments.metric_catalogue import ACCURACY_GAP, METRICS, Metric
from jaxplan.experiments.schema import (
    ConfigError,
    Reader,
    Setting,
    describe,
    did_you_mean,
    frozen,
    join,
    overlay,
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

_generators = map_generators  # the name jaxplan.experiments.prepare imports


def default_data_dir() -> Path:
    """``$JAXPLAN_DATA``, else ``shared/benchmarks`` beside the checkout (as the tests and benchmarks)."""
    env = os.environ.get("JAXPLAN_DATA")
    return Path(env) if env else Path(__file__).resolve().parents[3] / "shared" / "benchmarks"


# ---------------------------------------------------------------------------------------------
# Tables


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
                check_generator(r, join(p, "params"), gen, gens[gen], params, resolution)
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


_NAVIGATE_ONLY = ("nav", "dwa", "robot", "params", "obstacles", "team")


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
            check_tsp(r, p, name, overrides)
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
            check_overrides(r, join(p, "overrides"), global_name, overrides, resolve,
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
            check_robot(r, join(p, "robot"), robot)
            if name in pipes:
                check_nav(r, p, name, nav, dwa, robot, params, mppi)
                if team is not None:
                    check_team(r, join(p, "team"), name, nav, dwa, robot, params, mppi, team)
        out.append(PlannerConfig(label, kind or "plan", name or "", frozen(overrides), frozen(nav), frozen(dwa),
                                 frozen(robot), frozen(params), obstacles, frozen(mppi), team))
    return tuple(out)


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
        check_figure_scenario(r, p, name, kind, f, sites, planners)
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
    """The ``[experiment.quick]`` table: its overrides and nav settings against the planners they reach, its planner
    labels and map names against the configured ones."""
    check_quick_overrides(r, q["overrides"], planners)
    if q["nav"]:
        navs = [pc for pc in planners if pc.kind == "navigate"]
        if not navs:
            r.bad("experiment.quick.nav", "no planner has kind = 'navigate'")
        fields = setting_of(PlannerConfig, "nav").allowed_keys() or ()
        for k in q["nav"]:
            if k not in fields:
                r.bad(f"experiment.quick.nav.{k}", "unknown NavConfig field" + did_you_mean(k, list(fields)))
        if all(k in fields for k in q["nav"]):
            check_quick_nav(r, q["nav"], navs)
    labels, names = [pc.label for pc in planners], map_names
    for key, known in (("planners", labels), ("maps", names)):
        for j, x in enumerate(q.get(key) or []):
            if known is not None and x not in known:
                r.bad(f"experiment.quick.{key}[{j}]", f"unknown {key[:-1]} {x!r} (configured: {', '.join(known)})")
    return QuickSpec(q["seeds"], q["count"], q["chunk"], frozen(q["overrides"]), frozen(q["nav"]),
                     tuple(q["planners"]) if q.get("planners") else None, tuple(q["maps"]) if q.get("maps") else None)


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
    check_sites(r, maps, planners)
    kinds = frozenset(p.kind for p in planners if p.kind)
    metrics = _read_metrics(r, raw, kinds)
    check_team_metrics(r, planners, metrics)
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
    """The config with its ``[experiment.quick]`` changes applied (``is_quick=True``): the overlay `QuickSpec`
    declares (`jaxplan.experiments.schema.overlay`; overrides go to the planners that accept them, nav settings to
    the navigate planners), and only draw 0 of a generated map with draws (a smoke run checks the pipeline, not the
    map-to-map variance)."""
    q = overlay(cfg, cfg.quick, QuickSpec, where={"overrides": lambda pc, k: k in accepted_overrides(pc),
                                                  "nav": lambda pc, k: pc.kind == "navigate"})
    return q.replace(maps=tuple(m for m in q.maps if m.draw == 0), is_quick=True)
