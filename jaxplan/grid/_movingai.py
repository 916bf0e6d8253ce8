"""MovingAI benchmark formats: ``.map`` grids and ``.scen`` scenario files.

Map format (https://movingai.com/benchmarks/formats.html)::

    type octile
    height H
    width W
    map
    <H rows of W characters>

Passable: ``.`` ``G`` ``S``; blocked: ``@`` ``O`` ``T`` ``W`` (trees, water and
swamp are blocked, as in the optimal lengths of the benchmark scenarios).

Scenario files: a ``version`` line, then tab-separated rows
``bucket  map  width  height  start_x  start_y  goal_x  goal_y  optimal_length``.
The classic Dragon Age files (``*.map.scen``) and the MAPF benchmark files
(``*-random-*.scen``, ``*-even-*.scen``) share this layout.

A header's claimed size is checked against the rows that follow before the grid is allocated (a
header claiming a width of 10^12 is an error, not a `MemoryError`), and the first line, which tells
the format, is never quoted in an error: a config that names the wrong file must not print its content.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from jaxplan.core.io import atomic_write
from jaxplan.grid._gridmap import GridMap, grid_from_array

__all__ = ["load_movingai_map", "save_movingai_map", "parse_map", "load_scenarios", "parse_scenarios", "Scenarios"]

PASSABLE = frozenset(".GS")
BLOCKED = frozenset("@OTW")
_PASSABLE_BYTES = np.frombuffer("".join(sorted(PASSABLE)).encode(), dtype=np.uint8)


def _read_text(path: str | os.PathLike, what: str) -> str:
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"{what} file not found: {p}")
    if p.is_dir():
        raise ValueError(f"{what} path is a directory, not a file: {p}")
    try:
        return p.read_text(encoding="ascii")
    except UnicodeDecodeError as e:
        raise ValueError(f"{p}: not a MovingAI {what} file (non-ASCII byte at offset {e.start})") from None


def _quote(text: str, limit: int = 60) -> str:
    """``repr`` of at most ``limit`` characters of a line (an error shows what is wrong, not a whole file)."""
    return repr(text if len(text) <= limit else text[:limit] + "…")


def _header_int(line: str, key: str, lineno: int, where: str) -> int:
    parts = line.split()
    if len(parts) != 2 or parts[0] != key:
        raise ValueError(f"{where}:{lineno}: expected '{key} <integer>', got {_quote(line)}")
    try:
        v = int(parts[1])
    except ValueError:
        raise ValueError(f"{where}:{lineno}: '{key}' must be an integer, got {_quote(parts[1])}") from None
    if v < 1:
        raise ValueError(f"{where}:{lineno}: '{key}' must be >= 1, got {v}")
    return v


def _lines(text: str) -> list[str]:
    """Lines split at "\\n" only, each less a trailing "\\r" (Windows files).

    Not `str.splitlines`, which also breaks at \\x0b, \\x0c and \\x1c–\\x1e (and \\x85,
    \\u2028, ...): a control character inside a row would split it in two and shift every
    later line number, where it should be reported as what it is.
    """
    return [line[:-1] if line.endswith("\r") else line for line in text.split("\n")]


def parse_map(text: str, resolution: float = 1.0, where: str = "<map>") -> GridMap:
    """Parses the text of a MovingAI ``.map`` file into a `GridMap`.

    Raises:
      ValueError: naming the line of a malformed header, a wrong row count or
        width, or an unknown character.
    """
    lines = _lines(text)
    if len(lines) < 4:
        raise ValueError(f"{where}: a map needs 4 header lines (type, height, width, map), found {len(lines)} lines")
    if lines[0].split() != ["type", "octile"]:
        raise ValueError(f"{where}:1: expected 'type octile': not a MovingAI map file")
    h = _header_int(lines[1], "height", 2, where)
    w = _header_int(lines[2], "width", 3, where)
    if lines[3].strip() != "map":
        raise ValueError(f"{where}:4: expected 'map', got {_quote(lines[3])}")
    rows = lines[4:]
    while rows and rows[-1].strip() == "":
        rows.pop()
    # Characters first: a stray control character is the cause a row count or width would hide.
    for y, row in enumerate(rows):
        unknown = set(row) - PASSABLE - BLOCKED
        if unknown:
            c = sorted(unknown)[0]
            raise ValueError(
                f"{where}:{y + 5}: unknown map character {c!r} at column {row.index(c)} "
                f"(passable: . G S; blocked: @ O T W)"
            )
    if len(rows) != h:
        raise ValueError(f"{where}: header says height {h} but {len(rows)} map rows follow")
    for y, row in enumerate(rows):  # every width before the [h, w] grid is allocated
        if len(row) != w:
            raise ValueError(f"{where}:{y + 5}: row {y} has {len(row)} characters, header says width {w}")
    free = np.zeros((h, w), dtype=bool)
    for y, row in enumerate(rows):
        free[y] = np.isin(np.frombuffer(row.encode("ascii"), dtype=np.uint8), _PASSABLE_BYTES)
    return grid_from_array(free, resolution=resolution)


def load_movingai_map(path: str | os.PathLike, resolution: float = 1.0) -> GridMap:
    """Reads a MovingAI ``.map`` file.

    Args:
      path: the file.
      resolution: metres per cell (MovingAI maps are unitless; 1.0 by default).

    Returns:
      `GridMap` with ``free`` from the characters and default other layers.
    """
    return parse_map(_read_text(path, "map"), resolution=resolution, where=str(path))


def save_movingai_map(grid: GridMap, path: str | os.PathLike) -> None:
    """Writes ``grid.free`` as a MovingAI ``.map`` file (``.`` free, ``@`` blocked).

    Only occupancy is stored: the format has no place for the other layers. The
    file is written to a temporary name and renamed, so a crash leaves no half file.
    """
    free = np.asarray(grid.free, dtype=bool)
    h, w = free.shape
    body = "\n".join("".join("." if c else "@" for c in row) for row in free)
    text = f"type octile\nheight {h}\nwidth {w}\nmap\n{body}\n"
    atomic_write(path, text, encoding="ascii")


@dataclass(frozen=True)
class Scenarios:
    """Rows of a scenario file.

    Attributes:
      starts: ``int64[N, 2]`` start cells ``(x, y)``.
      goals: ``int64[N, 2]`` goal cells ``(x, y)``.
      optimal: ``f64[N]`` published optimal octile lengths (cells).
      buckets: ``int64[N]`` difficulty buckets.
      map_name: the map file named in the rows.
      width, height: map size named in the rows.
    """

    starts: np.ndarray
    goals: np.ndarray
    optimal: np.ndarray
    buckets: np.ndarray
    map_name: str
    width: int
    height: int

    def __len__(self) -> int:
        return len(self.optimal)

    def select(self, mask_or_index: ArrayLike) -> "Scenarios":
        """The subset of rows given by a boolean mask or index array."""
        sel = np.asarray(mask_or_index)
        return replace(self, starts=self.starts[sel], goals=self.goals[sel], optimal=self.optimal[sel],
                       buckets=self.buckets[sel])


def parse_scenarios(text: str, where: str = "<scen>", grid: GridMap | None = None) -> Scenarios:
    """Parses the text of a ``.scen`` file. With ``grid``, rows are checked against it.

    Raises:
      ValueError: naming the line of a bad version line, a row with the wrong number
        of fields or a non-numeric field, a row whose size differs from the others
        or from ``grid``, a cell outside the map, or (with ``grid``) a blocked start
        or goal.
    """
    lines = _lines(text)
    if not lines or not lines[0].strip().lower().startswith("version"):
        raise ValueError(f"{where}:1: expected a 'version' line first: not a MovingAI scenario file")
    vparts = lines[0].split()
    if len(vparts) != 2:
        raise ValueError(f"{where}:1: expected 'version <number>', got {_quote(lines[0])}")
    try:
        float(vparts[1])
    except ValueError:
        raise ValueError(f"{where}:1: version must be a number, got {_quote(vparts[1])}") from None
    rows: list[tuple] = []
    map_name, size = "", (0, 0)
    for lineno, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        f = line.split("\t") if "\t" in line else line.split()
        f = [x.strip() for x in f]
        if len(f) != 9:
            raise ValueError(f"{where}:{lineno}: expected 9 fields (bucket map width height sx sy gx gy optimal), "
                             f"got {len(f)}")
        try:
            bucket, w, h, sx, sy, gx, gy = (int(f[i]) for i in (0, 2, 3, 4, 5, 6, 7))
            opt = float(f[8])
        except ValueError:
            raise ValueError(f"{where}:{lineno}: non-numeric field in {_quote(line, 120)}") from None
        if not math.isfinite(opt) or opt < 0:
            raise ValueError(f"{where}:{lineno}: optimal length must be finite and >= 0, got {_quote(f[8])}")
        if not rows:
            size, map_name = (w, h), f[1]
        elif (w, h) != size:
            raise ValueError(f"{where}:{lineno}: map size {w}x{h} differs from the first row's {size[0]}x{size[1]}")
        for name, (x, y) in (("start", (sx, sy)), ("goal", (gx, gy))):
            if not (0 <= x < w and 0 <= y < h):
                raise ValueError(f"{where}:{lineno}: {name} ({x}, {y}) lies outside the {w}x{h} map")
        rows.append((bucket, sx, sy, gx, gy, opt))
    if not rows:
        raise ValueError(f"{where}: no scenario rows after the version line")
    a = np.array([r[:5] for r in rows], dtype=np.int64)
    scen = Scenarios(
        starts=a[:, 1:3].copy(),
        goals=a[:, 3:5].copy(),
        optimal=np.array([r[5] for r in rows], dtype=np.float64),
        buckets=a[:, 0].copy(),
        map_name=map_name,
        width=size[0],
        height=size[1],
    )
    if grid is not None:
        _check_against(scen, grid, where)
    return scen


def _check_against(scen: Scenarios, grid: GridMap, where: str) -> None:
    H, W = grid.shape
    if (scen.width, scen.height) != (W, H):
        raise ValueError(f"{where}: scenarios are for a {scen.width}x{scen.height} map, the map is {W}x{H}")
    free = np.asarray(grid.free)
    for name, cells in (("start", scen.starts), ("goal", scen.goals)):
        bad = ~free[cells[:, 1], cells[:, 0]]
        if bad.any():
            i = int(np.argmax(bad))
            raise ValueError(f"{where}: row {i + 1}: {name} {tuple(cells[i].tolist())} is on a blocked cell")


def load_scenarios(path: str | os.PathLike, grid: GridMap | None = None) -> Scenarios:
    """Reads a MovingAI ``.scen`` file (classic Dragon Age or MAPF benchmark layout).

    Args:
      path: the file.
      grid: optional map to check the rows against (size, free start and goal cells).

    Returns:
      `Scenarios` with ``starts [N, 2]``, ``goals [N, 2]``, ``optimal [N]``, ``buckets [N]``.
    """
    return parse_scenarios(_read_text(path, "scenario"), where=str(path), grid=grid)
