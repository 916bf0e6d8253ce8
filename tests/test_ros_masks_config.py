"""Nav2 filter masks from configs and the command line: a ROS map's keep-out and speed masks given in an
experiment's ``[[maps]]`` entry or to ``jaxplan plan``/``navigate`` load exactly as `load_map` loads them, the
map's digest covers every file read, and masks on a map that cannot have them are refused by name."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import data_dir

import jaxplan as jp
from jaxplan.cli import main
from jaxplan.experiments.config import ConfigError, parse_config
from jaxplan.experiments.prepare import load_map_spec

RES = 0.3  # coarse cells keep the full warehouse (0.03 m) small: 10x10 image pixels per cell


@pytest.fixture(scope="module")
def ros() -> Path:
    d = data_dir() / "ros"
    if not (d / "warehouse.yaml").is_file():
        pytest.skip(f"ROS maps not found at {d} (set JAXPLAN_DATA to the benchmarks folder)")
    return d


def _config(entry: str) -> str:
    return f"""
[experiment]
name = "masks"
seeds = 1

[[planners]]
kind = "plan"
name = "astar"

[[maps]]
{entry}
scenarios = {{ source = "random", count = 2 }}
"""


def _spec(ros: Path, entry: str):
    return parse_config(_config(entry), data_dir=ros.parent).maps[0]


def test_a_maps_entry_loads_the_masks_as_load_map_does(ros):
    spec = _spec(ros, f'path = "ros/warehouse.yaml"\nresolution = {RES}\nkeepout = "ros/warehouse_keepout.yaml"\n'
                      'speed_mask = "ros/warehouse_speed.yaml"')
    grid, _, _, digest = load_map_spec(spec)
    want = jp.load_map(ros / "warehouse.yaml", resolution=RES, keepout=ros / "warehouse_keepout.yaml",
                       speed=ros / "warehouse_speed.yaml")
    np.testing.assert_array_equal(np.asarray(grid.free), np.asarray(want.free))
    np.testing.assert_array_equal(np.asarray(grid.speed_limit), np.asarray(want.speed_limit))
    plain, _, _, plain_digest = load_map_spec(_spec(ros, f'path = "ros/warehouse.yaml"\nresolution = {RES}'))
    assert plain.speed_limit is None
    # the keep-out zones block cells that the plain map leaves free, and the digest tells the two maps apart
    assert int(np.sum(np.asarray(plain.free) & ~np.asarray(grid.free))) > 0
    assert digest != plain_digest
    assert float(np.min(np.asarray(grid.speed_limit))) < 1.0


def test_the_digest_covers_the_image_not_only_the_yaml(ros, tmp_path):
    (tmp_path / "ros").mkdir()
    for f in ("warehouse.yaml", "warehouse.pgm"):
        (tmp_path / "ros" / f).write_bytes((ros / f).read_bytes())
    spec = parse_config(_config(f'path = "ros/warehouse.yaml"\nresolution = {RES}'), data_dir=tmp_path).maps[0]
    before = load_map_spec(spec)[3]
    img = bytearray((tmp_path / "ros" / "warehouse.pgm").read_bytes())
    img[-1] = 0 if img[-1] else 254  # one pixel changes; the YAML does not
    (tmp_path / "ros" / "warehouse.pgm").write_bytes(bytes(img))
    assert load_map_spec(spec)[3] != before


def test_unknown_and_speed_filter_reach_the_loader(ros):
    spec = _spec(ros, 'path = "ros/warehouse.yaml"\nunknown = "free"\nspeed_mask = "ros/warehouse_speed.yaml"\n'
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
    grid = jp.load_map(ros / "warehouse.yaml", resolution=RES, keepout=ros / "warehouse_keepout.yaml")
    plain = jp.load_map(ros / "warehouse.yaml", resolution=RES)
    ys, xs = np.nonzero(np.asarray(grid.free))
    start, goal = (int(xs[0]), int(ys[0])), (int(xs[-1]), int(ys[-1]))
    keep_out = np.asarray(plain.free) & ~np.asarray(grid.free)
    through = np.asarray(jp.plan(plain, start, goal, planner="astar").path)
    assert keep_out[through[:, 1], through[:, 0]].any()  # the plain map's shortest path crosses a keep-out zone
    out = tmp_path / "plan.json"
    rc = main(["plan", str(ros / "warehouse.yaml"), "--resolution", str(RES), "--keepout",
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

    entry = (f'path = "{ros / "warehouse.yaml"}"\nresolution = {RES}\nkeepout = "{ros / "warehouse_keepout.yaml"}"\n'
             f'speed_mask = "{ros / "warehouse_speed.yaml"}"')
    cfg = tmp_path / "masks.toml"
    cfg.write_text(_config(entry))
    run = run_experiment(cfg, tmp_path / "runs", data_dir=ros.parent, progress=False)
    rows = (run / "trials.csv").read_text().splitlines()
    header = rows[0].split(",")
    assert len(rows) == 3 and all(r.split(",")[header.index("success")] in ("1", "True", "true") for r in rows[1:])
