"""ROS maps outside the planners (issue 30 review): an experiment config and the CLI keep a ROS map's own
resolution unless one is given, and every figure and export puts cells in world metres with the map's origin
(`GridMap.centre`), while a map without an origin gives the same numbers as before; Nav2's keep-out and speed
masks come from configs and the CLI as from `load_map`."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from conftest import data_dir

import jaxplan as jp
from jaxplan.cli import main
from jaxplan.experiments.config import ConfigError, parse_config
from jaxplan.experiments.prepare import load_map_spec

ORIGIN = (-3.25, 7.5)
RES = 0.25


def _ros_map(folder: Path, origin=ORIGIN, res: float = RES) -> Path:
    """A 12 x 8 ROS map (P5) with a wall, at ``res`` m per cell and ``origin``."""
    free = np.ones((8, 12), bool)
    free[2:7, 5] = False
    grid = jp.grid_from_array(free, resolution=res, origin=origin)
    path = folder / "room.yaml"
    jp.save_map(grid, path)
    return path


MOVINGAI = "type octile\nheight 4\nwidth 6\nmap\n......\n..@@..\n......\n......\n"


def _config(map_lines: str) -> str:
    return f"""
[experiment]
name = "ros-frames"
seeds = 1

[[maps]]
{map_lines}
scenarios = {{ source = "random", count = 2, seed = 0, min_distance = 0.5 }}

[[planners]]
kind = "plan"
name = "astar"
"""


# ---------------------------------------------------------------------------------------------
# 1. Experiment configs: a ROS map keeps its own resolution unless one is given


def test_a_config_keeps_a_ros_maps_own_resolution_unless_one_is_given(tmp_path):
    _ros_map(tmp_path)
    cfg = parse_config(_config('path = "room.yaml"'), data_dir=tmp_path)
    assert cfg.maps[0].resolution is None
    grid = load_map_spec(cfg.maps[0])[0]
    assert grid.resolution == RES and grid.shape == (8, 12) and grid.origin == ORIGIN
    coarse = parse_config(_config('path = "room.yaml"\nresolution = 0.5'), data_dir=tmp_path)
    grid = load_map_spec(coarse.maps[0])[0]
    assert grid.resolution == 0.5 and grid.shape == (4, 6) and grid.origin == ORIGIN


def test_a_config_still_gives_movingai_and_generated_maps_one_metre(tmp_path):
    (tmp_path / "m.map").write_text(MOVINGAI)
    cfg = parse_config(_config('path = "m.map"'), data_dir=tmp_path)
    assert cfg.maps[0].resolution == 1.0 and load_map_spec(cfg.maps[0])[0].resolution == 1.0
    gen = parse_config(_config('generator = "random"\nparams = { width = 10, height = 8 }'), data_dir=tmp_path)
    assert gen.maps[0].resolution == 1.0 and load_map_spec(gen.maps[0])[0].resolution == 1.0


def test_the_config_reference_documents_both_defaults():
    from jaxplan import config_reference

    text = config_reference.reference_markdown()
    assert "1.0 for a MovingAI or generated map; a ROS map's own" in text


# ---------------------------------------------------------------------------------------------
# 2. World coordinates everywhere


def test_plot_extent_and_paths_are_in_world_metres_with_the_origin():
    from jaxplan.experiments import plots

    free = np.ones((4, 6), bool)
    g0 = jp.grid_from_array(free, resolution=RES)
    g = jp.grid_from_array(free, resolution=RES, origin=ORIGIN)
    assert plots._extent(g0) == (0.0, 6 * RES, 4 * RES, 0.0)
    assert plots._extent(g) == (ORIGIN[0], ORIGIN[0] + 6 * RES, ORIGIN[1] + 4 * RES, ORIGIN[1])
    fig, ax = plots.plt.subplots()
    plots.plot_map(ax, g)
    plots.plot_paths(ax, g, [np.array([[0, 0], [5, 3]])], labels=["p"], start=np.array([0, 0]))
    assert ax.get_xlim() == (ORIGIN[0], ORIGIN[0] + 6 * RES)
    np.testing.assert_array_equal(ax.lines[0].get_xydata(), g.centre([[0, 0], [5, 3]]))
    np.testing.assert_array_equal(ax.lines[0].get_xydata()[0], np.add(ORIGIN, 0.5 * RES))
    plots.plt.close(fig)


def test_run_figures_put_cells_at_their_world_centres():
    from jaxplan.experiments.run_data import cell_path_m

    g = jp.grid_from_array(np.ones((4, 6), bool), resolution=RES, origin=ORIGIN)
    pts = np.array([[0, 0], [2, 1], [-1, -1]])
    np.testing.assert_array_equal(cell_path_m(pts, 2, g), np.add(ORIGIN, (pts[:2] + 0.5) * RES))


def test_plan_out_json_csv_and_png_use_the_origin(tmp_path, capsys):
    yaml = _ros_map(tmp_path)
    out = tmp_path / "p.json"
    assert main(["plan", str(yaml), "--start", "0", "0", "--goal", "11", "7", "--out", str(out), "--no-progress"]) == 0
    rec = json.loads(out.read_text())
    assert rec["map"]["resolution_m"] == RES and rec["map"]["origin_m"] == list(ORIGIN)
    cells = np.asarray(rec["path_cells"])
    np.testing.assert_allclose(rec["path_m"], np.add(ORIGIN, (cells + 0.5) * RES), rtol=0, atol=1e-12)
    assert main(["plan", str(yaml), "--start", "0", "0", "--goal", "11", "7", "--out", str(tmp_path / "p.csv"),
                 "--no-progress"]) == 0
    rows = list(csv.DictReader((tmp_path / "p.csv").open()))
    assert float(rows[0]["x_m"]) == ORIGIN[0] + 0.5 * RES and float(rows[0]["y_m"]) == ORIGIN[1] + 0.5 * RES
    capsys.readouterr()


def test_plan_keeps_a_ros_maps_resolution_by_default_and_resamples_with_resolution(tmp_path, capsys):
    yaml = _ros_map(tmp_path)
    for argv, res in (([], RES), (["--resolution", "0.5"], 0.5)):
        out = tmp_path / "p.json"
        assert main(["plan", str(yaml), "--start", "0", "0", "--goal", "3", "3", "--out", str(out),
                     "--no-progress", *argv]) == 0, capsys.readouterr().err
        rec = json.loads(out.read_text())
        assert rec["map"]["resolution_m"] == res and rec["map"]["origin_m"] == list(ORIGIN)


def test_plan_and_navigate_help_document_the_resolution_default(capsys):
    for cmd in ("plan", "navigate"):
        with pytest.raises(SystemExit):
            main([cmd, "--help"])
        text = " ".join(capsys.readouterr().out.split())
        assert "a ROS .yaml map keeps its own" in text and "1.0 for a MovingAI .map" in text


def test_navigate_out_json_is_in_world_metres_and_walkers_avoid_the_world_start(tmp_path, capsys):
    yaml = _ros_map(tmp_path, res=1.0)
    out = tmp_path / "e.json"
    main(["navigate", str(yaml), "--start", "0", "0", "--goal", "11", "7", "--walkers", "2", "--out", str(out),
          "--no-progress", "--time-limit", "5", "--walker-radius", "0.1"])
    rec = json.loads(out.read_text())
    assert rec["resolution_m"] == 1.0 and rec["origin_m"] == list(ORIGIN)
    traj = np.asarray(rec["episode"]["trajectory"], np.float64)
    np.testing.assert_allclose(traj[0, :2], np.add(ORIGIN, 0.5), atol=1e-5)
    discs = np.asarray(rec["episode"]["obstacle_positions"], np.float64)[0]  # [M, 2] at t = 0, world
    assert (np.hypot(*(discs - traj[0, :2]).T) >= 1.5 + 0.1 - 1e-6).all()
    capsys.readouterr()


# ---------------------------------------------------------------------------------------------
# Nav2 filter masks from configs and the command line: a ROS map's keep-out and speed masks given in an
# experiment's [[maps]] entry or to `jaxplan plan`/`navigate` load exactly as `load_map` loads them, the map's
# digest covers every file read, and masks on a map that cannot have them are refused by name.

COARSE = 0.3  # coarse cells keep Nav2's full warehouse (0.03 m) small: 10x10 image pixels per cell


def _mask_spec(ros: Path, entry: str):
    return parse_config(_config(entry), data_dir=ros.parent).maps[0]


def test_a_maps_entry_loads_the_masks_as_load_map_does(ros):
    spec = _mask_spec(ros, f'path = "ros/warehouse.yaml"\nresolution = {COARSE}\n'
                           'keepout = "ros/warehouse_keepout.yaml"\nspeed_mask = "ros/warehouse_speed.yaml"')
    grid, _, _, digest = load_map_spec(spec)
    want = jp.load_map(ros / "warehouse.yaml", resolution=COARSE, keepout=ros / "warehouse_keepout.yaml",
                       speed=ros / "warehouse_speed.yaml")
    np.testing.assert_array_equal(np.asarray(grid.free), np.asarray(want.free))
    np.testing.assert_array_equal(np.asarray(grid.speed_limit), np.asarray(want.speed_limit))
    plain, _, _, plain_digest = load_map_spec(_mask_spec(ros, f'path = "ros/warehouse.yaml"\nresolution = {COARSE}'))
    assert plain.speed_limit is None
    # the keep-out zones block cells that the plain map leaves free, and the digest tells the two maps apart
    assert int(np.sum(np.asarray(plain.free) & ~np.asarray(grid.free))) > 0
    assert digest != plain_digest
    assert float(np.min(np.asarray(grid.speed_limit))) < 1.0


def test_the_digest_covers_the_image_not_only_the_yaml(ros, tmp_path):
    (tmp_path / "ros").mkdir()
    for f in ("warehouse.yaml", "warehouse.pgm"):
        (tmp_path / "ros" / f).write_bytes((ros / f).read_bytes())
    spec = parse_config(_config(f'path = "ros/warehouse.yaml"\nresolution = {COARSE}'), data_dir=tmp_path).maps[0]
    before = load_map_spec(spec)[3]
    img = bytearray((tmp_path / "ros" / "warehouse.pgm").read_bytes())
    img[-1] = 0 if img[-1] else 254  # one pixel changes; the YAML does not
    (tmp_path / "ros" / "warehouse.pgm").write_bytes(bytes(img))
    assert load_map_spec(spec)[3] != before


def test_unknown_and_speed_filter_reach_the_loader(ros):
    spec = _mask_spec(ros, 'path = "ros/warehouse.yaml"\nunknown = "free"\nspeed_mask = "ros/warehouse_speed.yaml"\n'
                      "speed_filter = [2, 0.0, 0.01]\ntop_speed = 2.0")
    assert spec.ros["unknown"] == "free" and spec.ros["speed_filter"] == (2, 0.0, 0.01)
    assert spec.ros["top_speed"] == 2.0 and spec.ros["speed"] == ros / "warehouse_speed.yaml"


@pytest.mark.parametrize("entry, problem", [
    ('path = "movingai/maze-32-32-2.map"\nkeepout = "ros/warehouse_keepout.yaml"',
     "maps[0].keepout: only applies to a ROS map_server map"),
    ('generator = "demo_warehouse"\nunknown = "free"', "maps[0].unknown: only applies to a ROS map_server map"),
    ('path = "ros/warehouse.yaml"\nkeepout = "ros/nowhere.yaml"', "maps[0].keepout: file not found"),
    ('path = "ros/warehouse.yaml"\ntop_speed = 1.0', "maps[0].top_speed: only applies with a speed_mask"),
    ('path = "ros/warehouse.yaml"\nspeed_mask = "ros/warehouse_speed.yaml"\nspeed_filter = [3, 0, 1]',
     "maps[0].speed_filter: expected [type, base, multiplier]"),
    ('path = "ros/warehouse.yaml"\nspeed_mask = "ros/warehouse_speed.yaml"\nspeed_filter = [2, 0.0, 0.01]',
     "maps[0].top_speed: a type 2 speed mask gives metres per second"),
    ('path = "ros/warehouse.yaml"\nunknown = "maybe"', "maps[0].unknown"),
])
def test_mask_problems_are_named(ros, entry, problem):
    with pytest.raises(ConfigError) as ei:
        parse_config(_config(entry), data_dir=ros.parent)
    assert any(problem in p for p in ei.value.problems), ei.value.problems


def test_the_cli_plans_on_the_masked_warehouse_and_records_the_masks(ros, tmp_path, capsys):
    grid = jp.load_map(ros / "warehouse.yaml", resolution=COARSE, keepout=ros / "warehouse_keepout.yaml")
    plain = jp.load_map(ros / "warehouse.yaml", resolution=COARSE)
    ys, xs = np.nonzero(np.asarray(grid.free))
    start, goal = (int(xs[0]), int(ys[0])), (int(xs[-1]), int(ys[-1]))
    keep_out = np.asarray(plain.free) & ~np.asarray(grid.free)
    through = np.asarray(jp.plan(plain, start, goal, planner="astar").path)
    assert keep_out[through[:, 1], through[:, 0]].any()  # the plain map's shortest path crosses a keep-out zone
    out = tmp_path / "plan.json"
    rc = main(["plan", str(ros / "warehouse.yaml"), "--resolution", str(COARSE), "--keepout",
               str(ros / "warehouse_keepout.yaml"), "--start", *map(str, start), "--goal", *map(str, goal),
               "--out", str(out), "--no-progress"])
    assert rc == 0, capsys.readouterr().err
    rec = json.loads(out.read_text())
    assert rec["map"]["options"] == {"keepout": str(ros / "warehouse_keepout.yaml")}
    cells = np.asarray(rec["path_cells"])
    free = np.asarray(grid.free)
    assert free[cells[:, 1], cells[:, 0]].all()  # every cell of the path is outside the keep-out zones
    assert np.asarray(plain.free).sum() > free.sum()


def test_the_cli_refuses_masks_on_a_movingai_map(capsys):
    movingai = data_dir() / "movingai" / "maze-32-32-2.map"
    if not movingai.is_file():
        pytest.skip("MovingAI maps not found")
    rc = main(["plan", str(movingai), "--start", "1", "1", "--goal", "2", "2", "--unknown", "free"])
    assert rc == 2
    assert "apply to ROS maps (.yaml) only" in capsys.readouterr().err


def test_jaxplan_run_plans_on_a_masked_ros_map(ros, tmp_path):
    from jaxplan.experiments.runner import run_experiment

    entry = (f'path = "{ros / "warehouse.yaml"}"\nresolution = {COARSE}\nkeepout = "{ros / "warehouse_keepout.yaml"}"\n'
             f'speed_mask = "{ros / "warehouse_speed.yaml"}"')
    cfg = tmp_path / "masks.toml"
    cfg.write_text(_config(entry))
    run = run_experiment(cfg, tmp_path / "runs", data_dir=ros.parent, progress=False)
    rows = (run / "trials.csv").read_text().splitlines()
    header = rows[0].split(",")
    assert len(rows) == 3 and all(r.split(",")[header.index("success")] in ("1", "True", "true") for r in rows[1:])
