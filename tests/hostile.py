"""One rule for hostile input, measured: the harness every hostile corpus uses.

The rule (docs/architecture.md, "User files"): a refused file gives
``FILE:LINE:COL: error: …`` at a line the file has, exit status 2, no Python
traceback, in under :data:`MAX_SECONDS` and :data:`MAX_MB`.  The corpora live in
``tests/hostile/<format>/``; each ``tests/test_hostile_<format>.py`` feeds them
to the command a user would run and asserts the rule with :func:`assert_refused`.

Two ways to run a command, both measured:

* :func:`run_inprocess` calls :func:`shary.cli.main` in this process and traces
  Python allocations with :mod:`tracemalloc` (fast: for the many small files);
* :func:`run_subprocess` runs ``python -m shary`` in a child and reads its peak
  resident memory from the child's own ``VmHWM`` (exact: for the few large or deep inputs, and
  for anything that could hurt the test process itself).
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
import tracemalloc
from dataclasses import dataclass
from pathlib import Path

MAX_SECONDS = 10.0
"""A refusal takes less than this many CPU seconds, whatever the input.

CPU time, not wall time: these machines are shared, and at a load of 8 on two
cores the same refusal takes three to four times longer on the wall clock
while costing the same.  The wall clock is still bounded: a child is killed at
three times this limit (:func:`run_subprocess`)."""
MAX_MB = 500.0
"""A refusal needs less memory than this, whatever the input."""

HOSTILE = Path(__file__).resolve().parent / "hostile"
PROBLEM = re.compile(r"^(?P<file>.+?):(?P<line>\d+):(?P<col>\d+): error: (?P<message>.+)$")


@dataclass
class Outcome:
    """What one run of the command did, and what it cost."""

    status: int
    out: str
    err: str
    seconds: float
    """CPU seconds the command used (user + system), see :data:`MAX_SECONDS`."""
    peak_mb: float

    def problems(self) -> list[re.Match]:
        """The ``FILE:LINE:COL: error:`` lines of standard error."""
        found = (PROBLEM.match(line) for line in self.err.splitlines())
        return [m for m in found if m]


def run_inprocess(*argv: object) -> Outcome:
    """Run ``shary ARGV`` here; memory is the peak of Python allocations."""
    from shary.cli import main

    out, err = io.StringIO(), io.StringIO()
    tracemalloc.start()
    start = time.thread_time()
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            status = main([str(a) for a in argv])
    finally:
        seconds = time.thread_time() - start
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
    return _noted(Outcome(int(status), out.getvalue(), err.getvalue(), seconds,
                          peak / 2**20), "in-process", argv)


_CHILD = """\
import os, runpy, sys
sys.argv[0] = "shary"
try:
    runpy.run_module("shary", run_name="__main__", alter_sys=True)
finally:
    with open(os.environ["SHARY_TEST_HWM"], "w") as out:
        out.write(open("/proc/self/status").read())
"""
"""The child's body: ``python -m shary`` that writes its own status on the way out.

Its peak resident size is read from ``VmHWM`` in ``/proc/self/status``, which
belongs to the child's own address space.  ``wait4``'s ``ru_maxrss`` would not
do: Linux carries the parent's high-water mark across fork and exec, so a test
process that had grown made a 46 MB child look like 475 MB.
"""


def run_subprocess(*argv: object, cwd: Path | None = None,
                   timeout: float = 3 * MAX_SECONDS) -> Outcome:
    """Run ``python -m shary ARGV`` in a child; memory is its own peak resident size."""
    with tempfile.TemporaryDirectory() as scratch:
        status_file = Path(scratch) / "status"
        env = dict(os.environ, COLUMNS="200", SHARY_TEST_HWM=str(status_file))
        start = _children_cpu()
        try:
            done = subprocess.run([sys.executable, "-c", _CHILD, *map(str, argv)], cwd=cwd,
                                  env=env, capture_output=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            raise AssertionError(f"shary {' '.join(map(str, argv))} killed after "
                                 f"{timeout:.0f} s") from None
        seconds = _children_cpu() - start
        status = status_file.read_text() if status_file.exists() else ""
    peak = re.search(r"^VmHWM:\s+(\d+) kB", status, re.MULTILINE)
    assert peak, f"the child left no status (exit {done.returncode}):\n{done.stderr[-2000:]!r}"
    decode = lambda b: b.decode("utf-8", "replace")  # noqa: E731
    return _noted(Outcome(done.returncode, decode(done.stdout), decode(done.stderr), seconds,
                          int(peak[1]) / 1024), "child", argv)


def _children_cpu() -> float:
    """CPU seconds used so far by this process's finished children (user + system)."""
    used = resource.getrusage(resource.RUSAGE_CHILDREN)
    return used.ru_utime + used.ru_stime


def _noted(outcome: Outcome, mode: str, argv: tuple) -> Outcome:
    """Append what a run cost to the file named by ``SHARY_HOSTILE_REPORT``, if set.

    ``python tests/hostile_report.py`` runs the corpora that way and prints, per
    format, the slowest and the largest run: the figures the rule is judged by.
    """
    report = os.environ.get("SHARY_HOSTILE_REPORT")
    if report:
        test = os.environ.get("PYTEST_CURRENT_TEST", "?").split(" ")[0]
        with open(report, "a", encoding="utf-8") as out:
            out.write(json.dumps({"test": test, "mode": mode, "argv": [str(a) for a in argv],
                                  "status": outcome.status, "seconds": outcome.seconds,
                                  "peak_mb": outcome.peak_mb}) + "\n")
    return outcome


def assert_refused(outcome: Outcome, *files: Path, message: str | None = None) -> None:
    """Assert the rule: exit 2, positioned errors on lines the files have, no traceback.

    ``files`` are the user's files that may be blamed; every problem line must
    name one of them (by the name the user gave) at a line that exists in it.
    ``message``, if given, is a regular expression that some problem must match.
    """
    where = f"\n--- stderr ---\n{outcome.err[-3000:]}\n--- stdout ---\n{outcome.out[-1000:]}"
    assert "Traceback (most recent call last)" not in outcome.err + outcome.out, where
    assert outcome.status == 2, f"exit status {outcome.status}, not 2{where}"
    found = outcome.problems()
    assert found, f"no FILE:LINE:COL: error: line{where}"
    lines = {str(f): _line_count(f) for f in files}
    for m in found:
        if lines:
            assert m["file"] in lines, f"blames {m['file']!r}, not one of {list(lines)}{where}"
            assert 1 <= int(m["line"]) <= max(lines[m["file"]], 1), \
                f"line {m['line']} is not in {m['file']} ({lines[m['file']]} lines){where}"
        assert int(m["col"]) >= 1, where
    if message is not None:
        assert any(re.search(message, m["message"]) for m in found), \
            f"no problem matches {message!r}{where}"
    assert outcome.seconds < MAX_SECONDS, f"took {outcome.seconds:.1f} s{where}"
    assert outcome.peak_mb < MAX_MB, f"needed {outcome.peak_mb:.0f} MB{where}"


def _line_count(path: Path) -> int:
    """Lines of a file as an editor shows them (a last line without newline counts)."""
    data = Path(path).read_bytes()
    return data.count(b"\n") + (0 if data.endswith(b"\n") or not data else 1)
