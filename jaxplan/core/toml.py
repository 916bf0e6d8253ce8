"""The one TOML writer: documents through `tomli_w`, single inline values for hand-laid config fragments.

Configs are read with `tomllib` and written here, never by string formatting elsewhere:

* `dumps`: a whole document (tables, arrays of tables) with `tomli_w.dumps`, after `plain` turned numpy
  scalars and arrays, tuples and read-only mappings into TOML's types; an optional comment heads it.
* `literal`: one value inline (``true``, ``"even"``, ``[1, 2]``, ``{ a = 1 }``), for a ``key = value`` line of
  a fragment laid out by hand (a ``[[planners]]`` entry with a comment) and for the config reference's cells.
  `tomli_w` writes the scalars and the keys (its escaping, its number format); arrays and tables are written
  inline and on one line, which `tomli_w` has no switch for.

Everything written here reads back with `tomllib` to the same values (tuples as lists)::

    literal({"alpha": 1.5, "ants": [10, 20]})    # '{ alpha = 1.5, ants = [10, 20] }'
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Any, Mapping

import tomli_w

__all__ = ["plain", "dumps", "literal", "key"]


def plain(v: Any) -> Any:
    """``v`` with numpy scalars and arrays as Python numbers and lists, tuples as lists and any mapping as a dict
    (what `tomli_w` takes). Raises TypeError for a value TOML cannot hold (None, an object)."""
    if isinstance(v, (bool, int, float, str)):
        return v
    if isinstance(v, (Mapping, MappingProxyType)):
        return {str(k): plain(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [plain(x) for x in v]
    if hasattr(v, "tolist") and hasattr(v, "dtype"):  # numpy scalar or array (numpy is not imported for this)
        return plain(v.tolist())
    raise TypeError(f"cannot write {v!r} (a {type(v).__name__}) to TOML")


def dumps(doc: Mapping[str, Any], *, comment: str = "") -> str:
    """The TOML text of document ``doc`` (`tomli_w.dumps` of `plain` ``doc``), after ``comment``'s lines as
    ``# `` comments."""
    head = "".join(f"# {line}\n".replace("# \n", "#\n") for line in comment.splitlines())
    return head + tomli_w.dumps(plain(doc))


def key(k: str) -> str:
    """Key ``k`` as TOML writes it: bare when it may be, else quoted."""
    return tomli_w.dumps({str(k): 0})[: -len(" = 0\n")]


def literal(v: Any) -> str:
    """Value ``v`` as one inline TOML value (arrays and tables on one line; an empty table is ``{}``)."""
    v = plain(v)
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{key(k)} = {literal(x)}" for k, x in v.items()) + " }" if v else "{}"
    if isinstance(v, list):
        return "[" + ", ".join(literal(x) for x in v) + "]"
    return tomli_w.dumps({"v": v})[len("v = "):-1]
