"""A team spread over processes over Zenoh on loopback: ``shary team up`` runs the
managers and starts every person as ``shary agent``; the outcome and the times are the
in-process run's; a member killed with SIGKILL mid-task is noticed within a second, its
task goes to another, the goal is still met, its log up to its last commit is there, and
the member restarted joins the running team.

Two runs of a few processes each (slow on a loaded machine: keep it to these)."""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

from shary.log import read_events
from shary.team import Team, load_team

TEAM = Path(__file__).parent / "data" / "transport" / "panels.team.yaml"


def _endpoint() -> str:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return f"tcp/127.0.0.1:{s.getsockname()[1]}"


def _up(logdir: Path, *extra: str, endpoint: str | None = None) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-u", "-m", "shary", "team", "up", str(TEAM), "--listen",
         endpoint or _endpoint(),
         "--log-dir", str(logdir), *extra],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env={**os.environ, "COLUMNS": "200"}, start_new_session=True)


def _stop(process: subprocess.Popen[str]) -> None:
    """No leftovers: the whole process group (the agents too) goes."""
    if process.poll() is None:
        os.killpg(process.pid, signal.SIGKILL)
    process.wait(timeout=30)


def _done(path: Path) -> list[tuple[str, str, float]]:
    return [(e.task, e.agent, e.time) for e in read_events(path) if e.kind == "task-done"]


def test_team_up_runs_the_goal_as_in_process(tmp_path: Path, shary) -> None:
    process = _up(tmp_path / "logs", "--json")
    try:
        out, err = process.communicate(timeout=180)
    finally:
        _stop(process)
    assert process.returncode == 0, err
    result = json.loads(out.strip().splitlines()[-1])
    assert result["outcome"] == "done" and result["lost"] == []
    spec = load_team(TEAM)
    logs = tmp_path / "logs"
    assert sorted(p.name for p in logs.glob("*.sqlite")) == [
        "EVA1.sqlite", "EVA2.sqlite", "IVA.sqlite", "managers.sqlite"]
    from shary.log import ContextLog

    inproc = ContextLog(tmp_path / "inproc.sqlite")
    again = Team(spec, log=inproc)
    assert again.run(3600) == "done"
    inproc.close()
    assert _done(logs / "managers.sqlite") == _done(tmp_path / "inproc.sqlite")
    assert result["time"] == _done(tmp_path / "inproc.sqlite")[-1][2]
    # each person's own log holds what that person did
    heard = [e for e in read_events(logs / "EVA1.sqlite") if e.kind == "message"]
    assert [e.data["status"] for e in heard] == ["accepted", "done"]
    # shary log merges the four logs into one view ordered by time
    status, out, _ = shary("log", *sorted(map(str, logs.glob("*.sqlite"))), "--json")
    rows = [json.loads(line) for line in out.splitlines()]
    assert status == 0 and [r["time"] for r in rows] == sorted(r["time"] for r in rows)
    assert {r["agent"] for r in rows if r["kind"] == "message"} >= {"EVA1", "EVA2", "IVA",
                                                                      "tasks"}


def test_a_member_killed_mid_task_is_noticed_and_its_task_goes_to_another(
        tmp_path: Path) -> None:
    endpoint = _endpoint()
    process = _up(tmp_path / "logs", "--pace", "0.2", endpoint=endpoint)
    assert process.stdout is not None
    restart = None
    lines: list[tuple[float, str]] = []
    pids: dict[str, int] = {}
    killed_at = None
    try:
        for line in process.stdout:
            lines.append((time.monotonic(), line.rstrip()))
            joined = re.match(r"\+ (\S+) joined \(pid (\d+)\)", line.strip())
            if joined:
                pids[joined[1]] = int(joined[2])
            if killed_at is None and re.search(r"mount-P\d running: EVA1", line):
                os.kill(pids["EVA1"], signal.SIGKILL)
                killed_at = time.monotonic()
            if line.strip() == "- EVA1 left":  # restarted: it joins the running team
                restart = subprocess.Popen(
                    [sys.executable, "-m", "shary", "agent", "EVA1", "--team", str(TEAM),
                     "--connect", endpoint, "--log-dir", str(tmp_path / "logs")],
                    stdin=subprocess.DEVNULL)
        process.wait(timeout=60)
    finally:
        _stop(process)
        if restart is not None:
            try:
                restart.wait(timeout=10)  # it stops with the team
            finally:
                if restart.poll() is None:
                    restart.kill()
                    restart.wait()
    text = "\n".join(line for _, line in lines)
    assert killed_at is not None, text
    assert process.returncode == 0, text + process.stderr.read()
    (left_at,) = [t for t, line in lines if line.strip() == "- EVA1 left"]
    assert left_at - killed_at < 1.0, text
    assert re.search(r"! EVA1 lost while running mount-P\d: offered again", text)
    logs = tmp_path / "logs"
    done = {task: agent for task, agent, _ in _done(logs / "managers.sqlite")}
    assert set(done) == {"mount-P1", "mount-P2", "check"} and done["check"] == "IVA"
    # the restarted EVA1 joined the running team, in a log of its own
    assert [line for _, line in lines if line.strip().startswith("+ EVA1 joined")][1:], text
    assert (logs / "EVA1.1.sqlite").exists()
    # the killed member's log is readable up to its last commit, and everything the
    # managers acted on (its acceptance) is in it
    eva1 = [e for e in read_events(logs / "EVA1.sqlite") if e.kind == "message"]
    running = [e for e in read_events(logs / "managers.sqlite")
               if e.kind == "task-running" and e.agent == "EVA1"]
    assert running and all(any(m.task == r.task and m.data["status"] == "accepted"
                               for m in eva1) for r in running)


def test_what_cannot_run_distributed_is_refused_plainly(shary) -> None:
    nobody = _endpoint()
    status, _, err = shary("agent", "EVA1", "--team", str(TEAM), "--connect", nobody)
    assert status == 2 and f"cannot join the team at {nobody}" in err and ".rs:" not in err
    seam = Path(__file__).parent / "data" / "team" / "seam-team.yaml"
    status, _, err = shary("team", "up", str(seam), "--listen", nobody)
    assert status == 2 and "has robots, whose atomic tasks a world performs" in err
    status, _, err = shary("agent", "NOBODY", "--team", str(TEAM))
    assert status == 2 and "no agent 'NOBODY' in team 'panels'" in err
