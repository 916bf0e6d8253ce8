"""The study's figure and its Markdown results page (`jaxplan.core.markdown`).

`figure` draws the held-out cost of each method's best-so-far weights against the counted training evaluations
(mean ± sd over tuner seeds, the defaults as a dashed line); `page` writes the results page: how to regenerate it
and how long it took, the setup (planner, cost, maps, splits, budget), the results table with the verdict
(`jaxplan.tune.study.judge`), the best weights as a ``[[planners]]`` entry and the link to the confirmation.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from jaxplan.core import markdown as md
from jaxplan.core import toml
from jaxplan.tune.study.config import StudyConfig

__all__ = ["figure", "page", "rel_path"]


def rel_path(p: Path | None) -> str:
    """``p`` relative to the working folder when it lies inside it (as a command would name it); ``CONFIG`` for
    None."""
    if p is None:
        return "CONFIG"
    try:
        return str(Path(p).resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(p)


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" + ("" if n == 1 else "s")


def _fmt(v: float, d: int = 4) -> str:
    """A score with ``d`` decimals (scores are gaps and fractions: fixed decimals line up); `md.MISSING` if not
    finite."""
    return f"{v:.{d}f}" if isinstance(v, float) and math.isfinite(v) else md.MISSING


def _compile_note(s: Mapping[str, Any]) -> str:
    return f"{s['compile_s_total']:.0f} s of compilation over all runs of all sessions"


def figure(cfg: StudyConfig, runs: Mapping[tuple[str, int], Mapping[str, Any]], defaults: float,
           path: str | Path) -> None:
    """The convergence figure at ``path`` (module docstring); ``defaults``: the defaults' held-out cost."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from jaxplan.experiments.plots import save_figure

    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for i, m in enumerate(cfg.methods):
        ev = np.asarray(runs[(m, cfg.tuner_seeds[0])]["evaluations"], np.float64)
        h = np.asarray([runs[(m, s)]["heldout"] for s in cfg.tuner_seeds], np.float64)
        mean = h.mean(axis=0)
        sd = h.std(axis=0, ddof=1) if len(h) > 1 else np.zeros_like(mean)
        (line,) = ax.plot(ev, mean, lw=1.6, color=f"C{i % 10}", label=m)
        ax.fill_between(ev, mean - sd, mean + sd, color=line.get_color(), alpha=0.15, lw=0)
    ax.axhline(defaults, color="k", ls="--", lw=1.0, label="defaults")
    ax.set_xlabel("training evaluations (weight vectors, counted)")
    ax.set_ylabel("held-out cost of best-so-far weights (lower is better)")
    ax.set_title(f"{cfg.name}: mean ± sd over {len(cfg.tuner_seeds)} tuner seeds")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    save_figure(fig, str(path))
    plt.close(fig)


def page(cfg: StudyConfig, s: Mapping[str, Any], frag: str) -> str:
    """The results page of study ``cfg`` from its summary ``s`` (``summary.json`` with its sessions) and best-weights
    entry ``frag`` (best.toml)."""
    t0 = cfg.tunes[0]
    cmd = f"jaxplan study {rel_path(cfg.path)}" + (" --quick" if cfg.is_quick else "") + \
        " --results docs/results/tuning"
    main = max(s["sessions"], key=lambda x: x["wall_s"])
    load = ", ".join(f"{v:.2f}" for v in (main["loadavg_start"] or s["loadavg_start"]))
    n_sess = len(s["sessions"])
    n_work = sum(1 for x in s["sessions"] if x.get("worker"))
    load_end = ", ".join(f"{v:.2f}" for v in (main["loadavg_end"] or s["loadavg_end"]))
    gap = {"own": "the gap of the best path's own IACO cost (at the default λ) to its exact own optimum "
                  "(`jaxplan.search.exact_objectives`)",
           "length": "the gap of the best path's length to the shortest path"}[cfg.gap]
    kinds = f" × {len(t0.walkers)} walker kinds" if t0.kind == "nav" else ""
    mw = " + ".join(f"{w:g}·{k}" for k, w in s["metric_weights"].items())
    space = ", ".join(f"{n} ∈ [{lo:g}, {hi:g}]" for n, (lo, hi) in s["space"].items())
    dft = s["defaults"]
    lines = [f"# Tuning study `{cfg.name}`" + (" (quick)" if cfg.is_quick else ""), "", s["description"], "",
             f"Regenerate: `{cmd}` (add `--confirm` to run the confirmation too) — measured "
             f"{s['wall_s_total'] / 60:.1f} min wall in total"
             + (f" over {n_sess} sessions (the longest {main['wall_s'] / 60:.1f} min; later ones resumed from the "
                "checkpoints" + (f"; {n_work} of them workers (`--only`) running side by side" if n_work else "")
                + ")" if n_sess > 1 else "")
             + (f", at niceness {main['nice']} on {_count(main['cores'], 'core')}" if main.get("nice") is not None
                else "")
             + f" (1-, 5-, 15-min load averages {load} at the start and {load_end} at the end of the longest "
             "session).", "",
             "## Setup", "",
             f"- Planner: `{t0.planner}` with overrides {toml.literal(dict(t0.overrides)) if t0.overrides else '{}'}; "
             f"tuned: {space}.",
             (f"- Cost (lower is better): {mw}, where gap is {gap} (a failed run counts gap 1), averaged over "
              "scenarios and seeds." if t0.kind != "nav" else
              f"- Cost (lower is better): {mw} per episode, where failure = not at the goal without contact within "
              "the time limit and time = time to the goal over that limit (1 when not reached): success first, time "
              f"second; averaged over episodes. Pipeline `{t0.pipeline}`, {t0.walker_count} walkers at "
              f"{t0.walker_speed:g} m/s, each vector scored among each kind: {', '.join(t0.walkers)}."),
             "- Maps: " + "; ".join(f"{m['name']} (train seeds {m['train_seeds']}, held-out seeds "
                                    f"{m['heldout_seeds']})" for m in s["maps"]) + ".",
             f"- Training split: {s['train_rows']} scenario rows × {_count(len(t0.train_seeds), 'seed')}{kinds} = "
             f"{s['train_runs']} runs per evaluation; held-out split: {s['heldout_rows']} other rows × "
             f"{_count(len(t0.test_seeds), 'other seed')}{kinds} = {s['heldout_runs']} runs. Rows and seeds are "
             "disjoint (checked: the study refuses to run otherwise).",
             f"- Budget: {cfg.budget} training evaluations (weight vectors) per method and tuner seed, counted by "
             f"the objective wrapper ({cfg.population} per generation × {cfg.generations} generations); "
             f"{len(cfg.tuner_seeds)} tuner seeds {list(cfg.tuner_seeds)}. The strategies that take a starting "
             "point begin from the defaults (`tune_loop`'s x0); grid and random search cover the box. "
             + ("The grid does not depend on the tuner seed and the objective is deterministic, so it ran once and "
                "that run stands for every seed (its sd is 0 by construction). " if "grid" in cfg.methods else "")
             + "Held-out evaluations are not charged.", "",
             "## Results", "",
             "Train = the best training cost the tuner found (the minimum over its evaluations, so optimistic); "
             "held-out = the cost of those same weights on the held-out split. Mean ± sd over tuner seeds, "
             "95 % t-interval of the mean; wall = seconds per run (training evaluations and the strategy) without "
             "XLA compilation, which a process pays once, in whichever run comes first "
             f"({_compile_note(s)}).",
             ""]
    rows = []
    for m in cfg.methods:
        r = s["methods"][m]
        tr, ho = r["train"], r["heldout"]
        rows.append([m, md.pm(tr["mean"], tr["sd"], _fmt), md.pm(ho["mean"], ho["sd"], _fmt),
                     md.interval(*ho["ci95"], num=_fmt), f"{r['run_s']['mean']:.1f}", str(r["evaluations"])])
    rows.append(["**defaults**", _fmt(dft["train"]), _fmt(dft["heldout"]),
                 f"± {_fmt(dft['heldout_ci95_halfwidth'])} (over {len(dft['heldout_per_seed'])} held-out seeds)",
                 md.MISSING, md.MISSING])
    lines.append(md.table(["method", "train (mean ± sd)", "held-out (mean ± sd)", "held-out 95 % interval", "wall (s)",
                           "evaluations (counted)"], rows))
    b = s["best"]
    bm = s["methods"][b["method"]]["heldout"]
    verdict = {"beats": f"**yes**: the 95 % interval of `{b['method']}` (upper end {_fmt(bm['ci95'][1])}) lies below "
                        f"the defaults' held-out cost minus its own 95 % half-width ({_fmt(dft['heldout'])} − "
                        f"{_fmt(dft['heldout_ci95_halfwidth'])})",
               "within": f"**no**: the best method, `{b['method']}`, is not below the defaults by more than the "
                         f"intervals (its held-out mean {_fmt(bm['mean'])}, 95 % interval [{_fmt(bm['ci95'][0])}, "
                         f"{_fmt(bm['ci95'][1])}], against the defaults' {_fmt(dft['heldout'])} ± "
                         f"{_fmt(dft['heldout_ci95_halfwidth'])}): at this budget the defaults are at the optimum "
                         "within noise",
               "worse": f"**no**: even the best method, `{b['method']}`, is worse than the defaults on the held-out "
                        "split (over-fitted to the training split)"}[s["verdict"]]
    hm = b["heldout_metrics"]
    dm = dft["heldout_metrics"]
    lines += ["", f"Does the best method beat the defaults on the held-out split by more than the interval? {verdict}.",
              "",
              "Held-out metrics (means over runs), defaults → best weights: " + ", ".join(
                  f"{k} {dm[k]:.4f} → {hm[k]:.4f}" for k in dm if k in hm) + ".", "",
              f"![held-out cost against training evaluations]({cfg.name}.png)", "",
              "## Best weights", "",
              f"`{b['method']}` with tuner seed {b['tuner_seed']} (chosen among that method's seeds by its training "
              f"cost, {_fmt(b['train'])}; held-out {_fmt(b['heldout'])}), written as `{cfg.name}_best.toml`:", "",
              "```toml", frag.rstrip(), "```", "",
              f"Confirmation: `{cfg.name}_confirm.toml` runs the defaults against these weights with `jaxplan run` "
              f"on fresh random start-goal pairs and trial seeds {list(cfg.confirm_seeds)}: "
              f"see [{cfg.name}_confirm.md]({cfg.name}_confirm.md).", ""]
    return "\n".join(lines)
