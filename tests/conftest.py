"""Shared fixtures: the benchmark data folder and small maps."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

import jaxplan as jp

ROOT = Path(__file__).resolve().parents[1]


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
