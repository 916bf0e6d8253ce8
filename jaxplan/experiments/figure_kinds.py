"""The figure kinds of `jaxplan figures`: one function per kind, ``(run, spec) -> (figure, caption)``.

Each draws from a run folder read back (`jaxplan.experiments.run_data.RunData`) with the plotting
primitives of `jaxplan.experiments.plots`; `DRAW` maps a config's ``kind`` to its function (the kinds
and their keys: `jaxplan.experiments.figures`).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Callable

import numpy as np

from jaxplan.experiments import plots
from jaxplan.experiments.config import METRICS, ExperimentConfig, FigureSpec, applies, nav_config
from jaxplan.experiments.run_data import (
    RunData,
    cell_path_m,
    disc_positions,
    figure_metric,
    figure_title,
    map_layer,
    metric_label,
    metric_scale,
    need_trials,
    panel_grid,
    scenario_of,
    scenario_seed,
    selected,
    trial_obstacles,
)

__all__ = ["DRAW"]

plt = plots.plt  # the Agg backend is chosen in plots


COSTS: dict[str, tuple[str, str, tuple[str, ...]]] = {
    "aco": ("path length L", "m", ()),
    "iaco": ("fitness F = l1 L/L0 + l2 sum|turn|/pi + l3 sum 1/d", "dimensionless", ("lambdas",)),
    "risk_aco": ("cost B = u L + v risk + w turns", "cost units", ("u", "v", "w")),
    "opt_ant": ("cost S = a L + b turns + c height msd", "cost units", ("a", "b", "c")),
    "praco": ("cost Z = w1 L + w2 turns", "cost units", ("omega1", "omega2")),
}
"""ACO planner -> (its cost, the cost's unit, the parameters that weigh it): a convergence curve's quantity.
Two planners share a cost only with the same name and the same weights (tsp planners: the tour length)."""


def _cost_of(pc) -> tuple:
    """A planner's cost definition: (name, weights) — equal for planners whose best costs share an axis."""
    if pc.kind == "tsp":
        return ("tour",)
    _, _, keys = COSTS.get(pc.name, ("", "", ()))
    return (pc.name,) + tuple((k, str(pc.overrides.get(k))) for k in keys)


def _curves(run: RunData, spec: FigureSpec, key: str, what: str):
    """Convergence (``history``) or diversity curves of the selected iterative planners, one panel per map.

    Planners are drawn on one quantity only: their own best cost (with its unit) when they all share one
    cost definition (`COSTS`); otherwise each seed's curve relative to that seed's final best cost, in %
    (best cost: the excess over the final best; diversity: the sd of the ants' costs over the final best)."""
    mi, pi = selected(run, spec, ("plan", "tsp"))
    cfg = run.config
    pi = [p for p in pi if cfg.planners[p].name not in ("astar", "dijkstra")]
    if not pi:
        raise ValueError(f"figure {spec.name!r}: no iterative plan planner selected")
    sc = scenario_of(run, spec, mi)
    band = spec.params.get("band", "iqr") or None
    shared = len({_cost_of(cfg.planners[p]) for p in pi}) == 1
    first = cfg.planners[pi[0]]
    if shared:
        qty, unit = ("best tour length", "TSPLIB distance") if first.kind == "tsp" else \
            (f"best {COSTS.get(first.name, ('cost', 'cost units'))[0]}", COSTS.get(first.name, ('', 'cost units'))[1])
        ylabel = f"{qty} ({unit})" if key == "history" else f"sd of the ants' {qty[5:]} ({unit})"
    else:
        ylabel = ("best cost above the run's final best (%)" if key == "history"
                  else "sd of the ants' costs / the run's final best (%)")
    fig, axes = panel_grid(len(mi))
    for ax, m in zip(axes[0], mi, strict=True):
        curves = {}
        for p in pi:
            got = run.arrays(m, p, sc)
            if got is None or key not in got[0]:
                continue
            h = np.asarray(got[0][key][got[1]], np.float64)
            if not shared:
                final = np.asarray(got[0]["history"][got[1]], np.float64)[:, -1:]
                with np.errstate(invalid="ignore", divide="ignore"):
                    h = np.where(np.isfinite(final) & (final > 0),
                                 100.0 * (h / final - (1.0 if key == "history" else 0.0)), np.nan)
            curves[cfg.planners[p].label] = h
        if curves:
            plots.plot_convergence(ax, curves, band=band, ylabel=ylabel)
        if spec.params.get("log"):
            ax.set_yscale("log")
        ax.set_title(f"{run.prep.maps[m].spec.name}, scenario {sc}")
    fig.suptitle(figure_title(spec, what))
    bands = {"iqr": "median and 25-75 % band", "sd": "mean ± 1 sd", "minmax": "median and min-max band",
             None: "median"}[band]
    how = ("" if shared else " The planners' costs are defined differently, so each seed's curve is drawn "
           "relative to that seed's final best cost (in %), one quantity for every planner.")
    return fig, f"{what} over {len(cfg.seeds)} seeds at scenario {sc} ({bands}).{how}"


def _convergence(run, spec):
    return _curves(run, spec, "history", "Convergence: best cost per iteration")


def _diversity(run, spec):
    return _curves(run, spec, "diversity", "Population diversity (sd of the ants' path costs) per iteration")


def _box(run, spec):
    from jaxplan.experiments.stats import per_seed_means

    t = need_trials(run)
    metric = figure_metric(run, spec)
    mi, pi = selected(run, spec)
    fig, axes = panel_grid(len(mi), w=max(4.0, 1.1 * len(pi) + 1.5))
    for ax, m in zip(axes[0], mi, strict=True):
        name = run.prep.maps[m].spec.name
        data, labels = [], []
        for p in pi:
            label = run.config.planners[p].label
            if METRICS[metric].kinds.isdisjoint({run.config.planners[p].kind}) or not applies(
                    run.config.planners[p], run.prep.maps[m].spec):
                continue
            v, _ = per_seed_means(t, name, label, metric, run.config.seeds)
            data.append(v[np.isfinite(v)] * metric_scale(metric))
            labels.append(label)
        ax.boxplot(data, tick_labels=labels) if data else None
        ax.set_ylabel(metric_label(metric))
        ax.set_title(name)
        ax.tick_params(axis="x", labelrotation=30)
    fig.suptitle(figure_title(spec, f"{metric_label(metric)}: per-seed means"))
    return fig, (f"Box plot of the per-seed means of {metric_label(metric)} (each seed averaged over the map's "
                 "scenarios; box: quartiles, whiskers: 1.5 IQR, circles: seeds beyond).")


def _paper_value(cfg: ExperimentConfig, map_: str, label: str, metric: str):
    """The paper's value for (map, planner, metric), as the summary tables pick it (`stats._paper`)."""
    from jaxplan.experiments.stats import _paper

    return _paper(cfg, map_, label, metric)


def _bar(run, spec):
    from jaxplan.experiments.stats import per_seed_means

    t = need_trials(run)
    metric = figure_metric(run, spec)
    mi, pi = selected(run, spec)
    cfg = run.config
    fig, axes = panel_grid(len(mi), w=max(4.0, 1.2 * len(pi) + 1.5))
    any_paper = False
    for ax, m in zip(axes[0], mi, strict=True):
        name = run.prep.maps[m].spec.name
        here = [p for p in pi if applies(cfg.planners[p], run.prep.maps[m].spec)]
        xs, labels = np.arange(len(here)), []
        for j, p in enumerate(here):
            label = cfg.planners[p].label
            labels.append(label)
            v, _ = per_seed_means(t, name, label, metric, cfg.seeds)
            v = v[np.isfinite(v)] * metric_scale(metric)
            if v.size:
                ax.bar(j - 0.2, v.mean(), 0.4, yerr=v.std(ddof=1) if v.size > 1 else 0, color="C0", capsize=3,
                       label="ours" if j == 0 else None)
            pv = _paper_value(cfg, name, label, metric)
            if pv is not None:
                any_paper = True
                ax.bar(j + 0.2, pv.mean * metric_scale(metric), 0.4, yerr=(pv.sd or 0) * metric_scale(metric),
                       color="white", edgecolor="C1", hatch="//",
                       capsize=3, label="paper" if not ax.get_legend_handles_labels()[1].count("paper") else None)
        ax.set_xticks(xs, labels, rotation=30)
        ax.set_ylabel(metric_label(metric))
        ax.set_title(name)
        if ax.get_legend_handles_labels()[1]:
            ax.legend(fontsize=8)
    fig.suptitle(figure_title(spec, f"{metric_label(metric)}: mean ± sd over seeds"))
    cap = f"Mean ± sd over seeds of the per-seed means of {metric_label(metric)}"
    if any_paper:
        cap += f"; hatched bars: the paper's reported values ({cfg.paper_source}), not ours"
    return fig, cap + "."


def _log_x(xs: np.ndarray) -> bool:
    """A sweep over orders of magnitude (all x > 0, largest / smallest >= 100) is drawn on a log x axis."""
    xs = xs[np.isfinite(xs)]
    return bool(xs.size > 1 and np.all(xs > 0) and xs.max() / xs.min() >= 100.0)


def _sweep(run, spec):
    """``metric`` against ``x``: a generator parameter (one line per planner, a point per map), one number per
    map, or a planner parameter (one line per map, a point per planner: e.g. IACO's elite weight)."""
    from jaxplan.experiments.stats import per_seed_means

    t = need_trials(run)
    metric = figure_metric(run, spec)
    mi, pi = selected(run, spec)
    cfg = run.config
    x = spec.params["x"]
    scale = metric_scale(metric)
    xlabel = spec.params.get("xlabel", x if isinstance(x, str) else "x")
    by_planner = isinstance(x, str) and all(x not in run.prep.maps[m].spec.params for m in mi) and all(
        x in cfg.planners[p].overrides for p in pi)
    if isinstance(x, str) and not by_planner:
        xs = []
        for m in mi:
            ms = run.prep.maps[m].spec
            if x not in ms.params:
                raise ValueError(f"figure {spec.name!r}: map {ms.name!r} has no generator parameter {x!r} (nor does "
                                 f"every selected planner set it)")
            xs.append(float(ms.params[x]))
    elif by_planner:
        xs = [float(cfg.planners[p].overrides[x]) for p in pi]
    else:
        xs = [float(v) for v in x]
    xs = np.asarray(xs)
    order = np.argsort(xs, kind="stable")
    # lines: (legend label, [(map index, planner index)] along x)
    lines = ([(run.prep.maps[m].spec.name, [(m, p) for p in pi]) for m in mi] if by_planner
             else [(cfg.planners[p].label, [(m, p) for m in mi]) for p in pi])
    fig, ax = plt.subplots(figsize=(6, 4.2), constrained_layout=True)
    any_paper = False
    for name, cells in lines:
        mean, sd, pap = [], [], []
        for m, p in cells:
            mname, label = run.prep.maps[m].spec.name, cfg.planners[p].label
            v, _ = per_seed_means(t, mname, label, metric, cfg.seeds)
            v = v[np.isfinite(v)] * scale
            mean.append(v.mean() if v.size else math.nan)
            sd.append(v.std(ddof=1) if v.size > 1 else 0.0)
            pv = _paper_value(cfg, mname, label, metric)
            pap.append(pv.mean * scale if pv is not None else math.nan)
        mean, sd, pap = (np.asarray(a)[order] for a in (mean, sd, pap))
        (line,) = ax.plot(xs[order], mean, marker="o", label=f"{name} (ours, mean ± sd)")
        ax.fill_between(xs[order], mean - sd, mean + sd, color=line.get_color(), alpha=0.2, lw=0)
        if np.isfinite(pap).any():
            any_paper = True
            ax.plot(xs[order], pap, ls="--", marker="s", mfc="none", color=line.get_color(), label=f"{name} (paper)")
    log = _log_x(xs)
    if log:
        ax.set_xscale("log")
    ax.set_xlabel(xlabel + ("" if "(" in xlabel else " (dimensionless)"))
    ax.set_ylabel(metric_label(metric))
    if ax.get_legend_handles_labels()[1]:
        ax.legend(fontsize=8)
    ax.set_title(figure_title(spec, f"{metric_label(metric)} against {xlabel}"))
    cap = (f"{metric_label(metric)} against {xlabel}{' (log axis)' if log else ''}: mean ± sd over seeds of the "
           "per-seed means" + (", one line per map" if by_planner else ", one line per planner"))
    if any_paper:
        cap += f"; dashed open markers: the paper's values ({cfg.paper_source}), not ours"
    return fig, cap + "."


def _paths(run, spec):
    from jaxplan.smooth import smooth

    mi, pi = selected(run, spec, ("plan", "navigate"))
    sc, seed, r = scenario_seed(run, spec, mi)
    smoother = spec.params.get("smoothing")
    fig, axes = panel_grid(len(mi), w=6.0, h=4.8)
    for ax, m in zip(axes[0], mi, strict=True):
        mw = run.prep.maps[m]
        paths, labels, smoothed, smoothed_labels = [], [], [], []
        for p in pi:
            got = run.arrays(m, p, sc)
            if got is None:
                continue
            a, i = got
            if "paths" in a:
                pts, n = a["paths"][i, r], int(a["n_cells"][i, r])
            elif "plans" in a:
                pts, n = a["plans"][i, r], int(a["n_plan"][i, r])
            else:
                continue
            paths.append(cell_path_m(pts, n, mw.grid))
            labels.append(run.config.planners[p].label)
            if smoother and n > 0:
                sm = smooth(np.asarray(pts[:n], np.float64), mw.grid, smoother)
                smoothed.append(cell_path_m(np.asarray(sm.points), int(sm.n), mw.grid))
                smoothed_labels.append(f"{labels[-1]} ({smoother})")
        plots.plot_map(ax, mw.grid, layer=map_layer(mw.grid), title=f"{mw.spec.name}, scenario {sc}, seed {seed}")
        plots.plot_paths(ax, mw.grid, paths, labels=labels, start=cell_path_m(mw.starts[sc][None], 1, mw.grid)[0],
                         goal=cell_path_m(mw.goals[sc][None], 1, mw.grid)[0], coords="m")
        if smoothed:
            lines_before = len(ax.lines)
            plots.plot_paths(ax, mw.grid, smoothed, labels=smoothed_labels, coords="m", lw=1.4)
            for line in ax.lines[lines_before:]:
                line.set_linestyle("--")
            ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, borderaxespad=0.0)  # with the dashes
    fig.suptitle(figure_title(spec, "Planned paths"))
    cap = f"Global paths of each planner at scenario {sc}, seed {seed} (cell centres; start circle, goal star)"
    if smoother:
        cap += f"; dashed: the same path after the {smoother!r} smoother (jaxplan.smooth)"
    return fig, cap + "."


def _pheromone(run, spec):
    from jaxplan.aco import COLONIES  # the ant colony planners (as the runner tells them apart)
    from jaxplan.planning import plan

    mi, pi = selected(run, spec, "plan")
    sc, seed, _ = scenario_seed(run, spec, mi)
    todo = [(m, p) for m in mi for p in pi if run.config.planners[p].name in COLONIES]
    if not todo:
        raise ValueError(f"figure {spec.name!r}: no ant colony planner selected")
    fig, axes = panel_grid(len(todo), w=5.5, h=4.4)
    for ax, (m, p) in zip(axes[0], todo, strict=True):
        mw, pc = run.prep.maps[m], run.config.planners[p]
        overrides = {k: tuple(v) if isinstance(v, list) else v for k, v in pc.overrides.items()}
        res = plan(mw.grid, mw.starts[sc], mw.goals[sc], planner=pc.name, seed=seed, keep_pheromone=True,
                   **overrides)
        plots.plot_pheromone(ax, mw.grid, res.info["tau"], log=spec.params.get("log", True),
                             title=f"{pc.label} on {mw.spec.name}")
        if res.success:
            plots.plot_paths(ax, mw.grid, [np.asarray(res.path)], labels=[f"{pc.label} path"], lw=1.2)
            if ax.get_legend() is not None:  # one line, named in the caption: no legend beside the heat map
                ax.get_legend().remove()
    fig.suptitle(figure_title(spec, "Final pheromone per cell"))
    return fig, (f"Final pheromone per cell (max over its allowed outgoing edges) at scenario {sc}, seed {seed}, "
                 "with that trial's path (blue line); recomputed by re-planning the trial with keep_pheromone=True.")


def _nav_trial(run, m, p, sc, r):
    """(positions f32[T, 2] m, states f32[T, 5] or None, steps, plan m [L, 2]) of one navigate trial, or None."""
    got = run.arrays(m, p, sc)
    if got is None:
        return None
    a, i = got
    steps = int(a["steps"][i, r])
    pos = np.asarray(a["positions"][i, r, :steps + 1], np.float64)
    states = np.asarray(a["states"][i, r, :steps + 1], np.float64) if "states" in a else None
    plan = cell_path_m(a["plans"][i, r], int(a["n_plan"][i, r]), run.prep.maps[m].grid)
    return pos, states, steps, plan


def _teammates(run, m, p, sc, r) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """``(positions f64[T_j, 2] m, start m [2], goal m [2])`` of robots 1.. of a team trial (`team_positions`);
    empty for a single-robot planner. Robot 0 is the trial's own (`_nav_trial`)."""
    got = run.arrays(m, p, sc)
    if got is None or "team_positions" not in got[0]:
        return []
    a, i = got
    grid = run.prep.maps[m].grid
    out = []
    for j in range(1, a["team_positions"].shape[2]):
        steps = int(a["team_steps"][i, r, j])
        ends = cell_path_m(np.stack([a["team_starts"][i, j], a["team_goals"][i, j]]), 2, grid)
        out.append((np.asarray(a["team_positions"][i, r, j, :steps + 1], np.float64), ends[0], ends[1]))
    return out


def _trajectories(run, spec):
    mi, pi = selected(run, spec, "navigate")
    if not pi:
        raise ValueError(f"figure {spec.name!r}: no navigate planner selected")
    sc, seed, r = scenario_seed(run, spec, mi)
    fig, axes = panel_grid(len(mi) * len(pi), w=6.0, h=4.8)
    k = team = 0
    for m in mi:
        mw = run.prep.maps[m]
        for p in pi:
            ax = axes[0][k]
            k += 1
            pc = run.config.planners[p]
            plots.plot_map(ax, mw.grid, layer=map_layer(mw.grid), title=f"{pc.label} on {mw.spec.name}")
            got = _nav_trial(run, m, p, sc, r)
            if got is None:
                continue
            pos, _, steps, plan = got
            period = nav_config(pc)[0].dwa.period
            obs = trial_obstacles(run, m, p, sc, seed)
            if obs is not None:
                times = np.arange(steps + 1) * period
                d = disc_positions(obs, times)
                radii = np.asarray(obs.radii, np.float64)
                for j in range(d.shape[1]):
                    ax.plot(d[:, j, 0], d[:, j, 1], color="0.45", lw=0.8, ls=":")
                    # where each disc was when the robot came closest to it
                    t_close = int(np.argmin(np.hypot(*(d[:, j] - pos[:len(d)]).T)))
                    ax.add_patch(plt.Circle(tuple(d[t_close, j]), radii[j], color="tab:red", alpha=0.5))
                    ax.plot(*pos[t_close], "x", color="tab:red", ms=5)
            mates = _teammates(run, m, p, sc, r)
            team = max(team, len(mates) + 1)
            for j, (tp, ts, tg) in enumerate(mates):
                ax.plot(tp[:, 0], tp[:, 1], color="tab:purple", lw=1.0, alpha=0.8,
                        label="teammates (executed)" if j == 0 else None)
                ax.plot(*ts, "o", color="tab:purple", ms=4)
                ax.plot(*tg, "*", color="tab:purple", ms=7)
            plots.plot_paths(ax, mw.grid, [plan, pos], labels=["global path", "executed"],
                             start=pos[0], goal=cell_path_m(mw.goals[sc][None], 1, mw.grid)[0], coords="m", lw=1.5)
    fig.suptitle(figure_title(spec, f"Executed trajectories, scenario {sc}, seed {seed}"))
    caption = (f"Executed trajectories (scenario {sc}, seed {seed}) over the global path; dotted: the moving "
               "discs' tracks, red discs where each disc was at the robot's closest approach (x).")
    if team > 1:
        caption += (f" A team of {team} robots shares each episode: robot 0 (the scenario's start and goal) is drawn "
                    "with its global path; purple: its teammates' executed paths, starts (o) and goals (*).")
    return fig, caption


def _controls(run, spec):
    mi, pi = selected(run, spec, "navigate")
    if not pi:
        raise ValueError(f"figure {spec.name!r}: no navigate planner selected")
    sc, seed, r = scenario_seed(run, spec, mi)
    fig, axes = plt.subplots(2, len(mi), figsize=(7 * len(mi), 5.5), constrained_layout=True, squeeze=False,
                             sharex="col")
    for c, m in enumerate(mi):
        for p in pi:
            pc = run.config.planners[p]
            got = _nav_trial(run, m, p, sc, r)
            if got is None or got[1] is None:
                continue
            states = got[1]
            t = np.arange(len(states)) * nav_config(pc)[0].dwa.period
            axes[0][c].plot(t, states[:, 3], label=pc.label, lw=1.3)
            axes[1][c].plot(t, states[:, 4], label=pc.label, lw=1.3)
        axes[0][c].set_ylabel("v (m/s)")
        axes[1][c].set_ylabel("omega (rad/s)")
        axes[1][c].set_xlabel("time (s)")
        axes[0][c].set_title(f"{run.prep.maps[m].spec.name}, scenario {sc}, seed {seed}")
        axes[0][c].legend(fontsize=8)
    fig.suptitle(figure_title(spec, "Linear and angular velocity"))
    return fig, f"Linear velocity v and angular velocity omega of the executed episode (scenario {sc}, seed {seed})."


def _fan(run, spec):
    from jaxplan.dwa import dwa_step
    from jaxplan.nav import get_pipeline

    mi, pi = selected(run, spec, "navigate")
    if not pi:
        raise ValueError(f"figure {spec.name!r}: no navigate planner selected")
    sc, seed, r = scenario_seed(run, spec, mi)
    panels = [(m, p) for m in mi for p in pi]
    fig, axes = panel_grid(len(panels), w=6.0, h=4.8)
    for ax, (m, p) in zip(axes[0], panels, strict=True):
        mw, pc = run.prep.maps[m], run.config.planners[p]
        navcfg, weights = nav_config(pc)
        dwa = navcfg.dwa
        pipe = get_pipeline(pc.name)
        if navcfg.evaluator is None and pipe.evaluator and hasattr(dwa, "evaluator"):
            dwa = dataclasses.replace(dwa, evaluator=pipe.evaluator)
        dwa = dataclasses.replace(dwa, keep_rollouts=True)  # episodes drop them; the fan needs them
        plots.plot_map(ax, mw.grid, title=f"{pc.label} on {mw.spec.name}", colorbar=False)
        got = _nav_trial(run, m, p, sc, r)
        if got is None or got[1] is None:
            continue
        pos, states, steps, plan = got
        wanted = spec.params.get("steps") or [steps // 2]
        obs = trial_obstacles(run, m, p, sc, seed)
        ax.plot(pos[:, 0], pos[:, 1], color="0.3", lw=1.0, label="executed")
        ax.plot(plan[:, 0], plan[:, 1], color="C2", lw=1.0, ls="--", label="global path")
        for s in wanted:
            s = min(int(s), steps)
            state = states[s]
            # sub-goal: the global path's point `lookahead` metres past the point nearest the robot
            near = int(np.argmin(np.hypot(*(plan - state[:2]).T))) if len(plan) else 0
            seg = np.r_[0.0, np.cumsum(np.hypot(*np.diff(plan[near:], axis=0).T))] if len(plan) else np.zeros(1)
            ahead = near + int(np.searchsorted(seg, navcfg.lookahead)) if len(plan) else 0
            subgoal = plan[min(ahead, len(plan) - 1)] if len(plan) else state[:2]
            discs = None
            if obs is not None:
                from jaxplan.nav import discs_at

                discs = discs_at(obs, s * dwa.period)
                for c, rad in zip(np.asarray(discs.positions), np.asarray(discs.radii), strict=True):
                    ax.add_patch(plt.Circle(tuple(c), float(rad), color="tab:red", alpha=0.5))
            _, info = dwa_step(state, subgoal, mw.grid, obstacles=discs, params=weights or None, config=dwa,
                               path=plan if len(plan) > 1 else None)
            ro, ok = np.asarray(info.rollouts), np.asarray(info.feasible)
            for j in np.flatnonzero(~ok)[::2]:
                ax.plot(ro[j, :, 0], ro[j, :, 1], color="tab:red", lw=0.3, alpha=0.4)
            for j in np.flatnonzero(ok):
                ax.plot(ro[j, :, 0], ro[j, :, 1], color="tab:blue", lw=0.3, alpha=0.5)
            ch = int(info.chosen)
            ax.plot(ro[ch, :, 0], ro[ch, :, 1], color="k", lw=2.0)
            ax.plot(*subgoal, "*", color="C1", ms=9)
        ax.legend(fontsize=7, loc="best")
        if len(wanted) == 1:  # zoom on the fan
            c = states[min(int(wanted[0]), steps), :2]
            span = max(2.5, dwa.horizon * float(dwa.robot.v_max) * 1.3)
            ax.set_xlim(c[0] - span, c[0] + span)
            ax.set_ylim(c[1] + span, c[1] - span)  # row 0 at the top, as plot_map draws it
    fig.suptitle(figure_title(spec, "DWA trajectory fans"))
    steps_text = ", ".join(str(int(v)) for v in spec.params["steps"]) if spec.params.get("steps") else "mid-episode"
    return fig, (f"Dynamic-window rollouts at control steps {steps_text} "
                 f"(scenario {sc}, seed {seed}): feasible blue, infeasible red, chosen black, sub-goal star; "
                 "recomputed with jaxplan.dwa_step at the stored robot states.")


def _tours(run, spec):
    from jaxplan.aco import load_tour, tour_length

    mi, pi = selected(run, spec, "tsp")
    _, seed, r = scenario_seed(run, spec)
    fig, axes = panel_grid(len(mi), w=5.5, h=4.8)
    for ax, m in zip(axes[0], mi, strict=True):
        mw = run.prep.maps[m]
        if mw.problem.coords is None:
            raise ValueError(f"figure {spec.name!r}: instance {mw.spec.name!r} has no city coordinates")
        xy = np.asarray(mw.problem.coords, np.float64)
        if mw.spec.tour is not None:  # the optimal tour underneath, for comparison
            t = load_tour(mw.spec.tour)
            c = xy[np.append(t, t[0])]
            ax.plot(c[:, 0], c[:, 1], color="0.6", ls="--", lw=2.5,
                    label=f"optimal ({tour_length(mw.problem, t):g})")
        for p in pi:
            got = run.arrays(m, p, 0)
            if got is None or "tours" not in got[0]:
                continue
            t = np.asarray(got[0]["tours"][got[1], r], np.int64)
            c = xy[np.append(t, t[0])]
            label = f"{run.config.planners[p].label} ({tour_length(mw.problem, t):g})"
            ax.plot(c[:, 0], c[:, 1], lw=1.2, label=label)
        ax.plot(xy[:, 0], xy[:, 1], "k.", ms=5)
        ax.set_aspect("equal")
        ax.set_title(f"{mw.spec.name}, seed {seed}")
        ax.legend(fontsize=8)
    fig.suptitle(figure_title(spec, "Best tours"))
    return fig, (f"Best tour of each TSP planner at seed {seed} (length in the instance's metric); dashed grey: "
                 "the optimal tour of the instance's .opt.tour file.")


DRAW: dict[str, Callable[[RunData, FigureSpec], tuple[Any, str]]] = {
    "convergence": _convergence, "diversity": _diversity, "box": _box, "bar": _bar, "sweep": _sweep,
    "paths": _paths, "pheromone": _pheromone, "trajectories": _trajectories, "controls": _controls, "fan": _fan,
    "tours": _tours,
}
"""Figure kind -> drawing function ``(run, spec) -> (figure, caption)``."""
