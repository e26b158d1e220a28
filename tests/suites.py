"""Where the external suites are, and what a test says when one is absent.

The suites are data written by others (SCION's statechart traces, the IPC 2020 HTN
domains); they are never copied into this repository.  They are read from
``$SHARY_SUITES`` (default: ``../shared/suites`` beside the checkout), laid out as the
README's "External suites" section makes them: ``scion/`` is the ``test/`` folder of
github.com/jbeard4/scxml-test-framework, ``ipc2020/`` a clone of
github.com/panda-planner-dev/ipc2020-domains.  A test that needs one and does not find
it skips with :func:`absent`'s message, which says how to get it.

Whether a suite is there is asked when each test runs, not when its module is imported
(:func:`pytest_runtest_setup`, this module being a pytest plugin that ``conftest.py``
loads): a suite put in place while pytest collects is found by every test.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SUITES = Path(os.environ.get("SHARY_SUITES") or REPO.parent / "shared" / "suites")
"""The folder of the external suites: ``$SHARY_SUITES``, else ``../shared/suites``."""

def how_to_get(name: str) -> str:
    """The commands that put the suite ``name`` where the tests read it (as the README's
    "External suites" section does, into :data:`SUITES`)."""
    if name == "scion":
        return (f"git clone --depth 1 https://github.com/jbeard4/scxml-test-framework "
                f"{SUITES}/scxml-test-framework && ln -s scxml-test-framework/test "
                f"{SUITES}/scion")
    return (f"git clone --depth 1 https://github.com/panda-planner-dev/ipc2020-domains "
            f"{SUITES}/ipc2020")


def suite(name: str) -> Path:
    """The folder of the suite ``name`` (``scion`` or ``ipc2020``), present or not."""
    return SUITES / name


def absent(name: str) -> str:
    """Why a test of the suite ``name`` skips: where it was looked for, how to get it."""
    return (f"the {name} suite is not at {suite(name)}: get it with '{how_to_get(name)}', or "
            f"set SHARY_SUITES to the folder that holds it (the README's 'External suites')")


def needs(name: str) -> pytest.MarkDecorator:
    """Mark a test that reads the suite ``name``: it skips, saying how to get the suite,
    when the suite is absent as the test starts."""
    return pytest.mark.suite(name)


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "suite(name): reads the external suite NAME "
                            "(tests/suites.py); skipped when it is absent")


def pytest_runtest_setup(item: pytest.Item) -> None:
    """Skip a test marked :func:`needs` whose suite is not there now."""
    for mark in item.iter_markers("suite"):
        if not suite(mark.args[0]).is_dir():
            pytest.skip(absent(mark.args[0]))
