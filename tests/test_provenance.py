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
