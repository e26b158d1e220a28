"""The operator console without a browser: the view's fold, the operator's messages,
the endpoints' files, replay over a WebSocket, and the MCAP export read back.

A small log is written here with :class:`ContextLog` (the events a give-object
run logs, plus a snapshot), so most of these tests need no simulation; the
live run and the page itself are tested in a real browser
(test_console_browser.py), and what ``shary serve`` says on its terminal with
a live run of give-bottle here.
"""

from __future__ import annotations

import base64
import json
import os
import time
import urllib.error
import urllib.request
from pathlib import Path

import jsonschema
import pytest
from hostile import HOSTILE, assert_refused, run_inprocess
from PIL import Image
from websockets.sync.client import connect

from shary.cli import main
from shary.console.export import SCHEMAS
from shary.console.operator import Refused, parse
from shary.console.replay import Replay, named_schemes
from shary.console.server import serving
from shary.console.view import View
from shary.log.contextlog import ContextLog, read_events

MESSAGES = HOSTILE / "console"
LOGS = HOSTILE / "log"
SNAPSHOT = "snapshot-01-0000.0s-ask-task-give-object.png"


def write_run(folder: Path) -> Path:
    """A give-object run's log (asked, agreed, fetched, ended) and one snapshot."""
    Image.new("RGB", (8, 6), (200, 30, 30)).save(folder / SNAPSHOT)
    path = folder / "log.sqlite"
    with ContextLog(path, seed=0) as log:
        r = log.record
        r(0.0, "goal-added", goal=1, name="give-object", args={"object": "b", "partner": "alice"},
          priority=0, todo="default", source="request")
        r(0.0, "goal-started", goal=1, name="give-object")
        r(0.0, "node", task="n1", parent=None, node_kind="task", name="give-object",
          state="planned")
        r(0.0, "task-state", task="n1", name="give-object", state="ongoing")
        r(0.0, "task-start", task="n1", agent="jido", name="give-object", scheme="give-object",
          roles={"robot": "jido", "partner": "alice"})
        r(0.0, "enter", task="n1", state="ask")
        r(0.0, "act", task="n1", agent="jido", act="ASK-TASK", act_type="R-ACT")
        r(0.0, "snapshot", file=SNAPSHOT)
        r(0.0, "fact-added", perspective="robot", s="alice", p="looksAt", o="jido")
        r(0.5, "node", task="n2", parent="n1", node_kind="act", name="ASK-TASK",
          state="ongoing")
        r(0.5, "exec-request", task="n2", agent="jido", atomic="speak", request="r1",
          args={"text": "Bottle?"})
        r(2.0, "exec-result", task="n2", agent="jido", request="r1", status="done")
        r(3.0, "act-received", agent="alice", act="H-AGREE")
        r(3.0, "event", task="n1", event="H-AGREE")
        r(3.0, "exit", task="n1", state="ask")
        r(3.0, "node-removed", task="n2", nodes=["n2"])
        r(3.0, "enter", task="n1", state="realize")
        r(3.0, "act", task="n1", agent="jido", act="REALIZE-TASK", act_type="R-ACT")
        r(4.0, "fact-removed", perspective="robot", s="alice", p="looksAt", o="jido")
        r(9.0, "exit", task="n1", state="realize")
        r(9.0, "enter", task="n1", state="end")
        r(9.0, "act", task="n1", agent="jido", act="END-TASK", act_type="R-ACT")
        r(10.0, "exit", task="n1", state="end")
        r(10.0, "enter", task="n1", state="ended")
        r(10.0, "task-state", task="n1", name="give-object", state="done")
        r(10.0, "task-end", task="n1", name="give-object", outcome="done", state="ended")
        r(10.0, "goal-over", task="n1", goal=1, name="give-object", outcome="done")
        r(10.0, "run-end", scenario="test")
    return path


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("run")
    write_run(folder)
    return folder


def fold(path: Path, until: float = 1e9) -> tuple[View, list[list]]:
    view = View(named_schemes())
    changes = [c for e in read_events(path) if e.time <= until for c in view.apply(e)]
    return view, changes


# -- the view ---------------------------------------------------------------------------


def test_the_view_opens_a_question_while_the_robot_asks(run_dir: Path):
    view, changes = fold(run_dir / "log.sqlite", until=2.0)
    assert view.agents == {"jido": "robot", "alice": "human"}
    assert view.questions["n1"] == ["question", "n1", "ASK-TASK", ["alice"],
                                    ["H-AGREE", "H-DISAGREE"], SNAPSHOT]
    assert list(view.tasks["n1"]["config"]) == ["ask"]
    assert ["config", "n1", ["ask"]] in changes
    assert view.facts["robot"] == {("alice", "looksAt", "jido"): None}


def test_the_view_closes_the_question_cuts_the_tree_and_ends_the_task(run_dir: Path):
    view, changes = fold(run_dir / "log.sqlite")
    assert view.questions == {}
    assert ["question-end", "n1"] in changes
    assert ["cut", ["n2"]] in changes and "n2" not in view.nodes
    assert view.tasks["n1"]["outcome"] == "done"
    assert view.goals[1][4] == "done"
    assert view.facts["robot"] == {}
    acts = [line[4] for line in view.lines if line[3] == "act"]
    assert acts == ["[ASK-TASK] give-object", "[REALIZE-TASK] give-object",
                    "[END-TASK] give-object"]
    assert view.items["xr1"][4:] == ["done", 2.0]


def test_a_snapshot_rebuilds_the_same_view(run_dir: Path):
    view, _ = fold(run_dir / "log.sqlite", until=3.0)
    again = View(named_schemes())
    for change in view.snapshot():
        assert change[0] in {"time", "agent", "task", "config", "task-end", "node", "item",
                             "item-end", "goal", "fact", "line", "question"}
    # the page applies the snapshot as changes; the same events give the same snapshot
    for e in read_events(run_dir / "log.sqlite"):
        if e.time <= 3.0:
            again.apply(e)
    assert again.snapshot() == view.snapshot()


# -- operator messages ------------------------------------------------------------------


def test_a_good_message_is_read():
    assert parse('{"kind": "answer", "by": "ann", "task": "n1", "agent": "alice", '
                 '"act": "H-AGREE", "id": 3}')["act"] == "H-AGREE"


@pytest.mark.parametrize("path", sorted(MESSAGES.glob("*.json")), ids=lambda p: p.stem)
def test_hostile_messages_are_refused(path: Path):
    text = path.read_bytes().decode("utf-8", "replace")
    with pytest.raises(Refused) as refused:
        parse(text)
    assert refused.value.reason and len(refused.value.reason) <= 300


def test_a_huge_message_is_refused_unread():
    with pytest.raises(Refused, match="at most 4096 bytes"):
        parse('{"kind": "pause", "by": "' + "a" * 100_000 + '"}')


# -- the server: files and the WebSocket ----------------------------------------------


@pytest.fixture(scope="module")
def replay_server(run_dir: Path):
    outside = run_dir.parent / "secret.png"
    outside.write_bytes(b"not for the page")
    link = run_dir / "snapshot-99-link.png"
    if not link.exists():
        os.symlink(outside, link)
    with serving(Replay(run_dir / "log.sqlite", named_schemes())) as url:
        yield url


def get(url: str) -> tuple[int, bytes]:
    try:
        with urllib.request.urlopen(url, timeout=10) as response:
            return response.status, response.read()
    except urllib.error.HTTPError as err:
        return err.code, b""


def test_the_page_and_a_snapshot_are_served(replay_server: str, run_dir: Path):
    status, body = get(replay_server + "/")
    assert status == 200 and b"console.js" in body
    status, body = get(f"{replay_server}/run/{SNAPSHOT}")
    assert status == 200 and body == (run_dir / SNAPSHOT).read_bytes()


@pytest.mark.parametrize("path", [
    "/run/log.sqlite", "/run/..%2Fsecret.png", "/run/../secret.png", "/run/%2e%2e/secret.png",
    "/run/snapshot-99-link.png", "/run/%2Fetc%2Fpasswd", "/run/snapshot-x.png%00.txt",
    "/run/snapshot-" + "a" * 300 + ".png", "/static/../operator.schema.json",
    "/static/%2e%2e/operator.py", "/run/snapshot-..%2F..%2Fsecret.png",
])
def test_no_endpoint_reads_outside_the_run(replay_server: str, path: str):
    status, body = get(replay_server + path)
    assert status == 404 and b"not for the page" not in body


def messages(ws, until: str, limit: int = 50) -> list[dict]:
    got = []
    for _ in range(limit):
        got.append(json.loads(ws.recv(timeout=10)))
        if got[-1]["type"] == until:
            return got
    raise AssertionError(f"no {until!r} message in {got}")


def test_replay_seeks_and_refuses_steering(replay_server: str):
    with connect(replay_server.replace("http", "ws") + "/ws") as ws:
        first = messages(ws, "status")
        assert first[0] == {"type": "hello", "title": "run0 (replay)", "mode": "replay"}
        ws.send(json.dumps({"kind": "seek", "by": "ann", "time": 1.0, "id": 1}))
        got = messages(ws, "reply")
        view = next(m for m in got if m["type"] == "changes")
        assert view["reset"] and ["config", "n1", ["ask"]] in view["changes"]
        assert got[-1] == {"type": "reply", "id": 1, "ok": True, "error": None}
        ws.send(json.dumps({"kind": "pause", "by": "ann", "id": 2}))
        reply = messages(ws, "reply")[-1]
        assert not reply["ok"] and "cannot be steered" in reply["error"]
        for path in sorted(MESSAGES.glob("*.json"))[:5]:
            ws.send(path.read_bytes().decode("utf-8", "replace"))
            assert not messages(ws, "reply")[-1]["ok"]


# -- the MCAP export ------------------------------------------------------------------


def test_the_mcap_file_reads_back(run_dir: Path, tmp_path: Path):
    from mcap.reader import make_reader

    out = tmp_path / "run.mcap"
    assert run_inprocess("export", run_dir / "log.sqlite", "--mcap", out).status == 0
    with out.open("rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        topics = {c.topic: c for c in summary.channels.values()}
        assert set(topics) == set(SCHEMAS)
        got: dict[str, list] = {}
        for schema, channel, message in reader.iter_messages():
            assert schema.encoding == "jsonschema" and channel.message_encoding == "json"
            data = json.loads(message.data)
            jsonschema.validate(data, json.loads(schema.data))
            got.setdefault(channel.topic, []).append((message.log_time, data))
    assert [d["act"] for _, d in got["/acts"]] == ["ASK-TASK", "H-AGREE", "REALIZE-TASK",
                                                   "END-TASK"]
    assert [d["states"] for _, d in got["/configurations"]][:3] == [["ask"], [], ["realize"]]
    (t, image), = got["/snapshots"]
    assert t == 0 and image["format"] == "png"
    assert base64.b64decode(image["data"]) == (run_dir / SNAPSHOT).read_bytes()
    assert {d["change"] for _, d in got["/tree"]} == {"node", "state", "cut"}
    assert [d["change"] for _, d in got["/facts"]] == ["added", "removed"]
    assert len(got["/events"]) == len(read_events(run_dir / "log.sqlite"))
    assert any(d["message"] == "speak Bottle?" for _, d in got["/log"])
    assert got["/actions"][1][1]["status"] == "done" and got["/actions"][1][0] == 2_000_000_000


@pytest.mark.parametrize("log", sorted(LOGS.glob("*.sqlite")), ids=lambda p: p.stem)
def test_export_and_replay_refuse_a_hostile_log(log: Path, tmp_path: Path):
    out = tmp_path / "x.mcap"
    assert_refused(run_inprocess("export", log, "--mcap", out), log)
    assert not out.exists() and not list(tmp_path.iterdir())
    assert_refused(run_inprocess("serve", "--replay", log), log)


def test_serve_refuses_bad_arguments():
    for argv in (("serve",), ("serve", "give-bottle", "--replay", "x.sqlite"),
                 ("serve", "give-bottle", "--port", "70000"), ("serve", "no-such-scenario"),
                 ("serve", "give-bottle", "--speed", "-1")):  # (a team scenario is served now)
        outcome = run_inprocess(*argv)
        assert outcome.status == 2 and "Traceback" not in outcome.err, argv


# -- a live run steered over the WebSocket (the page's own tests: test_console_browser.py) --


def test_a_live_run_logs_refusals_and_cancels_a_task(tmp_path: Path):
    from sim.cli import live_run
    from sim.scenario import find_scenario

    live = live_run(find_scenario("give-bottle"), out=tmp_path, speed=0, paused=True)
    with serving(live) as url, connect(url.replace("http", "ws") + "/ws") as ws:
        got = messages(ws, "status", limit=500)
        while not any(c[0] == "question" for m in got if m["type"] == "changes"
                      for c in m["changes"]):
            got.append(json.loads(ws.recv(timeout=30)))
        asking = next(c[1] for m in got if m["type"] == "changes" for c in m["changes"]
                      if c[0] == "question")
        hostile = sorted(MESSAGES.glob("*.json"))
        for path in hostile:
            ws.send(path.read_bytes().decode("utf-8", "replace"))
        refusals = {
            "answer": {"task": asking, "agent": "alice", "act": "H-MAYBE"},
            "take-control": {"agent": "jido"},
            "seek": {"time": 2.0},
            "cancel": {"task": "n77"},
        }
        for kind, fields in refusals.items():
            ws.send(json.dumps({"kind": kind, "by": "ann", **fields}))
        ws.send(json.dumps({"kind": "step", "by": "ann"}))
        ws.send(json.dumps({"kind": "speed", "by": "ann", "value": 0}))
        ws.send(json.dumps({"kind": "cancel", "by": "ann", "task": asking, "id": 7}))
        ws.send(json.dumps({"kind": "resume", "by": "ann"}))
        replies = []
        while len(replies) < len(hostile) + len(refusals) + 4:
            message = json.loads(ws.recv(timeout=30))
            if message["type"] == "reply":
                replies.append(message)
        assert [r["ok"] for r in replies] == [False] * (len(hostile) + len(refusals)) + [True] * 4
        assert "waits for H-AGREE or H-DISAGREE, not H-MAYBE" in replies[len(hostile)]["error"]
        assert "control-authority" in replies[len(hostile) + 1]["error"]
        while live.state != "ended":
            ws.recv(timeout=30)
    events = read_events(tmp_path / "log.sqlite")
    refused = [e for e in events if e.kind == "operator-refused"]
    assert len(refused) == len(hostile) + len(refusals)
    assert {e.agent for e in refused} == {"unknown", "ann"}
    done = [(e.agent, e.data["action"]) for e in events if e.kind == "operator"]
    assert done == [("ann", "step"), ("ann", "speed"), ("ann", "cancel"), ("ann", "resume")]
    ends = {e.task: e.data["outcome"] for e in events if e.kind == "task-end"}
    assert ends[asking] == "cancelled"
    assert live.verdict is not None and live.verdict["passed"] is False


def test_pages_of_other_sites_and_other_host_names_are_refused(replay_server: str):
    from websockets.exceptions import InvalidStatus

    with pytest.raises(InvalidStatus, match="403"):
        connect(replay_server.replace("http", "ws") + "/ws", origin="http://evil.example")
    request = urllib.request.Request(replay_server + "/", headers={"Host": "evil.example"})
    with pytest.raises(urllib.error.HTTPError) as refused:
        urllib.request.urlopen(request, timeout=10)
    assert refused.value.code == 400
    with pytest.raises(InvalidStatus, match="400"):
        connect(replay_server.replace("http", "ws") + "/ws",
                additional_headers={"Host": "evil.example"})


# -- shary serve on its terminal ------------------------------------------------------


def _serve_until(monkeypatch, ended: bool) -> None:
    """Stand in for the blocking server of ``shary serve``: serve the run on a free port,
    connect a page (which starts the run), then stop the server once the run has ended
    (``ended``) or as soon as it runs, as Ctrl-C does."""
    def serve(live, host: str, port: int) -> int:
        with serving(live) as url, connect(url.replace("http", "ws") + "/ws") as ws:
            deadline = time.monotonic() + 120
            while live.state != ("ended" if ended else "running"):
                assert time.monotonic() < deadline, live.state
                ws.recv(timeout=30)
        return 0

    monkeypatch.setattr("shary.console.server.serve", serve)


def test_serve_says_the_verdict_and_the_files_when_the_run_ends(tmp_path, monkeypatch,
                                                                 capsys):
    """Before: nothing on the terminal after the address, whatever the run did."""
    _serve_until(monkeypatch, ended=True)
    assert main(["serve", "give-bottle", "--speed", "0", "--out", str(tmp_path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("PASSED give-bottle: ") and lines[0].endswith(" s simulated")
    assert lines[1:] == [f"wrote {tmp_path}/: log.sqlite, tree.svg, timeline.svg, summary.json"]


def test_serve_stopped_before_the_run_ends_says_so(tmp_path, monkeypatch, capsys):
    _serve_until(monkeypatch, ended=False)
    assert main(["serve", "give-bottle", "--paused", "--out", str(tmp_path)]) == 0
    assert capsys.readouterr().out.splitlines() == [
        f"the run was stopped before its end: {tmp_path}/ holds its log so far"]
    assert (tmp_path / "log.sqlite").is_file()
