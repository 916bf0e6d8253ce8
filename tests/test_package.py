"""The lazy top-level package: every public name resolves on first use, ``__all__`` and ``dir`` list them, the
deprecated aliases still work, and ``import jaxplan`` loads no subpackage (nor JAX, numba or numpy)."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import pytest

import jaxplan as jp


def test_every_public_name_resolves_from_its_subpackage():
    for name in jp.__all__:
        value = getattr(jp, name)
        assert value is not None, name
    assert set(jp.__all__) <= set(dir(jp))
    assert {"__version__", "search", "nav", "use_host_devices", "plan", "planners"} <= set(dir(jp))
    assert jp.metrics.path_metrics is jp.path_metrics
    with pytest.raises(AttributeError, match="no attribute 'nonesuch'"):
        jp.nonesuch  # noqa: B018


def test_smooth_is_the_function_and_smoothing_the_subpackage():
    import jaxplan.smoothing
    from jaxplan.smoothing import Smoothed, smooth

    assert jp.smooth is smooth and jp.smoothing is jaxplan.smoothing and jp.Smoothed is Smoothed
    assert callable(jp.smooth) and not isinstance(jp.smooth, type(jaxplan))


def test_plan_batch_and_its_result_sit_beside_plan():
    import jaxplan.planning
    import jaxplan.result

    assert jp.plan_batch is jaxplan.planning.plan_batch and jp.plan is jaxplan.planning.plan
    assert jp.BatchResult is jaxplan.result.BatchResult and jp.PlanResult is jaxplan.result.PlanResult
    assert jp.PathMetrics is jp.metrics.PathMetrics


def test_plan_and_planners_see_every_shipped_planner():
    assert {"astar", "dijkstra", "astar_kng", "rrt_star", "mrbs_rrt", "aco", "iaco", "risk_aco", "opt_ant",
            "praco"} <= set(jp.planners())


@pytest.mark.parametrize("old,new", [("warehouse_seed003", "warehouse_chen2023"),
                                     ("warehouse_seed004", "warehouse_yu2020")])
def test_deprecated_aliases_warn_and_work(old, new):
    with pytest.warns(DeprecationWarning, match=new):
        assert getattr(jp, old) is getattr(jp, new)


def test_import_loads_nothing_heavy():
    code = textwrap.dedent("""
        import json, sys
        import jaxplan
        print(json.dumps(sorted(m for m in sys.modules if m.split(".")[0] in ("jax", "numba", "numpy", "scipy")
                                or m.startswith("jaxplan."))))
        """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert json.loads(proc.stdout.strip().splitlines()[-1]) == []
