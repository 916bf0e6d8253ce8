"""Experiments: configs, the resumable runner, statistics, reports and figures (docs/guide/experiments.md).

* `config`: TOML experiment configs, validated in full before any work (`load_config`, `ConfigError`,
  `apply_quick`); `config_schema` declares their tables and resolved dataclasses, `config_checks` holds the checks
  across keys, `metric_catalogue` the metrics a config may name (`METRICS`).
* `schema`: settings declared once on dataclass fields, the reader that checks configs against them, and
  the renderers of the reference page and the JSON Schemas (`jaxplan.config_reference`).
* `runner`: `run_experiment` — batched compiled calls per chunk, checkpointed and resumable; its stages
  `prepare` (the work plan), `execute` (one compiled call per chunk), `trial_metrics`, `store`
  (checkpoints, manifest, meta.json) and `progress`.
* `stats`, `report`: per-seed summaries, ANOVA / Welch t-tests, Markdown reports.
* `plots`: map, path, pheromone and convergence figures; `figures` draws a run folder's ``[[figures]]``
  (`run_data` reads the folder back, `figure_kinds` holds one drawing function per kind).

The names below are imported from their modules when first used (PEP 562 ``__getattr__``): importing one
module of the package (a config reader, the schema) does not load the runner and JAX with it.
"""

from __future__ import annotations

import importlib
from typing import Any

_EXPORTS: dict[str, tuple[str, ...]] = {
    "config": ("METRICS", "ConfigError", "ExperimentConfig", "apply_quick", "load_config", "parse_config"),
    "prepare": ("ID_COLUMNS", "MapWork", "Prepared", "Unit", "load_map_spec", "prepare", "random_pairs",
                "spec_scenarios", "trial_columns"),
    "progress": ("clock",),
    "runner": ("run_experiment",),
    "store": ("CheckpointError", "RunFolderError", "load_chunk_arrays", "read_manifest"),
    "trial_metrics": ("accuracy", "grid_path_lengths", "objective_gaps", "optimality_gaps", "reductions"),
}
_SOURCE = {name: module for module, names in _EXPORTS.items() for name in names}

__all__ = list(_SOURCE)


def __getattr__(name: str) -> Any:
    if name in _SOURCE:
        value = getattr(importlib.import_module(f"jaxplan.experiments.{_SOURCE[name]}"), name)
        globals()[name] = value  # later lookups skip __getattr__
        return value
    raise AttributeError(f"module 'jaxplan.experiments' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
