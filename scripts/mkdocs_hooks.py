"""MkDocs hooks of the documentation site (``mkdocs.yml``: ``hooks``): the repository's Markdown as it reads on GitHub.

The docs link to each other and to files outside ``docs/`` with paths relative to the Markdown file, as the
repository host resolves them (``../../figures/x.png``, ``../configs/x.toml``, ``../CHANGELOG.md``). The site holds
``docs/`` only, so these hooks

- add ``README.md`` as the home page (``index.md``) and ``CHANGELOG.md`` as ``changelog.md``;
- copy every other repository file a page links to (figures, configs, sources) into the site under ``repo/``;
- rewrite each relative link to where its target lands in the site, so MkDocs still checks every link
  (``mkdocs build --strict`` fails on one that points nowhere);
- expand a nav entry written as a folder (``- Results: results/``) into that folder's pages, so generated pages
  (``jaxplan reproduce``'s results, the examples) join the navigation without editing ``mkdocs.yml``.
"""

from __future__ import annotations

import posixpath
import re
from pathlib import Path
from typing import Any

from mkdocs.structure.files import File, Files, InclusionLevel

GENERATED = {"index.md": "README.md", "changelog.md": "CHANGELOG.md"}
"""Site page -> the repository file it is made from."""

COPIED = "repo"
"""Site folder that holds the repository files (outside docs/) a page links to."""

_FENCE = re.compile(r"^\s*(`{3,}|~{3,})")
_LINK = re.compile(r"(!?\[(?:[^\]\[]|\[[^\]]*\])*\]\()([^)\s]+)((?:\s+\"[^\"]*\")?\))")
_URL = re.compile(r"^[a-z][a-z0-9+.-]*:", re.I)


def _root(config: Any) -> Path:
    return Path(config["config_file_path"]).resolve().parent


def _docs_prefix(config: Any) -> str:
    return Path(config["docs_dir"]).resolve().relative_to(_root(config)).as_posix() + "/"


def _repo_path(src_uri: str, config: Any) -> str:
    """The repository path (from the root) of the site page ``src_uri``."""
    if src_uri in GENERATED:
        return GENERATED[src_uri]
    if src_uri.startswith(COPIED + "/"):
        return src_uri[len(COPIED) + 1:]
    return _docs_prefix(config) + src_uri


def _site_uri(repo_path: str, config: Any) -> str:
    """Where the repository file ``repo_path`` lands in the site (a ``src_uri``)."""
    for page, source in GENERATED.items():
        if repo_path == source:
            return page
    prefix = _docs_prefix(config)
    return repo_path[len(prefix):] if repo_path.startswith(prefix) else f"{COPIED}/{repo_path}"


def _outside_lines(markdown: str):
    """Yields ``(index, line)`` of the lines outside fenced code blocks."""
    fence = None
    for i, line in enumerate(markdown.split("\n")):
        m = _FENCE.match(line)
        if fence is None and m:
            fence = m.group(1)
        elif fence is not None:
            if line.strip().startswith(fence):
                fence = None
        else:
            yield i, line


def _targets(markdown: str) -> list[str]:
    """Relative link targets (no anchor) outside code: inline code spans are not links."""
    out = []
    for _, line in _outside_lines(markdown):
        for m in _links(line):
            target = m.group(2).split("#", 1)[0]
            if target and not _URL.match(target) and not target.startswith("/"):
                out.append(target)
    return out


def _links(line: str) -> list[re.Match]:
    """The links of one line, found with its inline code spans masked (a code span is no link, but a link's text
    may hold one); the matches' positions are the line's own."""
    masked = re.sub(r"`[^`]*`", lambda m: "`" + "x" * (len(m.group(0)) - 2) + "`", line)
    return list(_LINK.finditer(masked))


def on_config(config: Any) -> Any:
    """Expands nav entries written as a folder into that folder's Markdown pages (index first, then files, then
    one section per sub-folder)."""
    docs = Path(config["docs_dir"])

    def pages(folder: Path) -> list:
        items = sorted(p for p in folder.glob("*.md") if p.is_file())
        items.sort(key=lambda p: p.name != "index.md")
        out: list = [p.relative_to(docs).as_posix() for p in items]
        for sub in sorted(p for p in folder.iterdir() if p.is_dir()):
            if any(sub.rglob("*.md")):
                out.append({sub.name: pages(sub)})
        return out

    def expand(entry: Any) -> Any:
        if isinstance(entry, list):
            return [e for e in (expand(e) for e in entry) if e not in (None, [], {})]
        if isinstance(entry, dict):
            return {k: v for k, v in ((k, expand(v)) for k, v in entry.items()) if v not in (None, [])}
        if isinstance(entry, str) and entry.endswith("/"):
            # a folder that does not exist (yet) or holds no page drops out of the nav
            return pages(docs / entry) if (docs / entry).is_dir() else None
        return entry

    if config.get("nav"):
        config["nav"] = expand(config["nav"])
    return config


def on_files(files: Files, config: Any) -> Files:
    """Adds the README and CHANGELOG pages, and copies each repository file outside ``docs/`` a page links to (a
    Markdown file among them becomes a page outside the nav, whose own links are followed in turn)."""
    root = _root(config)
    for page, source in GENERATED.items():
        if files.get_file_from_path(page) is None:
            files.append(File.generated(config, page, abs_src_path=str(root / source)))
    pages = [f for f in files if f.src_uri.endswith(".md")]
    while pages:
        f = pages.pop()
        text = Path(f.abs_src_path).read_text(encoding="utf-8")
        base = posixpath.dirname(_repo_path(f.src_uri, config))
        for target in _targets(text):
            repo = posixpath.normpath(posixpath.join(base, target))
            uri = _site_uri(repo, config)
            if not uri.startswith(COPIED + "/") or files.get_file_from_path(uri) is not None:
                continue
            if repo.startswith(".."):
                continue  # outside the repository: MkDocs reports the link
            if (root / repo).is_file():
                copy = File.generated(config, uri, abs_src_path=str(root / repo), inclusion=InclusionLevel.NOT_IN_NAV)
                files.append(copy)
                if uri.endswith(".md"):
                    pages.append(copy)
            elif (root / repo).is_dir() and files.get_file_from_path(uri + "/index.md") is None:
                _add_listing(files, config, root, repo)
    return files


def _add_listing(files: Files, config: Any, root: Path, repo: str) -> None:
    """A page listing the files of the repository folder ``repo`` (a link to a folder reads on the repository host
    as its file list), each copied into the site."""
    names = sorted(p.name for p in (root / repo).iterdir() if p.is_file() and not p.name.startswith("."))
    for name in names:
        uri = f"{COPIED}/{repo}/{name}"
        if files.get_file_from_path(uri) is None:
            files.append(File.generated(config, uri, abs_src_path=str(root / repo / name)))
    body = "\n".join(f"- [`{name}`]({name})" for name in names)
    files.append(File.generated(config, f"{COPIED}/{repo}/index.md", content=f"# `{repo}/`\n\n{body}\n",
                                inclusion=InclusionLevel.NOT_IN_NAV))


def on_page_markdown(markdown: str, page: Any, config: Any, files: Files) -> str:
    """Rewrites each relative link from its repository meaning to its place in the site."""
    src = page.file.src_uri
    base = posixpath.dirname(_repo_path(src, config))
    lines = markdown.split("\n")

    root = _root(config)

    def fix(target: str) -> str:
        path, sep, anchor = target.partition("#")
        if not path or _URL.match(path) or path.startswith("/"):
            return target
        repo = posixpath.normpath(posixpath.join(base, path))
        uri = _site_uri(repo, config)
        if uri.startswith(COPIED + "/") and (root / repo).is_dir():
            uri += "/index.md"  # the listing on_files made
        return posixpath.relpath(uri, posixpath.dirname(src) or ".") + sep + anchor

    for i, line in _outside_lines(markdown):
        for m in reversed(_links(line)):  # from the right, so earlier positions stay valid
            target = line[m.start(2):m.end(2)]
            new = fix(target)
            line = line[:m.start(2)] + new + line[m.end(2):]
        lines[i] = line
    return "\n".join(lines)
