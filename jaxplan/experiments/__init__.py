"""Experiments: configs, the resumable runner, statistics, reports and figures (docs/guide/experiments.md).

* `config`: TOML experiment configs, validated in full before any work (`load_config`, `ConfigError`).
* `schema`: settings declared once on dataclass fields, the reader that checks configs against them, and
  the renderers of the reference page and the JSON Schemas (`jaxplan.config_reference`).
* `runner`: `run_experiment` — batched compiled calls per chunk, checkpointed and resumable; its stages
  `prepare` (the work plan), `execute` (one compiled call per chunk), `trial_metrics`, `store`
  (checkpoints, manifest, meta.json) and `progress`.
* `stats`, `report`: per-seed summaries, ANOVA / Welch t-tests, Markdown reports.
* `plots`: map, path, pheromone and convergence figures; `figures` draws a run folder's ``[[figures]]``
  (`run_data` reads the folder back, `figure_kinds` holds one drawing function per kind).
* `tables`: plain-text tables for the terminal (`jaxplan plan`, `jaxplan demo`).
"""

from jaxplan.experiments.config import (
    METRICS,
    ConfigError,
    ExperimentConfig,
    apply_quick,
    load_config,
    parse_config,
)
from jaxplan.experiments.prepare import (
    ID_COLUMNS,
    MapWork,
    Prepared,
    Unit,
    load_map_spec,
    prepare,
    random_pairs,
    spec_scenarios,
    trial_columns,
)
from jaxplan.experiments.progress import clock
from jaxplan.experiments.runner import run_experiment
from jaxplan.experiments.store import CheckpointError, RunFolderError, load_chunk_arrays, read_manifest
from jaxplan.experiments.trial_metrics import accuracy, grid_path_lengths, objective_gaps, optimality_gaps, reductions

__all__ = ["METRICS", "ConfigError", "ExperimentConfig", "apply_quick", "load_config", "parse_config",
           "ID_COLUMNS", "MapWork", "Prepared", "Unit", "load_map_spec", "prepare", "random_pairs", "spec_scenarios",
           "trial_columns", "clock", "run_experiment", "RunFolderError", "CheckpointError", "load_chunk_arrays",
           "read_manifest", "accuracy", "grid_path_lengths", "objective_gaps", "optimality_gaps", "reductions"]
