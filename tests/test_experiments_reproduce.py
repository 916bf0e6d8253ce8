"""The reproduction configs (configs/<paper>_*.toml): each validates, stores the paper's numbers and documents its
deviations; `jaxplan reproduce --quick` runs them all and draws their figures (the quick runs together must stay
within the issue's CI budget of 3 min)."""

from __future__ import annotations

from pathlib import Path

import pytest

from jaxplan.cli import main
from jaxplan.experiments.config import load_config
from jaxplan.experiments.reproduce import reproduction_configs
from jaxplan.papers import PAPERS

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = reproduction_configs(ROOT / "configs")


def test_every_paper_has_a_reproduction_config():
    names = [p.name for p in CONFIGS]
    assert all(any(n.startswith(f"{key}_") for n in names) for key in PAPERS), names


@pytest.mark.parametrize("path", CONFIGS, ids=lambda p: p.stem)
def test_reproduction_config_is_complete(path):
    from jaxplan.experiments.claims import load_claims

    cfg = load_config(path)
    claims = [c for c in load_claims(ROOT / "configs" / "results" / "claims.toml").claims if c.config == cfg.name]
    assert cfg.paper or claims, "the paper's numbers or claims it holds the evidence of"
    if cfg.paper:
        assert cfg.paper_source.startswith(PAPERS[path.stem.split("_")[0]].short), "labelled with their table"
    assert cfg.quick.seeds and cfg.figures
    assert "Deviations from the paper" in path.read_text()


def test_reproduce_quick_runs_every_config_and_draws_its_figures(tmp_path, capsys):
    rc = main(["reproduce", "--quick", "--configs", str(ROOT / "configs"), "--out", str(tmp_path / "runs"),
               "--figures", str(tmp_path / "figures"), "--no-progress", "--no-cache",
               "--results", str(tmp_path / "results")])
    out = capsys.readouterr().out
    assert rc == 0, out
    index = (tmp_path / "figures" / "index.md").read_text()
    for p in CONFIGS:
        run = tmp_path / "runs" / f"{load_config(p).name}-quick"
        assert (run / "trials.csv").is_file() and (run / "report.md").is_file()
        assert f"({run.name}/index.md)" in index
        assert "paper" in (run / "summary.md").read_text()
    # the results pages of quick runs say so, in their names, titles and the index (issue 28)
    results = (tmp_path / "results" / "index-quick.md").read_text()
    assert results.startswith("# Reproduction results — QUICK")
    for p in CONFIGS:
        paper, _, table = p.stem.partition("_")
        page = tmp_path / "results" / paper / f"{table}-quick.md"
        assert page.read_text().startswith(f"# {p.stem} — QUICK"), page
        assert f"({paper}/{table}-quick.md)" in results
    assert "(li2026/fig7-quick.md)" in results  # li2026's optimiser study, not a config
    assert not (tmp_path / "results" / "index.md").exists()


def test_quick_keeps_only_the_named_planners_and_maps():
    from jaxplan.experiments.config import ConfigError, apply_quick, parse_config

    text = (ROOT / "configs" / "yu2020_tables2_3.toml").read_text()
    q = apply_quick(parse_config(text))
    assert [m.name for m in q.maps] == ["map30"] and [p.label for p in q.planners] == ["ACO", "P-RACO"]
    bad = text.replace('maps = ["map30"]', 'maps = ["map31"]\nplanners = ["PRACO"]')
    with pytest.raises(ConfigError) as e:
        parse_config(bad)
    assert "experiment.quick.maps[0]: unknown map 'map31'" in str(e.value)
    assert "experiment.quick.planners[0]: unknown planner 'PRACO'" in str(e.value)


def test_hausdorff_to_the_exact_path_is_zero_for_astar(tmp_path):
    import numpy as np

    from jaxplan.experiments.runner import run_experiment
    from jaxplan.experiments.stats import read_trials

    cfg = tmp_path / "h.toml"
    cfg.write_text("""
metrics = ["success", "length", "hausdorff"]
[experiment]
name = "h"
seeds = 2
chunk = 2
[[maps]]
name = "wh"
generator = "warehouse"
seed = 0
params = { width = 14, height = 10, shelf_length = 4, shelf_depth = 2, aisle = 1, cross_aisle = 2 }
[scenarios]
source = "random"
count = 2
seed = 3
min_distance = 5.0
[[planners]]
label = "A*"
kind = "plan"
name = "astar"
[[planners]]
label = "AS"
kind = "plan"
name = "aco"
overrides = { ants = 6, iterations = 3, dead_end = "retreat" }
""")
    t = read_trials(run_experiment(cfg, tmp_path / "runs", progress=False) / "trials.csv")
    astar = t["planner"] == "A*"
    assert np.all(t["hausdorff"][astar] == 0.0)
    h = t["hausdorff"][~astar & (t["success"] == 1)]
    assert h.size and np.all(np.isfinite(h) & (h >= 0))


def _fake_reproduction(tmp_path, monkeypatch, run_fails=(), figures_fail=()):
    """Three empty configs; `run_experiment` and `draw_figures` replaced by stand-ins that fail where asked."""
    from jaxplan.experiments import figures, runner

    for n in ("seedA", "seedB", "seedC"):
        (tmp_path / f"{n}.toml").write_text("")

    def run(cfg, out, **kw):
        if Path(cfg).stem in run_fails:
            raise FloatingPointError("broke mid-run")
        d = Path(out) / Path(cfg).stem
        d.mkdir(parents=True, exist_ok=True)
        return d

    def draw(run_dir, out, **kw):
        if Path(run_dir).name in figures_fail:
            raise IndexError("index 9 is out of bounds")
        return [object()], ["paths_sc9 (paths): figure 'paths_sc9': scenario 9 is past map 'm''s 4 scenarios"]

    monkeypatch.setattr(runner, "run_experiment", run)
    monkeypatch.setattr(figures, "draw_figures", draw)
    return sorted(tmp_path.glob("seed*.toml"))


def test_reproduce_goes_on_after_a_config_fails_to_run_or_draw(tmp_path, monkeypatch):
    from jaxplan.experiments.reproduce import reproduce

    configs = _fake_reproduction(tmp_path, monkeypatch, run_fails=("seedA",), figures_fail=("seedB",))
    done = reproduce(configs, tmp_path / "runs", tmp_path / "figs", progress=False)
    assert [d.config.stem for d in done] == ["seedA", "seedB", "seedC"]
    assert done[0].run_dir is None and done[0].error == "FloatingPointError: broke mid-run"
    assert done[1].run_dir is not None and done[1].error == "figures: IndexError: index 9 is out of bounds"
    assert done[2].error is None and done[2].figures == 1 and len(done[2].problems) == 1


def test_reproduce_reports_every_failure_and_exits_2_at_the_end(tmp_path, monkeypatch, capsys):
    _fake_reproduction(tmp_path, monkeypatch, run_fails=("seedA",), figures_fail=("seedB",))
    argv = ["reproduce", "--configs", str(tmp_path), "--pattern", "seed*.toml", "--out", str(tmp_path / "runs"),
            "--figures", str(tmp_path / "figs"), "--no-progress", "--no-cache"]
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert "seedA.toml: FloatingPointError: broke mid-run" in err
    assert "seedB.toml: figures: IndexError: index 9 is out of bounds" in err
    assert "seedC.toml: not drawn: paths_sc9" in err and "seedC.toml  seedC" in out  # the last config still ran
