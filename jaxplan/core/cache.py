"""The one cache of jaxplan: bounded, least-recently-used memoisation of pure builds.

Maps are prepared (move tables, collision maps, k-d trees) and programs compiled once, then
reused while they are among the last few used. Every such memo in jaxplan is one of two forms:

* ``functools.lru_cache(maxsize=n)`` where the arguments hash (configs, names, shapes);
* `memoize` ``(maxsize=n, key=...)`` where they do not (maps, arrays): ``key(*args, **kwargs)``
  names the entry by content — `digest` of the layers that matter, plus hashable settings —
  and the arguments are dropped once the value is built, so the cache holds keys and values only.

Both are pure memoisation: a hit returns what a miss would build. `Built` carries a build's own
duration, so a caller can report "seconds spent compiling now (0 if cached)".
"""

from __future__ import annotations

import functools
import hashlib
import time
from typing import Any, Callable, Hashable, TypeVar

import numpy as np

__all__ = ["lru_cache", "memoize", "digest", "Built"]

lru_cache = functools.lru_cache
"""`functools.lru_cache`, re-exported so that every cache of the library is found here."""

T = TypeVar("T")


def digest(*parts: Any) -> str:
    """A 128-bit hex digest (BLAKE2b) of arrays and scalars: each part's shape, dtype and bytes.

    Two calls give the same digest exactly when their parts have equal shapes, dtypes and contents,
    so a digest stands for map layers or arrays in a cache key.
    """
    h = hashlib.blake2b(digest_size=16)
    for part in parts:
        a = np.ascontiguousarray(part)
        h.update(f"{a.shape}{a.dtype.str};".encode())
        h.update(np.packbits(a).tobytes() if a.dtype == bool else a.tobytes())  # a map's free cells: 1 bit each
    return h.hexdigest()


class _Call:
    """One call, as an ``lru_cache`` argument: it hashes and compares by ``key`` alone and carries the
    call's arguments to the build (and no further)."""

    __slots__ = ("key", "args", "kwargs")

    def __init__(self, key: Hashable, args: tuple, kwargs: dict) -> None:
        self.key, self.args, self.kwargs = key, args, kwargs

    def __hash__(self) -> int:
        return hash(self.key)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, _Call) and self.key == other.key


def memoize(maxsize: int, key: Callable[..., Hashable]) -> Callable[[Callable[..., T]], Callable[..., T]]:
    """Decorator: ``fn(*args, **kwargs)`` memoised under ``key(*args, **kwargs)``, the last ``maxsize`` kept.

    Args:
      maxsize: entries kept (least recently used dropped first).
      key: the entry's name, hashable; for maps and arrays use `digest` of the relevant layers.

    Returns:
      The memoised function, with ``cache_info()`` and ``cache_clear()`` of ``functools.lru_cache``.
    """

    def decorate(fn: Callable[..., T]) -> Callable[..., T]:
        @functools.lru_cache(maxsize=maxsize)
        def build(call: _Call) -> T:
            try:
                return fn(*call.args, **call.kwargs)
            finally:  # the cache keeps this call as its key: drop the (possibly large) arguments
                call.args, call.kwargs = (), {}

        @functools.wraps(fn)
        def cached(*args: Any, **kwargs: Any) -> T:
            return build(_Call(key(*args, **kwargs), args, kwargs))

        cached.cache_info = build.cache_info  # type: ignore[attr-defined]
        cached.cache_clear = build.cache_clear  # type: ignore[attr-defined]
        return cached

    return decorate


class Built:
    """A built value (a compiled program) and the seconds its build took, reported once.

    A memoised builder returns ``Built.timed(make)``; its callers call `take`: the first gets the
    build time, every later one (a cache hit) 0.0.
    """

    __slots__ = ("value", "seconds")

    def __init__(self, value: Any, seconds: float) -> None:
        self.value, self.seconds = value, seconds

    @classmethod
    def timed(cls, make: Callable[[], Any]) -> "Built":
        """Runs ``make()`` and records its wall-clock duration."""
        t0 = time.perf_counter()
        value = make()
        return cls(value, time.perf_counter() - t0)

    def take(self) -> tuple[Any, float]:
        """``(value, seconds of the build)`` the first time, ``(value, 0.0)`` after."""
        seconds, self.seconds = self.seconds, 0.0
        return self.value, seconds
