"""Tuning the planners' weights (docs/guide/experiments.md): objectives over scenario batches, gradient-free and
differentiable
optimisers.

* `_bounds`: the search box (`make_bounds`, validated: finite, low < high, named dimensions).
* `_objective`: `Objective` — a population ``f32[P, D]`` of weight vectors evaluated over a
  training split of scenarios × seeds in ONE compiled call (`aco_objective`, `dwa_objective`,
  `function_objective`); a held-out test split kept apart.
* `_nav_objective`: `nav_objective` — the local planner's weights scored on full two-level navigation episodes
  among blind and seeing walkers over several MovingAI maps (one compiled call per map).
* `_base`: the one `Strategy` interface (``init/ask/tell``) and the helpers every state shares;
  `_search`, `_evosax`, `_sparrow`, `_gradients`: grid and random search, CMA-ES and SNES
  (evosax), li2026's ISSA and the plain SSA, the score-function (REINFORCE) and surrogate routes;
  `relaxed_dwa` differentiates softmax-DWA episodes through `lax.scan` with optax.
* `_strategies`: the registry of strategies by name (`STRATEGY_SPECS`, `make_strategy`), used by
  configs, the workflow and the benchmarks.
* `_composite`: objectives of objectives (a colony's own-objective gap, several maps at once).
* `study`: tuning studies (`run_study`: every method at an equal counted budget, judged on held-out scenarios;
  one module per job: config, objective, run, judge, page, confirm).
* `_loop`: `tune_loop` (progress, CSV log, checkpoints in a `jaxplan.core.run_folder.RunFolder`, exact resume).
* `_config`, `_workflow`: TOML tuning configs (schema: `TuneFile`; ``quick=True`` applies the ``[tune.quick]``
  overlay) and `run_tuning` (the objective of a config, `tune_loop`, best weights as a ``[[planners]]`` fragment,
  convergence figure).

Example::

    from jaxplan.tune import make_strategy, run_tuning, tune_loop
    run_dir = run_tuning("configs/tune_iaco.toml", out="runs", quick=True)
"""

from jaxplan.tune._base import Strategy, sanitize
from jaxplan.tune._bounds import Bounds, clip, from_unit, make_bounds, reflect, to_unit
from jaxplan.tune._composite import aco_own_objective, check_disjoint, concat_objectives, path_costs
from jaxplan.tune._config import (
    TuneConfig,
    TuneFile,
    apply_tune_quick,
    load_tune_config,
    parse_tune_config,
    quick_tune_config,
)
from jaxplan.tune._evosax import cma_es, snes
from jaxplan.tune._gradients import (
    RelaxedResult,
    quadratic_features,
    reinforce,
    relaxed_dwa,
    relaxed_dwa_loss,
    score_function_grad,
    surrogate,
)
from jaxplan.tune._loop import TUNE_LAYOUT, TuneResult, tune_loop
from jaxplan.tune._nav_objective import (
    NAV_METRICS,
    WALKER_KINDS,
    NavMap,
    NavObjective,
    nav_map,
    nav_objective,
    spread_rows,
)
from jaxplan.tune._objective import (
    ACO_METRICS,
    DWA_METRICS,
    DWAEpisodes,
    Evaluation,
    Objective,
    Split,
    aco_objective,
    dwa_episodes,
    dwa_objective,
    dwa_scenarios,
    function_objective,
    mppi_objective,
)
from jaxplan.tune._search import grid_search, random_search
from jaxplan.tune._sparrow import SparrowState, adaptive_weight, issa, levy, ssa
from jaxplan.tune._strategies import (
    STRATEGIES,
    STRATEGY_SPECS,
    StrategySpec,
    make_strategy,
    option_problems,
    strategy_options,
)
from jaxplan.tune._workflow import build_objective, compare, fragment_toml, plot_tuning, run_tuning
from jaxplan.tune.study import (
    CountedObjective,
    StudyConfig,
    StudyFile,
    apply_study_quick,
    build_study_objective,
    confirm_config,
    load_study_config,
    parse_study_config,
    quick_study_config,
    run_study,
)

__all__ = [
    "Bounds", "clip", "from_unit", "make_bounds", "reflect", "to_unit",
    "STRATEGIES", "STRATEGY_SPECS", "Strategy", "StrategySpec", "cma_es", "grid_search", "make_strategy",
    "option_problems", "random_search", "sanitize", "snes", "strategy_options",
    "RelaxedResult", "quadratic_features", "reinforce", "relaxed_dwa", "relaxed_dwa_loss", "score_function_grad",
    "surrogate", "ACO_METRICS", "DWA_METRICS", "DWAEpisodes", "Evaluation", "Objective", "Split", "aco_objective",
    "dwa_episodes", "dwa_objective", "dwa_scenarios", "function_objective", "mppi_objective",
    "NAV_METRICS", "WALKER_KINDS", "NavMap", "NavObjective", "nav_map", "nav_objective", "spread_rows",
    "TuneConfig", "TuneFile", "apply_tune_quick", "load_tune_config", "parse_tune_config", "quick_tune_config",
    "TuneResult", "TUNE_LAYOUT", "build_objective",
    "compare", "fragment_toml", "plot_tuning", "run_tuning", "tune_loop",
    "SparrowState", "adaptive_weight", "issa", "levy", "ssa",
    "aco_own_objective", "check_disjoint", "concat_objectives", "path_costs",
    "CountedObjective", "StudyConfig", "StudyFile", "apply_study_quick", "build_study_objective", "confirm_config",
    "load_study_config", "parse_study_config", "quick_study_config", "run_study",
]
