"""`jaxplan plan` and `jaxplan navigate`: seeds, ``--set`` planner parameters, smoothing, ``--out`` files, and why a
failed plan failed (issue 30)."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from jaxplan.cli import main
from jaxplan.cli.args import literal, parse_sets

MAP = "type octile\nheight 8\nwidth 10\nmap\n..........\n..........\n..@@@@....\n.....@....\n.....@....\n" \
      "..........\n..........\n..........\n"
WALLED = "type octile\nheight 5\nwidth 7\nmap\n...@...\n...@...\n...@...\n...@...\n...@...\n"


@pytest.fixture
def small_map(tmp_path):
    p = tmp_path / "small.map"
    p.write_text(MAP)
    return p


def test_set_values_are_read_as_python_literals():
    assert literal("64") == 64 and literal("0.5") == 0.5 and literal("geodesic") == "geodesic"
    assert literal("true") is True and literal("None") is None and literal("0.6,0.3,0.1") == (0.6, 0.3, 0.1)
    assert parse_sets(["ants=64", "heuristic=geodesic", "ants=8"]) == {"ants": 8, "heuristic": "geodesic"}
    with pytest.raises(ValueError, match="KEY=VALUE"):
        parse_sets(["ants"])


@pytest.mark.parametrize("argv, words", [
    (["--planner", "iaco", "--set", "antz=4"], ["--set antz=4", "no parameter 'antz'", "did you mean 'ants'"]),
    (["--planner", "iaco", "--set", "rho=3"], ["--set rho=3", "'rho'", "[0, 1]"]),
    (["--planner", "iaco", "--set", "ants=0"], ["ants", "positive integer"]),
    (["--planner", "iaco", "--set", "heuristic=geodesik"], ["heuristic"]),
    (["--planner", "iacoo"], ["'iacoo' is not a planner", "did you mean 'iaco'"]),
    (["--set", "ants"], ["KEY=VALUE"]),
    (["--out", "x.txt"], ["--out", ".json"]),
])
def test_bad_planner_parameters_exit_2_naming_the_key_and_value(small_map, capsys, argv, words):
    rc = main(["plan", str(small_map), "--start", "0", "0", "--goal", "9", "7", *argv])
    err = capsys.readouterr().err
    assert rc == 2, err
    for w in words:
        assert w in err, err


def test_plan_out_json_has_the_path_in_cells_and_metres_metrics_parameters_and_provenance(small_map, tmp_path,
                                                                                           capsys):
    out = tmp_path / "path.json"
    rc = main(["plan", str(small_map), "--start", "0", "0", "--goal", "9", "7", "--planner", "iaco", "--seed", "3",
               "--set", "ants=8", "--set", "iterations=4", "--set", "heuristic=geodesic", "--resolution", "0.5",
               "--smooth", "los", "--out", str(out)])
    assert rc == 0, capsys.readouterr().err
    rec = json.loads(out.read_text())
    assert rec["planner"] == "iaco" and rec["seed"] == 3 and rec["success"] is True
    assert rec["parameters"]["ants"] == 8 and rec["parameters"]["heuristic"] == "geodesic"
    assert rec["parameters"]["lambdas"] == [0.5, 0.3, 0.2]  # the defaults too
    assert rec["overrides"] == {"ants": 8, "iterations": 4, "heuristic": "geodesic"}
    cells = np.asarray(rec["path_cells"])
    assert cells[0].tolist() == [0, 0] and cells[-1].tolist() == [9, 7]
    np.testing.assert_allclose(rec["path_m"], (cells + 0.5) * 0.5)
    assert len(rec["history"]) == 4 and rec["iterations"] == 4
    assert rec["metrics"]["length"] == pytest.approx(rec["length_m"])
    assert rec["smoothed"]["method"] == "los" and len(rec["smoothed"]["points_cells"]) <= len(cells)
    assert rec["metrics"]["smoothed_length"] <= rec["length_m"] + 1e-9
    assert rec["provenance"]["versions"]["jax"] and "git_revision" in rec["provenance"]
    # The same seed gives the same path.
    again = tmp_path / "again.json"
    main(["plan", str(small_map), "--start", "0", "0", "--goal", "9", "7", "--planner", "iaco", "--seed", "3",
          "--set", "ants=8", "--set", "iterations=4", "--set", "heuristic=geodesic", "--resolution", "0.5",
          "--smooth", "los", "--out", str(again)])
    assert json.loads(again.read_text())["path_cells"] == rec["path_cells"]


def test_plan_out_png_and_csv(small_map, tmp_path, capsys):
    png, table = tmp_path / "path.png", tmp_path / "path.csv"
    for out in (png, table):
        rc = main(["plan", str(small_map), "--start", "0", "0", "--goal", "9", "7", "--out", str(out)])
        assert rc == 0, capsys.readouterr().err
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 2000
    rows = list(csv.DictReader(table.open()))
    assert list(rows[0]) == ["step", "x", "y", "x_m", "y_m"]
    assert (rows[0]["x"], rows[0]["y"], rows[-1]["x"], rows[-1]["y"]) == ("0", "0", "9", "7")
    assert float(rows[-1]["x_m"]) == 9.5


def test_a_failed_plan_says_why(tmp_path, capsys):
    walled = tmp_path / "walled.map"
    walled.write_text(WALLED)
    out = tmp_path / "fail.json"
    rc = main(["plan", str(walled), "--start", "0", "0", "--goal", "6", "4", "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 1 and "unreachable" in err
    rec = json.loads(out.read_text())
    assert rec["success"] is False and rec["length_m"] is None and "unreachable" in rec["failure"]


def test_a_failed_colony_reports_its_iterations_ants_and_what_to_try(movingai, capsys):
    rc = main(["plan", str(movingai / "maze-32-32-2.map"), "--start", "11", "13", "--goal", "19", "31", "--planner",
               "aco", "--set", "ants=2", "--set", "iterations=2", "--set", "max_steps=10", "--set", "dead_end=die"])
    err = capsys.readouterr().err
    assert rc == 1
    for w in ("reachable", "exact shortest path", "no ant of 2", "2 iterations", "dead_end=retreat", "max_steps"):
        assert w in err, err


def test_navigate_out_json_and_gif(small_map, tmp_path, capsys):
    js, gif = tmp_path / "episode.json", tmp_path / "episode.gif"
    for out in (js, gif):
        rc = main(["navigate", str(small_map), "--start", "0", "0", "--goal", "9", "7", "--pipeline", "astar_kng_dwa",
                   "--walkers", "1", "--seed", "1", "--out", str(out)])
        assert rc in (0, 1), capsys.readouterr().err
    rec = json.loads(js.read_text())
    assert rec["pipeline"] == "astar_kng_dwa" and rec["walkers"]["n"] == 1
    ep = rec["episode"]
    assert len(ep["trajectory"]) == len(ep["controls"]) + 1 and len(ep["trajectory"][0]) == 3
    assert ep["reason"] in ("goal", "collision", "time limit")
    assert len(ep["obstacles"]["radii"]) == 1
    assert gif.read_bytes()[:6] in (b"GIF89a", b"GIF87a")


def test_navigate_rejects_a_bad_pipeline_and_suffix(small_map, capsys):
    assert main(["navigate", str(small_map), "--start", "0", "0", "--goal", "9", "7", "--pipeline", "nope"]) == 2
    assert "not a pipeline" in capsys.readouterr().err
    assert main(["navigate", str(small_map), "--start", "0", "0", "--goal", "9", "7", "--out", "e.mp4"]) == 2
    assert ".gif" in capsys.readouterr().err


def _readme_plan_commands() -> list[list[str]]:
    """The README's ``jaxplan plan ... --out FILE`` commands (continuation lines joined, comments dropped)."""
    import shlex

    from conftest import ROOT

    text = (ROOT / "README.md").read_text().replace("\\\n", " ")
    found = []
    for line in text.splitlines():
        line = line.strip()
        if line.startswith("jaxplan plan ") and "--out" in line:
            found.append(shlex.split(line, comments=True)[1:])
    return found


def test_the_readme_plan_commands_write_their_json_and_png(movingai, tmp_path, capsys):
    """Every ``jaxplan plan ... --out`` line of the README runs, with its output redirected to a temporary folder
    and its map path read from the repository root (README paths are relative to it)."""
    from conftest import ROOT

    commands = _readme_plan_commands()
    if not commands:
        pytest.skip("the README shows no `jaxplan plan ... --out` command yet")
    suffixes = set()
    for argv in commands:
        k = argv.index("--out")
        out = tmp_path / Path(argv[k + 1]).name
        argv = [*argv[:k + 1], str(out), *argv[k + 2:]]
        argv[1] = str((ROOT / argv[1]).resolve()) if not Path(argv[1]).is_absolute() else argv[1]
        assert main(argv) == 0, capsys.readouterr().err
        assert out.stat().st_size > 0
        suffixes.add(out.suffix)
        if out.suffix == ".json":
            assert json.loads(out.read_text())["success"] is True
    assert {".json", ".png"} <= suffixes
