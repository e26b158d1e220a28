"""The hostile corpora of the reader formats: each file says what its refusal must say.

A corpus file's first line is ``# expect: REGEX``; the test asserts the rule of
:mod:`tests.hostile` and that some problem matches REGEX.  Files in a ``deps/``
sub-folder are dependencies of the others (a broken recipe file a scenario
names), not cases of their own.
"""

from __future__ import annotations

import re
from pathlib import Path

from hostile import HOSTILE

_EXPECT = re.compile(r"^# expect: (?P<regex>.+)$")


def corpus(fmt: str) -> list[Path]:
    """The cases of one format, sorted by name."""
    return sorted((HOSTILE / fmt).glob("*.yaml"))


def expected(path: Path) -> str:
    """The regular expression the refusal of ``path`` must match."""
    match = _EXPECT.match(path.read_text("utf-8").split("\n", 1)[0])
    assert match, f"{path} does not start with '# expect: REGEX'"
    return match["regex"]


def blamable(path: Path) -> list[Path]:
    """The files a refusal of ``path`` may name: itself and its corpus's dependencies."""
    return [path, *sorted((path.parent / "deps").glob("*.yaml"))]
