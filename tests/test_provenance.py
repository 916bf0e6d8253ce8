"""The one provenance record (`jaxplan.core.provenance`): its keys, and that describing a process imports no
heavy library unless asked for JAX's devices."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

from jaxplan.core.provenance import PACKAGES, git_revision, machine_line, provenance


def test_the_record_names_code_libraries_and_machine():
    rec = provenance(devices=False)
    for key in ("git_revision", "git_dirty", "cpu", "cpu_info", "cpu_line", "cores", "affinity", "ram_gb", "host",
                "python", "platform", "versions", "devices", "xla_flags"):
        assert key in rec, key
    assert set(rec["versions"]) == set(PACKAGES) and rec["versions"]["jaxplan"]
    assert rec["devices"] is None and rec["cores"] >= 1
    assert machine_line(rec["cpu_info"]).startswith(rec["cpu"])
    json.dumps(rec)  # JSON-able, for meta.json and the benchmark results
    rev, dirty = git_revision()
    assert (rev is None and dirty is None) or (len(rev) == 40 and isinstance(dirty, bool))
    assert provenance()["devices"]  # JAX's devices on request


def test_describing_a_process_imports_neither_jax_nor_numba():
    code = textwrap.dedent("""
        import json, sys
        from jaxplan.core.provenance import provenance
        provenance(devices=False)
        print(json.dumps([m for m in ("jax", "numba", "numpy", "scipy") if m in sys.modules]))
        """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120)
    assert json.loads(out.stdout.strip().splitlines()[-1]) == []


def test_outputs_the_commands_write_do_not_make_a_checkout_dirty(tmp_path):
    """`jaxplan reproduce` rewrites docs/results and figures config by config: a page written after the first
    one must still record the clean revision it ran, and a changed source must not."""
    from jaxplan.core.provenance import GENERATED

    def git(*args):
        subprocess.run(["git", "-C", str(tmp_path), *args], check=True, capture_output=True)

    git("init", "-q")
    for rel in ("jaxplan/x.py", *(f"{g}/page.md" for g in GENERATED)):
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text("one\n")
    git("add", ".")
    git("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", "c")
    for g in GENERATED:
        (tmp_path / g / "page.md").write_text("two\n")
    rev, dirty = git_revision(tmp_path)
    assert len(rev) == 40 and dirty is False
    (tmp_path / "jaxplan" / "x.py").write_text("two\n")
    assert git_revision(tmp_path) == (rev, True)
