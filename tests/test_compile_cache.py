"""The on-disk compilation caches (`jaxplan.core.compile_cache`): where they go, ``JAXPLAN_CACHE`` and ``off``,
turning them on once and on first use, a second process loading what the first compiled, and the notice."""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from jaxplan.cli import build_parser
from jaxplan.core import compile_cache as cc

ROOT = Path(__file__).resolve().parents[1]
_BLOCK = "\n#--\n"  # separates the blocks of a child's code


def _child(code: str, env: dict[str, str]) -> dict:
    """Runs ``code`` (blocks dedented one by one) in a fresh interpreter with ``env`` added (and no JAX or numba
    cache settings of the caller); returns the JSON object of its last line."""
    base = {k: v for k, v in os.environ.items()
            if k not in ("JAXPLAN_CACHE", "NUMBA_CACHE_DIR", "JAX_COMPILATION_CACHE_DIR", "XDG_CACHE_HOME")}
    base["PYTHONPATH"] = os.pathsep.join([str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])
    source = "\n".join(map(textwrap.dedent, code.split(_BLOCK)))
    proc = subprocess.run([sys.executable, "-c", source], env={**base, **env}, capture_output=True, text=True,
                          timeout=300, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def test_folder_follows_jaxplan_cache_xdg_and_home(tmp_path):
    assert cc.cache_folder({"JAXPLAN_CACHE": str(tmp_path / "c")}) == tmp_path / "c"
    assert cc.cache_folder({"JAXPLAN_CACHE": "~/c"}) == Path.home() / "c"
    for off in ("off", "OFF", " Off "):
        assert cc.cache_folder({"JAXPLAN_CACHE": off}) is None
    assert cc.cache_folder({"XDG_CACHE_HOME": str(tmp_path)}) == tmp_path / "jaxplan"
    assert cc.cache_folder({"JAXPLAN_CACHE": "", "XDG_CACHE_HOME": ""}) == Path.home() / ".cache" / "jaxplan"


STATE = """
    import json, os, jax
    def state():
        return {"jax": jax.config.jax_compilation_cache_dir, "numba": os.environ.get("NUMBA_CACHE_DIR"),
                "numba_config": __import__("numba").core.config.CACHE_DIR if "numba" in __import__("sys").modules
                else None}
#--
"""


def test_enable_honours_jaxplan_cache_and_is_idempotent(tmp_path):
    out = _child(STATE + """
        import jaxplan as jp
        before = state()
        first = str(jp.enable_compilation_cache())
        again = str(jp.enable_compilation_cache())
        import jaxplan.grid  # first use of the compiled parts: nothing changes
        after = state()
        other = str(jp.enable_compilation_cache(os.environ["OTHER"]))
        print(json.dumps({"before": before, "first": first, "again": again, "after": after, "other": other,
                          "moved": state()}))
        """, {"JAXPLAN_CACHE": str(tmp_path / "c"), "OTHER": str(tmp_path / "o")})
    folder = (tmp_path / "c").resolve()
    assert out["before"]["jax"] is None and out["before"]["numba"] is None
    assert out["first"] == out["again"] == str(folder)
    assert out["after"] == {"jax": str(folder / "jax"), "numba": str(folder / "numba"),
                            "numba_config": str(folder / "numba")}
    assert (folder / "jax").is_dir() and (folder / "numba").is_dir()
    other = (tmp_path / "o").resolve()
    assert out["other"] == str(other) and out["moved"]["jax"] == str(other / "jax")
    assert out["moved"]["numba"] == str(other / "numba")  # jaxplan's own setting moves; a user's would not


def test_first_use_turns_the_caches_on_and_off_turns_them_off(tmp_path):
    code = STATE + """
        import jaxplan
        untouched = state()
        import jaxplan.grid  # first use: the numba kernels' module sets the folders before their decoration
        print(json.dumps({"untouched": untouched, "used": state()}))
        """
    on = _child(code, {"XDG_CACHE_HOME": str(tmp_path)})
    folder = (tmp_path / "jaxplan").resolve()
    assert on["untouched"] == {"jax": None, "numba": None, "numba_config": None}  # import jaxplan: no side effect
    assert on["used"] == {"jax": str(folder / "jax"), "numba": str(folder / "numba"),
                          "numba_config": str(folder / "numba")}
    off = _child(code, {"XDG_CACHE_HOME": str(tmp_path / "x"), "JAXPLAN_CACHE": "off"})
    assert off["used"]["jax"] is None and off["used"]["numba"] is None and not (tmp_path / "x").exists()
    mine = _child(code, {"JAXPLAN_CACHE": str(tmp_path / "c"), "NUMBA_CACHE_DIR": str(tmp_path / "mine")})
    assert mine["used"]["numba"] == str(tmp_path / "mine")  # a user's NUMBA_CACHE_DIR stands
    assert mine["used"]["jax"] == str((tmp_path / "c" / "jax").resolve())


def test_disable_after_enable_turns_jax_and_numba_back(tmp_path):
    out = _child(STATE + """
        from jaxplan.core.compile_cache import disable_compilation_cache, enable_compilation_cache
        on = str(enable_compilation_cache())
        disable_compilation_cache()
        import jaxplan.grid  # first use after a decision: stays off
        print(json.dumps({"on": on, "off": state()}))
        """, {"JAXPLAN_CACHE": str(tmp_path)})
    assert out["on"] == str(tmp_path.resolve())
    assert out["off"] == {"jax": None, "numba": None, "numba_config": ""}


def test_a_second_process_compiles_nothing_new(tmp_path):
    code = """
        import json, jax, jax.numpy as jnp
        import jaxplan.core.geometry as g  # first use: the caches on, in $JAXPLAN_CACHE
        events = []  # cache_misses: a program compiled and written; cache_hits: one loaded
        jax.monitoring.register_event_listener(lambda e, **kw: events.append(e.rsplit("/", 1)[-1]))
        d = jax.jit(g.point_segment_distance)(jnp.zeros(2), jnp.ones(2), jnp.full(2, 2.0))
        n = g.segment_square_distance_nb(0.0, 0.0, 1.0, 1.0, 3.0, 3.0)
        stats = g.segment_square_distance_nb.stats
        print(json.dumps({"jax_hits": events.count("cache_hits"), "jax_misses": events.count("cache_misses"),
                          "numba_hits": sum(stats.cache_hits.values()),
                          "numba_misses": sum(stats.cache_misses.values()), "d": float(d), "n": n}))
        """
    env = {"JAXPLAN_CACHE": str(tmp_path)}
    first = _child(code, env)
    files = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*") if p.is_file())
    assert any(p.parts[0] == "jax" for p in files) and any(p.suffix == ".nbi" for p in files)
    assert first["jax_misses"] >= 1 and first["numba_misses"] >= 1
    second = _child(code, env)
    assert sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*") if p.is_file()
                  if not p.name.endswith("-atime")) == [p for p in files if not p.name.endswith("-atime")]
    assert second["jax_misses"] == 0 and second["jax_hits"] >= first["jax_misses"]
    assert second["numba_misses"] == 0 and second["numba_hits"] >= 1
    assert (second["d"], second["n"]) == (first["d"], first["n"])


def test_an_unwritable_folder_is_skipped_on_first_use_and_named_by_an_explicit_call(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    out = _child(STATE + """
        import jaxplan.grid  # first use: no cache, no failure
        used = state()
        from jaxplan.core.compile_cache import enable_compilation_cache
        try:
            enable_compilation_cache(os.environ["JAXPLAN_CACHE"])
            error = None
        except OSError as e:
            error = str(e)
        print(json.dumps({"used": used, "error": error}))
        """, {"JAXPLAN_CACHE": str(blocker / "sub")})
    assert out["used"]["jax"] is None and out["used"]["numba"] is None
    assert out["error"] is not None and str(blocker / "sub") in out["error"] and "JAXPLAN_CACHE" in out["error"]


@pytest.mark.parametrize("argv", [
    ["demo"], ["plan", "m.map", "--start", "0", "0", "--goal", "1", "1"],
    ["navigate", "m.map", "--start", "0", "0", "--goal", "1", "1"], ["run", "c.toml"], ["figures", "runs/x"],
    ["export", "runs/x"], ["reproduce"], ["tune", "t.toml"], ["study", "s.toml"]])
def test_every_command_takes_no_cache(argv):
    assert build_parser().parse_args([*argv, "--no-cache"]).no_cache is True
    assert build_parser().parse_args(argv).no_cache is False


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def _terminal(monkeypatch) -> _Terminal:
    """stderr a terminal, outside pytest and CI as far as `compile_notice` can tell. Called in the test's body:
    pytest sets its own stderr and variable again when the test's call begins."""
    stream = _Terminal()
    monkeypatch.setattr(sys, "stderr", stream)
    monkeypatch.delenv("PYTEST_CURRENT_TEST", raising=False)
    monkeypatch.delenv("CI", raising=False)
    return stream


def test_notice_prints_one_line_on_a_terminal_only_when_the_block_is_slow(monkeypatch):
    terminal = _terminal(monkeypatch)
    with cc.compile_notice("the IACO walk", 45, after_s=0.05):
        time.sleep(0.5)
    lines = terminal.getvalue().splitlines()
    assert len(lines) == 1 and lines[0].startswith("jaxplan: compiling the IACO walk (first use, ~45 s; cached")
    with cc.compile_notice("the IACO walk", 45, after_s=0.3):
        pass  # a warm start: done before the notice is due
    time.sleep(0.5)
    assert terminal.getvalue().splitlines() == lines


def test_notice_never_prints_off_a_terminal_or_under_ci_or_pytest(monkeypatch):
    pipe = io.StringIO()
    monkeypatch.setattr(sys, "stderr", pipe)
    monkeypatch.delenv("PYTEST_CURRENT_TEST", raising=False)
    with cc.compile_notice("x", 1, after_s=0.01):
        time.sleep(0.2)
    assert pipe.getvalue() == ""
    for name, value in (("CI", "true"), ("PYTEST_CURRENT_TEST", "t.py::test (call)")):
        terminal = _terminal(monkeypatch)
        monkeypatch.setenv(name, value)
        with cc.compile_notice("x", 1, after_s=0.01):
            time.sleep(0.2)
        assert terminal.getvalue() == "", name
