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
from matplotlib.lines import Line2D

from jaxplan.experiments import plots, style
from jaxplan.experiments.comparability import comparable
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


ITERATION_METRICS = ("turning_point", "optimum_iteration", "converged_iteration", "converged_iteration_strict")
"""The convergence iterations a paper may report, the paper-specific definitions first: the one a convergence
figure marks for a planner is the first of these the config's [paper] values give."""


def _cost_label(pc, key: str) -> str:
    """The y-axis label of a planner's convergence (``history``) or diversity curve: its own cost, with unit."""
    qty, unit = ("best tour length", "TSPLIB distance") if pc.kind == "tsp" else \
        (f"best {COSTS.get(pc.name, ('cost', 'cost units'))[0]}", COSTS.get(pc.name, ('', 'cost units'))[1])
    return f"{qty} ({unit})" if key == "history" else f"sd of the ants' {qty[5:]} ({unit})"


def _paper_iteration(run: RunData, m: int, label: str):
    """``(metric, value)`` of the paper's convergence iteration for a planner on map ``m``, or None; and whether
    it may be marked (`comparable`: an iteration count only on the paper's own map or instance)."""
    ms = run.prep.maps[m].spec
    for metric in ITERATION_METRICS:
        pv = _paper_value(run.config, ms.name, label, metric)
        if pv is not None:
            return (metric, pv), comparable(metric, _is_paper_map(ms))
    return None, False


def _curves(run: RunData, spec: FigureSpec, key: str, what: str):
    """Convergence (``history``) or diversity curves of the selected iterative planners in absolute cost: one
    panel per map and cost definition (`COSTS`; planners share a panel only when they share a cost and its
    weights). On a convergence panel, a planner's convergence iteration as the paper reports it is a dashed
    vertical line, where the paper's number is comparable (`jaxplan.experiments.comparability`)."""
    mi, pi = selected(run, spec, ("plan", "tsp"))
    cfg = run.config
    pi = [p for p in pi if cfg.planners[p].name not in ("astar", "dijkstra")]
    if not pi:
        raise ValueError(f"figure {spec.name!r}: no iterative plan planner selected")
    sc = scenario_of(run, spec, mi)
    band = spec.params.get("band", "iqr") or None
    groups: dict[tuple, list[int]] = {}
    for p in pi:
        groups.setdefault(_cost_of(cfg.planners[p]), []).append(p)
    panels = [(m, g) for m in mi for g in groups.values()]
    fig, axes = panel_grid(len(panels))
    marked, hidden = [], []
    for ax, (m, group) in zip(axes[0], panels, strict=True):
        curves, colours = {}, []
        for p in group:
            got = run.arrays(m, p, sc)
            if got is None or key not in got[0]:
                continue
            curves[cfg.planners[p].label] = np.asarray(got[0][key][got[1]], np.float64)
            colours.append(f"C{pi.index(p) % 10}")  # a planner keeps its colour across panels
        ylabel = _cost_label(cfg.planners[group[0]], key)
        if curves:
            plots.plot_convergence(ax, curves, band=band, ylabel=ylabel, colors=colours)
        if key == "history":
            colours = {ln.get_label(): ln.get_color() for ln in ax.lines}
            for p in group:
                label = cfg.planners[p].label
                got, show = _paper_iteration(run, m, label)
                if got is None:
                    continue
                metric, pv = got
                note = f"{label}: {pv.mean:g} ({metric})"
                if not show:
                    hidden.append(note)
                    continue
                marked.append(note)
                ax.axvline(pv.mean, ls="--", lw=1.2, color=colours.get(label, "0.3"),
                           label=f"paper: iteration {pv.mean:g} ({label})")
            if ax.get_legend_handles_labels()[1]:
                ax.legend(fontsize=8)
        if spec.params.get("log"):
            ax.set_yscale("log")
        ax.set_ylabel(ylabel)
        title = f"{run.prep.maps[m].spec.name}, scenario {sc}"
        ax.set_title(title if len(groups) == 1 else f"{title}\n{', '.join(cfg.planners[p].label for p in group)}",
                     fontsize=10)
    fig.suptitle(figure_title(spec, what))
    bands = {"iqr": "median and 25-75 % band", "sd": "mean ± 1 sd", "minmax": "median and min-max band",
             None: "median"}[band]
    cap = f"{what} over {len(cfg.seeds)} seeds at scenario {sc} ({bands}), in each planner's own cost"
    if len(groups) > 1:
        cap += "; planners whose costs are defined differently are drawn in panels of their own"
    if marked:
        cap += ("; dashed vertical lines: the iteration the paper reports for the planner (its count from 1, on "
                f"the x axis's count): {'; '.join(marked)}")
    if hidden:
        cap += (f". The paper's iteration counts ({'; '.join(hidden)}) are not marked: an iteration count on a "
                "stand-in map or instance is not comparable with the paper's")
    return fig, cap + "."


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


def _is_paper_map(ms) -> bool:
    """The map (or instance) is the paper's own, as published (`MapSpec.paper_map`)."""
    return bool(getattr(ms, "paper_map", False))


def _shown_paper(run: RunData, m: int, label: str, metric: str):
    """``(value, hidden)``: the paper's value to draw beside ours on map ``m`` (None: none given, or not
    comparable there), and whether a value exists but is withheld (`jaxplan.experiments.comparability`)."""
    ms = run.prep.maps[m].spec
    pv = _paper_value(run.config, ms.name, label, metric)
    if pv is None:
        return None, False
    if not comparable(metric, _is_paper_map(ms)):
        return None, True
    return pv, False


def _wilson(k: int, n: int, level: float = 0.95) -> tuple[float, float]:
    """Wilson score interval of the proportion ``k / n`` (`scipy.stats.binomtest`): ``(low, high)`` inside
    [0, 1], nan without trials."""
    from scipy.stats import binomtest

    if n <= 0:
        return math.nan, math.nan
    ci = binomtest(int(k), int(n)).proportion_ci(confidence_level=level, method="wilson")
    return float(ci.low), float(ci.high)


def _rate_counts(run: RunData, name: str, p: int, metric: str) -> tuple[int, int]:
    """``(k, n)``: a proportion's successes and outcomes pooled over every trial (seeds and scenarios) of
    planner ``p`` on map ``name``. A trial's value is 0 or 1, except a team's ``arrived``, the share of its
    robots that arrived: there the team's robots are the outcomes (k = share x robots)."""
    from jaxplan.experiments.stats import trial_mask

    t = run.trials
    label = run.config.planners[p].label
    v = np.asarray(t[metric][trial_mask(t, name, label, metric)], np.float64)
    v = v[np.isfinite(v)]
    team = run.config.planners[p].team
    units = int(team.robots) if team is not None and metric == "arrived" else 1
    return int(round(float(v.sum()) * units)), int(v.size) * units


def _ours(run: RunData, name: str, p: int, metric: str, scale: float) -> tuple[float, float, float]:
    """``(centre, low, high)`` of our value on map ``name`` (times ``scale``): a proportion (`Metric.rate`) as the
    pooled share of trials with its Wilson 95 % interval, any other metric as the mean ± sd of the per-seed
    means. nan where the planner has no defined value."""
    from jaxplan.experiments.stats import per_seed_means

    if METRICS[metric].rate:
        k, n = _rate_counts(run, name, p, metric)
        lo, hi = _wilson(k, n)
        return (k / n * scale if n else math.nan), lo * scale, hi * scale
    v, _ = per_seed_means(run.trials, name, run.config.planners[p].label, metric, run.config.seeds)
    v = v[np.isfinite(v)] * scale
    if not v.size:
        return math.nan, math.nan, math.nan
    sd = float(v.std(ddof=1)) if v.size > 1 else 0.0
    return float(v.mean()), float(v.mean()) - sd, float(v.mean()) + sd


def _steering_limits(cfg: ExperimentConfig, pi) -> list[tuple[float, float, float]]:
    """``(δmax rad, L m, κ 1/m)`` of each distinct Ackermann robot among planners ``pi``: the curvature
    ``κ = tan(δmax) / L`` its steering cannot exceed (`jaxplan.dwa.Ackermann`)."""
    from jaxplan.dwa import Ackermann

    out = []
    for p in pi:
        pc = cfg.planners[p]
        if pc.kind != "navigate":
            continue
        robot = nav_config(pc)[0].dwa.robot
        if isinstance(robot, Ackermann):
            lim = (float(robot.steer_max), float(robot.wheelbase),
                   math.tan(float(robot.steer_max)) / float(robot.wheelbase))
            if lim not in out:
                out.append(lim)
    return out


def _draw_steering_limits(ax, limits) -> None:
    """A dotted horizontal line per Ackermann steering limit, named in the legend with its arithmetic."""
    for j, (steer, wheelbase, kappa) in enumerate(limits):
        ax.axhline(kappa, ls=":", lw=1.5, color=("k", "0.4", "0.6")[j % 3],
                   label=f"Ackermann limit tan(δmax)/L = tan({steer:g} rad)/{wheelbase:g} m = {kappa:.2f} 1/m")


def _ours_text(metric: str) -> str:
    return ("pooled share of trials, Wilson 95 % interval" if METRICS[metric].rate
            else "mean ± sd of per-seed means")


def _hidden_text(metric: str, hidden: list[str]) -> str:
    """The caption sentence naming paper values withheld as not comparable (empty when none is)."""
    if not hidden:
        return ""
    return (f" The paper's values of {metric_label(metric)} for {', '.join(sorted(set(hidden)))} are not drawn: an "
            "absolute number on a stand-in map is not comparable with ours (jaxplan.experiments.comparability).")


def _bar(run, spec):
    need_trials(run)
    metric = figure_metric(run, spec)
    mi, pi = selected(run, spec)
    cfg = run.config
    scale = metric_scale(metric)
    rate = METRICS[metric].rate
    fig, axes = panel_grid(len(mi), w=max(4.0, 1.2 * len(pi) + 1.5))
    any_paper, hidden = False, []
    limits = _steering_limits(cfg, pi) if metric == "max_curvature" else []
    for ax, m in zip(axes[0], mi, strict=True):
        name = run.prep.maps[m].spec.name
        here = [p for p in pi if applies(cfg.planners[p], run.prep.maps[m].spec)]
        labels = [cfg.planners[p].label for p in here]
        papers = [_shown_paper(run, m, label, metric) for label in labels]
        hidden += [label for label, (_, withheld) in zip(labels, papers, strict=True) if withheld]
        pair = any(pv is not None for pv, _ in papers)  # ours and the paper's side by side, else ours centred
        any_paper |= pair
        for j, (p, (pv, _)) in enumerate(zip(here, papers, strict=True)):
            centre, lo, hi = _ours(run, name, p, metric, scale)
            if np.isfinite(centre):
                ax.bar(j - 0.2 if pair else j, centre, 0.4 if pair else 0.6, yerr=[[centre - lo], [hi - centre]],
                       color="C0", capsize=3, label=f"ours ({_ours_text(metric)})" if j == 0 else None)
            if pv is not None:
                sd = (pv.sd or 0.0) * scale
                ax.bar(j + 0.2, pv.mean * scale, 0.4, yerr=sd, color="white", edgecolor="C1", hatch="//",
                       capsize=3, label=None if "paper" in " ".join(ax.get_legend_handles_labels()[1])
                       else ("paper (mean ± sd)" if pv.sd else "paper"))
        if limits:
            _draw_steering_limits(ax, limits)
        if rate:
            ax.set_ylim(0.0, 1.05 * scale)
        ax.set_xticks(np.arange(len(here)), labels, rotation=30, ha="right", rotation_mode="anchor")
        ax.set_ylabel(metric_label(metric))
        ax.set_title(name)
    plots.figure_legend(fig)
    fig.suptitle(figure_title(spec, f"{metric_label(metric)}: ours" + (" and the paper's" if any_paper else "")))
    cap = (f"{metric_label(metric)}: " + ("the share of all trials (pooled over seeds and scenarios) with its "
                                           "Wilson 95 % interval" if rate else
                                           "mean ± sd over seeds of the per-seed means"))
    if any_paper:
        cap += f"; hatched bars: the paper's reported values ± its sd ({cfg.paper_source}), not ours"
    if limits:
        cap += ("; dotted: the largest curvature the Ackermann steering allows, tan(δmax)/L of the configured "
                "robot (every executed path is bounded by it)")
    return fig, cap + "." + _hidden_text(metric, hidden)


def _log_x(xs: np.ndarray) -> bool:
    """A sweep over orders of magnitude (all x > 0, largest / smallest >= 100) is drawn on a log x axis."""
    xs = xs[np.isfinite(xs)]
    return bool(xs.size > 1 and np.all(xs > 0) and xs.max() / xs.min() >= 100.0)


def _sweep(run, spec):
    """``metric`` against ``x``: a generator parameter (one line per planner, a point per map), one number per
    map, or a planner parameter (one line per map, a point per planner: e.g. IACO's elite weight)."""
    need_trials(run)
    metric = figure_metric(run, spec)
    mi, pi = selected(run, spec)
    cfg = run.config
    x = spec.params["x"]
    scale = metric_scale(metric)
    rate = METRICS[metric].rate
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
    any_paper, hidden = False, []
    for name, cells in lines:
        ours, pap, pap_sd = [], [], []
        for m, p in cells:
            mname, label = run.prep.maps[m].spec.name, cfg.planners[p].label
            ours.append(_ours(run, mname, p, metric, scale))
            pv, withheld = _shown_paper(run, m, label, metric)
            if withheld:
                hidden.append(label)
            pap.append(pv.mean * scale if pv is not None else math.nan)
            pap_sd.append((pv.sd or 0.0) * scale if pv is not None else math.nan)
        centre, lo, hi = (np.asarray(a)[order] for a in zip(*ours, strict=True))
        pap, pap_sd = np.asarray(pap)[order], np.asarray(pap_sd)[order]
        (line,) = ax.plot(xs[order], centre, marker="o", label=f"{name} (ours, {_ours_text(metric)})")
        ax.fill_between(xs[order], lo, hi, color=line.get_color(), alpha=0.2, lw=0)
        if np.isfinite(pap).any():
            any_paper = True
            ok = np.isfinite(pap)
            ax.errorbar(xs[order][ok], pap[ok], yerr=pap_sd[ok], ls="--", marker="s", mfc="none", capsize=3,
                        color=line.get_color(), label=f"{name} (paper, mean ± sd)")
    log = _log_x(xs)
    if log:
        ax.set_xscale("log")
    if rate:
        ax.set_ylim(0.0, 1.05 * scale)
    ax.set_xlabel(xlabel + ("" if "(" in xlabel else " (dimensionless)"))
    ax.set_ylabel(metric_label(metric))
    plots.figure_legend(fig)
    ax.set_title(figure_title(spec, f"{metric_label(metric)} against {xlabel}"))
    cap = (f"{metric_label(metric)} against {xlabel}{' (log axis)' if log else ''}: "
           + ("the share of all trials (pooled over seeds and scenarios), band: its Wilson 95 % interval" if rate
              else "mean ± sd over seeds of the per-seed means")
           + (", one line per map" if by_planner else ", one line per planner"))
    if any_paper:
        cap += f"; dashed open markers: the paper's values ± its sd ({cfg.paper_source}), not ours"
    return fig, cap + "." + _hidden_text(metric, hidden)


def _map_features(grid) -> tuple[bool, bool]:
    """``(right-turn cells, tunnels)``: whether the map has free cells with chu2024's right-hand rule
    (``turn_rule == 1``) or a finite headroom (``clearance_height``), which a paths figure then marks."""
    free = np.asarray(grid.free)
    rules = bool(np.any((np.asarray(grid.turn_rule) == 1) & free))
    tunnels = bool(np.any(np.isfinite(np.asarray(grid.clearance_height)) & free))
    return rules, tunnels


def _map_view(mw) -> dict:
    """`plots.plot_map`'s ``keepout`` and ``y_up`` for a prepared map: a ROS map in its world frame (y up) with its
    keep-out cells drawn as zones, not walls (`style.keepout_mask`); any other map as before."""
    from jaxplan.grid import is_ros_map

    path = getattr(mw.spec, "path", None)
    if path is None or not is_ros_map(path):
        return {"keepout": None, "y_up": False}
    return {"keepout": style.keepout_mask(path, mw.grid, dict(mw.spec.ros)), "y_up": True}


def _paths(run, spec):
    from jaxplan.smoothing import smooth

    mi, pi = selected(run, spec, ("plan", "navigate"))
    sc, seed, r = scenario_seed(run, spec, mi)
    smoother = spec.params.get("smoothing")
    fig, axes = panel_grid(len(mi), w=6.0, h=5.6)
    marks: set[str] = set()
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
        rules, tunnels = _map_features(mw.grid)
        marks |= {k for k, on in (("turn", rules), ("tunnel", tunnels)) if on}
        plots.plot_map(ax, mw.grid, layer=map_layer(mw.grid), title=f"{mw.spec.name}, scenario {sc}, seed {seed}",
                       show_turn_rule=rules, show_tunnels=tunnels, **_map_view(mw))
        plots.plot_paths(ax, mw.grid, paths, labels=labels, start=cell_path_m(mw.starts[sc][None], 1, mw.grid)[0],
                         goal=cell_path_m(mw.goals[sc][None], 1, mw.grid)[0], coords="m")
        if smoothed:
            lines_before = len(ax.lines)
            plots.plot_paths(ax, mw.grid, smoothed, labels=smoothed_labels, coords="m", lw=1.4)
            for line in ax.lines[lines_before:]:
                line.set_linestyle("--")
            plots.legend_outside(ax)  # with the dashes
    fig.suptitle(figure_title(spec, "Planned paths"))
    cap = (f"Global paths of each planner at scenario {sc}, seed {seed} (cell centres; start green circle, goal "
           "red star)")
    if smoother:
        cap += f"; dashed: the same path after the {smoother!r} smoother (jaxplan.smoothing)"
    if "turn" in marks:
        cap += ("; purple squares: right-turn cells (chu2024's right-hand rule: opt_ant's ants entering one must "
                "turn right; the other planners ignore it)")
    if "tunnel" in marks:
        cap += ("; hatched cells: tunnels, passable only by a vehicle lower than the headroom (opt_ant's "
                "vehicle_height)")
    return fig, cap + "."


def _pheromone(run, spec):
    from jaxplan.aco import COLONIES  # the ant colony planners (as the runner tells them apart)
    from jaxplan.planning import plan

    mi, pi = selected(run, spec, "plan")
    sc, seed, _ = scenario_seed(run, spec, mi)
    todo = [(m, p) for m in mi for p in pi if run.config.planners[p].name in COLONIES]
    if not todo:
        raise ValueError(f"figure {spec.name!r}: no ant colony planner selected")
    fig, axes = panel_grid(len(todo), w=5.5, h=4.8)
    for ax, (m, p) in zip(axes[0], todo, strict=True):
        mw, pc = run.prep.maps[m], run.config.planners[p]
        overrides = {k: tuple(v) if isinstance(v, list) else v for k, v in pc.overrides.items()}
        res = plan(mw.grid, mw.starts[sc], mw.goals[sc], planner=pc.name, seed=seed, keep_pheromone=True,
                   **overrides)
        plots.plot_pheromone(ax, mw.grid, res.info["tau"], log=spec.params.get("log", True),
                             title=f"{pc.label} on {mw.spec.name}", y_up=_map_view(mw)["y_up"])
        if res.success:  # its legend goes below the map, clear of the colour bar
            plots.plot_paths(ax, mw.grid, [np.asarray(res.path)], labels=[f"{pc.label} path"], lw=1.2)
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
    fig, axes = panel_grid(len(mi) * len(pi), w=6.0, h=5.8)
    k = team = 0
    for m in mi:
        mw = run.prep.maps[m]
        for p in pi:
            ax = axes[0][k]
            k += 1
            pc = run.config.planners[p]
            plots.plot_map(ax, mw.grid, layer=map_layer(mw.grid), title=f"{pc.label} on {mw.spec.name}",
                           **_map_view(mw))
            got = _nav_trial(run, m, p, sc, r)
            if got is None:
                continue
            pos, _, steps, plan = got
            dwa = nav_config(pc)[0].dwa
            obs = trial_obstacles(run, m, p, sc, seed)
            if obs is not None:
                d = disc_positions(obs, np.arange(steps + 1) * dwa.period)
                radii = np.asarray(obs.radii, np.float64)
                # each walker where the robot came closest to it, the robot's footprint there: the gap it kept
                near = style.closest_approach(pos, d)
                style.draw_walkers(ax, d, radii, at=near, disc_label="walkers at their closest approach (to scale)")
                for i, j in enumerate(style.real_walkers(radii)):
                    style.draw_footprint(ax, pos[min(int(near[j]), len(pos) - 1)], dwa.robot.footprint,
                                         color="0.2", fill=False, alpha=1.0,
                                         label="robot at a walker's closest approach (to scale)" if i == 0 else None)
            mates = _teammates(run, m, p, sc, r)
            team = max(team, len(mates) + 1)
            for j, (tp, ts, tg) in enumerate(mates):
                ax.plot(tp[:, 0], tp[:, 1], color="tab:purple", lw=1.0, alpha=0.8,
                        label="teammates (executed)" if j == 0 else None)
                style.mark_start_goal(ax, ts, tg, team=True, label=j == 0)
            # the robot in the style's colours (the colour cycle's orange is the walkers')
            if len(plan):
                ax.plot(plan[:, 0], plan[:, 1], **{**style.PLAN, "label": "global path"})
            ax.plot(pos[:, 0], pos[:, 1], color=style.ROBOT, lw=1.5, zorder=3, label="executed")
            style.mark_start_goal(ax, pos[0, :2], cell_path_m(mw.goals[sc][None], 1, mw.grid)[0])
            plots.legend_outside(ax)
    fig.suptitle(figure_title(spec, f"Executed trajectories, scenario {sc}, seed {seed}"))
    caption = (f"Executed trajectories (scenario {sc}, seed {seed}) over the global path; dashed orange: the "
               "walkers' paths, orange discs (to scale) where each walker was at the robot's closest approach, with "
               "the robot's footprint (outline) at that moment.")
    if team > 1:
        caption += (f" A team of {team} robots shares each episode: robot 0 (the scenario's start and goal) is drawn "
                    "with its global path; purple: its teammates' executed paths; hollow circles and stars: their "
                    "starts and goals.")
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
    fig, axes = panel_grid(len(panels), w=6.0, h=5.8)
    for ax, (m, p) in zip(axes[0], panels, strict=True):
        mw, pc = run.prep.maps[m], run.config.planners[p]
        navcfg, weights = nav_config(pc)
        dwa = navcfg.dwa
        pipe = get_pipeline(pc.name)
        if navcfg.evaluator is None and pipe.evaluator and hasattr(dwa, "evaluator"):
            dwa = dataclasses.replace(dwa, evaluator=pipe.evaluator)
        dwa = dataclasses.replace(dwa, keep_rollouts=True)  # episodes drop them; the fan needs them
        view = _map_view(mw)
        plots.plot_map(ax, mw.grid, title=f"{pc.label} on {mw.spec.name}", colorbar=False, **view)
        got = _nav_trial(run, m, p, sc, r)
        if got is None or got[1] is None:
            continue
        pos, states, steps, plan = got
        wanted = spec.params.get("steps") or [steps // 2]
        obs = trial_obstacles(run, m, p, sc, seed)
        ax.plot(pos[:, 0], pos[:, 1], color=style.ROBOT, lw=1.0, label="executed")
        ax.plot(plan[:, 0], plan[:, 1], **{**style.PLAN, "label": "global path"})
        for w, s in enumerate(wanted):
            s = min(int(s), steps)
            once = w == 0  # one legend entry per kind of mark
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
                style.draw_walkers(ax, np.asarray(discs.positions)[None], np.asarray(discs.radii), at=0, paths=False,
                                   disc_label="walkers (to scale)" if once else None)
            _, info = dwa_step(state, subgoal, mw.grid, obstacles=discs, params=weights or None, config=dwa,
                               path=plan if len(plan) > 1 else None)
            ro, ok = np.asarray(info.rollouts), np.asarray(info.feasible)
            for i, j in enumerate(np.flatnonzero(~ok)[::2]):
                ax.plot(ro[j, :, 0], ro[j, :, 1], color="tab:red", lw=0.3, alpha=0.4,
                        label="infeasible rollouts (every 2nd)" if once and i == 0 else None)
            for i, j in enumerate(np.flatnonzero(ok)):
                ax.plot(ro[j, :, 0], ro[j, :, 1], color="tab:blue", lw=0.3, alpha=0.5,
                        label="feasible rollouts" if once and i == 0 else None)
            ch = int(info.chosen)
            ax.plot(ro[ch, :, 0], ro[ch, :, 1], color="k", lw=2.0, label="chosen rollout" if once else None)
            # an outline: the fan starts inside the footprint
            style.draw_footprint(ax, state[:3], dwa.robot.footprint, fill=False, alpha=1.0,
                                 label="robot (footprint to scale)" if once else None)
            # a diamond: the goal's star stays the goal's, in every figure
            ax.plot(*subgoal, "D", color="tab:cyan", mec="k", ms=7, zorder=6,
                    label=f"sub-goal ({navcfg.lookahead:g} m ahead on the global path)" if once else None)
        legend = plots.legend_outside(ax)
        for h in legend.legend_handles if legend is not None else ():
            if isinstance(h, Line2D) and h.get_linewidth() < 1.0:
                h.set_linewidth(1.5)  # a rollout's hairline, legible in the legend
                h.set_alpha(1.0)
        if len(wanted) == 1:  # zoom on the fan
            c = states[min(int(wanted[0]), steps), :2]
            span = max(2.5, dwa.horizon * float(dwa.robot.v_max) * 1.3)
            ax.set_xlim(c[0] - span, c[0] + span)
            # row 0 at the top, as plot_map draws it (a ROS map's world frame: y up)
            ax.set_ylim((c[1] - span, c[1] + span) if view["y_up"] else (c[1] + span, c[1] - span))
    fig.suptitle(figure_title(spec, "DWA trajectory fans"))
    steps_text = ", ".join(str(int(v)) for v in spec.params["steps"]) if spec.params.get("steps") else "mid-episode"
    return fig, (f"Dynamic-window rollouts at control steps {steps_text} "
                 f"(scenario {sc}, seed {seed}): feasible blue, infeasible red, chosen black, sub-goal diamond, the "
                 "robot's footprint to scale; "
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
        ax.plot(xy[:, 0], xy[:, 1], "k.", ms=5, label="cities")
        ax.set_aspect("equal")
        ax.set_title(f"{mw.spec.name}, seed {seed}")
        plots.legend_outside(ax)
    fig.suptitle(figure_title(spec, "Best tours"))
    return fig, (f"Best tour of each TSP planner at seed {seed} (length in the instance's metric); dashed grey: "
                 "the optimal tour of the instance's .opt.tour file.")


DRAW: dict[str, Callable[[RunData, FigureSpec], tuple[Any, str]]] = {
    "convergence": _convergence, "diversity": _diversity, "box": _box, "bar": _bar, "sweep": _sweep,
    "paths": _paths, "pheromone": _pheromone, "trajectories": _trajectories, "controls": _controls, "fan": _fan,
    "tours": _tours,
}
"""Figure kind -> drawing function ``(run, spec) -> (figure, caption)``."""
