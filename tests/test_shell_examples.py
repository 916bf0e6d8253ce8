"""Every shell command of the README and docs/ runs from a fresh clone, and a clone stays clean (issue 43).

Which commands. Every line of a ```bash, ```sh, ```shell or ```console fence (console: the ``$ `` lines) in
README.md and docs/**/*.md, with ``\\`` continuations joined and ``#`` comments dropped, split at ``&&``, ``||``,
``;`` and ``|`` into commands; leading ``NAME=value`` words are the command's environment. So the ``jaxplan demo``
at the end of the README's quickstart chain counts as well as a line of its own.

What happens to each. A ``jaxplan`` command runs, as documented, unless a table below says otherwise:

- `RUN_AS` maps a long documented command to the command the test runs instead, with the reason: its
  ``--quick`` form (a smoke run of the same config through the same code), or a run folder's ``-quick`` name
  for a command that reads what an earlier, now quick, command wrote. A ``run``, ``reproduce``, ``tune``,
  ``study``, ``demo`` or ``bench`` command without ``--quick`` that is in no table fails the fast test, so the
  run stays bounded.
- `OPTIONAL` names the commands that need an optional extra: with the extra installed the command must succeed;
  without it, it must fail and say what to install.
- `NOT_RUN` lists the commands that cannot run here, with the reason (an allow-list, not a silent skip); any
  command of another program must match a prefix in `OTHER_PROGRAMS`, again with the reason.

Fresh-clone layout. Each document's commands run in order (a guide's ``figures`` reads its own ``run``) in a
temporary copy of the repository's tracked files (``git ls-files``), with ``shared/benchmarks`` beside the
copy as a symlink to the benchmark folder, so ``../shared/benchmarks/...`` in a command resolves as in a clone
beside ``shared/``, and ``$JAXPLAN_DATA`` points at that symlink for the configs' map paths. Every output
(``runs/``, ``--out`` files, the figures of ``reproduce``) lands inside the copy, never in the checkout. The
package under test is the checkout's (``python -P -m jaxplan.cli`` with the checkout first on ``PYTHONPATH``, as
an installed ``jaxplan`` would import it; its numba cache and the user's JAX cache are reused). A command that
exits non-zero fails the test, naming the file and line.

Time. Running them takes minutes, so those tests are ``slow`` (``pytest -m slow tests/test_shell_examples.py``).
2026-12-06, 2 cores shared with another full-load job, at nice 19, the 24 commands run of README.md, experiments.md,
ros-maps.md and tuning.md: 313 s with warm compilation caches (141 + 75 + 23 + 74 s), 630 s cold; the clean-clone
test 41 s warm, 94 s cold. What stays fast and runs in every ``pytest`` (about 6 s): every documented command is
classified (run, run as, or listed with a reason), parses with the command line's own parser (its stand-in too),
and names a map that exists from the repository root with start and goal cells inside it and free.

Clean clone. `test_a_clone_stays_clean_after_demo_run_and_figures`: in a copy of the tracked files made a git
repository with one commit, ``jaxplan demo --quick``, ``jaxplan run configs/example_plan.toml --quick`` and
``jaxplan figures runs/example_plan-quick`` leave ``git status --porcelain`` empty (their outputs go under the
ignored ``runs/``), and the files they announce exist there.
"""

from __future__ import annotations

import importlib.util
import os
import re
import shlex
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT, data_dir
from test_docs import blocks

SHELL = {"bash", "sh", "shell", "console"}
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
OPERATORS = {"&&", "||", ";", "|", "&"}
ENV_WORD = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*=")
LONG = {"run", "reproduce", "tune", "study", "demo", "bench"}  # commands that must run in a quick form
TIMEOUT_S = 1800  # one command; a hang fails instead of stalling CI

RUN_AS: dict[str, tuple[str, str]] = {
    "jaxplan demo": ("jaxplan demo --quick",
                     "the full demo compiles two pipelines on the 48x32 warehouse (~1 min); --quick drives the same "
                     "pipelines through the same code on a 14x10 one"),
    "jaxplan reproduce --quick": (
        "jaxplan reproduce --quick --pattern cui2025_table2.toml",
        "every config's quick run is tests/test_experiments_reproduce.py's job; one config checks the command "
        "from a fresh clone"),
    "jaxplan reproduce": ("jaxplan reproduce --quick --pattern cui2025_table2.toml",
                          "the full reproduction takes about half an hour; its quick form, one config"),
    "jaxplan reproduce --pattern 'yu2020_*.toml'": ("jaxplan reproduce --quick --pattern yu2020_tsp.toml",
                                                    "full runs take minutes; the quick form of one matching config"),
    "jaxplan run configs/cui2025_table2.toml": ("jaxplan run configs/cui2025_table2.toml --quick",
                                                "the full run takes minutes; its smoke run"),
    "jaxplan figures runs/cui2025_table2": ("jaxplan figures runs/cui2025_table2-quick",
                                            "the run above ran quick, into runs/cui2025_table2-quick"),
    "jaxplan export runs/cui2025_table2 --format parquet": (
        "jaxplan export runs/cui2025_table2-quick --format parquet",
        "the run above ran quick, into runs/cui2025_table2-quick"),
    "jaxplan run configs/example_plan.toml": ("jaxplan run configs/example_plan.toml --quick",
                                              "the full run takes minutes; its smoke run (which resumes here)"),
    "jaxplan figures runs/example_plan": ("jaxplan figures runs/example_plan-quick",
                                          "the runs above ran quick, into runs/example_plan-quick"),
    "jaxplan tune configs/tune_iaco.toml": ("jaxplan tune configs/tune_iaco.toml --quick",
                                            "16 weight vectors x 10 generations take minutes; the smoke run"),
    "jaxplan study configs/study_iaco.toml --results docs/results/tuning --confirm": (
        "jaxplan study configs/study_iaco.toml --quick --results docs/results/tuning --confirm",
        "the full study takes hours; its quick form writes the same page and runs the confirmation (inside the "
        "temporary copy)"),
}

OPTIONAL: dict[str, tuple[str, str]] = {
    "jaxplan export runs/cui2025_table2 --format parquet": ("pyarrow", "jaxplan[export]"),
}

NOT_RUN: dict[str, str] = {
    "jaxplan bench -- --quick": "the benchmarks time the machine for about 3 minutes on 2 cores; they run on "
                                "purpose (docs/benchmarks.md), and tests/test_cli.py checks that the command exists",
}

OTHER_PROGRAMS: dict[tuple[str, ...], str] = {
    ("python3", "-m", "venv"): "creates the environment the tests already run in",
    (".", ".venv/bin/activate"): "activates that environment",
    ("pip", "install"): "installs packages: CI installs them once, before the tests",
    ("pytest",): "the test suite itself",
    ("python", "scripts/sweep_hosts.py"): "multi-host: needs n hosts and a coordinator (MAP and SCEN are "
                                          "placeholders); tests/test_scale.py runs the script as two local processes",
    ("python", "benchmarks/run_all.py"): "the benchmarks: minutes of timing runs, run on purpose "
                                         "(docs/benchmarks.md)",
}


@dataclass(frozen=True)
class Command:
    """One documented command: where it is, its environment words and its words."""

    doc: str
    line: int
    env: tuple[str, ...]
    argv: tuple[str, ...]

    @property
    def text(self) -> str:
        return shlex.join(self.argv)

    @property
    def where(self) -> str:
        return f"{self.doc}:{self.line}"


def _rel(path: Path) -> str:
    return str(path.relative_to(ROOT))


def logical_lines(code: str, first: int, console: bool) -> list[tuple[int, str]]:
    """``(line number, text)`` of each command line of a block whose first line is ``first``: ``\\``
    continuations joined; in a console block only the ``$ `` lines (and their continuations) are commands."""
    out: list[tuple[int, str]] = []
    pending: tuple[int, str] | None = None
    for k, raw in enumerate(code.splitlines()):
        line = raw.rstrip()
        if pending is None:
            if console:
                if not line.lstrip().startswith("$ "):
                    continue
                line = line.lstrip()[2:]
            pending = (first + k, "")
        body = line[:-1] if line.endswith("\\") else line
        pending = (pending[0], f"{pending[1]} {body}".strip())
        if not line.endswith("\\"):
            out.append(pending)
            pending = None
    if pending is not None:
        out.append(pending)
    return out


def strip_comment(text: str) -> str:
    """``text`` without its comment: from an unquoted ``#`` that starts a word, as bash reads it (``a#b`` is one
    word; an apostrophe in the comment is no quote)."""
    quote = None
    for k, ch in enumerate(text):
        if quote:
            quote = None if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch == "#" and (k == 0 or text[k - 1].isspace()):
            return text[:k].rstrip()
    return text


def split_commands(text: str) -> list[list[str]]:
    """The words of each command of one shell line: comment dropped (`strip_comment`), quotes removed, split at
    ``&&``, ``||``, ``;``, ``|`` and ``&``."""
    lex = shlex.shlex(strip_comment(text), posix=True, punctuation_chars=True)
    lex.whitespace_split, lex.commenters = True, ""
    words = list(lex)
    out, cur = [], []
    for w in words:
        if w in OPERATORS:
            out.append(cur)
            cur = []
        else:
            cur.append(w)
    return [c for c in [*out, cur] if c]


def documented_commands(docs: list[Path] = DOCS) -> list[Command]:
    """Every command of the shell blocks of ``docs``, in document order."""
    out = []
    for doc in docs:
        for lang, code, _reason, line in blocks(doc.read_text()):
            if lang not in SHELL:
                continue
            for n, text in logical_lines(code, line + 1, lang == "console"):
                for words in split_commands(text):
                    k = next((i for i, w in enumerate(words) if not ENV_WORD.match(w)), len(words))
                    out.append(Command(_rel(doc), n, tuple(words[:k]), tuple(words[k:])))
    return out


def _other_reason(cmd: Command) -> str | None:
    return next((r for prefix, r in OTHER_PROGRAMS.items() if cmd.argv[:len(prefix)] == prefix), None)


def plan_of(cmd: Command) -> tuple[str, str] | None:
    """``(command line the test runs, why it differs)`` for a ``jaxplan`` command, or None when it is not run."""
    if cmd.text in NOT_RUN:
        return None
    if cmd.text in RUN_AS:
        return RUN_AS[cmd.text]
    return cmd.text, ""


def _problems() -> list[str]:
    """Every documented command that is not classified, or whose run would be unbounded; stale table entries."""
    bad, seen = [], set()
    for cmd in documented_commands():
        seen.add(cmd.text)
        if not cmd.argv:
            continue
        if cmd.argv[0] != "jaxplan":
            if _other_reason(cmd) is None:
                bad.append(f"{cmd.where}: {cmd.text!r} is not a jaxplan command: list it in OTHER_PROGRAMS with the "
                           "reason it cannot run here")
            continue
        plan = plan_of(cmd)
        if plan is None:
            continue
        words = shlex.split(plan[0])
        if len(words) > 1 and words[1] in LONG and "--quick" not in words:
            bad.append(f"{cmd.where}: {cmd.text!r} would run in full: map it to its --quick form in RUN_AS")
    for name, table in (("RUN_AS", RUN_AS), ("OPTIONAL", OPTIONAL), ("NOT_RUN", NOT_RUN)):
        bad += [f"{name}[{k!r}] is documented nowhere (stale entry)" for k in table if k not in seen]
    return bad


def test_commands_are_found_in_every_shell_block_form():
    code = ("$ jaxplan plan a.map --start 1 2 \\\n    --goal 3 4   # a comment\nsome output\n"
            "$ python3 -m venv .venv && jaxplan demo\n")
    found = [(n, words) for n, text in logical_lines(code, 10, console=True) for words in split_commands(text)]
    assert found == [(10, ["jaxplan", "plan", "a.map", "--start", "1", "2", "--goal", "3", "4"]),
                     (13, ["python3", "-m", "venv", ".venv"]), (13, ["jaxplan", "demo"])]
    assert split_commands("A=1 jaxplan reproduce --pattern 'yu2020_*.toml'; pytest | tee x#y  # it's") == [
        ["A=1", "jaxplan", "reproduce", "--pattern", "yu2020_*.toml"], ["pytest"], ["tee", "x#y"]]


def test_every_documented_command_is_run_or_listed_with_a_reason():
    cmds = documented_commands()
    assert sum(c.argv[:1] == ("jaxplan",) for c in cmds) >= 20, "the shell blocks were not found"
    assert any(c.doc == "README.md" and c.text == "jaxplan demo" for c in cmds), "the quickstart's && chain"
    bad = _problems()
    assert not bad, "\n".join(bad)


def _parse(words: list[str]):
    """The parsed arguments of ``jaxplan WORDS[1:]``, or an AssertionError with argparse's message."""
    import contextlib
    import io

    from jaxplan.cli import build_parser

    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err):
            return build_parser().parse_args(words[1:])
    except SystemExit as e:
        raise AssertionError(err.getvalue().strip().splitlines()[-1] if err.getvalue() else str(e)) from None


def test_every_jaxplan_command_parses():
    """Fast: every documented command, and the command run in its place, takes only options that exist."""
    bad = []
    for cmd in documented_commands():
        if cmd.argv[:1] != ("jaxplan",):
            continue
        for line in {cmd.text, *(p[0] for p in [plan_of(cmd)] if p)}:
            try:
                _parse(shlex.split(line))
            except AssertionError as e:
                bad.append(f"{cmd.where}: {line!r}: {e}")
    assert not bad, "\n".join(bad)


def _map_path(path: str) -> Path:
    """A command's map path as seen from the repository root (``../shared/benchmarks`` = the data folder)."""
    prefix = "../shared/benchmarks/"
    return data_dir() / path[len(prefix):] if path.startswith(prefix) else ROOT / path


def test_start_and_goal_are_free_cells_of_their_map():
    """Fast: a documented ``plan``/``navigate`` names a map that exists from the repository root and start and goal
    cells inside it and free (the README once took a .scen row's width and height columns for a start)."""
    from jaxplan.cli.args import load_map_args

    cmds = [c for c in documented_commands() if c.argv[:2] in (("jaxplan", "plan"), ("jaxplan", "navigate"))]
    assert cmds
    if not data_dir().is_dir():
        pytest.skip(f"the benchmark data is not at {data_dir()} (set JAXPLAN_DATA)")
    bad = []
    for cmd in cmds:
        try:
            args = _parse(list(cmd.argv))
        except AssertionError:
            continue  # test_every_jaxplan_command_parses names it
        shown = args.map
        for key in ("map", "keepout", "speed_mask"):
            if getattr(args, key) is not None:
                setattr(args, key, str(_map_path(getattr(args, key))))
        if not Path(args.map).is_file():
            bad.append(f"{cmd.where}: map {shown!r} does not exist from the repository root")
            continue
        grid, _ = load_map_args(args)
        H, W = grid.free.shape
        for name in ("start", "goal"):
            cell, metres = getattr(args, name), getattr(args, f"{name}_m", None)
            if cell is None and metres is None:
                bad.append(f"{cmd.where}: no {name}")
                continue
            # --start-m X Y: metres in the map's world frame, the cell they fall in
            x, y = (int(v) for v in (cell if cell is not None else grid.cell_at(np.array(metres, np.float64))))
            if not (0 <= x < W and 0 <= y < H):
                bad.append(f"{cmd.where}: {name} ({x}, {y}) is outside the {W}x{H} map")
            elif not bool(grid.free[y, x]):
                bad.append(f"{cmd.where}: {name} ({x}, {y}) is a blocked cell")
    assert not bad, "\n".join(bad)


def test_a_map_path_written_as_in_a_config_fails_saying_where_the_file_is(capsys, monkeypatch):
    """``jaxplan plan ros/warehouse.yaml`` (a path relative to the data folder, as configs write it) is relative to
    the working folder on the command line; the error names the file it probably meant."""
    from jaxplan.cli import main

    if not (data_dir() / "ros" / "warehouse.yaml").is_file():
        pytest.skip(f"the ROS maps are not in {data_dir()}")
    monkeypatch.setenv("JAXPLAN_DATA", str(data_dir()))
    monkeypatch.chdir(ROOT)
    assert main(["plan", "ros/warehouse.yaml", "--start", "5", "20", "--goal", "90", "140"]) == 2
    err = capsys.readouterr().err
    assert "relative to the working folder" in err and str(data_dir() / "ros" / "warehouse.yaml") in err


# ---------------------------------------------------------------------------------------------
# Running them


def fresh_clone(parent: Path) -> Path:
    """A copy of the checkout's tracked files in ``parent/jaxplan`` with ``parent/shared/benchmarks`` linked to the
    benchmark folder (skips without git, a git checkout or the data)."""
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("needs git and a git checkout (the copy is of `git ls-files`)")
    if not data_dir().is_dir():
        pytest.skip(f"the documented commands read the benchmark data, which is not at {data_dir()}")
    files = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True).stdout
    clone = parent / "jaxplan"
    for name in filter(None, files.decode().split("\0")):
        src = ROOT / name
        if src.is_file():  # a tracked file deleted in the work tree is not part of the clone
            (clone / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, clone / name, follow_symlinks=False)
    (parent / "shared").mkdir()
    (parent / "shared" / "benchmarks").symlink_to(data_dir().resolve(), target_is_directory=True)
    return clone


def _env(clone: Path) -> dict[str, str]:
    env = dict(os.environ, MPLBACKEND="Agg", JAXPLAN_DATA=str(clone.parent / "shared" / "benchmarks"))
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH")) if p)
    return env


def jaxplan(line: str, clone: Path, extra_env: tuple[str, ...] = ()) -> tuple[subprocess.CompletedProcess, float]:
    """Runs the command line ``line`` (``jaxplan ...``) in ``clone`` as its own process; (result, seconds)."""
    words = shlex.split(line)
    assert words[0] == "jaxplan", line
    env = _env(clone) | dict(w.split("=", 1) for w in extra_env)
    t0 = time.perf_counter()
    # -P: the clone's own jaxplan/ folder is not put first on sys.path; the checkout's package is the one tested.
    res = subprocess.run([sys.executable, "-P", "-m", "jaxplan.cli", *words[1:]], cwd=clone, env=env,
                         capture_output=True, text=True, timeout=TIMEOUT_S)
    return res, time.perf_counter() - t0


def _tail(text: str, n: int = 8) -> str:
    return "\n".join("    " + s for s in text.strip().splitlines()[-n:])


def _shell_docs() -> list[Path]:
    """The documents with a command to run (a document whose commands are all in `NOT_RUN` has none)."""
    return [d for d in DOCS if any(c.argv[:1] == ("jaxplan",) and plan_of(c) for c in documented_commands([d]))]


@pytest.mark.slow  # minutes on 2 cores (module docstring); the fast tests above keep every command honest meanwhile
@pytest.mark.parametrize("doc", _shell_docs(), ids=_rel)
def test_documented_commands_run_from_a_fresh_clone(doc: Path, tmp_path):
    clone = fresh_clone(tmp_path)
    failures, timings = [], []
    for cmd in documented_commands([doc]):
        if cmd.argv[:1] != ("jaxplan",) or (plan := plan_of(cmd)) is None:
            continue
        line = plan[0]
        res, seconds = jaxplan(line, clone, cmd.env)
        timings.append(f"{seconds:7.1f} s  {cmd.where}  {line}")
        optional = OPTIONAL.get(cmd.text)
        if optional and importlib.util.find_spec(optional[0]) is None:
            if res.returncode == 0 or optional[1] not in res.stderr:
                failures.append(f"{cmd.where}: without {optional[0]}, {line!r} should fail naming "
                                f"{optional[1]!r}; exit {res.returncode}:\n{_tail(res.stderr)}")
            continue
        if res.returncode != 0:
            failures.append(f"{cmd.where}: {line!r} exited {res.returncode}:\n{_tail(res.stderr or res.stdout)}")
    print(f"\n{_rel(doc)}: {len(timings)} commands\n" + "\n".join(timings))
    assert not failures, f"{_rel(doc)}: documented commands failed:\n" + "\n".join(failures)


@pytest.mark.slow  # three jaxplan processes: about a minute on 2 cores
def test_a_clone_stays_clean_after_demo_run_and_figures(tmp_path):
    clone = fresh_clone(tmp_path)
    git = ["git", "-c", "user.name=test", "-c", "user.email=test@example.com", "-c", "commit.gpgsign=false"]
    for step in (["init", "-q"], ["add", "-A"], ["commit", "-q", "-m", "clone"]):
        subprocess.run([*git, *step], cwd=clone, check=True, capture_output=True)
    assert subprocess.run(["git", "status", "--porcelain"], cwd=clone, capture_output=True, text=True,
                          check=True).stdout == ""
    for line in ("jaxplan demo --quick", "jaxplan run configs/example_plan.toml --quick",
                 "jaxplan figures runs/example_plan-quick"):
        res, _ = jaxplan(line, clone)
        assert res.returncode == 0, f"{line}: exit {res.returncode}\n{_tail(res.stderr)}"
    status = subprocess.run(["git", "status", "--porcelain", "--untracked-files=all"], cwd=clone,
                            capture_output=True, text=True, check=True).stdout
    assert status == "", f"the commands wrote into tracked or unignored places:\n{status}"
    for made in ("runs/demo/demo.png", "runs/demo/demo.gif", "runs/example_plan-quick/trials.csv",
                 "runs/figures/example_plan-quick/index.md", "runs/figures/index.md"):
        assert (clone / made).is_file(), f"{made} was not written"
