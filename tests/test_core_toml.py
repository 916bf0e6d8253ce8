"""The TOML writer (`jaxplan.core.toml`): what it writes reads back with tomllib to the same values."""

from __future__ import annotations

import math
import tomllib
from types import MappingProxyType

import numpy as np
import pytest

from jaxplan.core import toml


@pytest.mark.parametrize("value, text", [
    (True, "true"), ("even", '"even"'), ('a"b\\c', '"a\\"b\\\\c"'), (3, "3"), (1.5, "1.5"), (1e-06, "1e-06"),
    ([1, 2], "[1, 2]"), (("x",), '["x"]'), ({"a": 1}, "{ a = 1 }"), ({}, "{}"), ({"a b": [1.0]}, '{ "a b" = [1.0] }'),
    (np.float32(0.5), "0.5"), (np.int64(7), "7"), (np.arange(3), "[0, 1, 2]"),
    (MappingProxyType({"n": (1, 2)}), "{ n = [1, 2] }"),
])
def test_literal_writes_one_inline_value(value, text):
    assert toml.literal(value) == text


@pytest.mark.parametrize("value", [0.1, 1e300, -0.0, 2**40, "é\tx\n", [[1, 2], [3]], {"k": {"j": [True, "s"]}}])
def test_literal_reads_back_to_the_same_value(value):
    assert tomllib.loads(f"v = {toml.literal(value)}")["v"] == value


def test_nan_and_infinity_read_back():
    got = tomllib.loads(f"v = {toml.literal([math.nan, math.inf, -math.inf])}")["v"]
    assert math.isnan(got[0]) and got[1:] == [math.inf, -math.inf]


def test_dumps_writes_tables_arrays_of_tables_and_a_comment():
    doc = {"metrics": ("success", "length"), "experiment": {"name": "x", "seeds": np.arange(2)},
           "planners": [{"label": "A", "overrides": MappingProxyType({"ants": 8})}, {"label": "B", "kind": "plan"}]}
    text = toml.dumps(doc, comment="written by a test\n\nsecond line")
    assert text.startswith("# written by a test\n#\n# second line\n")
    assert tomllib.loads(text) == {"metrics": ["success", "length"], "experiment": {"name": "x", "seeds": [0, 1]},
                                   "planners": [{"label": "A", "overrides": {"ants": 8}},
                                                {"label": "B", "kind": "plan"}]}


def test_keys_are_bare_when_they_may_be():
    assert (toml.key("ants"), toml.key("a.b"), toml.key("")) == ("ants", '"a.b"', '""')


@pytest.mark.parametrize("bad", [None, object(), {"a": None}])
def test_a_value_toml_cannot_hold_is_refused(bad):
    with pytest.raises(TypeError, match="TOML"):
        toml.literal(bad)
