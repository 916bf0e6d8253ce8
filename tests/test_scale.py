"""Scale-out: sharded batches equal single-device ones; the memory guard refuses what cannot fit."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import jaxplan as jp
from jaxplan.core.io import TMP_GLOB
from jaxplan.scale import MemoryLimitError, aco_memory, batch_mesh, check_memory, memory_limit, pad_leading


def _child(code: str, devices: int | None = 1) -> dict:
    """Runs ``code`` in a fresh interpreter (XLA's device count is fixed at start-up); its last stdout line is JSON.
    ``devices=None``: jaxplan's default (no XLA_FLAGS device count, no $JAXPLAN_HOST_DEVICES)."""
    env = {k: v for k, v in os.environ.items() if k not in ("XLA_FLAGS", "JAXPLAN_HOST_DEVICES", "JAX_NUM_CPU_DEVICES")}
    if devices is not None:
        env["XLA_FLAGS"] = f"--xla_force_host_platform_device_count={devices}"
    proc = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, env=env,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.slow  # 18-38 s each on 2 cores; the suite must stay well under CI's 20 minutes
def test_plan_batch_on_four_devices_equals_one_device():
    """5 scenarios (padded to 8) x 2 seeds over 4 host devices: every field identical, for a plain,
    a multi-colony (praco) and a hooked, 16-direction (opt_ant) colony."""
    out = _child("""
        import json
        import numpy as np, jax
        import jaxplan as jp
        from jaxplan.scale import batch_mesh
        scene = jp.RandomMapGenerator(24, 24, 0.2)(1)
        free = np.argwhere(np.asarray(scene.grid.free))[:, ::-1]
        idx = np.random.default_rng(0).choice(len(free), (5, 2), replace=False)
        starts, goals = free[idx[:, 0]], free[idx[:, 1]]
        res = {"devices": len(jax.devices())}
        for planner in ("iaco", "praco", "opt_ant"):
            a = jp.plan_batch(scene.grid, starts, goals, planner=planner, seeds=[0, 3], ants=12, iterations=4)
            b = jp.plan_batch(scene.grid, starts, goals, planner=planner, seeds=[0, 3], ants=12, iterations=4,
                              mesh=batch_mesh())
            res[planner] = [f for f in ("paths", "n_cells", "length", "cost", "turns", "success", "converged",
                                        "history", "diversity", "successes")
                            if not np.array_equal(getattr(a, f), getattr(b, f))]
            res[planner + "_success"] = float(a.success.mean())
        print(json.dumps(res))
        """, devices=4)
    assert out["devices"] == 4
    for planner in ("iaco", "praco", "opt_ant"):
        assert out[planner] == [], f"{planner}: fields differ between 1 and 4 devices: {out[planner]}"
        assert out[planner + "_success"] > 0.5


@pytest.mark.parametrize("local", ["follow", pytest.param("dwa", marks=pytest.mark.slow)])  # dwa: +30 s of compiling
def test_navigate_batch_and_a_tuning_generation_on_four_devices_equal_one_device(local):
    """Batched navigation among moving discs (re-planning per group of 3 episodes; 5 scenarios x 2 seeds
    padded to 12 over 4 devices) and one tuning generation (7 members padded to 8): identical to one device
    (the tuning metrics that are float sums over path points: to float32 rounding, see below)."""
    out = _child(f"""
        LOCAL = {local!r}
""" + """
        import json
        import numpy as np, jax
        import jaxplan as jp
        from jaxplan.dwa import DWAConfig
        from jaxplan.nav import NavConfig
        from jaxplan.nav._front import planning_grid
        from jaxplan.scale import batch_mesh
        from jaxplan.tune import Split, aco_objective

        res = {"devices": len(jax.devices())}
        grid = jp.WarehouseGenerator()(0).grid
        free = np.argwhere(np.asarray(planning_grid(grid, 0.3).free))[:, ::-1]
        idx = np.random.default_rng(0).choice(len(free), (5, 2), replace=False)
        s, g = free[idx[:, 0]], free[idx[:, 1]]
        # Groups of 3: one device runs 10 episodes as 3 + 3 + 3 + 1 (a partial group, nothing padded);
        # 4 devices get 3 each (12, the last 2 padded with episodes that do not run).
        cfg = NavConfig(replan_group=3, max_time=25.0, dwa=NavConfig().dwa.replace(n_v=6, n_omega=11))
        obs = lambda e, seed: jp.random_obstacles(grid, 3, speed=1.0, seed=seed * 100 + e,
                                                  avoid=[(s[e] + 0.5) * grid.resolution])
        kw = dict(pipeline="iaco_dwa", local_planner=LOCAL, seeds=[0, 1], obstacles=obs, config=cfg, ants=12,
                  iterations=4)
        a = jp.navigate_batch(grid, s, g, mesh=None, **kw)
        b = jp.navigate_batch(grid, s, g, mesh=batch_mesh(), **kw)
        same = lambda x, y: np.array_equal(x, y, equal_nan=x.dtype.kind == "f")
        res["nav"] = [f for f in a._fields
                      if isinstance(getattr(a, f), np.ndarray) and not same(getattr(a, f), getattr(b, f))]
        res["replans"] = int(a.replans.sum())
        after = np.arange(a.states.shape[-2]) > a.steps[..., None]  # rows after each robot's last step
        res["rest"] = bool(np.all(a.states[..., 3:][after] == 0) and np.all(b.states[..., 3:][after] == 0))
        res["moved"] = float(np.mean(a.path_length > 1.0))

        scene = jp.RandomMapGenerator(20, 20, 0.15)(2)
        pts = np.argwhere(np.asarray(scene.grid.free))[:, ::-1]
        j = np.random.default_rng(1).choice(len(pts), (4, 2), replace=False)
        st, go = pts[j[:, 0]], pts[j[:, 1]]
        opt = jp.shortest_lengths(scene.grid, st, go)
        sp = Split(st, go, opt, (0, 1))
        obj = aco_objective(scene.grid, sp, sp._replace(seeds=(2,)), "iaco", overrides=dict(ants=8, iterations=3))
        pop = np.random.default_rng(0).uniform(obj.bounds.low, obj.bounds.high, (7, obj.bounds.dim))
        e1 = obj.with_mesh(None).evaluate(pop)
        e4 = obj.with_mesh(batch_mesh()).evaluate(pop)
        res["tune"] = [k for k in ("fitness", "per_seed") if not np.array_equal(getattr(e1, k), getattr(e4, k))]
        res["tune"] += [k for k in ("gap", "failure", "turns") if not np.array_equal(e1.metrics[k], e4.metrics[k])]
        # Mean clearance and roughness are float sums over path points: XLA's CPU code for a batch of 7
        # members and for one of 2 (a device's share) rounds them differently in the last bits — the
        # same happens on ONE device between populations of 7 and 2 — so they agree to float32 rounding.
        res["tune"] += [k for k in ("clearance", "roughness")
                        if not np.allclose(e1.metrics[k], e4.metrics[k], rtol=1e-6, atol=0)]
        res["finite"] = bool(np.isfinite(e1.fitness).all())
        print(json.dumps(res))
        """, devices=4)
    assert out["devices"] == 4
    assert out["nav"] == [], f"navigate_batch fields differ between 1 and 4 devices: {out['nav']}"
    assert out["replans"] > 0 and out["moved"] > 0.5  # the comparison covers re-planning among moving discs
    assert out["rest"]  # after its last step a robot stands still in the state buffer
    assert out["tune"] == [], f"tuning generation outputs differ between 1 and 4 devices: {out['tune']}"
    assert out["finite"]


def test_default_host_devices_and_auto_mesh(monkeypatch):
    """One host device per core unless the user chose; "auto" shards only batches of enough elements per device."""
    from jaxplan.scale import auto_mesh, host_devices_setting

    monkeypatch.delenv("JAXPLAN_HOST_DEVICES", raising=False)
    assert 1 <= host_devices_setting() <= len(os.sched_getaffinity(0))  # the affinity, capped by a cgroup quota
    assert host_devices_setting("3") == 3 and host_devices_setting("off") is None
    for bad in ("0", "-2", "many"):
        with pytest.raises(ValueError, match="JAXPLAN_HOST_DEVICES"):
            host_devices_setting(bad)
    with pytest.raises(ValueError, match="'auto'"):
        auto_mesh("all", 4)
    assert auto_mesh(None, 100) is None
    import jax

    from jaxplan.scale import AUTO_MIN_PER_DEVICE

    n = len(jax.local_devices())
    assert auto_mesh("auto", AUTO_MIN_PER_DEVICE * n - 1) is None
    m = auto_mesh("auto", AUTO_MIN_PER_DEVICE * n)
    assert (m is None) == (n == 1)
    out = _child("""
        import json, jax, jaxplan
        print(json.dumps({"before": jaxplan.use_host_devices(), "devices": len(jax.devices()),
                          "again": jaxplan.use_host_devices()}))
        """, devices=None)
    assert out["devices"] == out["before"] == out["again"] == host_devices_setting("auto")
    out = _child("""
        import json, jax
        jax.config.update("jax_num_cpu_devices", 1)  # the user's own choice, before the opt-in
        import jaxplan
        print(json.dumps({"set": jaxplan.use_host_devices(), "devices": len(jax.devices())}))
        """, devices=None)
    assert out == {"set": 1, "devices": 1}
    out = _child("""
        import json, os, jax
        import jaxplan
        os.environ["JAXPLAN_HOST_DEVICES"] = "3"
        print(json.dumps({"set": jaxplan.use_host_devices(), "devices": len(jax.devices())}))
        """, devices=None)
    assert out == {"set": 3, "devices": 3}
    scene = jp.RandomMapGenerator(12, 12, 0.1)(0)
    for planner in ("astar", "aco"):
        with pytest.raises(ValueError, match="'auto'"):
            jp.plan_batch(scene.grid, [scene.start], [scene.goal], planner=planner, mesh="everywhere")


def test_mesh_helpers():
    mesh = batch_mesh(1)
    assert mesh.axis_names == ("batch",)
    with pytest.raises(ValueError, match="devices must lie"):
        batch_mesh(0)
    with pytest.raises(ValueError, match="jax.sharding.Mesh"):
        scene = jp.RandomMapGenerator(12, 12, 0.1)(0)
        jp.plan_batch(scene.grid, [scene.start], [scene.goal], planner="aco", mesh="all", ants=4, iterations=2)
    import jax.numpy as jnp

    padded = pad_leading({"a": jnp.arange(3), "b": jnp.ones((3, 2))}, 4)
    np.testing.assert_array_equal(padded["a"], [0, 1, 2, 2])
    assert padded["b"].shape == (4, 2)


def test_memory_guard_refuses_with_the_largest_batch_that_fits(monkeypatch):
    big = jp.RandomMapGenerator(100, 100, 0.2)(0)
    monkeypatch.setenv("JAXPLAN_MEMORY_LIMIT", "64M")
    with pytest.raises(MemoryLimitError, match=r"at most (\d+) runs") as err:
        jp.plan_batch(big.grid, [big.start] * 8, [big.goal] * 8, planner="praco", seeds=range(4), ants=16)
    fits = int(err.value.args[0].split("at most ")[1].split(" ")[0])
    assert 0 < fits < 32
    # The named batch does fit under the same estimate, one more does not.
    est = lambda runs: aco_memory(big.grid.n_cells, 8, runs, 5, 16, 400, 100, penalty=True)  # noqa: E731
    assert est(fits).total <= 64 * 2**20 < est(fits + 1).total
    for bad in ("lots", "-3G", "0"):
        monkeypatch.setenv("JAXPLAN_MEMORY_LIMIT", bad)
        with pytest.raises(ValueError, match="JAXPLAN_MEMORY_LIMIT"):
            memory_limit()
    monkeypatch.setenv("JAXPLAN_MEMORY_LIMIT", "1.5K")
    assert memory_limit() == 1536
    check_memory(est(1), "one run", limit=2**40)  # fits: no error


def test_a_single_run_too_large_names_the_largest_ant_count_and_a_higher_limit(monkeypatch):
    """One run of 10^7 ants cannot be split: the refusal names the largest ant count that fits (it fits, one more
    does not), never "split the batch", and a JAXPLAN_MEMORY_LIMIT above the current one."""
    import re

    from jaxplan.aco import plan_memory
    from jaxplan.scale._memory import _parse_bytes

    scene = jp.RandomMapGenerator(20, 20, 0.1)(0)
    monkeypatch.setenv("JAXPLAN_MEMORY_LIMIT", "1G")
    with pytest.raises(MemoryLimitError) as err:
        jp.plan_batch(scene.grid, [scene.start], [scene.goal], planner="iaco", seeds=[0], ants=10_000_000)
    msg = str(err.value)
    assert "split" not in msg.lower().replace("cannot be split", "") and "at most 0 runs" in msg
    ants = int(re.search(r"use at most (\d+) ants \(now 10000000\)", msg, re.I).group(1))
    assert plan_memory(scene.grid, "iaco", 1, ants=ants).total <= 2**30 < plan_memory(scene.grid, "iaco", 1,
                                                                                        ants=ants + 1).total
    suggested = _parse_bytes(re.search(r"JAXPLAN_MEMORY_LIMIT=(\S+)", msg).group(1))
    assert suggested > 2**30 and suggested >= plan_memory(scene.grid, "iaco", 1, ants=10_000_000).total


def test_a_batch_too_large_keeps_the_batch_advice_and_adds_the_ant_count():
    """When some runs fit, splitting the batch is advice; the ants that fit with every run are named too."""
    from jaxplan.scale import Knob

    est = lambda ants: aco_memory(400, 8, 64, 1, ants, 100, 10)  # noqa: E731
    limit = est(32).total  # the 64 runs fit with 32 ants, not with 64
    with pytest.raises(MemoryLimitError) as err:
        check_memory(est(64), "x", limit=limit, advice="Plan fewer scenarios", knob=Knob("ants", 64, est))
    msg = str(err.value)
    fits = est(64).largest_batch(limit)
    assert 1 <= fits < 64 and f"at most {fits} runs fit. Plan fewer scenarios; or use at most 32 ants (now 64) " \
        "with all 64 runs." in msg


@pytest.mark.slow  # 18-38 s each on 2 cores; the suite must stay well under CI's 20 minutes
def test_memory_estimate_bounds_the_measured_peak():
    """The estimate is an upper bound of a run's peak RSS rise, and not wildly pessimistic (< 3x)."""
    out = _child("""
        import gc, json
        import numpy as np
        import jaxplan as jp
        from jaxplan.aco._planners import _run_colony, split_params
        from jaxplan.registry import resolve
        from jaxplan.scale import aco_memory

        def status(key):
            for line in open("/proc/self/status"):
                if line.startswith(key):
                    return int(line.split()[1]) * 1024

        s = jp.RandomMapGenerator(100, 100, 0.2)(0)
        fr = np.argwhere(s.grid.free)[:, ::-1]
        i = np.random.default_rng(0).choice(len(fr), (16, 2))
        res = {}
        for planner, ants in (("iaco", 64), ("praco", 16)):
            _, p = resolve(planner, dict(ants=ants, iterations=3))
            _run_colony(planner, s.grid, fr[i[:, 0]], fr[i[:, 1]], range(4), p)  # compiles
            gc.collect()
            base = status("VmRSS:")
            open("/proc/self/clear_refs", "w").write("5")  # resets the peak (VmHWM) to the current RSS
            _run_colony(planner, s.grid, fr[i[:, 0]], fr[i[:, 1]], range(4), p)
            cfg, _, _, _ = split_params(s.grid, p)
            est = aco_memory(s.grid.n_cells, 8, 64, cfg.colonies, cfg.ants, cfg.max_steps, cfg.iterations,
                             penalty=cfg.penalise)
            res[planner] = [status("VmHWM:") - base, est.total]
        print(json.dumps(res))
        """)
    for planner, (measured, estimate) in out.items():
        assert measured <= estimate < 3 * max(measured, 1), (planner, measured / 2**20, estimate / 2**20)


def test_host_shares_cover_the_batch_and_shards_merge(tmp_path):
    from jaxplan.scale import host_share, merge_shards, write_shard

    for n, hosts in ((10, 3), (2, 4), (0, 2), (7, 1)):
        shares = [host_share(n, k, hosts) for k in range(hosts)]
        assert [i for s in shares for i in range(n)[s]] == list(range(n))
        assert max(len(range(n)[s]) for s in shares) - min(len(range(n)[s]) for s in shares) <= 1
    with pytest.raises(ValueError, match="process_id"):
        host_share(4, 2, 2)
    data = np.arange(20.0).reshape(10, 2)
    for k in range(3):
        write_shard(tmp_path, "sweep", {"x": data[host_share(10, k, 3)]}, k, 3)
    np.testing.assert_array_equal(merge_shards(tmp_path, "sweep", 3)["x"], data)
    with pytest.raises(FileNotFoundError, match="host 0 of 4"):
        merge_shards(tmp_path, "sweep", 4)
    assert not list(tmp_path.glob(TMP_GLOB)) and sorted(p.name for p in tmp_path.iterdir()) == [
        f"sweep.host-{k}-of-3.npz" for k in range(3)]


def test_importing_jaxplan_leaves_jax_as_the_user_had_it():
    """``import jaxplan`` and a small `jp.plan` (an ant colony: JAX runs) change no ``jax.config`` value but the
    persistent compilation cache's (on by default at first use; ``JAXPLAN_CACHE=off`` leaves even those) and
    leave the device count at JAX's own default; the opt-in is explicit, and too late is a clear error."""
    code = """
        import json
        import jax
        before = dict(jax.config.values)
        import jaxplan as jp
        scene = jp.RandomMapGenerator(12, 12, 0.1)(0)
        res = jp.plan(scene.grid, scene.start, scene.goal, planner="aco", ants=8, iterations=3)
        changed = sorted(k for k, v in jax.config.values.items() if before.get(k, "missing") != v)
        try:
            jp.use_host_devices(jax.device_count() + 1)
            late = "no error"
        except RuntimeError as e:
            late = str(e)
        print(json.dumps({"changed": changed, "devices": jax.device_count(), "success": bool(res.success),
                          "late": late, "same": jp.use_host_devices(jax.device_count())}))
        """
    out = _child(code, devices=None)
    os.environ["JAXPLAN_CACHE"], saved = "off", os.environ.get("JAXPLAN_CACHE")
    try:
        off = _child(code, devices=None)
    finally:
        if saved is None:
            del os.environ["JAXPLAN_CACHE"]
        else:
            os.environ["JAXPLAN_CACHE"] = saved
    plain = _child("""
        import json, jax
        print(json.dumps({"devices": jax.device_count()}))
        """, devices=None)
    assert set(out["changed"]) <= {"jax_compilation_cache_dir", "jax_persistent_cache_min_compile_time_secs"}
    assert off["changed"] == [] and out["success"] and off["success"]
    assert out["devices"] == plain["devices"]
    assert "too late" in out["late"] and "before any JAX computation" in out["late"]
    assert out["same"] == out["devices"]  # asking for the count in effect is no error
    with pytest.raises(ValueError, match="positive integer"):
        jp.use_host_devices(0)


def test_importing_jaxplan_leaves_the_backend_alone():
    """jax.distributed.initialize must come before any backend use, so the import may not start XLA."""
    out = _child("""
        import json
        import jax._src.xla_bridge as xb
        import jaxplan, jaxplan.scale
        print(json.dumps({"backends": sorted(xb._backends)}))
        """)
    assert out["backends"] == []


@pytest.mark.slow
def test_two_hosts_on_localhost_merge_to_the_single_host_result(tmp_path):
    """scripts/sweep_hosts.py on two processes joined by jax.distributed (gloo on loopback), then merged."""
    import socket
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    data = root.parent / "shared" / "benchmarks" / "movingai"
    m, s = data / "warehouse-10-20-10-2-1.map", data / "warehouse-10-20-10-2-1-random-1.scen"
    if not m.exists():
        pytest.skip(f"{m} not found")
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    args = [sys.executable, str(root / "scripts" / "sweep_hosts.py"), str(m), str(s), "--count", "5", "--seeds", "2",
            "--ants", "10", "--iterations", "3", "--out", str(tmp_path)]
    procs = [subprocess.Popen(args, env=dict(os.environ, JAXPLAN_COORDINATOR=f"127.0.0.1:{port}",
                                             JAXPLAN_NUM_PROCESSES="2", JAXPLAN_PROCESS_ID=str(k)),
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for k in range(2)]
    for p in procs:
        _, err = p.communicate(timeout=600)
        assert p.returncode == 0, err[-2000:]
    subprocess.run(args[:4] + ["--out", str(tmp_path), "--merge", "2"], check=True)
    merged = np.load(tmp_path / "sweep.npz")
    grid = jp.load_map(m)
    scen = jp.load_scenarios(s, grid=grid)
    ref = jp.plan_batch(grid, scen.starts[:5], scen.goals[:5], planner="iaco", seeds=range(2), ants=10, iterations=3)
    np.testing.assert_array_equal(merged["length"], ref.length)
    np.testing.assert_array_equal(merged["history"], ref.history)
