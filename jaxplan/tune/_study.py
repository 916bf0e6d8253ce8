"""Tuning studies: every method against every other at an equal, counted budget, judged on held-out scenarios.

A study config is a tuning config (``[tune]`` and ``[[maps]]``, read by `load_tune_config` one map at a time,
so a study may span several maps: `concat_objectives`) plus a ``[study]`` table::

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

Budget: the objective is wrapped (`CountedObjective`) so that every weight vector a strategy has evaluated on the
training split is counted; a run whose count differs from ``budget`` is an error, and every method's count is in
the log. The gradient routes that apply to a black-box planner (``reinforce``: a score-function gradient;
``surrogate``: a quadratic model) spend exactly their population's forward evaluations per step, so one step
costs ``population`` evaluations; a differentiable objective (relaxed DWA) would be charged its forward
evaluations too (the backward pass is not counted as an evaluation).

After each generation, the held-out score of the best-so-far weights is recorded (held-out evaluations are not
charged to the budget; one evaluation per distinct weight vector, cached in ``heldout.json``).

Study folder ``OUT/NAME`` (``NAME-quick``)::

    config.toml                the study config, verbatim
    runs/<method>-s<seed>/     one `tune_loop` folder per method and tuner seed (checkpoints: exact resume),
                               with counts.json (counted evaluations and wall seconds after each generation)
    heldout.json               held-out scores by weight vector (the cache; a worker's runs keep theirs in
                               runs/<method>-s<seed>/heldout.json, read as part of it)
    worker-*.json              a worker's session (`run_study(only=...)`, ``--only``), until the page pass takes it in
    log.csv                    method, tuner_seed, generation, evaluations (counted), train_best,
                               heldout_best (held-out score of the best-so-far weights), wall_s, weights
    summary.json               per method: train and held-out scores over tuner seeds, 95 % intervals, wall time
                               (with and without XLA compilation), counted evaluations; the defaults; the verdict
    convergence.png            held-out score against evaluations, one line per method, ± sd band over tuner seeds
    best.toml                  the best weights as a ``[[planners]]`` entry (`fragment_toml`)
    confirm.toml               an experiment config: defaults vs tuned on fresh scenarios and seeds (`jaxplan run`)
    page.md                    the results page (also written to ``results/NAME.md`` with ``results``)
    sessions.json              each session's wall seconds, load averages and generations run (the page's time)
    confirm.md                 with ``confirm``: the confirmation run's report (the run itself: OUT/NAME_confirm)
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import shutil
import sys
import time
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from jaxplan.core.io import atomic_write, confined, folder_lock
from jaxplan.experiments.config import MapTable, ScenarioSpec
from jaxplan.experiments.schema import ConfigError, Reader, declaration, setting
from jaxplan.tune._base import Strategy
from jaxplan.tune._composite import aco_own_objective, check_disjoint, concat_objectives
from jaxplan.tune._config import TuneConfig, TuneTable, apply_tune_quick, parse_tune_config
from jaxplan.tune._objective import Evaluation, Objective
from jaxplan.tune._strategies import STRATEGIES, STRATEGY_SPECS, make_strategy, option_problems
from jaxplan.tune._workflow import _inline, _json_safe, _splits, _toml_value, fragment_toml, tune_loop

__all__ = ["StudyConfig", "load_study_config", "parse_study_config", "apply_study_quick", "CountedObjective",
           "build_study_objective", "run_study", "confirm_config", "GAPS", "StudyFile", "StudyTable",
           "StudyQuickTable"]

GAPS = ("length", "own")


def _strategies() -> tuple[str, ...]:
    return STRATEGIES


@declaration
class StudyQuickTable:
    """What ``quick=True`` (``jaxplan study --quick``) changes besides ``[tune.quick]``: a smoke run in NAME-quick
    (every key optional)."""

    methods: tuple[str, ...] = setting("strings", None, "the methods of the quick run", choices=_strategies)
    tuner_seeds: Any = setting("seeds", None, "tuner seeds: a count or a list")
    budget: int = setting("int", None, "training evaluations per method and tuner seed", ge=2)
    population: int = setting("int", None, "weight vectors per generation", ge=2)
    held_out_count: int = setting("int", None, "held-out scenario rows per map", ge=1)
    confirm_seeds: Any = setting("seeds", None, "trial seeds of the confirmation run: a count (from 5000) or a list")
    confirm_count: int = setting("int", None, "random start-goal pairs per map of the confirmation run", ge=1)


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


def _dump(v: Any) -> str:
    """TOML for a parsed value (tables inline)."""
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{json.dumps(k)} = {_dump(x)}" for k, x in v.items()) + " }"
    if isinstance(v, list):
        return "[" + ", ".join(_dump(x) for x in v) + "]"
    return _toml_value(v)


def _confirm_seeds(raw: Any, read: tuple[int, ...]) -> tuple[int, ...]:
    """The confirmation seeds: a count n in the file (``raw``) means 5000..5000+n-1 (apart from the train seeds 0..
    and the held-out seeds 1000..); a list (``read``) is taken as it is."""
    return tuple(range(5000, 5000 + raw)) if isinstance(raw, int) and not isinstance(raw, bool) else tuple(read)


def parse_study_config(text: str, *, data_dir: str | os.PathLike | None = None, source: str = "config",
                       path: Path | None = None) -> StudyConfig:
    """Parses and validates a study config. Raises `ConfigError` listing every problem with its key path."""
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ConfigError([f"not valid TOML: {e}"], source) from None
    r = Reader()
    r.section(raw, "", StudyFile)
    st = r.section(raw.get("study"), "study", StudyTable)
    quick = r.section(st.get("quick"), "study.quick", StudyQuickTable)
    maps = raw.get("maps")
    if not isinstance(maps, list) or not maps or not all(isinstance(m, dict) for m in maps):
        r.bad("maps", "at least one [[maps]] table is required")
        raise ConfigError(r.problems, source)
    tune_raw = {k: v for k, v in raw.items() if k != "study"}
    tunes = []
    for i, m in enumerate(maps):
        one = {**tune_raw, "maps": [m]}
        try:
            tunes.append(parse_tune_config("\n".join(f"{json.dumps(k)} = {_dump(v)}" for k, v in one.items()),
                                           data_dir=data_dir, source=f"{source} (maps[{i}])", path=path))
        except ConfigError as e:
            r.problems += [p for p in e.problems if p not in r.problems]
    opts = st.get("options") or {}
    for k, v in opts.items():
        if not isinstance(v, dict):
            r.bad(f"study.options.{k}", f"expected a table of options, got {v!r}")
    if st["gap"] == "own" and tunes and tunes[0].kind != "aco":
        r.bad("study.gap", "'own' applies to kind = 'aco' only")
    for where, ms in (("study.methods", st["methods"]), ("study.quick.methods", quick.get("methods") or ())):
        for m in ms:
            if m not in STRATEGIES:
                r.bad(where, f"unknown strategy {m!r}; choose from {', '.join(STRATEGIES)}")
    if len(set(st["methods"])) != len(st["methods"]):
        r.bad("study.methods", f"a method is listed twice: {list(st['methods'])}")
    st_raw = raw.get("study") if isinstance(raw.get("study"), dict) else {}
    confirm = _confirm_seeds(st_raw.get("confirm_seeds"), st["confirm_seeds"]) if st.get("confirm_seeds") else \
        tuple(range(5000, 5010))
    qr = st_raw.get("quick") if isinstance(st_raw.get("quick"), dict) else {}
    if quick.get("confirm_seeds") is not None:
        quick["confirm_seeds"] = _confirm_seeds(qr.get("confirm_seeds"), quick["confirm_seeds"])
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
                      quick={k: v for k, v in quick.items() if v is not None}, text=text, path=path)
    _check_sizes(cfg, source)
    return cfg


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


def load_study_config(path: str | os.PathLike, *, data_dir: str | os.PathLike | None = None) -> StudyConfig:
    """Reads and validates the study config at ``path`` (`ConfigError` lists every problem)."""
    from jaxplan.experiments.config import read_config_text

    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"study config not found: {p}")
    return parse_study_config(read_config_text(p), data_dir=data_dir, source=str(p), path=p.resolve())


def apply_study_quick(cfg: StudyConfig) -> StudyConfig:
    """The config with its ``[study.quick]`` and ``[tune.quick]`` settings applied (folder NAME-quick)."""
    q = cfg.quick
    ch: dict[str, Any] = {"is_quick": True, "tunes": tuple(apply_tune_quick(t) for t in cfg.tunes)}
    for k in ("budget", "population", "held_out_count"):
        if q.get(k) is not None:
            ch[k] = q[k]
    if q.get("methods") is not None:
        ch["methods"] = tuple(q["methods"])
        ch["options"] = {k: v for k, v in cfg.options.items() if k in ch["methods"]}
    if q.get("tuner_seeds") is not None:
        ch["tuner_seeds"] = tuple(q["tuner_seeds"])
    if q.get("confirm_seeds") is not None:
        ch["confirm_seeds"] = tuple(q["confirm_seeds"])
    if q.get("confirm_count") is not None:
        ch["confirm_count"] = q["confirm_count"]
    new = dataclasses.replace(cfg, **ch)
    _check_sizes(new, cfg.name + " [study.quick]")
    return new


# ---------------------------------------------------------------------------------------------
# The objective


class CountedObjective:
    """An `Objective` whose training-split evaluations are counted (rows of every population evaluated).

    Everything else is the wrapped objective's; ``count`` is the number of weight vectors evaluated on ``"train"``
    through this wrapper (held-out evaluations go to the objective itself and are not charged)."""

    def __init__(self, objective: Objective):
        self.objective = objective
        self.count = 0

    def evaluate(self, pop, split: str = "train") -> Evaluation:
        ev = self.objective.evaluate(pop, split)
        if split == "train":
            self.count += int(np.atleast_2d(np.asarray(pop)).shape[0])
        return ev

    def __getattr__(self, name: str) -> Any:
        return getattr(self.objective, name)


def build_study_objective(cfg: StudyConfig) -> Objective:
    """The study's `Objective`: each map's (train and held-out split disjoint, checked), joined over the maps.

    Raises:
      ValueError: a map whose train and held-out splits share seeds or a (start, goal) row.
    """
    from jaxplan.experiments import load_map_spec, spec_scenarios
    from jaxplan.tune._workflow import build_objective

    t0 = cfg.tunes[0]
    if t0.kind == "nav":
        # One navigation objective over every map: its `evaluate` runs the maps one compiled call each (a join of
        # per-map objectives would evaluate the first map's episodes only); it checks rows and seeds disjoint.
        t = dataclasses.replace(t0, maps=tuple(m for one in cfg.tunes for m in one.maps),
                                test_count=cfg.held_out_count if cfg.held_out_count is not None else t0.test_count)
        return dataclasses.replace(build_objective(t), name=cfg.name, _compiled={})
    objs = []
    for t in cfg.tunes:
        if cfg.held_out_count is not None:
            t = dataclasses.replace(t, test_count=cfg.held_out_count)
        grid, s0, g0, _ = load_map_spec(t.map)
        starts, goals, optimal, _ = spec_scenarios(t.map, grid, s0, g0)
        train, test = _splits(t, grid, starts, goals, optimal)
        check_disjoint(train, test, t.map.name)
        if cfg.gap == "own":
            space = {k: (list(v) if isinstance(v, list) else tuple(v)) for k, v in t.space.items()}
            o = aco_own_objective(grid, train, test, t.planner, space, dict(t.weights), dict(t.overrides),
                                  name=f"{cfg.name}:{t.map.name}")
        else:
            o = dataclasses.replace(build_objective(t), name=f"{cfg.name}:{t.map.name}")
        objs.append(o)
    return concat_objectives(objs, name=cfg.name)


# ---------------------------------------------------------------------------------------------
# Running


def _key(x) -> str:
    return np.asarray(x, "<f4").tobytes().hex()


class _HeldOut:
    """Held-out scores by weight vector: evaluated in padded chunks of ``chunk`` rows (one compiled program),
    cached in ``path`` (JSON); the caches in ``read`` (other processes' files) are read too, never written."""

    def __init__(self, objective: Objective, path: Path, chunk: int, read: Sequence[Path] = ()):
        self.objective, self.path, self.chunk = objective, path, chunk
        self.cache: dict[str, dict] = {}
        for f in (*read, path):
            if f.is_file():
                try:
                    self.cache.update(json.loads(f.read_text()))
                except ValueError:  # a damaged cache only costs its evaluations again
                    pass
        self.seconds = 0.0

    def scores(self, xs: list[np.ndarray]) -> list[dict]:
        todo = list(dict.fromkeys(_key(x) for x in xs if _key(x) not in self.cache))
        if todo:
            t0 = time.perf_counter()
            vecs = [np.frombuffer(bytes.fromhex(k), "<f4") for k in todo]
            for i in range(0, len(vecs), self.chunk):
                part = vecs[i:i + self.chunk]
                pop = np.stack(part + [part[-1]] * (self.chunk - len(part)))
                ev = self.objective.evaluate(pop, "test")
                for j, k in enumerate(todo[i:i + len(part)]):
                    self.cache[k] = {"fitness": float(ev.fitness[j]), "per_seed": [float(v) for v in ev.per_seed[j]],
                                     "metrics": {m: float(v[j]) for m, v in ev.metrics.items()}}
            atomic_write(self.path, json.dumps(_json_safe(self.cache)).encode())
            self.seconds += time.perf_counter() - t0
        return [self.cache[_key(x)] for x in xs]


def _run_one(cfg: StudyConfig, objective: Objective, method: str, strategy: Strategy, seed: int, folder: Path,
             progress: bool, resume: bool) -> dict:
    """One method with one tuner seed: `tune_loop` on the counted objective; returns rows, counts, wall times."""
    counted = CountedObjective(objective)
    fp = hashlib.sha256(cfg.text.encode() + f"|{cfg.is_quick}|{method}|{seed}".encode()).hexdigest()
    folder.mkdir(parents=True, exist_ok=True)
    counts_path = folder / "counts.json"
    saved = json.loads(counts_path.read_text()) if (resume and counts_path.is_file()) else {"evaluations": [],
                                                                                            "wall_s": []}
    state = {"first": None, "t": time.perf_counter()}
    evals: list[int] = []
    walls: list[float] = []

    def callback(g: int, row: dict) -> None:
        if state["first"] is None:  # the first generation of this session: the earlier ones are in `saved`
            state["first"] = g
            evals[:] = saved["evaluations"][:g - 1]
            walls[:] = saved["wall_s"][:g - 1]
            state["base_e"] = evals[-1] if evals else 0
            state["base_w"] = walls[-1] if walls else 0.0
        now = time.perf_counter()
        evals.append(state["base_e"] + counted.count)
        walls.append(state["base_w"] + now - state["t0"])
        atomic_write(counts_path, json.dumps({"evaluations": evals, "wall_s": walls}).encode())

    state["t0"] = time.perf_counter()
    res = tune_loop(counted, strategy, cfg.generations, folder, seed=seed, checkpoint_every=1, resume=resume,
                    progress=progress, fingerprint=fp, callback=callback)
    if state["first"] is None:  # every generation was already done
        evals, walls = saved["evaluations"][:cfg.generations], saved["wall_s"][:cfg.generations]
    if len(evals) != cfg.generations or evals[-1] != cfg.budget:
        raise RuntimeError(f"{folder.name}: counted {evals[-1] if evals else 0} training evaluations in "
                           f"{len(evals)} generations; the budget is {cfg.budget} in {cfg.generations}")
    return {"rows": res["rows"], "evaluations": evals, "wall_s": walls, "compile_s": _compile_seconds(folder),
            "best_x": np.asarray(res["best_x"]),
            "best_f": res["best_f"], "new": cfg.generations - res["resumed_from"]}


def _compile_seconds(run_dir: Path) -> float:
    """Seconds of XLA compilation inside a run's evaluations (`tune_loop`'s timings.csv, every generation): a
    process compiles once, in whichever run comes first, so it is taken out of the wall times compared."""
    lines = (run_dir / "timings.csv").read_text().splitlines()[1:]
    return float(sum(float(x.split(",")[2]) for x in lines if x))


def _read_sessions(folder: Path) -> list[dict]:
    """The study's earlier sessions (``sessions.json``) and its workers' (``worker-*.json``, each entry once); a
    folder from before sessions.json takes its first session from summary.json."""
    path = folder / "sessions.json"
    out: list[dict] = []
    if path.is_file():
        out = json.loads(path.read_text())
    elif (folder / "summary.json").is_file():
        old = json.loads((folder / "summary.json").read_text())
        out = [{"wall_s": old.get("wall_s_this_session", 0.0), "loadavg_start": old.get("loadavg_start"),
                "loadavg_end": old.get("loadavg_end"), "generations": None}]
    seen = {s.get("worker") for s in out}
    for f in sorted(folder.glob("worker-*.json")):
        entry = json.loads(f.read_text())
        if entry.get("worker") not in seen:
            out.append(entry)
    return out


def _session_entry(wall: float, load0, generations: int) -> dict:
    """A session's wall seconds, load averages, generations run, the process's niceness and the cores it could
    use."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return {"wall_s": wall, "loadavg_start": list(load0), "loadavg_end": list(os.getloadavg()),
            "generations": generations, "nice": os.nice(0), "cores": cores}


def _sessions(folder: Path, earlier: list[dict], wall: float, load0, generations: int) -> list[dict]:
    """``earlier`` sessions with this one (so far) appended (`_session_entry`), written to ``sessions.json``.
    Written after every run, so a session that is interrupted still counts the time of the runs it finished; the
    workers' files it took in are then removed (their entries live on in sessions.json)."""
    sessions = earlier + [_session_entry(wall, load0, generations)]
    atomic_write(folder / "sessions.json", json.dumps(sessions, indent=1).encode())
    for f in folder.glob("worker-*.json"):
        if any(s.get("worker") == f.stem for s in earlier):
            f.unlink(missing_ok=True)
    return sessions


def _t95(n: int) -> float:
    from scipy.stats import t

    return float(t.ppf(0.975, n - 1)) if n > 1 else math.nan


def _stats(v) -> dict:
    v = np.asarray(v, np.float64)
    n = len(v)
    sd = float(v.std(ddof=1)) if n > 1 else math.nan
    hw = _t95(n) * sd / math.sqrt(n) if n > 1 else math.nan
    return {"mean": float(v.mean()), "sd": sd, "ci95": [float(v.mean() - hw), float(v.mean() + hw)], "n": n}


def run_study(config_path, out="runs", quick: bool = False, data_dir=None, progress: bool = True,
              resume: bool = True, results: str | os.PathLike | None = None, confirm: bool = False,
              only: Sequence[str] | None = None) -> Path:
    """Runs (or resumes) the study config at ``config_path``; returns its folder ``OUT/NAME`` (``NAME-quick``).

    Every method runs once per tuner seed with the same counted budget; then the log, summary, figure,
    best.toml, confirm.toml and page.md are written (module docstring). With ``results``, the page, figure,
    best.toml and confirm.toml are copied to ``results/NAME.md``, ``NAME.png``, ``NAME_best.toml`` and
    ``NAME_confirm.toml``. With ``confirm``, the confirmation experiment then runs (`jaxplan run` of confirm.toml,
    into ``OUT/NAME_confirm``) and its report becomes ``confirm.md`` (and ``results/NAME_confirm.md``).

    With ``only`` (method names), this process is a worker: it runs (or resumes) those methods' runs alone, each
    under its own run folder's lock and with its held-out scores in that folder, and writes nothing else, so
    workers with disjoint methods share one study folder (one per core or machine). A later call without
    ``only`` finds their runs done, reads their held-out scores and writes the page.

    Raises:
      ValueError: ``only`` names a method the study does not run, or is combined with ``resume=False`` (a fresh
        start would delete the other workers' runs) or ``confirm``.
    """
    cfg = load_study_config(config_path, data_dir=data_dir)
    if quick:
        cfg = apply_study_quick(cfg)
    if only is not None:
        bad = sorted(set(only) - set(cfg.methods))
        if bad or not only:
            what = f"{', '.join(bad)} not among" if bad else "give at least one of"
            raise ValueError(f"only: {what} the study's methods ({', '.join(cfg.methods)})")
        if not resume or confirm:
            raise ValueError("only (a worker) resumes and runs its methods' runs alone: not with a fresh start "
                             "(it would delete the other workers' runs) or the confirmation")
    objective = build_study_objective(cfg)
    objective.check_population(cfg.population)
    objective.check_population(cfg.population, "test")
    folder = confined(out, cfg.name + ("-quick" if cfg.is_quick else ""))
    folder.mkdir(parents=True, exist_ok=True)
    if only is not None:
        _run_worker(cfg, objective, folder, [m for m in cfg.methods if m in set(only)], progress)
        return folder
    with folder_lock(folder):
        _run_study(cfg, objective, folder, progress, resume, results, data_dir)
    if confirm:
        _confirm(cfg, folder, out, results, data_dir, progress)
    return folder


def _confirm(cfg: StudyConfig, folder: Path, out, results, data_dir, progress: bool) -> Path:
    """Runs the study's confirm.toml with `run_experiment` and writes its page (the run's report, introduced)."""
    from jaxplan.experiments import run_experiment

    t0 = time.perf_counter()
    load = os.getloadavg()
    run = run_experiment(folder / "confirm.toml", out, data_dir=data_dir, progress=progress)
    wall = time.perf_counter() - t0
    report = (run / "report.md").read_text()
    chunks = json.loads((run / "checkpoints" / "manifest.json").read_text())["chunks"].values()
    calls = sum(float(c.get("compile_s", 0.0)) + float(c.get("time_s", 0.0)) for c in chunks)
    head = [f"# Confirmation of tuning study `{cfg.name}`", "",
            f"The defaults against the tuned weights of [{cfg.name}]({cfg.name}.md) (`{cfg.name}_best.toml`) with "
            f"`jaxplan run {cfg.name}_confirm.toml` on fresh random start-goal pairs and trial seeds "
            f"{list(cfg.confirm_seeds)} (neither the tuner nor the held-out split saw them; checked). Regenerate: "
            f"`jaxplan study {_rel(cfg.path)} --results docs/results/tuning --confirm` (the study resumes from its "
            f"checkpoints); the confirmation run's batched calls took {calls:.0f} s (compilation included; "
            f"this session {wall:.0f} s wall, load average {', '.join(f'{v:.2f}' for v in load)} at its start; a "
            "finished run is only read again).", "",
            "The run's report follows.", ""]
    body = report.split("\n", 1)[1] if report.startswith("# ") else report
    if cfg.gap == "own":
        head += own_gap_table(cfg, run, data_dir) + [""]
    text = "\n".join(head) + body.replace("\n# ", "\n## ")
    atomic_write(folder / "confirm.md", text.encode())
    if results is not None:
        atomic_write(Path(results) / f"{cfg.name}_confirm.md", text.encode())
    return run


def _run_study(cfg: StudyConfig, objective: Objective, folder: Path, progress: bool, resume: bool,
               results, data_dir) -> Path:
    t_start = time.perf_counter()
    load0 = os.getloadavg()
    atomic_write(folder / "config.toml", cfg.text.encode())
    if not resume:
        for p in (folder / "runs", folder / "heldout.json", folder / "sessions.json", folder / "summary.json",
                  *folder.glob("worker-*.json")):
            shutil.rmtree(p, ignore_errors=True) if p.is_dir() else p.unlink(missing_ok=True)
    held = _HeldOut(objective, folder / "heldout.json", cfg.population,
                    read=sorted(folder.glob(f"runs/*/{HELDOUT_FILE}")))
    names = list(objective.bounds.names)
    earlier = _read_sessions(folder)
    runs: dict[tuple[str, int], dict] = {}
    for m in cfg.methods:
        for _ in _method_runs(cfg, objective, m, folder, progress, resume, lambda _run_dir: held, runs):
            _sessions(folder, earlier, time.perf_counter() - t_start, load0, sum(x["new"] for x in runs.values()))
    counts = {m: sorted({runs[(m, s)]["evaluations"][-1] for s in cfg.tuner_seeds}) for m in cfg.methods}
    if any(c != [cfg.budget] for c in counts.values()):
        raise RuntimeError(f"unequal budgets (counted): {counts}")
    d = objective.defaults
    d_test = held.scores([d])[0]
    d_train = objective.evaluate(np.stack([d] * cfg.population), "train")  # not charged: not part of a search
    wall = time.perf_counter() - t_start
    sessions = _sessions(folder, earlier, wall, load0, sum(r["new"] for r in runs.values()))
    summary = _summary(cfg, objective, runs, d_train, d_test, held, wall, load0)
    summary["sessions"] = sessions
    summary["wall_s_total"] = sum(x["wall_s"] for x in sessions)
    atomic_write(folder / "log.csv", _log_csv(cfg, runs, names).encode())
    atomic_write(folder / "summary.json", json.dumps(_json_safe(summary), indent=1, allow_nan=False).encode())
    _figure(cfg, runs, d_test["fitness"], folder / "convergence.png")
    best_m, best_s = summary["best"]["method"], summary["best"]["tuner_seed"]
    bx = runs[(best_m, best_s)]["best_x"]
    t0 = cfg.tunes[0]
    comment = (f"best weights of study {cfg.name}: {best_m}, tuner seed {best_s}, {cfg.budget} counted training "
               f"evaluations\nheld-out cost {summary['best']['heldout']:.6g}; defaults {d_test['fitness']:.6g}")
    frag = fragment_toml(objective, bx, label=f"{t0.planner.upper()} (tuned)", overrides=dict(t0.overrides),
                         pipeline=t0.pipeline, comment=comment)
    atomic_write(folder / "best.toml", frag.encode())
    dflt = None if t0.kind == "aco" else fragment_toml(objective, objective.defaults, label=f"{t0.planner} (defaults)",
                                                        overrides=dict(t0.overrides), pipeline=t0.pipeline)
    confirm = confirm_config(cfg, frag, data_dir, dflt)
    atomic_write(folder / "confirm.toml", confirm.encode())
    page = _page(cfg, summary, frag, results)
    atomic_write(folder / "page.md", page.encode())
    if results is not None:
        res = Path(results)
        res.mkdir(parents=True, exist_ok=True)
        atomic_write(res / f"{cfg.name}.md", page.encode())
        shutil.copyfile(folder / "convergence.png", res / f"{cfg.name}.png")
        atomic_write(res / f"{cfg.name}_best.toml", frag.encode())
        atomic_write(res / f"{cfg.name}_confirm.toml", confirm.encode())
    return folder


HELDOUT_FILE = "heldout.json"
"""A worker's run keeps the held-out scores of its best-so-far weights here, in its own folder."""


def _method_runs(cfg: StudyConfig, objective: Objective, m: str, folder: Path, progress: bool, resume: bool,
                 held_for, runs: dict):
    """Runs (or resumes) method ``m`` for every tuner seed into ``runs``, scoring each run's best-so-far weights
    on the held-out split with ``held_for(run_dir)``; yields ``(seed, run)`` after each."""
    names = list(objective.bounds.names)
    # One strategy serves every tuner seed: its ask and tell are then the same functions, so JAX compiles
    # them once per study instead of once per run (each compile also maps more code into the process).
    strategy = make_strategy(m, cfg.population, cfg.generations, **cfg.options.get(m, {}))
    first = cfg.tuner_seeds[0]
    for s in cfg.tuner_seeds:
        if s != first and not STRATEGY_SPECS[m].uses_key:
            # Its proposals do not depend on the key and the objective is deterministic, so this seed's run
            # would repeat the first one evaluation for evaluation: the first stands for it, wall times too.
            runs[(m, s)] = dict(runs[(m, first)], new=0, same_as_seed=first)
            continue
        run_dir = folder / "runs" / f"{m}-s{s}"
        run_dir.mkdir(parents=True, exist_ok=True)
        with folder_lock(run_dir):  # a worker may hold it (`run_study(only=...)`)
            r = _run_one(cfg, objective, m, strategy, s, run_dir, progress, resume)
            xs = [np.array([row[n] for n in names], np.float32) for row in r["rows"]]
            r["heldout"] = [h["fitness"] for h in held_for(run_dir).scores(xs)]
        runs[(m, s)] = r
        yield s, r


def _run_worker(cfg: StudyConfig, objective: Objective, folder: Path, methods: list[str], progress: bool) -> None:
    """`run_study` with ``only``: these methods' runs, each run's held-out scores in its own folder."""
    atomic_write(folder / "config.toml", cfg.text.encode())
    shared = [folder / "heldout.json"]
    t0, load0 = time.perf_counter(), os.getloadavg()
    me = f"worker-{os.getpid()}-{int(time.time())}"

    def held_for(run_dir: Path) -> _HeldOut:
        return _HeldOut(objective, run_dir / HELDOUT_FILE, cfg.population, read=shared)

    runs: dict[tuple[str, int], dict] = {}
    for m in methods:
        for s, r in _method_runs(cfg, objective, m, folder, progress, True, held_for, runs):
            entry = _session_entry(time.perf_counter() - t0, load0, sum(x["new"] for x in runs.values()))
            atomic_write(folder / f"{me}.json", json.dumps({**entry, "worker": me, "methods": methods}).encode())
            print(f"{cfg.name}: {m}-s{s} done ({r['evaluations'][-1]} counted evaluations)", file=sys.stderr,
                  flush=True)


def _log_csv(cfg: StudyConfig, runs: dict, names: list[str]) -> str:
    cols = ["method", "tuner_seed", "generation", "evaluations", "train_best", "heldout_best", "wall_s"] + names
    lines = [",".join(cols)]
    for (m, s), r in runs.items():
        for i, row in enumerate(r["rows"]):
            vals = [m, s, row["generation"], r["evaluations"][i], repr(float(row["best"])), repr(r["heldout"][i]),
                    f"{r['wall_s'][i]:.3f}"] + [repr(float(row[n])) for n in names]
            lines.append(",".join(map(str, vals)))
    return "\n".join(lines) + "\n"


def _summary(cfg, objective, runs, d_train, d_test, held, wall, load0) -> dict:
    methods = {}
    for m in cfg.methods:
        rs = [runs[(m, s)] for s in cfg.tuner_seeds]
        methods[m] = {
            "train": _stats([r["best_f"] for r in rs]),
            "heldout": _stats([r["heldout"][-1] for r in rs]),
            "wall_s": _stats([r["wall_s"][-1] for r in rs]),
            "compile_s": _stats([r["compile_s"] for r in rs]),
            "run_s": _stats([r["wall_s"][-1] - r["compile_s"] for r in rs]),
            "evaluations": rs[0]["evaluations"][-1],
            "per_seed": {str(s): {"train": runs[(m, s)]["best_f"], "heldout": runs[(m, s)]["heldout"][-1],
                                  "weights": objective.params(runs[(m, s)]["best_x"])} for s in cfg.tuner_seeds},
        }
    ps = np.asarray(d_test["per_seed"], np.float64)
    R = len(ps)
    d_hw = _t95(R) * ps.std(ddof=1) / math.sqrt(R) if R > 1 else math.nan
    best_m = min(cfg.methods, key=lambda m: methods[m]["heldout"]["mean"])
    best_s = min(cfg.tuner_seeds, key=lambda s: runs[(best_m, s)]["best_f"])  # chosen by its TRAIN score
    bm = methods[best_m]["heldout"]
    hi = bm["ci95"][1] if math.isfinite(bm["ci95"][1]) else bm["mean"]
    lo_d = d_test["fitness"] - (d_hw if math.isfinite(d_hw) else 0.0)
    verdict = "beats" if hi < lo_d else ("worse" if bm["mean"] > d_test["fitness"] else "within")
    kinds = len(getattr(objective, "walkers", ())) or 1  # a navigation objective runs every row among each kind
    return {
        "name": cfg.name, "description": cfg.description, "quick": cfg.is_quick, "kind": cfg.tunes[0].kind,
        "planner": cfg.tunes[0].planner, "gap": cfg.gap, "methods_order": list(cfg.methods),
        "tuner_seeds": list(cfg.tuner_seeds), "budget": cfg.budget, "population": cfg.population,
        "generations": cfg.generations,
        "space": {n: [float(lo), float(hi_)] for n, lo, hi_ in zip(objective.bounds.names, objective.bounds.low,
                                                                   objective.bounds.high, strict=True)},
        "metric_weights": dict(objective.weights),
        "maps": [{"name": t.map.name, "train_rows": int(min(t.train_count, 10**9)),
                  "train_seeds": list(t.train_seeds), "heldout_seeds": list(t.test_seeds)} for t in cfg.tunes],
        "train_runs": int(len(objective.splits["train"].starts) * len(objective.splits["train"].seeds) * kinds),
        "heldout_runs": int(len(objective.splits["test"].starts) * len(objective.splits["test"].seeds) * kinds),
        "train_rows": int(len(objective.splits["train"].starts)),
        "heldout_rows": int(len(objective.splits["test"].starts)),
        "defaults": {"weights": objective.params(objective.defaults), "train": float(d_train.fitness[0]),
                     "heldout": d_test["fitness"], "heldout_per_seed": d_test["per_seed"],
                     "heldout_ci95_halfwidth": d_hw, "heldout_metrics": d_test["metrics"]},
        "methods": methods,
        "best": {"method": best_m, "tuner_seed": best_s, "heldout": runs[(best_m, best_s)]["heldout"][-1],
                 "train": runs[(best_m, best_s)]["best_f"],
                 "heldout_metrics": held.scores([runs[(best_m, best_s)]["best_x"]])[0]["metrics"],
                 "weights": objective.params(runs[(best_m, best_s)]["best_x"])},
        "verdict": verdict,
        "compile_s_total": float(sum(r["compile_s"] for r in runs.values() if "same_as_seed" not in r)),
        "wall_s_this_session": wall, "heldout_eval_s_this_session": held.seconds,
        "loadavg_start": list(load0), "loadavg_end": list(os.getloadavg()),
    }


def _figure(cfg: StudyConfig, runs: dict, defaults: float, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from jaxplan.experiments.plots import save_figure

    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for i, m in enumerate(cfg.methods):
        ev = np.asarray(runs[(m, cfg.tuner_seeds[0])]["evaluations"], np.float64)
        h = np.asarray([runs[(m, s)]["heldout"] for s in cfg.tuner_seeds], np.float64)
        mean = h.mean(axis=0)
        sd = h.std(axis=0, ddof=1) if len(h) > 1 else np.zeros_like(mean)
        (line,) = ax.plot(ev, mean, lw=1.6, color=f"C{i % 10}", label=m)
        ax.fill_between(ev, mean - sd, mean + sd, color=line.get_color(), alpha=0.15, lw=0)
    ax.axhline(defaults, color="k", ls="--", lw=1.0, label="defaults")
    ax.set_xlabel("training evaluations (weight vectors, counted)")
    ax.set_ylabel("held-out cost of best-so-far weights (lower is better)")
    ax.set_title(f"{cfg.name}: mean ± sd over {len(cfg.tuner_seeds)} tuner seeds")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    save_figure(fig, str(path))
    plt.close(fig)


def confirm_config(cfg: StudyConfig, fragment: str, data_dir: str | os.PathLike | None = None,
                   defaults: str | None = None) -> str:
    """An experiment config (`jaxplan run`): the defaults against the tuned ``fragment`` on every map of the study,
    on ``confirm_count`` fresh random start-goal pairs per map (``confirm_scenario_seed``) and ``confirm_seeds``.

    ``defaults`` is the defaults' ``[[planners]]`` entry (`fragment_toml` of the objective's defaults); None: the
    planner by name with the study's overrides (an ACO planner). Navigation kinds are confirmed on the episode
    metrics (success, time, collisions, path length); a navigation study's entries are repeated once per walker
    kind, with its walkers (`_nav_entries`).

    Raises:
      ValueError: a confirmation pair that is one of the study's training rows, or seeds that meet the training
        or held-out seeds.
    """
    from jaxplan.experiments import load_map_spec, spec_scenarios
    from jaxplan.experiments.config import parse_config
    from jaxplan.tune._objective import Split

    t0 = cfg.tunes[0]
    shared = sorted(set(cfg.confirm_seeds) & (set(t0.train_seeds) | set(t0.test_seeds)))
    if shared:
        raise ValueError(f"confirm_seeds meet the study's train or held-out seeds: {shared}")
    if t0.kind == "nav":
        defaults, fragment = _nav_entries(defaults or "", t0), "\n" + _nav_entries(fragment, t0)
    lines = [f"# Confirmation of study {cfg.name}: the defaults against the tuned weights (best.toml) on fresh random",
             f"# start-goal pairs (scenario seed {cfg.confirm_scenario_seed}, checked against the training rows) and "
             "trial seeds", "# that neither the tuner nor the held-out split used. Written by `jaxplan study`.", "",
             'metrics = ["success", "length", "optimality_gap", "turns", "smoothness", "plan_time_s"]', "",
             "[experiment]", f'name = "{cfg.name}_confirm"',
             f'description = "defaults vs tuned {t0.planner} weights of study {cfg.name}, on fresh scenarios"',
             f"seeds = {_toml_value(list(cfg.confirm_seeds))}", ""]
    for m in cfg.maps_raw:
        entry = {k: v for k, v in m.items() if k != "scenarios"}
        scen = {"source": "random", "count": cfg.confirm_count, "seed": cfg.confirm_scenario_seed,
                "min_distance": float(m.get("scenarios", {}).get("min_distance", 8.0))}
        for k in ("min_clearance",):
            if k in m.get("scenarios", {}):
                scen[k] = m["scenarios"][k]
        entry["scenarios"] = scen
        lines.append("[[maps]]")
        lines += [f"{k} = {_dump(v)}" for k, v in entry.items()]
        lines.append("")
    ov = dict(t0.overrides)
    if defaults is None:
        lines += ["[[planners]]", f'label = "{t0.planner.upper()} (defaults)"', 'kind = "plan"',
                  f"name = {_toml_value(t0.planner)}"] + ([f"overrides = {_inline(ov)}"] if ov else []) + [""]
    else:
        lines += [defaults]
    tested = '["success", "length", "optimality_gap", "turns"]' if t0.kind == "aco" else \
        '["success", "time_s", "collisions", "path_length"]'
    if t0.kind != "aco":
        lines = [ln if not ln.startswith("metrics = ") else f"metrics = {tested}" for ln in lines]
    text = "\n".join(lines) + fragment + f"\n[stats]\nanova = false\npairwise = true\nmetrics = {tested}\n"
    exp = parse_config(text, data_dir=data_dir, source=f"{cfg.name}_confirm")
    for spec, t in zip(exp.maps, cfg.tunes, strict=True):  # fresh pairs: none may be a training row
        grid, s0, g0, _ = load_map_spec(spec)
        starts, goals, optimal, _ = spec_scenarios(spec, grid, s0, g0)
        gridt, st0, gt0, _ = load_map_spec(t.map)
        ts, tg, topt, _ = spec_scenarios(t.map, gridt, st0, gt0)
        train, _ = _splits(t, gridt, ts, tg, topt)
        check_disjoint(train, Split(starts, goals, optimal, tuple(cfg.confirm_seeds)), f"confirmation, {spec.name}")
    return text


def _nav_entries(block: str, t: TuneConfig) -> str:
    """A navigation ``[[planners]]`` entry once per walker kind of ``t``: labelled with the kind, with the study's
    walkers (`nav_objective`'s: their count, speed, 0.25 m radius, `AVOID_RADIUS` from start and goal) and its
    episode length (``nav.max_time``)."""
    from jaxplan.tune._nav_objective import AVOID_RADIUS, WALKER_KINDS

    out = []
    for kind in t.walkers:
        obs = {"n": t.walker_count, "speed": t.walker_speed, "radius": 0.25, "avoid_radius": AVOID_RADIUS,
               "behavior": WALKER_KINDS[kind]}
        lines = []
        for ln in block.strip("\n").splitlines():
            if ln.startswith("label = "):
                ln = f"label = {_toml_value(tomllib.loads(ln)['label'] + f', {kind} walkers')}"
            lines.append(ln)
        lines += [f"obstacles = {_inline(obs)}", f"nav = {_inline({'max_time': t.max_time})}"]
        out.append("\n".join(lines) + "\n")
    return "\n".join(out)


def own_gap_table(cfg: StudyConfig, run: Path, data_dir=None) -> list[str]:
    """Markdown lines: the confirmation run's own-objective gap at the DEFAULT weights, per map and planner.

    The run's own ``objective_gap`` metric would cost each planner's paths with that planner's weights (the tuned
    λ for the tuned entry); the study's yardstick is the default-weight cost, so it is computed here from the run's
    stored paths (`jaxplan.search.path_objectives` over `jaxplan.search.exact_objectives`). Per seed the mean over
    the successful trials, then mean ± sd over seeds; Welch's t-test between the two planners per map."""
    from scipy.stats import ttest_ind

    from jaxplan.experiments import load_chunk_arrays, load_map_spec
    from jaxplan.experiments.config import load_config
    from jaxplan.search import exact_objectives, path_objectives

    t0 = cfg.tunes[0]
    weights = dict(t0.overrides)
    exp = load_config(run / "config.toml", data_dir=data_dir)
    grids = {m.name: load_map_spec(m)[0] for m in exp.maps}
    man = json.loads((run / "checkpoints" / "manifest.json").read_text())
    per: dict[tuple[str, str], list[np.ndarray]] = {}
    for uid, ch in sorted(man["chunks"].items()):
        a = load_chunk_arrays(run, uid, ch.get("arrays_sha256"))
        paths, n, ok = np.asarray(a["paths"]), np.asarray(a["n_cells"]), np.asarray(a["success"], bool)
        S, R = ok.shape
        g = grids[ch["map"]]
        flat_p, flat_n = paths.reshape(S * R, *paths.shape[2:]).astype(np.int64), n.reshape(-1)
        cost = np.full(S * R, np.nan)
        good = ok.reshape(-1) & (flat_n >= 2)
        cost[good] = path_objectives(flat_p[good], flat_n[good], g, t0.planner, **weights)
        r = np.argmax(n, axis=1)  # a seed whose path reached the goal (scenario ends are the same for every seed)
        starts, goals = paths[np.arange(S), r, 0], paths[np.arange(S), r, np.maximum(n[np.arange(S), r] - 1, 0)]
        opt = exact_objectives(g, starts, goals, t0.planner, **weights)
        gap = cost.reshape(S, R) / opt[:, None] - 1.0
        per.setdefault((ch["map"], ch["planner"]), []).append(gap)
    lines = ["## Own-objective gap at the default weights", "",
             f"The study's yardstick on the confirmation trials: each path's {t0.planner.upper()} cost at the default "
             "weights over that cost's exact optimum, minus 1 (successful trials; per seed the mean over scenarios, "
             "then mean ± sd over seeds; Welch's t-test over the per-seed means).", "",
             "| map | planner | own-objective gap | vs defaults: t | p |", "|---|---|---:|---:|---:|"]
    for m in grids:
        seeds = {}
        for (mp, pl), parts in per.items():
            if mp == m:
                seeds[pl] = np.nanmean(np.concatenate(parts, axis=0), axis=0)
        ref = next((v for k, v in seeds.items() if k.endswith("(defaults)")), None)
        for pl, v in seeds.items():
            test = ("–", "–")
            if ref is not None and v is not ref and len(v) > 1:
                t, pv = ttest_ind(ref, v, equal_var=False)
                test = (f"{t:.3g}", f"{pv:.3g}")
            sd = f"{np.std(v, ddof=1):.4f}" if len(v) > 1 else "–"  # one seed has no spread
            lines.append(f"| {m} | {pl} | {np.mean(v):.4f} ± {sd} | {test[0]} | {test[1]} |")
    return lines


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" + ("" if n == 1 else "s")


def _fmt(v: float, d: int = 4) -> str:
    return f"{v:.{d}f}" if isinstance(v, float) and math.isfinite(v) else "–"


def _page(cfg: StudyConfig, s: dict, frag: str, results) -> str:
    t0 = cfg.tunes[0]
    cmd = f"jaxplan study {_rel(cfg.path)}" + (" --quick" if cfg.is_quick else "") + \
        " --results docs/results/tuning"
    main = max(s["sessions"], key=lambda x: x["wall_s"])
    load = ", ".join(f"{v:.2f}" for v in (main["loadavg_start"] or s["loadavg_start"]))
    n_sess = len(s["sessions"])
    n_work = sum(1 for x in s["sessions"] if x.get("worker"))
    load_end = ", ".join(f"{v:.2f}" for v in (main["loadavg_end"] or s["loadavg_end"]))
    gap = {"own": "the gap of the best path's own IACO cost (at the default λ) to its exact own optimum "
                  "(`jaxplan.search.exact_objectives`)",
           "length": "the gap of the best path's length to the shortest path"}[cfg.gap]
    kinds = f" × {len(t0.walkers)} walker kinds" if t0.kind == "nav" else ""
    mw = " + ".join(f"{w:g}·{k}" for k, w in s["metric_weights"].items())
    space = ", ".join(f"{n} ∈ [{lo:g}, {hi:g}]" for n, (lo, hi) in s["space"].items())
    dft = s["defaults"]
    lines = [f"# Tuning study `{cfg.name}`" + (" (quick)" if cfg.is_quick else ""), "", s["description"], "",
             f"Regenerate: `{cmd}` (add `--confirm` to run the confirmation too) — measured "
             f"{s['wall_s_total'] / 60:.1f} min wall in total"
             + (f" over {n_sess} sessions (the longest {main['wall_s'] / 60:.1f} min; later ones resumed from the "
                "checkpoints" + (f"; {n_work} of them workers (`--only`) running side by side" if n_work else "")
                + ")" if n_sess > 1 else "")
             + (f", at niceness {main['nice']} on {_count(main['cores'], 'core')}" if main.get("nice") is not None
                else "")
             + f" (1-, 5-, 15-min load averages {load} at the start and {load_end} at the end of the longest "
             "session).", "",
             "## Setup", "",
             f"- Planner: `{t0.planner}` with overrides {_inline(dict(t0.overrides)) if t0.overrides else '{}'}; "
             f"tuned: {space}.",
             (f"- Cost (lower is better): {mw}, where gap is {gap} (a failed run counts gap 1), averaged over "
              "scenarios and seeds." if t0.kind != "nav" else
              f"- Cost (lower is better): {mw} per episode, where failure = not at the goal without contact within "
              "the time limit and time = time to the goal over that limit (1 when not reached): success first, time "
              f"second; averaged over episodes. Pipeline `{t0.pipeline}`, {t0.walker_count} walkers at "
              f"{t0.walker_speed:g} m/s, each vector scored among each kind: {', '.join(t0.walkers)}."),
             "- Maps: " + "; ".join(f"{m['name']} (train seeds {m['train_seeds']}, held-out seeds "
                                    f"{m['heldout_seeds']})" for m in s["maps"]) + ".",
             f"- Training split: {s['train_rows']} scenario rows × {_count(len(t0.train_seeds), 'seed')}{kinds} = "
             f"{s['train_runs']} runs per evaluation; held-out split: {s['heldout_rows']} other rows × "
             f"{_count(len(t0.test_seeds), 'other seed')}{kinds} = {s['heldout_runs']} runs. Rows and seeds are "
             "disjoint (checked: the study refuses to run otherwise).",
             f"- Budget: {cfg.budget} training evaluations (weight vectors) per method and tuner seed, counted by "
             f"the objective wrapper ({cfg.population} per generation × {cfg.generations} generations); "
             f"{len(cfg.tuner_seeds)} tuner seeds {list(cfg.tuner_seeds)}. The strategies that take a starting "
             "point begin from the defaults (`tune_loop`'s x0); grid and random search cover the box. "
             + ("The grid does not depend on the tuner seed and the objective is deterministic, so it ran once and "
                "that run stands for every seed (its sd is 0 by construction). " if "grid" in cfg.methods else "")
             + "Held-out evaluations are not charged.", "",
             "## Results", "",
             "Train = the best training cost the tuner found (the minimum over its evaluations, so optimistic); "
             "held-out = the cost of those same weights on the held-out split. Mean ± sd over tuner seeds, "
             "95 % t-interval of the mean; wall = seconds per run (training evaluations and the strategy) without "
             "XLA compilation, which a process pays once, in whichever run comes first "
             f"({_compile_note(s)}).",
             "",
             "| method | train (mean ± sd) | held-out (mean ± sd) | held-out 95 % interval | wall (s) | evaluations "
             "(counted) |",
             "|---|---|---|---|---|---|"]
    for m in cfg.methods:
        r = s["methods"][m]
        lines.append(f"| {m} | {_fmt(r['train']['mean'])} ± {_fmt(r['train']['sd'])} | "
                     f"{_fmt(r['heldout']['mean'])} ± {_fmt(r['heldout']['sd'])} | "
                     f"[{_fmt(r['heldout']['ci95'][0])}, {_fmt(r['heldout']['ci95'][1])}] | "
                     f"{r['run_s']['mean']:.1f} | {r['evaluations']} |")
    lines.append(f"| **defaults** | {_fmt(dft['train'])} | {_fmt(dft['heldout'])} | "
                 f"± {_fmt(dft['heldout_ci95_halfwidth'])} (over {len(dft['heldout_per_seed'])} held-out seeds) | – "
                 "| – |")
    b = s["best"]
    bm = s["methods"][b["method"]]["heldout"]
    verdict = {"beats": f"**yes**: the 95 % interval of `{b['method']}` (upper end {_fmt(bm['ci95'][1])}) lies below "
                        f"the defaults' held-out cost minus its own 95 % half-width ({_fmt(dft['heldout'])} − "
                        f"{_fmt(dft['heldout_ci95_halfwidth'])})",
               "within": f"**no**: the best method, `{b['method']}`, is not below the defaults by more than the "
                         f"intervals (its held-out mean {_fmt(bm['mean'])}, 95 % interval [{_fmt(bm['ci95'][0])}, "
                         f"{_fmt(bm['ci95'][1])}], against the defaults' {_fmt(dft['heldout'])} ± "
                         f"{_fmt(dft['heldout_ci95_halfwidth'])}): at this budget the defaults are at the optimum "
                         "within noise",
               "worse": f"**no**: even the best method, `{b['method']}`, is worse than the defaults on the held-out "
                        "split (over-fitted to the training split)"}[s["verdict"]]
    hm = b["heldout_metrics"]
    dm = dft["heldout_metrics"]
    lines += ["", f"Does the best method beat the defaults on the held-out split by more than the interval? {verdict}.",
              "",
              "Held-out metrics (means over runs), defaults → best weights: " + ", ".join(
                  f"{k} {dm[k]:.4f} → {hm[k]:.4f}" for k in dm if k in hm) + ".", "",
              f"![held-out cost against training evaluations]({cfg.name}.png)", "",
              "## Best weights", "",
              f"`{b['method']}` with tuner seed {b['tuner_seed']} (chosen among that method's seeds by its training "
              f"cost, {_fmt(b['train'])}; held-out {_fmt(b['heldout'])}), written as `{cfg.name}_best.toml`:", "",
              "```toml", frag.rstrip(), "```", "",
              f"Confirmation: `{cfg.name}_confirm.toml` runs the defaults against these weights with `jaxplan run` "
              f"on fresh random start-goal pairs and trial seeds {list(cfg.confirm_seeds)}: "
              f"see [{cfg.name}_confirm.md]({cfg.name}_confirm.md).", ""]
    return "\n".join(lines)


def _compile_note(s: dict) -> str:
    return f"{s['compile_s_total']:.0f} s of compilation over all runs of all sessions"


def _rel(p: Path | None) -> str:
    if p is None:
        return "CONFIG"
    try:
        return str(Path(p).resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(p)
