"""The experiment config's checks that need more than one key, a registry or the planners themselves.

`jaxplan.experiments.config` reads each table against its declaration (`jaxplan.experiments.config_schema`);
what a single key's type, bounds or choices cannot say is checked here and reported to the same
`jaxplan.experiments.schema.Reader`, with its key path: a generator's parameters, a planner's overrides against its
defaults and its own value checks, a TSP planner's, a robot model's keys, a navigate planner's settings as its
pipeline would resolve them (`nav_config`, `nav_problem`), a team's spacing, which metrics a team has, that every
map has a planner that runs on it, a figure's scenario against a map's scenarios, and the quick table's overrides
and nav settings against the planners they reach.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any, Callable, Mapping, Sequence

from jaxplan.experiments.config_schema import (
    GENERATOR_PARAMS,
    ROBOT_MODELS,
    SCENARIO_FIGURE_PLANNERS,
    MapSpec,
    PlannerConfig,
    TeamSpec,
    applies,
)
from jaxplan.experiments.schema import Reader, did_you_mean, frozen, join

if TYPE_CHECKING:  # pragma: no cover
    from jaxplan.nav import NavConfig

__all__ = ["check_generator", "check_tsp", "check_sites", "check_overrides", "check_robot", "check_team",
           "nav_config", "check_nav", "nav_problem", "check_team_metrics", "scenario_bound", "check_figure_scenario",
           "check_quick_overrides", "check_quick_nav", "accepted_overrides"]


def check_generator(r: Reader, path: str, name: str, entry: tuple, params: dict, resolution: float) -> None:
    factory, is_dc = entry
    if is_dc:
        fields = [f.name for f in dataclasses.fields(factory) if f.name != "resolution"]
        known = tuple(fields)
    else:
        known = GENERATOR_PARAMS[name]
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


_TEAM_REFUSED = ("hausdorff", "accuracy", "smoothness", "mean_clearance")
"""Metrics of one robot's global path against the scenario's exact path: a team trial has N paths, so none."""


def check_tsp(r: Reader, p: str, name: str, overrides: dict) -> None:
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


def check_sites(r: Reader, maps: tuple[MapSpec, ...], planners: tuple[PlannerConfig, ...]) -> None:
    """Every map and instance has a planner that runs on it, and every planner a map or instance."""
    for m in maps:
        if planners and not any(applies(pc, m) for pc in planners):
            what = "kind = 'tsp' planner" if m.is_tsp else "plan or navigate planner"
            r.bad(m.key, f"no {what} is configured to run on {m.name!r}")
    for i, pc in enumerate(planners):
        if maps and not any(applies(pc, m) for m in maps):
            r.bad(f"planners[{i}].kind", "a kind = 'tsp' planner runs on [[instances]] entries, and there is none"
                  if pc.kind == "tsp" else f"a kind = {pc.kind!r} planner runs on [[maps]] entries, and there is none")


def check_overrides(r: Reader, path: str, planner: str, overrides: dict, resolve: Callable[..., Any],
                    base: dict) -> None:
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


def check_robot(r: Reader, path: str, robot: Mapping) -> None:
    """``robot.model`` is a known model, and only an Ackermann robot has a wheelbase and a steering limit."""
    model = robot.get("model", "unicycle")
    if model not in ROBOT_MODELS:
        r.bad(join(path, "model"), f"unknown robot model {model!r} (known: {', '.join(ROBOT_MODELS)})"
              + did_you_mean(str(model), list(ROBOT_MODELS)))
    elif model != "ackermann":
        for k in ("wheelbase", "steer_max"):
            if k in robot:
                r.bad(join(path, k), f"only applies to model = 'ackermann' (this robot is a {model!r})")


def check_team(r: Reader, path: str, pipeline: str, nav: Mapping, dwa: Mapping, robot: Mapping, params: Mapping,
                mppi: Mapping, team: TeamSpec) -> None:
    """A team's spacing keeps teammates apart by more than two footprint radii (`jaxplan.navigate_multi` refuses
    robots overlapping at their starts or sharing a goal)."""
    from jaxplan.dwa import footprint_radius

    if nav_problem(pipeline, nav, dwa, robot, params, mppi) is not None:
        return  # reported by check_nav
    probe = PlannerConfig("probe", "navigate", pipeline, robot=frozen(dict(robot)), dwa=frozen(dict(dwa)),
                          nav=frozen(dict(nav)))
    rad = float(footprint_radius(nav_config(probe)[0].dwa.robot.footprint))
    if team.spacing <= 2 * rad:
        r.bad(join(path, "spacing"), f"{team.spacing:g} m does not keep teammates apart: it must exceed two footprint "
                                     f"radii ({2 * rad:.4g} m)")


def nav_config(planner: PlannerConfig) -> tuple[NavConfig, dict[str, Any]]:
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


def check_nav(r: Reader, p: str, pipeline: str, nav: Mapping, dwa: Mapping, robot: Mapping,
               params: Mapping, mppi: Mapping | None = None) -> None:
    problem = nav_problem(pipeline, nav, dwa, robot, params, mppi or {})
    if problem is not None:
        r.bad(p, f"navigation settings: {problem}")


def nav_problem(pipeline: str, nav: Mapping, dwa: Mapping, robot: Mapping, params: Mapping,
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


def check_team_metrics(r: Reader, planners: tuple[PlannerConfig, ...], metrics: tuple[str, ...]) -> None:
    """A team planner has no single global path to compare with the scenario's exact one."""
    refused = [m for m in metrics if m in _TEAM_REFUSED]
    for i, pc in enumerate(planners):
        if pc.team is not None and refused:
            r.bad(f"planners[{i}].team", f"metrics {', '.join(map(repr, refused))} compare one robot's path with the "
                                         "scenario's exact path and are not defined for a team: drop them")


def scenario_bound(spec: MapSpec) -> int | None:
    """How many scenarios ``spec`` has at most, when the config alone tells (None: only the data does)."""
    sc = spec.scenarios
    if spec.is_tsp or sc.source == "scene":
        return 1
    if sc.source == "random":
        return sc.count or 10  # `runner._random_pairs` finds exactly this many or fails
    return sc.count  # scen rows: count is an upper bound; the filters may keep fewer


def check_figure_scenario(r: Reader, p: str, name: str | None, kind: str | None, t: dict,
                           sites: Sequence[MapSpec], planners: Sequence[PlannerConfig]) -> None:
    """A figure's ``scenario`` past a map's scenarios would crash the drawing (or leave an empty panel)."""
    sc = t.get("scenario")
    if kind not in SCENARIO_FIGURE_PLANNERS or not isinstance(sc, int) or isinstance(sc, bool):
        return
    labels = t.get("planners") if isinstance(t.get("planners"), list) else None
    named = t.get("maps") if isinstance(t.get("maps"), list) else None
    drawn = [pc for pc in planners
             if pc.kind in SCENARIO_FIGURE_PLANNERS[kind] and (labels is None or pc.label in labels)]
    for m in sites:
        n = scenario_bound(m)
        if (named is None or m.name in named) and any(applies(pc, m) for pc in drawn) and n is not None and sc >= n:
            r.bad(join(p, "scenario"), f"figure {name!r}: scenario {sc} is past map {m.name!r}'s {n} scenario"
                                        f"{'s' if n > 1 else ''} (0..{n - 1})")
            return


def check_quick_overrides(r: Reader, overrides: Mapping[str, Any], planners: Sequence[PlannerConfig]) -> None:
    """Quick overrides: each key must be accepted by at least one planner, and valid for each that accepts it."""
    from jaxplan.aco import resolve_tsp as tsp_resolve
    from jaxplan.nav import get_pipeline
    from jaxplan.registry import resolve

    for k, v in overrides.items():
        takers = [pc for pc in planners if k in accepted_overrides(pc)]
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


def check_quick_nav(r: Reader, quick_nav: Mapping, navs: Sequence[PlannerConfig]) -> None:
    """The quick nav values merged into each navigate planner's own, checked as `check_nav` checks those: else a
    bad value surfaces only mid-run, after a chunk is committed, under no config key."""
    from jaxplan.nav import pipelines

    for pc in navs:
        if pc.name not in pipelines():
            continue  # reported at its planners[i].name
        own = (pc.nav, pc.dwa, pc.robot, pc.params, pc.mppi)
        if nav_problem(pc.name, *own) is not None:
            continue  # reported at its planners[i]; the quick values are not to blame
        found = False
        for k, v in quick_nav.items():  # one key at a time, to name it
            problem = nav_problem(pc.name, {**dict(pc.nav), k: v}, *own[1:])
            if problem is not None:
                found = True
                r.bad(f"experiment.quick.nav.{k}", f"for {pc.label!r}: {problem}")
        problem = None if found else nav_problem(pc.name, {**dict(pc.nav), **dict(quick_nav)}, *own[1:])
        if problem is not None:  # fine alone, not together
            r.bad("experiment.quick.nav", f"for {pc.label!r}: {problem}")


def accepted_overrides(pc: PlannerConfig) -> tuple[str, ...]:
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
