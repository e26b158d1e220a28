"""Every command of the README works as written, pasted in order into a fresh checkout.

The commands are read from the README's ``sh`` and ``python`` code blocks, so
the README cannot drift from what the commands do.  They run in a copy of the
checkout under ``tmp_path`` (what they write stays there); ``shary`` runs in
this process (:func:`shary.cli.main`: the same parser and code as the
installed script, without paying for an interpreter per command), the Python
block in a fresh interpreter.  ``pip install …`` and ``pytest`` are
what set this environment up and what runs this test, so they are not re-run.
The commands that fetch the external suites (``mkdir``, ``git clone``, ``ln``) need the
network and write beside the checkout, so they are not run either; the commands that
read ``../shared/suites`` are skipped, saying how to get the suites, when it is absent
(:mod:`suites`).
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from collections import Counter
from itertools import pairwise
from pathlib import Path

import pytest
from conftest import REPO
from suites import SUITES, absent

from shary.cli import main

BLOCK = re.compile(r"^```(?P<lang>sh|python)\n(?P<body>.*?)^```", re.M | re.S)
SUITE_SETUP = ("mkdir", "git", "ln")
"""The README's commands that fetch the external suites."""
COPY_IGNORED = shutil.ignore_patterns(".git", ".venv", "build", "dist", "runs", "out",
                                      "__pycache__", "*.egg-info", ".pytest_cache",
                                      ".ruff_cache", ".benchmarks")


def readme_commands(text: str) -> list[tuple[str, list[str] | str]]:
    """(language, argv or source) of every command, in the README's order."""
    commands: list[tuple[str, list[str] | str]] = []
    for block in BLOCK.finditer(text):
        if block["lang"] == "python":
            commands.append(("python", block["body"]))
            continue
        for line in block["body"].splitlines():
            words = shlex.split(line, comments=True)
            while words:
                end = words.index("&&") if "&&" in words else len(words)
                commands.append(("sh", words[:end]))
                words = words[end + 1:]
    return commands


COMMANDS = readme_commands((REPO / "README.md").read_text(encoding="utf-8"))


def _shown(command: tuple[str, list[str] | str]) -> str:
    language, what = command
    return "python block" if language == "python" else " ".join(what)[:60]


@pytest.fixture(scope="module")
def checkout(tmp_path_factory) -> Path:
    """A copy of the checkout, beside a ``shared/suites`` like the one next to the repo."""
    root = tmp_path_factory.mktemp("fresh")
    shutil.copytree(REPO, root / "shary", ignore=COPY_IGNORED)
    if SUITES.is_dir():
        (root / "shared").mkdir()
        (root / "shared" / "suites").symlink_to(SUITES)
    return root / "shary"


def test_the_readme_shows_commands_of_every_kind():
    words = [what[0] for language, what in COMMANDS if language == "sh"]
    assert words.count("pip") == 2 and "pytest" in words
    assert sum(word == "shary" for word in words) >= 15


def test_the_readme_says_where_to_get_the_suites_its_commands_read():
    """A clone has no ``../shared/suites``: the README fetches each suite a command reads
    to the path the command reads it from (the tests' default, :data:`suites.SUITES`)."""
    fetched = {what[-1] for language, what in COMMANDS if language == "sh" and what[0] == "git"}
    linked = {what[-1] for language, what in COMMANDS if language == "sh" and what[0] == "ln"}
    read = {word.split("/")[3] for language, what in COMMANDS if language == "sh"
            and what[0] == "shary" for word in what if word.startswith("../shared/suites/")}
    assert read and read <= {path.split("/")[3] for path in fetched | linked}
    assert "https://github.com/jbeard4/scxml-test-framework" in " ".join(
        " ".join(what) for language, what in COMMANDS if language == "sh")


RUN_FILES = ("log.sqlite", "tree.svg", "timeline.svg", "summary.json")
"""What ``shary run --out DIR`` writes in DIR."""


def _written(argv: list[str]) -> list[str]:
    """The files a shary command of the README writes where its command line says."""
    files = []
    for flag, value in pairwise(argv):
        if flag in ("-o", "--output", "--mcap"):
            files.append(os.path.normpath(value))
        elif flag == "--out" and argv[1] == "run":
            files += [os.path.normpath(os.path.join(value, name)) for name in RUN_FILES]
    return files


def test_no_two_readme_commands_write_the_same_file():
    """Each command's file is still there to look at after the whole block has run."""
    written = Counter(file for language, what in COMMANDS if language == "sh"
                      and what[0] == "shary" for file in _written(what))
    assert written and not [file for file, times in written.items() if times > 1]


@pytest.mark.parametrize("command", COMMANDS, ids=[_shown(c) for c in COMMANDS])
def test_readme_command_works_as_written(checkout, command, monkeypatch, capsys):
    language, what = command
    if language == "python":
        done = subprocess.run([sys.executable, "-c", what], cwd=checkout, capture_output=True,
                              text=True, timeout=300)
        assert done.returncode == 0, done.stderr
        return
    if what[0] in ("pip", "pytest"):
        pytest.skip("set-up of this environment; it is what runs this test")
    if what[0] in SUITE_SETUP:
        assert any(word.startswith("../shared/suites") for word in what), what
        pytest.skip("fetches the external suites (the network); tests/suites.py reads them")
    assert what[0] == "shary", f"the README shows a command that is not shary's: {what}"
    for name in ("scion", "ipc2020"):
        if any(f"../shared/suites/{name}" in word for word in what) and not (
                SUITES / name).is_dir():
            pytest.skip(absent(name))
    monkeypatch.chdir(checkout)
    try:
        status = main(what[1:])
    except SystemExit as exit_:  # --version and --help exit from argparse
        status = exit_.code
    captured = capsys.readouterr()
    assert status == 0, f"{_shown(command)}\n{captured.out}\n{captured.err}"
    if what[1:] == ["run", "give-bottle"]:
        # what the set-up paragraph promises
        for name in ("log.sqlite", "tree.svg", "timeline.svg"):
            assert (checkout / "runs" / "give-bottle" / name).is_file()
