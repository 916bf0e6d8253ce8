"""li2026's Figure 7: sparrow search (SSA), its improved form (ISSA) and CMA-ES on benchmark functions.

li2026 compares its ISSA's best fitness per iteration on the "Generalized Rastrigin" and "Generalized
Rosenbrock" functions (500 iterations; it prints one number: ISSA reaches 6.2 on Rastrigin) against
models we cannot build (GRPO, FRC, CPSO: no specification). We compare the three optimisers jaxplan
has (`jaxplan.tune`: ``ssa``, ``issa``, ``cma_es``) on those two functions and the classic others of
the same suite (Yao, Liu & Lin 1999: Sphere, Ackley, Griewank), each in its usual box, with the same
population and generation budget.

The functions are the classic ones, not evosax's BBOB suite (whose Rastrigin and Rosenbrock are
shifted, rotated and asymmetric transforms, another benchmark). The optimum is moved off the box
centre by a fixed shift (drawn once, at most 40 % of the half-width per coordinate; the same for every
optimiser and seed): CMA-ES starts its mean at the centre, where the textbook functions have their
optimum. Every function's minimum is 0.

`run_study` runs each optimiser × function over seeds as one ``vmap`` of a ``lax.scan`` over
generations; `write_study` writes the results page (`jaxplan.experiments.results` conventions: the
paper's number in the paper column, ours beside it, the verdict) and one convergence figure.
(Formerly ``jaxplan.benchmark_functions``: that path still works for one release, with a `DeprecationWarning`.)
"""

from __future__ import annotations

import json
import math
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np

from jaxplan.core import markdown as md

__all__ = ["FUNCTIONS", "StudySpec", "FULL", "QUICK", "run_study", "write_study", "NAME"]

NAME = "li2026_fig7"
"""The study's name: its page is ``<results>/li2026/fig7.md``, its figures ``<figures>/li2026_fig7/``."""


def _rastrigin(x):
    return 10.0 * x.shape[-1] + jnp.sum(x * x - 10.0 * jnp.cos(2.0 * jnp.pi * x), axis=-1)


def _rosenbrock(x):
    y = x + 1.0  # minimum at x = 0 (the textbook one at 1), so that the shift alone places it
    return jnp.sum(100.0 * (y[..., 1:] - y[..., :-1] ** 2) ** 2 + (y[..., :-1] - 1.0) ** 2, axis=-1)


def _sphere(x):
    return jnp.sum(x * x, axis=-1)


def _ackley(x):
    d = x.shape[-1]
    return (-20.0 * jnp.exp(-0.2 * jnp.sqrt(jnp.sum(x * x, axis=-1) / d))
            - jnp.exp(jnp.sum(jnp.cos(2.0 * jnp.pi * x), axis=-1) / d) + 20.0 + jnp.e)


def _griewank(x):
    i = jnp.arange(1, x.shape[-1] + 1, dtype=x.dtype)
    return 1.0 + jnp.sum(x * x, axis=-1) / 4000.0 - jnp.prod(jnp.cos(x / jnp.sqrt(i)), axis=-1)


FUNCTIONS: dict[str, tuple[Callable, float]] = {
    "rastrigin": (_rastrigin, 5.12),
    "rosenbrock": (_rosenbrock, 30.0),
    "sphere": (_sphere, 100.0),
    "ackley": (_ackley, 32.0),
    "griewank": (_griewank, 600.0),
}
"""Name -> (f(x f32[..., D]) -> f32[...], half-width h of the box [-h, h]^D); minimum 0 at x = 0."""


@dataclass(frozen=True)
class StudySpec:
    """Dimensions, population, generations, seeds, optimisers and functions of the study."""

    dim: int = 30
    population: int = 30
    generations: int = 500
    seeds: int = 10
    strategies: tuple[str, ...] = ("ssa", "issa", "cma_es")
    functions: tuple[str, ...] = tuple(FUNCTIONS)
    quick: bool = False


FULL = StudySpec()
"""The full study: D = 30 (the classic suite's), 30 individuals, li2026's 500 iterations, 10 seeds."""
QUICK = StudySpec(dim=5, population=10, generations=20, seeds=2, functions=("rastrigin",), quick=True)
"""The CI smoke version."""


def _shift(name: str, dim: int, half: float) -> jnp.ndarray:
    key = jax.random.fold_in(jax.random.key(2026), sorted(FUNCTIONS).index(name))
    return jax.random.uniform(key, (dim,), minval=-0.4 * half, maxval=0.4 * half)


def _one(strategy_name: str, fn_name: str, spec: StudySpec):
    """``f32[seeds, G]`` best-so-far fitness per generation of one optimiser on one function."""
    from jaxplan.tune import make_bounds, make_strategy

    f, half = FUNCTIONS[fn_name]
    shift = _shift(fn_name, spec.dim, half)
    bounds = make_bounds([(f"x{i}", -half, half) for i in range(spec.dim)])
    strat = make_strategy(strategy_name, spec.population, spec.generations)

    def run(seed):
        key = jax.random.key(seed)
        state = strat.init(jax.random.fold_in(key, 10**6), bounds, None)

        def gen(carry, g):
            state, best = carry
            pop = strat.ask(jax.random.fold_in(key, g), state)
            fit = f(pop - shift)
            state = strat.tell(state, pop, fit)
            best = jnp.minimum(best, jnp.min(jnp.where(jnp.isfinite(fit), fit, jnp.inf)))
            return (state, best), best

        _, curve = jax.lax.scan(gen, (state, jnp.asarray(jnp.inf, jnp.float32)), jnp.arange(spec.generations))
        return curve

    return np.asarray(jax.jit(jax.vmap(run))(jnp.arange(spec.seeds)), np.float64)


def run_study(spec: StudySpec = FULL) -> dict[tuple[str, str], np.ndarray]:
    """``{(function, optimiser): f64[seeds, generations]}`` best-so-far fitness curves."""
    return {(fn, s): _one(s, fn, spec) for fn in spec.functions for s in spec.strategies}


PAPER = {("rastrigin", "issa"): 6.2}
"""The paper's one printed number: ISSA's final best fitness on Rastrigin (li2026, Fig. 7 text)."""
PAPER_REASON = "the paper states neither the dimension, the box nor the population of its runs"


def _figure(curves: dict, spec: StudySpec, path: Path) -> None:
    from jaxplan.experiments.plots import plot_convergence, plt, save_figure

    fns = list(spec.functions)
    fig, axes = plt.subplots(1, len(fns), figsize=(4.2 * len(fns), 3.8), constrained_layout=True, squeeze=False)
    for ax, fn in zip(axes[0], fns, strict=True):
        plot_convergence(ax, {s: np.maximum(curves[fn, s], 1e-12) for s in spec.strategies}, band="iqr",
                         ylabel="best fitness f(x) (dimensionless, log scale)")
        ax.set_yscale("log")
        ax.set_xlabel("generation (count)")
        ax.set_title(f"{fn}, D = {spec.dim}")
    fig.suptitle(f"li2026 Fig. 7: best fitness per generation ({spec.population} individuals, median and "
                 f"25-75 % band over {spec.seeds} seeds)" + (" — QUICK" if spec.quick else ""))
    try:
        save_figure(fig, str(path))
    finally:
        plt.close(fig)


def _pm(x: np.ndarray) -> str:
    """Mean ± sd (ddof=1) of the per-seed values ``x``."""
    return md.pm(float(np.mean(x)), float(np.std(x, ddof=1)) if x.size > 1 else math.nan)


def write_study(results: str | os.PathLike, figures: str | os.PathLike, spec: StudySpec = FULL) -> Path:
    """Runs the study and writes its page (``results/li2026/fig7[-quick].md``) and figure; returns the page."""
    from scipy import stats as sps

    from jaxplan.core.io import atomic_write
    from jaxplan.experiments.results import VERDICTS
    from jaxplan.experiments.stats import confidence_interval, hedges_g, holm

    t0 = time.perf_counter()
    curves = run_study(spec)
    elapsed = time.perf_counter() - t0
    tag = "-quick" if spec.quick else ""
    fdir = Path(figures) / f"{NAME}{tag}"
    fdir.mkdir(parents=True, exist_ok=True)
    _figure(curves, spec, fdir / "fig7_fitness.png")
    page = Path(results) / "li2026" / f"fig7{tag}.md"
    page.parent.mkdir(parents=True, exist_ok=True)
    final = {k: v[:, -1] for k, v in curves.items()}
    counts = {v: 0 for v in VERDICTS}
    paper_rows = []
    for (fn, s), p in PAPER.items():
        if (fn, s) not in final:
            continue
        x = final[fn, s]
        v, why = "not comparable", PAPER_REASON
        counts[v] += 1
        paper_rows.append([fn, s, "best fitness", md.fmt(p), _pm(x), md.interval(*confidence_interval(x)),
                           str(x.size), f"{v}{': ' + why if why else ''}"])
    summary = {"config": NAME, "quick": spec.quick, "seeds": spec.seeds, "counts": counts, "compute_s": elapsed}
    out = [f"# {NAME}" + (" — QUICK smoke run, not a result" if spec.quick else ""), "",
           f"<!-- summary: {json.dumps(summary)} -->", ""]
    if spec.quick:
        out += ["> **QUICK RUN.** Tiny dimension, population and budget; not the reproduction.", ""]
    out += ["li2026 Fig. 7: the optimisers' best fitness on benchmark functions. The paper compares ISSA with GRPO, "
            "FRC and CPSO (not reproduced: no specification); we compare ISSA with the plain sparrow search (SSA) "
            "and CMA-ES, the optimisers `jaxplan.tune` has, with one budget.", "",
            "Regenerate: `jaxplan reproduce" + (" --quick" if spec.quick else "") + " --pattern 'li2026_fig7'`.", "",
            "## Setup", "",
            f"- Functions: {', '.join(spec.functions)} (the classic suite of Yao, Liu & Lin 1999; Rastrigin box "
            "±5.12, Rosenbrock ±30, Sphere ±100, Ackley ±32, Griewank ±600), D = "
            f"{spec.dim}, minimum 0 moved off the box centre by a fixed shift (at most 40 % of the half-width).",
            f"- Optimisers: {', '.join(spec.strategies)} (`jaxplan.tune.make_strategy` defaults), "
            f"{spec.population} individuals, {spec.generations} generations (li2026: 500 iterations), "
            f"{spec.seeds} seeds; one `vmap` over seeds of a `lax.scan` over generations per pair.",
            f"- Compute: {elapsed:.0f} s (compile included) on this machine.", "",
            "## The paper's number beside ours", "",
            md.table(["function", "optimiser", "metric", "paper", "ours: mean ± sd", "ours: 95 % CI", "seeds",
                      "verdict"], paper_rows, text=3, last_text=True), "",
            "Verdicts: " + ", ".join(f"{v} {counts[v]}" for v in VERDICTS) + ".", "",
            "## All our results: final best fitness", "",
            "Mean ± sd over seeds of the best fitness after the last generation, then the 95 % interval of the mean "
            "(the minimum of every function is 0).", "",
            md.table(["function"] + [f"ours: {s}" for s in spec.strategies],
                     [[fn] + [f"{_pm(final[fn, s])} {md.interval(*confidence_interval(final[fn, s]))}"
                              for s in spec.strategies] for fn in spec.functions]), "",
            "## ISSA against the others", "",
            "Welch t-test on the final best fitness per seed (Holm-adjusted within each function) and Hedges' g "
            "(ISSA − other, in pooled sds: negative means ISSA lower, i.e. better).", ""]
    test_rows = []
    for fn in spec.functions:
        others = [s for s in spec.strategies if s != "issa"]
        if "issa" not in spec.strategies:
            break
        tests = []
        for o in others:
            a, b = final[fn, "issa"], final[fn, o]
            r = sps.ttest_ind(a, b, equal_var=False) if a.size > 1 and b.size > 1 else None
            tests.append((o, float(r.statistic) if r else math.nan, float(r.pvalue) if r else math.nan,
                          hedges_g(a, b)))
        adj = holm([t[2] for t in tests])
        test_rows += [[fn, o, md.fmt(t), md.fmt(float(pa), 3), md.fmt(g, 3)]
                      for (o, t, _, g), pa in zip(tests, adj, strict=True)]
    rel = os.path.relpath(fdir / "fig7_fitness.png", page.parent)
    out += [md.table(["function", "other", "t", "p (Holm)", "Hedges' g"], test_rows, text=2), "",
            "## Not reproduced", "", "- GRPO, FRC and CPSO (the paper's comparison models): no specification.", "",
            "## Figures", "", md.image("fig7_fitness", Path(rel).as_posix()), "",
            "Best fitness so far per generation (median line, 25-75 % band over seeds; log axis).", ""]
    atomic_write(page, "\n".join(out))
    return page
