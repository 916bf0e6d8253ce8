"""Experiments and studies on a Ray cluster: two nodes on loopback (one CPU each), the same bits as a local run,
faults (a worker killed mid-task, SIGTERM, an unreachable cluster). Skipped without Ray (``jaxplan[ray]``)."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import pytest
from conftest import SMALL_ACO, config_toml, loopback_ray_cluster

ray = pytest.importorskip("ray")

from jaxplan.experiments import run_experiment  # noqa: E402

# Three ACO planners of different shapes (each compiles on its own), two scenarios in chunks of one: six chunks, so a
# run is still going when the first chunk is committed.
PLANNERS = [SMALL_ACO, {**SMALL_ACO, "label": "AS5", "overrides": {**SMALL_ACO["overrides"], "ants": 5}},
            {**SMALL_ACO, "label": "AS6", "overrides": {**SMALL_ACO["overrides"], "ants": 6}}]
CONFIG = config_toml(experiment={"name": "tiny", "seeds": 2, "chunk": 1}, planners=PLANNERS)


def jaxplan(*args: str, cwd: Path, check: bool = True, env: dict | None = None) -> subprocess.CompletedProcess:
    """``jaxplan ARGS`` in a process of its own (host devices as the command sets them: one per core)."""
    out = subprocess.run([sys.executable, "-m", "jaxplan.cli", *args], cwd=cwd, capture_output=True, text=True,
                         env=env)
    if check:
        assert out.returncode == 0, out.stderr
    return out


def start(*args: str, cwd: Path, env: dict | None = None) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "jaxplan.cli", *args], cwd=cwd, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)


@pytest.fixture(scope="module")
def cluster():
    """A head and a second node, one CPU each, on this machine (Ray's loopback test cluster): its executor."""
    with loopback_ray_cluster() as ex:
        yield ex


@pytest.fixture(scope="module")
def work(tmp_path_factory) -> Path:
    """A folder with the tiny config, and its local run by the command line (``local/tiny``)."""
    d = tmp_path_factory.mktemp("ray")
    (d / "tiny.toml").write_text(CONFIG)
    jaxplan("run", "tiny.toml", "--out", "local", "--no-progress", cwd=d)
    return d


def trials(run: Path) -> bytes:
    return (run / "trials.csv").read_bytes()


def chunks(run: Path) -> dict:
    return json.loads((run / "checkpoints" / "manifest.json").read_text())["chunks"]


@pytest.mark.slow
def test_run_experiment_on_ray_equals_local(cluster, work):
    run = run_experiment(work / "tiny.toml", work / "py", progress=False, executor=cluster)
    assert trials(run) == trials(work / "local" / "tiny")
    meta = json.loads((run / "meta.json").read_text())
    nodes = meta["sessions"][-1]["executor"]["nodes"]
    assert meta["sessions"][-1]["executor"]["kind"] == "ray"
    assert len(nodes) == 2 and all(n["cpus"] == 1.0 for n in nodes)
    assert set(meta["placement"]) == set(chunks(run))  # every chunk says where it ran, on a node of the cluster
    assert {p["node"] for p in meta["placement"].values()} <= {n["node"] for n in nodes}


@pytest.mark.slow
def test_cli_run_on_ray_equals_local(cluster, work):
    out = jaxplan("run", "tiny.toml", "--out", "cli", "--ray", cluster.address, "--no-progress", cwd=work)
    assert "wrote cli/tiny/" in out.stdout
    assert trials(work / "cli" / "tiny") == trials(work / "local" / "tiny")  # 2 host devices here, 1 per worker
    assert (work / "cli" / "tiny" / "timings.csv").read_text().count("\n") == 1 + len(chunks(work / "cli" / "tiny"))


def _kill_a_running_task(stop: threading.Event, killed: list[int]) -> None:
    """SIGKILLs the first worker process of this test's cluster seen running a task (``ray::_ray_call``)."""
    import psutil

    me = psutil.Process()
    while not stop.is_set() and not killed:
        for p in me.children(recursive=True):
            try:
                if p.cmdline()[:1] == ["ray::_ray_call"]:
                    p.kill()
                    killed.append(p.pid)
                    return
            except psutil.Error:
                continue
        time.sleep(0.02)


@pytest.mark.slow
def test_a_worker_killed_mid_task_is_retried_and_the_run_ends_identical(cluster, tmp_path):
    # seeds = 3: shapes these workers have not compiled yet, so every task lasts long enough to be caught
    cfg = tmp_path / "kill.toml"
    cfg.write_text(config_toml(experiment={"name": "kill", "seeds": 3, "chunk": 1}, scenarios={"count": 3}))
    local = run_experiment(cfg, tmp_path / "local", progress=False)
    stop, killed = threading.Event(), []
    killer = threading.Thread(target=_kill_a_running_task, args=(stop, killed))
    killer.start()
    try:
        run = run_experiment(cfg, tmp_path / "ray", progress=False, executor=cluster)
    finally:
        stop.set()
        killer.join()
    assert killed, "no running task was seen to kill"
    assert trials(run) == trials(local)
    assert len(chunks(run)) == 3  # committed once each


@pytest.mark.slow
def test_sigterm_stops_a_run_like_ctrl_c_and_the_same_command_resumes(cluster, work):
    # --ray auto with no cluster of `ray start` in sight (Ray's records in a folder of its own): the command starts a
    # Ray instance for itself and shuts it down as it stops, which resets the signals underneath Python
    ray_tmp = tempfile.mkdtemp(prefix="r", dir="/tmp")  # short: Ray's socket paths must fit in 107 bytes
    env = {**os.environ, "RAY_TMPDIR": ray_tmp}
    args = ("run", "tiny.toml", "--out", "term", "--ray", "auto", "--no-progress")
    proc = start(*args, cwd=work, env=env)
    manifest = work / "term" / "tiny" / "checkpoints" / "manifest.json"
    deadline = time.time() + 120
    while time.time() < deadline and proc.poll() is None:
        try:
            if json.loads(manifest.read_text())["chunks"]:
                break
        except (OSError, ValueError, KeyError):
            pass
        time.sleep(0.05)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    assert err.strip().splitlines()[-1] == ("jaxplan: terminated (SIGTERM); everything finished so far is saved: run "
                                            "the same command to resume (exit 143)")
    kept = chunks(work / "term" / "tiny")
    assert 1 <= len(kept) < 2 * len(PLANNERS)
    again = jaxplan(*args, cwd=work, env=env)
    shutil.rmtree(ray_tmp, ignore_errors=True)
    assert trials(work / "term" / "tiny") == trials(work / "local" / "tiny")
    assert all(chunks(work / "term" / "tiny")[k]["session"] == 1 for k in kept)  # not computed again
    assert again.returncode == 0
    meta = json.loads((work / "term" / "tiny" / "meta.json").read_text())
    assert len(meta["sessions"]) == 2 and meta["sessions"][-1]["executor"]["started_here"]


@pytest.mark.slow
def test_study_on_ray_equals_local(cluster, tmp_path):
    from jaxplan.tune import run_study

    (tmp_path / "study.toml").write_text(config_toml("study"))
    local = run_study(tmp_path / "study.toml", out=tmp_path / "local", progress=False)
    jaxplan("study", "study.toml", "--out", "ray", "--ray", cluster.address, "--no-progress", cwd=tmp_path)
    here = tmp_path / "ray" / local.name

    def log(folder: Path) -> list[list[str]]:  # wall_s (column 7) aside
        return [line.split(",")[:6] + line.split(",")[7:] for line in (folder / "log.csv").read_text().splitlines()]

    assert log(here) == log(local)
    assert len(log(local)) > 1
    verdict = [json.loads((f / "summary.json").read_text())["best"] for f in (local, here)]
    assert verdict[0] == verdict[1]
    assert not (here / "runs").exists()  # the runs ran in the workers' own scratch folders
    runs = json.loads((here / "checkpoints" / "manifest.json").read_text())["runs"]
    assert {e["node"] for e in runs.values()} <= {n["node"] for n in cluster.cluster()["nodes"]}


def test_an_unreachable_cluster_is_one_line_and_exit_1(tmp_path):
    (tmp_path / "tiny.toml").write_text(CONFIG)
    t0 = time.perf_counter()
    out = jaxplan("run", "tiny.toml", "--ray", "127.0.0.1:9", cwd=tmp_path, check=False)
    assert out.returncode == 1
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("jaxplan: error: no Ray cluster answers at 127.0.0.1:9"), lines
    assert time.perf_counter() - t0 < 60
    assert not (tmp_path / "runs").exists()  # nothing was started

