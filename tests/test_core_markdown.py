"""The Markdown toolkit (`jaxplan.core.markdown`): numbers, "mean ± sd" cells, intervals, tables, links, headings."""

from __future__ import annotations

import math

import pytest

from jaxplan.core import markdown as md


def test_fmt_significant_digits_missing_and_infinite():
    assert md.fmt(3.14159265) == "3.142"
    assert md.fmt(0.000123456, 3) == "0.000123"
    assert md.fmt(12345678.0) == "1.235e+07"
    assert md.fmt(7) == "7"
    assert md.fmt(None) == md.fmt(math.nan) == md.MISSING == "–"
    assert (md.fmt(math.inf), md.fmt(-math.inf)) == ("∞", "−∞")


def test_pm_drops_an_unknown_sd_and_shows_a_missing_mean_once():
    assert md.pm(2.0, 0.5) == "2 ± 0.5"
    assert md.pm(2.0, 0.0) == "2 ± 0"
    for sd in (None, math.nan, math.inf):
        assert md.pm(2.0, sd) == "2"
    assert md.pm(None, 1.0) == md.pm(math.nan, math.nan) == "–"
    # the mean and the sd each through their own formatter (e.g. a unit scale, a noise floor)
    assert md.pm(1.5, 0.25, lambda x: f"{x * 100:g}", lambda s: f"{s:.1f}") == "150 ± 0.2"


def test_interval_needs_both_ends_finite():
    assert md.interval(1.0, 2.5) == "[1, 2.5]"
    assert md.interval(1.0, math.nan) == md.interval(None, 2.0) == md.interval(-math.inf, 0.0) == "–"
    assert md.interval(0.5, 0.75, lambda x: f"{x:.0%}") == "[50%, 75%]"


def test_table_aligns_labels_left_numbers_right_and_escapes_cells():
    t = md.table(["planner", "length (m)", "verdict"], [["A|B", "1.5", "ok\nfine"]], last_text=True)
    assert t.splitlines() == ["| planner | length (m) | verdict |", "| --- | ---: | --- |",
                              "| A\\|B | 1.5 | ok fine |"]
    assert md.table(["a", "b", "c"], [], text=2).splitlines()[1] == "| --- | --- | ---: |"
    assert md.table(["a", "b"], [["1", "2"]], align="rl").splitlines()[1] == "| ---: | --- |"


def test_table_refuses_a_ragged_row_or_a_bad_alignment():
    with pytest.raises(ValueError, match="2 columns"):
        md.table(["a", "b"], [["1"]])
    with pytest.raises(ValueError, match="per column"):
        md.table(["a", "b"], [], align="l")
    with pytest.raises(ValueError, match="per column"):
        md.table(["a"], [], align="c")


def test_links_images_headings_and_slugs():
    assert md.link("cui2025_table2", "cui2025/table2.md") == "[cui2025_table2](cui2025/table2.md)"
    assert md.image("fig", "../figures/a.png") == "![fig](../figures/a.png)"
    assert md.heading("Setup", 3) == "### Setup"
    with pytest.raises(ValueError):
        md.heading("x", 7)
    assert md.slug("`[experiment.quick]`") == "experimentquick"
    assert md.slug("Experiment configs: top level") == "experiment-configs-top-level"
