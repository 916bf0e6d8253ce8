"""The navigation frontier: what each local-planner safety mode costs, written from a finished run folder.

A frontier config (``configs/navigation.toml``: its name is ``navigation`` or starts with ``navigation_``) runs
navigate planners that differ in four coordinates — the local planner (``dwa`` or ``mppi``, from the pipeline),
the safety mode (``NavConfig.safety``: ``none``, ``predicted``, ``passive``), the walkers (``[planners.obstacles]
behavior``: ``blind`` or ``seeing`` = ``"social"``) and the walkers' speed — plus, per local planner and speed,
the oracle-prediction ceiling (``NavConfig.prediction = "oracle"``, safety none, blind walkers). `arms` reads
these coordinates from each planner entry itself (never from its label), so a config may label them as it likes.

Per map and arm (`frontier_rows`), over every feasible episode (seeds × scenario rows pooled):

- success and "episodes with an active contact": shares with their Wilson 95 % interval
  (`jaxplan.experiments.verdicts.wilson_interval`);
- active and passive contacts per episode, and time to goal over the successful episodes: means with their 95 %
  Student-t interval (`jaxplan.experiments.verdicts.mean_interval`).

`write_frontier` draws one figure per map (`frontier_figure`: success against the active-contact rate, and
against time to goal, one point per arm with both intervals as error bars) and writes the page
(`frontier_page`, ``RESULTS/navigation.md``; ``navigation-quick.md`` from a ``--quick`` run), which says in one
line whether the passive mode had zero active contacts in every row. `jaxplan reproduce` calls it for a frontier
config in place of a paper table's page (`jaxplan.experiments.reproduce`), and the results index lists the page
under "Beyond the papers" (`jaxplan.experiments.results.index_page`).
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from jaxplan.core import markdown as md
from jaxplan.experiments.config import ExperimentConfig, PlannerConfig
from jaxplan.experiments.verdicts import mean_interval, wilson_interval

__all__ = ["SAFETY_ORDER", "WALKER_KINDS", "Arm", "Rate", "Mean", "Row", "is_frontier", "arms", "frontier_rows",
           "pooled_rows", "frontier_figure", "frontier_page", "page_name", "write_frontier", "passive_verdict"]

SAFETY_ORDER = ("none", "predicted", "passive")
"""The safety modes of the local planners (`jaxplan.dwa.SAFETY_MODES`), in the order the page lists them."""
WALKER_KINDS = {"blind": "blind", "social": "seeing"}
"""``[planners.obstacles] behavior`` -> what the page calls those walkers."""
LOCAL_NAMES = {"dwa": "DWA", "mppi": "MPPI"}
CONFIDENCE = 0.95


@dataclass(frozen=True)
class Arm:
    """A planner entry's place in the design.

    Attributes:
      label: the entry's label (its trials' ``planner`` column).
      local: ``"dwa"`` or ``"mppi"``.
      safety: one of `SAFETY_ORDER`.
      walkers: ``"blind"`` or ``"seeing"``.
      speed: the walkers' route speed (m/s).
      oracle: the local planner predicts the walkers along their true routes (the prediction ceiling).
    """

    label: str
    local: str
    safety: str
    walkers: str
    speed: float
    oracle: bool

    @property
    def planner(self) -> str:
        return LOCAL_NAMES.get(self.local, self.local)


@dataclass(frozen=True)
class Rate:
    """``k`` of ``n`` episodes, with the Wilson interval (nan, nan for n = 0)."""

    k: int
    n: int

    @property
    def value(self) -> float:
        return self.k / self.n if self.n else math.nan

    @property
    def interval(self) -> tuple[float, float]:
        return wilson_interval(self.k, self.n, CONFIDENCE)

    def cell(self) -> str:
        """``"p % [lo, hi]"`` (percent), `md.MISSING` without episodes."""
        if not self.n:
            return md.MISSING
        lo, hi = self.interval
        return f"{_pct(self.value)} [{_pct(lo)}, {_pct(hi)}]"


@dataclass(frozen=True)
class Mean:
    """The mean of ``n`` values with its Student-t interval (nan where undefined), for a quantity that cannot be
    negative (contacts, seconds): the interval's lower end is clipped at 0, as a rate's is at 0 %."""

    mean: float
    lo: float
    hi: float
    n: int

    @classmethod
    def of(cls, values: np.ndarray) -> "Mean":
        v = np.asarray(values, np.float64)
        v = v[np.isfinite(v)]
        if not v.size:
            return cls(math.nan, math.nan, math.nan, 0)
        lo, hi = mean_interval(v, CONFIDENCE)
        return cls(float(v.mean()), max(lo, 0.0) if math.isfinite(lo) else lo, hi, int(v.size))

    def cell(self, digits: int = 3) -> str:
        """``"mean [lo, hi]"``; the mean alone where there is no interval (one value); `md.MISSING` without any."""
        if not self.n:
            return md.MISSING
        num = _num(digits)
        text = md.interval(self.lo, self.hi, num)
        return num(self.mean) if text == md.MISSING else f"{num(self.mean)} {text}"


@dataclass(frozen=True)
class Row:
    """One arm on one map (or pooled over maps: ``map = ""``).

    Attributes:
      arm: the arm.
      map: the map's name.
      infeasible: episodes not run (the robot cannot use the scenario's start or goal, or cannot reach it).
      success: episodes that reached the goal in time without any contact.
      touched: episodes with at least one active contact (the robot moving at contact).
      active, passive: contacts per episode.
      time: time to goal (s) of the successful episodes.
    """

    arm: Arm
    map: str
    infeasible: int
    success: Rate
    touched: Rate
    active: Mean
    passive: Mean
    time: Mean

    @property
    def episodes(self) -> int:
        return self.success.n


def _pct(x: float) -> str:
    return md.fmt(100.0 * x, 3)


def _num(digits: int) -> Callable[[float], str]:
    return lambda x: md.fmt(x, digits)


def is_frontier(name: str) -> bool:
    """Whether config ``name`` (an ``[experiment] name``, without ``-quick``) is a frontier config."""
    return name == "navigation" or name.startswith("navigation_")


def page_name(name: str, quick: bool = False) -> str:
    """The page's file name under the results root: ``NAME.md`` (``NAME-quick.md`` for a quick run)."""
    return f"{name}{'-quick' if quick else ''}.md"


def _arm(pc: PlannerConfig) -> Arm:
    from jaxplan.experiments.config_checks import nav_config
    from jaxplan.nav import get_pipeline

    where = f"planner {pc.label!r}"
    if pc.kind != "navigate" or pc.obstacles is None or pc.obstacles.n == 0 or pc.team is not None:
        raise ValueError(f"{where}: a frontier compares single-robot navigate planners among walkers "
                         "([planners.obstacles] with n >= 1)")
    cfg, _ = nav_config(pc)
    local = cfg.local or get_pipeline(pc.name).local
    if local not in LOCAL_NAMES:
        raise ValueError(f"{where}: local planner {local!r} has no safety mode (dwa or mppi)")
    sub = cfg.mppi if local == "mppi" else cfg.dwa
    safety = cfg.safety if cfg.safety is not None else getattr(sub, "safety", "none")
    oracle = cfg.prediction == "oracle"
    return Arm(pc.label, local, str(safety), WALKER_KINDS[pc.obstacles.behavior], float(pc.obstacles.speed), oracle)


def arms(cfg: ExperimentConfig) -> tuple[Arm, ...]:
    """The design coordinates of every planner of ``cfg``, in config order.

    Raises:
      ValueError: a planner that is not a single-robot navigate planner among walkers with the DWA or MPPI.
    """
    return tuple(_arm(pc) for pc in cfg.planners)


def _order(arm: Arm) -> tuple:
    """Table order: local planner, then the oracle after the plain arms, walkers, speed, safety."""
    return (list(LOCAL_NAMES).index(arm.local) if arm.local in LOCAL_NAMES else 9, arm.oracle,
            sorted(WALKER_KINDS.values()).index(arm.walkers), arm.speed,
            SAFETY_ORDER.index(arm.safety) if arm.safety in SAFETY_ORDER else 9)


def _row(t: Mapping[str, np.ndarray], cells: Sequence[tuple[str, str]], arm: Arm, name: str) -> Row:
    """The `Row` of ``arm`` over the trials of ``cells`` (``(map, planner label)`` pairs); which trials count is
    `jaxplan.experiments.stats.trial_mask`'s rule (never an infeasible one; time to goal only a successful one)."""
    from jaxplan.experiments.stats import trial_mask

    def mask(metric: str | None) -> np.ndarray:
        out = np.zeros(len(t["map"]), bool)
        for m, label in cells:
            out |= trial_mask(t, m, label, metric) if metric else (t["map"] == m) & (t["planner"] == label)
        return out

    ran = mask("success")
    everything = mask(None)
    ok = ran & (t["success"] == 1)
    active = t["active_contacts"][ran]
    return Row(arm, name, int((everything & ~ran).sum()), Rate(int(ok.sum()), int(ran.sum())),
               Rate(int((active > 0).sum()), int(ran.sum())), Mean.of(active), Mean.of(t["passive_contacts"][ran]),
               Mean.of(t["time_s"][mask("time_s")]))


_NEEDED = ("success", "active_contacts", "passive_contacts", "time_s")


def _check_columns(t: Mapping[str, np.ndarray]) -> None:
    missing = [c for c in _NEEDED if c not in t]
    if missing:
        raise ValueError(f"the run's trials lack {', '.join(missing)}: a frontier config's metrics must include "
                         + ", ".join(_NEEDED))


def frontier_rows(trials: Mapping[str, np.ndarray], cfg: ExperimentConfig) -> dict[str, list[Row]]:
    """``{map: [Row per arm]}`` in map config order, each map's rows in table order (`Row`)."""
    _check_columns(trials)
    out = {}
    the_arms = sorted(arms(cfg), key=_order)
    for ms in cfg.maps:
        on_map = trials["map"] == ms.name
        if not on_map.any():
            continue
        out[ms.name] = [_row(trials, [(ms.name, a.label)], a, ms.name) for a in the_arms]
    return out


def pooled_rows(trials: Mapping[str, np.ndarray], cfg: ExperimentConfig) -> list[Row]:
    """One `Row` per (local planner, safety mode, oracle), pooled over the maps, walkers and speeds."""
    _check_columns(trials)
    groups: dict[tuple, list[Arm]] = {}
    for a in sorted(arms(cfg), key=_order):
        groups.setdefault((a.local, a.safety, a.oracle), []).append(a)
    out = []
    for (local, safety, oracle), members in sorted(groups.items(), key=lambda kv: _order(kv[1][0])[:2]
                                                   + _order(kv[1][0])[-1:]):
        cells = [(ms.name, a.label) for ms in cfg.maps for a in members]
        walkers = sorted({a.walkers for a in members})
        speeds = sorted({a.speed for a in members})
        arm = Arm("", local, safety, "/".join(walkers), speeds[0] if len(speeds) == 1 else math.nan, oracle)
        out.append(_row(trials, cells, arm, ""))
    return out


def _ceiling(rows: Sequence[Row], arm: Arm) -> Row | None:
    """The oracle row of ``arm``'s local planner and speed (blind walkers), or None."""
    for r in rows:
        a = r.arm
        if a.oracle and a.local == arm.local and a.walkers == "blind" and a.speed == arm.speed:
            return r
    return None


def passive_verdict(rows: Mapping[str, Sequence[Row]]) -> tuple[bool | None, int, int, list[str]]:
    """``(zero, rows, episodes, offenders)`` of the passive mode over every map: whether every passive row had zero
    active contacts (None when no passive row ran an episode), how many rows and episodes that covers, and the
    rows that had some (``"map: label (k of n episodes)"``)."""
    n_rows = n_eps = 0
    bad = []
    for name, rs in rows.items():
        for r in rs:
            if r.arm.safety != "passive" or r.arm.oracle or not r.episodes:
                continue
            n_rows += 1
            n_eps += r.episodes
            if r.touched.k:
                bad.append(f"{name}: {r.arm.label} ({r.touched.k} of {r.episodes} episodes)")
    return (None if not n_rows else not bad), n_rows, n_eps, bad


# ---------------------------------------------------------------------------------------------
# The figure

SAFETY_COLOURS = {"none": "C0", "predicted": "C1", "passive": "C2"}
"""Colour of a safety mode's points; the oracle ceiling is black."""
ORACLE_COLOUR = "k"
WALKER_MARKERS = {"blind": "o", "seeing": "^"}
SPEED_SIZES = (4.0, 6.5, 9.0)
"""Marker sizes (points) of the slowest, middle and fastest walker speeds (more speeds repeat the largest)."""


def _err(centre: float, lo: float, hi: float) -> list[list[float]] | None:
    if not (math.isfinite(centre) and math.isfinite(lo) and math.isfinite(hi)):
        return None
    return [[max(centre - lo, 0.0)], [max(hi - centre, 0.0)]]


def frontier_figure(name: str, rows: Sequence[Row], *, quick: bool = False) -> tuple[Any, str]:
    """One map's figure: a row of two panels per local planner — success (%) against the share of episodes with an
    active contact (%), and against the mean time to goal (s) — one point per arm, coloured by safety mode
    (the oracle ceiling black), shaped by walkers (circle blind, triangle seeing), sized by walker speed, with
    their 95 % intervals (Wilson for shares, Student t for time) as error bars. Returns ``(figure, caption)``."""
    from matplotlib.lines import Line2D

    from jaxplan.experiments.plots import plt

    locals_ = [x for x in LOCAL_NAMES if any(r.arm.local == x for r in rows)]
    speeds = sorted({r.arm.speed for r in rows})
    size = {v: SPEED_SIZES[min(i, len(SPEED_SIZES) - 1)] for i, v in enumerate(speeds)}
    fig, axes = plt.subplots(len(locals_), 2, figsize=(10.0, 3.6 * len(locals_) + 1.2), squeeze=False,
                             sharey=True, layout="constrained")
    for ax_row, local in zip(axes, locals_, strict=True):
        for r in (r for r in rows if r.arm.local == local and r.episodes):
            a = r.arm
            colour = ORACLE_COLOUR if a.oracle else SAFETY_COLOURS.get(a.safety, "C7")
            kw = dict(marker=WALKER_MARKERS.get(a.walkers, "s"), ms=size[a.speed], color=colour, ls="none",
                      capsize=2, elinewidth=0.8, mec="k", mew=0.5, alpha=0.9,
                      mfc=colour if a.walkers == "blind" else "white")
            s, (s_lo, s_hi) = 100 * r.success.value, r.success.interval
            yerr = _err(s, 100 * s_lo, 100 * s_hi)
            x, (x_lo, x_hi) = 100 * r.touched.value, r.touched.interval
            ax_row[0].errorbar(x, s, xerr=_err(x, 100 * x_lo, 100 * x_hi), yerr=yerr, **kw)
            if r.time.n:
                ax_row[1].errorbar(r.time.mean, s, xerr=_err(r.time.mean, r.time.lo, r.time.hi), yerr=yerr, **kw)
        title = LOCAL_NAMES[local]
        ax_row[0].set_title(f"{title}: success against active contacts")
        ax_row[1].set_title(f"{title}: success against time to goal")
        ax_row[0].set_xlabel("episodes with an active contact (%)")
        ax_row[1].set_xlabel("time to goal, successful episodes (s)")
        ax_row[0].set_ylabel("success (%)")
        ax_row[0].set_xlim(-3.0, 103.0)
        ax_row[1].set_xlim(left=0.0)
        for ax in ax_row:
            ax.set_ylim(-3.0, 103.0)
            ax.grid(True, lw=0.3, alpha=0.5)
    handles = [Line2D([], [], color=SAFETY_COLOURS[s], marker="s", ls="none", label=f"safety {s}")
               for s in SAFETY_ORDER if any(r.arm.safety == s and not r.arm.oracle for r in rows)]
    if any(r.arm.oracle for r in rows):
        handles.append(Line2D([], [], color=ORACLE_COLOUR, marker="s", ls="none",
                              label="oracle prediction (safety none, blind)"))
    handles += [Line2D([], [], color="0.4", marker=WALKER_MARKERS[w], ls="none", mec="k",
                       mfc="0.4" if w == "blind" else "white", label=f"{w} walkers")
                for w in ("blind", "seeing") if any(r.arm.walkers == w for r in rows)]
    handles += [Line2D([], [], color="0.4", marker="o", ms=size[v], ls="none", mec="k", label=f"walkers at {v:g} m/s")
                for v in speeds]
    fig.legend(handles=handles, loc="outside lower center", ncol=4, fontsize=8, frameon=False)
    fig.suptitle(f"{name}: what each safety mode costs" + (" (QUICK run, not a result)" if quick else ""))
    caption = (f"{name}: one point per local planner × safety mode × walkers × walker speed (colour: safety mode, "
               "black the oracle-prediction ceiling; circle blind walkers, hollow triangle walkers that see; size: "
               "walker speed). Left: success against the share of episodes with an active contact (robot moving "
               "at contact), both with Wilson 95 % intervals; right: success against the mean time to goal of the "
               "successful episodes with its 95 % Student-t interval. Up and to the left is better.")
    return fig, caption


# ---------------------------------------------------------------------------------------------
# The page

INTRO = (
    "What does it cost a robot never to touch a walker while it moves? Each point of this page is one local planner "
    "(`iaco_dwa`'s DWA or `iaco_mppi`'s MPPI) with one safety mode among five random walkers of one kind and speed, "
    "on a MovingAI map, over the same scenario rows, seeds and walker routes for every arm (paired). The local "
    "planners' safety modes (`NavConfig.safety`, docs/guide/navigation.md):")
SAFETY_TABLE = (
    ("`none` (default)", "its rollout keeps `d_safe` from the map and from the walkers as predicted (constant "
     "velocity)", "none if a walker turns"),
    ("`predicted`", "… and from the rollout's end the robot can brake to rest before any *predicted* contact",
     "none if a walker turns"),
    ("`passive`", "after one control period at that control, braking as hard as the robot can keeps it off the map "
     "and out of every point a walker *can* reach", "a walker touches the robot only at rest"),
)
ASSUMPTION = (
    "The passive mode's guarantee holds under stated assumptions: every walker moves no faster than a known bound "
    "(here each episode's fastest walker: its route speed, × 1.3 for walkers that see, whose social force model may "
    "speed them up that much), each walker's position is known at the start of every control period, and the robot "
    "executes its commands. It says nothing about a walker that runs into a robot at rest: those are the passive "
    "contacts. The oracle ceiling tells the local planner (safety none) every blind walker's true route: no "
    "predictor can do better, so it bounds what better prediction alone could buy.")


def _setup(prep: Any, cfg: ExperimentConfig, rows: Mapping[str, Sequence[Row]]) -> list[str]:
    out = []
    for mw in prep.maps:
        if mw.spec.name not in rows:
            continue
        H, W = mw.grid.shape
        infeasible = max((r.infeasible for r in rows[mw.spec.name]), default=0)
        R = len(cfg.seeds)
        out.append(f"{mw.spec.name}: {W}×{H} cells of {float(mw.grid.resolution):g} m, {len(mw.starts)} scenario rows "
                   f"(optimal ≤ 80 cells, spread evenly over the file) × {R} seed{'s' if R != 1 else ''}"
                   + (f"; {infeasible} infeasible episodes per arm (not run)" if infeasible else "") + ".")
    return out


def _arm_cells(a: Arm) -> list[str]:
    return [a.planner, a.walkers, f"{a.speed:.1f}", "oracle (none)" if a.oracle else a.safety]


_HEAD = ["planner", "walkers", "speed (m/s)", "safety", "episodes", "success % [Wilson 95 %]",
         "active contacts / ep. [95 % t]", "passive contacts / ep. [95 % t]",
         "episodes with an active contact % [Wilson 95 %]", "time to goal (s) [95 % t]",
         "oracle ceiling: success % [Wilson 95 %]"]


def _map_table(rows: Sequence[Row]) -> str:
    body = []
    for r in rows:
        if r.arm.oracle:
            continue
        ceiling = _ceiling(rows, r.arm) if r.arm.walkers == "blind" else None
        body.append(_arm_cells(r.arm) + [str(r.episodes), r.success.cell(), r.active.cell(), r.passive.cell(),
                                         r.touched.cell(), r.time.cell(), ceiling.success.cell() if ceiling else
                                         md.MISSING])
    for r in rows:  # the ceilings themselves, with every column
        if r.arm.oracle:
            body.append(_arm_cells(r.arm) + [str(r.episodes), r.success.cell(), r.active.cell(), r.passive.cell(),
                                             r.touched.cell(), r.time.cell(), md.MISSING])
    return md.table(_HEAD, body, text=4)


def _pooled_table(rows: Sequence[Row]) -> str:
    body = [[r.arm.planner, "oracle (none)" if r.arm.oracle else r.arm.safety, str(r.episodes), r.success.cell(),
             r.touched.cell(), r.active.cell(), r.passive.cell(), r.time.cell()] for r in rows]
    return md.table(["planner", "safety", "episodes", "success % [Wilson 95 %]",
                     "episodes with an active contact % [Wilson 95 %]", "active contacts / ep. [95 % t]",
                     "passive contacts / ep. [95 % t]", "time to goal (s) [95 % t]"], body, text=2)


def _passive_line(rows: Mapping[str, Sequence[Row]]) -> str:
    zero, n_rows, n_eps, bad = passive_verdict(rows)
    if zero is None:
        return "**Passive safety:** no passive-mode row ran an episode."
    if zero:
        return (f"**Passive safety: zero active contacts in every passive-mode row** ({n_rows} rows, {n_eps} "
                "episodes): wherever a walker touched the robot, the robot was at rest.")
    return (f"**Passive safety: active contacts in {len(bad)} of {n_rows} passive-mode rows** ({n_eps} episodes): "
            + "; ".join(bad) + ". The guarantee's assumptions are stated above; each such contact is a defect to "
            "investigate.")


@dataclass(frozen=True)
class Figure:
    """A figure on the page: map name, PNG path relative to the page, caption."""

    map: str
    path: str
    caption: str


def frontier_page(rows: Mapping[str, Sequence[Row]], pooled: Sequence[Row], cfg: ExperimentConfig, *,
                  setup: Sequence[str] = (), figures: Sequence[Figure] = (), meta: Mapping | None = None,
                  compute_s: float | None = None, quick: bool = False) -> str:
    """The Markdown page (pure given its inputs): intro, the passive-safety line, set-up, the pooled table, then per
    map its figure and table."""
    meta = meta or {}
    zero, n_rows, n_eps, _ = passive_verdict(rows)
    episodes = sum(r.episodes for rs in rows.values() for r in rs)
    title = "# Navigation among walkers: the safety–efficiency frontier" + (
        " — QUICK smoke run, not a result" if quick else "")
    summary = {"config": cfg.name, "quick": quick, "beyond": True, "title": title[2:], "seeds": len(cfg.seeds),
               "maps": list(rows), "episodes": episodes, "passive_zero": zero, "passive_rows": n_rows,
               "compute_s": compute_s}
    out = [title, "", f"<!-- summary: {json.dumps(summary)} -->", ""]
    if quick:
        out += ["> **QUICK RUN.** This page comes from a `--quick` run: two maps, a few scenario rows, one seed. It "
                "checks that the pipeline works; its numbers are not the result.", ""]
    out += [INTRO, "", md.table(["safety", "a control counts only if …", "guarantee"], [list(r) for r in SAFETY_TABLE],
                                text=3), "", ASSUMPTION, ""]
    pattern = cfg.name + ".toml"
    command = f"jaxplan reproduce --quick --pattern '{pattern}' --results runs/results" if quick else \
        f"jaxplan reproduce --pattern '{pattern}'"
    out += [f"Regenerate: `{command}` (resumes a finished run; the run folder alone: `jaxplan run "
            f"configs/{pattern}{' --quick' if quick else ''}`).", "", _passive_line(rows), ""]
    out += ["## Setup", ""]
    out += ["- Robot: cui2025's unicycle (1.2 m/s, 0.5 m/s², radius 0.25 m, d_safe 0.3 m, control period 0.2 s), "
            "global plans by IACO; the pipelines' defaults otherwise.",
            "- Walkers: 5 discs of 0.25 m on random routes, starting at least 3 m from the robot's start and goal; "
            "blind walkers keep to their routes, walkers that see avoid robots, each other and walls (social force "
            "model).",
            "- Contacts do not end an episode: each is counted, *active* if the robot moved faster than 0.05 m/s as "
            "it began, else *passive*. Success: the goal reached within the time limit without any contact. Time "
            "to goal: over the successful episodes.",
            "- Intervals over every feasible episode (seeds × scenario rows pooled): Wilson 95 % for shares, "
            "Student-t 95 % for means (lower ends clipped at 0). Fractions in %.",
            "- The oracle ceiling column: the same local planner, walker speed and (blind) walkers with safety none "
            "and the walkers' true routes as its prediction (its own row closes each table); walkers that see leave "
            "their routes to avoid the robot, so no route oracle exists for them (–)."]
    out += [f"- {ln}" for ln in setup]
    if meta:
        out.append(f"- jaxplan {meta.get('jaxplan_version')} (git {meta.get('git_revision') or 'unknown'}), jax "
                   f"{meta.get('jax_version')}, started {meta.get('started')}"
                   + (f"; compute {compute_s / 60:.1f} min (sum of the chunks' compile and run times), "
                      f"{episodes} episodes" if compute_s is not None else "") + ".")
    out += ["", "## Over all maps", "",
            "Each local planner and safety mode pooled over the maps, walker kinds and speeds (the oracle: blind "
            "walkers only).", "", _pooled_table(pooled), ""]
    by_map = {f.map: f for f in figures}
    for name, rs in rows.items():
        out += [f"## {name}", ""]
        f = by_map.get(name)
        if f is not None:
            out += [md.image(f"{name}: the frontier", f.path), "", f.caption, ""]
        out += [_map_table(rs), ""]
    return "\n".join(out).rstrip() + "\n"


def write_frontier(run_dir: str | os.PathLike, results: str | os.PathLike | None, figures_dir: str | os.PathLike, *,
                   data_dir: str | os.PathLike | None = None) -> tuple[Path | None, list[Any]]:
    """Draws the figures of a finished frontier run folder into ``figures_dir/RUN/frontier_MAP.png`` and, with
    ``results``, writes its page ``results/NAME[-quick].md``.

    Returns:
      ``(page or None, drawn)``: the page's path, and the figures as `jaxplan.experiments.figures.Drawn` (for the
      figure folder's index).
    """
    from jaxplan.core.io import atomic_write, confined
    from jaxplan.experiments.figures import Drawn
    from jaxplan.experiments.plots import plt, save_figure
    from jaxplan.experiments.results import _compute_s
    from jaxplan.experiments.run_data import load_run

    run_dir = Path(run_dir)
    run = load_run(run_dir, data_dir)
    cfg = run.config
    if run.trials is None:
        raise FileNotFoundError(f"{run_dir}: no trials.csv (run the config first)")
    quick = bool(cfg.is_quick)
    rows = frontier_rows(run.trials, cfg)
    d = Path(figures_dir) / run_dir.resolve().name
    d.mkdir(parents=True, exist_ok=True)
    drawn = []
    for name, rs in rows.items():
        fig, caption = frontier_figure(name, rs, quick=quick)
        stem = f"frontier_{name}"
        try:
            files = []
            for ext in ("png", "svg"):
                save_figure(fig, str(confined(d, stem, f".{ext}")))
                files.append(f"{stem}.{ext}")
        finally:
            plt.close(fig)
        drawn.append(Drawn(stem, "frontier", tuple(files), caption))
    if results is None:
        return None, drawn
    page = Path(results) / page_name(cfg.name, quick)
    rel = Path(os.path.relpath(d, page.parent))
    figs = [Figure(name, (rel / f"frontier_{name}.png").as_posix(), dr.caption)
            for name, dr in zip(rows, drawn, strict=True)]
    meta_path = run_dir / "meta.json"
    meta = json.loads(meta_path.read_text()) if meta_path.is_file() else {}
    text = frontier_page(rows, pooled_rows(run.trials, cfg), cfg, setup=_setup(run.prep, cfg, rows), figures=figs,
                         meta=meta, compute_s=_compute_s(run_dir), quick=quick)
    page.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(page, text)
    return page, drawn
