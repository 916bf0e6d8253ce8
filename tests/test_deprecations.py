"""The front door's new signatures, and the previous release's forms: each still works for one release, warns
with a `DeprecationWarning` naming the new form, and gives the same result as the new form (same seed, equal
arrays)."""

from __future__ import annotations

import inspect
import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pytest

import jaxplan as jp
from jaxplan.core.deprecation import keyword_only
from jaxplan.nav import NavConfig, prepare_episodes

KW = inspect.Parameter.KEYWORD_ONLY
POS = inspect.Parameter.POSITIONAL_OR_KEYWORD

# name -> its positional parameters, then its keyword-only parameters with their defaults, in order.
NAV_KEYWORDS = ["pipeline", "global_planner", "local_planner"]
NAV_TAIL = ["config", "params", "time_limit"]
SAFETY = {"safety": None, "walker_speed_max": None}
SIGNATURES = {
    "plan": (["grid", "start", "goal"], {"planner": "astar", "seed": 0}),
    "plan_batch": (["grid", "starts", "goals"], {"planner": "astar", "seeds": range(1), "mesh": "auto",
                                                 "progress": False}),
    "navigate": (["grid", "start", "goal"], {**dict.fromkeys(NAV_KEYWORDS), "seed": 0, "obstacles": None,
                                             **dict.fromkeys(NAV_TAIL), "progress": False, **SAFETY}),
    "navigate_batch": (["grid", "starts", "goals"], {**dict.fromkeys(NAV_KEYWORDS), "pipeline": "iaco_dwa",
                                                     "seeds": range(1), "obstacles": None, **dict.fromkeys(NAV_TAIL),
                                                     "mesh": "auto", "progress": False, **SAFETY}),
}
SIGNATURES["navigate_multi"] = SIGNATURES["navigate_batch"]


def _checked(name: str, fn) -> None:
    positional, keywords = SIGNATURES[name]
    params = inspect.signature(fn).parameters
    got_pos = [n for n, p in params.items() if p.kind is POS]
    got_kw = {n: p.default for n, p in params.items() if p.kind is KW}
    assert got_pos == positional, name
    assert list(got_kw) == list(keywords) and got_kw == keywords, name
    assert list(params.values())[-1].kind is inspect.Parameter.VAR_KEYWORD, name  # planner parameters


@pytest.mark.parametrize("name", sorted(SIGNATURES))
def test_the_front_door_has_the_documented_signatures(name):
    _checked(name, getattr(jp, name))


def test_prepare_episodes_takes_navigate_batch_keywords():
    mine = inspect.signature(prepare_episodes).parameters
    batch = inspect.signature(jp.navigate_batch).parameters
    assert [n for n in mine if n != "progress"] == [n for n in batch if n != "progress"]


def test_plan_and_plan_batch_share_their_default_planner_and_keywords():
    p, b = inspect.signature(jp.plan).parameters, inspect.signature(jp.plan_batch).parameters
    assert p["planner"].default == b["planner"].default == "astar"
    assert {"planner", "seed"} <= set(p) and {"planner", "seeds"} <= set(b)


# ---------------------------------------------------------------------------------------------
# The previous release's forms: they warn and give the same result as the new form.


@pytest.fixture(scope="module")
def scene():
    return jp.WarehouseGenerator(20, 20)(0)


def _equal(a, b) -> None:
    """Two results (NamedTuples or dicts of arrays and numbers) equal field by field, timings aside."""
    items = a.items() if isinstance(a, dict) else a._asdict().items()
    for k, x in items:
        if k.endswith("time_s") or k == "compile_s" or k == "info":
            continue
        y = b[k] if isinstance(b, dict) else getattr(b, k)
        if isinstance(x, dict) or (isinstance(x, tuple) and hasattr(x, "_asdict")):
            _equal(x, y)
        elif isinstance(x, (np.ndarray, list)) or np.ndim(x):
            np.testing.assert_array_equal(np.asarray(x), np.asarray(y), err_msg=k)
        else:
            assert x == y or (x != x and y != y), k


def _quiet(fn):
    """``fn()`` with a `DeprecationWarning` an error: the new form must not warn."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        return fn()


def test_plan_with_planner_and_seed_by_position(scene):
    g, s, t = scene.grid, scene.start, scene.goal
    with pytest.warns(DeprecationWarning, match=r"pass planner=\.\.\., seed=\.\.\. by keyword"):
        old = jp.plan(g, s, t, "iaco", 3, ants=8, iterations=3)
    new = _quiet(lambda: jp.plan(g, s, t, planner="iaco", seed=3, ants=8, iterations=3))
    _equal(old, new)
    assert old.success and old.planner == "iaco"


def test_plan_batch_with_planner_and_seeds_by_position(scene):
    S, G = np.array([scene.start, [1, 1]]), np.array([scene.goal, [17, 18]])
    with pytest.warns(DeprecationWarning, match=r"pass planner=\.\.\., seeds=\.\.\. by keyword"):
        old = jp.plan_batch(scene.grid, S, G, "aco", [0, 5], ants=8, iterations=3)
    new = _quiet(lambda: jp.plan_batch(scene.grid, S, G, planner="aco", seeds=[0, 5], ants=8, iterations=3))
    _equal(old, new)
    assert old.length.shape == (2, 2)


def test_plan_batch_without_a_planner_warns_that_the_default_is_now_astar(scene):
    S, G = np.array([scene.start]), np.array([scene.goal])
    with pytest.warns(DeprecationWarning, match="default planner is now 'astar'.*it was 'aco'"):
        default = jp.plan_batch(scene.grid, S, G, seeds=[0, 1])
    named = _quiet(lambda: jp.plan_batch(scene.grid, S, G, planner="astar", seeds=[0, 1]))
    _equal(default, named)
    assert default.planner == "astar" and type(default.planner) is str


def test_aco_plan_batch_warns_and_keeps_its_aco_default(scene):
    S, G = np.array([scene.start]), np.array([scene.goal])
    with pytest.warns(DeprecationWarning, match="use jaxplan.plan_batch"):
        from jaxplan.aco import plan_batch as old_plan_batch
    old = old_plan_batch(scene.grid, S, G, seeds=[2], ants=8, iterations=3)
    new = _quiet(lambda: jp.plan_batch(scene.grid, S, G, planner="aco", seeds=[2], ants=8, iterations=3))
    _equal(old, new)
    assert old.planner == "aco"


QUICK = NavConfig(max_time=20.0)


def test_navigate_with_its_old_positional_arguments(scene):
    g, s, t = scene.grid, scene.start, scene.goal
    walkers = jp.random_obstacles(g, 2, seed=1, avoid=np.array([s, t]) + 0.5, avoid_radius=1.5)
    with pytest.warns(DeprecationWarning, match=r"global_planner=\.\.\., local_planner=\.\.\., seed=\.\.\., "
                                                r"obstacles=\.\.\. by keyword"):
        old = jp.navigate(g, s, t, "astar", "dwa", 4, walkers, config=QUICK)
    new = _quiet(lambda: jp.navigate(g, s, t, global_planner="astar", local_planner="dwa", seed=4,
                                     obstacles=walkers, config=QUICK))
    _equal(old, new)
    assert len(old.trajectory) > 10 and len(old.plan) > 1  # the robot drove along a plan


def test_navigate_batch_and_multi_with_their_old_positional_arguments(scene):
    free = np.argwhere(np.asarray(scene.grid.free))[:, ::-1]
    S, G = free[[0, 5]], free[[-1, -7]]
    with pytest.warns(DeprecationWarning, match=r"pass pipeline=\.\.\., seeds=\.\.\., obstacles=\.\.\. by keyword"):
        old = jp.navigate_batch(scene.grid, S, G, "astar_kng_dwa", [0, 1], None, config=QUICK, mesh=None)
    new = _quiet(lambda: jp.navigate_batch(scene.grid, S, G, pipeline="astar_kng_dwa", seeds=[0, 1],
                                           config=QUICK, mesh=None))
    _equal(old, new)
    assert old.success.shape == (2, 2, 1)
    with pytest.warns(DeprecationWarning, match=r"pass pipeline=\.\.\. by keyword"):
        old = jp.navigate_multi(scene.grid, S, G, "astar_kng_dwa", config=QUICK, mesh=None)
    new = _quiet(lambda: jp.navigate_multi(scene.grid, S, G, pipeline="astar_kng_dwa", config=QUICK, mesh=None))
    _equal(old, new)
    assert old.success.shape == (1, 1, 2)


def test_prepare_episodes_with_its_old_positional_arguments(scene):
    S, G = np.array([scene.start]), np.array([scene.goal])
    with pytest.warns(DeprecationWarning, match=r"pass pipeline=\.\.\., seeds=\.\.\. by keyword"):
        old = prepare_episodes(scene.grid, S, G, "astar_kng_dwa", [0, 3], config=QUICK)
    new = _quiet(lambda: prepare_episodes(scene.grid, S, G, pipeline="astar_kng_dwa", seeds=[0, 3], config=QUICK))
    _equal(old.inputs, new.inputs)
    np.testing.assert_array_equal(old.reason, new.reason)
    assert (old.E, old.R, old.N) == (new.E, new.R, new.N) == (1, 2, 1)


def test_a_bad_positional_call_still_fails_as_a_plain_call_would():
    @keyword_only("b", "c")
    def f(a, *, b=1, c=2, d=3):
        return a, b, c, d

    with pytest.warns(DeprecationWarning):
        assert f(0, 5) == (0, 5, 2, 3)
    with pytest.raises(TypeError, match="takes 1 positional arguments but 4 were given"):
        f(0, 1, 2, 3)
    with pytest.raises(TypeError, match="multiple values for argument 'b'"):
        f(0, 1, b=2)
    assert _quiet(lambda: f(0, c=7)) == (0, 1, 7, 3)
    with pytest.raises(TypeError, match="not keyword-only"):
        keyword_only("a")(f.__wrapped__)


# ---------------------------------------------------------------------------------------------
# path_metrics: a typed result; dict access for one release.


def test_path_metrics_dict_access_warns_and_reads_the_fields(scene):
    path = jp.plan(scene.grid, scene.start, scene.goal).path
    m = _quiet(lambda: jp.path_metrics(path, scene.grid))
    assert isinstance(m, jp.PathMetrics) and m.objective_gap is None and m.optimality_gap == pytest.approx(0, abs=1e-6)
    fields = m._asdict()
    old_keys = list(jp.metrics.PATH_METRICS)
    checks = {
        "m['length']": lambda: m["length"] == m.length,
        "m.get": lambda: m.get("turns") == m.turns and m.get("objective_gap", 7) == 7,
        "m.keys()": lambda: list(m.keys()) == old_keys,
        "m.values()": lambda: m.values() == [fields[k] for k in old_keys],
        "m.items()": lambda: dict(m.items()) == {k: fields[k] for k in old_keys},
        "dict(m)": lambda: dict(m) == {k: fields[k] for k in old_keys},
        "iteration": lambda: list(m) == old_keys,
        "len": lambda: len(m) == len(old_keys),
        "in": lambda: "length" in m and "objective_gap" not in m,
    }
    for what, check in checks.items():
        with pytest.warns(DeprecationWarning, match="no longer a dict"):
            assert check(), what
    with pytest.warns(DeprecationWarning), pytest.raises(KeyError):
        m["objective_gap"]  # noqa: B018  (absent without cost=, as the dict's key was)
    assert _quiet(lambda: bool(m))  # truth does not go through the deprecated len()


# ---------------------------------------------------------------------------------------------
# jaxplan.smooth: the function; the subpackage's old import path warns (in a fresh process: importing it binds the
# name jaxplan.smooth to the module, which must not leak into other tests).


def test_the_old_smooth_subpackage_import_warns_and_still_smooths():
    code = textwrap.dedent("""
        import warnings
        import numpy as np
        import jaxplan as jp
        import jaxplan.smoothing
        grid = jp.grid_from_array(np.ones((6, 6), bool))
        path = np.array([[0, 0], [1, 1], [2, 2], [3, 2], [4, 2]])
        new = jp.smooth(path, grid, "los")
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            from jaxplan.smooth import Smoothed, smooth
        assert [w.category for w in caught] == [DeprecationWarning], caught
        assert "jaxplan.smoothing" in str(caught[0].message) and caught[0].filename == "<string>"
        assert smooth is jaxplan.smoothing.smooth and Smoothed is jaxplan.smoothing.Smoothed
        old = jp.smooth(path, grid, "los")  # jp.smooth is now the old module, callable as the function
        assert not callable(getattr(jp.smooth, "__code__", None)) and type(jp.smooth).__name__ == "_CallableModule"
        np.testing.assert_array_equal(np.asarray(old.points), np.asarray(new.points))
        try:
            import jaxplan.smooth._front  # noqa: F401
        except ModuleNotFoundError as e:
            assert "not a package" in str(e), e
        else:
            raise AssertionError("jaxplan.smooth._front imported")
        print("ok")
        """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0 and proc.stdout.strip().endswith("ok"), proc.stderr[-2000:]
