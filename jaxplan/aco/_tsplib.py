"""TSPLIB reading: ``.tsp`` problems, ``.opt.tour`` tours, tour lengths (host-side numpy).

Distances follow the TSPLIB 95 specification (Reinelt, "TSPLIB 95", section 2):

* ``EUC_2D``: ``nint(sqrt(dx² + dy²))``, ``nint(x) = (int)(x + 0.5)``;
* ``CEIL_2D``: ``ceil(sqrt(dx² + dy²))``;
* ``ATT`` (pseudo-Euclidean): ``r = sqrt((dx² + dy²) / 10)``, ``t = nint(r)``, ``d = t + 1`` if
  ``t < r`` else ``t``;
* ``GEO``: coordinates are ``DDD.MM`` (degrees.minutes, x latitude, y longitude), converted with
  ``PI = 3.141592`` as ``PI · (deg + 5·min/3) / 180`` where ``deg`` is the integer part
  (truncation, as in the TSPLIB FAQ's code; the specification's ``nint`` there is a known
  misprint), and ``d = (int)(RRR · acos(½((1 + q1)·q2 − (1 − q1)·q3)) + 1)``, ``RRR = 6378.388``;
* ``EXPLICIT``: an ``EDGE_WEIGHT_SECTION`` in ``FULL_MATRIX``, ``UPPER_ROW``, ``LOWER_ROW``,
  ``UPPER_DIAG_ROW`` or ``LOWER_DIAG_ROW`` order (and the column-wise orders, which for a
  symmetric matrix are the row-wise ones of the other triangle).

jaxplan's own ``"EUCLIDEAN"`` metric is the unrounded Euclidean distance. The diagonal is 0
whatever the file says (TSPLIB matrices often carry a large sentinel there; a tour never uses it).

Sizes are checked against content before anything is allocated: a ``DIMENSION`` the coordinate or
matrix section does not hold is an error (a 200-byte file claiming a billion cities must not ask for
gigabytes), and the ``[n, n]`` distance matrix of a file that does hold n cities goes through the
memory guard (`jaxplan.scale.check_memory`). Errors quote no line that is not recognisably TSPLIB
(a config that names the wrong file must not print that file's content).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from jaxplan.scale import MemoryLimitError, memory_limit

__all__ = ["TSPProblem", "load_tsplib", "load_tour", "tour_length", "tsp_distances", "METRICS"]

# Metrics computed from coordinates; "EUCLIDEAN" is jaxplan's (unrounded), the rest are TSPLIB's.
METRICS = ("EUC_2D", "CEIL_2D", "ATT", "GEO", "EUCLIDEAN")
_EXPLICIT_FORMATS = {  # symmetric matrices: a column-wise order is the row-wise order of the other triangle
    "FULL_MATRIX": "FULL_MATRIX",
    "UPPER_ROW": "UPPER_ROW", "LOWER_COL": "UPPER_ROW",
    "LOWER_ROW": "LOWER_ROW", "UPPER_COL": "LOWER_ROW",
    "UPPER_DIAG_ROW": "UPPER_DIAG_ROW", "LOWER_DIAG_COL": "UPPER_DIAG_ROW",
    "LOWER_DIAG_ROW": "LOWER_DIAG_ROW", "UPPER_DIAG_COL": "LOWER_DIAG_ROW",
}
_HEADER_KEYS = ("NAME", "TYPE", "COMMENT", "DIMENSION", "CAPACITY", "EDGE_WEIGHT_TYPE", "EDGE_WEIGHT_FORMAT",
                "EDGE_DATA_FORMAT", "NODE_COORD_TYPE", "DISPLAY_DATA_TYPE")
_SECTIONS = ("NODE_COORD_SECTION", "EDGE_WEIGHT_SECTION", "DISPLAY_DATA_SECTION", "TOUR_SECTION",
             "FIXED_EDGES_SECTION", "DEPOT_SECTION", "DEMAND_SECTION", "EDGE_DATA_SECTION")
_GEO_PI, _GEO_RRR = 3.141592, 6378.388
_MATRIX_BYTES = 40  # per entry of an [n, n] distance matrix: the f64 result and tsp_distances' temporaries


class TSPProblem(NamedTuple):
    """A symmetric TSP instance.

    Attributes:
      name: the file's ``NAME`` (the file stem when absent).
      coords: ``f64[n, 2]`` node coordinates (display coordinates for an explicit matrix
        with a ``DISPLAY_DATA_SECTION``), or ``None`` when the file has none.
      dist: ``f64[n, n]`` symmetric distances, zero diagonal; integer-valued for the rounding
        metrics (``EUC_2D``, ``CEIL_2D``, ``ATT``, ``GEO``) and explicit integer matrices.
      metric: ``"EUC_2D"``, ``"CEIL_2D"``, ``"ATT"``, ``"GEO"``, ``"EUCLIDEAN"`` or ``"EXPLICIT"``.
      n: number of cities.
    """

    name: str
    coords: np.ndarray | None
    dist: np.ndarray
    metric: str
    n: int


def tsp_distances(coords: ArrayLike, metric: str) -> np.ndarray:
    """``f64[n, n]`` distances between ``coords [n, 2]`` under a TSPLIB ``metric`` (see `METRICS`)."""
    xy = np.asarray(coords, np.float64)
    m = _check_metric(metric)
    if m == "GEO":
        deg = np.trunc(xy)  # integer part of DDD.MM (toward zero, so southern/western minutes keep their sign)
        rad = _GEO_PI * (deg + 5.0 * (xy - deg) / 3.0) / 180.0
        lat, lon = rad[:, 0], rad[:, 1]
        q1 = np.cos(lon[:, None] - lon[None, :])
        q2 = np.cos(lat[:, None] - lat[None, :])
        q3 = np.cos(lat[:, None] + lat[None, :])
        # Clipped: rounding can push the cosine a hair past ±1 for (nearly) equal points.
        d = np.floor(_GEO_RRR * np.arccos(np.clip(0.5 * ((1.0 + q1) * q2 - (1.0 - q1) * q3), -1.0, 1.0)) + 1.0)
    else:
        diff = xy[:, None, :] - xy[None, :, :]
        sq = np.sum(diff * diff, axis=-1)
        if m == "EUC_2D":
            d = np.floor(np.sqrt(sq) + 0.5)
        elif m == "CEIL_2D":
            d = np.ceil(np.sqrt(sq))
        elif m == "ATT":
            r = np.sqrt(sq / 10.0)
            t = np.floor(r + 0.5)
            d = np.where(t < r, t + 1.0, t)
        else:  # EUCLIDEAN
            d = np.sqrt(sq)
    np.fill_diagonal(d, 0.0)
    return d


def _check_metric(metric: str) -> str:
    m = str(metric).upper()
    if m not in METRICS:
        raise ValueError(f"unknown metric {metric!r}; accepted: None (trust the file's header) or one of {METRICS}")
    return m


def _read_lines(path: str | Path, what: str) -> tuple[Path, list[str]]:
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"{what} file not found: {p}")
    return p, p.read_text(errors="replace").splitlines()


def _parse(p: Path, lines: list[str]) -> tuple[dict[str, tuple[int, str]], dict[str, tuple[int, list]]]:
    """Splits a TSPLIB file into header ``{KEY: (line, value)}`` and sections
    ``{NAME: (line, [(line, tokens), ...])}`` (1-based line numbers). A section's data are the
    lines after its keyword up to the next keyword line (one starting with a letter)."""
    header: dict[str, tuple[int, str]] = {}
    sections: dict[str, tuple[int, list]] = {}
    current: list | None = None
    for i, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line:
            continue
        if not line[0].isalpha():
            if current is None:
                raise ValueError(f"{p.name} line {i}: data outside a section (is this a TSPLIB file?)")
            current.append((i, line.split()))
            continue
        current = None
        word = line.split(":", 1)[0].split()[0].upper()
        if word == "EOF":
            break
        if word.endswith("_SECTION"):
            if word not in _SECTIONS:
                raise ValueError(f"{p.name} line {i}: unknown section {word[:40]!r}")
            if word in sections:
                raise ValueError(f"{p.name} line {i}: section {word} appears twice")
            current = []
            sections[word] = (i, current)
            continue
        if ":" in line:
            key, value = line.split(":", 1)
        else:  # "KEY value" without a colon, seen in some hand-edited files
            key, value = (line.split(None, 1) + [""])[:2]
        key = key.strip().upper()
        if key not in _HEADER_KEYS:
            if ":" in line:
                continue  # unknown specification fields (e.g. BEST_KNOWN) are informational
            raise ValueError(f"{p.name} line {i}: unrecognised line: neither a TSPLIB header key nor a section "
                             f"(is this a TSPLIB file?)")
        header[key] = (i, value.strip())
    return header, sections


def _dimension(p: Path, header: dict) -> int:
    if "DIMENSION" not in header:
        raise ValueError(f"{p.name}: missing DIMENSION in the header")
    line, value = header["DIMENSION"]
    try:
        n = int(value)
    except ValueError:
        raise ValueError(f"{p.name} line {line}: DIMENSION must be a positive integer, got {value!r}") from None
    if n < 1:
        raise ValueError(f"{p.name} line {line}: DIMENSION must be a positive integer, got {value!r}")
    return n


def _number(p: Path, line: int, token: str) -> float:
    try:
        v = float(token)
    except ValueError:
        raise ValueError(f"{p.name} line {line}: {token[:40]!r} is not a number") from None
    if not math.isfinite(v):
        raise ValueError(f"{p.name} line {line}: {token[:40]!r} is not a finite number")
    return v


def _check_matrix(p: Path, n: int) -> None:
    """The memory guard for an ``[n, n]`` distance matrix, naming the most cities that fit."""
    need, limit = _MATRIX_BYTES * n * n, memory_limit()
    if need > limit:
        raise MemoryLimitError(
            f"{p.name}: the distance matrix of {n} cities needs about {need / 2**30:.2f} GiB, above the limit of "
            f"{limit / 2**30:.2f} GiB; at most {math.isqrt(limit // _MATRIX_BYTES)} cities fit. Use a smaller "
            f"instance, or raise the limit with JAXPLAN_MEMORY_LIMIT (e.g. 16G)")


def _coordinates(p: Path, name: str, section: tuple[int, list], n: int) -> np.ndarray:
    """``f64[n, 2]`` from ``index x y`` lines (any order, each index 1..n once); nothing of size n is allocated
    before the section is known to hold n nodes."""
    start, rows = section
    xy: dict[int, tuple[float, float]] = {}
    for line, tokens in rows:
        if len(tokens) != 3:
            raise ValueError(f"{p.name} line {line}: {name} expects 'index x y' (3 numbers), got {len(tokens)}: "
                             f"{' '.join(tokens)[:60]!r}")
        try:
            k = int(tokens[0])
        except ValueError:
            raise ValueError(f"{p.name} line {line}: node index {tokens[0][:40]!r} is not an integer") from None
        if not 1 <= k <= n:
            raise ValueError(f"{p.name} line {line}: node index {k} outside 1..{n} (DIMENSION)")
        if k in xy:
            raise ValueError(f"{p.name} line {line}: node {k} listed twice in {name}")
        xy[k] = (_number(p, line, tokens[1]), _number(p, line, tokens[2]))
    if len(xy) < n:
        missing = next(k for k in range(1, n + 1) if k not in xy)  # at most len(xy) + 1 steps
        raise ValueError(f"{p.name} line {start}: {name} has {len(xy)} of {n} nodes (DIMENSION); "
                         f"missing node {missing}")
    return np.asarray([xy[k] for k in range(1, n + 1)], np.float64).reshape(n, 2)


def _explicit(p: Path, header: dict, sections: dict, n: int) -> np.ndarray:
    if "EDGE_WEIGHT_FORMAT" not in header:
        raise ValueError(f"{p.name}: EDGE_WEIGHT_TYPE EXPLICIT needs an EDGE_WEIGHT_FORMAT")
    fline, fmt_raw = header["EDGE_WEIGHT_FORMAT"]
    fmt = _EXPLICIT_FORMATS.get(fmt_raw.upper())
    if fmt is None:
        raise ValueError(f"{p.name} line {fline}: unsupported EDGE_WEIGHT_FORMAT {fmt_raw!r}; "
                         f"supported: {tuple(_EXPLICIT_FORMATS)}")
    if "EDGE_WEIGHT_SECTION" not in sections:
        raise ValueError(f"{p.name}: EDGE_WEIGHT_TYPE EXPLICIT needs an EDGE_WEIGHT_SECTION")
    start, rows = sections["EDGE_WEIGHT_SECTION"]
    # Entries run across lines freely; remember each one's line for error messages.
    values = [(line, t) for line, tokens in rows for t in tokens]
    # The entry count from DIMENSION, checked against the section before any [n, n] array exists.
    needed = {"FULL_MATRIX": n * n, "UPPER_ROW": n * (n - 1) // 2, "LOWER_ROW": n * (n - 1) // 2,
              "UPPER_DIAG_ROW": n * (n + 1) // 2, "LOWER_DIAG_ROW": n * (n + 1) // 2}[fmt]
    if len(values) != needed:
        last = values[-1][0] if values else start
        raise ValueError(f"{p.name} line {last}: EDGE_WEIGHT_SECTION ({fmt_raw}, DIMENSION {n}) needs {needed} "
                         f"entries, found {len(values)}")
    _check_matrix(p, n)
    if fmt == "FULL_MATRIX":
        ii, jj = np.indices((n, n)).reshape(2, -1)
    else:
        ii, jj = np.indices((n, n)).reshape(2, -1)
        keep = {"UPPER_ROW": jj > ii, "LOWER_ROW": jj < ii, "UPPER_DIAG_ROW": jj >= ii, "LOWER_DIAG_ROW": jj <= ii}[fmt]
        ii, jj = ii[keep], jj[keep]  # row-major order of the listed triangle
    w = np.array([_number(p, line, t) for line, t in values], np.float64)
    bad = np.flatnonzero(w < 0)
    if bad.size:
        raise ValueError(f"{p.name} line {values[bad[0]][0]}: negative edge weight {values[bad[0]][1]}")
    d = np.zeros((n, n))
    d[ii, jj] = w
    if fmt == "FULL_MATRIX":
        off = ~np.eye(n, dtype=bool)
        if not np.array_equal(d[off], d.T[off]):
            i, j = np.argwhere((d != d.T) & off)[0]
            raise ValueError(f"{p.name}: FULL_MATRIX is not symmetric (d[{i + 1},{j + 1}] = {d[i, j]:g} but "
                             f"d[{j + 1},{i + 1}] = {d[j, i]:g}); asymmetric TSPs are not supported")
    else:
        d[jj, ii] = w
    np.fill_diagonal(d, 0.0)
    return d


def load_tsplib(path: str | Path, metric: str | None = None) -> TSPProblem:
    """Reads a symmetric TSPLIB ``.tsp`` file.

    Args:
      path: the file.
      metric: ``None`` to use the file's ``EDGE_WEIGHT_TYPE``, or one of ``"EUC_2D"``,
        ``"CEIL_2D"``, ``"ATT"``, ``"GEO"``, ``"EUCLIDEAN"`` (unrounded) to compute the
        distances from the coordinates instead (files in circulation carry wrong headers).
        Impossible for explicit matrices.

    Returns:
      `TSPProblem` with ``dist f64[n, n]`` and ``coords f64[n, 2]`` (or None).

    Raises:
      FileNotFoundError: no such file.
      ValueError: naming the file, the line and the problem (missing DIMENSION, a coordinate
        line without exactly ``index x y``, an unknown EDGE_WEIGHT_TYPE or format, a wrong
        number of matrix entries, a negative weight, an impossible metric override, ...).
    """
    p, lines = _read_lines(path, "TSPLIB")
    header, sections = _parse(p, lines)
    name = header.get("NAME", (0, p.stem))[1] or p.stem
    if "TYPE" in header:
        tline, kind = header["TYPE"]
        first = kind.split()[0].upper() if kind.split() else ""
        if first == "TOUR":
            raise ValueError(f"{p.name} line {tline}: TYPE TOUR is a tour file; read it with load_tour")
        if first != "TSP":
            raise ValueError(f"{p.name} line {tline}: TYPE {kind!r} is not supported (only symmetric TSP)")
    n = _dimension(p, header)
    if "EDGE_WEIGHT_TYPE" not in header:
        raise ValueError(f"{p.name}: missing EDGE_WEIGHT_TYPE in the header")
    wline, wtype = header["EDGE_WEIGHT_TYPE"]
    wtype = wtype.upper()
    if wtype not in ("EXPLICIT",) + METRICS[:-1]:
        raise ValueError(f"{p.name} line {wline}: unknown EDGE_WEIGHT_TYPE {wtype!r}; supported: "
                         f"{('EXPLICIT',) + METRICS[:-1]}")
    if "NODE_COORD_TYPE" in header and header["NODE_COORD_TYPE"][1].upper() not in ("TWOD_COORDS", "NO_COORDS"):
        cline, ctype = header["NODE_COORD_TYPE"]
        raise ValueError(f"{p.name} line {cline}: NODE_COORD_TYPE {ctype!r} is not supported (2-D coordinates only)")
    coords = None
    if "NODE_COORD_SECTION" in sections:
        coords = _coordinates(p, "NODE_COORD_SECTION", sections["NODE_COORD_SECTION"], n)
    elif "DISPLAY_DATA_SECTION" in sections:
        coords = _coordinates(p, "DISPLAY_DATA_SECTION", sections["DISPLAY_DATA_SECTION"], n)
    if wtype == "EXPLICIT":
        if metric is not None:
            _check_metric(metric)
            raise ValueError(f"{p.name} line {wline}: metric override {metric!r} is impossible: the file gives an "
                             f"explicit EDGE_WEIGHT_SECTION, not coordinates to measure")
        return TSPProblem(name, coords, _explicit(p, header, sections, n), "EXPLICIT", n)
    if "NODE_COORD_SECTION" not in sections:
        raise ValueError(f"{p.name}: EDGE_WEIGHT_TYPE {wtype} needs a NODE_COORD_SECTION")
    m = wtype if metric is None else _check_metric(metric)
    _check_matrix(p, n)
    assert coords is not None  # read from the NODE_COORD_SECTION above
    return TSPProblem(name, coords, tsp_distances(coords, m), m, n)


def load_tour(path: str | Path) -> np.ndarray:
    """Reads a TSPLIB tour (``.opt.tour``): the first tour of its ``TOUR_SECTION``.

    Returns:
      ``int64[n]`` city order, 0-based (the file's nodes minus one).

    Raises:
      FileNotFoundError: the file does not exist.
      ValueError: naming the line, when the section is missing, holds a non-integer, or the tour is not a
        permutation of 1..n (n = DIMENSION when given).
    """
    p, lines = _read_lines(path, "tour")
    header, sections = _parse(p, lines)
    if "TOUR_SECTION" not in sections:
        raise ValueError(f"{p.name}: no TOUR_SECTION")
    start, rows = sections["TOUR_SECTION"]
    nodes: list[tuple[int, int]] = []  # (line, node)
    for line, tokens in rows:
        for t in tokens:
            try:
                v = int(t)
            except ValueError:
                raise ValueError(f"{p.name} line {line}: tour entry {t[:40]!r} is not an integer") from None
            if v == -1:
                break
            nodes.append((line, v))
        else:
            continue
        break  # a -1 ends the (first) tour
    if not nodes:
        raise ValueError(f"{p.name} line {start}: TOUR_SECTION is empty")
    n = _dimension(p, header) if "DIMENSION" in header else len(nodes)
    seen: set[int] = set()
    for line, v in nodes:
        if not 1 <= v <= n or v in seen:
            why = f"node {v} outside 1..{n}" if not 1 <= v <= n else f"node {v} appears twice"
            raise ValueError(f"{p.name} line {line}: the tour is not a permutation of 1..{n}: {why}")
        seen.add(v)
    if len(nodes) != n:
        raise ValueError(f"{p.name} line {start}: the tour is not a permutation of 1..{n}: "
                         f"TOUR_SECTION lists {len(nodes)} nodes")
    return np.asarray([v for _, v in nodes], np.int64) - 1


def tour_length(problem: TSPProblem, tour: ArrayLike) -> float:
    """Length of the closed tour ``tour`` (``int[n]``, 0-based city order) in ``problem``'s metric.

    Raises:
      ValueError: ``tour`` is not a permutation of ``0..n-1``.
    """
    t = np.asarray(tour)
    n = problem.dist.shape[0]
    if t.ndim != 1 or t.shape[0] != n or not np.issubdtype(t.dtype, np.integer) \
            or not np.array_equal(np.sort(t), np.arange(n)):
        raise ValueError(f"tour must be a permutation of 0..{n - 1} (int[{n}]), got shape {t.shape}, dtype {t.dtype}")
    return float(problem.dist[t, np.roll(t, -1)].sum())
