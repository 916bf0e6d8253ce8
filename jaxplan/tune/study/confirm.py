"""The confirmation of a study: an experiment config (`jaxplan run`) that runs the defaults against the tuned
weights on fresh scenarios and seeds, and its page.

`confirm_config` writes the config: every map of the study, ``confirm_count`` fresh random start-goal pairs per map
(drawn with ``confirm_scenario_seed`` and checked against the training rows), trial seeds ``confirm_seeds`` (checked
against the training and held-out seeds). `run_confirmation` runs it (`jaxplan.experiments.run_experiment`) and writes
its page: the run's report, introduced, with `own_gap_table` for an own-objective study.
"""

from __future__ import annotations

import json
import os
import time
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from jaxplan.core import markdown as md
from jaxplan.core import toml
from jaxplan.core.io import atomic_write
from jaxplan.tune._composite import check_disjoint
from jaxplan.tune._config import TuneConfig
from jaxplan.tune._workflow import split_scenarios
from jaxplan.tune.study.config import StudyConfig
from jaxplan.tune.study.page import rel_path

__all__ = ["confirm_config", "own_gap_table", "run_confirmation"]


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
             f"seeds = {toml.literal(list(cfg.confirm_seeds))}", ""]
    for m in cfg.maps_raw:
        entry = {k: v for k, v in m.items() if k != "scenarios"}
        scen = {"source": "random", "count": cfg.confirm_count, "seed": cfg.confirm_scenario_seed,
                "min_distance": float(m.get("scenarios", {}).get("min_distance", 8.0))}
        for k in ("min_clearance",):
            if k in m.get("scenarios", {}):
                scen[k] = m["scenarios"][k]
        entry["scenarios"] = scen
        lines.append("[[maps]]")
        lines += [f"{toml.key(k)} = {toml.literal(v)}" for k, v in entry.items()]
        lines.append("")
    ov = dict(t0.overrides)
    if defaults is None:
        lines += ["[[planners]]", f'label = "{t0.planner.upper()} (defaults)"', 'kind = "plan"',
                  f"name = {toml.literal(t0.planner)}"] + ([f"overrides = {toml.literal(ov)}"] if ov else []) + [""]
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
        train, _ = split_scenarios(t, gridt, ts, tg, topt)
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
                ln = f"label = {toml.literal(tomllib.loads(ln)['label'] + f', {kind} walkers')}"
            lines.append(ln)
        lines += [f"obstacles = {toml.literal(obs)}", f"nav = {toml.literal({'max_time': t.max_time})}"]
        out.append("\n".join(lines) + "\n")
    return "\n".join(out)


def own_gap_table(cfg: StudyConfig, run: Path, data_dir: str | os.PathLike | None = None) -> list[str]:
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
             "then mean ± sd over seeds; Welch's t-test over the per-seed means).", ""]
    rows = []
    for m in grids:
        seeds = {}
        for (mp, pl), parts in per.items():
            if mp == m:
                seeds[pl] = np.nanmean(np.concatenate(parts, axis=0), axis=0)
        ref = next((v for k, v in seeds.items() if k.endswith("(defaults)")), None)
        for pl, v in seeds.items():
            test = (md.MISSING, md.MISSING)
            if ref is not None and v is not ref and len(v) > 1:
                t, pv = ttest_ind(ref, v, equal_var=False)
                test = (f"{t:.3g}", f"{pv:.3g}")
            sd = float(np.std(v, ddof=1)) if len(v) > 1 else None  # one seed has no spread
            rows.append([m, pl, md.pm(float(np.mean(v)), sd, lambda x: f"{x:.4f}"), *test])
    lines.append(md.table(["map", "planner", "own-objective gap", "vs defaults: t", "p"], rows, text=2))
    return lines


def run_confirmation(cfg: StudyConfig, folder: Path, out: str | os.PathLike, results: str | os.PathLike | None,
                     data_dir: str | os.PathLike | None, progress: bool, executor: Any = None) -> Path:
    """Runs the study's confirm.toml (in study folder ``folder``) with `run_experiment` into ``out`` and writes its page
    ``confirm.md`` (also ``results/NAME_confirm.md`` with ``results``): the run's report, introduced. Returns the
    run folder. ``executor``: where its chunks run (`run_experiment`'s)."""
    from jaxplan.experiments import run_experiment

    t0 = time.perf_counter()
    load = os.getloadavg()
    run = run_experiment(folder / "confirm.toml", out, data_dir=data_dir, progress=progress, executor=executor)
    wall = time.perf_counter() - t0
    report = (run / "report.md").read_text()
    chunks = json.loads((run / "checkpoints" / "manifest.json").read_text())["chunks"].values()
    calls = sum(float(c.get("compile_s", 0.0)) + float(c.get("time_s", 0.0)) for c in chunks)
    head = [f"# Confirmation of tuning study `{cfg.name}`", "",
            f"The defaults against the tuned weights of [{cfg.name}]({cfg.name}.md) (`{cfg.name}_best.toml`) with "
            f"`jaxplan run {cfg.name}_confirm.toml` on fresh random start-goal pairs and trial seeds "
            f"{list(cfg.confirm_seeds)} (neither the tuner nor the held-out split saw them; checked). Regenerate: "
            f"`jaxplan study {rel_path(cfg.path)} --results docs/results/tuning --confirm` (the study resumes from its "
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
