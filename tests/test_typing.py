"""Types: jaxplan ships its annotations (PEP 561 ``py.typed``), and every public function of the front door and of
the library subpackages is annotated completely (mypy, configured in pyproject.toml, checks the bodies)."""

from __future__ import annotations

import importlib
import inspect
import tomllib
from pathlib import Path

import pytest

import jaxplan

ROOT = Path(__file__).resolve().parents[1]

# The modules whose public names must be annotated (the set mypy checks, pyproject.toml [tool.mypy]).
CHECKED = ("jaxplan.planning", "jaxplan.registry", "jaxplan.result", "jaxplan.aco", "jaxplan.grid", "jaxplan.metrics",
           "jaxplan.scale", "jaxplan.search", "jaxplan.smoothing", "jaxplan.nav._front")


def _functions(module: str):
    """``(qualified name, function)`` of each public function of ``module`` and each public method of its
    public classes defined in jaxplan."""
    mod = importlib.import_module(module)
    for name in getattr(mod, "__all__", ()):
        obj = getattr(mod, name)
        if inspect.isfunction(obj):
            yield f"{module}.{name}", obj
        elif inspect.isclass(obj) and obj.__module__.startswith("jaxplan"):
            for m, f in vars(obj).items():
                if m.startswith("_") and m != "__call__":
                    continue
                f = f.__func__ if isinstance(f, (staticmethod, classmethod)) else f
                if inspect.isfunction(f):
                    yield f"{module}.{name}.{m}", f


def _missing(fn) -> list[str]:
    sig = inspect.signature(fn)
    out = [p.name for p in sig.parameters.values()
           if p.annotation is inspect.Parameter.empty and p.name not in ("self", "cls")]
    return out + (["return"] if sig.return_annotation is inspect.Signature.empty else [])


@pytest.mark.parametrize("module", CHECKED)
def test_every_public_function_is_annotated(module):
    functions = dict(_functions(module))
    assert functions, module
    bad = {name: miss for name, fn in functions.items() if (miss := _missing(fn))}
    assert not bad, f"not fully annotated: {bad}"


def test_the_front_door_names_are_annotated():
    functions = {n: f for n in jaxplan.__all__ if inspect.isfunction(f := getattr(jaxplan, n))
                 and inspect.unwrap(f).__module__.startswith(CHECKED)}
    assert {"plan", "plan_batch", "navigate", "navigate_batch", "navigate_multi", "smooth", "path_metrics"} <= set(
        functions)
    bad = {n: miss for n, f in functions.items() if (miss := _missing(f))}
    assert not bad, bad


def test_the_annotations_ship_with_the_package():
    assert (ROOT / "jaxplan" / "py.typed").is_file()
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert "py.typed" in config["tool"]["setuptools"]["package-data"]["jaxplan"]
    files = config["tool"]["mypy"]["files"]
    assert all((ROOT / f).exists() for f in files) and {"jaxplan/planning.py", "jaxplan/nav/_front.py"} <= set(files)
