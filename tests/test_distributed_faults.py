"""A bad link over real Zenoh, between processes: the managers and the rover (whose only
atomic task is the team's own ``ask``: no world needed) run here, the IVA as a
``shary agent`` process.  Started with ``--inject-latency 40s``, IVA's link delays the
rover's question (expires in 30 s, fallback "yes") past its expiry: the fallback is
taken and the goal is met.  On a good link IVA answers "no" in 3 s and the check fails,
as the team file says.  The managers' merged view holds every row of every process's
log, in time order."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from test_transport import free_port

from shary.log.contextlog import read_events
from shary.team import load_team
from shary.transport.distributed import Conductor

ASK = Path(__file__).parent / "data" / "transport" / "ask.team.yaml"


@pytest.mark.parametrize("latency", ["40s", None], ids=["slow-link", "good-link"])
def test_a_question_over_a_slow_link_expires_and_falls_back(tmp_path: Path,
                                                           latency: str | None) -> None:
    logs = tmp_path / "logs"
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    conductor = Conductor(load_team(ASK), listen=endpoint, logdir=logs, members=["IVA"])
    faults = ["--inject-latency", latency] if latency else []
    iva = subprocess.Popen(
        [sys.executable, "-m", "shary", "agent", "IVA", "--team", str(ASK), "--connect",
         endpoint, "--log-dir", str(logs), *faults],
        stdin=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
        env={**os.environ, "COLUMNS": "200"})
    try:
        assert conductor.wait_for_members(60) == []
        outcome = conductor.run(900)
        iva.wait(timeout=20)  # it stops when told, while the managers are still there
    finally:
        conductor.close()
        if iva.poll() is None:
            iva.kill()
            iva.wait()
    assert iva.returncode == 0, iva.stderr.read() if iva.stderr else ""
    managers = list(read_events(logs / "managers.sqlite"))
    (question,) = [e for e in managers if e.kind == "question"]
    (asked,) = [e for e in managers if e.kind == "message" and e.data["type"] == "question"
                and e.data["to"] == "IVA"]
    (answer,) = [e for e in managers if e.kind == "answer"]
    said = [e for e in read_events(logs / "IVA.sqlite") if e.kind == "message"]
    assert asked.time == question.time
    if latency:  # it reached IVA too late: nobody answered, the fallback was taken
        assert outcome == "done" and said == []
        assert answer.data["expired"] is True and answer.data["value"] == "yes"
        assert answer.time - question.time == 30.0
    else:
        assert outcome == "failed" and [e.data["value"] for e in said] == ["no"]
        assert answer.agent == "IVA" and answer.time - question.time == 3.0
    # the managers' merged view: every row of every process's log while the run went on
    # (not the others leaving once it is over), ordered by time
    view = conductor.records
    end = managers[-1].time
    for process in ("IVA", "managers"):
        rows = [e for e in read_events(logs / f"{process}.sqlite")
                if not (e.kind == "agent-left" and e.time == end)]
        assert view.by[process] == len(rows) > 0, process
    assert [e.time for e in view.events] == sorted(e.time for e in view.events)
