"""ROS ``map_server`` maps: a YAML file naming an image (PGM or PNG) and how to read it; Nav2 filter masks.

A map (ROS 1 ``map_server`` and Nav2 ``nav2_map_server`` read the same files)::

    image: warehouse.pgm          # relative to the YAML file's folder
    mode: trinary                 # trinary (default) or scale; raw is refused
    resolution: 0.03              # metres per cell
    origin: [-15.1, -25, 0]       # (x, y, yaw) of the lower-left corner of the image, in metres
    negate: 0
    occupied_thresh: 0.65
    free_thresh: 0.1

Each pixel's occupancy is ``occ = 1 - shade`` (``shade = value / maxval``, the mean of the colour
channels for a colour PNG; ``occ = shade`` with ``negate: 1``). As Nav2's ``map_io`` does: a cell is
occupied if ``occ > occupied_thresh``, free if ``occ < free_thresh`` and unknown otherwise (``trinary``);
``scale`` keeps the value in between as ``rint(100 (occ - free) / (occupied - free))`` and makes
transparent pixels unknown. In a `GridMap`, occupied cells are blocked, unknown cells are blocked
unless ``unknown="free"``, and ``scale``'s in-between cells are free (Nav2's static layer makes them a
cost, not an obstacle).

Rows: the image's top row is the map's highest ``y``. The loaded grid's cell ``(x, y)`` is ROS's
``OccupancyGrid`` cell — ``y`` counts rows from the bottom of the image, as ``map_server`` stores them —
so that world coordinates are ``origin + (cell + 0.5) * resolution`` with ``y`` up, exactly as in ROS.
(Draw such a grid with ``imshow(..., origin="lower")`` to see the image upright.) A non-zero origin yaw
is refused: ROS itself mostly ignores it, and ignoring it here would misplace every world coordinate.

Nav2 costmap filter masks are maps of the same kind:

* keep-out (``keepout=``): cells the mask marks occupied become blocked;
* speed (``speed=``): a mask value ``m`` in 0..100 gives the speed limit ``base + multiplier · m`` —
  percent of the robot's top speed with ``speed_filter=(1, base, multiplier)`` (Nav2's type 1, default
  ``(1, 100.0, -1.0)`` as in Nav2's tutorial), or metres per second with type 2 (then give
  ``top_speed=``, the robot's top speed, to turn it into a fraction). As in Nav2's speed filter, ``m = 0``,
  unknown cells and limits outside ``(0, 100] %`` mean "no limit". The result is `GridMap.speed_limit`.

Masks must have the map's size, resolution and origin. Sizes are checked against the bytes present before
anything is allocated; every error is one line naming the file and the problem, and never quotes a file
that is not of the expected format.
"""

from __future__ import annotations

import math
import os
import re
from pathlib import Path
from typing import Any

import numpy as np

from jaxplan.core.io import atomic_write
from jaxplan.grid._gridmap import GridMap, grid_from_array

__all__ = ["RosMap", "load_ros_map", "read_ros_yaml", "read_pgm", "save_ros_map", "occupancy_values"]

MAX_YAML_BYTES = 1 << 16
"""A map's YAML is a few lines; a larger file is not one (refused before it is read)."""

MAX_CELLS = 1 << 31
"""At most 2^31 cells (an image of 46 341 × 46 341), checked before any array is allocated."""

UNKNOWN = -1
OCCUPIED = 100
FREE = 0
_REQUIRED = ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh")
_KEYS = frozenset(_REQUIRED) | {"mode"}
_MODES = ("trinary", "scale")


class RosMap(dict):
    """The parsed YAML of a ROS map: ``image`` (an absolute `Path`), ``mode``, ``resolution``,
    ``origin`` (x, y, yaw), ``negate`` (bool), ``occupied_thresh``, ``free_thresh``."""


def _fail(where: Any, msg: str) -> ValueError:
    return ValueError(f"{where}: {msg}")


def _scalar(text: str) -> str:
    t = text.strip()
    if len(t) >= 2 and t[0] == t[-1] and t[0] in "'\"":
        return t[1:-1]
    return t


def _number(where: str, key: str, text: str) -> float:
    try:
        v = float(_scalar(text))
    except ValueError:
        raise _fail(where, f"'{key}' must be a number, got {_scalar(text)[:40]!r}") from None
    if not math.isfinite(v):
        raise _fail(where, f"'{key}' must be finite, got {v}")
    return v


def read_ros_yaml(path: str | os.PathLike) -> RosMap:
    """Reads and checks the YAML of a ROS map (the flat ``key: value`` subset map_server files use).

    Raises:
      FileNotFoundError: the file is missing.
      ValueError: ``path:line: ...`` for a line that is not ``key: value``, an unknown or repeated key,
        a bad value; ``path: ...`` for a missing key, thresholds out of order, a non-zero yaw or an
        unsupported mode.
    """
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"ROS map YAML file not found: {p}")
    if p.is_dir():
        raise _fail(p, "is a directory, not a ROS map YAML file")
    size = p.stat().st_size
    if size > MAX_YAML_BYTES:
        raise _fail(p, f"{size} bytes: too large for a ROS map YAML file (at most {MAX_YAML_BYTES})")
    raw = p.read_bytes()
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise _fail(p, f"not a ROS map YAML file (not UTF-8 text: byte offset {e.start})") from None
    values: dict[str, tuple[str, int]] = {}
    for lineno, line in enumerate(text.split("\n"), start=1):
        body = line.split("#", 1)[0].rstrip("\r").rstrip()
        if not body.strip() or body.strip() in ("---", "..."):
            continue
        m = re.fullmatch(r"\s*([A-Za-z_][A-Za-z0-9_]*)\s*:\s*(.*)", body)
        if m is None:
            raise _fail(f"{p}:{lineno}", "expected 'key: value': not a ROS map YAML file")
        key, value = m.group(1), m.group(2)
        if key not in _KEYS:
            raise _fail(f"{p}:{lineno}", f"unknown key {key!r} (a ROS map has {', '.join(sorted(_KEYS))})")
        if key in values:
            raise _fail(f"{p}:{lineno}", f"key {key!r} given twice (first on line {values[key][1]})")
        values[key] = (value, lineno)
    missing = [k for k in _REQUIRED if k not in values]
    if missing:
        raise _fail(p, f"missing key{'s' if len(missing) > 1 else ''} {', '.join(missing)} "
                       f"(a ROS map needs {', '.join(_REQUIRED)})")
    out = RosMap()
    where = {k: f"{p}:{ln}" for k, (_, ln) in values.items()}
    image = _scalar(values["image"][0])
    if not image:
        raise _fail(where["image"], "'image' is empty")
    out["image"] = (p.parent / image) if not Path(image).is_absolute() else Path(image)
    mode = _scalar(values["mode"][0]) if "mode" in values else "trinary"
    if mode not in _MODES:
        raise _fail(where.get("mode", p), f"mode {mode[:40]!r} is not supported (use trinary or scale)")
    out["mode"] = mode
    res = _number(where["resolution"], "resolution", values["resolution"][0])
    if res <= 0:
        raise _fail(where["resolution"], f"'resolution' must be > 0 metres per cell, got {res}")
    out["resolution"] = res
    o = values["origin"][0].strip()
    if not (o.startswith("[") and o.endswith("]")):
        raise _fail(where["origin"], "'origin' must be a list [x, y, yaw]")
    parts = [x for x in o[1:-1].split(",")]
    if len(parts) != 3:
        raise _fail(where["origin"], f"'origin' must have 3 entries [x, y, yaw], got {len(parts)}")
    ox, oy, yaw = (_number(where["origin"], "origin", x) for x in parts)
    if yaw != 0.0:
        raise _fail(where["origin"], f"origin yaw {yaw} is not supported (only 0: an unrotated map)")
    out["origin"] = (ox, oy, yaw)
    neg = _scalar(values["negate"][0])
    if neg.lower() in ("0", "false"):
        out["negate"] = False
    elif neg.lower() in ("1", "true"):
        out["negate"] = True
    else:
        raise _fail(where["negate"], f"'negate' must be 0 or 1, got {neg[:40]!r}")
    occ = _number(where["occupied_thresh"], "occupied_thresh", values["occupied_thresh"][0])
    fre = _number(where["free_thresh"], "free_thresh", values["free_thresh"][0])
    if not (0.0 <= fre <= 1.0 and 0.0 <= occ <= 1.0):
        raise _fail(p, f"thresholds must lie in [0, 1], got free_thresh {fre} and occupied_thresh {occ}")
    if fre > occ or (mode == "scale" and fre == occ):
        raise _fail(p, f"free_thresh {fre} must be below occupied_thresh {occ}")
    out["occupied_thresh"], out["free_thresh"] = occ, fre
    return out


# ---------------------------------------------------------------------------------------------
# Images


def _pgm_header(data: bytes, where: Any) -> tuple[str, int, int, int, int]:
    """``(magic, width, height, maxval, offset of the first pixel)`` of a PGM file's bytes."""
    magic = data[:2]
    if magic not in (b"P2", b"P5"):
        raise _fail(where, "not a PGM image (expected P2 or P5 at the start)")
    pos, tokens = 2, list[int]()
    n = len(data)
    while len(tokens) < 3:
        while pos < n and data[pos:pos + 1] in (b" ", b"\t", b"\n", b"\r", b"\x0b", b"\x0c"):
            pos += 1
        if pos < n and data[pos:pos + 1] == b"#":
            end = data.find(b"\n", pos)
            pos = n if end < 0 else end + 1
            continue
        start = pos
        while pos < n and data[pos:pos + 1].isdigit():
            pos += 1
        if start == pos:
            what = ("width", "height", "maxval")[len(tokens)]
            raise _fail(where, f"PGM header: expected the {what} (a number) at byte {start}")
        if pos - start > 12:
            raise _fail(where, f"PGM header: a number of {pos - start} digits at byte {start}")
        tokens.append(int(data[start:pos]))
    w, h, maxval = tokens
    if w < 1 or h < 1:
        raise _fail(where, f"PGM header: size {w}x{h} must be at least 1x1")
    if not 1 <= maxval <= 65535:
        raise _fail(where, f"PGM header: maxval {maxval} must be in 1..65535")
    if pos >= n or data[pos:pos + 1] not in (b" ", b"\t", b"\n", b"\r"):
        raise _fail(where, "PGM header: expected one whitespace byte after maxval")
    return magic.decode(), w, h, maxval, pos + 1


def read_pgm(path: str | os.PathLike) -> tuple[np.ndarray, int]:
    """Reads a PGM image (binary P5 or ASCII P2, 8 or 16 bit): ``(uint16[H, W] values, maxval)``, row 0 at the
    top of the image. Sizes are checked against the bytes present before the image is allocated."""
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"PGM image not found: {p}")
    if p.is_dir():
        raise _fail(p, "is a directory, not a PGM image")
    data = p.read_bytes()
    magic, w, h, maxval, off = _pgm_header(data, p)
    if w * h > MAX_CELLS:
        raise _fail(p, f"PGM header claims {w}x{h} = {w * h} pixels, more than the {MAX_CELLS} a map may have")
    if magic == "P5":
        depth = 1 if maxval < 256 else 2
        need = w * h * depth
        have = len(data) - off
        if have < need:
            raise _fail(p, f"PGM header claims {w}x{h} pixels ({need} bytes) but {have} bytes follow")
        dtype = np.uint8 if depth == 1 else np.dtype(">u2")
        values = np.frombuffer(data, dtype=dtype, count=w * h, offset=off).astype(np.uint16)
    else:
        body = data[off:]
        if len(body) + 1 < 2 * w * h - 1:  # each value takes a digit and all but the last a separator
            raise _fail(p, f"PGM header claims {w}x{h} pixels but only {len(body)} bytes of values follow")
        body = re.sub(rb"#[^\n]*", b" ", body)
        words = body.split()
        if len(words) < w * h:
            raise _fail(p, f"PGM header claims {w}x{h} = {w * h} pixels but {len(words)} values follow")
        bad = next((i for i, x in enumerate(words[:w * h]) if not x.isdigit() or len(x) > 5), None)
        if bad is not None:
            raise _fail(p, f"P2 pixel {bad} (row {bad // w}, column {bad % w}) is not a number in 0..{maxval}")
        values = np.array(words[:w * h], dtype=np.int64)
        if values.max(initial=0) > maxval:
            i = int(np.argmax(values > maxval))
            raise _fail(p, f"P2 pixel {i} (row {i // w}, column {i % w}) is {values[i]}, above maxval {maxval}")
        values = values.astype(np.uint16)
    if magic == "P5" and maxval < 65535 and values.max(initial=0) > maxval:
        i = int(np.argmax(values > maxval))
        raise _fail(p, f"pixel {i} (row {i // w}, column {i % w}) is {values[i]}, above maxval {maxval}")
    return values.reshape(h, w), maxval


def _read_png(path: Path) -> tuple[np.ndarray, np.ndarray | None]:
    """``(shade f64[H, W] in [0, 1], opaque bool[H, W] or None)`` of a PNG, read with Pillow (matplotlib's)."""
    try:
        from PIL import Image
    except ImportError:  # pragma: no cover - matplotlib requires Pillow
        raise _fail(path, "reading a PNG map needs Pillow (pip install pillow), or convert it to PGM") from None
    if not path.exists():
        raise FileNotFoundError(f"PNG image not found: {path}")
    if path.is_dir():
        raise _fail(path, "is a directory, not a PNG image")
    try:
        with Image.open(path) as im:
            if im.format != "PNG":
                raise _fail(path, f"not a PNG image (Pillow reads it as {im.format})")
            w, h = im.size
            if w * h > MAX_CELLS:
                raise _fail(path, f"PNG claims {w}x{h} = {w * h} pixels, more than the {MAX_CELLS} a map may have")
            mode = im.mode
            if mode.startswith("I"):  # 16-bit grey (Pillow's I;16 variants, or I for a 16-bit PNG)
                return np.asarray(im, dtype=np.float64) / 65535.0, None
            if mode in ("P", "PA"):
                a = np.asarray(im.convert("RGBA"))
                mode = "RGBA"
            else:
                a = np.asarray(im)
    except (OSError, SyntaxError, Image.DecompressionBombError) as e:
        raise _fail(path, f"not a readable PNG image ({type(e).__name__})") from None
    if a.ndim == 2:
        return a.astype(np.float64) / (1.0 if mode == "1" else 255.0), None
    colour = a[..., :3] if a.shape[-1] >= 3 else a[..., :1]
    alpha = a[..., -1] == 255 if a.shape[-1] in (2, 4) else None
    return colour.astype(np.float64).mean(axis=-1) / 255.0, alpha


def occupancy_values(meta: RosMap, where: Any = None) -> np.ndarray:
    """``int8[H, W]`` the map's cells as ROS ``OccupancyGrid`` values (0 free, 100 occupied, -1 unknown, 1..99
    in ``scale`` mode), row 0 = the image's bottom row (ROS's cell order)."""
    img = Path(meta["image"])
    where = where if where is not None else img
    suffix = img.suffix.lower()
    if suffix == ".pgm":
        values, maxval = read_pgm(img)
        shade, opaque = values.astype(np.float64) / float(maxval), None
    elif suffix == ".png":
        shade, opaque = _read_png(img)
    else:
        raise _fail(where, f"image {img.name!r}: only PGM (P2, P5) and PNG images are read")
    occ = shade if meta["negate"] else 1.0 - shade
    hi, lo = float(meta["occupied_thresh"]), float(meta["free_thresh"])
    out = np.full(occ.shape, UNKNOWN, np.int8)
    if meta["mode"] == "trinary":
        out[occ > hi] = OCCUPIED
        out[occ < lo] = FREE
    else:
        mid = np.rint((occ - lo) / (hi - lo) * 100.0)
        out[:] = np.clip(mid, 0, 100).astype(np.int8)
        out[occ > hi] = OCCUPIED
        out[occ < lo] = FREE
        if opaque is not None:
            out[~opaque] = UNKNOWN
    return out[::-1].copy()


def _speed_fraction(values: np.ndarray, speed_filter: tuple[int, float, float], top_speed: float | None,
                    where: Any) -> np.ndarray:
    """Nav2's speed filter: mask values -> ``f32[H, W]`` fraction of the top speed (1 = no limit)."""
    try:
        kind, base, mult = int(speed_filter[0]), float(speed_filter[1]), float(speed_filter[2])
    except (TypeError, ValueError, IndexError):
        raise ValueError(f"speed_filter must be (type, base, multiplier), got {speed_filter!r}") from None
    if kind not in (1, 2) or not (math.isfinite(base) and math.isfinite(mult)):
        raise ValueError(f"speed_filter type must be 1 (percent) or 2 (m/s) with finite base and multiplier, "
                         f"got {speed_filter!r}")
    limit = base + mult * values.astype(np.float64)
    if kind == 1:
        frac = limit / 100.0
    else:
        if top_speed is None or not math.isfinite(float(top_speed)) or float(top_speed) <= 0:
            raise ValueError(f"{where}: an absolute speed mask (speed_filter type 2, m/s) needs top_speed=, the "
                             f"robot's top speed in m/s, to become a fraction of it; got {top_speed!r}")
        frac = limit / float(top_speed)
    none = (values <= 0) | ~(frac > 0)  # no limit: mask 0, unknown, or a limit of 0 or below (Nav2: no limit)
    return np.where(none, 1.0, np.minimum(frac, 1.0)).astype(np.float32)


def _mask(path: str | os.PathLike, meta: RosMap, what: str) -> np.ndarray:
    m = read_ros_yaml(path)
    for key in ("resolution", "origin"):
        if m[key] != meta[key]:
            raise _fail(path, f"{what} mask {key} {m[key]} differs from the map's {meta[key]}")
    values = occupancy_values(m, where=path)
    if values.shape != meta["_shape"]:
        H, W = values.shape
        raise _fail(path, f"{what} mask is {W}x{H} cells, the map {meta['_shape'][1]}x{meta['_shape'][0]}")
    return values


def load_ros_map(path: str | os.PathLike, *, unknown: str = "blocked", keepout: str | os.PathLike | None = None,
                 speed: str | os.PathLike | None = None, speed_filter: tuple[int, float, float] = (1, 100.0, -1.0),
                 top_speed: float | None = None) -> GridMap:
    """Reads a ROS ``map_server`` map (its YAML file) into a `GridMap` (module docstring for the rules).

    Args:
      path: the map's YAML file; its ``image`` is read relative to the YAML's folder.
      unknown: ``"blocked"`` (default: a robot does not drive where the map knows nothing) or ``"free"``.
      keepout: a Nav2 keep-out mask's YAML: its occupied cells become blocked.
      speed: a Nav2 speed mask's YAML: becomes `GridMap.speed_limit`.
      speed_filter: ``(type, base, multiplier)`` of the speed filter (Nav2's ``CostmapFilterInfo``).
      top_speed: the robot's top speed (m/s), needed only for an absolute (type 2) speed mask.

    Returns:
      `GridMap` with ``resolution`` and ``origin`` from the YAML; cell ``(x, y)`` is ROS's cell (``y`` from
      the image's bottom row).
    """
    if unknown not in ("blocked", "free"):
        raise ValueError(f"unknown must be 'blocked' or 'free', got {unknown!r}")
    meta = read_ros_yaml(path)
    values = occupancy_values(meta, where=path)
    meta["_shape"] = values.shape
    free = (values != OCCUPIED) & ((values != UNKNOWN) if unknown == "blocked" else True)
    if keepout is not None:
        free &= _mask(keepout, meta, "keep-out") != OCCUPIED
    limit = None
    if speed is not None:
        limit = _speed_fraction(_mask(speed, meta, "speed"), speed_filter, top_speed, speed)
    return grid_from_array(free, resolution=meta["resolution"], origin=meta["origin"][:2], speed_limit=limit)


def _pgm_bytes(pixels: np.ndarray) -> bytes:
    h, w = pixels.shape
    return f"P5\n{w} {h}\n255\n".encode("ascii") + np.ascontiguousarray(pixels, np.uint8).tobytes()


def _yaml_text(image: str, mode: str, res: float, origin: tuple[float, float], occ: float, free: float) -> str:
    return (f"image: {image}\nmode: {mode}\nresolution: {res!r}\norigin: [{origin[0]!r}, {origin[1]!r}, 0.0]\n"
            f"negate: 0\noccupied_thresh: {occ!r}\nfree_thresh: {free!r}\n")


def save_ros_map(grid: GridMap, path: str | os.PathLike, speed_filter: tuple[int, float, float] = (1, 100.0, -1.0)
                 ) -> list[Path]:
    """Writes ``grid`` as a ROS map: ``path`` (YAML) and the P5 PGM beside it (``<stem>.pgm``: 254 free,
    0 blocked, trinary, ``free_thresh`` 0.196, ``occupied_thresh`` 0.65); with a speed limit, also the speed
    mask ``<stem>_speed.yaml``/``.pgm`` (scale mode, for the same ``speed_filter``, type 1). Each file is
    written atomically. `load_ros_map` of the files gives ``grid``'s occupancy, resolution and origin back
    (and its speed limit, to 1/100 of the top speed, between 1 % and 99 %, from the mask), bit for bit.

    Returns:
      The files written.
    """
    p = Path(path)
    if p.suffix.lower() not in (".yaml", ".yml"):
        raise ValueError(f"{p}: a ROS map is saved as a .yaml file (and a .pgm beside it)")
    free = np.asarray(grid.free, dtype=bool)[::-1]  # ROS cell rows (bottom first) -> image rows (top first)
    origin = (float(grid.origin[0]), float(grid.origin[1]))
    stem = p.stem
    written = [atomic_write(p.with_name(stem + ".pgm"), _pgm_bytes(np.where(free, 254, 0)))]
    written.append(atomic_write(p, _yaml_text(stem + ".pgm", "trinary", float(grid.resolution), origin, 0.65, 0.196)))
    if grid.speed_limit is not None:
        kind, base, mult = int(speed_filter[0]), float(speed_filter[1]), float(speed_filter[2])
        if kind != 1 or mult == 0:
            raise ValueError("save_map writes percent speed masks (speed_filter type 1, non-zero multiplier)")
        frac = np.asarray(grid.speed_limit, np.float64)[::-1]
        m = np.rint((100.0 * frac - base) / mult)
        # 0 means "no limit" and 100 a limit of 0 % (also none, in Nav2): a limit below 1 % is written as 1 %.
        m = np.where(frac >= 1.0, 0, np.clip(m, 1, 99))
        pixels = np.rint(255.0 * (1.0 - m / 100.0)).astype(np.uint8)
        written.append(atomic_write(p.with_name(stem + "_speed.pgm"), _pgm_bytes(pixels)))
        written.append(atomic_write(p.with_name(stem + "_speed.yaml"),
                                    _yaml_text(stem + "_speed.pgm", "scale", float(grid.resolution), origin, 1.0, 0.0)))
    return written
