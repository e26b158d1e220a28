"""A team spread over processes over Zenoh on loopback: ``shary team up`` runs the
managers and starts every person as ``shary agent``; the outcome and the times are the
in-process run's; a member killed with SIGKILL mid-task is noticed within a second, its
task goes to another, the goal is still met, its log up to its last commit is there, and
the member restarted joins the running team.

Two runs of a few processes each (slow on a loaded machine: keep it to these)."""

from __future__ import annotations

import json
import os
import queue
import re
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

from shary.log.contextlog import read_events
from shary.team import Team, load_team

TEAM = Path(__file__).parent / "data" / "transport" / "panels.team.yaml"
REJOIN = Path(__file__).parent / "data" / "transport" / "rejoin.team.yaml"


def _endpoint() -> str:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return f"tcp/127.0.0.1:{s.getsockname()[1]}"


def _up(logdir: Path, *extra: str, endpoint: str | None = None,
        team: Path = TEAM) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-u", "-m", "shary", "team", "up", str(team), "--listen",
         endpoint or _endpoint(),
         "--log-dir", str(logdir), *extra],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env={**os.environ, "COLUMNS": "200"}, start_new_session=True)


def _stop(process: subprocess.Popen[str]) -> None:
    """No leftovers: the whole process group (the agents too) goes."""
    if process.poll() is None:
        os.killpg(process.pid, signal.SIGKILL)
    process.wait(timeout=30)


def _lines(process: subprocess.Popen[str], seconds: float) -> Iterator[str]:
    """``process``'s output lines as they come, for ``seconds`` at most (then the test
    fails with what came: a run that never ends must not hang the suite)."""
    lines: queue.SimpleQueue[str | None] = queue.SimpleQueue()

    def read() -> None:
        assert process.stdout is not None
        for line in process.stdout:
            lines.put(line)
        lines.put(None)

    threading.Thread(target=read, daemon=True).start()
    end = time.monotonic() + seconds
    seen: list[str] = []
    while True:
        try:
            line = lines.get(timeout=max(0.0, end - time.monotonic()))
        except queue.Empty:
            raise AssertionError(f"no end after {seconds:g} s:\n" + "".join(seen)) from None
        if line is None:
            return
        seen.append(line)
        yield line


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
    from shary.log.contextlog import ContextLog

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


def test_a_member_killed_mid_task_is_noticed_and_restarted_learns_the_state(
        tmp_path: Path, shary) -> None:
    endpoint = _endpoint()
    process = _up(tmp_path / "logs", "--pace", "0.2", endpoint=endpoint, team=REJOIN)
    assert process.stdout is not None
    restart = None
    lines: list[tuple[float, str]] = []
    pids: dict[str, int] = {}
    killed_at = None
    try:
        for line in _lines(process, 240):
            lines.append((time.monotonic(), line.rstrip()))
            joined = re.match(r"\+ (\S+) joined \(pid (\d+)\)", line.strip())
            if joined:
                pids[joined[1]] = int(joined[2])
            if killed_at is None and re.search(r"mount-P\d running: EVA1", line):
                os.kill(pids["EVA1"], signal.SIGKILL)
                killed_at = time.monotonic()
            if line.strip() == "- EVA1 left":  # restarted: it joins the running team
                restart = subprocess.Popen(
                    [sys.executable, "-m", "shary", "agent", "EVA1", "--team", str(REJOIN),
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
    assert re.search(r"\+ EVA1 rejoined at [\d.]+ s: told 4 tasks \(\d done\), "
                     r"0 open questions; it holds no task", text), text
    logs = tmp_path / "logs"
    done = {task: agent for task, agent, _ in _done(logs / "managers.sqlite")}
    assert set(done) == {"mount-P1", "mount-P2", "check", "report"}
    assert done["check"] == "IVA" and done["report"] == "EVA1"
    # the restarted EVA1 learned the task table, in a log of its own, and worked again
    again = list(read_events(logs / "EVA1.1.sqlite"))
    (learned,) = [e for e in again if e.kind == "state-learned"]
    table = learned.data["tasks"]
    assert set(table) == set(done) and table["report"]["state"] == "pending"
    assert all(row["agent"] != "EVA1" for row in table.values())
    assert [e.data["status"] for e in again if e.kind == "message"
            and e.task == "report"] == ["accepted", "done"]
    # the killed member's log is readable up to its last commit, and every progress the
    # managers acted on (an acceptance, a task done) is in one of EVA1's logs: merged by
    # shary log, nothing acknowledged is missing
    status, out, _ = shary("log", *sorted(map(str, logs.glob("*.sqlite"))), "--json")
    assert status == 0
    rows = [json.loads(line) for line in out.splitlines()]
    said = {(r["task"], r["data"]["status"]) for r in rows
            if r["kind"] == "message" and r["agent"] == "EVA1" and "status" in r["data"]}
    acted = [(r["task"], {"task-running": "accepted", "task-done": "done"}[r["kind"]])
             for r in rows if r["kind"] in ("task-running", "task-done")
             and r["agent"] == "EVA1"]
    assert acted and set(acted) <= said
    assert [e for e in read_events(logs / "EVA1.sqlite") if e.kind == "message"]


def test_what_cannot_run_distributed_is_refused_plainly(shary) -> None:
    nobody = _endpoint()
    status, _, err = shary("agent", "EVA1", "--team", str(TEAM), "--connect", nobody)
    assert status == 2 and f"cannot join the team at {nobody}" in err and ".rs:" not in err
    seam = Path(__file__).parent / "data" / "team" / "seam-team.yaml"
    status, _, err = shary("team", "up", str(seam), "--listen", nobody)
    assert status == 2 and "has robots, whose atomic tasks a world performs" in err
    status, _, err = shary("agent", "NOBODY", "--team", str(TEAM))
    assert status == 2 and "no agent 'NOBODY' in team 'panels'" in err
