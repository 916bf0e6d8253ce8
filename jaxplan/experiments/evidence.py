"""The evidence of a finished run arranged for verdicts: per-unit values of a (map, planner, metric).

The unit of replication. A map read from a file is one map: its trials' independent units are the seeds
(each seed's mean over the map's scenarios). A generated map with several draws (``[[maps]] draws``) is a
sample of maps: a difference that one draw produces belongs to that map, not to the planner, so the units
are the draws (each draw's mean over its seeds and scenarios) — the per-draw means of a two-level design.
Pooling several maps of a claim, the units of every map are put side by side.

A single *run* of the experiment, for comparing with a number a paper got from one run, is one (draw, seed)
mean. A rate (a 0/1 metric) is also counted as successes out of trials, for Wilson intervals.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from jaxplan.experiments.config import METRICS, ExperimentConfig, MapSpec, applies
from jaxplan.experiments.stats import read_trials, trial_mask

__all__ = ["Evidence", "load_evidence", "family_sites", "units", "unit_name", "runs", "rate_counts", "paired_units"]


@dataclass(frozen=True)
class Evidence:
    """A run's trials (`read_trials` columns) with its config."""

    config: ExperimentConfig
    trials: Mapping[str, np.ndarray]

    def families(self) -> list[str]:
        """The configured maps (a drawn map once), in config order."""
        return list(dict.fromkeys(m.map_family for m in self.config.maps))

    def drawn(self, family: str) -> bool:
        return len(family_sites(self.config, family)) > 1

    def has(self, family: str, planner: str) -> bool:
        pc = next((p for p in self.config.planners if p.label == planner), None)
        return pc is not None and any(applies(pc, m) for m in family_sites(self.config, family))


def load_evidence(run_dir: str | os.PathLike, config: ExperimentConfig) -> Evidence:
    """The trials of run folder ``run_dir`` (its ``trials.csv``) with ``config``."""
    return Evidence(config, read_trials(Path(run_dir) / "trials.csv"))


def family_sites(cfg: ExperimentConfig, family: str) -> list[MapSpec]:
    """The sites (draws) of configured map ``family``, draw 0 first."""
    return [m for m in cfg.maps if m.map_family == family]


def _seed_matrix(ev: Evidence, site: str, planner: str, metric: str) -> np.ndarray:
    """``f64[R]`` per-seed means of ``metric`` on one site (nan where no trial defines it)."""
    t = ev.trials
    if metric not in t:
        return np.full(len(ev.config.seeds), math.nan)
    base = trial_mask(t, site, planner, metric)
    v = t[metric]
    out = np.full(len(ev.config.seeds), math.nan)
    for i, s in enumerate(ev.config.seeds):
        x = v[base & (t["seed"] == s)]
        x = x[np.isfinite(x)]
        if x.size:
            out[i] = float(np.mean(x))
    return out


def runs(ev: Evidence, family: str, planner: str, metric: str) -> np.ndarray:
    """``f64[D * R]`` one value per run of the experiment: the (draw, seed) means (nan where undefined)."""
    return np.concatenate([_seed_matrix(ev, m.name, planner, metric) for m in family_sites(ev.config, family)])


def units(ev: Evidence, family: str, planner: str, metric: str) -> np.ndarray:
    """The independent units of ``metric`` (see the module docstring): ``f64[D]`` per-draw means of a drawn map,
    else ``f64[R]`` per-seed means."""
    sites = family_sites(ev.config, family)
    if len(sites) == 1:
        return _seed_matrix(ev, sites[0].name, planner, metric)
    out = []
    for m in sites:
        x = _seed_matrix(ev, m.name, planner, metric)
        out.append(float(np.nanmean(x)) if np.isfinite(x).any() else math.nan)
    return np.asarray(out)


def unit_name(ev: Evidence, family: str) -> str:
    """What a unit is, for tables: "map draws" or "seeds"."""
    return "map draws" if ev.drawn(family) else "seeds"


def rate_counts(ev: Evidence, family: str, planner: str, metric: str) -> tuple[int, int]:
    """(successes, trials) of a rate metric over every counted trial of the map's draws."""
    if not METRICS[metric].rate:
        raise ValueError(f"{metric!r} is not a rate")
    k = n = 0
    t = ev.trials
    for m in family_sites(ev.config, family):
        x = t[metric][trial_mask(t, m.name, planner, metric)]
        x = x[np.isfinite(x)]
        k += int(np.sum(x > 0.5))
        n += int(x.size)
    return k, n


def paired_units(ev: Evidence, families: Sequence[str], proposed: str, baseline: str,
                 metric: str) -> tuple[np.ndarray, np.ndarray]:
    """Per-unit means of ``proposed`` and ``baseline`` over the trials both define, matched on (site, scenario,
    seed): ``(f64[U], f64[U])`` with the units of every family in ``families`` side by side.

    Pairing removes what the two share — the map, the start-goal pair, the seed's moving obstacles — so the
    difference is the planners'. The units are a family's draws if it is drawn, else its seeds."""
    t = ev.trials
    a_out, b_out = [], []
    for fam in families:
        sites = family_sites(ev.config, fam)
        per_site_a, per_site_b = [], []
        for m in sites:
            ma, mb = trial_mask(t, m.name, proposed, metric), trial_mask(t, m.name, baseline, metric)
            key_a = {(int(sc), int(sd)): float(v) for sc, sd, v in
                     zip(t["scenario"][ma], t["seed"][ma], t[metric][ma], strict=True) if math.isfinite(v)}
            key_b = {(int(sc), int(sd)): float(v) for sc, sd, v in
                     zip(t["scenario"][mb], t["seed"][mb], t[metric][mb], strict=True) if math.isfinite(v)}
            both = sorted(set(key_a) & set(key_b))
            sa, sb = np.full(len(ev.config.seeds), math.nan), np.full(len(ev.config.seeds), math.nan)
            for i, s in enumerate(ev.config.seeds):
                ks = [k for k in both if k[1] == int(s)]
                if ks:
                    sa[i] = float(np.mean([key_a[k] for k in ks]))
                    sb[i] = float(np.mean([key_b[k] for k in ks]))
            per_site_a.append(sa)
            per_site_b.append(sb)
        if len(sites) == 1:
            a_out.append(per_site_a[0])
            b_out.append(per_site_b[0])
        else:
            ok = [np.isfinite(x).any() for x in per_site_a]
            a_out.append(np.asarray([np.nanmean(x) if o else math.nan for x, o in zip(per_site_a, ok, strict=True)]))
            b_out.append(np.asarray([np.nanmean(x) if o else math.nan for x, o in zip(per_site_b, ok, strict=True)]))
    return np.concatenate(a_out), np.concatenate(b_out)
