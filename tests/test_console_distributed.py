"""The operator console on a distributed team: ``shary team up TEAM --console``.

One run of the panels team (the managers and three people, each its own process),
watched and steered over the console's WebSocket from the managers' machine: the
page gets every agent's block and the team tasks going done from the merged records;
pause holds the shared clock, step moves it once, speed and resume let it go; a person's
answer is refused with its reason; every action is in the managers' log with who
did it.  A cancelled team task is withdrawn at the Task Manager (in one process:
the same code path, without processes)."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any
from urllib.request import urlopen

from websockets.sync.client import connect

from shary.log.contextlog import ContextLog, read_events
from shary.team import Team, load_team

TEAM = Path(__file__).parent / "data" / "transport" / "panels.team.yaml"


def _free() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _connect(url: str) -> Any:
    """The console's WebSocket, once the command listens."""
    deadline = time.monotonic() + 60
    while True:
        try:
            return connect(url, open_timeout=5)
        except OSError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.2)


class Page:
    """A WebSocket client that keeps what the console sent it."""

    def __init__(self, ws: Any, http: str):
        self.ws = ws
        self.http = http
        self.changes: list[list[Any]] = []
        self.status: dict[str, Any] = {}
        self.replies: dict[int, dict[str, Any]] = {}
        self.schemes: set[str] = set()
        self._id = 0

    def read(self, until: Any, timeout: float = 60) -> None:
        end = time.monotonic() + timeout
        while not until():
            left = end - time.monotonic()
            assert left > 0, f"timed out; status {self.status}"
            try:
                message = json.loads(self.ws.recv(timeout=min(left, 0.2)))
            except TimeoutError:
                continue
            if message["type"] == "changes":
                self.changes += message["changes"]
            elif message["type"] == "status":
                self.status = message["status"]
            elif message["type"] == "scheme":
                self.schemes.add(message["name"])
            elif message["type"] == "reply":
                self.replies[message["id"]] = message

    def send(self, kind: str, **fields: Any) -> dict[str, Any]:
        self._id += 1
        ident = self._id
        self.ws.send(json.dumps({"kind": kind, "by": "tester", "id": ident, **fields}))
        self.read(lambda: ident in self.replies)
        return self.replies[ident]

    def tasks(self) -> dict[str, str]:
        return {c[1]: c[2]["state"] for c in self.changes if c[0] == "team-task"}


def _steer(page: Page) -> None:
    """Pause at once, look, refuse, step, resume until the verdict."""
    assert page.send("pause")["ok"]
    members = {"EVA1", "EVA2", "IVA"}
    page.read(lambda: members <= {c[1] for c in page.changes if c[0] == "member"}
              and page.tasks().get("mount-P1") == "offered")
    # held before the clock's first step: nobody has accepted (1 s after the offer)
    until = time.monotonic() + 1.0
    page.read(lambda: time.monotonic() > until)
    assert "running" not in page.tasks().values()
    assert page.status["state"] == "paused"
    refused = page.send("answer", question="q1", agent="EVA1", text="yes")
    assert not refused["ok"]
    assert refused["error"] == "question q1 is not open (answered or expired)"
    assert "not offered or running" in page.send(
        "cancel-team-task", team_task="check")["error"]
    page.ws.send('{"kind": "pause", "by": "tester", "kind": "resume"}')  # refused unread
    page.read(lambda: None in page.replies)
    assert "given twice" in page.replies[None]["error"]
    assert page.send("step")["ok"]  # one step: EVA1 accepts at 1 s
    page.read(lambda: page.tasks().get("mount-P1") == "running")
    assert page.tasks()["mount-P2"] == "offered"
    assert page.send("speed", value=50)["ok"]
    page.read(lambda: page.status["speed"] == 50)
    assert page.send("speed", value=0)["ok"]  # as fast as it goes
    assert page.send("resume")["ok"]
    page.read(lambda: page.status.get("state") == "ended", timeout=120)
    assert page.status["verdict"]["passed"], page.status
    assert set(page.tasks().values()) == {"done"}
    assert {"EVA1", "EVA2", "IVA"} <= {c[1] for c in page.changes if c[0] == "agent"}


def _team_up(what: str, logs: Path, steer: Callable[[Page], None]) -> tuple[int, str]:
    """``shary team up WHAT --console`` steered by ``steer`` over the WebSocket, then
    stopped with Ctrl-C (the console stays up until then); its exit status and output.
    Every process of the team goes in the end (its process group)."""
    port = _free()
    process = subprocess.Popen(
        [sys.executable, "-u", "-m", "shary", "team", "up", what, "--listen",
         f"tcp/127.0.0.1:{_free()}", "--log-dir", str(logs), "--console",
         "--console-port", str(port)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env={**os.environ, "COLUMNS": "200"}, start_new_session=True)
    try:
        with _connect(f"ws://127.0.0.1:{port}/ws") as ws:
            steer(Page(ws, f"http://127.0.0.1:{port}"))
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
        process.wait(timeout=30)
    assert f"shary console: http://127.0.0.1:{port}/" in out
    return process.returncode, err


def test_a_distributed_team_is_watched_and_steered_from_the_managers(tmp_path: Path) -> None:
    logs = tmp_path / "logs"
    status, err = _team_up(str(TEAM), logs, _steer)
    assert status == 0, err
    rows = list(read_events(logs / "managers.sqlite"))
    actions = [(e.agent, e.data["action"]) for e in rows if e.kind == "operator"]
    assert actions == [("tester", kind) for kind in ("pause", "step", "speed", "speed",
                                                      "resume")]
    refusals = [e.data for e in rows if e.kind == "operator-refused"]
    assert [r["action"] for r in refusals] == ["answer", "cancel-team-task", "malformed"]
    assert [e.agent for e in rows if e.kind == "operator-refused"] == [
        "tester", "tester", "unknown"]  # a message not read says nobody


def _watch_weld(page: Page) -> None:
    """A breakpoint at K-10's question; the answer is IVA's to give, from IVA's process."""
    assert page.send("breakpoint", act="question")["ok"]
    page.read(lambda: page.status.get("state") == "paused" and any(
        c[0] == "tq" and c[2]["holder"] == "IVA" for c in page.changes), timeout=120)
    question = next(c for c in page.changes if c[0] == "tq")
    assert question[2]["asker"] == "K-10"
    with urlopen(f"{page.http}/run/{question[2]['image']}") as picture:  # K-10's camera
        assert picture.read(8) == b"\x89PNG\r\n\x1a\n"
    refused = page.send("answer", question=question[1], agent="IVA", text="no")
    assert "IVA runs in its own process" in refused["error"]
    assert page.send("take-control", agent="K-10", person="IVA")["error"].startswith(
        "K-10 runs in its own process: control authority")
    assert "runs in its own process" in page.send("robot-breakpoint", agent="K-10")["error"]
    assert page.send("clear-breakpoint", act="question")["ok"]
    assert page.send("resume")["ok"]
    page.read(lambda: page.status.get("state") == "ended", timeout=120)
    assert page.status["verdict"] == {"passed": True, "differences": []}
    agents = {c[1] for c in page.changes if c[0] == "member"}
    assert {"K-10", "Robonaut-B", "IVA"} <= agents
    own = {c[1] for c in page.changes if c[0] == "member" and c[3].get("process") == "own"}
    assert own >= {"K-10", "Robonaut-B", "IVA"}  # the page offers them no actions of theirs
    assert set(page.tasks().values()) == {"done"}
    configs = {c[1].partition("/")[0] for c in page.changes if c[0] == "config" and c[2]}
    assert configs == {"K-10", "Robonaut-B"}  # the robots' schemes, from their processes
    page.read(lambda: bool(page.schemes))  # and their diagrams


def test_a_weld_scenario_distributed_shows_the_robots_and_the_question(tmp_path: Path) -> None:
    status, err = _team_up("weld-human-supports-robot", tmp_path / "logs", _watch_weld)
    assert status == 0, err


def test_a_cancelled_team_task_is_withdrawn_at_the_task_manager(tmp_path: Path) -> None:
    log = ContextLog(tmp_path / "log.sqlite")
    team = Team(load_team(TEAM), log=log)
    team.start()
    team.loop.advance(1.5)  # EVA1 runs mount-P1
    assert team.tasks.tasks["mount-P1"].state == "running"
    assert team.tasks.withdraw("check", "no") == "team task check is not offered or running now"
    assert team.tasks.withdraw("mount-P1", "cancelled by the operator tester") is None
    team.loop.advance(0.0)
    assert team.tasks.tasks["mount-P1"].state in ("failed", "ready", "pending", "offered")
    assert team.agents["EVA1"].current == "mount-P1"  # busy until it says it is over
    team.loop.advance(60)
    log.close()
    rows = list(read_events(tmp_path / "log.sqlite"))
    failed = [e for e in rows if e.kind == "task-failed"]
    assert [(e.task, e.agent, e.data["reason"]) for e in failed] == [
        ("mount-P1", "EVA1", "cancelled by the operator tester")]
    heard = [e for e in rows if e.kind == "heard" and e.agent == "EVA1"]
    assert any(e.data.get("status") == "withdrawn" for e in heard)
