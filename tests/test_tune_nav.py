"""The navigation objective (`nav_objective`): full two-level episodes among walkers, a population per compiled call."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import jaxplan as jp
from jaxplan.experiments.config import parse_config
from jaxplan.nav import NavConfig
from jaxplan.tune import fragment_toml, nav_map, nav_objective, spread_rows

DATA = Path(__file__).resolve().parents[2] / "shared" / "benchmarks" / "movingai"
if not DATA.is_dir():
    DATA = Path("/work/shared/benchmarks/movingai")
MAZE = DATA / "maze-32-32-2.map"
pytestmark = pytest.mark.skipif(not MAZE.is_file(), reason=f"MovingAI maps not found in {DATA}")

TRAIN, TEST = (133, 143), (138, 149)  # short rows (optimal 3.4-8.4 cells) of maze-32-32-2
CFG = NavConfig(max_time=20.0)
ONE = NavConfig(max_time=20.0, replan_group=1)  # the objective's episodes: each its own re-planning group


@pytest.fixture(scope="module")
def maze():
    return nav_map(MAZE, train_rows=TRAIN, test_rows=TEST)


def _walkers(grid, S, G, behavior):
    def make(e, seed):
        avoid = (np.stack([S[e], G[e]]).astype(float) + 0.5) * grid.resolution
        return jp.random_obstacles(grid, n=5, speed=1.0, radius=0.25, seed=10_000 * seed + e, avoid=avoid,
                                   avoid_radius=3.0, behavior=behavior)
    return make


@pytest.mark.parametrize("local", ["dwa", pytest.param("mppi", marks=pytest.mark.slow)])
def test_population_rows_match_each_other_and_navigate_batch(maze, local):
    obj = nav_objective([maze], (0,), (1,), local, config=CFG)
    pop = np.stack([obj.defaults, obj.defaults])
    ev = obj.evaluate(pop)
    assert ev.fitness.shape == (2,) and ev.per_seed.shape == (2, 1)
    assert ev.fitness[0] == ev.fitness[1]
    for k, v in ev.metrics.items():
        assert v[0] == v[1], k
    # the defaults row is navigate_batch's episodes with the default params, each episode its own
    # re-planning group; evaluate (finished episodes dropped) scores as the pure program does
    import jax

    cost, m = jax.jit(obj.map_program("train", 0))(pop[:1])
    np.testing.assert_allclose(ev.fitness[0], np.asarray(cost, np.float64).mean(), rtol=1e-6)
    for k, v in m.items():
        np.testing.assert_allclose(ev.metrics[k][0], np.asarray(v, np.float64).mean(), rtol=1e-6, err_msg=k)
    E, K = len(TRAIN), 2
    success = np.asarray(m["success"]).reshape(E, K, 1)
    time_s = np.asarray(m["time_s"]).reshape(E, K, 1)
    S, G = maze.starts[list(TRAIN)], maze.goals[list(TRAIN)]
    for k, behavior in enumerate(("blind", "social")):
        b = jp.navigate_batch(maze.grid, S, G, pipeline=f"astar_kng_{local}", seeds=[0], config=ONE, mesh=None,
                              obstacles=_walkers(maze.grid, S, G, behavior))
        np.testing.assert_array_equal(success[:, k], b.success[..., 0])
        if local == "dwa":
            np.testing.assert_allclose(time_s[:, k], b.steps[..., 0] * b.period, rtol=1e-6)
        else:  # MPPI with per-episode weights (not broadcast scalars) differs in float's last bits, and its
            # softmax carries that on: measured 9.0 s against 9.4 s on one episode (docs: open item)
            np.testing.assert_allclose(time_s[:, k], b.steps[..., 0] * b.period, atol=1.0)
    assert success.any()  # the episodes are not all trivially failing
    # success first, time second: failure + time / limit (the limit is max_time here: 20 s)
    np.testing.assert_allclose(np.asarray(cost)[0].reshape(E, K, 1), np.where(success, time_s / 20.0, 2.0), rtol=1e-6)


def test_splits_must_be_disjoint(maze):
    with pytest.raises(ValueError, match=r"rows \[143\] are in both"):
        nav_objective([maze._replace(test_rows=(143, 149))], (0,), (1,), "dwa", config=CFG)
    with pytest.raises(ValueError, match=r"seeds \[1\] are in both"):
        nav_objective([maze], (0, 1), (1, 2), "dwa", config=CFG)
    with pytest.raises(ValueError, match="names must be unique"):
        nav_objective([maze, maze], (0,), (1,), "dwa", config=CFG)
    tr, te = spread_rows(maze.optimal, 4, 4)
    assert len(tr) == 4 and len(te) == 4 and not set(tr) & set(te)
    assert all(maze.optimal[r] <= 80 for r in tr + te)


@pytest.mark.parametrize("kw, match", [
    (dict(local="teb"), "local must be 'dwa' or 'mppi'"),
    (dict(pipeline="astar_kng_mppi"), "runs the 'mppi' local planner"),
    (dict(walkers=("flying",)), "walkers must be distinct kinds"),
    (dict(n_walkers=0), "n_walkers must be an integer >= 1"),
    (dict(speed=float("nan")), "speed must be a finite number > 0"),
    (dict(weights={"gap": 1.0}), "unknown metric 'gap'"),
    (dict(train_rows=(0, 999)), r"train_rows \[999\] outside"),
])
def test_bad_values_raise_clearly(maze, kw, match):
    kw = dict(kw)
    m = maze._replace(train_rows=kw.pop("train_rows")) if "train_rows" in kw else maze
    with pytest.raises(ValueError, match=match):
        nav_objective([m], (0,), (1,), **{"local": "dwa", "config": CFG, **kw})


def test_bad_space_raises_after_planning(maze):
    one = maze._replace(train_rows=TRAIN[:1], test_rows=TEST[:1])
    with pytest.raises(ValueError, match="cannot be tuned"):
        nav_objective([one], (0,), (1,), "dwa", config=CFG, walkers=("blind",), space={"temperature": (0.01, 1.0)})


def test_best_fragment_loads_in_the_experiment_parser(maze):
    one = maze._replace(train_rows=TRAIN[:1], test_rows=TEST[:1])
    obj = nav_objective([one], (0,), (1,), "mppi", config=CFG, walkers=("blind",))
    frag = fragment_toml(obj, obj.defaults * 1.1, label="mppi-tuned", overrides={"samples": 64})
    assert 'name = "astar_kng_mppi"' in frag
    exp = parse_config('[experiment]\nname = "x"\nseeds = 1\n[[maps]]\ngenerator = "random"\n'
                       'scenarios = { source = "random", count = 1 }\n' + frag)
    p = exp.planners[0]
    assert p.name == "astar_kng_mppi" and abs(p.params["obstacle"] - 1.1) < 1e-6 and p.mppi["samples"] == 64


NAV_CONFIG = """
[tune]
name = "n"
kind = "nav"
planner = "mppi"
population = 2
generations = 1
train_count = 2
train_seeds = [0]
test_seeds = [1]
[tune.space]
obstacle = [0.05, 5.0]
[scenarios]
max_optimal = 80.0
count = 4
[[maps]]
path = "maze-32-32-2.map"
[[maps]]
path = "random-32-32-20.map"
"""


def test_nav_config_parses_and_defaults():
    from jaxplan.tune import parse_tune_config
    from jaxplan.tune._workflow import _alternate

    cfg = parse_tune_config(NAV_CONFIG, data_dir=DATA)
    assert cfg.kind == "nav" and cfg.pipeline == "astar_kng_mppi" and len(cfg.maps) == 2
    assert cfg.walkers == ("blind", "seeing") and cfg.walker_count == 5 and cfg.max_time == 180.0
    assert cfg.weights == {"failure": 1.0, "time": 1.0}
    train, test = _alternate(np.array([10, 20, 30, 40]), 2, None)
    assert train == (10, 30) and test == (20, 40)


@pytest.mark.parametrize("edit, match", [
    (('pipeline = "x"\n', 'pipeline = "astar_kng_dwa"\n'), "runs the 'dwa' local planner"),
    (('pipeline = "x"\n', 'walkers = ["blind", "flying"]\n'), "tune.walkers: must be distinct kinds"),
    (('pipeline = "x"\n', "time_limit = 300.0\n"), "tune.time_limit: must be at most max_time"),
    (('pipeline = "x"\n', "discs = 2\n"), "tune.discs: applies to kind"),
    (('pipeline = "x"\n', 'weights = { gap = 1.0 }\n'), "gap"),
    (('kind = "nav"', 'kind = "mppi"'), "exactly one map"),
    (('test_seeds = [1]', 'test_seeds = [0]'), "must not share seeds"),
])
def test_bad_nav_config_values_raise_clearly(edit, match):
    from jaxplan.experiments.config import ConfigError
    from jaxplan.tune import parse_tune_config

    text = NAV_CONFIG.replace('planner = "mppi"\n', 'planner = "mppi"\npipeline = "x"\n')
    if edit[0] == 'pipeline = "x"\n':
        text = text.replace(*edit)
    else:
        text = text.replace('pipeline = "x"\n', "").replace(*edit)
    with pytest.raises(ConfigError, match=match):
        parse_tune_config(text, data_dir=DATA)


def test_a_navigation_study_is_one_objective_over_every_map():
    """`jaxplan study` on a ``kind = "nav"`` config: one navigation objective over all maps (not a join that would
    run the first map's episodes only), with the pipeline's default params kept through the study's renaming."""
    from jaxplan.tune import build_study_objective, parse_study_config

    root = Path(__file__).resolve().parents[1]
    text = (root / "configs" / "study_local_mppi.toml").read_text()
    cfg = parse_study_config(text, data_dir=DATA.parent, quick=True)
    obj = build_study_objective(cfg)
    assert obj.name == "study_local_mppi" and obj.kind == "nav"
    assert [m.name for m in obj.maps] == ["maze-32-32-2", "random-32-32-20", "room-64-64-8"]
    assert type(obj.base_params).__name__ == "MPPIParams"
    assert [len(e.index) for e in obj.episodes["train"]] == [1, 1, 1]  # [tune.quick] train_count = 1 per map
    for m in obj.maps:
        assert not set(m.train_rows) & set(m.test_rows)
    # every episode re-plans on its own, so no episode is padded and finished ones can be dropped one by one
    assert [e.B for e in obj.episodes["train"]] == [2, 2, 2]  # 1 row x 1 seed x 2 walker kinds
    assert all(e.config.replan_group == 1 for e in obj.episodes["train"])


def test_a_navigation_study_is_confirmed_among_its_walkers():
    """The confirmation of a navigation study runs defaults and tuned weights among each walker kind of the study,
    with its walkers and episode length, and the config it writes is one `jaxplan run` accepts."""
    from jaxplan.tune import confirm_config, parse_study_config

    root = Path(__file__).resolve().parents[1]
    cfg = parse_study_config((root / "configs" / "study_local_mppi.toml").read_text(), data_dir=DATA.parent)
    entry = ('[[planners]]\nlabel = "{}"\nkind = "navigate"\nname = "astar_kng_mppi"\n'
             'params = {{ obstacle = {} }}\n')
    text = confirm_config(cfg, entry.format("MPPI (tuned)", 2.5), DATA.parent, entry.format("mppi (defaults)", 1.0))
    exp = parse_config(text, data_dir=DATA.parent)
    got = {(p.label, p.obstacles.behavior, p.obstacles.n, p.obstacles.speed) for p in exp.planners}
    assert got == {(f"{who}, {kind} walkers", beh, 5, 1.0) for who in ("mppi (defaults)", "MPPI (tuned)")
                   for kind, beh in (("blind", "blind"), ("seeing", "social"))}
    assert {p.nav["max_time"] for p in exp.planners} == {120.0}
    assert [m.name for m in exp.maps] == ["maze-32-32-2", "random-32-32-20", "room-64-64-8"]
