"""ROS map_server maps (issue 30): loading Nav2's warehouse and a depot, masks, saving, resampling, the origin
in every world <-> cell conversion, and the speed limit layer in the DWA/MPPI windows."""

from __future__ import annotations

import re
import time
from pathlib import Path

import numpy as np
import pytest

import jaxplan as jp
from jaxplan.grid import load_ros_map, read_pgm, resampled_shape


@pytest.fixture(scope="session")
def warehouse(ros):
    return jp.load_map(ros / "warehouse.yaml")


@pytest.fixture(scope="session")
def warehouse_masked(ros):
    return jp.load_map(ros / "warehouse.yaml", keepout=ros / "warehouse_keepout.yaml",
                       speed=ros / "warehouse_speed.yaml")


def _hand_pixels(path: Path) -> tuple[int, int, np.ndarray]:
    """An independent P5 reader: header by regular expression, pixels as bytes (row 0 = the image's top)."""
    data = path.read_bytes()
    m = re.match(rb"P5\s+(?:#[^\n]*\n\s*)*(\d+)\s+(?:#[^\n]*\n\s*)*(\d+)\s+(?:#[^\n]*\n\s*)*(\d+)\s", data)
    w, h, maxval = (int(x) for x in m.groups())
    assert maxval == 255
    return w, h, np.frombuffer(data[m.end():], np.uint8).reshape(h, w)


# ---------------------------------------------------------------------------------------------
# The shared maps


@pytest.mark.parametrize("name, size, res, origin, free_thresh", [
    ("warehouse", (1006, 1674), 0.03, (-15.1, -25.0), 0.1),
    ("depot", (604, 307), 0.05, (0.0, 0.0), 0.25),
])
def test_shared_maps_load_with_their_size_resolution_origin_and_hand_counted_blocked_cells(
        ros, name, size, res, origin, free_thresh):
    grid = jp.load_map(ros / f"{name}.yaml")
    w, h, pixels = _hand_pixels(ros / f"{name}.pgm")
    assert (w, h) == size
    assert grid.shape == (h, w) and grid.resolution == res and grid.origin == origin
    # By hand: occ = 1 - p/255; free iff occ < free_thresh; everything else (occupied or unknown) blocked.
    free_by_hand = (1.0 - pixels / 255.0) < free_thresh
    assert int((~grid.free).sum()) == int((~free_by_hand).sum())
    # ROS cell rows run from the image's bottom row up.
    np.testing.assert_array_equal(grid.free, free_by_hand[::-1])


def test_warehouse_blocked_counts_by_pixel_value(warehouse, warehouse_masked, ros):
    _, _, px = _hand_pixels(ros / "warehouse.pgm")
    values = dict(zip(*np.unique(px, return_counts=True), strict=True))
    assert {int(k): int(v) for k, v in values.items()} == {0: 30951, 205: 230801, 254: 1318485, 255: 103807}
    assert int((~warehouse.free).sum()) == 30951 + 230801 == 261752  # black walls + grey unknown
    unknown_free = jp.load_map(ros / "warehouse.yaml", unknown="free")
    assert int((~unknown_free.free).sum()) == 30951
    _, _, keep = _hand_pixels(ros / "warehouse_keepout.pgm")
    keep_blocked = (1.0 - keep / 255.0)[::-1] > 0.65
    assert int((~warehouse_masked.free).sum()) == int(((~warehouse.free) | keep_blocked).sum()) == 295779


def test_speed_mask_follows_nav2_percent_rule(warehouse_masked, ros):
    """Nav2's speed filter, type 1 (percent), base 100, multiplier -1: limit = 100 - mask value %; mask 0, unknown
    and a limit of 0 % mean no limit. The mask's grey 204/205 pixels are value 20 -> 80 %."""
    _, _, px = _hand_pixels(ros / "warehouse_speed.pgm")
    mask = np.rint(100.0 * (1.0 - px[::-1] / 255.0))
    want = np.where((mask > 0) & (mask < 100), (100.0 - mask) / 100.0, 1.0).astype(np.float32)
    np.testing.assert_array_equal(warehouse_masked.speed_limit, want)
    assert sorted(np.unique(want).tolist()) == [pytest.approx(0.8), 1.0]
    assert int((want < 1).sum()) == 72195 + 227585


# ---------------------------------------------------------------------------------------------
# Round trips and formats


def test_save_load_round_trip_is_identical(warehouse_masked, tmp_path):
    crop = jp.grid_from_array(warehouse_masked.free[100:260, 50:230], resolution=0.03, origin=(-13.6, -22.0),
                              speed_limit=warehouse_masked.speed_limit[100:260, 50:230])
    jp.save_map(crop, tmp_path / "crop.yaml")
    back = jp.load_map(tmp_path / "crop.yaml", speed=tmp_path / "crop_speed.yaml")
    for field in ("free", "speed_limit"):
        np.testing.assert_array_equal(getattr(back, field), getattr(crop, field))
    assert back.resolution == crop.resolution and back.origin == crop.origin
    # And once more: the files written from the reloaded map are byte-identical.
    jp.save_map(back, tmp_path / "again.yaml")
    assert (tmp_path / "again.pgm").read_bytes() == (tmp_path / "crop.pgm").read_bytes()
    assert (tmp_path / "again_speed.pgm").read_bytes() == (tmp_path / "crop_speed.pgm").read_bytes()


def test_shared_warehouse_round_trip(warehouse, tmp_path):
    jp.save_map(warehouse, tmp_path / "w.yaml")
    back = jp.load_map(tmp_path / "w.yaml")
    np.testing.assert_array_equal(back.free, warehouse.free)
    assert (back.resolution, back.origin) == (warehouse.resolution, warehouse.origin)


def _write(tmp_path: Path, yaml: str, image: bytes, name: str = "m.pgm") -> Path:
    (tmp_path / name).write_bytes(image)
    p = tmp_path / "m.yaml"
    p.write_text(yaml)
    return p


_YAML = "image: m.pgm\nresolution: 0.5\norigin: [1.0, -2.0, 0.0]\nnegate: {neg}\noccupied_thresh: 0.65\n" \
        "free_thresh: 0.196\nmode: {mode}\n"


def test_p2_and_p5_give_the_same_map_and_negate_inverts(tmp_path):
    px = np.array([[0, 254, 205], [254, 254, 0]], np.uint8)
    p5 = _write(tmp_path, _YAML.format(neg=0, mode="trinary"), b"P5\n3 2\n255\n" + px.tobytes())
    g5 = jp.load_map(p5)
    p2 = _write(tmp_path, _YAML.format(neg=0, mode="trinary"),
                b"P2\n# a comment\n3 2\n255\n0 254 205\n254 254 0\n")
    g2 = jp.load_map(p2)
    np.testing.assert_array_equal(g5.free, g2.free)
    np.testing.assert_array_equal(g5.free, [[True, True, False], [False, True, False]])  # bottom image row first
    assert g5.origin == (1.0, -2.0) and g5.resolution == 0.5
    neg = jp.load_map(_write(tmp_path, _YAML.format(neg=1, mode="trinary"), b"P5\n3 2\n255\n" + px.tobytes()))
    np.testing.assert_array_equal(neg.free, [[False, False, True], [True, False, False]])


def test_scale_mode_keeps_in_between_cells_free(tmp_path):
    px = np.array([[0, 128, 254]], np.uint8)  # occ 1.0 (occupied), 0.498 (in between), 0.004 (free)
    g = jp.load_map(_write(tmp_path, _YAML.format(neg=0, mode="scale"), b"P5\n3 1\n255\n" + px.tobytes()))
    np.testing.assert_array_equal(g.free, [[False, True, True]])


def test_png_maps_read_with_pillow(tmp_path):
    from PIL import Image

    px = np.array([[0, 254, 205], [254, 254, 0]], np.uint8)
    Image.fromarray(px, mode="L").save(tmp_path / "m.png")
    (tmp_path / "m.yaml").write_text(_YAML.format(neg=0, mode="trinary").replace("m.pgm", "m.png"))
    g = jp.load_map(tmp_path / "m.yaml")
    np.testing.assert_array_equal(g.free, [[True, True, False], [False, True, False]])


@pytest.mark.parametrize("yaml, image, message", [
    ("resolution: 0.5\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.2\n", None,
     "missing key image"),
    (_YAML.format(neg=0, mode="raw"), None, "mode 'raw' is not supported"),
    (_YAML.format(neg=0, mode="trinary").replace("[1.0, -2.0, 0.0]", "[1.0, -2.0, 0.5]"), None,
     "origin yaw 0.5 is not supported"),
    (_YAML.format(neg=0, mode="trinary").replace("0.5", "-1"), None, "'resolution' must be > 0"),
    (_YAML.format(neg=0, mode="trinary").replace("0.196", "0.9"), None, "must be below occupied_thresh"),
    (_YAML.format(neg=0, mode="trinary") + "colour: red\n", None, "unknown key 'colour'"),
    ("this is not yaml at all", None, "expected 'key: value'"),
    (_YAML.format(neg=0, mode="trinary"), b"P5\n1000000 1000000\n255\n" + bytes(10),
     "header claims 1000000x1000000"),
    (_YAML.format(neg=0, mode="trinary"), b"P5\n3 2\n255\n" + bytes(4), "claims 3x2 pixels (6 bytes) but 4 bytes"),
    (_YAML.format(neg=0, mode="trinary"), b"P2\n3 2\n255\n1 2 3 4 5", "claims 3x2 pixels but only"),
    (_YAML.format(neg=0, mode="trinary"), b"P2\n2 2\n255\n1 2 x 4", "P2 pixel 2 (row 1, column 0) is not a number"),
    (_YAML.format(neg=0, mode="trinary"), b"P2\n2 1\n100\n1 200", "above maxval 100"),
    (_YAML.format(neg=0, mode="trinary"), b"secret: do not print me", "not a PGM image"),
])
def test_malformed_files_are_one_line_errors_naming_file_and_problem(tmp_path, yaml, image, message):
    p = _write(tmp_path, yaml, image if image is not None else b"P5\n3 2\n255\n" + bytes(6))
    with pytest.raises(ValueError) as e:
        jp.load_map(p)
    text = str(e.value)
    assert message in text and "\n" not in text and "secret" not in text
    assert str(p) in text or str(tmp_path / "m.pgm") in text


def test_a_huge_claimed_pgm_is_refused_before_allocation(tmp_path):
    p = _write(tmp_path, _YAML.format(neg=0, mode="trinary"), b"P5\n99999 99999\n255\n" + bytes(100))
    t0 = time.perf_counter()
    with pytest.raises(ValueError, match="pixels"):
        jp.load_map(p)
    assert time.perf_counter() - t0 < 1.0
    with pytest.raises(FileNotFoundError, match="not found"):
        jp.load_map(tmp_path / "nope.yaml")


def test_masks_must_match_the_map(tmp_path, ros):
    p = _write(tmp_path, _YAML.format(neg=0, mode="trinary"), b"P5\n3 2\n255\n" + bytes(6))
    with pytest.raises(ValueError, match="keep-out mask resolution 0.03 differs"):
        load_ros_map(p, keepout=ros / "warehouse_keepout.yaml")
    with pytest.raises(ValueError, match="apply to ROS maps"):
        jp.load_map(tmp_path / "x.map", keepout=p)


def test_read_pgm_16_bit(tmp_path):
    (tmp_path / "a.pgm").write_bytes(b"P5 2 1 65535\n" + np.array([0, 65535], ">u2").tobytes())
    values, maxval = read_pgm(tmp_path / "a.pgm")
    assert maxval == 65535 and values.tolist() == [[0, 65535]]


# ---------------------------------------------------------------------------------------------
# Origin: world <-> cell


def test_world_cell_conversions_use_the_origin(warehouse):
    g = warehouse
    assert g.has_origin
    np.testing.assert_allclose(g.centre([0, 0]), [-15.1 + 0.015, -25.0 + 0.015])
    np.testing.assert_allclose(g.centre([1005, 1673]), [-15.1 + 1005.5 * 0.03, -25.0 + 1673.5 * 0.03])
    cells = np.array([[0, 0], [17, 901], [1005, 1673]])
    np.testing.assert_array_equal(g.cell_at(g.centre(cells)), cells)
    assert g.cell_at((0.0, 0.0)).tolist() == [503, 833]  # (15.1 / 0.03, 25 / 0.03) floored
    pts = np.array([[1.0, 2.0, 0.3], [-3.0, 4.0, -1.0]])
    np.testing.assert_allclose(g.to_world(g.to_local(pts)), pts)
    np.testing.assert_allclose(g.to_local(pts)[:, :2], pts[:, :2] - [-15.1, -25.0])
    assert (g.to_local(pts)[:, 2] == pts[:, 2]).all()
    plain = jp.grid_from_array(np.ones((4, 4), bool), resolution=0.5)
    assert plain.origin == (0.0, 0.0) and not plain.has_origin
    p = np.array([[0.3, 1.7]], np.float32)
    assert plain.to_world(p) is p and plain.to_local(p) is p  # no origin: the same array, bit for bit
    np.testing.assert_array_equal(plain.centre([[1, 2]]), [[0.75, 1.25]])


def test_origin_is_validated_and_kept_by_replace():
    g = jp.grid_from_array(np.ones((3, 3), bool), origin=(2.0, -1.0))
    assert g.replace(risk=np.ones((3, 3))).origin == (2.0, -1.0)
    for bad in ((1.0,), (np.nan, 0.0), "xy"):
        with pytest.raises(ValueError, match="origin"):
            jp.grid_from_array(np.ones((3, 3), bool), origin=bad)
    with pytest.raises(ValueError, match="speed_limit"):
        jp.grid_from_array(np.ones((2, 2), bool), speed_limit=np.zeros((2, 2)))


def test_dwa_step_with_an_origin_equals_the_shifted_step_without():
    free = np.ones((30, 30), bool)
    free[10:20, 14] = False
    plain = jp.grid_from_array(free, resolution=0.2)
    moved = plain.replace(origin=(-100.25, 37.5))
    o = np.array([-100.25, 37.5])
    state = np.array([1.0, 3.0, 0.2, 0.3, 0.0])
    sub = np.array([5.0, 3.0])
    obs = (np.array([[3.0, 2.0]]), np.array([[0.0, 0.5]]), np.array([0.2]))
    u0, i0 = jp.dwa_step(state, sub, plain, obstacles=obs)
    u1, i1 = jp.dwa_step(state + np.r_[o, 0, 0, 0], sub + o, moved,
                         obstacles=(obs[0] + o, obs[1], obs[2]))
    np.testing.assert_array_equal(u0, u1)
    np.testing.assert_allclose(i1.rollouts[..., :2] - o, i0.rollouts[..., :2], atol=1e-4)
    m0, _ = jp.mppi_step(state, sub, plain, key=3)
    m1, _ = jp.mppi_step(state + np.r_[o, 0, 0, 0], sub + o, moved, key=3)
    np.testing.assert_array_equal(m0, m1)


def test_navigate_with_an_origin_is_the_shifted_episode():
    free = np.ones((24, 24), bool)
    free[6:18, 11:13] = False
    plain = jp.grid_from_array(free, resolution=0.25)
    moved = plain.replace(origin=(12.5, -40.0))
    kw = dict(global_planner="astar", local_planner="dwa", time_limit=40.0)
    e0 = jp.navigate(plain, (3, 12), (20, 12), **kw)
    e1 = jp.navigate(moved, (3, 12), (20, 12), **kw)
    assert e0.success and e1.success
    # The same episode, moved: the map frame's numbers are identical, the world's differ by float32 rounding.
    np.testing.assert_allclose(e1.trajectory[:, :2] - np.float32([12.5, -40.0]), e0.trajectory[:, :2], atol=1e-5)
    np.testing.assert_array_equal(e1.trajectory[:, 2], e0.trajectory[:, 2])
    np.testing.assert_array_equal(e1.controls, e0.controls)
    np.testing.assert_allclose(e1.waypoints - [12.5, -40.0], e0.waypoints, atol=1e-5)
    wall = ("plan_time_s", "step_time_s", "run_time_s", "compile_s")  # wall-clock times differ run to run
    assert {k: v for k, v in e1.metrics.items() if k not in wall} == {k: v for k, v in e0.metrics.items()
                                                                        if k not in wall}
    # Walkers generated on the moved map live in world coordinates, and give the same episode.
    w0 = jp.random_obstacles(plain, n=2, seed=1, avoid=plain.centre([[3, 12], [20, 12]]))
    w1 = jp.random_obstacles(moved, n=2, seed=1, avoid=moved.centre([[3, 12], [20, 12]]))
    np.testing.assert_allclose(np.asarray(w1.waypoints) - [12.5, -40.0], np.asarray(w0.waypoints), atol=1e-5)
    f0 = jp.navigate(plain, (3, 12), (20, 12), obstacles=w0, **kw)
    f1 = jp.navigate(moved, (3, 12), (20, 12), obstacles=w1, **kw)
    assert f0.success == f1.success and f0.collisions == f1.collisions
    np.testing.assert_allclose(f1.trajectory[:, :2] - [12.5, -40.0], f0.trajectory[:, :2], atol=1e-3)


# ---------------------------------------------------------------------------------------------
# Resampling


def test_resample_blocks_a_coarse_cell_if_any_fine_cell_is():
    free = np.ones((7, 10), bool)
    free[2, 3] = False
    g = jp.grid_from_array(free, resolution=0.03, origin=(-1.0, 2.0))
    c = jp.resample(g, 0.1)  # 3.33 fine cells per coarse cell
    assert c.shape == resampled_shape(g, 0.1) == (3, 3) and c.origin == g.origin
    # Fine x 3 spans [0.09, 0.12) m: coarse columns 0 ([0, 0.1)) and 1; fine y 2 spans [0.06, 0.09): row 0.
    # The map is 0.30 m wide (3 whole coarse columns) and 0.21 m high: the last coarse row sticks out, blocked.
    np.testing.assert_array_equal(c.free, [[False, False, True], [True, True, True], [False, False, False]])
    assert jp.resample(g, 0.03) is g


def test_resample_is_conservative_on_the_warehouse(warehouse_masked):
    c = jp.resample(warehouse_masked, 0.1)
    assert c.shape == (503, 302) and c.resolution == 0.1 and c.origin == warehouse_masked.origin
    # Every free coarse cell's centre lies on a free fine cell, and its speed limit is the minimum beneath it.
    ys, xs = np.nonzero(c.free)
    fine = warehouse_masked.cell_at(c.centre(np.stack([xs, ys], 1)))
    assert warehouse_masked.free[fine[:, 1], fine[:, 0]].all()
    assert (c.speed_limit[ys, xs] <= warehouse_masked.speed_limit[fine[:, 1], fine[:, 0]]).all()


# ---------------------------------------------------------------------------------------------
# Planning on the warehouse


ROUTE = ((-12.0, -22.0), (-12.0, -10.0))  # world metres, along the west aisle


def test_astar_and_iaco_plan_on_a_crop_of_the_warehouse(warehouse_masked):
    c = jp.resample(warehouse_masked, 0.1)
    s, g = c.cell_at(ROUTE[0]), c.cell_at(ROUTE[1])
    a = jp.plan(c, s, g, planner="astar")
    assert a.success and 11.5 < a.length < 13.0
    r = jp.plan(c, s, g, planner="iaco", seed=0, ants=20, iterations=10)
    assert r.success and r.length >= a.length - 1e-9
    assert c.free[r.path[:, 1], r.path[:, 0]].all()


@pytest.mark.slow
@pytest.mark.parametrize("resolution", [0.03, 0.1])
def test_astar_and_iaco_plan_on_the_full_warehouse(warehouse_masked, resolution):
    grid = jp.resample(warehouse_masked, resolution)
    s, g = grid.cell_at(ROUTE[0]), grid.cell_at(ROUTE[1])
    a = jp.plan(grid, s, g, planner="astar")
    r = jp.plan(grid, s, g, planner="iaco", seed=0)
    assert a.success and r.success and r.length >= a.length - 1e-9
    far = grid.cell_at((12.0, 21.0))
    assert jp.plan(grid, s, far, planner="astar").success


# ---------------------------------------------------------------------------------------------
# Speed limit in the DWA/MPPI windows


ZONE = (2.0, 5.0)  # the slow zone's x range in the map frame (m)


def _zone_grid(limit: float = 0.4):
    free = np.ones((16, 80), bool)
    free[0], free[-1] = False, False
    speed = np.ones(free.shape, np.float32)
    speed[:, 20:50] = limit  # a slow zone across the corridor, x in [2.0, 5.0) m
    return jp.grid_from_array(free, resolution=0.1, origin=(5.0, 5.0), speed_limit=speed)


def test_dwa_and_mppi_steps_respect_the_speed_limit_of_the_robots_cell():
    g = _zone_grid(0.4)
    cfg = jp.DWAConfig()
    vmax = float(cfg.robot.v_max)
    inside = np.array([5.0 + 3.0, 5.8, 0.0, 0.4 * vmax, 0.0])
    u, info = jp.dwa_step(inside, [5.0 + 5.5, 5.8], g, config=cfg)
    assert u[0] <= 0.4 * vmax + 1e-6
    free_run, _ = jp.dwa_step(inside, [5.0 + 5.5, 5.8], g.replace(speed_limit=None), config=cfg)
    assert free_run[0] > 0.4 * vmax + 1e-3  # without the layer it would speed up
    m, _ = jp.mppi_step(inside, [5.0 + 5.5, 5.8], g, key=0)
    assert m[0] <= 0.4 * float(jp.MPPIConfig().robot.v_max) + 1e-6


@pytest.mark.parametrize("local", ["dwa", "mppi"])
def test_an_episode_through_a_slow_zone_keeps_to_its_limit(local):
    g = _zone_grid(0.4)
    ep = jp.navigate(g, (5, 8), (74, 8), global_planner="astar", local_planner=local, time_limit=60.0)
    plain = jp.navigate(g.replace(speed_limit=None), (5, 8), (74, 8), global_planner="astar", local_planner=local,
                        time_limit=60.0)
    assert ep.success and plain.success
    cfg = jp.NavConfig()
    robot = cfg.dwa.robot if local == "dwa" else cfg.local_mppi().robot
    vmax, decel, period = float(robot.v_max), float(robot.decel), float(cfg.dwa.period)
    x = ep.trajectory[:-1, 0] - 5.0  # where each control was chosen (map frame)
    v = ep.controls[:, 0]
    limit = np.where((x >= ZONE[0]) & (x < ZONE[1]), 0.4 * vmax, vmax)
    # In the zone the robot drives at most at the limit, except while it brakes at full rate on entering.
    braking = np.concatenate([[False], v[1:] <= v[:-1] - decel * period * 0.999])
    assert np.all((v <= limit + 1e-5) | braking)
    brake = (vmax ** 2 - (0.4 * vmax) ** 2) / (2 * decel) + vmax * period  # farthest it can take to slow down
    deep = (x >= ZONE[0] + brake) & (x < ZONE[1])
    assert deep.sum() > 5 and v[deep].max() <= 0.4 * vmax + 1e-5
    assert v.max() > 0.8 * vmax > 0.4 * vmax + 0.3  # outside the zone it runs much faster
    assert ep.time_s > plain.time_s  # the zone slows it down


def test_without_a_speed_layer_episodes_are_bit_identical_to_a_map_without_the_field():
    free = np.ones((16, 40), bool)
    g = jp.grid_from_array(free, resolution=0.1)
    ones = g.replace(speed_limit=np.ones(free.shape, np.float32))
    e0 = jp.navigate(g, (3, 8), (36, 8), global_planner="astar", time_limit=30.0)
    e1 = jp.navigate(ones, (3, 8), (36, 8), global_planner="astar", time_limit=30.0)
    # A layer of ones caps nothing: the same trajectory (the no-layer program is the unchanged one).
    np.testing.assert_array_equal(e0.trajectory, e1.trajectory)


# ---------------------------------------------------------------------------------------------
# Fuzzing: any YAML or PGM edit gives a map or a one-line ValueError naming the file


_FUZZ_YAML = _YAML.format(neg=0, mode="trinary")
_FUZZ_PGM = b"P5\n# c\n4 3\n255\n" + bytes([0, 254, 205, 254] * 3)


def _fuzzed():
    from hypothesis import strategies as st

    @st.composite
    def case(draw):
        lines = _FUZZ_YAML.splitlines()
        for _ in range(draw(st.integers(0, 3))):
            i = draw(st.integers(0, len(lines)))
            op = draw(st.sampled_from(["number", "drop", "dup", "junk", "cut"]))
            j = min(i, len(lines) - 1)
            if op == "number" and lines:
                key = lines[j].split(":")[0]
                lines[j] = f"{key}: {draw(st.sampled_from(['1e999', '-3', 'nan', 'x', '[1, 2]', '[1,2,3,4]', '']))}"
            elif op == "drop" and lines:
                del lines[j]
            elif op == "dup" and lines:
                lines.insert(i, lines[j])
            elif op == "junk":
                lines.insert(i, draw(st.text(max_size=20)))
            elif op == "cut" and lines:
                lines[j] = lines[j][: draw(st.integers(0, len(lines[j])))]
        pgm = bytearray(_FUZZ_PGM)
        for _ in range(draw(st.integers(0, 3))):
            k = draw(st.integers(0, len(pgm) - 1))
            op = draw(st.sampled_from(["byte", "cut", "digits"]))
            if op == "byte":
                pgm[k] = draw(st.integers(0, 255))
            elif op == "cut":
                del pgm[k:]
                if not pgm:
                    break
            else:
                pgm[k:k] = draw(st.sampled_from([b"999999999", b"0", b"65536", b"-1"]))
        return "\n".join(lines) + "\n", bytes(pgm)

    return case()


def test_fuzz_ros_map_parser(tmp_path_factory):
    from hypothesis import HealthCheck, given, settings

    folder = tmp_path_factory.mktemp("fuzz")
    seen = {"ok": 0, "ValueError": 0}

    @settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
    @given(_fuzzed())
    def run(case):
        yaml, pgm = case
        (folder / "m.yaml").write_bytes(yaml.encode("utf-8", "surrogatepass"))
        (folder / "m.pgm").write_bytes(pgm)
        try:
            g = jp.load_map(folder / "m.yaml")
        except (ValueError, FileNotFoundError) as e:
            assert str(e) and "\n" not in str(e) and str(folder) in str(e)
            seen["ValueError"] += 1
        else:
            assert g.free.ndim == 2
            seen["ok"] += 1

    run()
    assert seen["ok"] > 0 and seen["ValueError"] > 0
