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
# # Tuning the MPPI local planner's weights
#
# MPPI scores sampled control sequences with weighted critics (obstacle clearance, distance to moving
# obstacles, following the path) and averages them with a softmax of temperature λ. Which weights work best is
# an empirical question: here CMA-ES searches them on episodes in a small hall with two discs crossing the
# robot's way, the result is judged on held-out scenarios and seeds the search never saw, and the tuned
# weights then drive full navigation episodes among random walkers beside the defaults.
#
# No data needed. Quick mode (`--quick` or `JAXPLAN_EXAMPLES_QUICK=1`) runs the config's `[tune.quick]`
# variant: a smoke run far too small to find better weights, but the same code path. Everything goes to
# `$JAXPLAN_EXAMPLES_OUT` (default `runs/examples/`).

# %%
import csv
import json
import os
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import jaxplan as jp
from jaxplan.experiments import plots, random_pairs
from jaxplan.tune import run_tuning

QUICK = "--quick" in sys.argv or os.environ.get("JAXPLAN_EXAMPLES_QUICK", "") not in ("", "0")
OUT = Path(os.environ.get("JAXPLAN_EXAMPLES_OUT", "runs/examples"))
OUT.mkdir(parents=True, exist_ok=True)

# %% [markdown]
# ## The tuning config
#
# `kind = "mppi"`: each weight vector drives the MPPI through the training scenarios × seeds, each episode
# among `discs` moving discs, and costs its time to the goal over `max_time` plus 1 if it failed. The
# `[tune.space]` box names the weights searched; the others keep their defaults. The first `train_count`
# scenarios train, the rest are held out, and the test seeds never meet the training seeds.

# %%
CONFIG = """
[tune]
name = "mppi_weights"
description = "MPPI critic weights and temperature by CMA-ES in a small hall with two crossing discs"
kind = "mppi"
strategy = "cma_es"
population = 8
generations = 8
train_count = 8
train_seeds = 2
test_seeds = [1000, 1001]
weights = { time = 1.0, failure = 1.0 }
overrides = { samples = 64 }
max_time = 15.0
discs = 2

[tune.space]
obstacle = [0.05, 5.0]
dynamic = [0.05, 5.0]
path_follow = [0.05, 5.0]
temperature = [0.005, 0.2]

[tune.quick]
population = 4
generations = 3
train_count = 3
test_count = 3
train_seeds = 1
test_seeds = [1000]

[[maps]]
name = "hall"
generator = "random"
seed = 1
params = { width = 16, height = 16, obstacle_ratio = 0.05 }
resolution = 0.5
scenarios = { source = "random", count = 16, seed = 0, min_distance = 4.0 }
"""
config = OUT / "mppi_weights.toml"
config.write_text(CONFIG)

# %% [markdown]
# ## Run the search
#
# `run_tuning` is what `jaxplan tune` calls. Each generation's population is one compiled call; the run folder
# keeps `generations.csv`, orbax checkpoints (a killed run resumes on the same trajectory), `summary.json`
# (defaults against the best weights on both splits) and `best.toml`, a `[[planners]]` entry for experiment
# configs.

# %%
run = run_tuning(config, out=OUT / "runs", quick=QUICK, progress=False)
summary = json.loads((run / "summary.json").read_text())
with open(run / "generations.csv") as f:
    generations = list(csv.DictReader(f))
print(f"{summary['evaluations']} weight vectors evaluated")
for name in summary["defaults"]:
    print(f"  {name:12s} default {summary['defaults'][name]:7.3f}   best {summary['best'][name]:7.3f}")
for split in ("train", "test"):
    d, t = summary[split]["defaults"], summary[split]["tuned"]
    print(f"{split:5s} cost: defaults {d['objective']:.3f} (failures {d['metrics']['failure']:.0%}), "
          f"tuned {t['objective']:.3f} (failures {t['metrics']['failure']:.0%})")

# %% [markdown]
# The search's progress and the verdict on held-out scenarios. A training cost below the defaults' that does
# not carry over to the held-out split is over-fitting to a few scenarios, which a quick run shows readily.

# %%
fig, (a, b) = plt.subplots(1, 2, figsize=(9, 3.3), constrained_layout=True)
g = [int(r["generation"]) for r in generations]
a.plot(g, [float(r["best"]) for r in generations], "o-", label="best so far")
a.plot(g, [float(r["gen_mean"]) for r in generations], "s--", alpha=0.7, label="generation mean")
a.axhline(summary["train"]["defaults"]["objective"], color="grey", lw=1, label="defaults")
a.set_xticks(g)
a.set_xlabel("generation")
a.set_ylabel("training cost")
a.set_title("the search")
a.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=3)
labels = [f"{s}\n{w}" for s in ("train", "held out") for w in ("defaults", "tuned")]
costs = [summary[s][w]["objective"] for s in ("train", "test") for w in ("defaults", "tuned")]
b.bar(range(4), costs, color=["grey", "C0", "grey", "C0"])
b.set_xticks(range(4), labels)
b.set_ylabel("cost (time share + failures)")
b.set_title("defaults against the best weights")
plots.save_figure(fig, str(OUT / "tune_mppi_search.png"))
fig  # noqa: B018 (a notebook shows the figure)

# %% [markdown]
# ## The tuned weights in full navigation episodes
#
# The search scored the local planner alone among crossing discs. Does it carry over to two-level navigation
# among walkers? `jp.navigate_batch` with `params=` runs the MPPI pipeline with given weights (a dict of
# `MPPIParams` fields); fresh start-goal pairs on the same hall, fresh walkers per seed.

# %%
grid = jp.RandomMapGenerator(16, 16, obstacle_ratio=0.05, resolution=0.5)(1).grid  # the config's map
starts, goals, _ = random_pairs(grid, 4 if QUICK else 12, seed=7, min_distance=4.0, min_clearance=0.6)


def walkers(i: int, seed: int) -> jp.MovingObstacles:
    """Three walkers on random routes, kept clear of scenario i's start and goal."""
    clear = grid.centre(np.stack([starts[i], goals[i]]))
    return jp.random_obstacles(grid, n=3, speed=0.5, radius=0.2, seed=100 * i + seed, avoid=clear, avoid_radius=1.0)


config_nav = jp.NavConfig(max_time=40.0, replan=False)
config_nav = config_nav.replace(mppi=config_nav.mppi.replace(samples=64))
results = {}
for label, params in (("defaults", summary["defaults"]), ("tuned", summary["best"])):
    batch = jp.navigate_batch(grid, starts, goals, pipeline="astar_kng_mppi", seeds=range(2 if QUICK else 4),
                              obstacles=walkers, config=config_nav, params=params)
    s = batch.summary()
    results[label] = {"success": s["success"][0], "time_s": s["time_s"][0], "collisions": s["collisions"][0]}
    print(f"{label:8s} success {s['success'][0]:4.0%}  time to goal {s['time_s'][0]:5.1f} s  "
          f"contacts {s['collisions'][0]:.2f} per episode")
(OUT / "tune_mppi.json").write_text(json.dumps({"summary": summary, "navigation": results}))
