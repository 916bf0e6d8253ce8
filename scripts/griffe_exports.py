"""Griffe extension for the API reference (``mkdocs.yml``): lazily re-exported names at their public paths.

``jaxplan`` and some of its subpackages re-export their public names lazily (PEP 562 ``__getattr__`` over a table
such as ``jaxplan._EXPORTS``: subpackage -> names), which a static reading of the ``__init__.py`` cannot see. For
every module of the loaded package that has such a table, this extension imports the module (a lazy
``__init__`` loads nothing heavy) and adds each listed name as an alias of the module it comes from. So the API
pages cite public paths (``::: jaxplan.plan_batch``) and keep working when a name moves between subpackages:
the table moves with it.
"""

from __future__ import annotations

import importlib
from typing import Any

from griffe import Alias, Extension

TABLES = ("_EXPORTS", "_SOURCE")
"""Names of the lazy export tables: ``{module: (name, ...)}`` or ``{name: module}``, modules relative to the
package."""


def lazy_exports(module_path: str) -> dict[str, str]:
    """``{public name: "<module_path>.<module>.<name>"}`` from the lazy export table of ``module_path`` (empty when it
    has none)."""
    module = importlib.import_module(module_path)
    out: dict[str, str] = {}
    for attr in TABLES:
        table = getattr(module, attr, None)
        if not isinstance(table, dict):
            continue
        for key, value in table.items():
            pairs = [(name, key) for name in value] if isinstance(value, tuple) else [(key, value)]
            for name, source in pairs:
                if isinstance(name, str) and isinstance(source, str):
                    out.setdefault(name, f"{module_path}.{source}.{name}")
    return out


class JaxplanExports(Extension):
    """Adds ``<package>.NAME`` aliases for lazily re-exported public names."""

    def on_package(self, *, pkg: Any, **kwargs: Any) -> None:
        if pkg.path.split(".")[0] != "jaxplan":
            return
        self._visit(pkg)

    def _visit(self, module: Any) -> None:
        if module.is_init_module and "__getattr__" in module.members:
            for name, target in lazy_exports(module.path).items():
                if target.startswith(f"{module.path}.{name}."):
                    continue  # a name defined in a submodule of its own name: the submodule is the way to it
                # a module of the same name (``jaxplan.smooth``, the previous release's module name) gives way to
                # the public name, as at run time
                module.set_member(name, Alias(name, target, parent=module))
        for sub in list(module.members.values()):
            if not sub.is_alias and sub.is_module:  # its own submodules, not imported modules
                self._visit(sub)
