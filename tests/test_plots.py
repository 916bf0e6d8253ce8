"""Plot helpers: what is drawn is where the conventions say, and bad input is refused."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pytest
from conftest import unlabelled_marks
from matplotlib.colors import LogNorm

import jaxplan as jp
from jaxplan.experiments.plots import (
    TURN_RULE_LABEL,
    convergence_bands,
    legend_outside,
    pheromone_per_cell,
    plot_convergence,
    plot_map,
    plot_paths,
    plot_pheromone,
    plot_run,
    save_figure,
)
from jaxplan.grid import offsets

RES = 0.5
H, W = 10, 12


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


@pytest.fixture
def grid() -> jp.GridMap:
    free = np.ones((H, W), bool)
    free[2:8, 4] = False  # a wall
    free[5, 7:10] = False
    free[0, 11] = False  # a blocked corner
    free[9, 0] = False
    rng = np.random.default_rng(3)
    height = rng.uniform(0, 2, (H, W))
    risk = rng.poisson(1.0, (H, W)).astype(float)
    clearance = np.full((H, W), np.inf)
    clearance[1, 1:4] = 0.4  # a low tunnel
    clearance[3, 6] = 1.2
    clearance[2, 4] = 1.0  # on a blocked cell: not drawn
    turn = np.zeros((H, W), np.int8)
    turn[7, 2] = turn[0, 0] = turn[4, 4] = 1  # (4, 4) is blocked: not marked
    return jp.grid_from_array(free, resolution=RES, height=height, risk=risk, clearance_height=clearance,
                              turn_rule=turn)


def _ax():
    return plt.subplots()[1]


def _image(ax, label):
    found = [im for im in ax.images if im.get_label() == label]
    assert len(found) == 1, [im.get_label() for im in ax.images]
    return found[0]


# ---------------------------------------------------------------------------------------------
# plot_map


@pytest.mark.parametrize("layer,label", [("height", "height (m)"), ("risk", "risk"),
                                         ("clearance_height", "clearance height (m)")])
def test_map_layer_shows_free_cells_only(grid, layer, label):
    ax = plot_map(_ax(), grid, layer=layer)
    im = _image(ax, label)
    data = im.get_array()
    values = np.asarray(getattr(grid, layer), np.float64)
    shown = grid.free & np.isfinite(values)
    np.testing.assert_array_equal(~np.ma.getmaskarray(data), shown)
    np.testing.assert_allclose(data.data[shown], values[shown])
    assert im.get_extent() == [0.0, W * RES, H * RES, 0.0]  # row 0 at the top, metres
    blocked = _image(ax, "blocked").get_array()
    np.testing.assert_array_equal(np.ma.getmaskarray(blocked), grid.free)
    assert ax.get_xlim() == (0.0, W * RES) and ax.get_ylim() == (H * RES, 0.0)


def test_clearance_layer_shows_only_the_tunnels(grid):
    data = _image(plot_map(_ax(), grid, layer="clearance_height"), "clearance height (m)").get_array()
    ys, xs = np.nonzero(~np.ma.getmaskarray(data))
    assert sorted(zip(xs.tolist(), ys.tolist(), strict=True)) == [(1, 1), (2, 1), (3, 1), (6, 3)]


def test_risk_scale_starts_at_zero_and_an_empty_layer_gets_no_colorbar(grid):
    ax = plot_map(_ax(), grid, layer="risk")
    assert _image(ax, "risk").norm.vmin == 0.0
    plain = jp.grid_from_array(np.asarray(grid.free), resolution=RES)
    fig, ax = plt.subplots()
    n_axes = len(fig.axes)
    plot_map(ax, plain, layer="clearance_height")  # no tunnel anywhere
    assert len(fig.axes) == n_axes  # no colour bar axes added
    plot_map(ax, plain, layer="height")
    assert len(fig.axes) == n_axes + 1


def test_map_rejects_unknown_layer(grid):
    with pytest.raises(ValueError, match="layer must be None or one of .*'slope'"):
        plot_map(_ax(), grid, layer="slope")


def test_turn_rule_markers_at_free_rule_cells(grid):
    ax = plot_map(_ax(), grid, show_turn_rule=True)
    (line,) = [ln for ln in ax.lines if ln.get_label() == TURN_RULE_LABEL]
    got = sorted(zip(line.get_xdata().tolist(), line.get_ydata().tolist(), strict=True))
    assert got == sorted([((0 + 0.5) * RES, (0 + 0.5) * RES), ((2 + 0.5) * RES, (7 + 0.5) * RES)])
    assert not plot_map(_ax(), grid).lines  # off by default
    # The markers leave the colour cycle alone: a path drawn next takes the first colour, as on a plain map.
    plot_paths(ax, grid, [np.array([[0, 0], [1, 1]])], labels=["p"])
    from matplotlib.colors import to_hex

    assert to_hex(ax.lines[-1].get_color()) == "#1f77b4"  # C0


def test_tunnel_cells_are_outlined_with_their_headroom(grid):
    """The free cells with a finite clearance_height, (1..3, 1) at 0.4 m and (6, 3) at 1.2 m, each a hatched
    square of one cell; the blocked (4, 2) is not drawn. One legend entry names the headroom range."""
    ax = plot_map(_ax(), grid, show_tunnels=True)
    rects = [pt for pt in ax.patches if pt.get_hatch()]
    corners = sorted((round(r.get_x() / RES), round(r.get_y() / RES)) for r in rects)
    assert corners == [(1, 1), (2, 1), (3, 1), (6, 3)]
    assert all(r.get_width() == pytest.approx(RES) and r.get_height() == pytest.approx(RES) for r in rects)
    assert [r.get_label() for r in rects if r.get_label() and not r.get_label().startswith("_")] == [
        "tunnel (headroom 0.40-1.20 m)"]
    assert not [pt for pt in plot_map(_ax(), grid).patches if pt.get_hatch()]  # off by default


def test_legend_outside_puts_every_labelled_artist_below_the_map(grid):
    fig, ax = plt.subplots()
    plot_map(ax, grid, show_turn_rule=True, show_tunnels=True)
    plot_paths(ax, grid, [np.array([[0, 0], [3, 3]])], labels=["p"], start=[0, 0], goal=[3, 3])
    fig.canvas.draw()
    legend = ax.get_legend()
    assert [t.get_text() for t in legend.get_texts()] == [TURN_RULE_LABEL, "tunnel (headroom 0.40-1.20 m)", "p",
                                                          "start", "goal"]
    assert legend.get_window_extent().y1 < ax.get_window_extent().y0
    assert legend_outside(plt.subplots()[1]) is None  # nothing labelled: no legend
    plt.close(fig)


# ---------------------------------------------------------------------------------------------
# plot_paths


def test_paths_pass_through_cell_centres_in_metres(grid):
    cells = np.array([[0, 0], [1, 1], [2, 1], [3, 2]])
    smooth = np.array([[0.0, 0.0], [1.4, 0.7], [3.0, 2.0]])
    ax = plot_paths(_ax(), grid, [cells, smooth], labels=["grid", "smoothed"], start=cells[0], goal=cells[-1])
    lines = {ln.get_label(): ln for ln in ax.lines}
    for name, p in (("grid", cells), ("smoothed", smooth)):
        np.testing.assert_allclose(lines[name].get_xdata(), (p[:, 0] + 0.5) * RES)
        np.testing.assert_allclose(lines[name].get_ydata(), (p[:, 1] + 0.5) * RES)
    np.testing.assert_allclose(lines["goal"].get_xydata()[0], (cells[-1] + 0.5) * RES)


def test_paths_in_metres_are_drawn_as_given(grid):
    pts = np.array([[0.25, 0.25], [1.0, 2.5]])
    (line,) = plot_paths(_ax(), grid, [pts], coords="m").lines
    np.testing.assert_allclose(line.get_xydata(), pts)
    with pytest.raises(ValueError, match="coords must be 'cells' or 'm'"):
        plot_paths(_ax(), grid, [pts], coords="metres")


def test_padded_paths_with_lengths(grid):
    padded = np.full((3, 5, 2), -1, np.int64)
    padded[0, :3] = [[0, 0], [1, 0], [2, 0]]
    padded[1, :5] = [[0, 1], [1, 1], [2, 1], [3, 1], [3, 2]]
    lengths = np.array([3, 5, 0])  # the third plan failed
    ax = plot_paths(_ax(), grid, padded, lengths=lengths, labels=["a", "b", "failed"])
    lines = {ln.get_label(): ln for ln in ax.lines}
    assert set(lines) == {"a", "b"}  # an empty path draws nothing
    np.testing.assert_allclose(lines["a"].get_xdata(), (np.array([0, 1, 2]) + 0.5) * RES)
    np.testing.assert_allclose(lines["b"].get_ydata(), (np.array([1, 1, 1, 1, 2]) + 0.5) * RES)
    # The same padded array without lengths: the -1 padding is refused, not drawn.
    with pytest.raises(ValueError, match=r"paths\[0\] holds negative cells .*pass lengths"):
        plot_paths(_ax(), grid, padded)


def test_one_path_array_is_one_path(grid):
    p = np.array([[0, 0], [1, 1], [2, 2]])
    (line,) = plot_paths(_ax(), grid, p).lines
    np.testing.assert_allclose(line.get_xdata(), (p[:, 0] + 0.5) * RES)


def test_jax_smoothed_path_with_a_scalar_length(grid):
    """A smoother's output: f32 points padded by repeating the last one, and a count n."""
    import jax.numpy as jnp

    pts = jnp.array([[0.0, 0.0], [2.5, 1.25], [5.0, 3.0], [5.0, 3.0], [5.0, 3.0]], jnp.float32)
    (line,) = plot_paths(_ax(), grid, pts, lengths=jnp.int32(3)).lines
    np.testing.assert_allclose(line.get_xydata(), (np.asarray(pts[:3]) + 0.5) * RES)


@pytest.mark.parametrize("kwargs,msg", [
    ({"paths": [np.zeros((3, 3))]}, r"paths\[0\] must be an array of points \[L, 2\]"),
    ({"paths": [np.zeros((2, 2))], "labels": ["a", "b"]}, "got 2 labels for 1 paths"),
    ({"paths": np.zeros((2, 4, 2)), "lengths": [1, 5]}, r"lengths\[1\] = 5 is outside \[0, 4\]"),
    ({"paths": np.zeros((2, 4, 2)), "lengths": [1]}, "lengths must have one entry per path"),
    ({"paths": [np.array([[0.0, 0.0], [np.nan, 1.0]])]}, r"paths\[0\] contains NaN or inf"),
    ({"paths": np.zeros((2, 4, 3))}, r"array \[P, L, 2\], got shape \(2, 4, 3\)"),
    ({"paths": [np.zeros((2, 2))], "start": [1, 2, 3]}, "start must be a point"),
])
def test_paths_reject_bad_input(grid, kwargs, msg):
    with pytest.raises(ValueError, match=msg):
        plot_paths(_ax(), grid, **kwargs)


# ---------------------------------------------------------------------------------------------
# Pheromone


def _allowed_8(free: np.ndarray) -> np.ndarray:
    """``bool[C, K]`` allowed 8-connected moves, written out here by hand (no corner cutting)."""
    Hh, Ww = free.shape
    offs = offsets(8)
    ok = np.zeros((Hh * Ww, len(offs)), bool)

    def f(x, y):
        return 0 <= x < Ww and 0 <= y < Hh and free[y, x]

    for y in range(Hh):
        for x in range(Ww):
            for k, (dx, dy) in enumerate(offs.tolist()):
                allowed = f(x, y) and f(x + dx, y + dy)
                if dx and dy:
                    allowed = allowed and f(x + dx, y) and f(x, y + dy)
                ok[y * Ww + x, k] = allowed
    return ok


@pytest.fixture
def tau(grid) -> np.ndarray:
    rng = np.random.default_rng(0)
    t = rng.uniform(0.5, 3.0, (H * W, 8))
    t[~_allowed_8(np.asarray(grid.free))] = 1e6  # disallowed edges: must never show
    return t


def test_pheromone_heat_map_is_max_over_allowed_edges(grid, tau):
    allowed = _allowed_8(np.asarray(grid.free))
    ax = plot_pheromone(_ax(), grid, tau, reduce="max", log=True)
    data = _image(ax, "pheromone").get_array()
    for i in range(H * W):
        y, x = divmod(i, W)
        if allowed[i].any():
            assert data[y, x] == pytest.approx(tau[i, allowed[i]].max())
        else:
            assert np.ma.getmaskarray(data)[y, x]
    assert np.ma.getmaskarray(data)[~np.asarray(grid.free)].all()
    norm = _image(ax, "pheromone").norm
    assert isinstance(norm, LogNorm)
    assert norm.vmax == pytest.approx(tau[allowed].max()) and norm.vmax < 3.0


def test_pheromone_sum_and_colonies(grid, tau):
    allowed = _allowed_8(np.asarray(grid.free))
    expect = np.where(allowed, tau, 0.0).sum(axis=1).reshape(H, W)
    got = pheromone_per_cell(grid, tau, reduce="sum")
    free = np.asarray(grid.free)
    np.testing.assert_allclose(got[free], expect[free])
    assert np.isnan(got[~free]).all()
    # S sub-colonies: reduced together with the edges.
    two = np.stack([tau, 2 * tau])
    np.testing.assert_allclose(pheromone_per_cell(grid, two, reduce="sum")[free], 3 * expect[free])
    np.testing.assert_allclose(pheromone_per_cell(grid, two, reduce="max")[free],
                               2 * pheromone_per_cell(grid, tau, reduce="max")[free])
    ax = plot_pheromone(_ax(), grid, tau, reduce="sum", log=False)
    assert not isinstance(_image(ax, "pheromone").norm, LogNorm)


def test_pheromone_ignores_nan_on_disallowed_edges(grid, tau):
    t = tau.copy()
    t[~_allowed_8(np.asarray(grid.free))] = np.nan
    np.testing.assert_allclose(pheromone_per_cell(grid, t), pheromone_per_cell(grid, tau))


def test_pheromone_respects_vehicle_height(grid, tau):
    """Moves into the 0.4 m tunnel are not allowed for a 0.5 m vehicle, so they cannot count."""
    t = np.ones((H * W, 16))
    offs = offsets(16).tolist()
    east = offs.index([1, 0])
    t[1 * W + 0, east] = 50.0  # (0, 1) -> (1, 1), into the tunnel
    assert pheromone_per_cell(grid, t)[1, 0] == 50.0
    assert pheromone_per_cell(grid, t, vehicle_height=0.5)[1, 0] == 1.0
    assert np.isnan(pheromone_per_cell(grid, t, vehicle_height=0.5)[1, 1])  # the tunnel cell itself


@pytest.mark.parametrize("shape,kwargs,msg", [
    ((H * W - 1, 8), {}, "tau has 119 cells, but the 12x10 map has 120"),
    ((H * W, 5), {}, "tau has K = 5 neighbour slots; expected 4, 8 or 16"),
    ((H * W, 8), {"neighbours": 4}, r"tau has 8 neighbour slots per cell, but the neighbour table is \(120, 4\)"),
    ((2, 3, H * W, 8), {}, r"tau must be \[C, K\] or \[S, C, K\]"),
    ((H * W, 8), {"reduce": "mean"}, "reduce must be 'max' or 'sum'"),
])
def test_pheromone_rejects_bad_input(grid, shape, kwargs, msg):
    with pytest.raises(ValueError, match=msg):
        plot_pheromone(_ax(), grid, np.ones(shape), **kwargs)


def test_pheromone_rejects_negative_or_nan_on_allowed_edges(grid, tau):
    allowed = _allowed_8(np.asarray(grid.free))
    i, k = np.argwhere(allowed)[0]
    for bad, msg in ((-1.0, "tau must be >= 0"), (np.nan, "tau holds NaN or inf")):
        t = tau.copy()
        t[i, k] = bad
        with pytest.raises(ValueError, match=msg):
            plot_pheromone(_ax(), grid, t)


def test_planner_returns_its_final_pheromone_on_request():
    free = np.ones((6, 8), bool)
    free[1:5, 3] = False
    g = jp.grid_from_array(free)
    small = dict(ants=6, iterations=4)
    r = jp.plan(g, (0, 0), (7, 5), planner="aco", seed=1, keep_pheromone=True, **small)
    plain = jp.plan(g, (0, 0), (7, 5), planner="aco", seed=1, **small)
    assert "tau" not in plain.info
    np.testing.assert_array_equal(r.path, plain.path)  # keeping it changes nothing else
    tau = r.info["tau"]
    assert tau.shape == (1, 48, 8)
    # Ant System: τ0 = 1, four evaporations by (1 − ρ) = 0.7; an edge no ant took holds 0.7**4,
    # an edge of the best path got at least one deposit Q/L.
    nb = jp.neighbour_table(g, 8)
    never = 0.7**4
    offs = nb.offsets.tolist()
    for a, b in zip(r.path[:-1], r.path[1:], strict=True):
        k = offs.index((b - a).tolist())
        assert tau[0, a[1] * 8 + a[0], k] > never * 1.001
    assert np.isclose(tau[0][nb.valid], never, rtol=1e-5).any()
    batch = jp.plan_batch(g, [(0, 0)], [(7, 5)], planner="aco", seeds=[1, 2], keep_pheromone=True, **small)
    assert batch.tau.shape == (1, 2, 1, 48, 8)
    np.testing.assert_array_equal(batch.result(0, 0).info["tau"], tau)
    assert jp.plan_batch(g, [(0, 0)], [(7, 5)], planner="aco", seeds=[1], **small).tau is None
    with pytest.raises(ValueError, match="keep_pheromone must be True or False"):
        jp.plan(g, (0, 0), (7, 5), planner="aco", keep_pheromone="yes", **small)
    fig = plot_run(g, r)
    assert len(fig.axes) == 3 + 1  # map, pheromone (+ its colour bar), convergence
    data = _image(fig.axes[1], "pheromone").get_array()
    assert data.max() == pytest.approx(tau[0][nb.valid].max())


# ---------------------------------------------------------------------------------------------
# Convergence


def _band_at(ax, xs):
    """{x: (low, high)} of the fill_between band vertices."""
    (coll,) = ax.collections
    out: dict[float, set] = {}
    for path in coll.get_paths():
        for vx, vy in path.vertices:
            out.setdefault(float(vx), set()).add(round(float(vy), 9))
    return {x: (min(out[x]), max(out[x])) for x in xs if x in out}, out


HIST = np.array([
    [np.inf, 9.0, 8.0, 7.0, 7.0],
    [np.inf, np.inf, 6.0, 6.0, 5.0],
    [np.inf, 12.0, 10.0, 9.0, 9.0],
    [np.inf, np.nan, 7.0, 7.0, 6.0],
    [np.inf, np.inf, np.inf, 8.0, 4.0],
])


def test_convergence_iqr_band_is_the_quantiles_of_runs_with_a_path():
    ax = plot_convergence(_ax(), HIST, band="iqr")
    (line,) = ax.lines
    xs = np.arange(1, 6)
    np.testing.assert_array_equal(line.get_xdata(), xs)
    y = np.asarray(line.get_ydata(), float)
    assert np.isnan(y[0])  # no run has a path after iteration 1: nothing drawn
    for t in range(1, 5):
        v = HIST[:, t][np.isfinite(HIST[:, t])]
        assert y[t] == pytest.approx(np.median(v))
    assert y[1] == pytest.approx(10.5)  # median of the two runs that found one (9, 12)
    band, verts = _band_at(ax, [float(x) for x in xs])
    assert 1.0 not in verts
    for t in range(1, 5):
        v = HIST[:, t][np.isfinite(HIST[:, t])]
        lo, hi = np.quantile(v, [0.25, 0.75])
        assert band[float(t + 1)] == (pytest.approx(lo), pytest.approx(hi))


@pytest.mark.parametrize("band", ["sd", "minmax"])
def test_convergence_other_bands(band):
    centre, low, high, found = convergence_bands(HIST, band)
    np.testing.assert_array_equal(found, [0, 2, 4, 5, 5])
    v = HIST[:, 3]
    if band == "sd":
        assert centre[3] == pytest.approx(v.mean())
        assert high[3] - centre[3] == pytest.approx(v.std(ddof=1))
        assert low[3] == pytest.approx(v.mean() - v.std(ddof=1))
    else:
        assert (centre[3], low[3], high[3]) == (np.median(v), v.min(), v.max())
    ax = plot_convergence(_ax(), HIST, band=band)
    b, _ = _band_at(ax, [4.0])
    assert b[4.0] == (pytest.approx(low[3]), pytest.approx(high[3]))


def test_convergence_one_run_has_a_zero_width_band():
    centre, low, high, _ = convergence_bands(np.array([5.0, 4.0, 3.0]), "sd")
    np.testing.assert_array_equal(centre, [5, 4, 3])
    np.testing.assert_array_equal(low, high)


def test_convergence_several_planners_and_x():
    ax = plot_convergence(_ax(), {"aco": HIST, "iaco": HIST[:, :3] - 1}, band="iqr")
    assert [ln.get_label() for ln in ax.lines] == ["aco", "iaco"]
    assert len(ax.collections) == 2
    assert len(ax.lines[1].get_xdata()) == 3
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["aco", "iaco"]
    ax = plot_convergence(_ax(), [HIST, HIST], labels=["a", "b"], band=None, x=np.arange(5) * 10)
    assert not ax.collections
    np.testing.assert_array_equal(ax.lines[0].get_xdata(), [0, 10, 20, 30, 40])


@pytest.mark.parametrize("args,kwargs,msg", [
    ((HIST,), {"band": "ci"}, "band must be one of"),
    ((HIST,), {"x": np.arange(4)}, r"x must have one value per iteration \(5\)"),
    ((np.zeros((2, 3, 4)),), {}, r"history must be \[R, I\]"),
    (({"a": HIST},), {"labels": ["a", "b"]}, "got 2 labels for 1 histories"),
])
def test_convergence_rejects_bad_input(args, kwargs, msg):
    with pytest.raises(ValueError, match=msg):
        plot_convergence(_ax(), *args, **kwargs)


# ---------------------------------------------------------------------------------------------
# Output


def test_save_figure_writes_atomically(tmp_path, grid):
    fig, ax = plt.subplots()
    plot_map(ax, grid, layer="height", show_turn_rule=True)
    out = tmp_path / "sub" / "map.png"
    assert save_figure(fig, str(out)) == [str(out)]
    assert out.read_bytes()[:4] == b"\x89PNG"
    assert [p.name for p in out.parent.iterdir()] == ["map.png"]


# ---------------------------------------------------------------------------------------------
# One visual language (issue 43, item 4): each rule checked on the artists


def _episode(traj, walkers=(), radii=(), plan=None, reason="goal"):
    """A `jaxplan.nav.Episode` from host data: poses ``[T, 3]`` (m, rad), walker centres ``[T, M, 2]``."""
    from types import SimpleNamespace

    from jaxplan.nav import Episode

    tr = np.asarray(traj, np.float32)
    T = len(tr)
    r = np.asarray(radii, np.float32).reshape(-1)
    pos = np.asarray(walkers, np.float32).reshape(T, r.shape[0], 2)
    return Episode(trajectory=tr, controls=np.zeros((T - 1, 2), np.float32), times=np.arange(T) * 0.2,
                   success=reason == "goal", reason=reason, collisions=0, time_s=(T - 1) * 0.2, metrics={},
                   plan=np.zeros((0, 2)) if plan is None else np.asarray(plan, np.float64),
                   waypoints=tr[[0, -1], :2], final_waypoints=tr[[0, -1], :2],
                   obstacles=SimpleNamespace(radii=r), obstacle_positions=pos)


def _walk(grid, T=30):
    """A robot crossing the open map diagonally and two walkers (radii 0.3 and 0.45 m) plus a padding slot."""
    from jaxplan.experiments import style  # noqa: F401 - the module under test is importable on its own

    H, W = grid.shape
    res = float(grid.resolution)
    s = np.linspace(0, 1, T)
    x = (0.5 + s * (W - 1.5)) * res
    y = (0.5 + s * (H - 1.5)) * res
    traj = np.stack([x, y, np.full(T, 0.6)], -1)
    w1 = np.stack([x[::-1], np.full(T, 0.5 * res)], -1)
    w2 = np.stack([np.full(T, (W - 0.5) * res), y], -1)
    pad = np.full((T, 2), 1e6)
    return _episode(traj, np.stack([w1, w2, pad], 1), [0.3, 0.45, 0.0], plan=np.array([[0, 0], [W - 1, H - 1]]))


def _outside(legend, ax) -> bool:
    """The legend's box and the axes' box do not overlap (in pixels, after a draw)."""
    ax.figure.canvas.draw()
    a, b = legend.get_window_extent(), ax.get_window_extent()
    return a.y1 <= b.y0 or a.y0 >= b.y1 or a.x1 <= b.x0 or a.x0 >= b.x1


def test_legend_sits_outside_even_a_tall_map_and_close_to_it():
    from jaxplan.experiments import style

    tall = jp.grid_from_array(np.ones((60, 12), bool), resolution=0.5)
    fig, ax = plt.subplots(figsize=style.map_figsize(tall), constrained_layout=True)
    plot_map(ax, tall)
    plot_paths(ax, tall, [np.array([[0, 0], [5, 50]])], labels=["p"], start=[0, 0], goal=[5, 50])
    legend = ax.get_legend()
    assert _outside(legend, ax)
    gap_in = (ax.get_window_extent().y0 - legend.get_window_extent().y1) / fig.dpi
    assert 0.0 < gap_in <= style.LEGEND_GAP_IN + 0.05  # below the axis label, not a fraction of the map away


def test_start_and_goal_markers_are_the_same_in_path_and_episode_pictures(grid):
    """A green circle and a red star everywhere: plot_paths (plan images, experiment figures) and the episode
    pictures (navigate --out png, the demo) draw them from one definition."""
    from matplotlib.colors import to_rgba

    from jaxplan.experiments import pictures, style

    a = plot_paths(_ax(), grid, [np.array([[0, 0], [3, 3]])], start=[0, 0], goal=[3, 3])
    b = pictures.draw_episodes(_ax(), grid, {"r": _walk(grid)}, footprint=0.25)
    for name, want in (("start", style.START), ("goal", style.GOAL)):
        got = [next(ln for ln in ax.lines if ln.get_label() == name) for ax in (a, b)]
        for ln in got:
            assert ln.get_marker() == want["marker"]
            assert to_rgba(ln.get_markerfacecolor()) == to_rgba(want["color"])
    assert style.START["color"] == "tab:green" and style.GOAL["color"] == "tab:red"
    assert style.START["marker"] == "o" and style.GOAL["marker"] == "*"


def test_walkers_are_discs_of_their_true_radius_with_dashed_paths(grid):
    from matplotlib.colors import to_rgba

    from jaxplan.experiments import pictures, style

    ep = _walk(grid)
    ax = pictures.draw_episodes(_ax(), grid, {"r": ep}, footprint=0.25)
    discs = [p for p in ax.patches if p.get_label() == "walkers at their closest approach (to scale)"]
    orange = to_rgba(style.WALKER["facecolor"])[:3]
    walkers = [p for p in ax.patches if type(p).__name__ == "Circle" and p.get_facecolor()[:3] == orange]
    assert len(discs) == 1 and sorted(p.get_radius() for p in walkers) == pytest.approx([0.3, 0.45])
    # the padding slot (radius 0, far away) is not drawn and did not move the view
    assert all(p.get_radius() > 0 for p in ax.patches if type(p).__name__ == "Circle")
    assert ax.get_xlim()[1] < 100
    paths = [ln for ln in ax.lines if ln.get_linestyle() == "--" and ln.get_color() == "tab:orange"]
    assert len(paths) == 2 and paths[0].get_label() == "walkers' paths"
    np.testing.assert_allclose(paths[0].get_xydata(), ep.obstacle_positions[:, 0])
    # each disc where the walker was when the robot came closest to it
    tr = ep.trajectory[:, :2]
    for j, disc in zip((0, 1), sorted(walkers, key=lambda p: p.get_radius()), strict=True):
        k = int(np.argmin(np.hypot(*(ep.obstacle_positions[:, j] - tr).T)))
        np.testing.assert_allclose(disc.center, ep.obstacle_positions[k, j], atol=1e-6)
    assert not unlabelled_marks(ax), unlabelled_marks(ax)
    assert _outside(ax.get_legend(), ax)


def test_robot_footprint_is_drawn_to_scale(grid):
    from jaxplan.dwa import Disc, Rectangle
    from jaxplan.experiments import style

    ax = _ax()
    disc = style.draw_footprint(ax, (1.0, 2.0, 0.3), Disc(0.35))
    assert disc.get_radius() == pytest.approx(0.35) and tuple(disc.center) == (1.0, 2.0)
    rect = style.draw_footprint(ax, (1.0, 2.0, np.pi / 2), Rectangle(0.8, 0.5, 3))
    # corners in data units: 0.8 m along the heading (here +y), 0.5 m across
    corners = (rect.get_transform() - ax.transData).transform(
        rect.get_path().vertices[:4])
    np.testing.assert_allclose(np.ptp(corners, axis=0), [0.5, 0.8], atol=1e-9)
    np.testing.assert_allclose(corners.mean(axis=0), [1.0, 2.0], atol=1e-9)
    with pytest.raises(ValueError, match="footprint must be"):
        style.draw_footprint(ax, (0, 0), "big")


def test_keepout_and_speed_zones_are_drawn_apart_from_walls_each_in_the_legend():
    from jaxplan.experiments import style

    free = np.ones((8, 10), bool)
    free[0, :] = False  # a wall
    keep = np.zeros_like(free)
    keep[4:6, 2:5] = True  # a keep-out zone (blocked for the planners)
    free &= ~keep
    limit = np.ones(free.shape, np.float32)
    limit[6:8, 6:10] = 0.5
    limit[2, 6:8] = 0.8
    g = jp.grid_from_array(free, resolution=0.5, speed_limit=limit)
    fig, ax = plt.subplots()
    plot_map(ax, g, keepout=keep)
    legend = legend_outside(ax)
    texts = [t.get_text() for t in legend.get_texts()]
    assert texts == ["speed zone: 50 % of top speed", "speed zone: 80 % of top speed", "keep-out zone (Nav2 mask)",
                     style.WALL_LABEL]
    ko = next(p for p in ax.patches if p.get_label() == "keep-out zone (Nav2 mask)")
    assert ko.get_hatch() and ko.get_path().contains_point((0.5 * 3.5, 0.5 * 4.5))  # cell (3, 4)'s centre
    assert not ko.get_path().contains_point((0.5 * 0.5, 0.5 * 0.5))  # the wall is not keep-out
    # the walls' image leaves keep-out cells to the hatch: they do not read as walls
    walls = next(im for im in ax.images if im.get_label() == "blocked").get_array()
    assert walls.mask[4, 3] and not walls.mask[0, 3]
    # a map without zones keeps its plain legend (no wall entry)
    ax2 = _ax()
    plot_map(ax2, jp.grid_from_array(free, resolution=0.5))
    assert ax2.get_legend_handles_labels()[1] == []


def test_keepout_mask_of_a_ros_map_is_the_cells_the_mask_blocked(ros):
    from jaxplan.experiments import style

    opts = {"keepout": str(ros / "warehouse_keepout.yaml")}
    masked = jp.load_map(ros / "warehouse.yaml", resolution=0.3, **opts)
    bare = jp.load_map(ros / "warehouse.yaml", resolution=0.3)
    keep = style.keepout_mask(ros / "warehouse.yaml", masked, opts)
    np.testing.assert_array_equal(keep, np.asarray(bare.free) & ~np.asarray(masked.free))
    assert keep.any() and not (keep & ~np.asarray(bare.free)).any()
    assert style.keepout_mask(ros / "warehouse.yaml", masked, {}) is None


def test_a_ros_map_is_drawn_in_its_world_frame_y_up():
    g = jp.grid_from_array(np.ones((4, 6), bool), resolution=0.5, origin=(-1.0, -2.0))
    ax = plot_map(_ax(), g, y_up=True)
    assert ax.get_ylim() == (-2.0, 0.0) and ax.get_xlim() == (-1.0, 2.0)  # y grows upwards
    assert ax.get_xlabel() == "x (m, map frame)" and ax.get_ylabel() == "y (m, map frame)"
    assert plot_map(_ax(), g).get_ylim() == (0.0, -2.0)  # MovingAI convention: row 0 at the top


def test_gif_layout_rule():
    from jaxplan.experiments import style

    # a small map: enlarged to FIT_PX on its longer side, shown whole, its aspect kept
    lay = style.gif_layout((20.0, 10.0), 0.5)
    assert not lay.cropped and lay.view_px == (style.FIT_PX, style.FIT_PX // 2)
    assert lay.robot_px >= style.MIN_ROBOT_PX
    # the demo's 48 x 32 m warehouse: the robot sets the scale, the map still fits whole
    lay = style.gif_layout((48.0, 32.0), 0.5)
    assert not lay.cropped and lay.robot_px == pytest.approx(style.MIN_ROBOT_PX)
    assert lay.view_px[0] / lay.view_px[1] == pytest.approx(48 / 32, rel=0.01)
    # MovingAI's warehouse-10-20-10-2-1 (161 x 63 m): whole, the robot would be 2 px; a window follows it
    lay = style.gif_layout((161.0, 63.0), 0.5)
    assert lay.cropped and lay.robot_px == pytest.approx(style.MIN_ROBOT_PX)
    assert lay.view_px == style.WINDOW_PX
    with pytest.raises(ValueError, match="robot size must be positive"):
        style.gif_layout((10.0, 10.0), 0.0)
    assert style.follow_window((1.0, 1.0), (4.0, 2.0), (0.0, 10.0, 0.0, 5.0)) == (0.0, 4.0, 0.0, 2.0)
    assert style.follow_window((9.5, 3.0), (4.0, 2.0), (0.0, 10.0, 0.0, 5.0)) == (6.0, 10.0, 2.0, 4.0)


@pytest.mark.parametrize("shape", [(10, 20), (63, 161)])
def test_gif_frames_keep_the_maps_aspect_the_robots_size_and_a_time_stamp(tmp_path, shape):
    from PIL import Image

    from jaxplan.experiments import pictures, style

    g = jp.grid_from_array(np.ones(shape, bool), resolution=1.0)
    ep = _walk(g, T=12)
    fig, draw, lay = pictures.gif_figure({"r": ep}, g, footprint=0.25)
    ax = fig.axes[0]
    draw(6)
    fig.canvas.draw()
    box = ax.get_window_extent()
    x0, x1 = ax.get_xlim()
    y0, y1 = sorted(ax.get_ylim())
    assert box.width / box.height == pytest.approx((x1 - x0) / (y1 - y0), rel=0.01)  # metres are square
    if shape == (10, 20):
        assert not lay.cropped and (x1 - x0, y1 - y0) == (20.0, 10.0)  # the whole map, its aspect
    else:
        assert lay.cropped and (x1 - x0) < 161 and len(fig.axes) == 2  # a window, and the overview
        assert x0 <= ep.trajectory[6, 0] <= x1 and y0 <= ep.trajectory[6, 1] <= y1  # around the robot
    robot = next(p for p in ax.patches if (p.get_label() or "").startswith("robot"))
    assert robot.get_window_extent().width >= style.MIN_ROBOT_PX - 0.5
    assert ax.get_title(loc="left").startswith(f"t = {6 * 0.2:6.1f} s")
    assert _outside(fig.legends[0], ax)
    size = tuple(int(round(v)) for v in fig.get_size_inches() * style.GIF_DPI)
    plt.close(fig)
    out = pictures.animate_episodes({"r": ep}, g, tmp_path / "e.gif", frames=3, footprint=0.25)
    with Image.open(out[0]) as im:
        assert im.size == size and im.n_frames == 3


def test_navigate_png_shows_trajectory_start_goal_and_walkers(tmp_path, grid):
    from jaxplan.cli.outputs import write_episode
    from jaxplan.experiments import pictures

    ep = _walk(grid)
    out = write_episode(tmp_path / "e.png", ep, grid, {"map": "m.map", "pipeline": "iaco_dwa"}, footprint=0.25)
    assert out.read_bytes()[:4] == b"\x89PNG"
    fig = pictures.episode_figure(grid, {"iaco_dwa": ep}, footprint=0.25)
    ax = fig.axes[0]
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    for want in ("global plan", "executed: iaco_dwa (goal)", "robot at the end (footprint to scale)",
                 "walkers' paths", "walkers at their closest approach (to scale)", "start", "goal"):
        assert want in texts, texts
    assert _outside(ax.get_legend(), ax)
    plt.close(fig)


def test_several_robots_never_take_the_walkers_or_the_start_and_goal_colours(grid):
    from matplotlib.colors import to_rgba

    from jaxplan.experiments import pictures, style

    eps = {f"r{k}": _walk(grid) for k in range(len(style.ROBOTS))}
    ax = pictures.draw_episodes(_ax(), grid, eps, footprint=0.25)
    taken = {to_rgba(c) for c in (style.WALKER["facecolor"], style.START["color"], style.GOAL["color"])}
    robots = [ln for ln in ax.lines if ln.get_label().startswith("executed: ")]
    assert len({to_rgba(ln.get_color()) for ln in robots}) == len(eps)  # one colour each
    assert not {to_rgba(ln.get_color()) for ln in robots} & taken
    assert "robot at a walker's closest approach (r0)" in ax.get_legend_handles_labels()[1]
