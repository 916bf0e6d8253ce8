"""Results as plain Python and as pandas DataFrames: the helpers behind every ``to_dict`` / ``to_dataframe``.

`PlanResult`, `jaxplan.BatchResult`, `jaxplan.nav.Episode` / `EpisodeBatch` and a run's trials
(`jaxplan.experiments.export`) convert through these, so every export follows one set of rules:

* ``to_dict()`` gives built-in types only (``dict``, ``list``, ``str``, ``int``, ``float``, ``bool``, None):
  numpy arrays become nested lists, numpy scalars Python numbers; non-finite floats stay floats (``inf`` length of
  a failed plan), and `json_text` writes them as ``null`` (JSON has no infinity).
* ``to_dataframe(what)`` gives a `pandas.DataFrame` in long form: ``"summary"`` one row per result (per run,
  per episode), ``"path"`` / ``"history"`` / ``"trajectory"`` one row per cell, iteration or control step, keyed
  by the result's indices (``scenario``, ``seed``, ``robot``). pandas is an optional extra
  (``pip install 'jaxplan[export]'``), imported only here and only when a DataFrame is asked for.
"""

from __future__ import annotations

import json
import math
from typing import Any, Mapping, Sequence

import numpy as np

__all__ = ["plain", "json_safe", "json_text", "require_pandas", "frame", "check_what"]


def plain(value: Any) -> Any:
    """``value`` with numpy arrays and scalars, tuples and NamedTuples turned into built-in lists, numbers, dicts."""
    if isinstance(value, np.ndarray):
        return value.tolist() if value.dtype != object else [plain(v) for v in value.tolist()]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, Mapping):
        return {str(k): plain(v) for k, v in value.items()}
    if hasattr(value, "_asdict"):  # a NamedTuple (e.g. MovingObstacles)
        return {k: plain(v) for k, v in value._asdict().items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if hasattr(value, "__array__") and not isinstance(value, (str, bytes)):  # a jax array
        return plain(np.asarray(value))
    return value


def json_safe(value: Any) -> Any:
    """`plain` ``value`` with non-finite floats as None (JSON has no inf or NaN)."""
    value = plain(value)
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, list):
        return [json_safe(v) for v in value]
    return value


def json_text(value: Any) -> str:
    """``value`` as strict JSON text (`json_safe`), indented, ending in a newline."""
    return json.dumps(json_safe(value), indent=1, allow_nan=False) + "\n"


def require_pandas(what: str = "to_dataframe()") -> Any:
    """The pandas module, or an ``ImportError`` saying how to install it."""
    try:
        import pandas
    except ImportError:
        raise ImportError(f"{what} needs pandas, an optional extra of jaxplan: pip install 'jaxplan[export]' "
                          f"(or pip install pandas)") from None
    return pandas


def check_what(what: str, allowed: Sequence[str], owner: str) -> None:
    """Raises ``ValueError`` unless ``what`` is one of ``allowed`` (the tables ``owner.to_dataframe`` offers)."""
    if what not in allowed:
        raise ValueError(f"{owner}.to_dataframe: what must be one of {', '.join(map(repr, allowed))}, got {what!r}")


def frame(columns: Mapping[str, Any]) -> Any:
    """A `pandas.DataFrame` of equal-length columns (numpy arrays or lists)."""
    pd = require_pandas()
    return pd.DataFrame({k: np.asarray(v) if not isinstance(v, np.ndarray) else v for k, v in columns.items()})
