"""The claims file (configs/results/claims.toml) and the one-judgement rule: every claim names runs that exist,
every paper has at least four testable claims, every metric a margin, and every paper number is judged on exactly
one page (`jaxplan.experiments.claims`, `jaxplan.experiments.results`)."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

import pytest

from jaxplan.experiments.claims import check_claims, load_claims
from jaxplan.experiments.config import load_config
from jaxplan.experiments.reproduce import reproduction_configs
from jaxplan.papers import PAPERS

ROOT = Path(__file__).resolve().parents[1]
CLAIMS = ROOT / "configs" / "results" / "claims.toml"

# Two different cells of one paper that happen to print the same number: not one number judged twice.
COINCIDENCES = {("chen2023", "converged_iteration", 4.0, None): "Table 2's Case 1 and Table 4's Case 2 group 3"}


@pytest.fixture(scope="module")
def configs():
    out = {}
    for p in reproduction_configs(ROOT / "configs"):
        c = load_config(p)
        out[c.name] = c
    return out


def test_the_claims_resolve_against_the_configs_and_cover_every_paper(configs):
    claims = load_claims(CLAIMS)
    assert check_claims(claims, configs) == []
    testable = defaultdict(int)
    for c in claims.claims:
        testable[c.paper] += c.test != "not_testable"
    assert all(testable[k] >= 4 for k in PAPERS), dict(testable)
    for cfg in configs.values():
        for v in cfg.paper:
            assert v.metric in claims.margins, f"{cfg.name}: no margin for {v.metric}"


def test_no_paper_number_is_judged_on_two_pages(configs):
    """A number is judged once: on one page (configs), and there in one cell (a number for every map of a
    config is pooled over them, `jaxplan.experiments.results.paper_cells`)."""
    seen = defaultdict(list)
    for cfg in configs.values():
        paper = cfg.name.split("_")[0]
        for v in cfg.paper:
            fams = {m.map_family for m in cfg.maps if v.map in (None, m.map_family)
                    and any(pc.label == v.planner and (pc.kind == "tsp") == m.is_tsp for pc in cfg.planners)}
            assert fams, f"{cfg.name}: {v.planner} {v.metric} = {v.mean} is judged on no map"
            seen[paper, v.metric, v.mean, v.sd].append(cfg.name)
    twice = {k: names for k, names in seen.items() if len(set(names)) > 1 and k not in COINCIDENCES}
    assert not twice, twice


def test_a_claims_file_with_mistakes_is_refused_by_name(tmp_path):
    f = tmp_path / "claims.toml"
    f.write_text('[margins]\nlength = { rel = 0.03 }\nturns = { abs = -1 }\n\n'
                 '[[claims]]\nid = "x.a"\npaper = "cui2025"\nclaim = "c"\nwhere = "T1"\ntest = "contrast"\n'
                 'config = "cui2025_table2"\nmetric = "length"\nproposed = "A"\n\n'
                 '[[claims]]\nid = "x.a"\npaper = "nobody2000"\nclaim = "c"\nwhere = "T1"\ntest = "guess"\n')
    with pytest.raises(ValueError) as e:
        load_claims(f)
    msg = str(e.value)
    for part in ("margins.turns", "needs 'baseline'", "needs 'direction'", "test must be one of"):
        assert part in msg, msg
    f.write_text('[[claims]]\nid = "x.a"\npaper = "cui2025"\nclaim = "c"\nwhere = "T1"\ntest = "contrast"\n'
                 'config = "cui2025_table2"\nmetric = "length"\nproposed = "A"\nbaseline = "B"\n'
                 'direction = "higher"\n')
    with pytest.raises(ValueError, match="no margin for metric 'length'"):
        load_claims(f)
