"""Bad input and faults (issue 27): no silent wrong result, no crash, nothing lost, every parser fuzzed.

Each observation of the issue is a test here: it failed at a0085ce and passes now. The cases a test
records (`_record`) are the rows of ``docs/guide/reliability.md``; the last test checks that every row
names a test of this file and that the message it quotes is the one the test saw.

The parsers (``.map``, ``.scen``, ``.tsp``, ``.tour``, ROS map YAML with its PGM/PNG image, experiment and
tuning TOML) are fuzzed with
hypothesis in a worker process under an address-space limit (``RLIMIT_AS``): any input must give a
result or a `ValueError` with a message — never another exception, never a hang (a time limit per input),
never more memory than the bound. ``JAXPLAN_FUZZ_EXAMPLES`` sets the examples per parser (default 40).
"""

from __future__ import annotations

import json
import os
import re
import resource
import select
import shutil
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jaxplan.cli import main

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "guide" / "reliability.md"

SEEN: dict[str, tuple[str, str]] = {}
"""case -> (exit code or exception name, what the user saw) of the cases run in this session."""


def _record(case: str, code, text: str) -> None:
    SEEN[case] = (str(code), text)


def _one_line(err: str) -> str:
    """The stderr of a failed command: one line, no traceback."""
    lines = [x for x in err.strip().splitlines() if x.strip()]
    assert "Traceback" not in err, err
    assert len(lines) == 1, err
    return lines[0]


CONV = """
[experiment]
name = "conv"
seeds = 2
chunk = 2

[[maps]]
name = "wh"
generator = "warehouse"
seed = 0
params = { width = 14, height = 10, shelf_length = 4, shelf_depth = 2, aisle = 1, cross_aisle = 2 }

[scenarios]
source = "random"
count = 3
seed = 3
min_distance = 5.0

[[planners]]
label = "AS"
kind = "plan"
name = "aco"
overrides = { ants = 4, iterations = 3, dead_end = "retreat" }

[[figures]]
kind = "convergence"
"""

TUNE = """
[tune]
name = "t"
kind = "aco"
planner = "iaco"
strategy = "issa"
population = 4
generations = 3
checkpoint_every = 2
train_count = 2
train_seeds = 2
test_seeds = [50, 51]
overrides = { ants = 4, iterations = 2 }
[tune.space]
beta = [1.0, 10.0]
[[maps]]
name = "r"
generator = "random"
seed = 2
params = { width = 12, height = 12, obstacle_ratio = 0.15 }
scenarios = { source = "random", count = 4, seed = 0, min_distance = 5.0 }
"""


@pytest.fixture(scope="module")
def conv(tmp_path_factory):
    """(config path, a finished run folder, its trials.csv bytes): the tiny experiment, run once."""
    from jaxplan.experiments import run_experiment

    d = tmp_path_factory.mktemp("conv")
    cfg = d / "conv.toml"
    cfg.write_text(CONV)
    run = run_experiment(cfg, d / "runs", progress=False)
    return cfg, run, (run / "trials.csv").read_bytes()


@pytest.fixture
def run_copy(conv, tmp_path):
    """A copy of the finished run in ``tmp_path/runs/conv`` (and the config path)."""
    cfg, run, _ = conv
    dst = tmp_path / "runs" / "conv"
    shutil.copytree(run, dst)
    return cfg, dst


def _run(cfg, out, *extra) -> int:
    return main(["run", str(cfg), "--out", str(out), "--no-progress", *extra])


# ---------------------------------------------------------------------------------------------
# Silent wrong results


def test_a_chunk_edited_to_the_same_size_is_recomputed_not_merged(conv, run_copy, capsys):
    cfg, run = run_copy
    f = run / "checkpoints" / "chunks" / "00000-m0-p0-c0.csv"
    text = f.read_text()
    row = text.split("\n")[0].split(",")
    length = row[12]  # the first trial's length, e.g. 9.0
    row[12] = ("7" if length[0] != "7" else "8") + length[1:]
    edited = "\n".join([",".join(row)] + text.split("\n")[1:])
    assert len(edited) == len(text) and edited != text
    f.write_text(edited)
    assert _run(cfg, run.parent) == 0
    err = capsys.readouterr().err
    assert (run / "trials.csv").read_bytes() == conv[2]  # the true rows, not the edited ones
    assert f.read_text() == text
    line = next(x for x in err.splitlines() if "00000-m0-p0-c0" in x)
    _record("chunk-edited", 0, line)


@pytest.mark.parametrize("damage", ["deleted", "truncated"])
def test_figures_refuse_a_chunk_whose_arrays_are_missing_or_truncated(run_copy, tmp_path, capsys, damage):
    cfg, run = run_copy
    arrays = run / "checkpoints" / "arrays" / "00000-m0-p0-c0"
    if damage == "deleted":
        shutil.rmtree(arrays)
    else:
        for p in arrays.rglob("*"):
            if p.is_file():
                p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])
    figs = tmp_path / "figs"
    assert main(["figures", str(run), "--out", str(figs)]) == 1
    err = capsys.readouterr().err
    assert "not drawn: convergence" in err and "00000-m0-p0-c0" in err and "jaxplan figures --partial" in err
    assert not (figs / "conv" / "convergence.png").exists()  # no figure that silently lacks a planner's curve
    _record(f"arrays-{damage}", 1, err.strip().splitlines()[-1])
    # With --partial it is drawn, and labelled partial in the index.
    assert main(["figures", str(run), "--out", str(figs), "--partial"]) == 0
    assert (figs / "conv" / "convergence.png").is_file()
    assert "## convergence (convergence, PARTIAL)" in (figs / "conv" / "index.md").read_text()
    capsys.readouterr()
    # `jaxplan run` recomputes the chunk; then the figure is complete.
    assert _run(cfg, run.parent) == 0
    assert "recomputing it" in capsys.readouterr().err
    assert main(["figures", str(run), "--out", str(figs)]) == 0
    assert "PARTIAL" not in (figs / "conv" / "index.md").read_text()


# ---------------------------------------------------------------------------------------------
# Parsers under an address-space limit (also the fuzzing worker)

_WORKER = r"""
import base64, json, os, resource, sys, tempfile, traceback
from pathlib import Path
from jaxplan.grid import load_ros_map, parse_map, parse_scenarios
from jaxplan.aco import load_tour, load_tsplib
from jaxplan.experiments.config import parse_config
from jaxplan.tune import parse_tune_config

def vm():
    for line in open("/proc/self/status"):
        if line.startswith("VmSize:"):
            return int(line.split()[1]) * 1024

bound = int(sys.argv[1])
limit = vm() + bound
resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
tmp = Path(tempfile.mkdtemp())
data = tmp / "data"
data.mkdir()
print(json.dumps({"ready": True, "limit": limit}), flush=True)
for line in sys.stdin:
    req = json.loads(line)
    kind, text = req["kind"], req["text"]
    try:
        if kind == "map":
            out = parse_map(text, where="in.map").shape
        elif kind == "scen":
            out = len(parse_scenarios(text, where="in.scen"))
        elif kind in ("tsp", "tour"):
            f = tmp / f"in.{kind}"
            f.write_bytes(text.encode("utf-8", "surrogatepass"))
            out = load_tsplib(f).n if kind == "tsp" else len(load_tour(f))
        elif kind == "ros":  # a ROS map: its YAML and the image it names, sent as JSON (the image in base64)
            case = json.loads(text)
            (tmp / "m.yaml").write_bytes(case["yaml"].encode("utf-8", "surrogatepass"))
            (tmp / case["name"]).write_bytes(base64.b64decode(case["image"]))
            out = load_ros_map(tmp / "m.yaml").shape
        elif kind == "experiment":
            out = parse_config(text, data_dir=data).name
        elif kind == "tune":
            out = parse_tune_config(text, data_dir=data).name
        elif kind == "alloc":  # the harness's own checks: an allocation of this many bytes
            out = len(bytearray(int(text)))
        elif kind == "sleep":
            import time
            out = time.sleep(float(text))
        res = {"outcome": "ok", "value": repr(out)[:100]}
    except ValueError as e:
        res = {"outcome": "ValueError", "type": type(e).__name__, "message": str(e)}
    except BaseException as e:
        res = {"outcome": "other", "type": type(e).__name__, "message": str(e)[:300],
               "traceback": traceback.format_exc()[-3000:]}
    print(json.dumps(res), flush=True)
"""

BOUND = 512 * 2**20
"""The memory a parser may take beyond the worker's own (after its imports): 512 MiB."""
TIMEOUT = 20.0
"""Seconds a parser may take for one input (a slow CI core included) before it counts as a hang."""


class Worker:
    """A process that parses what it is sent under ``RLIMIT_AS`` (its size after imports + `BOUND`)."""

    def __init__(self):
        self.proc = None

    def start(self) -> None:
        env = {k: v for k, v in os.environ.items() if k != "JAXPLAN_MEMORY_LIMIT"}
        self.proc = subprocess.Popen([sys.executable, "-c", _WORKER, str(BOUND)], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
        assert json.loads(self._read(120))["ready"]

    def _read(self, timeout: float) -> str:
        ready, _, _ = select.select([self.proc.stdout], [], [], timeout)
        if not ready:
            self.stop()
            raise TimeoutError(f"no answer within {timeout} s (a hang)")
        line = self.proc.stdout.readline()
        if not line:
            err = self.proc.stderr.read()
            self.proc = None
            raise RuntimeError(f"the worker died: {err[-2000:]}")
        return line

    def parse(self, kind: str, text: str, timeout: float = TIMEOUT) -> dict:
        if self.proc is None:
            self.start()
        self.proc.stdin.write(json.dumps({"kind": kind, "text": text}) + "\n")
        self.proc.stdin.flush()
        return json.loads(self._read(timeout))

    def stop(self) -> None:
        if self.proc is not None:
            self.proc.kill()
            self.proc.wait()
            self.proc = None


@pytest.fixture(scope="module")
def worker():
    w = Worker()
    w.start()
    yield w
    w.stop()


def _check(res: dict, text: str) -> None:
    """A result, or a ValueError with a message: nothing else."""
    assert res["outcome"] in ("ok", "ValueError"), f"{res}\ninput: {text[:500]!r}"
    if res["outcome"] == "ValueError":
        assert res["message"].strip(), f"a ValueError without a message for {text[:500]!r}"


def test_a_small_tsp_file_claiming_a_billion_cities_is_an_error_not_23_gb(worker):
    text = "NAME : big\nTYPE : TSP\nDIMENSION : 1000000000\nEDGE_WEIGHT_TYPE : EUC_2D\nNODE_COORD_SECTION\n" \
           "1 0 0\n2 3 4\n3 6 8\nEOF\n"
    assert len(text) < 200
    res = worker.parse("tsp", text)
    assert res["outcome"] == "ValueError", res
    assert "has 3 of 1000000000 nodes" in res["message"]
    _record("tsp-dimension", "ValueError", res["message"])
    explicit = "NAME : big\nTYPE : TSP\nDIMENSION : 1000000000\nEDGE_WEIGHT_TYPE : EXPLICIT\n" \
               "EDGE_WEIGHT_FORMAT : UPPER_ROW\nEDGE_WEIGHT_SECTION\n1 2 3\nEOF\n"
    res = worker.parse("tsp", explicit)
    assert res["outcome"] == "ValueError" and "needs 499999999500000000 entries, found 3" in res["message"], res


def test_a_map_header_claiming_a_width_of_a_trillion_is_an_error_not_a_memory_error(worker):
    res = worker.parse("map", "type octile\nheight 2\nwidth 1000000000000\nmap\n....\n....\n")
    assert res["outcome"] == "ValueError", res
    assert "row 0 has 4 characters, header says width 1000000000000" in res["message"]
    _record("map-width", "ValueError", res["message"])
    res = worker.parse("map", "type octile\nheight 1000000000000\nwidth 4\nmap\n....\n")
    assert res["outcome"] == "ValueError" and "header says height 1000000000000 but 1 map rows" in res["message"]


# ---------------------------------------------------------------------------------------------
# Memory: refused before any work, with the largest size that fits


def test_a_huge_seed_count_is_refused_at_once(tmp_path, capsys):
    cfg = tmp_path / "seeds.toml"
    cfg.write_text(CONV.replace("seeds = 2", "seeds = 100000000"))
    t0 = time.perf_counter()
    assert _run(cfg, tmp_path / "runs") == 2
    assert time.perf_counter() - t0 < 30
    err = capsys.readouterr().err
    assert "experiment.seeds: a seed count of 100000000 is more than the 1048576 seeds a run may have" in err
    assert not (tmp_path / "runs").exists()
    _record("seeds-1e8", 2, err.strip().splitlines()[-1].strip())


def test_seeds_times_scenarios_beyond_memory_are_refused_before_any_chunk(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("JAXPLAN_MEMORY_LIMIT", "2G")
    cfg = tmp_path / "seeds.toml"
    cfg.write_text(CONV.replace("seeds = 2", "seeds = 1000000"))
    assert _run(cfg, tmp_path / "runs") == 2
    line = _one_line(capsys.readouterr().err)
    assert "a chunk of planner 'AS' on 'wh' (2 scenarios x 1000000 seeds)" in line
    fits = int(re.search(r"at most (\d+) runs", line).group(1))
    assert 0 < fits < 2 * 1000000 and "lower --chunk" not in line
    assert f"Use at most {fits} seeds (now 1000000; a chunk runs every seed at once) with --chunk 1" in line
    assert not (tmp_path / "runs").exists()
    _record("seeds-memory", 2, line)


def test_ants_beyond_memory_are_refused_before_the_chunks_that_fit_run(tmp_path, capsys):
    cfg = tmp_path / "ants.toml"
    text = CONV.replace('[[planners]]\nlabel = "AS"', '[[planners]]\nlabel = "A*"\nkind = "plan"\nname = "astar"\n\n'
                                                       '[[planners]]\nlabel = "AS"')
    cfg.write_text(text.replace("ants = 4,", "ants = 1000000000,"))
    assert _run(cfg, tmp_path / "runs") == 2
    line = _one_line(capsys.readouterr().err)
    assert "a chunk of planner 'AS' on 'wh'" in line and "at most 0 runs" in line
    assert re.search(r"Use at most \d+ ants \(now 1000000000\)", line) and "Split" not in line
    assert not (tmp_path / "runs").exists()  # the A* chunks did not run first
    _record("ants-1e9", 2, line)


def test_a_generated_map_beyond_memory_is_refused(tmp_path, capsys):
    cfg = tmp_path / "huge.toml"
    cfg.write_text(CONV.replace("params = { width = 14, height = 10,", "params = { width = 1000000, height = 1000000,"))
    assert _run(cfg, tmp_path / "runs") == 2
    line = _one_line(capsys.readouterr().err)
    assert "map 'wh': a generated 1000000x1000000 map needs about" in line and "cells fit" in line
    _record("map-generator-size", 2, line)


def _capped(gib: int) -> str:
    """Python lines that cap the process's address space at ``gib`` GiB (a runaway allocation then fails in the
    process instead of taking the machine; set in the child itself, as a fork of this threaded process must not
    run Python before exec)."""
    return f"import resource\nresource.setrlimit(resource.RLIMIT_AS, ({gib} * 2**30, {gib} * 2**30))\n"


def _limited_cli(args: list[str], cwd: Path, gib: int = 6, timeout: float = 120) -> subprocess.CompletedProcess:
    """``jaxplan ARGS`` (the console script's way: ``main()`` reads sys.argv) under an address-space cap."""
    env = {k: v for k, v in os.environ.items() if k not in ("JAXPLAN_MEMORY_LIMIT", "XLA_FLAGS")}
    env["JAXPLAN_HOST_DEVICES"] = "1"
    code = _capped(gib) + f"import sys\nsys.argv = ['jaxplan', *{args!r}]\nfrom jaxplan.cli import main\n" \
                          "raise SystemExit(main())\n"
    return subprocess.run([sys.executable, "-c", code], cwd=cwd, capture_output=True, text=True, timeout=timeout,
                          env=env)


def test_a_tuning_population_beyond_memory_is_refused_before_xla_runs_out(tmp_path):
    cfg = tmp_path / "t.toml"
    cfg.write_text(TUNE.replace("population = 4", "population = 1000000000"))
    proc = _limited_cli(["tune", str(cfg), "--out", str(tmp_path / "runs"), "--no-progress"], tmp_path)
    assert proc.returncode == 2, proc.stderr[-3000:]
    line = _one_line(proc.stderr)
    assert "for 1000000000 weight vectors (population)" in line and "Use a smaller population" in line
    fits = int(re.search(r"at most (\d+) weight vectors", line).group(1))
    assert 0 < fits < 1000000000
    _record("population-1e9", 2, line)


def test_every_batched_entry_point_refuses_before_any_work(tmp_path):
    """plan_batch (a colony and an exact planner), solve_tsp: refused at once, under a capped address space."""
    code = textwrap.dedent("""
        import json, numpy as np, jaxplan as jp
        from jaxplan.aco import TSPProblem
        from jaxplan.scale import MemoryLimitError
        scene = jp.RandomMapGenerator(12, 12, 0.1)(0)
        s, g = np.asarray([scene.start]), np.asarray([scene.goal])
        out = {}
        cases = {
            "aco": lambda: jp.plan_batch(scene.grid, s, g, planner="aco", seeds=range(10**9), ants=4),
            "astar": lambda: jp.plan_batch(scene.grid, s, g, planner="astar", seeds=range(10**9)),
            "tsp": lambda: jp.solve_tsp(TSPProblem("x", None, np.ones((50, 50)) - np.eye(50), "EXPLICIT", 50),
                                        planner="aco", ants=10**8, iterations=2),
        }
        for k, fn in cases.items():
            try:
                fn()
                out[k] = "ran"
            except MemoryLimitError as e:
                out[k] = str(e)
            except BaseException as e:
                out[k] = f"{type(e).__name__}: {e}"[:300]
        print(json.dumps(out))
        """)
    proc = subprocess.run([sys.executable, "-c", _capped(6) + code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert "at most" in out["aco"] and "runs (scenarios x seeds)" in out["aco"], out
    assert "at most" in out["astar"] and "planner 'astar'" in out["astar"], out
    assert "at most" in out["tsp"] and "TSP planner 'aco' with 100000000 ants on 50 cities" in out["tsp"], out
    _record("plan-batch-seeds", "MemoryLimitError", out["astar"])


_PEAK = """
import gc, json, sys
import numpy as np
import jaxplan as jp
from jaxplan.aco import TSPProblem, resolve_tsp, tsp_distances
from jaxplan.nav import NavConfig, navigate_batch
from jaxplan.scale import episode_memory, tsp_memory

def status(key):
    for line in open("/proc/self/status"):
        if line.startswith(key):
            return int(line.split()[1]) * 1024

def peak(fn):
    fn()  # compiles
    gc.collect()
    base = status("VmRSS:")
    open("/proc/self/clear_refs", "w").write("5")  # resets the peak (VmHWM) to the current RSS
    fn()
    return status("VmHWM:") - base

what = sys.argv[1]
if what == "navigate":
    grid = jp.WarehouseGenerator()(0).grid
    free = np.argwhere(np.asarray(grid.free))[:, ::-1]
    idx = np.random.default_rng(0).choice(len(free), (16, 2))
    cfg = NavConfig(max_time=60.0)
    out = [peak(lambda: navigate_batch(grid, free[idx[:, 0]], free[idx[:, 1]], pipeline="astar_kng_dwa", seeds=range(4),
                                       config=cfg, mesh=None)),
           episode_memory(64, cfg.steps, cfg.dwa.samples, rollout_steps=cfg.dwa.steps, map_cells=grid.n_cells).total]
else:
    xy = np.random.default_rng(0).uniform(0, 1000, (1000, 2))
    prob = TSPProblem("r", xy, tsp_distances(xy, "EUC_2D"), "EUC_2D", 1000)
    p = resolve_tsp(what, {"iterations": 3})
    out = [peak(lambda: jp.solve_tsp(prob, what, seed=0, iterations=3)),
           tsp_memory(1000, int(p.get("colonies", 1)), int(p["ants"]), 3).total]
print(json.dumps(out))
"""


@pytest.mark.slow  # ~50 s on 2 cores: a navigation batch and two TSP runs, each compiled, then measured
@pytest.mark.parametrize("what", ["navigate", "aco", "praco"])
def test_the_navigation_and_tsp_estimates_bound_the_measured_peak(what):
    """`episode_memory` and `tsp_memory` are upper bounds of a call's peak RSS rise, and not wildly pessimistic
    (each measured in a process of its own: memory an earlier call freed would hide the peak)."""
    env = {k: v for k, v in os.environ.items() if k not in ("XLA_FLAGS", "JAX_NUM_CPU_DEVICES")}
    env["JAXPLAN_HOST_DEVICES"] = "1"
    proc = subprocess.run([sys.executable, "-c", _PEAK, what], capture_output=True, text=True, timeout=600, env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    measured, estimate = json.loads(proc.stdout.strip().splitlines()[-1])
    assert measured <= estimate < 3 * max(measured, 1), (what, measured / 2**20, estimate / 2**20)


# ---------------------------------------------------------------------------------------------
# Confinement and leaks


def test_a_figure_name_cannot_leave_the_figure_folder(tmp_path, capsys):
    cfg = tmp_path / "escape.toml"
    cfg.write_text(CONV + 'name = "../../../../tmp/x"\n')
    assert _run(cfg, tmp_path / "runs") == 2
    err = capsys.readouterr().err
    assert "figures[0].name: must match" in err and "it names the figure's files, inside the figure folder" in err
    _record("figure-name", 2, next(x.strip() for x in err.splitlines() if "figures[0].name" in x))
    from jaxplan.core.io import confined

    for bad in ("../x", "a/b", ".hidden", "-x", "", "x\0y", "/etc/passwd"):
        with pytest.raises(ValueError, match="cannot name a file"):
            confined(tmp_path, bad, ".png")
    assert confined(tmp_path, "conv_2", ".png") == tmp_path / "conv_2.png"


SECRET = "ghp_SECRETTOKEN0123456789 = do-not-print"


@pytest.mark.parametrize("where", ["map", "scen", "tsp", "tour", "config"])
def test_errors_never_quote_a_file_that_is_not_the_expected_format(tmp_path, capsys, where):
    secret = tmp_path / "secret.txt"
    secret.write_text(SECRET + "\nroot:x:0:0:root:/root:/bin/bash\n" + "daemon:x:1:1::/usr/sbin\n" * 4)
    generated = ('generator = "warehouse"\nseed = 0\nparams = { width = 14, height = 10, shelf_length = 4, '
                 'shelf_depth = 2, aisle = 1, cross_aisle = 2 }')
    if where == "map":
        cfg = tmp_path / "c.toml"
        cfg.write_text(CONV.replace(generated, f'path = "{secret}"'))
        rc = _run(cfg, tmp_path / "runs")
    elif where == "scen":
        m = tmp_path / "ok.map"
        m.write_text("type octile\nheight 2\nwidth 2\nmap\n..\n..\n")
        cfg = tmp_path / "c.toml"
        cfg.write_text(CONV.replace(generated, f'path = "{m}"\nscen = "{secret}"').replace(
            'source = "random"\ncount = 3\nseed = 3\nmin_distance = 5.0', 'source = "scen"'))
        rc = _run(cfg, tmp_path / "runs")
    elif where in ("tsp", "tour"):
        tsp = tmp_path / "ok.tsp"
        tsp.write_text("NAME : ok\nTYPE : TSP\nDIMENSION : 3\nEDGE_WEIGHT_TYPE : EUC_2D\nNODE_COORD_SECTION\n"
                       "1 0 0\n2 3 4\n3 6 0\nEOF\n")
        inst = f'path = "{secret if where == "tsp" else tsp}"' + (f'\ntour = "{secret}"' if where == "tour" else "")
        cfg = tmp_path / "c.toml"
        cfg.write_text(f'[experiment]\nname = "t"\nseeds = 1\n[[instances]]\n{inst}\n'
                       '[[planners]]\nkind = "tsp"\nname = "aco"\noverrides = { ants = 4, iterations = 2 }\n')
        rc = _run(cfg, tmp_path / "runs")
    else:
        rc = _run(secret, tmp_path / "runs")
    err = capsys.readouterr().err
    assert rc == 2, err
    assert "SECRET" not in err and "root:x" not in err and "do-not-print" not in err, err
    if where == "map":
        _record("foreign-file", 2, next(x.strip() for x in err.splitlines() if "secret.txt" in x))


# ---------------------------------------------------------------------------------------------
# A command line that fails well


def _writable(p: Path) -> bool:
    try:
        (p / ".probe").write_text("x")
        (p / ".probe").unlink()
        return True
    except OSError:
        return False


def test_a_read_only_output_folder_is_one_line_and_exit_1(conv, tmp_path, capsys):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    out = ro
    if _writable(ro):  # root writes anywhere: a system folder that refuses even root stands in
        out = Path("/sys/jaxplan-faults-test")
        try:
            out.mkdir()
            out.rmdir()
            pytest.skip("no folder here refuses writes")
        except OSError:
            pass
    try:
        assert _run(conv[0], out) == 1
    finally:
        ro.chmod(0o755)
    line = _one_line(capsys.readouterr().err)
    assert "cannot write" in line and str(out) in line and "pass a writable --out folder" in line
    _record("read-only", 1, line)


class _FileSizeLimit:
    """``RLIMIT_FSIZE`` in this process for a block (a full disk, as the writers see it: EFBIG)."""

    def __init__(self, nbytes: int):
        self.nbytes = nbytes

    def __enter__(self):
        self.old_signal = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        self.soft, self.hard = resource.getrlimit(resource.RLIMIT_FSIZE)
        resource.setrlimit(resource.RLIMIT_FSIZE, (self.nbytes, self.hard))

    def __exit__(self, *exc):
        resource.setrlimit(resource.RLIMIT_FSIZE, (self.soft, self.hard))
        signal.signal(signal.SIGXFSZ, self.old_signal)


def test_a_full_disk_during_a_run_loses_nothing_and_says_what_to_do(conv, run_copy, capsys):
    cfg, run = run_copy
    (run / "trials.csv").unlink()
    ck = run / "checkpoints"
    before = {p.relative_to(ck): p.read_bytes() for p in ck.rglob("*") if p.is_file()}
    with _FileSizeLimit(300):
        rc = _run(cfg, run.parent)
    line = _one_line(capsys.readouterr().err)
    assert rc == 1
    assert "cannot write" in line and "File too large" in line and "run the same command to resume" in line
    assert {p.relative_to(ck): p.read_bytes() for p in ck.rglob("*") if p.is_file()} == before  # nothing lost
    _record("disk-full-run", 1, line)
    assert _run(cfg, run.parent) == 0
    assert (run / "trials.csv").read_bytes() == conv[2]


def test_a_full_disk_during_figures_keeps_index_md(run_copy, tmp_path, capsys):
    _, run = run_copy
    figs = tmp_path / "figs"
    assert main(["figures", str(run), "--out", str(figs)]) == 0
    index = (figs / "conv" / "index.md").read_bytes()
    capsys.readouterr()
    with _FileSizeLimit(64):
        rc = main(["figures", str(run), "--out", str(figs)])
    err = capsys.readouterr().err
    assert rc == 1
    assert (figs / "conv" / "index.md").read_bytes() == index  # not 0 bytes, not half a page
    assert (figs / "conv" / "convergence.png").stat().st_size > 1000
    line = err.strip().splitlines()[-1]
    assert "cannot write" in line and "index.md" in line and "File too large" in line
    _record("disk-full-figures", 1, line)


def test_an_orbax_error_is_one_line_and_exit_1(conv, tmp_path, monkeypatch, capsys):
    import orbax.checkpoint as ocp

    def broken(self, *a, **k):
        raise RuntimeError("INTERNAL: tensorstore: Error writing local file: a simulated failure")

    monkeypatch.setattr(ocp.PyTreeCheckpointer, "save", broken)
    assert _run(conv[0], tmp_path / "runs") == 1
    line = _one_line(capsys.readouterr().err)
    assert "cannot save the arrays of chunk 00000-m0-p0-c0" in line and "run the same command to resume" in line
    _record("orbax-error", 1, line)


@pytest.mark.parametrize("error, case, expect", [
    ("xla", "xla-oom", "XLA ran out of memory (RESOURCE_EXHAUSTED: Out of memory while trying to allocate"),
    ("memory", "memory-error", "out of memory: the machine could not give the memory this step needed"),
])
def test_out_of_memory_in_the_middle_of_a_run_is_one_line_and_exit_1(conv, tmp_path, monkeypatch, capsys, error,
                                                                      case, expect):
    import jax

    def broken(*a, **k):
        if error == "xla":
            raise jax.errors.JaxRuntimeError("RESOURCE_EXHAUSTED: Out of memory while trying to allocate "
                                             "17179869184 bytes.")
        raise MemoryError()

    monkeypatch.setattr("jaxplan.aco._planners._run_colony", broken)  # inside plan_batch, as XLA would fail
    assert _run(conv[0], tmp_path / "runs") == 1
    line = _one_line(capsys.readouterr().err)
    assert expect in line and "JAXPLAN_MEMORY_LIMIT" in line
    _record(case, 1, line)


def test_debug_prints_the_traceback(conv, tmp_path, monkeypatch, capsys):
    def broken(*a, **k):
        raise MemoryError()

    monkeypatch.setattr("jaxplan.aco._planners._run_colony", broken)
    assert main(["--debug", "run", str(conv[0]), "--out", str(tmp_path / "runs"), "--no-progress"]) == 1
    err = capsys.readouterr().err
    assert "Traceback (most recent call last)" in err and err.strip().splitlines()[-1].startswith("jaxplan: error:")


@pytest.mark.parametrize("value", ["100000", "99999999999999999999", "abc"])
def test_a_bad_jaxplan_host_devices_is_one_line_and_exit_2(tmp_path, value):
    from jaxplan.scale import host_devices_setting

    with pytest.raises(ValueError, match="JAXPLAN_HOST_DEVICES"):
        host_devices_setting(value)
    # A process of its own: JAX fixes its device count once, and this one may have started already.
    env = {k: v for k, v in os.environ.items() if k not in ("XLA_FLAGS", "JAX_NUM_CPU_DEVICES")}
    env["JAXPLAN_HOST_DEVICES"] = value
    proc = subprocess.run([sys.executable, "-m", "jaxplan.cli", "run", str(tmp_path / "nothing.toml")],
                          capture_output=True, text=True, timeout=120, env=env)
    assert proc.returncode == 2, proc.stderr
    line = _one_line(proc.stderr)
    assert "$JAXPLAN_HOST_DEVICES" in line
    if value == "100000":
        _record("host-devices", 2, line)


def test_ctrl_c_exits_130_and_says_how_to_resume(tmp_path):
    """SIGINT once the first chunk is committed: exit 130, one line, no traceback, the lock released."""
    from jaxplan.experiments import read_manifest

    cfg = tmp_path / "long.toml"
    cfg.write_text(CONV.replace("count = 3", "count = 40").replace("chunk = 2", "chunk = 1"))
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "JAXPLAN_HOST_DEVICES": "1"}
    run = tmp_path / "runs" / "conv"
    committed = lambda: len(read_manifest(run)["chunks"]) if (run / "checkpoints" / "manifest.json").is_file() \
        else 0  # noqa: E731
    proc = subprocess.Popen([sys.executable, "-m", "jaxplan.cli", "run", str(cfg), "--out", str(tmp_path / "runs"),
                             "--no-progress"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and not committed():
            assert proc.poll() is None, proc.stderr.read()
            time.sleep(0.02)
        proc.send_signal(signal.SIGINT)
        err = proc.communicate(timeout=60)[1]
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, err
    line = _one_line(err)
    assert "interrupted" in line and "run the same command to resume" in line
    assert 1 <= committed() < 40
    _record("sigint", 130, line)
    from jaxplan.core.io import folder_lock

    with folder_lock(run):  # released: the same command can resume
        pass


def test_a_truncated_tuning_checkpoint_falls_back_to_the_intact_one_before(tmp_path, capsys):
    import jax.numpy as jnp

    from jaxplan.tune import function_objective, make_strategy, tune_loop

    obj = function_objective(lambda x, s: jnp.sum((x - 0.3) ** 2) + 0.01 * s, {"x": (-2.0, 2.0), "y": (-2.0, 2.0)})
    ref = tune_loop(obj, make_strategy("cma_es", 8, 6), 6, tmp_path / "ref", checkpoint_every=2, progress=False)
    tune_loop(obj, make_strategy("cma_es", 8, 6), 6, tmp_path / "a", checkpoint_every=2, progress=False)
    for p in (tmp_path / "a" / "checkpoints" / "gen_00006").rglob("*"):
        if p.is_file():
            p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])
    capsys.readouterr()
    res = tune_loop(obj, make_strategy("cma_es", 8, 6), 6, tmp_path / "a", checkpoint_every=2, progress=False)
    err = capsys.readouterr().err
    assert res.resumed_from == 4  # generations 5 and 6 recomputed from the intact checkpoint of 4
    assert (tmp_path / "a" / "generations.csv").read_bytes() == (tmp_path / "ref" / "generations.csv").read_bytes()
    assert (res.best_x == ref.best_x).all()
    _record("tune-checkpoint", "-", err.strip().splitlines()[0])


@pytest.mark.parametrize("damage", ["truncated", "emptied"])
def test_a_damaged_manifest_is_rebuilt_from_the_intact_chunks(conv, run_copy, capsys, damage):
    cfg, run = run_copy
    m = run / "checkpoints" / "manifest.json"
    m.write_bytes(m.read_bytes()[:100] if damage == "truncated" else b"{}")
    (run / "trials.csv").unlink()
    assert _run(cfg, run.parent) == 0
    err = capsys.readouterr().err
    line = next(x for x in err.splitlines() if "manifest.json" in x)
    assert "rebuilt from 2 intact chunks" in line
    assert "delete the run folder" not in err and "different experiment" not in err
    man = json.loads(m.read_text())
    assert {e["session"] for e in man["chunks"].values()} == {1}  # nothing recomputed
    assert (run / "trials.csv").read_bytes() == conv[2]
    _record(f"manifest-{damage}", 0, line)


def test_a_second_tune_process_on_one_folder_is_refused(tmp_path, capsys):
    cfg = tmp_path / "t.toml"
    cfg.write_text(TUNE.replace("generations = 3", "generations = 200"))
    out = tmp_path / "runs"
    env = {**os.environ, "JAXPLAN_HOST_DEVICES": "1"}
    first = subprocess.Popen([sys.executable, "-m", "jaxplan.cli", "tune", str(cfg), "--out", str(out),
                              "--no-progress"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and not (out / "t" / "config.toml").is_file():
            assert first.poll() is None, first.stderr.read()
            time.sleep(0.05)
        rc = main(["tune", str(cfg), "--out", str(out), "--no-progress"])
        assert first.poll() is None
    finally:
        first.kill()
        first.wait()
    assert rc == 1
    line = _one_line(capsys.readouterr().err)
    assert f"is in use by pid {first.pid}" in line and "pass another --out" in line
    _record("tune-lock", 1, line)


def test_a_lock_left_by_a_dead_process_is_taken_over(run_copy, capsys):
    cfg, run = run_copy
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    (run / ".lock").write_text(f"{dead.pid}\n")
    assert _run(cfg, run.parent) == 0
    assert (run / ".lock").read_text().split()[0] == str(os.getpid())
    _record("stale-lock", 0, capsys.readouterr().out.strip().splitlines()[-1])


def test_user_facing_files_are_written_only_through_the_atomic_write():
    """index.md, summary.md, report.md, figures, best.toml, ...: no writer in jaxplan bypasses jaxplan.core.io
    (a full disk or a kill mid-write leaves the old file, never a 0-byte one)."""
    bad = []
    for p in (ROOT / "jaxplan").rglob("*.py"):
        if p.relative_to(ROOT).as_posix() == "jaxplan/core/io.py":
            continue
        for i, line in enumerate(p.read_text().splitlines(), 1):
            code = line.split("#")[0]
            if re.search(r"\.write_text\(|\.write_bytes\(|\bopen\([^)]*['\"][wax]b?['\"]|os\.fdopen\(", code):
                bad.append(f"{p.relative_to(ROOT)}:{i}: {line.strip()}")
            if ".savefig(" in code and "tmp" not in code:
                bad.append(f"{p.relative_to(ROOT)}:{i}: {line.strip()}")
    assert not bad, "\n".join(bad)


# ---------------------------------------------------------------------------------------------
# Fuzzing every parser

EXAMPLES = int(os.environ.get("JAXPLAN_FUZZ_EXAMPLES", "40"))
"""Examples per parser; CI's 40 are derandomized (the same each run); ``JAXPLAN_FUZZ_RANDOM=1`` draws new ones."""
FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize="JAXPLAN_FUZZ_RANDOM" not in os.environ,
                database=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                       HealthCheck.function_scoped_fixture])

_numbers = st.one_of(st.integers(-3, 40), st.integers(-10**30, 10**30), st.sampled_from(
    ["1e9", "1000000000000", "nan", "inf", "-0", "0x10", "1_000", "", "three", "3.5", "٣"]))
_junk = st.text(alphabet=st.characters(codec="utf-8", exclude_categories=("Cs",)), max_size=30)


def _mutate(draw, text: str) -> str:
    """``text`` with 0-3 edits: a number replaced by a huge, negative or non-numeric one, a line dropped,
    doubled or inserted, a control character, or the text cut short."""
    lines = text.split("\n")
    for _ in range(draw(st.integers(0, 3))):
        op = draw(st.sampled_from(["number", "drop", "double", "junk", "control", "cut"]))
        i = draw(st.integers(0, max(len(lines) - 1, 0)))
        if op == "number" and lines:
            tokens = re.split(r"(-?\d+(?:\.\d+)?)", lines[i])
            spots = [k for k in range(1, len(tokens), 2)]
            if spots:
                tokens[draw(st.sampled_from(spots))] = str(draw(_numbers))
                lines[i] = "".join(tokens)
        elif op == "drop" and lines:
            del lines[i]
        elif op == "double" and lines:
            lines.insert(i, lines[i])
        elif op == "junk":
            lines.insert(i, draw(_junk))
        elif op == "control" and lines:
            j = draw(st.integers(0, len(lines[i])))
            ctrl = draw(st.sampled_from(["\x00", "\x0b", "\r", "\x1c", "\x85", "\t"]))
            lines[i] = lines[i][:j] + ctrl + lines[i][j:]
        elif op == "cut":
            text = "\n".join(lines)
            lines = text[: draw(st.integers(0, len(text)))].split("\n")
    return "\n".join(lines)


@st.composite
def map_texts(draw):
    h, w = draw(st.integers(1, 6)), draw(st.integers(1, 8))
    rows = ["".join(draw(st.lists(st.sampled_from(".@GSTOW"), min_size=w, max_size=w))) for _ in range(h)]
    text = "\n".join(["type octile", f"height {h}", f"width {w}", "map", *rows]) + draw(st.sampled_from(["", "\n"]))
    if draw(st.booleans()):
        text = text.replace("\n", "\r\n")
    return _mutate(draw, text)


@st.composite
def scen_texts(draw):
    w, h = draw(st.integers(1, 9)), draw(st.integers(1, 9))
    lines = ["version 1"]
    for _ in range(draw(st.integers(0, 5))):
        cells = [draw(st.integers(0, w - 1)), draw(st.integers(0, h - 1)), draw(st.integers(0, w - 1)),
                 draw(st.integers(0, h - 1))]
        opt = draw(st.sampled_from(["0", "1.41421356", "12.5", "3"]))
        lines.append("\t".join(map(str, [draw(st.integers(0, 9)), "m.map", w, h, *cells, opt])))
    return _mutate(draw, "\n".join(lines))


@st.composite
def tsplib_texts(draw):
    n = draw(st.integers(1, 7))
    wtype = draw(st.sampled_from(["EUC_2D", "CEIL_2D", "ATT", "GEO", "EXPLICIT"]))
    head = [f"NAME : fuzz{n}", draw(st.sampled_from(["TYPE : TSP", "TYPE : TOUR", "TYPE: TSP"])), f"DIMENSION : {n}",
            f"EDGE_WEIGHT_TYPE : {wtype}"]
    body = []
    if wtype == "EXPLICIT":
        fmt = draw(st.sampled_from(["FULL_MATRIX", "UPPER_ROW", "LOWER_ROW", "UPPER_DIAG_ROW", "LOWER_DIAG_ROW",
                                    "UPPER_COL"]))
        head.append(f"EDGE_WEIGHT_FORMAT : {fmt}")
        count = {"FULL_MATRIX": n * n, "UPPER_ROW": n * (n - 1) // 2, "LOWER_ROW": n * (n - 1) // 2,
                 "UPPER_COL": n * (n - 1) // 2}.get(fmt, n * (n + 1) // 2)
        values = [str(draw(st.integers(0, 99))) for _ in range(count)]
        if fmt == "FULL_MATRIX":  # symmetric, as the format requires
            m = [[0] * n for _ in range(n)]
            for i in range(n):
                for j in range(i + 1, n):
                    m[i][j] = m[j][i] = draw(st.integers(1, 99))
            values = [str(m[i][j]) for i in range(n) for j in range(n)]
        body = ["EDGE_WEIGHT_SECTION", " ".join(values)]
    else:
        coord = st.integers(-90, 90) if wtype == "GEO" else st.integers(0, 1000)
        body = ["NODE_COORD_SECTION"] + [f"{k} {draw(coord)} {draw(coord)}" for k in range(1, n + 1)]
    tour = ["TOUR_SECTION"] + [str(k) for k in draw(st.permutations(list(range(1, n + 1))))] + ["-1"]
    lines = head + body + (tour if draw(st.booleans()) else []) + ["EOF"]
    return _mutate(draw, "\n".join(lines))


_ROS_YAML = "resolution: 0.05\norigin: [-1.5, 2.0, 0.0]\nnegate: {neg}\noccupied_thresh: 0.65\nfree_thresh: 0.196\n" \
            "mode: {mode}\n"


def _mutate_bytes(draw, data: bytes) -> bytes:
    """``data`` with 0-3 edits: a byte changed, the file cut short, or a huge, zero or negative number inserted."""
    b = bytearray(data)
    for _ in range(draw(st.integers(0, 3))):
        if not b:
            break
        k = draw(st.integers(0, len(b) - 1))
        op = draw(st.sampled_from(["byte", "cut", "digits"]))
        if op == "byte":
            b[k] = draw(st.integers(0, 255))
        elif op == "cut":
            del b[k:]
        else:
            b[k:k] = draw(st.sampled_from([b"999999999", b"0", b"65536", b"-1", b"46341"]))
    return bytes(b)


@st.composite
def ros_map_cases(draw):
    """A ROS map as the worker takes it (JSON: the YAML, the image's name and its bytes in base64): a valid YAML
    (trinary or scale, negate 0 or 1) with `_mutate`'s edits under an ``image:`` line naming the image, which is
    a PGM (P2 or P5, 8 or 16 bit) or a PNG (grey or RGBA) with `_mutate_bytes`' edits."""
    import base64
    import io

    h, w = draw(st.integers(1, 6)), draw(st.integers(1, 8))
    fmt = draw(st.sampled_from(["P2", "P5", "P5-16", "png-L", "png-RGBA"]))
    maxval = 65535 if fmt == "P5-16" else 255
    px = [[draw(st.sampled_from([0, 1, 50, 128, 205, 254, maxval])) for _ in range(w)] for _ in range(h)]
    if fmt == "P2":
        name, image = "m.pgm", f"P2\n# fuzz\n{w} {h}\n255\n" + "\n".join(" ".join(map(str, r)) for r in px) + "\n"
        image = _mutate(draw, image).encode("utf-8", "surrogatepass")
    elif fmt.startswith("P5"):
        size = 2 if maxval > 255 else 1
        body = b"".join(v.to_bytes(size, "big") for r in px for v in r)
        name, image = "m.pgm", _mutate_bytes(draw, f"P5\n{w} {h}\n{maxval}\n".encode() + body)
    else:
        from PIL import Image

        mode = fmt[4:]
        im = Image.new(mode, (w, h))
        im.putdata([v if mode == "L" else (v, v, v, draw(st.sampled_from([0, 255]))) for r in px for v in r])
        buf = io.BytesIO()
        im.save(buf, format="PNG")
        name, image = "m.png", _mutate_bytes(draw, buf.getvalue())
    yaml = _ROS_YAML.format(neg=draw(st.sampled_from([0, 1])), mode=draw(st.sampled_from(["trinary", "scale"])))
    yaml = f"image: {name}\n" + _mutate(draw, yaml)  # the image line kept: every case names a file that exists
    return json.dumps({"yaml": yaml, "name": name, "image": base64.b64encode(image).decode()})


def _toml_value(draw, depth: int = 0) -> str:
    kind = draw(st.sampled_from(["int", "float", "str", "bool", "list", "table"] if depth < 2 else
                                ["int", "float", "str", "bool"]))
    if kind == "int":
        return str(draw(st.one_of(st.integers(-2, 40), st.integers(-2**63, 2**63 - 1))))
    if kind == "float":
        return draw(st.sampled_from(["0.5", "1e300", "-1e-300", "nan", "inf", "-inf", "1e9", "3.0"]))
    if kind == "str":
        return json.dumps(draw(st.sampled_from(["aco", "iaco", "astar", "plan", "navigate", "tsp", "random",
                                                "warehouse", "scen", "../../x", "", "convergence", "iaco_dwa"])))
    if kind == "bool":
        return draw(st.sampled_from(["true", "false"]))
    if kind == "list":
        return "[" + ", ".join(_toml_value(draw, depth + 1) for _ in range(draw(st.integers(0, 3)))) + "]"
    keys = draw(st.lists(st.sampled_from(_TOML_KEYS), max_size=3, unique=True))
    return "{ " + ", ".join(f"{k} = {_toml_value(draw, depth + 1)}" for k in keys) + " }"


_TOML_KEYS = ["name", "seeds", "chunk", "kind", "label", "overrides", "ants", "iterations", "count", "source",
              "seed", "width", "height", "generator", "path", "params", "population", "generations", "planner",
              "strategy", "train_count", "train_seeds", "test_seeds", "space", "beta", "alpha", "scenario", "metric",
              "maps", "planners", "quick", "obstacle_ratio", "min_distance", "x", "steps", "max_time"]
_TABLES = ["experiment", "tune", "scenarios", "stats", "paper", "experiment.quick", "tune.quick", "tune.space"]
_ARRAYS = ["maps", "planners", "figures", "instances", "paper.values"]


@st.composite
def toml_texts(draw, base: str):
    """A valid config with tables and keys changed, added or dropped (often still TOML, rarely valid)."""
    lines = base.strip().splitlines()
    for _ in range(draw(st.integers(1, 4))):
        op = draw(st.sampled_from(["set", "add", "drop", "table", "junk"]))
        i = draw(st.integers(0, len(lines)))
        if op == "set":
            j = draw(st.integers(0, len(lines) - 1))
            if "=" in lines[j]:
                lines[j] = lines[j].split("=")[0] + "= " + _toml_value(draw)
        elif op == "add":
            lines.insert(i, f"{draw(st.sampled_from(_TOML_KEYS))} = {_toml_value(draw)}")
        elif op == "drop" and lines:
            del lines[min(i, len(lines) - 1)]
        elif op == "table":
            head = f"[{draw(st.sampled_from(_TABLES))}]" if draw(st.booleans()) else \
                f"[[{draw(st.sampled_from(_ARRAYS))}]]"
            lines.insert(i, head)
        else:
            lines.insert(i, draw(_junk))
    return "\n".join(lines) + "\n"


FUZZ_SEEN: dict[str, dict[str, int]] = {}
"""parser -> outcome -> count over this session's examples."""


def _fuzz(worker, kind: str, text: str) -> None:
    res = worker.parse(kind, text)
    _check(res, text)
    seen = FUZZ_SEEN.setdefault(kind, {"ok": 0, "ValueError": 0})
    seen[res["outcome"]] += 1
    _record(f"fuzz-{kind}", "-", f"{seen['ok']} results, {seen['ValueError']} ValueErrors with a message, "
                                 f"0 other exceptions, 0 hangs")


@FUZZ
@given(text=map_texts())
def test_fuzz_map_parser(worker, text):
    _fuzz(worker, "map", text)


@FUZZ
@given(text=scen_texts())
def test_fuzz_scen_parser(worker, text):
    _fuzz(worker, "scen", text)


@FUZZ
@given(text=tsplib_texts())
def test_fuzz_tsp_parser(worker, text):
    _fuzz(worker, "tsp", text)


@FUZZ
@given(text=tsplib_texts())
def test_fuzz_tour_parser(worker, text):
    _fuzz(worker, "tour", text)


@FUZZ
@given(text=ros_map_cases())
def test_fuzz_ros_map_parser(worker, text):
    _fuzz(worker, "ros", text)


@FUZZ
@given(text=toml_texts(CONV))
def test_fuzz_experiment_config_parser(worker, text):
    _fuzz(worker, "experiment", text)


@FUZZ
@given(text=toml_texts(TUNE))
def test_fuzz_tuning_config_parser(worker, text):
    _fuzz(worker, "tune", text)


def test_the_fuzzing_worker_catches_a_memory_hog_and_a_hang():
    """The harness itself: an allocation beyond the bound fails in the worker (a MemoryError, which `_check`
    rejects) and a parser that does not answer in time is a hang."""
    w = Worker()
    try:
        res = w.parse("alloc", str(2 * BOUND))
        assert res["outcome"] == "other" and res["type"] == "MemoryError", res
        with pytest.raises(AssertionError):
            _check(res, "")
        assert w.parse("alloc", str(BOUND // 4))["outcome"] == "ok"  # within the bound
        with pytest.raises(TimeoutError, match="a hang"):
            w.parse("sleep", "30", timeout=1.0)
    finally:
        w.stop()
    with pytest.raises(AssertionError):
        _check({"outcome": "ValueError", "message": " "}, "")


# ---------------------------------------------------------------------------------------------
# The reliability page


def _rows() -> list[dict]:
    rows = []
    for line in DOC.read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 5 and cells[0].startswith("`") and cells[0] != "`Case`":
            rows.append({"case": cells[0].strip("`"), "tried": cells[1], "exit": cells[2],
                         "sees": cells[3], "test": cells[4].strip("`")})
    return rows


def test_the_reliability_page_lists_what_the_tests_saw():
    """Every row of docs/guide/reliability.md names a test of this file; for each case this session ran, the exit
    code and the message quoted first in its cell (``…`` stands for a path, a pid or a number that varies) are
    what the test saw; every case a test records has a row."""
    rows = _rows()
    assert len(rows) >= 20
    module = sys.modules[__name__]
    for r in rows:
        assert callable(getattr(module, r["test"], None)), f"{r['case']}: no test {r['test']!r} in test_faults.py"
        quoted = re.match(r"\s*(?:``\s?(.+?)\s?``|`([^`]+)`)", r["sees"])
        assert quoted, f"{r['case']}: the cell does not start with the quoted message"
        if r["case"] in SEEN:
            code, text = SEEN[r["case"]]
            assert r["exit"] == code, f"{r['case']}: the page says exit {r['exit']}, the test saw {code}"
            pos = 0
            for frag in (quoted.group(1) or quoted.group(2)).split("…"):
                found = text.find(frag.strip(), pos)
                assert found >= 0, f"{r['case']}: {frag.strip()!r} is not in what the test saw:\n{text}"
                pos = found + len(frag.strip())
    assert not set(SEEN) - {r["case"] for r in rows}, f"cases without a row: {set(SEEN) - {r['case'] for r in rows}}"
