"""Study configs: a tuning config (one or more maps) plus ``[study]``, read and validated in full.

A study config is a tuning config (``[tune]`` and ``[[maps]]``, read by `jaxplan.tune.parse_tune_config` one map
at a time, so a study may span several maps) plus a ``[study]`` table::

    [study]
    methods = ["grid", "random", "cma_es", "snes", "issa", "ssa", "reinforce", "surrogate"]
    tuner_seeds = 5          # a count n (0..n-1) or a list: each method runs once per tuner seed
    budget = 160             # training-split weight-vector evaluations per method and tuner seed
    population = 16          # weight vectors per generation (budget / population generations)
    gap = "own"              # aco: "length" (the shortest path) or "own" (the planner's own cost: aco_own_objective)
    held_out_count = 16      # held-out scenario rows per map (default: the rest of the map's rows)
    options = { cma_es = { sigma = 0.3 } }
    confirm_seeds = 10       # the confirmation run (`jaxplan run`): trial seeds (count from 5000, or a list),
    confirm_count = 8        #   random start-goal pairs per map,
    confirm_scenario_seed = 1  # drawn with this seed (checked against the training rows)

    [study.quick]            # --quick: any of methods, tuner_seeds, budget, population, held_out_count,
    budget = 8               # confirm_seeds, confirm_count ([tune.quick] applies too)

The schema is declared once, as `jaxplan.experiments.schema` settings: `StudyFile` (the top level), `StudyTable`
(``[study]``) and `StudyQuickTable` (``[study.quick]``, an overlay on the resolved config:
`jaxplan.experiments.schema.overlay`); the config reference and the editors' JSON Schema are generated from them.
"""

from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

from jaxplan.core import toml
from jaxplan.core.deprecation import warn_deprecated
from jaxplan.experiments.config import MapTable, ScenarioSpec
from jaxplan.experiments.schema import ConfigError, Reader, declaration, overlay, setting
from jaxplan.tune._config import TuneConfig, TuneTable, parse_tune_config, quick_tune_config, read_toml
from jaxplan.tune._strategies import STRATEGIES, option_problems

__all__ = ["GAPS", "StudyConfig", "StudyFile", "StudyTable", "StudyQuickTable", "parse_study_config",
           "load_study_config", "quick_study_config", "apply_study_quick"]

GAPS = ("length", "own")
"""The gap metric's yardsticks of an ACO study (``study.gap``)."""


def _strategies() -> tuple[str, ...]:
    return STRATEGIES


@declaration
class StudyQuickTable:
    """What ``quick=True`` (``jaxplan study --quick``) changes besides ``[tune.quick]``: a smoke run in NAME-quick
    (every key optional)."""

    methods: tuple[str, ...] = setting("strings", None, "the methods of the quick run", choices=_strategies,
                                  overlay="set")
    tuner_seeds: Any = setting("seeds", None, "tuner seeds: a count or a list", overlay="set")
    budget: int = setting("int", None, "training evaluations per method and tuner seed", ge=2, overlay="set")
    population: int = setting("int", None, "weight vectors per generation", ge=2, overlay="set")
    held_out_count: int = setting("int", None, "held-out scenario rows per map", ge=1, overlay="set")
    confirm_seeds: Any = setting("seeds", None, "trial seeds of the confirmation run: a count (from 5000) or a "
                                  "list", overlay="set")
    confirm_count: int = setting("int", None, "random start-goal pairs per map of the confirmation run", ge=1,
                                  overlay="set")


@declaration
class StudyTable:
    """The study: which methods, how many tuner seeds, the equal training budget, the confirmation run."""

    methods: tuple[str, ...] = setting("strings", ("random", "cma_es"), "the tuning methods compared "
                                       "(`jaxplan.tune.STRATEGIES`)", choices=_strategies)
    tuner_seeds: Any = setting("seeds", 5, "tuner seeds: a count n (0..n-1) or a list; each method runs once per seed")
    budget: int = setting("int", 160, "training-split weight-vector evaluations per method and tuner seed (counted)",
                          ge=2)
    population: int = setting("int", 16, "weight vectors per generation (budget / population generations)", ge=2)
    gap: str = setting("str", "length", "aco: the gap metric's yardstick: the shortest path, or the planner's own "
                       "cost at its default weights against its exact own optimum", choices=GAPS)
    held_out_count: int = setting("int", None, "held-out scenario rows per map", ge=1,
                                  default_text="the map's rows after the training rows")
    options: Mapping[str, Any] = setting("table", doc="per method, its options: method = { option = value }")
    confirm_seeds: Any = setting("seeds", None, "trial seeds of the confirmation run (`jaxplan run`): a count or a "
                                 "list",
                                 default_text="10 seeds from 5000")
    confirm_count: int = setting("int", 8, "random start-goal pairs per map of the confirmation run", ge=1)
    confirm_scenario_seed: int = setting("int", 1, "the seed the confirmation run draws its pairs with", ge=0)
    quick: Any = setting("section", None, "what `--quick` changes", section=StudyQuickTable)


@declaration
class StudyFile:
    """A tuning study config (`jaxplan study CONFIG`): a tuning config, with one or more maps, and ``[study]``."""

    tune: Any = setting("section", None, "the tuned planner, its search box, scenarios and seeds (as in tuning "
                        "configs; its strategy, population and generations are not used)", section=TuneTable,
                        required=True)
    maps: Any = setting("tables", None, "one or more maps, as in experiment configs (the study's objective is the "
                        "mean over all their scenarios)", section=MapTable, required=True, nonempty=True)
    scenarios: Any = setting("section", None, "as in experiment configs", section=ScenarioSpec)
    study: Any = setting("section", None, "the study", section=StudyTable, required=True)


@dataclass(frozen=True)
class StudyConfig:
    """A validated study config: ``tunes`` one `TuneConfig` per map (the first one names the study), and the
    ``[study]`` settings (`StudyTable`)."""

    name: str
    description: str
    tunes: tuple[TuneConfig, ...]
    maps_raw: tuple[Mapping[str, Any], ...]
    methods: tuple[str, ...]
    tuner_seeds: tuple[int, ...]
    budget: int
    population: int
    gap: str
    held_out_count: int | None
    options: Mapping[str, Mapping[str, Any]]
    confirm_seeds: tuple[int, ...]
    confirm_count: int
    confirm_scenario_seed: int
    quick: Mapping[str, Any]
    is_quick: bool = False
    text: str = ""
    path: Path | None = None

    @property
    def generations(self) -> int:
        """Generations per run: budget / population."""
        return self.budget // self.population


def _confirm_seeds(raw: Any, read: tuple[int, ...]) -> tuple[int, ...]:
    """The confirmation seeds: a count n in the file (``raw``) means 5000..5000+n-1 (apart from the train seeds 0..
    and the held-out seeds 1000..); a list (``read``) is taken as it is."""
    return tuple(range(5000, 5000 + raw)) if isinstance(raw, int) and not isinstance(raw, bool) else tuple(read)


def parse_study_config(text: str, *, data_dir: str | os.PathLike | None = None, source: str = "config",
                       path: Path | None = None, quick: bool = False) -> StudyConfig:
    """Parses and validates a study config; with ``quick``, its ``[study.quick]`` and ``[tune.quick]`` overlays
    applied (`quick_study_config`).

    Raises:
      ConfigError: listing every problem with its key path.
    """
    raw = read_toml(text, source)
    r = Reader()
    r.section(raw, "", StudyFile)
    st = r.section(raw.get("study"), "study", StudyTable)
    quick_table = r.section(st.get("quick"), "study.quick", StudyQuickTable)
    maps = raw.get("maps")
    if not isinstance(maps, list) or not maps or not all(isinstance(m, dict) for m in maps):
        r.bad("maps", "at least one [[maps]] table is required")
        raise ConfigError(r.problems, source)
    tune_raw = {k: v for k, v in raw.items() if k != "study"}
    tunes = []
    for i, m in enumerate(maps):
        one = {**tune_raw, "maps": [m]}
        try:
            tunes.append(parse_tune_config("\n".join(f"{toml.key(k)} = {toml.literal(v)}" for k, v in one.items()),
                                           data_dir=data_dir, source=f"{source} (maps[{i}])", path=path))
        except ConfigError as e:
            r.problems += [p for p in e.problems if p not in r.problems]
    opts = st.get("options") or {}
    for k, v in opts.items():
        if not isinstance(v, dict):
            r.bad(f"study.options.{k}", f"expected a table of options, got {v!r}")
    if st["gap"] == "own" and tunes and tunes[0].kind != "aco":
        r.bad("study.gap", "'own' applies to kind = 'aco' only")
    for where, ms in (("study.methods", st["methods"]), ("study.quick.methods", quick_table.get("methods") or ())):
        for m in ms:
            if m not in STRATEGIES:
                r.bad(where, f"unknown strategy {m!r}; choose from {', '.join(STRATEGIES)}")
    if len(set(st["methods"])) != len(st["methods"]):
        r.bad("study.methods", f"a method is listed twice: {list(st['methods'])}")
    st_raw = raw.get("study") if isinstance(raw.get("study"), dict) else {}
    confirm = _confirm_seeds(st_raw.get("confirm_seeds"), st["confirm_seeds"]) if st.get("confirm_seeds") else \
        tuple(range(5000, 5010))
    qr = st_raw.get("quick") if isinstance(st_raw.get("quick"), dict) else {}
    if quick_table.get("confirm_seeds") is not None:
        quick_table["confirm_seeds"] = _confirm_seeds(qr.get("confirm_seeds"), quick_table["confirm_seeds"])
    if tunes:
        shared = sorted(set(confirm) & (set(tunes[0].train_seeds) | set(tunes[0].test_seeds)))
        if shared:
            r.bad("study.confirm_seeds", f"must not meet the train or held-out seeds: {shared}")
    if r.problems:
        raise ConfigError(r.problems, source)
    cfg = StudyConfig(name=tunes[0].name, description=tunes[0].description, tunes=tuple(tunes), maps_raw=tuple(maps),
                      methods=tuple(st["methods"]), tuner_seeds=tuple(st["tuner_seeds"]), budget=st["budget"],
                      population=st["population"], gap=st["gap"], held_out_count=st.get("held_out_count"),
                      options={k: dict(v) for k, v in opts.items()}, confirm_seeds=confirm,
                      confirm_count=st["confirm_count"], confirm_scenario_seed=st["confirm_scenario_seed"],
                      quick={k: v for k, v in quick_table.items() if v is not None}, text=text, path=path)
    _check_sizes(cfg, source)
    return quick_study_config(cfg) if quick else cfg


def _check_sizes(cfg: StudyConfig, source: str) -> None:
    problems = []
    if cfg.budget % cfg.population:
        problems.append(f"study.budget: {cfg.budget} is not a multiple of study.population ({cfg.population}): every "
                        "method must spend the same whole number of generations")
    for k in cfg.options:
        if k not in cfg.methods:
            problems.append(f"study.options.{k}: not one of study.methods")
    if not problems:
        for m in cfg.methods:
            for key, problem in option_problems(m, cfg.options.get(m, {}), cfg.population, cfg.generations):
                problems.append(f"study.options.{m}" + (f".{key}" if key else "") + f": {problem}")
    if problems:
        raise ConfigError(problems, source)


def load_study_config(path: str | os.PathLike, *, data_dir: str | os.PathLike | None = None,
                      quick: bool = False) -> StudyConfig:
    """Reads and validates the study config at ``path``; with ``quick``, its quick overlays applied.

    Raises:
      FileNotFoundError: no such file.
      ConfigError: listing every problem with its key path.
    """
    from jaxplan.experiments.config import read_config_text

    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"study config not found: {p}")
    return parse_study_config(read_config_text(p), data_dir=data_dir, source=str(p), path=p.resolve(),
                              quick=quick)


def quick_study_config(cfg: StudyConfig) -> StudyConfig:
    """The config with its ``[study.quick]`` overlay (`StudyQuickTable`) and each map's ``[tune.quick]`` overlay
    (`jaxplan.tune.quick_tune_config`) applied (a smoke run: folder NAME-quick); the options of methods the quick run
    leaves out are dropped.

    Raises:
      ConfigError: the quick sizes do not fit (budget not a multiple of the population, a method's options).
    """
    new = overlay(cfg, cfg.quick, StudyQuickTable)
    new = dataclasses.replace(new, is_quick=True, tunes=tuple(quick_tune_config(t) for t in cfg.tunes),
                              options={k: v for k, v in cfg.options.items() if k in new.methods})
    _check_sizes(new, cfg.name + " [study.quick]")
    return new


def apply_study_quick(cfg: StudyConfig) -> StudyConfig:
    """Deprecated: `quick_study_config` (or ``load_study_config(path, quick=True)``)."""
    warn_deprecated("apply_study_quick is deprecated: use load_study_config(path, quick=True) or "
                    "jaxplan.tune.quick_study_config(cfg)")
    return quick_study_config(cfg)
