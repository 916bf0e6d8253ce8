"""Experiments: configs, the resumable runner, statistics, reports and figures (DESIGN §7).

* `config`: TOML experiment configs, validated in full before any work (`load_config`, `ConfigError`).
* `schema`: settings declared once on dataclass fields, the reader that checks configs against them, and
  the renderers of the reference page and the JSON Schemas (`jaxplan.config_reference`).
* `runner`: `run_experiment` — batched compiled calls per chunk, checkpointed and resumable.
* `stats`, `report`: per-seed summaries, ANOVA / Welch t-tests, Markdown reports.
* `plots`: map, path, pheromone and convergence figures.
"""

from jaxplan.experiments.config import (
    METRICS, ConfigError, ExperimentConfig, apply_quick, load_config, parse_config,
)
from jaxplan.experiments.runner import load_chunk_arrays, read_manifest, run_experiment

__all__ = ["METRICS", "ConfigError", "ExperimentConfig", "apply_quick", "load_config", "parse_config",
           "load_chunk_arrays", "read_manifest", "run_experiment"]
