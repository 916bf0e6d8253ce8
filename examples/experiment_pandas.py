# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # An experiment from a config, then its trials in pandas
#
# An experiment is a TOML file: maps, scenarios, planners with their settings, seeds, metrics. Running it
# gives a resumable run folder with one row per (map, planner, scenario, seed) in `trials.csv`, plus
# summaries and a report. Here we ask how IACO's heuristic weight β trades length for turns, against Ant
# System, on two generated maps; then we load the trials into pandas and compare the planners *paired* on
# the same scenarios and seeds.
#
# No data needed; pandas is (`pip install 'jaxplan[export]'`). Quick mode (`--quick` or
# `JAXPLAN_EXAMPLES_QUICK=1`) runs the config's `[experiment.quick]` variant. Everything goes to
# `$JAXPLAN_EXAMPLES_OUT` (default `runs/examples/`): the config, the run folder and the figure.

# %%
import os
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from scipy import stats

from jaxplan.experiments import plots, run_experiment
from jaxplan.experiments.export import trials_dataframe

QUICK = "--quick" in sys.argv or os.environ.get("JAXPLAN_EXAMPLES_QUICK", "") not in ("", "0")
OUT = Path(os.environ.get("JAXPLAN_EXAMPLES_OUT", "runs/examples"))
OUT.mkdir(parents=True, exist_ok=True)

# %% [markdown]
# ## The config
#
# Two generated 24 × 24 m maps (a warehouse and a random 20 % obstacle field; one size, so each planner
# compiles once for both), 12 random start-goal pairs each at least 10 m apart, A* as ground truth (the runner
# computes each trial's optimality gap against the exact optimum), Ant System and IACO at three values of β.
# `[experiment.quick]` says what a smoke run changes.

# %%
CONFIG = """
metrics = ["success", "length", "optimality_gap", "turns", "smoothness"]

[experiment]
name = "iaco_beta"
description = "IACO's heuristic weight beta against Ant System on two generated maps"
seeds = 8

[experiment.quick]
seeds = 3
count = 4
overrides = { ants = 12, iterations = 10 }

[[maps]]
name = "warehouse"
generator = "warehouse"
params = { width = 24, height = 24 }

[[maps]]
name = "random"
generator = "random"
params = { width = 24, height = 24, obstacle_ratio = 0.2 }

[scenarios]
source = "random"
count = 12
min_distance = 10.0

[[planners]]
label = "A*"
kind = "plan"
name = "astar"

[[planners]]
label = "AS"
kind = "plan"
name = "aco"
overrides = { ants = 30, iterations = 30 }

[[planners]]
label = "IACO β=3"
kind = "plan"
name = "iaco"
overrides = { ants = 30, iterations = 30, beta = 3.0 }

[[planners]]
label = "IACO β=7"
kind = "plan"
name = "iaco"
overrides = { ants = 30, iterations = 30, beta = 7.0 }

[[planners]]
label = "IACO β=12"
kind = "plan"
name = "iaco"
overrides = { ants = 30, iterations = 30, beta = 12.0 }
"""
config = OUT / "iaco_beta.toml"
config.write_text(CONFIG)

# %% [markdown]
# ## Run it
#
# `run_experiment` is what `jaxplan run` calls: it validates the whole config first, runs each chunk of
# trials as one compiled call and checkpoints it, so a killed run resumes where it stopped (run this cell
# twice: the second time nothing is recomputed). The quick run's folder is `iaco_beta-quick`.

# %%
run = run_experiment(config, out_dir=OUT / "runs", quick=QUICK, progress=False)
print(run, sorted(p.name for p in run.iterdir()))

# %% [markdown]
# ## The trials as a DataFrame
#
# `trials_dataframe` reads `trials.csv`: the ids (map, planner, scenario, seed, start and goal, the exact
# optimum) and one column per metric.

# %%
df = trials_dataframe(run)
order = ["A*", "AS", "IACO β=3", "IACO β=7", "IACO β=12"]
df["planner"] = pd.Categorical(df["planner"], categories=order, ordered=True)
df[["scenario", "seed"]] = df[["scenario", "seed"]].astype(int)
print(df.shape)
df.head()

# %% [markdown]
# Means per map and planner (pandas does what `summary.csv` does, and whatever else you ask of it):

# %%
table = df.groupby(["map", "planner"], observed=True)[["success", "optimality_gap", "turns"]].mean()
print(table.round(3).to_string())

# %% [markdown]
# ## Paired differences
#
# Every planner ran the same scenarios with the same seeds, so compare them pair by pair: the difference in
# gap and in turns between each IACO variant and Ant System on the same (map, scenario, seed), then its mean
# with a 95 % interval over the seeds' means (the seeds are the independent units here).

# %%
keys = ["map", "scenario", "seed"]
wide = df.pivot_table(index=keys, columns="planner", values=["optimality_gap", "turns"], observed=True)
rows = []
for variant in order[2:]:
    for metric in ("optimality_gap", "turns"):
        diff = (wide[(metric, variant)] - wide[(metric, "AS")]).groupby(["map", "seed"]).mean()
        for m, per_seed in diff.groupby(level="map"):
            n = len(per_seed)
            half = stats.t.ppf(0.975, n - 1) * per_seed.std(ddof=1) / np.sqrt(n)  # Student t: few seeds
            rows.append({"map": m, "variant": variant, "metric": metric, "mean": per_seed.mean(), "ci95": half})
paired = pd.DataFrame(rows)
paired.to_csv(OUT / "experiment_pandas_paired.csv", index=False)
print(paired.round(3).to_string(index=False))

# %%
fig, axes = plt.subplots(1, 2, figsize=(9, 3.4), constrained_layout=True)
for ax, metric, label in zip(axes, ("optimality_gap", "turns"), ("optimality gap (IACO − AS)", "turns (IACO − AS)"),
                             strict=True):
    for k, (m, part) in enumerate(paired[paired.metric == metric].groupby("map")):
        x = np.arange(len(part)) + (k - 0.5) * 0.2
        ax.errorbar(x, part["mean"], yerr=part["ci95"], fmt="o", capsize=3, label=m)
    ax.axhline(0.0, color="grey", lw=0.8)
    ax.set_xticks(range(len(order) - 2), order[2:])
    ax.set_ylabel(label)
    ax.legend(fontsize=8, title="map", title_fontsize=8)
fig.suptitle(f"paired on scenario and seed, mean ± 95 % interval over {df.seed.nunique()} seeds")
plots.save_figure(fig, str(OUT / "experiment_pandas_paired.png"))
fig  # noqa: B018 (a notebook shows the figure)

# %% [markdown]
# The same run folder feeds the command line: `jaxplan figures RUN` draws the config's `[[figures]]`,
# `jaxplan export RUN --format parquet` writes the trials and the per-trial paths and convergence histories
# as Parquet tables, and `report.md` holds the ANOVA and t-tests when the config asks for them (`[stats]`).
