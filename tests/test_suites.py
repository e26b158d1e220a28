"""A test that reads an external suite finds it whenever it is there when the test runs.

Each case runs a small pytest session of its own (a subprocess, with ``tests/`` on the
path for :mod:`suites`) whose suites folder does not exist when the session starts.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

HERE = Path(__file__).resolve().parent
TEST = """
    from suites import needs

    @needs("scion")
    def test_reads_the_suite():
        pass
"""
MADE_WHILE_COLLECTING = """
    import os
    from pathlib import Path

    pytest_plugins = ["suites"]

    def pytest_collection_finish(session):
        Path(os.environ["SHARY_SUITES"], "scion").mkdir(parents=True)
"""


def _session(tmp_path: Path, conftest: str) -> str:
    (tmp_path / "test_late.py").write_text(textwrap.dedent(TEST))
    (tmp_path / "conftest.py").write_text(textwrap.dedent(conftest))
    env = {**os.environ, "PYTHONPATH": str(HERE), "SHARY_SUITES": str(tmp_path / "suites")}
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider",
                           "-p", "no:xdist", str(tmp_path)], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=120)
    return done.stdout


def test_a_suite_put_in_place_after_collection_began_is_read(tmp_path):
    assert "1 passed" in _session(tmp_path, MADE_WHILE_COLLECTING)


def test_a_suite_still_absent_skips_saying_how_to_get_it(tmp_path):
    out = _session(tmp_path, 'pytest_plugins = ["suites"]\n')
    assert "1 skipped" in out
    assert f"the scion suite is not at {tmp_path / 'suites' / 'scion'}: get it with" in out
