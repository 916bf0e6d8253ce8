"""`jaxplan demo`: iaco_dwa beside aco_dwa among moving discs; table, demo.png and demo.gif.

The full demo (the built-in 48x32 warehouse) compiles two navigation pipelines; the test runs
its ``--quick`` variant on a generated 14x10 warehouse, which exercises the same code in a
fraction of the time.
"""

from __future__ import annotations

import numpy as np
from PIL import Image

from jaxplan.cli import main
from jaxplan.cli.demo import ROWS, min_clearance


def test_quick_demo_prints_the_table_and_writes_png_and_gif(tmp_path, capsys):
    assert main(["demo", "--quick", "--no-cache", "--out-dir", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    for row in ROWS:
        assert row in out
    assert "iaco_dwa" in out and "aco_dwa" in out
    assert (tmp_path / "demo.png").stat().st_size > 10_000
    with Image.open(tmp_path / "demo.gif") as im:
        assert im.format == "GIF" and im.n_frames > 5


class _Ep:
    def __init__(self, traj, obs_pos, radii):
        self.trajectory = np.asarray(traj, np.float64)
        self.obstacle_positions = np.asarray(obs_pos, np.float64)
        self.obstacles = type("O", (), {"radii": np.asarray(radii, np.float64)})()


def test_min_clearance_is_the_footprint_gap_to_squares_and_discs():
    import jaxplan as jp

    free = np.ones((5, 5), bool)
    free[2, 4] = False  # the square [4, 5] x [2, 3] (m, resolution 1)
    grid = jp.grid_from_array(free, resolution=1.0)
    traj = [[2.5, 2.5, 0.0], [2.9, 2.5, 0.0]]  # 1.1 m from the blocked square at the second step
    far = [[[0.5, 0.5]], [[0.5, 0.5]]]
    assert np.isclose(min_clearance(grid, _Ep(traj, far, [0.1]), 0.25), 1.1 - 0.25)
    near = [[[2.5, 2.0]], [[2.9, 2.0]]]  # a disc of radius 0.1 whose centre is 0.5 m away
    assert np.isclose(min_clearance(grid, _Ep(traj, near, [0.1]), 0.25), 0.5 - 0.1 - 0.25)
