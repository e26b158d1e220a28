"""A bad link over real Zenoh, between processes: the managers (with the robots, whose
executors are scripted) run here, the three people as ``shary agent`` processes, and
IVA's process is started with ``--inject-latency 40s``.  The seam inspection's question
cannot reach IVA within its 30 s: it expires, takes the fallback the team file gives,
and the goal is met before IVA ever hears it.
The managers' merged view holds every row of every log, in time order."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

from scripted import ScriptedExecutor
from test_transport import ATOMIC, free_port

from shary.log import read_events
from shary.team import load_team
from shary.transport.distributed import Conductor

SEAM = Path(__file__).parent / "data" / "team"
PEOPLE = ["EVA1", "EVA2", "IVA"]


def _team_file(folder: Path) -> Path:
    """The seam team, its question given a fallback within 30 s; IVA answers in 3 s."""
    shutil.copy(SEAM / "seam-recipes.yaml", folder / "seam-recipes.yaml")
    text = (SEAM / "seam-team.yaml").read_text()
    for old, new in (("expires: 1min", 'expires: 30s\n    fallback: "yes"'),
                     ("questions: {reply: answer, after: [3s, 5s]}",
                      "questions: {reply: answer, after: 3s}")):
        assert old in text
        text = text.replace(old, new)
    path = folder / "seam.team.yaml"
    path.write_text(text.replace("../../../shary", str(Path(__file__).parent.parent / "shary")))
    return path


def test_a_question_over_a_slow_link_expires_and_falls_back(tmp_path: Path) -> None:
    team_file = _team_file(tmp_path)
    logs = tmp_path / "logs"
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    conductor = Conductor(load_team(team_file), listen=endpoint, logdir=logs, members=PEOPLE)
    executor = ScriptedExecutor(conductor.team.loop, {"drive": 2.0, "weld": 10.0, "scan": 3.0,
                                                      "aim-light": 1.0})
    for robot in ("K-10", "Robonaut-B"):
        for atomic in ATOMIC:
            conductor.team.robot(robot).world.register(atomic, executor)
    children = []
    try:
        for name in PEOPLE:
            faults = ["--inject-latency", "40s"] if name == "IVA" else []
            children.append(subprocess.Popen(
                [sys.executable, "-m", "shary", "agent", name, "--team", str(team_file),
                 "--connect", endpoint, "--log-dir", str(logs), *faults],
                stdin=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                env={**os.environ, "COLUMNS": "200"}))
        assert conductor.wait_for_members(60) == []
        assert conductor.run(900) == "done"
    finally:
        conductor.close()
        for child in children:
            try:
                child.wait(timeout=20)
            except subprocess.TimeoutExpired:
                child.kill()
                child.wait()
    assert [child.returncode for child in children] == [0, 0, 0], \
        [child.stderr.read() for child in children if child.stderr]
    managers = list(read_events(logs / "managers.sqlite"))
    (question,) = [e for e in managers if e.kind == "question"]
    (answer,) = [e for e in managers if e.kind == "answer"]
    assert answer.data["expired"] is True and answer.data["value"] == "yes"
    assert answer.time - question.time == 30.0
    # it was asked of IVA, whose link delays it past its expiry (IVA answers in 3 s)
    (asked,) = [e for e in managers if e.kind == "message" and e.data["type"] == "question"]
    assert asked.data["to"] == "IVA" and asked.time == question.time
    assert not [e for e in read_events(logs / "IVA.sqlite") if e.kind == "message"]
    # the managers' merged view: every row of every process's log while the run went on
    # (not the others leaving once it is over), ordered by time
    view = conductor.records
    end = managers[-1].time
    for process in [*PEOPLE, "managers"]:
        rows = [e for e in read_events(logs / f"{process}.sqlite")
                if not (e.kind == "agent-left" and e.time == end)]
        assert view.by[process] == len(rows), process
    assert [e.time for e in view.events] == sorted(e.time for e in view.events)
    assert any(e.kind == "message" and e.agent == "EVA2" and e.data.get("status") == "done"
               for e in view.events)  # a member's row, forwarded
