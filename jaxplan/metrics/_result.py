"""`PathMetrics`: what `jaxplan.path_metrics` returns, one field per metric (docs/guide/smoothing-and-metrics.md).

The previous release returned a dict; reading the result as one (``m["length"]``, ``m.keys()``, ``dict(m)``,
``"objective_gap" in m``, iterating over its keys) still works for one release, with a `DeprecationWarning`.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Iterator

import numpy as np

from jaxplan.core.deprecation import warn_deprecated

__all__ = ["PATH_METRICS", "PathMetrics"]

PATH_METRICS = (
    "length", "turns", "sharp_turns", "smoothness", "min_clearance", "mean_clearance", "max_curvature",
    "hausdorff", "optimality_gap",
)
"""The metrics `path_metrics` always measures: the first fields of `PathMetrics`, in order."""

Metric = float | int | np.ndarray
"""One metric: a Python number for one path, ``np.ndarray [B]`` for a batch."""


def _mapping_access(what: str) -> None:
    warn_deprecated(f"PathMetrics{what}: path_metrics returns a PathMetrics, no longer a dict; read its fields "
                    "(m.length, getattr(m, name), m._asdict()); dict access will be removed in the next release",
                    stacklevel=4)


@dataclasses.dataclass(frozen=True)
class PathMetrics:
    """The path metrics of one path (Python numbers) or a batch (``np.ndarray [B]`` each).

    Attributes:
      length: m. turns: vertices with a heading change > 1e-6 rad. sharp_turns: turns of at least 45°.
      smoothness: 1 − mean|Δheading|/π. min_clearance, mean_clearance: m to the nearest blocked square.
      max_curvature: 1/m (Menger, at the vertices).
      hausdorff: m to the reference polyline; None without a reference.
      optimality_gap: length / optimal − 1; None without a sound optimum.
      objective_gap: cost / objective_optimum − 1; None unless ``cost`` and ``objective_optimum`` were given.
    """

    length: Metric
    turns: Metric
    sharp_turns: Metric
    smoothness: Metric
    min_clearance: Metric
    mean_clearance: Metric
    max_curvature: Metric
    hausdorff: Metric | None
    optimality_gap: Metric | None
    objective_gap: Metric | None = None

    def _asdict(self) -> dict[str, Any]:
        """Every field by name (as a NamedTuple's ``_asdict``), values as they are."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}

    def to_dict(self) -> dict[str, Any]:
        """Every field as built-in Python (`jaxplan.core.export.plain`): numbers, lists for a batch, None."""
        from jaxplan.core.export import plain

        return plain(self._asdict())

    # The previous release's dict interface, for one release: the keys it had (objective_gap only when measured).

    def _keys(self) -> tuple[str, ...]:
        return PATH_METRICS + (() if self.objective_gap is None else ("objective_gap",))

    def __getitem__(self, key: str) -> Any:
        _mapping_access(f"[{key!r}]")
        if key not in self._keys():
            raise KeyError(key)
        return getattr(self, key)

    def get(self, key: str, default: Any = None) -> Any:
        """Deprecated (dict access): ``getattr(m, key, default)``."""
        _mapping_access(f".get({key!r})")
        return getattr(self, key) if key in self._keys() else default

    def keys(self) -> tuple[str, ...]:
        """Deprecated (dict access): the metric names (`PATH_METRICS`, and ``objective_gap`` when measured)."""
        _mapping_access(".keys()")
        return self._keys()

    def values(self) -> list[Any]:
        """Deprecated (dict access): the values of `keys`."""
        _mapping_access(".values()")
        return [getattr(self, k) for k in self._keys()]

    def items(self) -> list[tuple[str, Any]]:
        """Deprecated (dict access): ``(name, value)`` pairs of `keys`."""
        _mapping_access(".items()")
        return [(k, getattr(self, k)) for k in self._keys()]

    def __iter__(self) -> Iterator[str]:
        _mapping_access(" iterated (its keys)")
        return iter(self._keys())

    def __len__(self) -> int:
        _mapping_access(" len()")
        return len(self._keys())

    def __contains__(self, key: object) -> bool:
        _mapping_access(f" 'in' ({key!r} in m)")
        return key in self._keys()

    def __bool__(self) -> bool:  # without it, truth would go through the deprecated __len__
        return True
