"""The seam-welding scenarios with every agent in its own process: ``shary team up
SCENARIO`` starts the world (``shary world``), each robot and each person (``shary
agent``) over Zenoh on loopback, and gives the in-process run's events at the same times:
task running / done / failed, respawns, questions and answers, and each robot's atomic
tasks.  Two distributed runs (a nominal one, and one where K-10 asks IVA with a picture);
the world's side of the messages is checked in process."""

from __future__ import annotations

import base64
import json
import os
import signal
import socket
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from shary.facts.database import FactDatabase
from shary.kernel.loop import EventLoop
from shary.log.contextlog import merged_events
from shary.team.agents import INFORM, QUERY
from shary.team.world import ATTACH, CANCEL, WORLD
from shary.transport.facts import SUBSCRIBE, apply_change
from shary.transport.messages import PICTURE, Act, Assignment, FactChange, Message, Progress
from shary.transport.port import MessagePort
from shary.transport.wire import MAX_BYTES, decode, encode
from sim.results import CHUNK
from sim.scenario import builtin_scenarios
from sim.weld.run import run_weld
from sim.weld.scenario import load_weld_scenario
from sim.weld.site import WeldSite
from sim.weld.world import WeldWorld

SHOWN = ("task-running", "task-done", "task-failed", "task-given-up", "respawn", "question",
         "answer", "exec-request", "exec-result")


def _endpoint() -> str:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return f"tcp/127.0.0.1:{s.getsockname()[1]}"


def _events(paths: list[Path]) -> list[tuple[Any, ...]]:
    """What the scenarios are about, wherever it was logged, by time."""
    with merged_events(paths) as events:
        return sorted((round(e.time, 6), e.kind, e.task if e.kind not in (
            "exec-request", "exec-result") else None, e.agent, e.data.get("value"),
            e.data.get("text"), e.data.get("atomic"), e.data.get("status"))
            for e in events if e.kind in SHOWN)


@pytest.mark.parametrize("name", ["weld-nominal", "weld-human-supports-robot"])
def test_a_weld_scenario_distributed_gives_the_in_process_events(name: str,
                                                                  tmp_path: Path) -> None:
    inproc = run_weld(builtin_scenarios()[name], out=tmp_path / "inproc")
    assert inproc.passed, inproc.differences
    logs = tmp_path / "logs"
    process = subprocess.Popen(
        [sys.executable, "-m", "shary", "team", "up", name, "--listen", _endpoint(),
         "--log-dir", str(logs), "--json"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True, start_new_session=True)
    try:
        out, err = process.communicate(timeout=240)
    finally:  # no leftovers: the whole process group (the world and the agents) goes
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
        process.wait(timeout=30)
    assert process.returncode == 0, err
    result = json.loads(out.strip().splitlines()[-1])
    assert result["passed"] and result["differences"] == [] and result["lost"] == []
    # the end: when nothing is left to do (in one process, looked at every CHUNK seconds)
    assert 0 <= inproc.simulated_seconds - result["time"] < CHUNK + 1e-9
    processes = {p.stem for p in logs.glob("*.sqlite")}
    assert processes == {"managers", "world", *load_weld_scenario(
        builtin_scenarios()[name]).team.agents} - {"SRA", "CM"}
    assert _events(sorted(logs.glob("*.sqlite"))) == _events([tmp_path / "inproc" /
                                                             "log.sqlite"])
    if name == "weld-human-supports-robot":  # the world took the question's picture
        (question,) = [e for e in _events([logs / "managers.sqlite"]) if e[1] == "question"]
        with merged_events([logs / "managers.sqlite"]) as events:
            data = next(e.data["data"] for e in events if e.kind == "question")
        assert Path(data["image"]).parent == logs and Path(data["image"]).exists()
        assert PICTURE not in data  # the bytes travel; the log keeps the path


@pytest.fixture(scope="module")
def world(tmp_path_factory: pytest.TempPathFactory) -> Any:
    """The world of weld-human-supports-robot on an in-process port, and what it sends."""
    out = tmp_path_factory.mktemp("world")
    loop = EventLoop()
    port = MessagePort(loop)
    heard: list[Message] = []
    for name in ("K-10", "Robonaut-B", "tasks"):
        port.subscribe(name, heard.append)
    with WeldSite() as site:
        facts = FactDatabase()
        yield WeldWorld(load_weld_scenario(builtin_scenarios()["weld-human-supports-robot"]),
                        site, port, facts, lambda kind, **data: None, out), heard


def _send(world: WeldWorld, message: Message, seconds: float = 0.0) -> None:
    world.port.send(message)
    world.loop.advance(seconds)


def test_the_world_attaches_a_picture_that_travels_in_the_question(world: Any) -> None:
    weld, heard = world
    heard.clear()
    _send(weld, Act("K-10", WORLD, id="w1", act=QUERY, data={
        "service": ATTACH, "topic": "seam-okay", "robot": "K-10",
        "team-task": "inspect-P2-P3"}))
    (reply,) = heard
    assert isinstance(reply, Act) and reply.act == INFORM and reply.id == "w1"
    png = base64.b64decode(reply.data[PICTURE])
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and png == Path(reply.data["image"]).read_bytes()
    assert reply.data["seam"] == "P2-P3"
    assert len(encode(reply)) < MAX_BYTES and decode(encode(reply)) == reply
    heard.clear()
    _send(weld, Act("K-10", WORLD, id="w2", act=QUERY, data={
        "service": ATTACH, "topic": "other", "robot": "K-10"}))
    assert heard[0].data == {"service": ATTACH}  # nothing to attach to other questions


def test_a_subscriber_gets_the_world_facts_then_their_changes(world: Any) -> None:
    weld, heard = world
    heard.clear()
    _send(weld, Act("tasks", WORLD, act=SUBSCRIBE))
    (snapshot,) = heard
    mine = FactDatabase()
    apply_change(mine, snapshot)
    assert mine.triples() == weld.facts.triples()
    assert mine.objects("K-10", "x") == [-1.5] and mine.objects("P1", "mounted") == [True]
    heard.clear()  # K-10 drives: its pose changes reach the subscriber, tick by tick
    _send(weld, Assignment("K-10", WORLD, id="r1", task="n1", skill="drive",
                           args={"place": "inspect-P2-P3"}), 60.0)
    changes = [m for m in heard if isinstance(m, FactChange)]
    (done,) = [m for m in heard if isinstance(m, Progress)]
    assert done.id == "r1" and done.status == "done" and done.data == {"place": "inspect-P2-P3"}
    assert len(changes) > 10 and heard.index(done) > heard.index(changes[0])
    for change in changes:
        apply_change(mine, decode(encode(change)))
    assert mine.triples() == weld.facts.triples()


def test_an_atomic_task_is_cancelled_and_an_unknown_one_fails(world: Any) -> None:
    weld, heard = world
    heard.clear()
    _send(weld, Assignment("K-10", WORLD, id="r2", task="n2", skill="drive",
                           args={"place": "k10-home"}), 1.0)
    _send(weld, Act("K-10", WORLD, id="r2", act=CANCEL), 30.0)
    assert not [m for m in heard if isinstance(m, Progress)]  # stopped, as the executor port
    _send(weld, Assignment("K-10", WORLD, id="r3", task="n3", skill="fly"))
    (failed,) = [m for m in heard if isinstance(m, Progress)]
    assert failed.status == "failed" and "cannot perform 'fly'" in failed.reason


def test_what_has_no_world_is_refused_plainly(shary) -> None:
    status, _, err = shary("world", "give-bottle")
    assert status == 2 and "not a seam-welding scenario" in err
    nobody = _endpoint()
    status, _, err = shary("world", "weld-nominal", "--connect", nobody)
    assert status == 2 and f"cannot join the team at {nobody}" in err and ".rs:" not in err


def test_the_world_refuses_what_it_cannot_do_and_goes_on(world: Any) -> None:
    """Anyone on the network may send the world anything the schema lets through."""
    weld, heard = world
    heard.clear()
    for i, (skill, args) in enumerate([("drive", {"place": [1]}), ("drive", {}),
                                       ("weld", {"seam": {"x": 1}}), ("inspect", {})]):
        _send(weld, Assignment("K-10", WORLD, id=f"h{i}", task="n", skill=skill, args=args))
    assert [(m.id, m.status) for m in heard] == [(f"h{i}", "failed") for i in range(4)]
    heard.clear()
    weld.port.subscribe("EVA1", heard.append)
    _send(weld, Assignment("EVA1", WORLD, id="h5", task="mount-P4", skill="mount-panel",
                           args={"panel": "P4", "helper": ["EVA2"]}))
    _send(weld, Act("K-10", WORLD, id="h6", act=QUERY, data={
        "service": ATTACH, "topic": "seam-okay", "robot": "nobody", "team-task": {}}))
    assert [(m.id, getattr(m, "status", None)) for m in heard] == [("h5", "failed"),
                                                                    ("h6", None)]
    assert "no picture" in heard[1].data["error"]
