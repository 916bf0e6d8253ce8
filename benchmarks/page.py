"""docs/benchmarks.md, generated from the benchmarks' JSON records in benchmarks/results/.

Run:  python benchmarks/run_all.py --page

Every benchmark writes one JSON record per run (`_timing.Record`: machine line, options, named tables). The page
says how to run each benchmark and shows, for each table name of each benchmark, the newest recorded table of
that name (a full run before a ``--quick`` one) with its date, command and machine line. Nothing on the page is
written by hand: to change a figure, run the benchmark; to change the text, change `INTRO` or `BENCHES` here.
``tests/test_site.py`` checks that the committed page is what this module makes of the committed records.
Standard library only, so the page can be made without JAX.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
PAGE = HERE.parent / "docs" / "benchmarks.md"


@dataclass(frozen=True)
class Bench:
    """One benchmark script: its section title, how to run it and what it measures."""

    name: str
    title: str
    usage: str
    measures: str


BENCHES = (
    Bench("run_all", "Everything in one table",
          "python benchmarks/run_all.py [--quick] [--only aco,dwa,exact,metrics,episodes,tune,tsp,scale]",
          "every section beside a reference measured in the same run (about 3 min with `--quick`)"),
    Bench("bench_aco_speed", "ACO speed", "python benchmarks/bench_aco_speed.py [--iterations 5] [--repeats 5]",
          "ant-steps/s of `aco` and `iaco` with 128, 1,024 and 8,192 ants for both walks, compile time per planner, "
          "the chen2023-sized run, peak memory"),
    Bench("bench_aco_quality", "ACO quality", "python benchmarks/bench_aco_quality.py --rows 20 --seeds 10",
          "success and optimality gap of every ACO planner on MovingAI scenario rows, and each colony's gap to its "
          "own optimum"),
    Bench("bench_exact", "Exact search", "python benchmarks/bench_exact.py [--queries 50] [--rows 1000]",
          "one A* query and 1,000 scenario rows through `shortest_lengths` on brc202d and a 512×512 random map, "
          "beside scipy's Dijkstra"),
    Bench("bench_tsp", "TSP", "python benchmarks/bench_tsp.py [--seeds 10] [--only quality speed reference]",
          "`praco` and `aco` tour quality on eil51 and berlin52, ms per iteration with 500 ants, Ant System "
          "against ACOTSP (`ACOTSP_BIN`)"),
    Bench("bench_sampling", "Sampling planners", "python benchmarks/bench_sampling.py [--rows 20]",
          "`rrt_star`, `mrbs_rrt`, `astar_kng` and `astar` on two maps: success, length ratio, turns, time"),
    Bench("bench_smoothing", "Smoothing", "python benchmarks/bench_smoothing.py --rows 100",
          "length, turn and sharp-turn cuts of each smoother on the MovingAI maps"),
    Bench("bench_metrics", "Path metrics", "python benchmarks/bench_metrics.py [--paths 10000]",
          "the path metrics of a batch in one compiled call, beside a numpy loop"),
    Bench("bench_dwa", "DWA", "python benchmarks/bench_dwa.py [--robots 1,64,1024]",
          "ms per DWA step and trajectory points/s for 1, 64 and 1,024 robots beside numpy; one robot from Python "
          "beside PythonRobotics' `dwa_control` (`PYTHONROBOTICS_DIR`)"),
    Bench("bench_mppi", "MPPI", "python benchmarks/bench_mppi.py [--samples 128,256,...] [--robots 64] [--repeats 5]",
          "ms per MPPI optimisation (K = 128 … 16,384 samples of 100 steps of 0.02 s) on MPPI-Generic's comparison "
          "problem (differential drive, 11 m costmap, λ = 1, σ = 0.2) for 1 and 64 robots, jaxplan's `mppi_control` "
          "beside jax_mppi (the JAX port of pytorch_mppi, installed at benchmark time: `pip install jaxtyping && pip "
          "install --no-deps --ignore-requires-python -C cmake.define.CMAKE_DISABLE_FIND_PACKAGE_CUDAToolkit=ON "
          "jax-mppi==0.3.0`) on the same dynamics and cost, checks that both compute the same thing, and the "
          "figures MPPI-Generic and Nav2 published (quoted); about 10 min on 2 cores"),
    Bench("bench_nav", "Navigation",
          "python benchmarks/bench_nav.py [--sections maps,allrows,pipelines,multi,speed] [--local dwa,mppi] "
          "[--oracle] [--quick]",
          "two-level navigation: `iaco_dwa` and `iaco_mppi` on every map among blind and seeing walkers, every "
          "scenario row, every pipeline, multi-robot teams, episodes per second"),
    Bench("bench_falsify", "Falsifying passive safety",
          "python benchmarks/bench_falsify.py [--local dwa,mppi] [--population 32] [--generations 16] [--quick]",
          "CMA-ES over blind walkers' routes searching for an active contact, with `safety=\"none\"` and "
          "`\"passive\"`"),
    Bench("bench_ros_maps", "ROS maps", "python benchmarks/bench_ros_maps.py [--seeds 1]",
          "planning on Nav2's warehouse at 0.03 m and resampled, and episodes through a speed zone"),
    Bench("bench_tune", "Tuning", "python benchmarks/bench_tune.py [--quick]",
          "every tuning strategy on the same evaluation budget, with a held-out test set"),
    Bench("bench_scale", "Scale-out", "python benchmarks/bench_scale.py [--quick]",
          "batched throughput with 1 and 2 host devices, each configuration in a fresh process"),
    Bench("ray_scale_out", "Scale-out with Ray",
          "jaxplan reproduce --quick --ray auto; jaxplan study configs/study_iaco.toml --quick --ray auto",
          "the same runs in one process and as Ray tasks (2 workers): wall time, compile time per worker, the "
          "per-task overhead (docs/guide/scale-out.md)"),
    Bench("bench_warm_start", "Warm starts", "python benchmarks/bench_warm_start.py [--repeats 3]",
          "a new process's `jaxplan navigate`, `jaxplan plan --planner iaco` and first `jp.navigate`, with the "
          "compilation caches cold, off and warm (about 15 min; `nice -n 19` beside other work)"),
)

INTRO = """\
# Benchmarks

<!-- Generated by `python benchmarks/run_all.py --page` from benchmarks/results/*.json: do not edit by hand. -->

The scripts in `benchmarks/` measure speed against reference implementations and quality against exact optima.
Run them from the repository root; those that read MovingAI, TSPLIB or ROS files take `--data-dir` (default
`$JAXPLAN_DATA`, else `../shared/benchmarks`). Each run writes a JSON record to `benchmarks/results/` (its
machine, options and tables), and this page shows the newest recorded table of each kind with its date, command
and machine line.

**Compare figures only between runs whose machine lines agree.** The same script gave figures 2–4× apart on two
cloud machines that both called themselves "2-core AMD EPYC", and a machine's host may lend its cores to other
guests during a run. So every record names the CPU family, model and widest vector ISA, and the share of CPU time
the hypervisor gave to other guests during the run ("steal"). Ratios against a reference measured in the same
run move much less than absolute figures; other processes on the machine make every figure noisy. Tables marked
*transcribed* were recorded by hand before this page was generated; a new run of their benchmark replaces them.

## Running them

```bash
python benchmarks/run_all.py --quick        # about 3 min on 2 cores
python benchmarks/run_all.py                # default sizes
jaxplan bench -- --quick                    # the same from the jaxplan command (options after --)
python benchmarks/run_all.py --only dwa,tsp # some sections: aco, dwa, exact, metrics, episodes, tune, tsp, scale
python benchmarks/run_all.py --page         # this page, from the JSON records
```
"""


def load_records(folder: Path = RESULTS) -> list[dict[str, Any]]:
    """Every JSON record in ``folder`` (each with ``bench``, ``started_utc`` and ``tables``), oldest first."""
    records = []
    for path in sorted(folder.glob("*.json")):
        data = json.loads(path.read_text())
        missing = [k for k in ("bench", "started_utc", "tables") if k not in data]
        if missing:
            raise ValueError(f"{path}: not a benchmark record (no {', '.join(missing)}); see benchmarks/_timing.py")
        data["file"] = path.name
        records.append(data)
    return sorted(records, key=lambda r: (r["started_utc"], r["file"]))


def latest_tables(records: list[dict[str, Any]], bench: str) -> list[tuple[dict[str, Any], dict[str, Any]]]:
    """``(record, table)`` of the newest table of each name of ``bench``: full runs before quick ones, then the
    newest; grouped by record (newest first), each record's tables in its own order."""
    own = [r for r in records if r["bench"] == bench]
    own.sort(key=lambda r: (not r.get("quick", False), r["started_utc"], r["file"]), reverse=True)
    seen: dict[str, tuple[int, dict[str, Any], dict[str, Any]]] = {}
    for k, rec in enumerate(own):
        for table in rec["tables"]:
            seen.setdefault(table["name"], (k, rec, table))
    return [(rec, table) for _, rec, table in sorted(seen.values(), key=lambda x: x[0])]


def cell(x: Any) -> str:
    """A table cell: numbers to three significant figures (one decimal from 100, whole from 1,000), missing values as
    a dash."""
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "—"
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, int):
        return f"{x:,}"
    if isinstance(x, float):
        if math.isinf(x):
            return "∞" if x > 0 else "−∞"
        if abs(x) >= 1000:
            return f"{x:,.0f}"
        if abs(x) >= 100:
            return f"{x:.1f}".removesuffix(".0")
        if x != 0 and abs(x) < 0.001:
            return f"{x:.1e}"
        return f"{x:.3g}"
    if isinstance(x, list):
        return ", ".join(cell(v) for v in x)
    return str(x).replace("|", "\\|").replace("\n", " ")


def run_line(rec: dict[str, Any]) -> str:
    """Date, command, machine line, steal and load of one record."""
    date = rec["started_utc"].replace("T", " ")[:16] + " UTC" if "T" in rec["started_utc"] else rec["started_utc"]
    parts = [f"Recorded {date}", f"`{rec['command']}`" if rec.get("command") else None, rec.get("machine_line")]
    if rec.get("steal") is not None:
        parts.append(f"steal {100 * rec['steal']:.1f} %")
    if rec.get("load_avg"):
        parts.append(f"load average {rec['load_avg'][0]:.1f} at the start")
    if rec.get("quick"):
        parts.append("quick sizes")
    line = "; ".join(p for p in parts if p) + "."
    if rec.get("source"):
        line += f" Source: {rec['source']}."
    return line


def render_table(rec: dict[str, Any], table: dict[str, Any]) -> list[str]:
    out = [f"### {table['name']}", ""]
    if table.get("title") and table["title"] != table["name"]:
        out += [f"*{table['title']}.*", ""]
    cols = table["columns"]
    out.append("| " + " | ".join(cell(c) for c in cols) + " |")
    out.append("|" + "---|" * len(cols))
    for row in table["rows"]:
        if len(row) != len(cols):
            raise ValueError(f"{rec['file']}: table {table['name']!r} has a row of {len(row)} cells for "
                             f"{len(cols)} columns")
        out.append("| " + " | ".join(cell(c) for c in row) + " |")
    out.append("")
    for note in table.get("notes", []):
        out += [note, ""]
    return out


def render(records: list[dict[str, Any]] | None = None) -> str:
    """The text of docs/benchmarks.md from ``records`` (default: every record in benchmarks/results/)."""
    records = load_records() if records is None else records
    benches = [b for b in BENCHES if (HERE / f"{b.name}.py").is_file() or any(r["bench"] == b.name for r in records)]
    known = {b.name for b in benches}
    benches += [Bench(n, n, f"python benchmarks/{n}.py", "") for n in sorted({r["bench"] for r in records} - known)]
    lines = [INTRO]
    for b in benches:
        lines += [f"## {b.title}", "", f"`{b.usage}`: {b.measures}." if b.measures else f"`{b.usage}`", ""]
        tables = latest_tables(records, b.name)
        if not tables:
            lines += ["No run recorded yet.", ""]
        shown = None
        for rec, table in tables:  # grouped by record: its run line once, above its tables
            if rec is not shown:
                lines += [run_line(rec), ""]
                shown = rec
            lines += render_table(rec, table)
    return "\n".join(lines).rstrip("\n") + "\n"


def write_page(path: Path = PAGE) -> Path:
    """Writes `render`'s page to ``path`` and returns it."""
    path.write_text(render())
    return path


if __name__ == "__main__":
    print(f"wrote {write_page()}")
