"""The transport port: the wire format and its refusals, faults injected at the port, and
the Zenoh port between two sessions of this process (no child processes here: see
tests/test_distributed.py)."""

from __future__ import annotations

import json
import socket
import time
from dataclasses import replace
from pathlib import Path

import jsonschema
import pytest
from scripted import ScriptedExecutor

from shary.kernel.loop import EventLoop
from shary.log.contextlog import ContextLog, read_events
from shary.team import Team, load_team
from shary.team.spec import Reply
from shary.transport.messages import (
    KINDS,
    Act,
    Answer,
    Assignment,
    Clock,
    FactChange,
    LogRecord,
    Progress,
    Question,
    State,
)
from shary.transport.port import Faults, MessagePort
from shary.transport.wire import WireError, _not_json, decode, encode, json_schema, key

HOSTILE = sorted((Path(__file__).parent / "hostile" / "message").glob("*.json"))
SCHEMA = Path(__file__).parent.parent / "shary" / "schemas" / "message.schema.json"
TEAM = Path(__file__).parent / "data" / "team" / "seam-team.yaml"
ATOMIC = ("drive", "weld", "scan", "aim-light")

EXAMPLES = [
    Act("K-10", "EVA1", id="m1", act="REQUEST-HELP", data={"skill": "point-light"}, task="t"),
    Assignment("tasks", "EVA1", id="a1", task="mount-P1", skill="mount-panel",
               args={"panel": "P1"}, attempt=2),
    Question("interaction", "IVA", id="q1", text="Is this seam okay?", type="choice",
             choices=("yes", "no"), priority=5, expires=60.0, fallback=None,
             data={"image": "seam.png"}),
    Answer("IVA", "interaction", question="q1", value="yes"),
    Progress("EVA1", "tasks", task="mount-P1", status="done"),
    FactChange("K-10", "CM", added=(("P1", "isOn", "frame"),), removed=(("P1", "isOn", "rack"),)),
    LogRecord("EVA1", "logs", time=12.5, event="task-done", task="mount-P1", data={"n": 1},
              agent="EVA1"),
    Clock("EVA1", "clock", state="idle", time=3.0, sent={"tasks": 2}, received={"EVA1": 1},
          next=4.5),
    State("tasks", "EVA1", id="s1", time=7.0,
          tasks={"mount-P1": {"state": "running", "agent": "EVA2", "done_by": []}},
          questions=("q3",), associated=("K-10",), controls=()),
]


def test_every_kind_travels_and_comes_back_equal() -> None:
    assert {type(m) for m in EXAMPLES} == set(KINDS.values())
    for message in EXAMPLES:
        expr = key("seam", message.to, message.kind)
        assert decode(encode(message), key_expr=expr) == message


def test_the_shipped_schema_is_the_wire_checks_schema() -> None:
    shipped = json.loads(SCHEMA.read_text())
    assert shipped == json_schema()
    validator = jsonschema.Draft202012Validator(shipped)
    for message in EXAMPLES:
        validator.validate(json.loads(encode(message)))


@pytest.mark.parametrize("path", HOSTILE, ids=lambda p: p.stem)
def test_a_hostile_message_is_refused(path: Path) -> None:
    payload = path.read_bytes()
    with pytest.raises(WireError):
        decode(payload)
    try:  # the JSON Schema that other peers use refuses it too
        data = json.loads(payload, parse_constant=_not_json)  # NaN: not JSON
    except ValueError:
        return
    assert not jsonschema.Draft202012Validator(json_schema()).is_valid(data)


def test_huge_deep_and_misaddressed_messages_are_refused() -> None:
    with pytest.raises(WireError, match="bytes"):
        decode(b'{"v":1,"kind":"act","sender":"A","to":"B","act":"' + b"x" * (2 << 20) + b'"}')
    with pytest.raises(WireError, match="not JSON"):
        decode(b'{"v":1,"kind":"act","sender":"A","to":"B","data":' + b"[" * 100_000
               + b"]" * 100_000 + b"}")
    with pytest.raises(WireError, match="published under"):
        decode(encode(Act("A", "B", act="PING")), key_expr="shary/t/C/act")
    with pytest.raises(WireError, match="key expression"):
        key("seam", "B/**", "act")


# -- faults at the port (in process, simulated clock) -------------------------------------


def _team(tmp_path: Path, faults: Faults, **question) -> tuple[Team, Path]:
    spec = load_team(TEAM)
    iva = spec.agents["IVA"]
    spec = replace(spec, agents={**spec.agents, "IVA": replace(iva, behaviour=replace(
        iva.behaviour, questions=Reply("answer", (3.0, 3.0))))})
    spec = replace(spec, questions={**spec.questions, "seam-okay": replace(
        spec.questions["seam-okay"], **question)})
    path = tmp_path / "run.sqlite"
    team = Team(spec, log=ContextLog(path),
                port=lambda loop, record: MessagePort(loop, record, faults=faults))
    for robot in spec.of_kind("robot"):
        executor = ScriptedExecutor(team.loop, {"drive": 2.0, "weld": 10.0, "scan": 3.0,
                                                "aim-light": 1.0})
        for name in ATOMIC:
            team.robot(robot.name).world.register(name, executor)
    return team, path


@pytest.mark.parametrize("faults", [Faults(loss=1.0, agents=frozenset({"IVA"})),
                                    Faults(latency=40.0, agents=frozenset({"IVA"}))],
                         ids=["dropped", "delayed"])
def test_a_bad_link_makes_the_question_expire_and_fall_back(tmp_path: Path,
                                                           faults: Faults) -> None:
    team, path = _team(tmp_path, faults, fallback="yes", expires=30.0)
    assert team.run(900) == "done"
    team.log.close()
    events = list(read_events(path))
    (answer,) = [e for e in events if e.kind == "answer"]
    assert answer.data["expired"] is True and answer.data["value"] == "yes"
    if faults.loss:
        assert any(e.kind == "message-dropped" and e.data["to"] == "IVA" for e in events)


def test_a_good_link_is_unchanged_by_the_fault_machinery(tmp_path: Path) -> None:
    team, path = _team(tmp_path, Faults(loss=1.0, agents=frozenset({"nobody"})),
                       fallback="yes", expires=30.0)
    assert team.run(900) == "done"
    team.log.close()
    (answer,) = [e for e in read_events(path) if e.kind == "answer"]
    assert answer.data["value"] == "yes" and not answer.data.get("expired")


def test_faults_are_checked() -> None:
    with pytest.raises(ValueError, match="loss"):
        Faults(loss=1.5)
    with pytest.raises(ValueError, match="latency"):
        Faults(latency=-1)


# -- the Zenoh port, two sessions in this process ------------------------------------------


def _wait(condition, seconds: float = 5.0, *ports) -> None:
    end = time.monotonic() + seconds
    while not condition():
        assert time.monotonic() < end, "timed out"
        for port in ports:
            port.pump(0.01)
            port.loop.run_until_idle()


def free_port() -> int:
    """A TCP port nobody listens on now (for one Zenoh listener)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_zenoh_delivers_refuses_and_notices_a_leaving_peer() -> None:
    from shary.transport.zenohport import ZenohPort, session_config

    endpoint = f"tcp/127.0.0.1:{free_port()}"
    rows: list[tuple[str, dict]] = []

    def record(kind: str, **data) -> None:
        rows.append((kind, data))

    a = ZenohPort(EventLoop(), record, team="t", name="A", local=["A"],
                  config=session_config(mode="router", listen=[endpoint]))
    try:
        b = ZenohPort(EventLoop(), None, team="t", name="B", local=["B"],
                      config=session_config(mode="client", connect=[endpoint]))
        got: list = []
        b.subscribe("B", got.append)
        _wait(lambda: ("agent-joined", {"agent": "B"}) in rows, 5.0, a)
        for path in HOSTILE:  # raw bytes straight onto A's key: refused, never delivered
            b.session.put(key("t", "A", "act"), path.read_bytes())
        handled: list = []
        a.subscribe("A", handled.append)
        b.send(Act("B", "A", act="PING"))
        b.flush()
        _wait(lambda: handled, 5.0, a)
        _wait(lambda: a.refused == len(HOSTILE), 5.0, a)
        assert handled == [Act("B", "A", act="PING")]
        refusals = [d for k, d in rows if k == "message-refused"]
        assert len(refusals) == len(HOSTILE) and all(d["reason"] for d in refusals)
        a.send(Act("A", "B", act="PONG"))
        a.flush()
        _wait(lambda: got, 5.0, b)
        assert got == [Act("A", "B", act="PONG")] and a.wire_sent == {"A>B": 1}
        b.close()
        _wait(lambda: ("agent-left", {"agent": "B"}) in rows, 1.0, a)
    finally:
        a.close()


# -- a member that rejoins learns the state (the managers' side and the member's) --------


def _asking(log) -> Team:
    """The seam team, its robots on scripted executors, run until K-10 asks its question
    (nobody answers: it stays open)."""
    spec = load_team(TEAM)
    for name in ("IVA", "EVA1", "EVA2"):
        person = spec.agents[name]
        spec = replace(spec, agents={**spec.agents, name: replace(person, behaviour=replace(
            person.behaviour, questions=Reply("ignore", (0.0, 0.0))))})
    team = Team(spec, log=log)
    for robot in spec.of_kind("robot"):
        executor = ScriptedExecutor(team.loop, {"drive": 2.0, "weld": 10.0, "scan": 3.0,
                                                "aim-light": 1.0})
        for name in ATOMIC:
            team.robot(robot.name).world.register(name, executor)
    team.start()
    while not team.interaction.open:
        team.loop.advance(1.0)
    return team


def test_a_rejoining_member_is_told_its_questions_control_and_the_task_table(
        tmp_path: Path) -> None:
    from shary.team.agents import USER
    from shary.transport.logshare import SharedLog, TeamRecords
    from shary.transport.rejoin import learn, state_for

    records = TeamRecords()
    team = _asking(SharedLog(ContextLog(tmp_path / "m.sqlite"), records.tap("m")))
    spec = team.spec
    (qid, entry), = team.interaction.open.items()
    holder = entry.holder
    team.take_control("EVA2", "Robonaut-B")
    team.loop.advance(5.0)
    messages = state_for(team, holder, records)
    state, again = messages
    assert isinstance(state, State) and state.to == holder and state.time == team.loop.now()
    assert state.questions == (qid,)
    assert state.tasks["weld-P1-P2"]["state"] == "done"
    assert state.tasks["inspect-P1-P2"] == {"state": "running", "agent": "K-10",
                                            "done_by": []}
    assert isinstance(again, Question) and again.id == qid and again.to == holder
    assert again.expires == entry.question.expires - 5.0
    (control,) = state_for(team, "EVA2", records)
    assert control.controls == ("Robonaut-B",) and control.questions == ()
    assert state_for(team, "Robonaut-B", records)[0].controls == ("EVA2",)
    # the member's side: a fresh team (its process started again) takes it in
    member = Team(spec, log=ContextLog(tmp_path / "eva2.sqlite"))
    learn(member, "EVA2", control)
    robot = member.robot("Robonaut-B")
    assert (robot.mode, robot.controller) == (USER, "EVA2")
    # the robot's side: restarted while EVA2 drove it, it is EVA2's again
    again = Team(spec, log=ContextLog(tmp_path / "robonaut.sqlite"))
    learn(again, "Robonaut-B", state_for(team, "Robonaut-B", records)[0])
    restarted = again.robot("Robonaut-B")
    assert (restarted.mode, restarted.controller) == (USER, "EVA2")
    assert restarted.hand_back("EVA2") and restarted.mode != USER
    again.log.close()
    assert member.tasks.tasks["weld-P1-P2"].state == "done"
    assert member.tasks.tasks["weld-P1-P2"].done_by == ["Robonaut-B"]
    member.log.close()
    (learned,) = [e for e in read_events(tmp_path / "eva2.sqlite")
                  if e.kind == "state-learned"]
    assert learned.agent == "EVA2" and learned.data["controls"] == ["Robonaut-B"]
    assert learned.data["tasks"]["inspect-P1-P2"]["agent"] == "K-10"


def test_a_member_says_nothing_until_it_is_admitted_to_the_clock(tmp_path: Path) -> None:
    """A restarted member's first log rows, counted by the managers before they knew of
    its new life, left the shared clock waiting forever for messages it already had (a
    CI run hung on it): a member holds what it sends until its first step, or its State."""
    from shary.transport.distributed import CLOCK, Conductor, Member

    spec = load_team(Path(__file__).parent / "data" / "transport" / "panels.team.yaml")
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    conductor = Conductor(spec, listen=endpoint, logdir=tmp_path, members=["EVA1"])
    try:
        member = Member(spec, "EVA1", connect=endpoint, logdir=tmp_path)
        try:
            assert conductor.wait_for_members(30) == []
            port = member.port  # it heard the managers join and logged it: held
            _wait(lambda: port.outbox, 5.0, port)
            assert port.held and port.wire_sent == {}
            conductor.port.publish(Clock(CLOCK, "EVA1", state="step", time=0.0))
            _wait(lambda: member.at == 0.0, 5.0, port)
            port.flush()
            assert not port.held and not port.outbox and port.wire_sent["EVA1>logs"] > 0
            sent = port.wire_sent["EVA1>logs"]
            _wait(lambda: conductor.port.wire_received.get("EVA1>logs") == sent, 5.0,
                  conductor.port)
        finally:
            member.close()
    finally:
        conductor.close()


def test_a_question_held_by_a_lost_person_goes_to_the_next_and_back_when_they_return(
        tmp_path: Path) -> None:
    team = _asking(ContextLog(tmp_path / "m.sqlite"))
    asked: list[Question] = []
    for name in ("IVA", "EVA1", "EVA2"):
        team.port.tap(name, lambda m: isinstance(m, Question) and not asked.append(m))
    (entry,) = team.interaction.open.values()
    first = entry.holder
    team.loop.advance(5.0)
    for _ in range(3):  # whoever holds it loses their process: the question follows
        lost = entry.holder
        assert lost is not None
        team.tasks.agent_lost(lost)
        team.interaction.agent_lost(lost)
        team.loop.advance(1.0)
    team.log.flush()
    rows = [e for e in read_events(tmp_path / "m.sqlite")]
    rerouted = [e.agent for e in rows if e.kind == "question-rerouted"]
    assert rerouted == [first, *(q.to for q in asked)] and len(set(rerouted)) == 3
    assert [q.expires for q in asked] == [entry.question.expires - 5.0,
                                          entry.question.expires - 6.0]  # the time left
    assert entry.holder is None and rows[-1].kind == "question-waiting"
    team.tasks.agent_back(first)  # the first comes back: it is asked again
    team.interaction.agent_back(first)
    team.loop.run_until_idle()
    assert entry.holder == first and asked[-1].to == first
    assert asked[-1].expires == entry.question.expires - 8.0


def test_the_merged_view_keeps_the_newest_rows_and_every_link() -> None:
    """The managers' view of every log is bounded (a team may run for hours), and what a
    restarted member is told of associations and control survives the rows let go."""
    from shary.transport.logshare import TeamRecords

    records = TeamRecords(keep=10)
    heard: list = []
    records.listeners.append(heard.append)
    tap = records.tap("K-10")
    tap(0.0, "associate", None, "K-10", {"requester": "EVA1"})
    tap(0.5, "control", None, "Robonaut-B", {"mode": "user", "by": "EVA2"})
    for i in range(1, 30):
        tap(float(i), "perceived", None, "world", {"i": i})
    tap(29.5, "release", None, "Robonaut-B", {})  # releases what it was never associated in
    assert 9 <= len(records.events) <= 10 and records.dropped + len(records.events) == 32
    assert records.events[-1].kind == "release" and records.events[-2].data["i"] == 29
    assert [e.time for e in records.events] == sorted(e.time for e in records.events)
    assert records.links() == ({"K-10": "EVA1"}, {"Robonaut-B": "EVA2"})
    assert len(heard) == 32 and records.by == {"K-10": 32}
