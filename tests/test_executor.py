"""Executors: units in this process, or Ray tasks on a two-node cluster on loopback (skipped without Ray)."""

from __future__ import annotations

import glob
import os
import signal
import sys
import threading
import time

import pytest
from conftest import loopback_ray_cluster

from jaxplan.core.executor import ClusterUnreachable, LocalExecutor, RayExecutor, executor_from


def _square(shared: int, x: int) -> int:
    if x < 0:
        raise ValueError(f"bad input {x}")
    return shared * x * x


def _slow_marked(folder: str, x: int) -> int:
    """Leaves a file naming its worker's pid, then takes long enough to be killed mid-task."""
    open(os.path.join(folder, f"{x}_{os.getpid()}"), "w").close()
    time.sleep(4.0)
    return x


def test_local_executor_runs_in_order():
    ex = executor_from(None)
    assert isinstance(ex, LocalExecutor)
    out = list(ex.run(_square, 2, [3, 1, 2]))
    assert [(i, r) for i, r, _ in out] == [(0, 18), (1, 2), (2, 8)]
    assert {w.node for _, _, w in out} == {"local"}
    assert ex.cluster()["kind"] == "local"


def test_import_jaxplan_does_not_import_ray():
    import subprocess

    code = "import sys, jaxplan, jaxplan.core.executor; jaxplan.plan; assert 'ray' not in sys.modules, 'ray'"
    subprocess.run([sys.executable, "-c", code], check=True)


def test_commands_without_ray_never_import_it(tmp_path):
    """A whole ``jaxplan run`` (and the modules of reproduce and study) without ``--ray`` leaves Ray unloaded."""
    import subprocess

    from conftest import ASTAR, config_toml

    code = ("import sys; from jaxplan.cli import main; "
            "assert main(['run', sys.argv[1], '--out', sys.argv[2], '--no-progress']) == 0; "
            "import jaxplan.experiments.reproduce, jaxplan.tune.study.run, jaxplan.cli.commands; "
            "assert 'ray' not in sys.modules, 'ray was imported'")
    cfg = tmp_path / "a.toml"
    cfg.write_text(config_toml(planners=[ASTAR]))
    subprocess.run([sys.executable, "-c", code, str(cfg), str(tmp_path / "runs")], check=True, cwd=tmp_path,
                   capture_output=True)


def test_unreachable_address_is_one_clear_error_fast():
    pytest.importorskip("ray")
    t0 = time.perf_counter()
    with pytest.raises(ClusterUnreachable, match="127.0.0.1:9"):
        RayExecutor("127.0.0.1:9", connect_timeout=2.0)
    assert time.perf_counter() - t0 < 10.0
    with pytest.raises(ClusterUnreachable, match="HOST:PORT"):
        RayExecutor("nonsense")


@pytest.fixture(scope="module")
def cluster():
    """A head and a second node, one CPU each, on this machine (Ray's loopback test cluster)."""
    ray = pytest.importorskip("ray")
    # the workers cannot import this test module: its functions travel by value
    ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])
    with loopback_ray_cluster() as ex:
        yield ex


@pytest.mark.slow
def test_ray_results_whatever_the_order(cluster):
    out = list(cluster.run(_square, 3, list(range(8))))
    assert sorted((i, r) for i, r, _ in out) == [(i, 3 * i * i) for i in range(8)]
    info = cluster.cluster()
    assert info["kind"] == "ray" and len(info["nodes"]) == 2
    assert all(n["cpus"] == 1.0 for n in info["nodes"])
    assert {w.node for _, _, w in out} <= {n["node"] for n in info["nodes"]}


@pytest.mark.slow
def test_ray_task_error_is_not_retried_and_raised_as_locally(cluster):
    with pytest.raises(ValueError, match="bad input -1"):
        list(cluster.run(_square, 1, [2, -1]))


@pytest.mark.slow
def test_ray_worker_killed_mid_task_is_retried(cluster, tmp_path):
    folder = str(tmp_path)

    def kill_first() -> None:
        deadline = time.time() + 60
        while time.time() < deadline:
            marks = glob.glob(os.path.join(folder, "0_*"))
            if marks:
                os.kill(int(marks[0].rsplit("_", 1)[1]), signal.SIGKILL)
                return
            time.sleep(0.1)

    killer = threading.Thread(target=kill_first)
    killer.start()
    out = sorted((i, r) for i, r, _ in cluster.run(_slow_marked, folder, [0, 1]))
    killer.join()
    assert out == [(0, 0), (1, 1)]
    assert len(glob.glob(os.path.join(folder, "0_*"))) == 2  # unit 0 ran twice: killed, then retried
