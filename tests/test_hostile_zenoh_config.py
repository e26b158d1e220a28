"""Hostile ``--zenoh-config`` files and fault options: refused by ``shary agent`` and
``shary team up`` with the rule of tests/hostile.py, before any Zenoh session opens.

The corpus is tests/hostile/zenoh-config/ (each file's first line: ``// expect: REGEX``);
a missing, an empty, a binary, a huge and a deeply nested file are made here."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from hostile import HOSTILE, assert_refused, run_inprocess, run_subprocess

from shary.transport.zconfig import MAX_BYTES

CASES = sorted((HOSTILE / "zenoh-config").glob("*.json5"))
TEAM = Path(__file__).parent / "data" / "transport" / "panels.team.yaml"


def _agent(config: Path, *extra: object):
    return run_inprocess("agent", "IVA", "--team", TEAM, "--zenoh-config", config, *extra)


@pytest.mark.parametrize("path", CASES, ids=[p.stem for p in CASES])
def test_a_hostile_zenoh_config_is_refused(path: Path) -> None:
    expect = re.match(r"^// expect: (.+)$", path.read_text().split("\n", 1)[0])
    assert expect, f"{path} does not start with '// expect: REGEX'"
    assert_refused(_agent(path), path, message=expect[1])


def test_team_up_checks_its_config_too(tmp_path: Path) -> None:
    path = HOSTILE / "zenoh-config" / "mode.json5"
    assert_refused(run_subprocess("team", "up", TEAM, "--zenoh-config", path, "--log-dir",
                                  tmp_path), path, message="the mode is chosen")


@pytest.mark.parametrize("name, content, message", [
    ("empty.json5", b"", "Empty strings are not legal JSON5"),
    ("binary.json5", b"{a: '\xff\xfe'}", "not UTF-8"),
    ("huge.json5", b"{a: '" + b"x" * (MAX_BYTES + 10) + b"'}", "the limit is"),
    ("deep.json5", b"{a: " + b"[" * 100_000 + b"]" * 100_000 + b"}", "nested 100001 deep"),
])
def test_unreadable_zenoh_configs_are_refused(tmp_path: Path, name: str,
                                              content: bytes, message: str) -> None:
    path = tmp_path / name
    path.write_bytes(content)
    assert_refused(_agent(path), path, message=message)


def test_a_missing_zenoh_config_is_named(tmp_path: Path) -> None:
    outcome = _agent(tmp_path / "nowhere.json5")
    assert outcome.status == 2 and "Traceback" not in outcome.err
    assert f"{tmp_path / 'nowhere.json5'}:1:1: error: cannot read file" in outcome.err


@pytest.mark.parametrize("option, value, message", [
    ("--inject-loss", "1.5", "not a share of messages"),
    ("--inject-loss", "nan", "not a share of messages"),
    ("--inject-loss", "-0.1", "not a share of messages"),
    ("--inject-latency", "soon", "not a duration"),
    ("--inject-latency", "-2s", "not a duration"),
    ("--fault-seed", "x", "invalid int value"),
])
def test_bad_fault_options_are_refused(shary, capsys, option: str, value: str,
                                       message: str) -> None:
    try:
        status, _, err = shary("agent", "IVA", "--team", TEAM, f"{option}={value}")
    except SystemExit as exit_:  # argparse's refusal: its usage line and the reason
        status, err = exit_.code, capsys.readouterr().err
    assert status == 2 and message in err and "Traceback" not in err
