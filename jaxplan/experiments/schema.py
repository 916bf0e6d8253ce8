"""Config schemas declared once: each key's type, default, bounds or choices and one-line doc.

A *section* is a dataclass whose fields carry a `Setting` (made with `setting`): one TOML table. Fields
without a setting (resolved paths, provenance) are not keys. A table with no resolved object of its own is
a `declaration`. A section may also carry ``schema_extra`` (a `Setting` describing keys beyond its own, such
as metric names) and ``schema_json`` (JSON Schema keywords added to its table's schema) as class attributes.
Everything else derives from these declarations:

* validation: `Reader.section` checks a parsed TOML table against a section and collects every problem
  with its key path (``maps[0].scenarios.count: must be >= 1, got 0``), with the closest known key or
  value for a misspelt one ("did you mean 'chunk'?"); `ConfigError` lists them all at once;
* defaults: a section's dataclass defaults are its settings' defaults;
* the reference page: `markdown` renders a tree of sections as tables (``docs/guide/config.md``);
* editor support: `json_schema` renders it as a JSON Schema, draft-07 (``configs/schema/*.schema.json``);
* quick runs: a quick table's settings (``[experiment.quick]``, ``[tune.quick]``, ``[study.quick]``) declare
  which part of the resolved config each changes and how (``overlay``, one of `OVERLAYS`), and the one
  function `overlay` applies any of them.

Checks that need more than one value or a registry (a planner's overrides, files on disk, which metrics
apply) stay in the code that reads each section and report to the same `Reader`.

Example::

    @dataclass(frozen=True)
    class Obstacles:  # a section: one TOML table
        n: int = setting("int", 0, "discs per episode", ge=0)
        speed: float = setting("float", 1.0, "m/s", ge=0)

    r = Reader()
    values = r.section({"n": -1, "sped": 2.0}, "obstacles", Obstacles)
    r.problems  # ["obstacles.sped: unknown key; did you mean 'speed'?", "obstacles.n: must be >= 0, got -1"]

This module imports nothing from jaxplan but `jaxplan.core` (`did_you_mean`, the package's one did-you-mean,
re-exported here; the Markdown toolkit and the TOML writer): experiment and tuning configs both build on it.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import re
import warnings
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Callable, Iterator, Mapping, Sequence

from jaxplan.core import markdown as md
from jaxplan.core.names import did_you_mean
from jaxplan.core.toml import literal

__all__ = [
    "TYPES", "UNSET", "MAX_SEED", "MAX_SEED_COUNT", "ConfigError", "Setting", "setting", "declaration", "settings",
    "setting_of",
    "extra_setting", "Reader", "check", "frozen", "describe", "did_you_mean", "join", "toml_literal", "markdown",
    "json_schema", "OVERLAYS", "overlay",
]

TYPES = ("int", "float", "str", "bool", "seeds", "strings", "table", "section", "tables", "custom")
"""Setting types: TOML scalars (``int`` refuses booleans, ``float`` takes integers and must be finite);
``seeds`` a count n <= `MAX_SEED_COUNT` (seeds 0..n-1) or a list of distinct integers in [0, 2**32);
``strings`` a list of strings; ``table`` a free-form inline table (its keys optionally restricted);
``section`` a nested table and ``tables`` an array of tables, both described by another section; ``custom`` a
value the section's own code checks (the setting gives its doc, Markdown type and JSON Schema)."""


OVERLAYS = ("set", "merge", "cap", "keep")
"""How a quick table's key changes the resolved config (`overlay`): ``set`` replaces the target field; ``merge``
merges the key's table into the target mapping; ``cap`` lowers the target number to at most the value (an unset
one takes it); ``keep`` keeps the items of the target sequence whose attribute (the path's last name) is listed.
A TARGET path names dataclass fields with dots; ``name[]`` goes into every item of the tuple ``name``
(``"cap maps[].scenarios.count"``, ``"keep planners[].label"``)."""


class _Unset:
    """The absence of a default (not None, which is a default: "unset")."""

    def __repr__(self) -> str:
        return "UNSET"


UNSET: Any = _Unset()
"""A setting without a default: its dataclass field has none either."""

MAX_SEED = 2**32
"""Seeds are unsigned 32-bit integers."""

MAX_SEED_COUNT = 2**20
"""The largest seed count a config may give: the seeds are held as a tuple (36 bytes each), so a count near
2**32 would take the machine's memory before any check could run; a million seeds is far beyond any statistics
(whether a run's seeds × scenarios fit is the memory guard's to say, `jaxplan.scale.check_memory`)."""


class ConfigError(ValueError):
    """A config with problems; ``problems`` lists each as ``"key.path: message"``."""

    def __init__(self, problems: list[str] | tuple[str, ...], source: str = "config"):
        self.problems = tuple(dict.fromkeys(problems))  # a shared [scenarios] problem is met once per map
        n = len(self.problems)
        head = f"{source}: {n} problem{'s' if n != 1 else ''}"
        super().__init__(head + "\n" + "\n".join(f"  - {p}" for p in self.problems))


@dataclass(frozen=True, eq=False)
class Setting:
    """One key of a section.

    Attributes:
      type: one of `TYPES`.
      default: the value when the key is absent (`UNSET`: none; None: absent means unset).
      doc: one line for the reference and the JSON Schema.
      name: the key (filled in from the field name by `settings`).
      default_text: the default in words, when it depends on other keys (the reader's caller applies it).
      required: the key must be present.
      ge, gt, le: bounds of a number (``>=``, ``>``, ``<=``).
      choices: the values allowed (a tuple, or a function returning one for registries read late).
      pattern: a regular expression the whole string must match; ``hint`` says why in the problem.
      aliases: deprecated value -> its new name; accepted with a `DeprecationWarning` (for one release).
      keys: ``table``: the keys allowed (a tuple or a function returning one; None: any key).
      values: ``table``: the setting each value must satisfy (None: unchecked here).
      section: ``section``/``tables``: the dataclass describing the nested table.
      when: ``(key, values)``: the key is allowed only when sibling ``key`` has one of ``values``.
      nonempty: ``tables``/``strings``: at least one entry.
      json: ``custom``: its JSON Schema.
      type_text: ``custom``: its type in words.
      overlay: a quick table's key: ``"OP"`` or ``"OP TARGET"``, how `overlay` applies its value to the
        resolved config (OP one of `OVERLAYS`; TARGET a field path, default the key's own name).
    """

    type: str
    default: Any = UNSET
    doc: str = ""
    name: str = ""
    default_text: str = ""
    required: bool = False
    ge: float | None = None
    gt: float | None = None
    le: float | None = None
    choices: tuple | Callable[[], tuple] | None = None
    pattern: str | None = None
    hint: str = ""
    aliases: Mapping[str, str] | None = None
    keys: tuple[str, ...] | Callable[[], tuple[str, ...]] | None = None
    values: Setting | None = None
    section: type | None = None
    when: tuple[str, tuple] | None = None
    nonempty: bool = False
    json: Mapping[str, Any] | None = None
    type_text: str = ""
    overlay: str | None = None

    def __post_init__(self) -> None:
        if self.type not in TYPES:
            raise ValueError(f"setting type must be one of {', '.join(TYPES)}, got {self.type!r}")
        if self.overlay is not None and self.overlay.split(" ")[0] not in OVERLAYS:
            raise ValueError(f"overlay must start with one of {', '.join(OVERLAYS)}, got {self.overlay!r}")
        if self.type in ("section", "tables") and self.section is None:
            raise ValueError(f"a {self.type!r} setting needs its section dataclass")

    def options(self) -> tuple | None:
        """The allowed values (None: any)."""
        return self.choices() if callable(self.choices) else self.choices

    def allowed_keys(self) -> tuple[str, ...] | None:
        """A ``table`` setting's allowed keys (None: any)."""
        return self.keys() if callable(self.keys) else self.keys

    @property
    def fallback(self) -> Any:
        """The value a reader returns when the key is absent or invalid."""
        return None if self.default is UNSET else self.default


def setting(type: str, default: Any = UNSET, doc: str = "", **kw: Any) -> Any:
    """A dataclass field declaring one key: ``x: int = setting("int", 0, "what x is", ge=0)``.

    The dataclass default is ``default`` (none for `UNSET`); a ``table`` setting defaults to
    an empty read-only mapping (the reader's: an empty dict). Keyword arguments are `Setting` attributes.
    """
    if type == "table" and default is UNSET:
        default = {}
    s = Setting(type, default, doc, **kw)
    md = {"setting": s}
    if type == "table":
        return dataclasses.field(default_factory=_empty, metadata=md)
    if default is UNSET:
        return dataclasses.field(metadata=md)
    return dataclasses.field(default=default, metadata=md)


def declaration(cls: type) -> type:
    """Makes ``cls`` a section that only declares keys: a TOML table read into a dict, with no resolved object of
    its own. A dataclass without generated methods (it is never instantiated), so it costs little to import."""
    return dataclass(init=False, repr=False, eq=False)(cls)


def _empty() -> Mapping[str, Any]:
    return MappingProxyType({})


@functools.lru_cache(maxsize=None)
def settings(section: type) -> tuple[Setting, ...]:
    """The settings of a section dataclass, in field order, named after their fields (cached per class)."""
    return tuple(dataclasses.replace(f.metadata["setting"], name=f.name) for f in dataclasses.fields(section)
                 if "setting" in f.metadata)


def setting_of(section: type, name: str) -> Setting:
    """The setting of key ``name`` of ``section``."""
    for s in settings(section):
        if s.name == name:
            return s
    raise KeyError(f"{section.__name__} has no setting {name!r}")


def extra_setting(section: type) -> Setting | None:
    """What a section's keys beyond its settings may be (its ``schema_extra`` attribute), or None (no more keys).

    The section's own code checks those keys; the setting documents them (its name is shown as the key)."""
    return getattr(section, "schema_extra", None)


# ---------------------------------------------------------------------------------------------
# Reading with error collection


_TYPE_NAMES = {"int": "an integer", "float": "a number", "str": "a string", "bool": "true or false"}


def describe(v: Any) -> str:
    """A TOML value for a problem message: its TOML type and (shortened) repr."""
    name = {bool: "boolean", int: "integer", float: "number", str: "string", list: "array", dict: "table"}.get(
        type(v), type(v).__name__)
    text = repr(v)
    return f"{name} {text if len(text) <= 40 else text[:37] + '...'}"


def join(path: str, key: str) -> str:
    """``path.key`` (``key`` alone at the top level)."""
    return f"{path}.{key}" if path else key


def frozen(d: Mapping[str, Any] | None) -> Mapping[str, Any]:
    """A read-only mapping whose lists became tuples (TOML arrays as hashable parameter values)."""
    def fix(v):
        if isinstance(v, list):
            return tuple(fix(x) for x in v)
        if isinstance(v, dict):
            return MappingProxyType({k: fix(x) for k, x in v.items()})
        return v

    return MappingProxyType({k: fix(v) for k, v in (d or {}).items()})


class Reader:
    """Checks parsed TOML against sections and collects problems; every check returns a usable fallback, so
    reading goes on and one `ConfigError` can list every problem of a config."""

    def __init__(self) -> None:
        self.problems: list[str] = []

    def bad(self, path: str, msg: str) -> None:
        """Records a problem at key path ``path``."""
        self.problems.append(f"{path}: {msg}")

    def table(self, obj: Any, path: str, allowed: Sequence[str], required: Sequence[str] = ()) -> dict:
        """``obj`` as a dict with only ``allowed`` keys (unknown ones reported, with a close match) and the
        ``required`` ones present (a missing one reported)."""
        if obj is None:
            obj = {}
        if not isinstance(obj, dict):
            self.bad(path, f"expected a table, got {describe(obj)}")
            return {}
        for k in obj:
            if k not in allowed:
                hint = did_you_mean(k, allowed) or f" (expected one of: {', '.join(sorted(allowed))})"
                self.bad(join(path, k), f"unknown key{hint}")
        for k in required:
            if k not in obj:
                self.bad(join(path, k), "required key is missing")
        return {k: v for k, v in obj.items() if k in allowed}

    def section(self, obj: Any, path: str, section: type, *, defaults: Mapping[str, Any] | None = None,
                skip: Sequence[str] = ()) -> dict[str, Any]:
        """Table ``obj`` at ``path`` checked against ``section``: unknown keys, required keys, then the value
        of each setting. Settings of types ``section``, ``tables`` and ``custom`` are left to the caller, who
        also reports a missing required ``section`` or ``tables`` (e.g. `entries` with ``required=True``).

        Args:
          obj: the parsed table (None: absent, every key takes its default).
          path: its key path, for problems.
          section: the dataclass declaring its keys.
          defaults: defaults that depend on other keys, replacing the settings' own.
          skip: settings not read here (the caller reads them with `value`, or reports them as misplaced).

        Returns:
          ``{name: value}`` for every setting read (its default or ``defaults[name]`` where absent or
          invalid), and the raw value of each present ``section``/``tables``/``custom`` key.
        """
        specs = settings(section)
        t = self.table(obj, path, self._allowed(obj, specs, extra_setting(section) is not None),
                       required=[s.name for s in specs if s.required and s.type not in ("section", "tables")])
        out: dict[str, Any] = {}
        for s in specs:
            if s.name in skip:
                continue
            if s.type in ("section", "tables", "custom"):
                if s.name in t:
                    out[s.name] = t[s.name]
                continue
            out[s.name] = self.value(t, path, s, (defaults or {}).get(s.name, UNSET))
        return out

    @staticmethod
    def _allowed(obj: Any, specs: Sequence[Setting], extra: bool) -> tuple[str, ...]:
        """The keys a table may have: settings without ``when``, and those whose sibling's value (or default)
        matches; every setting when a ``when`` sibling has no valid value (its own problem is reported: which
        keys it would allow is unknown); and every present key when the section takes extra keys."""
        names = [s.name for s in specs]
        if not isinstance(obj, dict):
            return tuple(names)
        by_name = {s.name: s for s in specs}
        allowed = []
        for s in specs:
            if s.when is None:
                allowed.append(s.name)
                continue
            key, values = s.when
            sib = by_name[key]
            v = obj.get(key, sib.fallback)
            v = (sib.aliases or {}).get(v, v) if isinstance(v, str) else v
            if not (isinstance(v, str) and v in (sib.options() or ())):
                allowed = names
                break
            if v in values:
                allowed.append(s.name)
        if extra:
            allowed = allowed + [k for k in obj if k not in allowed]
        return tuple(allowed)

    def value(self, t: Mapping[str, Any], path: str, s: Setting, default: Any = UNSET) -> Any:
        """``t[s.name]`` checked against setting ``s`` (``default``, else the setting's, when absent or invalid).

        A deprecated alias is replaced by its new name with a `DeprecationWarning`."""
        if default is UNSET:
            default = s.fallback
        if s.type == "seeds" and isinstance(default, int) and not isinstance(default, bool):
            default = tuple(range(default))
        if s.name not in t:
            return dict(default) if isinstance(default, dict) else default
        v, p = t[s.name], join(path, s.name)
        if s.type == "seeds":
            return self._seeds(v, p, default)
        if s.type == "strings":
            return self._strings(v, p, s, default)
        if s.type == "table":
            return self._table(v, p, s)
        if s.type not in _TYPE_NAMES:
            raise ValueError(f"{p}: a {s.type!r} setting is read by its section's code, not by Reader.value")
        ok = {
            "int": isinstance(v, int) and not isinstance(v, bool),
            "float": isinstance(v, (int, float)) and not isinstance(v, bool),
            "str": isinstance(v, str),
            "bool": isinstance(v, bool),
        }[s.type]
        if not ok:
            self.bad(p, f"expected {_TYPE_NAMES[s.type]}, got {describe(v)}")
            return default
        if s.type == "float":
            v = float(v)
            if not math.isfinite(v):
                self.bad(p, f"must be a finite number, got {v}")
                return default
        if s.aliases and v in s.aliases:
            warnings.warn(f"{p}: {v!r} is deprecated; use {s.aliases[v]!r} (the old name is accepted for one "
                          "more release)", DeprecationWarning, stacklevel=3)
            v = s.aliases[v]
        problem = check(s, v)
        if problem is not None:
            self.bad(p, problem)
            return default
        return v

    def _seeds(self, v: Any, p: str, default: Any) -> tuple[int, ...] | None:
        """A seed count ``n >= 1`` (seeds 0..n-1) or a list of distinct integers in [0, 2**32)."""
        if isinstance(v, int) and not isinstance(v, bool):
            if v < 1:
                self.bad(p, f"must be >= 1, got {v}")
                return default
            if v > MAX_SEED_COUNT:
                self.bad(p, f"a seed count of {v} is more than the {MAX_SEED_COUNT} seeds a run may have")
                return default
            return tuple(range(v))
        if isinstance(v, list) and v and all(isinstance(x, int) and not isinstance(x, bool) for x in v):
            bad = [x for x in v if not 0 <= x < MAX_SEED]
            if bad:
                self.bad(p, f"seeds must lie in [0, 2**32), got {bad[0]}")
                return default
            if len(set(v)) != len(v):
                self.bad(p, "seeds must be distinct")
                return default
            return tuple(v)
        self.bad(p, f"expected a seed count (integer >= 1) or a non-empty list of integers, got {describe(v)}")
        return default

    def _strings(self, v: Any, p: str, s: Setting, default: Any) -> list[str] | None:
        if not isinstance(v, list) or not all(isinstance(x, str) for x in v) or (s.nonempty and not v):
            self.bad(p, f"expected a {'non-empty ' if s.nonempty else ''}list of strings, got {describe(v)}")
            return default
        return v

    def _table(self, v: Any, p: str, s: Setting) -> dict:
        keys = s.allowed_keys()
        out = self.table(v, p, tuple(v) if keys is None and isinstance(v, dict) else (keys or ()))
        if s.values is not None:
            for k, x in out.items():
                self.value({k: x}, p, dataclasses.replace(s.values, name=k))
        return out

    def entries(self, raw: Mapping[str, Any], key: str, path: str = "", *, required: bool = False,
                nonempty: bool = True) -> Iterator[tuple[str, Any]]:
        """``(key path, entry)`` of each entry of the array of tables ``raw[key]`` (a problem for a missing
        required or malformed array; entries are yielded as they are, for `section` to check)."""
        p = join(path, key)
        v = raw.get(key)
        if v is None:
            if required:
                self.bad(p, f"at least one [[{p}]] entry is required")
            return iter(())
        if not isinstance(v, list) or (nonempty and not v):
            self.bad(p, f"expected {'one or more ' if nonempty else ''}[[{p}]] tables, got {describe(v)}")
            return iter(())
        return ((f"{p}[{i}]", e) for i, e in enumerate(v))


def check(s: Setting, v: Any) -> str | None:
    """Why value ``v`` (of the setting's type) breaks setting ``s``'s choices, bounds or pattern, or None."""
    choices = s.options()
    if choices is not None and v not in choices:
        hint = did_you_mean(str(v), [str(c) for c in choices])
        return f"must be one of {', '.join(map(repr, choices))}, got {v!r}{hint}"
    for bound, op, fails in ((s.ge, ">=", lambda b: v < b), (s.gt, ">", lambda b: v <= b),
                             (s.le, "<=", lambda b: v > b)):
        if bound is not None and fails(bound):
            return f"must be {op} {bound:g}, got {v!r}"
    if s.pattern is not None and not re.fullmatch(s.pattern, v):
        return f"must match {s.pattern}{f' ({s.hint})' if s.hint else ''}, got {v!r}"
    return None


# ---------------------------------------------------------------------------------------------
# Quick runs: a quick table as an overlay on the resolved config


def _quick_value(values: Any, name: str) -> Any:
    return values.get(name) if isinstance(values, Mapping) else getattr(values, name, None)


def _replace_at(obj: Any, path: Sequence[str], fn: Callable[[Any, Any], Any], item: Any = None) -> Any:
    """``obj`` with the field at ``path`` replaced by ``fn(current, item)`` (``item``: the innermost tuple entry
    on the way, for a `overlay` ``where`` rule); ``name[]`` goes into every entry of tuple ``name``."""
    head, rest = path[0], path[1:]
    name = head.removesuffix("[]")
    cur = getattr(obj, name)
    if head.endswith("[]") and rest:
        new = tuple(_replace_at(x, rest, fn, x) for x in cur)
    elif rest:
        new = _replace_at(cur, rest, fn, item)
    else:
        new = fn(cur, item)
    return dataclasses.replace(obj, **{name: new})


def overlay(obj: Any, values: Any, section: type, *,
            where: Mapping[str, Callable[[Any, str], bool]] | None = None) -> Any:
    """Frozen dataclass ``obj`` (a resolved config) with the quick table ``values`` applied as ``section``'s
    settings declare (`Setting.overlay`, in declaration order). A key that is absent, None or empty changes
    nothing.

    Args:
      obj: the resolved config (a dataclass; nested dataclasses are replaced along each target path).
      values: the quick table as read (a mapping, or a dataclass with the keys as attributes).
      section: the quick table's section, whose settings carry ``overlay``.
      where: key -> rule ``(item, subkey) -> bool``: a ``merge`` into every entry of a tuple takes, per entry,
        only the subkeys the rule admits (e.g. the overrides a planner accepts).

    Returns:
      The changed copy of ``obj`` (``obj`` itself is not changed).

    Example::

        @declaration
        class Quick:
            seeds: Any = setting("seeds", None, "the quick run's seeds", overlay="set")
            count: int = setting("int", None, "at most this many scenarios", overlay="cap maps[].count")

        overlay(cfg, {"seeds": (0, 1), "count": 2}, Quick)  # cfg with seeds (0, 1), every map's count <= 2
    """
    where = where or {}
    for s in settings(section):
        if s.overlay is None:
            continue
        v = _quick_value(values, s.name)
        if v is None or (isinstance(v, (Mapping, list, tuple)) and not v):
            continue
        op, _, target = s.overlay.partition(" ")
        path = (target or s.name).split(".")
        if op == "set":
            obj = _replace_at(obj, path, lambda cur, item, v=v: tuple(v) if isinstance(v, list) else v)
        elif op == "cap":
            obj = _replace_at(obj, path, lambda cur, item, v=v: v if cur is None else min(v, cur))
        elif op == "merge":
            rule = where.get(s.name)
            obj = _replace_at(obj, path, lambda cur, item, v=v, rule=rule: frozen(
                {**dict(cur), **{k: x for k, x in v.items() if rule is None or rule(item, k)}}))
        else:  # keep
            *seq, attr = path
            seq[-1] = seq[-1].removesuffix("[]")  # the sequence itself, not its entries
            obj = _replace_at(obj, seq, lambda cur, item, v=v, attr=attr: tuple(x for x in cur
                                                                                 if getattr(x, attr) in v))
    return obj


# ---------------------------------------------------------------------------------------------
# Rendering: the reference page and the JSON Schema


toml_literal = literal
"""``v`` as written in TOML (``true``, ``"even"``, ``[1, 2]``, ``{ a = 1 }``): `jaxplan.core.toml.literal`."""


@dataclass(frozen=True)
class _Node:
    """A section at its place in the tree: TOML key path, whether it is an array of tables, and where else it is
    read (``(key, parent header)`` pairs)."""

    section: type
    path: str
    array: bool
    also: tuple[tuple[str, str], ...] = ()

    @property
    def header(self) -> str:
        return _header(self.path, self.array)


def _header(path: str, array: bool) -> str:
    return f"[[{path}]]" if array else (f"[{path}]" if path else "the top level")


def _tree(root: type) -> list[_Node]:
    """Every section under ``root`` once, in depth-first order, each at its shallowest key path."""
    home: dict[type, tuple[str, bool]] = {}
    uses: dict[type, list[tuple[str, str, str]]] = {}  # (path, key, parent header)
    frontier = [(root, "", False)]
    while frontier:
        nxt = []
        for cls, path, array in frontier:
            if cls in home:
                continue
            home[cls] = (path, array)
            for s in settings(cls):
                if s.type in ("section", "tables"):
                    sub = join(path, s.name)
                    uses.setdefault(s.section, []).append((sub, s.name, _header(path, array)))
                    nxt.append((s.section, sub, s.type == "tables"))
        frontier = nxt
    out: list[_Node] = []

    def visit(cls: type, path: str) -> None:
        if home[cls][0] != path or any(n.section is cls for n in out):
            return
        also = tuple((key, parent) for p, key, parent in uses.get(cls, []) if p != path)
        out.append(_Node(cls, path, home[cls][1], also))
        for s in settings(cls):
            if s.type in ("section", "tables"):
                visit(s.section, join(path, s.name))

    visit(root, "")
    return out


def _first_paragraph(cls: type) -> str:
    doc = (cls.__doc__ or "").strip().split("\n\n")[0]
    return " ".join(doc.split())


def _md_type(s: Setting, anchors: Mapping[type, str]) -> str:
    if s.type in ("section", "tables"):
        link = f"[{'table' if s.type == 'section' else 'array of tables'}](#{anchors[s.section]})"
        return link
    return {"int": "integer", "float": "number", "str": "string", "bool": "boolean",
            "seeds": "integer or list of integers", "strings": "list of strings", "table": "table",
            "custom": s.type_text or "see description"}[s.type]


def _md_default(s: Setting) -> str:
    if s.required:
        return "**required**"
    if s.default_text:
        return s.default_text
    if s.default is UNSET or s.default is None:
        return "—"
    return f"`{toml_literal(s.default)}`"


def _md_bounds(s: Setting) -> str:
    parts = []
    bounds = [f"{op} {b:g}" for b, op in ((s.ge, ">="), (s.gt, ">"), (s.le, "<=")) if b is not None]
    if bounds:
        parts.append(", ".join(bounds))
    if s.options() is not None:
        parts.append(", ".join(f"`{toml_literal(c)}`" for c in s.options()))
    if s.pattern is not None:
        parts.append(f"matches `{s.pattern}`")
    if s.type == "table" and s.allowed_keys() is not None:
        parts.append("keys: " + (", ".join(f"`{k}`" for k in s.allowed_keys()) or "none"))
    if s.values is not None:
        parts.append(f"values: {_md_type(s.values, {})}" + (f" {_md_bounds(s.values)}" if _md_bounds(s.values) else ""))
    if s.nonempty:
        parts.append("at least one")
    if s.when is not None:
        parts.append(f"only where `{s.when[0]}` is " + ", ".join(f"`{toml_literal(v)}`" for v in s.when[1]))
    if s.aliases:
        parts.append("deprecated: " + ", ".join(f"`{toml_literal(a)}` (now `{toml_literal(b)}`)"
                                                for a, b in s.aliases.items()))
    return "; ".join(parts)


def markdown(root: type, heading: str, *, level: int = 2, anchors: Mapping[type, str] | None = None,
             root_header: str = "") -> tuple[str, dict[type, str]]:
    """The reference tables of every section under ``root`` (key, type, default, bounds or choices, doc).

    Args:
      root: the section of a file's top level.
      heading: the top level's heading (e.g. "Experiment configs: top level").
      level: Markdown heading level of each section.
      anchors: sections already rendered elsewhere on the page -> their anchor (linked, not repeated).
      root_header: how the top level's keys are written, for the root's intro.

    Returns:
      The Markdown, and every rendered or linked section -> its anchor.
    """
    anchors = dict(anchors or {})
    nodes = [n for n in _tree(root) if n.section not in anchors]
    for n in nodes:
        title = heading if n.path == "" else f"`{n.header}`"
        anchors[n.section] = md.slug(title)
    lines = []
    for n in nodes:
        title = heading if n.path == "" else f"`{n.header}`"
        lines += [f"{'#' * level} {title}", ""]
        intro = _first_paragraph(n.section)
        if n.also:
            intro += " Also the " + ", ".join(f"`{key}` key of `{parent}`" if parent.startswith("[") else
                                               f"`{key}` key at {parent}" for key, parent in n.also) + "."
        if n.path == "" and root_header:
            intro = (intro + " " + root_header).strip()
        if intro:
            lines += [intro, ""]
        rows = list(settings(n.section))
        extra = extra_setting(n.section)
        lines += [md.table(["key", "type", "default", "bounds, choices", "description"], [
            [f"`{s.name}`" if s is not extra else f"*{s.name}*", _md_type(s, anchors), _md_default(s), _md_bounds(s),
             s.doc] for s in rows + ([extra] if extra is not None else [])], text=5), ""]
    return "\n".join(lines), anchors


def _json_default(v: Any) -> Any:
    if isinstance(v, (tuple, list)):
        return [_json_default(x) for x in v]
    if isinstance(v, Mapping):
        return {k: _json_default(x) for k, x in v.items()}
    return v


def _json_property(s: Setting, ref: Callable[[type], str]) -> dict[str, Any]:
    """The JSON Schema of one setting's value."""
    bounds = {"minimum": s.ge, "exclusiveMinimum": s.gt, "maximum": s.le}
    j: dict[str, Any]
    if s.type in ("int", "float"):
        j = {"type": "integer" if s.type == "int" else "number"}
        j.update({k: b for k, b in bounds.items() if b is not None})
    elif s.type == "str":
        j = {"type": "string"}
        if s.pattern is not None:
            j["pattern"] = f"^(?:{s.pattern})$"
    elif s.type == "bool":
        j = {"type": "boolean"}
    elif s.type == "seeds":
        j = {"oneOf": [{"type": "integer", "minimum": 1, "maximum": MAX_SEED_COUNT},
                       {"type": "array", "minItems": 1, "uniqueItems": True,
                        "items": {"type": "integer", "minimum": 0, "maximum": MAX_SEED - 1}}]}
    elif s.type == "strings":
        j = {"type": "array", "items": {"type": "string"}}
        if s.options() is not None:
            j["items"]["enum"] = list(s.options())
        if s.nonempty:
            j["minItems"] = 1
    elif s.type == "table":
        j = {"type": "object"}
        if s.allowed_keys() is not None:
            j["propertyNames"] = {"enum": list(s.allowed_keys())}
        if s.values is not None:
            j["additionalProperties"] = _json_property(dataclasses.replace(s.values, doc=""), ref)
    elif s.type == "section":
        j = {"allOf": [{"$ref": ref(s.section)}]}
    elif s.type == "tables":
        j = {"type": "array", "items": {"$ref": ref(s.section)}}
        if s.nonempty:
            j["minItems"] = 1
    else:
        j = dict(s.json or {})
    if s.type in ("int", "float", "str") and s.options() is not None:
        j["enum"] = list(s.options())
    doc = s.doc + (f" (default: {s.default_text})" if s.default_text else "")
    if doc:
        j["description"] = doc
    if not s.default_text and s.default is not UNSET and s.default is not None:
        j["default"] = _json_default(s.default)
    return j


def _json_object(cls: type, ref: Callable[[type], str]) -> dict[str, Any]:
    """The JSON Schema of one section's table (``when`` settings become if/then rules)."""
    specs = settings(cls)
    extra = extra_setting(cls)
    j: dict[str, Any] = {"type": "object"}
    doc = _first_paragraph(cls)
    if doc:
        j["description"] = doc
    j["properties"] = {s.name: _json_property(s, ref) for s in specs}
    required = [s.name for s in specs if s.required]
    if required:
        j["required"] = required
    if extra is None:
        j["additionalProperties"] = False
    else:
        j["additionalProperties"] = _json_property(dataclasses.replace(extra, doc=""), ref)
        if extra.allowed_keys() is not None:
            j["propertyNames"] = {"enum": [s.name for s in specs] + list(extra.allowed_keys())}
    rules = []
    for key in dict.fromkeys(s.when[0] for s in specs if s.when is not None):
        sib = next(s for s in specs if s.name == key)
        for v in sib.options() or ():
            names = [s.name for s in specs if s.when is None or (s.when[0] == key and v in s.when[1])]
            rules.append({"if": {"properties": {key: {"const": v}}, "required": [key]},
                          "then": {"propertyNames": {"enum": names}}})
    if rules:
        j["allOf"] = rules
    j.update(getattr(cls, "schema_json", None) or {})
    return j


def json_schema(root: type, title: str, *, schema_id: str | None = None) -> dict[str, Any]:
    """A JSON Schema (draft-07) of the TOML files described by section ``root``, for editors.

    Nested sections are ``definitions`` named after their dataclass, referenced where they are used."""
    defs: dict[str, Any] = {}

    def ref(cls: type) -> str:
        return f"#/definitions/{cls.__name__}"

    for n in _tree(root)[1:]:
        defs[n.section.__name__] = _json_object(n.section, ref)
    out: dict[str, Any] = {"$schema": "http://json-schema.org/draft-07/schema#"}
    if schema_id:
        out["$id"] = schema_id
    out["title"] = title
    out.update(_json_object(root, ref))
    out["definitions"] = defs
    return out
