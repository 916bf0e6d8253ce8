"""MovingAI map and scenario I/O: real files, round trips, malformed input, fuzzing."""

from __future__ import annotations

import re

import numpy as np
import pytest
from conftest import manifest, scenario_pairs
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import jaxplan as jp
from jaxplan.grid import parse_map, parse_scenarios

HEADER = "type octile\nheight {h}\nwidth {w}\nmap\n"


def test_every_shared_map_and_scenario_file_loads_with_its_manifest_size(movingai):
    for row in manifest(movingai):
        path = movingai / row["file"]
        if row["file"].endswith(".map"):
            g = jp.load_map(path)
            assert g.shape == (int(row["height"]), int(row["width"]))
            assert g.free.any() and (~g.free).any()
        else:
            s = jp.load_scenarios(path)
            # The manifest counts the lines after the version line; den520d's and ost003d's files end in blank
            # lines, which are no rows.
            blank = sum(not ln.strip() for ln in path.read_text().splitlines()[1:])
            assert len(s) == int(row["scenario_rows"]) - blank
            assert (s.width, s.height) == (int(row["width"]), int(row["height"]))


def test_scenarios_checked_against_their_maps(movingai):
    for m, sc in scenario_pairs(movingai):
        g = jp.load_map(m)
        s = jp.load_scenarios(sc, grid=g)
        assert g.free[s.starts[:, 1], s.starts[:, 0]].all() and g.free[s.goals[:, 1], s.goals[:, 0]].all()


def test_parse_map_reads_characters_and_orientation():
    text = HEADER.format(h=2, w=4) + ".G@T\nSOW.\n"
    g = parse_map(text, resolution=0.5)
    np.testing.assert_array_equal(g.free, [[1, 1, 0, 0], [1, 0, 0, 1]])
    assert g.resolution == 0.5 and g.shape == (2, 4)


def test_save_map_round_trip(tmp_path, rng):
    free = rng.random((7, 11)) > 0.3
    g = jp.grid_from_array(free)
    p = tmp_path / "m.map"
    jp.save_map(g, p)
    np.testing.assert_array_equal(jp.load_map(p).free, free)
    assert not list(tmp_path.glob("*.tmp"))


@pytest.mark.parametrize(
    "text, message",
    [
        ("type grid\nheight 1\nwidth 1\nmap\n.\n", "expected 'type octile'"),
        ("type octile\nheight x\nwidth 1\nmap\n.\n", "'height' must be an integer"),
        ("type octile\nwidth 1\nheight 1\nmap\n.\n", "expected 'height <integer>'"),
        ("type octile\nheight 2\nwidth 2\nmap\n..\n", "header says height 2 but 1 map rows follow"),
        ("type octile\nheight 1\nwidth 3\nmap\n..\n", "row 0 has 2 characters, header says width 3"),
        ("type octile\nheight 1\nwidth 2\nmap\n.x\n", "unknown map character 'x' at column 1"),
        ("type octile\nheight 1\nwidth 1\nmop\n.\n", "expected 'map'"),
        ("type octile\n", "needs 4 header lines"),
    ],
)
def test_malformed_maps_name_the_problem(text, message):
    with pytest.raises(ValueError, match=message):
        parse_map(text, where="bad.map")


def test_missing_file_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError, match="map file not found"):
        jp.load_map(tmp_path / "nope.map")
    with pytest.raises(FileNotFoundError, match="scenario file not found"):
        jp.load_scenarios(tmp_path / "nope.scen")


SCEN_OK = "version 1\n0\tm.map\t4\t3\t0\t0\t3\t2\t3.82842712\n1\tm.map\t4\t3\t1\t0\t1\t2\t2\n"


def test_parse_scenarios_fields():
    s = parse_scenarios(SCEN_OK)
    np.testing.assert_array_equal(s.starts, [[0, 0], [1, 0]])
    np.testing.assert_array_equal(s.goals, [[3, 2], [1, 2]])
    np.testing.assert_allclose(s.optimal, [3.82842712, 2.0])
    np.testing.assert_array_equal(s.buckets, [0, 1])
    assert (s.map_name, s.width, s.height) == ("m.map", 4, 3)
    assert len(s.select(s.buckets == 1)) == 1


@pytest.mark.parametrize(
    "text, message",
    [
        ("0\tm.map\t4\t3\t0\t0\t3\t2\t1\n", "expected a 'version' line"),
        ("version one\n", "version must be a number"),
        ("version 1\n", "no scenario rows"),
        ("version 1\n0\tm.map\t4\t3\t0\t0\t3\t2\n", "expected 9 fields"),
        ("version 1\n0\tm.map\t4\t3\t0\ta\t3\t2\t1\n", "non-numeric field"),
        ("version 1\n0\tm.map\t4\t3\t0\t0\t4\t2\t1\n", r"goal \(4, 2\) lies outside the 4x3 map"),
        ("version 1\n0\tm.map\t4\t3\t0\t-1\t3\t2\t1\n", r"start \(0, -1\) lies outside"),
        ("version 1\n0\tm.map\t4\t3\t0\t0\t3\t2\tnan\n", "optimal length must be finite"),
        ("version 1\n0\tm.map\t4\t3\t0\t0\t3\t2\t1\n0\tm.map\t5\t3\t0\t0\t3\t2\t1\n", "differs from the first row"),
    ],
)
def test_malformed_scenarios_name_the_problem(text, message):
    with pytest.raises(ValueError, match=message):
        parse_scenarios(text, where="bad.scen")


def test_scenarios_against_a_map_reject_blocked_cells_and_size():
    g = jp.grid_from_array(np.array([[1, 0, 1, 1], [1, 1, 1, 1], [1, 1, 1, 1]], bool))
    with pytest.raises(ValueError, match=r"row 2: start \(1, 0\) is on a blocked cell"):
        parse_scenarios(SCEN_OK, grid=g)
    with pytest.raises(ValueError, match="scenarios are for a 4x3 map, the map is 3x3"):
        parse_scenarios(SCEN_OK, grid=jp.grid_from_array(np.ones((3, 3), bool)))


@settings(max_examples=300, suppress_health_check=[HealthCheck.too_slow], deadline=None)
@given(st.text(alphabet=st.sampled_from(list(".@GSOTWx \t\n0123456789typeoctilhgwdmap")), max_size=200))
def test_fuzz_parse_map_only_raises_value_error(text):
    try:
        g = parse_map(text)
    except ValueError:
        return
    assert g.free.ndim == 2


@settings(max_examples=200, suppress_health_check=[HealthCheck.too_slow], deadline=None)
@given(
    st.integers(1, 6), st.integers(1, 6), st.data(),
)
def test_fuzz_parse_map_mutated_valid_files(h, w, data):
    rows = ["".join(data.draw(st.sampled_from(".@GSOTW")) for _ in range(w)) for _ in range(h)]
    text = HEADER.format(h=h, w=w) + "\n".join(rows) + "\n"
    g = parse_map(text)
    np.testing.assert_array_equal(g.free, [[c in ".GS" for c in r] for r in rows])
    # One random edit: the parser either still agrees with a re-parse or names a ValueError.
    pos = data.draw(st.integers(0, len(text) - 1))
    ch = data.draw(st.sampled_from(list("x.@\n 9")))
    mutated = text[:pos] + ch + text[pos + 1 :]
    try:
        parse_map(mutated)
    except ValueError:
        pass


@settings(max_examples=300, suppress_health_check=[HealthCheck.too_slow], deadline=None)
@given(st.text(alphabet=st.sampled_from(list("version 0123456789.\t\nm-a-p.-e")), max_size=200))
def test_fuzz_parse_scenarios_only_raises_value_error(text):
    try:
        s = parse_scenarios(text)
    except ValueError:
        return
    assert s.starts.shape == s.goals.shape and len(s.optimal) == len(s.starts)


@pytest.mark.parametrize("ch", ["\x0b", "\x0c", "\x1c", "\x1d", "\x1e", "\x85"])
def test_control_characters_do_not_split_map_rows(ch):
    # One physical row of 7 characters is not two rows of 3 (str.splitlines would split it).
    with pytest.raises(ValueError, match=re.escape(f"bad.map:5: unknown map character {ch!r} at column 3")):
        parse_map(f"type octile\nheight 2\nwidth 3\nmap\n.@.{ch}...\n", where="bad.map")
    # Line numbers after it stay right; Windows line ends are still fine.
    with pytest.raises(ValueError, match=r"bad.map:6: row 1 has 4 characters"):
        parse_map(f"type octile\r\nheight 2\r\nwidth 3\r\nmap\r\n.@.\r\n..{ch}.\r\n".replace(ch, "."), where="bad.map")
    assert parse_map("type octile\r\nheight 2\r\nwidth 3\r\nmap\r\n.@.\r\n...\r\n").shape == (2, 3)


def test_control_characters_do_not_split_scenario_rows():
    text = "version 1\n0\tm.map\t4\t3\t0\t0\t3\t2\t1\x0c1\n0\tm.map\t4\t3\t0\tz\t3\t2\t1\n"
    with pytest.raises(ValueError, match=r"bad.scen:2: non-numeric field"):
        parse_scenarios(text, where="bad.scen")
    text = "version 1\n0\tm.map\t4\t3\t0\t0\t3\t2\t1\x0c\n0\tm.map\t4\t3\t0\tz\t3\t2\t1\n"
    with pytest.raises(ValueError, match=r"bad.scen:3: non-numeric field"):
        parse_scenarios(text, where="bad.scen")
