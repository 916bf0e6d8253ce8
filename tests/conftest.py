"""Shared fixtures: the benchmark data folder, small maps, and small configs written as TOML (`config_toml`,
`write_config`)."""

from __future__ import annotations

import contextlib
import copy
import importlib.util
import os
import sys
from pathlib import Path
from typing import Any, Callable, Iterator

import numpy as np
import pytest

import jaxplan as jp
from jaxplan.core.toml import dumps

ROOT = Path(__file__).resolve().parents[1]


def load_benchmark(name: str) -> Any:
    """``benchmarks/<name>.py`` imported as a module (benchmarks are scripts, not a package; their ``_timing``
    import resolves from their folder while it loads)."""
    path = ROOT / "benchmarks" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.path.insert(0, str(path.parent))
    try:
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(str(path.parent))
    return module


def data_dir() -> Path:
    """``$JAXPLAN_DATA`` or ``../shared/benchmarks`` beside the checkout."""
    env = os.environ.get("JAXPLAN_DATA")
    return Path(env) if env else ROOT.parent / "shared" / "benchmarks"


def _benchmark_folder(name: str, what: str) -> Path:
    d = data_dir() / name
    if not d.is_dir():
        pytest.skip(f"{what} benchmarks not found at {d} (set JAXPLAN_DATA to the benchmarks folder)")
    return d


@pytest.fixture(scope="session")
def movingai() -> Path:
    return _benchmark_folder("movingai", "MovingAI")


@pytest.fixture(scope="session")
def tsplib() -> Path:
    return _benchmark_folder("tsplib", "TSPLIB")


@pytest.fixture(scope="session")
def ros() -> Path:
    """The ROS map_server maps (Nav2's warehouse with its keep-out and speed masks, a depot)."""
    d = _benchmark_folder("ros", "ROS map")
    if not (d / "warehouse.yaml").is_file():
        pytest.skip(f"ROS maps not found at {d} (set JAXPLAN_DATA to the benchmarks folder)")
    return d


def manifest(folder: Path) -> list[dict[str, str]]:
    lines = (folder / "MANIFEST.tsv").read_text().splitlines()
    head = lines[0].split("\t")
    return [dict(zip(head, line.split("\t"), strict=True)) for line in lines[1:] if line.strip()]


def scenario_pairs(folder: Path) -> list[tuple[Path, Path]]:
    """(map, scen) pairs named by the manifest."""
    rows = manifest(folder)
    maps = {r["file"] for r in rows if r["file"].endswith(".map")}
    out = []
    for r in rows:
        f = r["file"]
        if f.endswith(".scen"):
            m = f[: -len(".scen")] if f.endswith(".map.scen") else f.split("-random-")[0].split("-even-")[0] + ".map"
            assert m in maps, f"no map for {f}"
            out.append((folder / m, folder / f))
    return out


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(0)


@pytest.fixture(scope="module")
def room():
    """A 16x12 map with walls and a dead-end pocket, and start/goal pairs across it."""
    free = np.ones((12, 16), bool)
    free[3, 2:13] = False
    free[3:9, 12] = False
    free[8, 5:12] = False
    free[5:8, 5] = False  # pocket opening up
    starts = np.array([[0, 0], [15, 11], [6, 6]])
    goals = np.array([[14, 10], [1, 5], [0, 11]])
    return jp.grid_from_array(free, resolution=0.5), starts, goals


def unlabelled_marks(ax) -> list[str]:
    """Kinds of mark (type, colour, line style or hatch) drawn on ``ax`` of which no member has a legend label:
    every line, marker and patch must be named (one labelled member names its kind)."""
    from matplotlib.colors import to_hex
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch
    from matplotlib.spines import Spine

    kinds: dict[tuple, bool] = {}
    for a in ax.get_children():
        if isinstance(a, Line2D) and len(a.get_xdata()):
            key = ("line", to_hex(a.get_color()), a.get_linestyle(), a.get_marker())
        elif isinstance(a, Patch) and not isinstance(a, Spine) and a is not ax.patch and a.get_visible():
            key = ("patch", to_hex(a.get_facecolor()), a.get_hatch())
        else:
            continue
        named = not (a.get_label() or "_").startswith("_")
        kinds[key] = kinds.get(key, False) or named
    return [str(k) for k, named in kinds.items() if not named]


# ---------------------------------------------------------------------------------------------
# Small configs: one builder for the experiment, tuning and study configs of the tests


TINY_WAREHOUSE = {"name": "wh", "generator": "warehouse", "seed": 0,
                  "params": {"width": 14, "height": 10, "shelf_length": 4, "shelf_depth": 2, "aisle": 1,
                             "cross_aisle": 2}}
"""A 14x10 generated warehouse: the ``[[maps]]`` entry of most small experiments."""

RANDOM_MAP = {"name": "r", "generator": "random", "seed": 2,
              "params": {"width": 12, "height": 12, "obstacle_ratio": 0.15},
              "scenarios": {"source": "random", "count": 4, "seed": 0, "min_distance": 5.0}}
"""A 12x12 random map with four random scenarios of its own: the ``[[maps]]`` entry of the small tuning configs."""

SMALL_ACO = {"label": "AS", "kind": "plan", "name": "aco", "overrides": {"ants": 4, "iterations": 3,
                                                                         "dead_end": "retreat"}}
"""A small Ant System planner (4 ants, 3 iterations)."""

ASTAR = {"label": "A*", "kind": "plan", "name": "astar"}

_TUNE = {"name": "t", "kind": "aco", "planner": "iaco", "strategy": "issa", "population": 4, "generations": 3,
         "checkpoint_every": 2, "train_count": 2, "train_seeds": 2, "test_seeds": [50, 51],
         "overrides": {"ants": 4, "iterations": 2}, "space": {"beta": [1.0, 10.0]}}

BASE_CONFIGS: dict[str, dict[str, Any]] = {
    "experiment": {"experiment": {"name": "tiny", "seeds": 2, "chunk": 2}, "maps": [TINY_WAREHOUSE],
                   "scenarios": {"source": "random", "count": 2, "seed": 3, "min_distance": 5.0},
                   "planners": [SMALL_ACO]},
    "tune": {"tune": _TUNE, "maps": [RANDOM_MAP]},
    "study": {"tune": {k: v for k, v in _TUNE.items() if k not in ("strategy", "population", "generations",
                                                                  "checkpoint_every")},
              "study": {"methods": ["random", "cma_es"], "tuner_seeds": 2, "budget": 8, "population": 4,
                        "confirm_seeds": [70], "confirm_count": 1},
              "maps": [RANDOM_MAP]},
}
"""The smallest config of each kind that loads (and runs in seconds): `config_toml` starts from these."""


def merged(base: dict[str, Any], changes: dict[str, Any]) -> dict[str, Any]:
    """``base`` with ``changes``: a table (dict) merges key by key into the base's table, any other value (a list of
    tables too) replaces it, None removes the key. ``base`` is not changed."""
    out = copy.deepcopy(base)
    for k, v in changes.items():
        if v is None:
            out.pop(k, None)
        elif isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = merged(out[k], v)
        else:
            out[k] = copy.deepcopy(v)
    return out


def config_toml(kind: str = "experiment", **changes: Any) -> str:
    """The TOML text of a small config of ``kind`` (``"experiment"``, ``"tune"``, ``"study"``): `BASE_CONFIGS`
    with ``changes`` (`merged`), written by the package's TOML writer.

    ``config_toml(experiment={"name": "x"}, planners=[ASTAR, SMALL_ACO], stats={"pairwise": True})``
    """
    return dumps(merged(BASE_CONFIGS[kind], changes))


@pytest.fixture
def write_config(tmp_path: Path) -> Callable[..., Path]:
    """``write_config(kind="experiment", name=None, **changes)``: `config_toml` written to ``tmp_path/NAME``
    (default ``KIND.toml``); returns the file."""

    def write(kind: str = "experiment", name: str | None = None, **changes: Any) -> Path:
        path = tmp_path / (name or f"{kind}.toml")
        path.write_text(config_toml(kind, **changes))
        return path

    return write


@contextlib.contextmanager
def loopback_ray_cluster() -> Iterator[Any]:
    """A head and a second node, one CPU each, on this machine (Ray's loopback test cluster): its `RayExecutor`,
    the cluster shut down afterwards. Skips the test without the ``ray`` extra."""
    ray = pytest.importorskip("ray")
    from ray.cluster_utils import Cluster

    from jaxplan.core.executor import RayExecutor

    c = Cluster(initialize_head=True, head_node_args={"num_cpus": 1})
    c.add_node(num_cpus=1)
    try:
        yield RayExecutor(c.address)
    finally:
        ray.shutdown()
        c.shutdown()
