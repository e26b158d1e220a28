"""Hostile schemes: bad invokes, invoke cycles, schemes that loop; refused with positions.

Each corpus file starts with ``# expect: REGEX`` (tests/hostile_files.py).
Files named ``simulate-*`` are valid schemes that loop once an event comes:
``shary simulate FILE go`` refuses them (a livelock, placed at the looping
transition) in bounded time.  The others are refused by ``shary validate``.
Chains and fans of invokes too big for git are generated in ``tmp_path``.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hostile import HOSTILE, MAX_SECONDS, assert_refused, run_inprocess, run_subprocess
from hostile_files import blamable, corpus, expected

from shary.io.invokes import MAX_DEPTH

SCHEMES = HOSTILE / "scheme"

CASES = corpus("scheme")


@pytest.fixture(autouse=True, scope="module")
def warm() -> None:
    """Pay for imports and schema compilation once, outside the measured refusals."""
    run_inprocess("validate", SCHEMES / "invoke-self.yaml")


@pytest.mark.parametrize("path", CASES, ids=[p.stem for p in CASES])
def test_hostile_scheme_is_refused(path: Path) -> None:
    if path.stem.startswith("simulate-"):
        outcome = run_inprocess("simulate", path, "go", "1s")
    else:
        outcome = run_inprocess("validate", path)
    partners = sorted(SCHEMES.glob("invoke-cycle-*.yaml")) if "cycle" in path.stem else []
    assert_refused(outcome, *blamable(path), *partners, message=expected(path))


def test_a_chain_of_invokes_too_long_is_refused(tmp_path):
    n = MAX_DEPTH + 4
    for i in range(n):
        child = f"invoke: {{scheme: s{i + 1}.yaml}}" if i + 1 < n else "on: {}"
        (tmp_path / f"s{i}.yaml").write_text(f"scheme: s{i}\nstates:\n  a:\n    {child}\n")
    outcome = run_subprocess("validate", tmp_path / "s0.yaml")
    assert_refused(outcome, *[tmp_path / f"s{i}.yaml" for i in range(n)],
                   message=f"invokes nest more than {MAX_DEPTH} schemes deep")


def test_a_wide_fan_of_invokes_loads_each_file_once(tmp_path):
    """Ten levels, each state invoking the next level four times: 4**10 paths, 10 files."""
    levels = 10
    for i in range(levels):
        if i + 1 < levels:
            text = f"scheme: l{i}\nstates:\n  p:\n    parallel: true\n    states:\n" + "\n".join(
                f"      a{k}:\n        invoke: {{scheme: l{i + 1}.yaml, id: k{k}}}"
                for k in range(4)) + "\n"
        else:
            text = f"scheme: l{i}\nstates:\n  leaf: {{}}\n"
        (tmp_path / f"l{i}.yaml").write_text(text)
    outcome = run_subprocess("validate", tmp_path / "l0.yaml")
    assert outcome.status == 0, outcome.err
    assert outcome.seconds < MAX_SECONDS


def test_a_symbolic_link_out_of_the_folder_is_refused(tmp_path):
    outside = tmp_path / "outside.yaml"
    outside.write_text("scheme: outside\nstates:\n  a: {}\n")
    folder = tmp_path / "f"
    folder.mkdir()
    os.symlink(outside, folder / "link.yaml")
    scheme = folder / "top.yaml"
    scheme.write_text("scheme: top\nstates:\n  a:\n    invoke: {scheme: link.yaml}\n")
    assert_refused(run_inprocess("validate", scheme), scheme,
                   message="'link.yaml' is outside the folder of top.yaml")
