"""Exports (issue 30): results as plain dicts and pandas DataFrames, a run's tables as npz and parquet."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import SMALL_ACO, config_toml

import jaxplan as jp
from jaxplan.cli import main
from jaxplan.core.export import json_text, plain, require_pandas

RUN = config_toml(  # the small Ant System and a navigate planner on the tiny warehouse, 2 scenarios x 2 seeds
    metrics=["success", "length", "collisions", "time_s"], experiment={"name": "exp"},
    planners=[SMALL_ACO, {"label": "KNG", "kind": "navigate", "name": "astar_kng_dwa",
                          "nav": {"max_time": 20.0, "replan": False}, "dwa": {"n_v": 4, "n_omega": 5}}])


def _is_plain(x) -> bool:
    if isinstance(x, dict):
        return all(isinstance(k, str) and _is_plain(v) for k, v in x.items())
    if isinstance(x, list):
        return all(_is_plain(v) for v in x)
    return x is None or isinstance(x, (str, int, float, bool))


@pytest.fixture(scope="module")
def scene():
    return jp.WarehouseGenerator(12, 12)(0)


@pytest.fixture(scope="module")
def batch(scene):
    s, g = np.array([scene.start, scene.start]), np.array([scene.goal, scene.goal])
    return jp.plan_batch(scene.grid, s, g, planner="aco", seeds=range(3), ants=6, iterations=4)


@pytest.fixture(scope="module")
def episodes(scene):
    return jp.navigate_batch(scene.grid, np.array([scene.start]), np.array([scene.goal]), pipeline="astar_kng_dwa",
                             seeds=range(2), time_limit=20.0)


def test_plain_turns_numpy_into_builtins():
    d = plain({"a": np.arange(3), "b": np.float32(1.5), "c": (np.int64(2), [np.bool_(True)]), "d": float("inf")})
    assert d == {"a": [0, 1, 2], "b": 1.5, "c": [2, [True]], "d": float("inf")} and _is_plain(d)
    assert json.loads(json_text(d))["d"] is None  # strict JSON: no Infinity


def test_plan_result_to_dict_and_dataframe(scene):
    res = jp.plan(scene.grid, scene.start, scene.goal, planner="iaco", ants=6, iterations=3)
    d = res.to_dict()
    assert _is_plain(d) and d["path"] == res.path.tolist() and d["history"] == res.history.tolist()
    assert d["success"] is True and d["planner"] == "iaco" and "successes" in d["info"]
    failed = jp.PlanResult.failure("aco", 0.1).to_dict()
    assert failed["length"] == float("inf") and failed["path"] == []
    pytest.importorskip("pandas")
    row = res.to_dataframe()
    assert len(row) == 1 and row["length"][0] == pytest.approx(res.length) and row["cells"][0] == len(res.path)
    path = res.to_dataframe("path")
    assert path[["x", "y"]].to_numpy().tolist() == res.path.tolist()
    assert res.to_dataframe("history")["best_cost"].tolist() == pytest.approx(res.history.tolist())
    with pytest.raises(ValueError, match="summary"):
        res.to_dataframe("paths")


def test_batch_result_to_dict_and_dataframe(batch):
    d = batch.to_dict()
    assert _is_plain(d) and np.asarray(d["length"]).shape == (2, 3)
    assert d["paths"][1][2] == batch.result(1, 2).path.tolist()  # no −1 padding
    pytest.importorskip("pandas")
    df = batch.to_dataframe()
    assert len(df) == 6 and df[["scenario", "seed"]].to_numpy().tolist() == [[i, r] for i in range(2) for r in range(3)]
    assert df["length"].tolist() == batch.length.ravel().tolist()
    p = batch.to_dataframe("path")
    one = p[(p.scenario == 1) & (p.seed == 2)]
    assert one[["x", "y"]].to_numpy().tolist() == batch.result(1, 2).path.tolist()
    h = batch.to_dataframe("history")
    assert len(h) == 2 * 3 * 4 and h["best_cost"].tolist() == batch.history.ravel().tolist()


def test_episodes_to_dict_and_dataframe(episodes):
    ep = episodes.episode(0, 1, 0)
    d = ep.to_dict()
    assert _is_plain(d) and d["trajectory"] == ep.trajectory.tolist() and d["reason"] == ep.reason
    db = episodes.to_dict()
    assert _is_plain(db) and db["pipeline"] == "astar_kng_dwa"
    pytest.importorskip("pandas")
    s = ep.to_dataframe()
    assert len(s) == 1 and s["reason"][0] == ep.reason and s["collisions"][0] == ep.collisions
    t = ep.to_dataframe("trajectory")
    assert t[["x", "y", "theta"]].to_numpy().tolist() == ep.trajectory.astype(float).tolist()
    assert t["v"].iloc[:-1].tolist() == ep.controls[:, 0].astype(float).tolist()
    bs = episodes.to_dataframe()
    assert len(bs) == 2 and bs["success"].tolist() == episodes.success.ravel().tolist()
    bt = episodes.to_dataframe("trajectory")
    rows = bt[(bt.scenario == 0) & (bt.seed == 1)]
    assert rows[["x", "y", "theta"]].to_numpy().tolist() == ep.trajectory.astype(float).tolist()


def test_without_pandas_the_error_says_what_to_install(monkeypatch, scene):
    import builtins

    real = builtins.__import__
    monkeypatch.setattr(builtins, "__import__", lambda name, *a, **k: (_ for _ in ()).throw(ImportError(name))
                        if name == "pandas" else real(name, *a, **k))
    with pytest.raises(ImportError, match=r"jaxplan\[export\]"):
        require_pandas()
    with pytest.raises(ImportError, match="pandas"):
        jp.PlanResult.failure("aco", 0.0).to_dataframe()


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory) -> Path:
    from jaxplan.experiments import run_experiment

    d = tmp_path_factory.mktemp("export")
    (d / "exp.toml").write_text(RUN)
    return run_experiment(d / "exp.toml", d / "runs", progress=False)


def test_export_npz_holds_paths_histories_and_trajectories(run_dir, tmp_path, capsys):
    from jaxplan.experiments.store import load_chunk_arrays, read_manifest

    out = tmp_path / "run.npz"
    assert main(["export", str(run_dir), "--format", "npz", "--out", str(out)]) == 0, capsys.readouterr().err
    z = np.load(out)  # no pickle needed
    tables = {k.split(".")[0] for k in z.files}
    assert tables == {"trials", "paths", "histories", "trajectories"}
    assert len(z["trials.success"]) == 2 * 2 * 2  # 2 planners x 2 scenarios x 2 seeds
    # Every plan trial's path, from the checkpoints: scenario 1, seed 1 of the ACO chunk.
    man = read_manifest(run_dir)["chunks"]
    uid = next(u for u, e in man.items() if e["kind"] == "plan")
    a = load_chunk_arrays(run_dir, uid)
    m = (z["paths.kind"] == "plan") & (z["paths.scenario"] == 1) & (z["paths.seed"] == 1)
    want = a["paths"][1, 1, : a["n_cells"][1, 1]]
    assert np.stack([z["paths.x"][m], z["paths.y"][m]], 1).tolist() == want.tolist()
    h = (z["histories.scenario"] == 0) & (z["histories.seed"] == 1)
    assert z["histories.best_cost"][h].tolist() == a["history"][0, 1].tolist()
    uid = next(u for u, e in man.items() if e["kind"] == "navigate")
    a = load_chunk_arrays(run_dir, uid)
    m = (z["trajectories.scenario"] == 0) & (z["trajectories.seed"] == 0)
    assert m.sum() == a["steps"][0, 0] + 1
    assert z["trajectories.x"][m].tolist() == a["states"][0, 0, : a["steps"][0, 0] + 1, 0].tolist()
    assert set(z["trajectories.planner"].tolist()) == {"KNG"}


def test_export_parquet(run_dir, tmp_path, capsys):
    pd = pytest.importorskip("pandas")
    pytest.importorskip("pyarrow")
    out = tmp_path / "pq"
    assert main(["export", str(run_dir), "--format", "parquet", "--out", str(out)]) == 0, capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == ["histories.parquet", "paths.parquet", "trajectories.parquet",
                                                     "trials.parquet"]
    z = np.load(_npz(run_dir, tmp_path))
    paths = pd.read_parquet(out / "paths.parquet")
    assert paths["x"].tolist() == z["paths.x"].tolist() and paths["planner"].tolist() == z["paths.planner"].tolist()
    trials = pd.read_parquet(out / "trials.parquet")
    assert len(trials) == 8 and set(trials["planner"]) == {"AS", "KNG"}


def _npz(run_dir, tmp_path):
    from jaxplan.experiments.export import export_run

    return export_run(run_dir, tmp_path / "x.npz", "npz")[0]


def test_export_needs_a_run_folder(tmp_path, capsys):
    assert main(["export", str(tmp_path)]) == 2
    assert "not a run folder" in capsys.readouterr().err
