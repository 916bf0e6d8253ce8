"""Tuning configs: TOML read with `tomllib`, validated in full (every problem with its key path), frozen dataclasses.

The schema is declared once, below, as `jaxplan.experiments.schema` settings: `TuneFile` is the top level,
`TuneTable` its ``[tune]`` table, `TuneQuickTable` ``[tune.quick]``; the one ``[[maps]]`` entry and
``[scenarios]`` are those of experiment configs (`jaxplan.experiments.config.MapTable`, `ScenarioSpec`).
The reference page ``docs/guide/config.md`` and the editors' JSON Schema
``configs/schema/tune.schema.json`` are generated from them (``python -m jaxplan.config_reference``);
``configs/tune_*.toml`` are complete examples. ``[tune.quick]`` is an overlay on the resolved config, declared
on `TuneQuickTable`'s settings (`jaxplan.experiments.schema.overlay`): ``parse_tune_config(..., quick=True)``.
"""

from __future__ import annotations

import dataclasses
import math
import os
import tomllib
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping

from jaxplan.core.deprecation import warn_deprecated
from jaxplan.experiments.config import (
    RUN_NAME,
    MapSpec,
    MapTable,
    ScenarioSpec,
    default_data_dir,
    read_config_text,
    read_maps,
)
from jaxplan.experiments.schema import (
    ConfigError,
    Reader,
    Setting,
    declaration,
    frozen,
    overlay,
    setting,
    setting_of,
)

__all__ = ["TuneConfig", "load_tune_config", "parse_tune_config", "apply_tune_quick", "KINDS", "TuneFile",
           "TuneTable", "TuneQuickTable", "read_toml", "quick_tune_config"]

KINDS = ("aco", "dwa", "mppi", "nav")
_DWA_PLANNERS = ("weighted", "fuzzy")
_MPPI_PLANNERS = ("mppi",)
_NAV_PLANNERS = ("dwa", "mppi")
_WALKERS = ("blind", "seeing")


def _aco_planners() -> tuple[str, ...]:
    from jaxplan.aco import COLONIES

    return tuple(sorted(COLONIES))


def _planners() -> tuple[str, ...]:
    return _aco_planners() + _DWA_PLANNERS + _MPPI_PLANNERS + ("dwa",)


def _strategies() -> tuple[str, ...]:
    from jaxplan.tune._strategies import STRATEGIES

    return STRATEGIES


def _metrics(kind: str | None = None) -> tuple[str, ...]:
    from jaxplan.tune._nav_objective import NAV_METRICS
    from jaxplan.tune._objective import ACO_METRICS, DWA_METRICS

    return {"aco": ACO_METRICS, "dwa": DWA_METRICS, "mppi": DWA_METRICS, "nav": NAV_METRICS}.get(
        kind, tuple(dict.fromkeys(ACO_METRICS + DWA_METRICS + NAV_METRICS)))


_DEFAULT_WEIGHTS = {"aco": {"gap": 1.0, "failure": 1.0}, "dwa": {"time": 1.0, "failure": 1.0},
                    "mppi": {"time": 1.0, "failure": 1.0}, "nav": {"failure": 1.0, "time": 1.0}}
_SPACE_JSON = {
    "type": "object", "minProperties": 1,
    "additionalProperties": {"oneOf": [
        {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2},
        {"type": "array", "minItems": 1,
         "items": {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2}}]}}


@declaration
class TuneQuickTable:
    """What ``quick=True`` (``jaxplan tune --quick``) changes: a smoke run in the run folder NAME-quick (every key
    optional)."""

    population: int = setting("int", None, "weight vectors per generation", ge=2, overlay="set")
    generations: int = setting("int", None, "generations", ge=1, overlay="set")
    train_count: int = setting("int", None, "training scenarios", ge=1, overlay="set")
    test_count: int = setting("int", None, "at most this many test scenarios", ge=1, overlay="set")
    train_seeds: Any = setting("seeds", None, "training seeds: a count or a list", overlay="set")
    test_seeds: Any = setting("seeds", None, "test seeds: a count or a list",
                              default_text="1000.. as many as the quick train_seeds, if those are given",
                              overlay="set")
    overrides: Mapping[str, Any] = setting("table", doc="merged over [tune] overrides", overlay="merge")
    max_time: float = setting("float", None, "dwa: episode length (s)", gt=0, overlay="set")


@declaration
class TuneTable:
    """The tuning run: what is tuned, by which strategy, on which scenarios and seeds."""

    name: str = setting("str", None, "the run folder OUT/NAME", required=True, pattern=RUN_NAME,
                        hint="it names the run folder")
    description: str = setting("str", "", "one line for the summary")
    kind: str = setting("str", "aco", "aco: a colony planner's weights; dwa: DWA critic weights; mppi: MPPI critic "
                        "weights, temperature and noise (both on local-planner-only episodes among crossing discs); "
                        "nav: the local planner's weights on full navigation episodes among walkers, over several "
                        "maps (`jaxplan.tune.nav_objective`)", required=True, choices=KINDS)
    planner: str = setting("str", None, "aco: a colony planner; dwa: the DWA evaluator (weighted or fuzzy); mppi: "
                           "mppi; nav: the local planner (dwa or mppi)", choices=_planners,
                           default_text='`"iaco"`; dwa: `"weighted"`; mppi: `"mppi"`; nav: `"dwa"`')
    strategy: str = setting("str", "cma_es", "the search strategy (`jaxplan.tune.STRATEGIES`)", choices=_strategies)
    population: int = setting("int", 16, "weight vectors per generation", ge=2)
    generations: int = setting("int", 10, "generations", ge=1)
    seed: int = setting("int", 0, "the strategy's PRNG seed", ge=0)
    checkpoint_every: int = setting("int", 2, "orbax checkpoint every k generations (and after the last)", ge=1)
    train_count: int = setting("int", 16, "the first train_count scenarios train; the rest are the held-out test "
                               "set (nav: per map, the map's selected rows alternate train and held-out until "
                               "train_count train)", ge=1)
    train_seeds: Any = setting("seeds", 4, "training seeds: a count n (0..n-1) or a list")
    test_seeds: Any = setting("seeds", None, "test seeds: a count or a list; must not meet train_seeds",
                              default_text="1000.. as many as train_seeds")
    weights: Mapping[str, float] = setting("table", doc="metric weights of the cost (aco: gap failure turns "
                                           "roughness clearance; dwa: time failure collision clearance)",
                                           keys=_metrics, values=Setting("float", ge=0),
                                           default_text="aco: `{ gap = 1.0, failure = 1.0 }`; dwa: "
                                                        "`{ time = 1.0, failure = 1.0 }`")
    overrides: Mapping[str, Any] = setting("table", doc="aco: planner settings; dwa: `DWAConfig` fields (n_v, "
                                           "n_omega, ...); mppi: `MPPIConfig` fields (samples, steps, ...)")
    options: Mapping[str, Any] = setting("table", doc="the strategy's own options")
    max_time: float = setting("float", 20.0, "dwa, mppi: episode length (s); nav: `NavConfig.max_time`, the "
                              "longest episode", gt=0, default_text="`20.0`; nav: `180.0` (`NavConfig`'s)")
    time_limit: float = setting("float", None, "nav: every episode's time limit (s), at most max_time",
                                gt=0, default_text="navigate_batch's: 60 s + 3 x the waypoint path at top speed")
    walkers: tuple[str, ...] = setting("strings", ("blind", "seeing"), "nav: walker kinds, each scored: blind "
                                       "(on their routes) and seeing (the social force model)", nonempty=True)
    walker_count: int = setting("int", 5, "nav: walkers per episode", ge=1)
    walker_speed: float = setting("float", 1.0, "nav: their speed (m/s)", gt=0)
    discs: int = setting("int", 2, "dwa: moving discs per episode", ge=0)
    pipeline: str = setting("str", None, "dwa, mppi: the navigate pipeline the best-weights fragment names; nav: "
                            "the pipeline the episodes run (its local planner must be planner's)",
                            default_text='`"astar_kng_dwa"`; fuzzy planner: `"iaco_dwa"`; mppi and nav: '
                                         '`"astar_kng_<planner>"`')
    space: Any = setting("custom", None, "the search box: name = [low, high], a vector weight one pair per "
                         "component (e.g. lambdas = [[0.0, 1.0], [0.0, 1.0], [0.0, 1.0]])", required=True,
                         type_text="table of [low, high] pairs", json=_SPACE_JSON)
    quick: Any = setting("section", None, "what `--quick` changes", section=TuneQuickTable)


@declaration
class TuneFile:
    """A tuning config (`jaxplan tune CONFIG`)."""

    tune: Any = setting("section", None, "the tuning run", section=TuneTable, required=True)
    maps: Any = setting("tables", None, "exactly one map, as in experiment configs (nav: one or more MovingAI "
                        "maps with their .scen rows)", section=MapTable, required=True, nonempty=True)
    scenarios: Any = setting("section", None, "as in experiment configs; count = train + test scenarios",
                             section=ScenarioSpec)


@dataclass(frozen=True)
class TuneConfig:
    """A validated tuning config (`TuneTable` documents every field)."""

    name: str
    description: str
    kind: str
    planner: str
    strategy: str
    population: int
    generations: int
    seed: int
    checkpoint_every: int
    train_count: int
    test_count: int | None
    train_seeds: tuple[int, ...]
    test_seeds: tuple[int, ...]
    weights: Mapping[str, float]
    overrides: Mapping[str, Any]
    options: Mapping[str, Any]
    max_time: float
    discs: int
    pipeline: str
    space: Mapping[str, Any]
    map: MapSpec
    quick: Mapping[str, Any]
    is_quick: bool = False
    text: str = ""
    path: Path | None = None
    maps: tuple[MapSpec, ...] = ()
    time_limit: float | None = None
    walkers: tuple[str, ...] = ("blind", "seeing")
    walker_count: int = 5
    walker_speed: float = 1.0


def _space(r: Reader, t: Any, path: str) -> dict:
    out: dict[str, Any] = {}
    if not isinstance(t, dict) or not t:
        r.bad(path, "a non-empty table of name = [low, high] bounds is required")
        return out
    num = lambda v: isinstance(v, (int, float)) and not isinstance(v, bool)  # noqa: E731
    for k, v in t.items():
        p = f"{path}.{k}"
        pairs = [v] if (isinstance(v, list) and len(v) == 2 and all(num(a) for a in v)) else v
        if not isinstance(pairs, list) or not pairs or not all(
                isinstance(q, list) and len(q) == 2 and all(num(a) for a in q) for q in pairs):
            r.bad(p, "expected [low, high] or a list of [low, high] pairs")
            continue
        for i, (lo, hi) in enumerate(pairs):
            q = p if pairs is not v else f"{p}[{i}]"
            if not (math.isfinite(lo) and math.isfinite(hi)):
                r.bad(q, f"bounds must be finite, got [{lo}, {hi}]")
            elif not lo < hi:
                r.bad(q, f"need low < high, got low={lo}, high={hi}")
        out[k] = tuple(float(a) for a in v) if pairs is not v else [tuple(float(a) for a in q) for q in v]
    return out


def read_toml(text: str, source: str) -> dict[str, Any]:
    """The TOML document ``text`` as a dict.

    Raises:
      ConfigError: the text is not valid TOML (naming ``source``).
    """
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ConfigError([f"not valid TOML: {e}"], source) from None


def parse_tune_config(text: str, *, data_dir: str | os.PathLike | None = None, source: str = "config",
                      path: Path | None = None, quick: bool = False) -> TuneConfig:
    """Parses and validates a tuning config; with ``quick``, its ``[tune.quick]`` overlay applied
    (`quick_tune_config`).

    Raises:
      ConfigError: listing every problem with its key path.
    """
    raw = read_toml(text, source)
    r = Reader()
    r.section(raw, "", TuneFile)
    tt = raw.get("tune") if isinstance(raw.get("tune"), dict) else {}
    t = r.section(raw.get("tune"), "tune", TuneTable, defaults={"name": "unnamed"},
                  skip=("planner", "test_seeds", "weights", "pipeline"))
    kind = t["kind"]
    choices = {"aco": _aco_planners(), "mppi": _MPPI_PLANNERS, "nav": _NAV_PLANNERS}.get(kind, _DWA_PLANNERS)
    planner = r.value(tt, "tune", dataclasses.replace(setting_of(TuneTable, "planner"), choices=choices),
                      {"aco": "iaco", "mppi": "mppi", "nav": "dwa"}.get(kind, "weighted"))
    train_seeds = t["train_seeds"]
    test_seeds = r.value(tt, "tune", setting_of(TuneTable, "test_seeds")) or _default_test_seeds(train_seeds)
    if set(train_seeds) & set(test_seeds):
        shared = _shared_seeds(train_seeds, test_seeds)
        r.bad("tune.test_seeds", f"must not share seeds with tune.train_seeds: {shared}")
    weights = r.value(tt, "tune", dataclasses.replace(setting_of(TuneTable, "weights"), keys=_metrics(kind)))
    weights = weights or dict(_DEFAULT_WEIGHTS[kind])
    quick_table = r.section(tt.get("quick"), "tune.quick", TuneQuickTable)
    dd = Path(data_dir) if data_dir is not None else default_data_dir()
    maps = read_maps(r, raw, dd)
    if len(maps) > 1 and kind != "nav":
        r.bad("maps", f"a tuning run uses exactly one map (kind = \"nav\" takes several), got {len(maps)}")
    default_pipeline = ("astar_kng_dwa" if planner != "fuzzy" else "iaco_dwa") if kind != "nav" else \
        f"astar_kng_{planner}"
    pipeline = r.value(tt, "tune", setting_of(TuneTable, "pipeline"), default_pipeline)
    if kind == "nav":
        _check_nav(r, tt, t, planner, pipeline, maps)
    cfg = TuneConfig(
        name=t["name"], description=t["description"], kind=kind, planner=planner, strategy=t["strategy"],
        population=t["population"], generations=t["generations"], seed=t["seed"],
        checkpoint_every=t["checkpoint_every"], train_count=t["train_count"], test_count=None,
        train_seeds=train_seeds, test_seeds=test_seeds,
        weights=MappingProxyType({k: float(v) for k, v in weights.items()}),
        overrides=frozen(t["overrides"]), options=frozen(t["options"]), max_time=t["max_time"], discs=t["discs"],
        pipeline=pipeline,
        space=MappingProxyType(_space(r, tt.get("space"), "tune.space")),
        map=maps[0] if maps else None,
        quick=MappingProxyType(quick_table),
        text=text, path=path, maps=tuple(maps), time_limit=t["time_limit"], walkers=tuple(t["walkers"]),
        walker_count=t["walker_count"], walker_speed=t["walker_speed"],
    )
    if kind == "nav" and "max_time" not in tt:
        cfg = dataclasses.replace(cfg, max_time=180.0)
    _check_options(r, cfg)
    if any(quick_table[k] is not None for k in ("train_seeds", "test_seeds")):
        shared = _shared_seeds(*_quick_seeds(train_seeds, test_seeds, quick_table))
        if shared:
            r.bad("tune.quick.test_seeds", f"the quick run's test seeds must not share seeds with its train seeds: "
                                           f"{shared}")
    if r.problems:
        raise ConfigError(r.problems, source)
    return quick_tune_config(cfg) if quick else cfg


def _check_nav(r: Reader, tt: Mapping[str, Any], t: Mapping[str, Any], planner: str, pipeline: str,
               maps: tuple[MapSpec, ...]) -> None:
    """The nav kind's own rules: a pipeline of that local planner, known walker kinds, MovingAI maps with .scen rows,
    a time limit within max_time, no dwa-kind keys."""
    from jaxplan.nav import PIPELINES

    pipe = PIPELINES.get(pipeline)
    if pipe is None:
        r.bad("tune.pipeline", f"unknown pipeline {pipeline!r}; choose from {', '.join(PIPELINES)}")
    elif pipe.local != planner:
        r.bad("tune.pipeline", f"{pipeline!r} runs the {pipe.local!r} local planner, but tune.planner is {planner!r}")
    bad = [w for w in t["walkers"] if w not in _WALKERS]
    if bad or len(set(t["walkers"])) != len(t["walkers"]):
        r.bad("tune.walkers", f"must be distinct kinds among {list(_WALKERS)}, got {list(t['walkers'])}")
    if "discs" in tt:
        r.bad("tune.discs", "applies to kind = \"dwa\" and \"mppi\" only; nav uses walker_count")
    limit, longest = t["time_limit"], t["max_time"] if "max_time" in tt else 180.0
    if limit is not None and limit > longest:
        r.bad("tune.time_limit", f"must be at most max_time ({longest:g} s), got {limit:g}")
    for i, m in enumerate(maps):
        if m.path is None or m.scen is None or m.scenarios.source != "scen":
            r.bad(f"maps[{i}]", "kind = \"nav\" needs MovingAI maps (path) with their .scen rows (source = \"scen\")")


def _check_options(r: Reader, cfg: TuneConfig) -> None:
    """``[tune] options`` against the strategy's signature and ranges (else: a raw TypeError, or NaN weights that
    run to the end)."""
    from jaxplan.tune._strategies import STRATEGIES, option_problems

    if cfg.strategy not in STRATEGIES:
        return  # already reported
    for key, problem in option_problems(cfg.strategy, dict(cfg.options), cfg.population, cfg.generations):
        r.bad("tune.options" + (f".{key}" if key else ""), problem)


def load_tune_config(path: str | os.PathLike, *, data_dir: str | os.PathLike | None = None,
                     quick: bool = False) -> TuneConfig:
    """Reads and validates the tuning config at ``path``; with ``quick``, its ``[tune.quick]`` overlay applied.

    Raises:
      FileNotFoundError: no such file.
      ConfigError: listing every problem with its key path.
    """
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"tuning config not found: {p}")
    return parse_tune_config(read_config_text(p), data_dir=data_dir, source=str(p), path=p.resolve(), quick=quick)


def _default_test_seeds(train_seeds: tuple[int, ...]) -> tuple[int, ...]:
    return tuple(1000 + i for i in range(len(train_seeds)))


def _quick_seeds(train: tuple[int, ...], test: tuple[int, ...], quick: Mapping[str, Any]
                 ) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """(train seeds, test seeds) of the quick run: its own where given; new train seeds alone bring default test
    seeds (1000..), as in the main section."""
    q_train, q_test = quick.get("train_seeds"), quick.get("test_seeds")
    train_q = q_train if q_train is not None else train
    test_q = q_test if q_test is not None else (_default_test_seeds(q_train) if q_train is not None else test)
    return tuple(train_q), tuple(test_q)


def _shared_seeds(train: tuple[int, ...], test: tuple[int, ...]) -> list[int]:
    return sorted(set(train) & set(test))


def quick_tune_config(cfg: TuneConfig) -> TuneConfig:
    """The config with its ``[tune.quick]`` overlay applied (a smoke run: run folder NAME-quick): the keys as
    `TuneQuickTable` declares them (`jaxplan.experiments.schema.overlay`), and default test seeds (1000..) for quick
    train seeds given alone, as in the main section.

    Raises:
      ConfigError: the quick run's test seeds meet its train seeds (the test set would not be held out).
    """
    q = cfg.quick
    train, test = _quick_seeds(cfg.train_seeds, cfg.test_seeds, q)
    shared = _shared_seeds(train, test)
    if shared:  # parse_tune_config reports this too; a config built in code reaches here unchecked
        raise ConfigError([f"tune.quick.test_seeds: the quick run's test seeds must not share seeds with its train "
                           f"seeds: {shared}"], cfg.name)
    return dataclasses.replace(overlay(cfg, q, TuneQuickTable), train_seeds=train, test_seeds=test, is_quick=True)


def apply_tune_quick(cfg: TuneConfig) -> TuneConfig:
    """Deprecated: `quick_tune_config` (or ``load_tune_config(path, quick=True)``)."""
    warn_deprecated("apply_tune_quick is deprecated: use load_tune_config(path, quick=True) or "
                    "jaxplan.tune.quick_tune_config(cfg)")
    return quick_tune_config(cfg)
