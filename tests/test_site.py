"""The documentation site and the generated benchmarks page.

- `mkdocs build --strict` passes (no broken link, anchor or API reference), when mkdocs is installed
  (``pip install -e '.[docs]'``); the home page is the README and the changelog is in the site.
- Every public name of ``jaxplan`` (its lazy export table) has an entry ``::: jaxplan.NAME`` in docs/api/.
- The hooks (scripts/mkdocs_hooks.py) move a link from its repository meaning to its place in the site.
- docs/benchmarks.md is what benchmarks/page.py makes of the JSON records in benchmarks/results/, and a record
  written by benchmarks/_timing.py's `Record` is one the page reads.
"""

from __future__ import annotations

import importlib.util
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pytest
from conftest import ROOT

BENCHMARKS = ROOT / "benchmarks"


def _module(path: Path, name: str):
    """The module at ``path`` (scripts and benchmarks are folders of scripts, not packages)."""
    sys.path.insert(0, str(path.parent))  # their own sibling imports (`_timing`)
    try:
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module  # dataclasses look their module up there
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(str(path.parent))
    return module


@pytest.fixture(scope="module")
def page():
    return _module(BENCHMARKS / "page.py", "benchmarks_page")


# ---------------------------------------------------------------------------------------------
# The API reference


def test_every_public_name_has_an_api_entry():
    import jaxplan

    public = {name for names in jaxplan._EXPORTS.values() for name in names}
    text = "\n".join(p.read_text() for p in sorted((ROOT / "docs" / "api").glob("*.md")))
    entries = re.findall(r"^::: jaxplan\.([\w.]+)\s*$", text, re.M)
    assert len(entries) == len(set(entries)), "a name has two API entries"
    missing = sorted(public - set(entries))
    assert not missing, f"public names without an entry in docs/api/*.md: {missing}"
    assert {"tune", "experiments", "scale"} <= set(entries), "the public subpackages' pages"
    nav = (ROOT / "mkdocs.yml").read_text()
    unlisted = [p.name for p in (ROOT / "docs" / "api").glob("*.md") if f"api/{p.name}" not in nav]
    assert not unlisted, f"API pages missing from mkdocs.yml's nav: {unlisted}"


def test_griffe_extension_finds_the_lazily_exported_names():
    pytest.importorskip("griffe", reason="the docs extra (pip install -e '.[docs]') is not installed")
    ext = _module(ROOT / "scripts" / "griffe_exports.py", "griffe_exports")
    top = ext.lazy_exports("jaxplan")
    assert top["plan"] == "jaxplan.planning.plan"
    assert all(target.startswith("jaxplan.") and target.endswith("." + name) for name, target in top.items())
    import jaxplan

    assert set(top) == {name for names in jaxplan._EXPORTS.values() for name in names}


# ---------------------------------------------------------------------------------------------
# Links


def _config(tmp_path: Path) -> dict:
    return {"config_file_path": str(ROOT / "mkdocs.yml"), "docs_dir": str(ROOT / "docs"), "site_dir": str(tmp_path)}


def _rewrite(src_uri: str, markdown: str, tmp_path: Path) -> str:
    hooks = _module(ROOT / "scripts" / "mkdocs_hooks.py", "mkdocs_hooks")
    page = SimpleNamespace(file=SimpleNamespace(src_uri=src_uri))
    return hooks.on_page_markdown(markdown, page, _config(tmp_path), files=None)


def test_links_move_from_the_repository_to_the_site(tmp_path):
    pytest.importorskip("mkdocs", reason="mkdocs is not installed (pip install -e '.[docs]')")
    readme = _rewrite("index.md", "[guide](docs/guide/planners.md#the-registry) [log](CHANGELOG.md) "
                                  "[cfg](configs/cui2025_table2.toml) `[not](a/link.md)` [web](https://x.org/a.md)",
                      tmp_path)
    assert readme == ("[guide](guide/planners.md#the-registry) [log](changelog.md) "
                      "[cfg](repo/configs/cui2025_table2.toml) `[not](a/link.md)` [web](https://x.org/a.md)")
    result = _rewrite("results/index.md", "![f](../../figures/x/a.png) [p](cui2025/table2.md) [d](../decisions.md)",
                      tmp_path)
    assert result == "![f](../repo/figures/x/a.png) [p](cui2025/table2.md) [d](../decisions.md)"
    fenced = "```bash\n[x](../../figures/a.png)\n```\n"
    assert _rewrite("results/index.md", fenced, tmp_path) == fenced


@pytest.mark.slow  # 20-32 s on 2 shared cores (rendering every API page); CI runs it with the slow tests
def test_mkdocs_build_strict(tmp_path):
    pytest.importorskip("mkdocs", reason="mkdocs is not installed (pip install -e '.[docs]')")
    pytest.importorskip("mkdocstrings", reason="mkdocstrings is not installed (pip install -e '.[docs]')")
    site = tmp_path / "site"
    t0 = time.perf_counter()
    res = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(ROOT / "mkdocs.yml"),
                          "-d", str(site)], cwd=ROOT, capture_output=True, text=True, timeout=600,
                         env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    wall = time.perf_counter() - t0
    problems = [line for line in res.stderr.splitlines() if line.startswith(("WARNING", "ERROR"))]
    assert res.returncode == 0, f"mkdocs build --strict failed ({wall:.0f} s):\n" + "\n".join(
        problems or res.stderr.splitlines()[-20:])
    home = (site / "index.html").read_text()
    assert "jaxplan demo" in home, "the home page is the README"
    assert (site / "changelog" / "index.html").is_file()
    api = re.sub(r"<[^>]+>", " ", (site / "api" / "planning" / "index.html").read_text())
    assert "jaxplan.plan_batch" in api and "Parameters" in api, "the docstrings are rendered, sections parsed"


# ---------------------------------------------------------------------------------------------
# docs/benchmarks.md


def test_benchmarks_page_is_generated_from_the_records(page):
    committed = (ROOT / "docs" / "benchmarks.md").read_text()
    assert committed == page.render(), ("docs/benchmarks.md is not what benchmarks/page.py makes of "
                                        "benchmarks/results/*.json: run `python benchmarks/run_all.py --page`")


def test_transcribed_records_say_so(page):
    for rec in page.load_records():
        if rec.get("source"):
            assert rec["source"].startswith("transcribed from docs/benchmarks.md of "), rec["file"]


def _record(bench: str, started: str, tables: dict[str, list], quick: bool = False) -> dict:
    return {"bench": bench, "started_utc": started, "quick": quick, "file": f"{bench}-{started}.json",
            "tables": [{"name": n, "title": n, "columns": ["x"], "rows": rows, "notes": []}
                       for n, rows in tables.items()]}


def test_page_shows_the_newest_full_table_of_each_name(page):
    old = _record("bench_x", "2026-01-01", {"a": [[1]], "b": [[2]]})
    new = _record("bench_x", "2026-02-01", {"a": [[3]]})
    newer_quick = _record("bench_x", "2026-03-01", {"a": [[4]], "c": [[5]]}, quick=True)
    other = _record("bench_y", "2026-04-01", {"a": [[6]]})
    got = [(rec["started_utc"], t["name"], t["rows"][0][0])
           for rec, t in page.latest_tables([old, new, newer_quick, other], "bench_x")]
    assert got == [("2026-02-01", "a", 3), ("2026-01-01", "b", 2), ("2026-03-01", "c", 5)]


def test_cells_read_as_figures(page):
    assert [page.cell(x) for x in (None, float("nan"), True, 12345, 8468.0, 442.2, 293.0, 16.41, 0.0926, 1e-5,
                                   "a|b", [1.5, 2])] == [
        "—", "—", "yes", "12,345", "8,468", "442.2", "293", "16.4", "0.0926", "1.0e-05", "a\\|b", "1.5, 2"]


def test_a_record_written_by_the_benchmarks_is_read_by_the_page(tmp_path, page):
    timing = _module(BENCHMARKS / "_timing.py", "_timing")
    record = timing.Record("bench_smoke", {"rows": 3, "data_dir": Path("/x")})
    rows = record.table("speed", ["what", "ms"], "a smoke table")
    rows.append(["step", 1.25])
    record.note("a note")
    record.table("empty", ["x"])  # a table without rows is left out
    path = record.write(tmp_path / "bench_smoke-2026-01-01-0000-abc.json")
    data = json.loads(path.read_text())
    assert data["options"] == {"rows": 3, "data_dir": "/x"} and data["machine_line"]
    records = page.load_records(tmp_path)
    assert [t["name"] for t in records[0]["tables"]] == ["speed"]
    text = page.render(records)
    assert "## bench_smoke" in text and "| step | 1.25 |" in text and "a note" in text
    with pytest.raises(ValueError, match="not a benchmark record"):
        (tmp_path / "other.json").write_text("{}")
        page.load_records(tmp_path)
