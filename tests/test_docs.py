"""The README, the changelog and docs/ stay true: every relative link resolves, every Python snippet runs.

Links: every ``[text](target)`` outside code blocks whose target is not a URL must name an existing
file or folder, relative to the Markdown file; a ``#anchor`` must match a heading of the target (or
of the same file), slugged as the repository host does (lower case, punctuation dropped, spaces to
hyphens, ``-1``, ``-2`` for repeats).

Snippets: the ```python blocks of one file run in order in one namespace, with the repository root as
the working directory, as a reader would paste them. A block preceded by ``<!-- not run: reason -->``
on the line right before its fence is skipped. A file whose snippets read ``../shared/benchmarks``
is skipped with a message when that folder is absent. Blocks of other languages (toml, yaml) are not run;
the shell blocks' commands run in tests/test_shell_examples.py.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from conftest import ROOT

DOCS = sorted(p for p in [ROOT / "README.md", ROOT / "CHANGELOG.md", *(ROOT / "docs").rglob("*.md")] if p.is_file())
DATA = ROOT.parent / "shared" / "benchmarks"

FENCE = re.compile(r"^(\s*)(`{3,}|~{3,})(.*)$")
LINK = re.compile(r"(?<!!)\[(?:[^\]\[]|\[[^\]]*\])*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
IMAGE = re.compile(r"!\[[^\]]*\]\(([^)\s]+)\)")
NOT_RUN = re.compile(r"^\s*<!--\s*not run:\s*(.+?)\s*-->\s*$")


def _rel(path: Path) -> str:
    return str(path.relative_to(ROOT))


def blocks(text: str) -> list[tuple[str, str, str | None, int]]:
    """``(language, code, not-run reason or None, line)`` of every fenced block, in order."""
    out, lines, i = [], text.splitlines(), 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        fence, lang, start = m.group(2), m.group(3).strip().split(" ")[0].lower(), i
        body = []
        i += 1
        while i < len(lines) and not lines[i].strip().startswith(fence):
            body.append(lines[i])
            i += 1
        prev = lines[start - 1] if start > 0 else ""
        reason = NOT_RUN.match(prev)
        out.append((lang, "\n".join(body) + "\n", reason.group(1) if reason else None, start + 1))
        i += 1
    return out


def prose(text: str, keep_code: bool = False) -> str:
    """``text`` with fenced blocks blanked out, and inline code too unless ``keep_code`` (links inside code are
    not links; a heading's code is part of its anchor)."""
    kept, fence = [], None
    for line in text.splitlines():
        m = FENCE.match(line)
        if fence is None and m:
            fence = m.group(2)
            kept.append("")
            continue
        if fence is not None:
            if line.strip().startswith(fence):
                fence = None
            kept.append("")
            continue
        kept.append(line if keep_code else re.sub(r"`[^`]*`", "``", line))
    return "\n".join(kept)


def slug(heading: str) -> str:
    """The anchor the repository host gives a heading (before de-duplication)."""
    h = re.sub(r"<[^>]+>", "", heading.strip().lower())
    h = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", h)  # links keep their text
    h = h.replace("`", "")
    h = re.sub(r"[^\w\- ]", "", h)
    return h.replace(" ", "-")


def anchors(path: Path) -> set[str]:
    seen: dict[str, int] = {}
    out = set()
    for line in prose(path.read_text(), keep_code=True).splitlines():
        m = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
        if not m:
            continue
        s = slug(m.group(1))
        n = seen.get(s, 0)
        seen[s] = n + 1
        out.add(s if n == 0 else f"{s}-{n}")
    return out


def test_docs_exist():
    names = {_rel(p) for p in DOCS}
    for need in ("README.md", "CHANGELOG.md", "docs/papers.md", "docs/decisions.md", "docs/benchmarks.md"):
        assert need in names, f"{need} is missing"
    assert len((ROOT / "README.md").read_text().splitlines()) <= 200, "README.md is over 200 lines"


@pytest.mark.parametrize("doc", DOCS, ids=_rel)
def test_relative_links_resolve(doc: Path):
    text = prose(doc.read_text())
    bad = []
    for target in LINK.findall(text) + IMAGE.findall(text):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target, re.I):  # http:, https:, mailto:
            continue
        file_part, _, anchor = target.partition("#")
        dest = (doc.parent / file_part).resolve() if file_part else doc
        if not dest.exists():
            bad.append(f"{target}: no such file {dest}")
            continue
        if anchor and dest.suffix == ".md" and anchor not in anchors(dest):
            bad.append(f"{target}: no heading #{anchor} in {dest.name}")
    assert not bad, f"{_rel(doc)}: broken links:\n" + "\n".join(bad)


def _snippet_docs() -> list[Path]:
    return [d for d in DOCS if any(lang == "python" for lang, *_ in blocks(d.read_text()))]


@pytest.mark.parametrize("doc", _snippet_docs(), ids=_rel)
def test_python_snippets_run(doc: Path, monkeypatch):
    runs = [(code, line) for lang, code, reason, line in blocks(doc.read_text()) if lang == "python" and reason is None]
    if not runs:
        pytest.skip(f"{_rel(doc)}: every Python block is marked not run")
    if any("shared/benchmarks" in code for code, _ in runs) and not DATA.is_dir():
        pytest.skip(f"{_rel(doc)}: its snippets read {DATA}, which is absent")
    monkeypatch.chdir(ROOT)
    namespace: dict = {"__name__": "__docs__"}
    for code, line in runs:
        try:
            exec(compile(code, f"{_rel(doc)}:{line}", "exec"), namespace)
        except Exception as e:  # pragma: no cover - the failure message is the point
            raise AssertionError(f"{_rel(doc)}, the python block at line {line} failed: {e!r}\n{code}") from e



CODE_POINTER = re.compile(r"docs/([\w/.-]+\.md)(?:#([\w-]+))?")


def test_code_pointers_into_docs_resolve():
    """Docstrings and comments that send the reader to ``docs/X.md`` (or ``docs/X.md#heading``) name a page, and
    a heading, that exist: measurements moved out of the code must stay findable."""
    bad = []
    for src in sorted([*(ROOT / "jaxplan").rglob("*.py"), *(ROOT / "benchmarks").glob("*.py")]):
        for page, anchor in CODE_POINTER.findall(src.read_text()):
            dest = ROOT / "docs" / page
            if not dest.is_file():
                bad.append(f"{_rel(src)}: docs/{page} does not exist")
            elif anchor and anchor not in anchors(dest):
                bad.append(f"{_rel(src)}: no heading #{anchor} in docs/{page}")
    assert not bad, "\n".join(bad)
