"""Tuning configs: TOML read with `tomllib`, validated in full (every problem with its key path), frozen dataclasses.

Schema (``#`` marks defaults)::

    [tune]
    name = "tune_iaco"          # the run folder OUT/NAME ([A-Za-z0-9][A-Za-z0-9_.-]*), required
    kind = "aco"                # "aco" (a colony planner's weights) | "dwa" (DWA critic weights)
    planner = "iaco"            # aco: aco | iaco | risk_aco | opt_ant | praco; dwa: weighted | fuzzy
    strategy = "cma_es"         # grid | random | cma_es | snes | ssa | issa | reinforce | surrogate
    population = 16             # weight vectors per generation (>= 2)
    generations = 10            # (>= 1)
    seed = 0                    # the strategy's PRNG seed
    checkpoint_every = 2        # orbax checkpoint every k generations (and after the last)
    train_count = 32            # the first train_count scenarios train, the rest are the held-out test set
    train_seeds = 4             # count (0..n-1) or list
    test_seeds = [1000, 1001, 1002, 1003]   # default: 1000.. as many as train_seeds; must not meet train_seeds
    weights = { gap = 1.0, failure = 1.0 }  # metric weights (aco: gap failure turns roughness clearance;
                                            #                 dwa: time failure collision clearance)
    overrides = { ants = 16, iterations = 8 }   # aco: planner settings; dwa: DWAConfig fields (n_v, n_omega, ...)
    options = { sigma = 0.3 }   # the strategy's own options
    max_time = 20.0             # dwa: episode length (s)
    discs = 2                   # dwa: moving discs per episode
    pipeline = "astar_kng_dwa"  # dwa: the navigate pipeline the best-weights fragment names

    [tune.space]                # the search box: name = [low, high], vector weights one pair per component
    alpha = [0.5, 3.0]
    lambdas = [[0.0, 1.0], [0.0, 1.0], [0.0, 1.0]]

    [tune.quick]                # what quick=True changes; every key optional
    population = 8
    generations = 3
    train_count = 4
    test_count = 4              # at most this many test scenarios
    train_seeds = 2
    test_seeds = [1000, 1001]
    overrides = { ants = 8, iterations = 4 }
    max_time = 10.0

    [[maps]]                    # exactly one map, as in experiment configs (`jaxplan.experiments.config`)
    ...
    [scenarios]                 # as in experiment configs; count = train + test scenarios
    ...
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

from jaxplan.experiments.config import _NAME_RE, ConfigError, MapSpec, _Reader, _read_maps, _frozen, default_data_dir

__all__ = ["TuneConfig", "load_tune_config", "parse_tune_config", "apply_tune_quick", "KINDS"]

KINDS = ("aco", "dwa")
_TUNE_KEYS = ("name", "kind", "planner", "strategy", "population", "generations", "seed", "checkpoint_every",
              "train_count", "train_seeds", "test_seeds", "weights", "overrides", "options", "max_time", "discs",
              "pipeline", "space", "quick", "description")
_QUICK_KEYS = ("population", "generations", "train_count", "test_count", "train_seeds", "test_seeds", "overrides",
               "max_time")


@dataclass(frozen=True)
class TuneConfig:
    """A validated tuning config (see the module docstring for every field's meaning)."""

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


def _space(r: _Reader, t: Any, path: str) -> dict:
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


def parse_tune_config(text: str, *, data_dir: str | os.PathLike | None = None, source: str = "config",
                      path: Path | None = None) -> TuneConfig:
    """Parses and validates a tuning config. Raises `ConfigError` listing every problem with its key path."""
    from jaxplan.tune._objective import ACO_METRICS, DWA_METRICS
    from jaxplan.tune._strategies import STRATEGIES

    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ConfigError([f"not valid TOML: {e}"], source) from None
    r = _Reader()
    r.table(raw, "", ("tune", "maps", "scenarios"))
    t = r.table(raw.get("tune"), "tune", _TUNE_KEYS, required=("name", "kind", "space"))
    name = r.get(t, "tune", "name", "str", "unnamed")
    if isinstance(t.get("name"), str) and not _NAME_RE.match(t["name"]):
        r.bad("tune.name", f"must match [A-Za-z0-9][A-Za-z0-9_.-]* (it names the run folder), got {name!r}")
    kind = r.get(t, "tune", "kind", "str", "aco", choices=KINDS)
    from jaxplan.aco._planners import COLONIES

    planners = tuple(sorted(COLONIES)) if kind == "aco" else ("weighted", "fuzzy")
    planner = r.get(t, "tune", "planner", "str", "iaco" if kind == "aco" else "weighted", choices=planners)
    train_seeds = r.seeds(t, "tune", "train_seeds", (0, 1, 2, 3))
    test_seeds = r.seeds(t, "tune", "test_seeds", None) or _default_test_seeds(train_seeds)
    if set(train_seeds) & set(test_seeds):
        r.bad("tune.test_seeds", f"must not share seeds with tune.train_seeds: {sorted(set(train_seeds) & set(test_seeds))}")
    metrics = ACO_METRICS if kind == "aco" else DWA_METRICS
    weights = r.table(t.get("weights"), "tune.weights", metrics)
    for k, v in weights.items():
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
            r.bad(f"tune.weights.{k}", f"must be a finite number >= 0, got {v!r}")
    weights = weights or ({"gap": 1.0, "failure": 1.0} if kind == "aco" else {"time": 1.0, "failure": 1.0})
    q = r.table(t.get("quick"), "tune.quick", _QUICK_KEYS)
    quick = {
        "population": r.get(q, "tune.quick", "population", "int", None, lo=2),
        "generations": r.get(q, "tune.quick", "generations", "int", None, lo=1),
        "train_count": r.get(q, "tune.quick", "train_count", "int", None, lo=1),
        "test_count": r.get(q, "tune.quick", "test_count", "int", None, lo=1),
        "train_seeds": r.seeds(q, "tune.quick", "train_seeds"),
        "test_seeds": r.seeds(q, "tune.quick", "test_seeds"),
        "overrides": r.table(q.get("overrides"), "tune.quick.overrides", tuple(q.get("overrides") or {})),
        "max_time": r.get(q, "tune.quick", "max_time", "float", None, lo=0, strict_lo=True),
    }
    dd = Path(data_dir) if data_dir is not None else default_data_dir()
    maps = _read_maps(r, raw, dd)
    if len(maps) > 1:
        r.bad("maps", f"a tuning run uses exactly one map, got {len(maps)}")
    cfg = TuneConfig(
        name=name,
        description=r.get(t, "tune", "description", "str", ""),
        kind=kind, planner=planner,
        strategy=r.get(t, "tune", "strategy", "str", "cma_es", choices=STRATEGIES),
        population=r.get(t, "tune", "population", "int", 16, lo=2),
        generations=r.get(t, "tune", "generations", "int", 10, lo=1),
        seed=r.get(t, "tune", "seed", "int", 0, lo=0),
        checkpoint_every=r.get(t, "tune", "checkpoint_every", "int", 2, lo=1),
        train_count=r.get(t, "tune", "train_count", "int", 16, lo=1),
        test_count=None,
        train_seeds=train_seeds, test_seeds=test_seeds,
        weights=MappingProxyType({k: float(v) for k, v in weights.items()}),
        overrides=_frozen(r.table(t.get("overrides"), "tune.overrides", tuple(t.get("overrides") or {}))),
        options=_frozen(r.table(t.get("options"), "tune.options", tuple(t.get("options") or {}))),
        max_time=r.get(t, "tune", "max_time", "float", 20.0, lo=0, strict_lo=True),
        discs=r.get(t, "tune", "discs", "int", 2, lo=0),
        pipeline=r.get(t, "tune", "pipeline", "str", "astar_kng_dwa" if planner != "fuzzy" else "iaco_dwa"),
        space=MappingProxyType(_space(r, t.get("space"), "tune.space")),
        map=maps[0] if maps else None,
        quick=MappingProxyType(quick),
        text=text, path=path,
    )
    _check_options(r, cfg)
    if any(quick[k] is not None for k in ("train_seeds", "test_seeds")):
        shared = _shared_seeds(*_quick_seeds(train_seeds, test_seeds, quick))
        if shared:
            r.bad("tune.quick.test_seeds", f"the quick run's test seeds must not share seeds with its train seeds: "
                                           f"{shared}")
    if r.problems:
        raise ConfigError(r.problems, source)
    return cfg


def _check_options(r: _Reader, cfg: TuneConfig) -> None:
    """``[tune] options`` against the strategy's signature and ranges (else: a raw TypeError, or NaN weights that
    run to the end)."""
    from jaxplan.tune._strategies import STRATEGIES, option_problems

    if cfg.strategy not in STRATEGIES:
        return  # already reported
    for key, problem in option_problems(cfg.strategy, dict(cfg.options), cfg.population, cfg.generations):
        r.bad("tune.options" + (f".{key}" if key else ""), problem)


def load_tune_config(path: str | os.PathLike, *, data_dir: str | os.PathLike | None = None) -> TuneConfig:
    """Reads and validates the tuning config at ``path`` (`ConfigError` lists every problem)."""
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"tuning config not found: {p}")
    return parse_tune_config(p.read_text(), data_dir=data_dir, source=str(p), path=p.resolve())


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


def apply_tune_quick(cfg: TuneConfig) -> TuneConfig:
    """The config with its ``[tune.quick]`` settings applied (a smoke run: run folder NAME-quick).

    Raises:
      ConfigError: the quick run's test seeds meet its train seeds (the test set would not be held out).
    """
    q = cfg.quick
    ch: dict[str, Any] = {"is_quick": True}
    for k in ("population", "generations", "train_count", "test_count", "max_time"):
        if q.get(k) is not None:
            ch[k] = q[k]
    if q.get("overrides"):
        ch["overrides"] = MappingProxyType({**cfg.overrides, **q["overrides"]})
    ch["train_seeds"], ch["test_seeds"] = _quick_seeds(cfg.train_seeds, cfg.test_seeds, q)
    shared = _shared_seeds(ch["train_seeds"], ch["test_seeds"])
    if shared:  # parse_tune_config reports this too; a config built in code reaches here unchecked
        raise ConfigError([f"tune.quick.test_seeds: the quick run's test seeds must not share seeds with its train "
                           f"seeds: {shared}"], cfg.name)
    return dataclasses.replace(cfg, **ch)
