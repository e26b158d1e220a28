"""A JAHRVIS shared plan in the operator console, without a browser: the fold
(shary/console/planview.py), replay, the operator's plan messages, the MCAP channels.

A small log is written here with :class:`ContextLog`: the rows a stack run logs for
a plan of six tasks with one human decision, where Alice misses the robot's pick
(NOT_SEEN in her view) and is told; so no simulation is needed.  The live page is
tested in a real browser (test_console_plan_browser.py).
"""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import pytest
from hostile import run_inprocess
from PIL import Image
from test_console import fold

from shary.console.live import LiveRun, _check_report
from shary.console.planview import plan_rows
from shary.console.replay import Replay, named_schemes
from shary.console.view import View
from shary.log.contextlog import ContextLog, LogEvent
from shary.recognition.models import builtin_models, load_action_models
from shary.recognition.recognizer import Recognizer

SNAPSHOT = "snapshot-01-0000.0s-plan.png"
TASKS = [  # (id, label, agent, kind, after, decision)
    ("P-1-1", "Pick(pr2, green_cube)", "pr2", "action", [], None),
    ("P-1-2", "Pick(alice, red_cube)", "alice", "action", ["P-1-1"], None),
    ("P-1-3", "Place(alice, red_cube, base)", "alice", "action", ["P-1-2"], "d1"),
    ("P-1-4", "WaitForCube(alice)", "alice", "action", ["P-1-2"], "d1"),
    ("P-1-5", "Place(pr2, green_cube, red_cube)", "pr2", "action", ["P-1-3"], None),
    ("P-1-6", "Place(pr2, red_cube, base)", "pr2", "action", ["P-1-4"], None),
    ("P-1-7", "DONE()", "pr2", "done", ["P-1-5"], None),
]


def write_plan_run(folder: Path) -> Path:
    """A stack run's plan rows: Alice looks away while the PR2 picks the green cube."""
    Image.new("RGB", (8, 6), (30, 30, 200)).save(folder / SNAPSHOT)
    path = folder / "log.sqlite"
    with ContextLog(path, seed=0) as log:
        r = log.record

        def state(t: float, task: str, pr2: str | None, alice: str | None, **why: str) -> None:
            name = next(label for i, label, *_ in TASKS if i == task)
            if pr2:
                r(t, "plan-task", task=task, agent="pr2", state=pr2, name=name, **why)
            if alice:
                r(t, "plan-task", task=task, agent="alice", state=alice, name=name,
                  estimate=True, **why)

        r(0.0, "node", task="n3", parent=None, node_kind="task", name="StackBuildingTask: s",
          state="planned")
        r(0.0, "plan-loaded", task="n3", agent="pr2", problem="stack", prefix="P-1",
          views=["pr2", "alice"], decisions=[
              {"id": "d1", "agent": "alice", "after": "P-1-2", "options": ["P-1-3", "P-1-4"]}],
          tasks=[{"id": i, "label": label, "agent": agent, "kind": kind, "after": after,
                  "decision": decision, "name": label.split("(")[0],
                  "objects": label.rstrip(")").split("(")[1].split(", ")[1:]}
                 for i, label, agent, kind, after, decision in TASKS])
        r(0.0, "shared-plan", task="n3", agent="pr2", state="started", problem="stack")
        r(0.0, "snapshot", file=SNAPSHOT)
        state(0.0, "P-1-1", "TODO", "TODO", event="ready")
        state(0.0, "P-1-1", "ONGOING", "ONGOING", event="start")
        r(0.0, "exec-request", task="n5", agent="pr2", atomic="look-at", request="p1",
          args={"target": "green_cube"})
        r(0.5, "exec-result", task="n5", agent="pr2", request="p1", status="done")
        r(1.0, "recognition", agent="alice", candidate="c1", state="started", action="pick",
          action_class="HumanPickAction", params={"Pickable": "red_cube"}, cause="move",
          fact="handMovingToward(alice, red_cube)")
        state(1.5, "P-1-1", "EXECUTED", None, event="achieved")
        state(1.5, "P-1-1", None, "NOT_SEEN", event="achieved-unseen")
        state(1.5, "P-1-2", "TODO", "TODO", event="ready")
        r(2.0, "recognition", agent="alice", candidate="c1", state="achieved", action="pick",
          action_class="HumanPickAction", params={"Pickable": "red_cube"}, cause="necessary",
          fact="isHolding(alice, red_cube)")
        state(2.0, "P-1-2", "EXECUTED", "EXECUTED", event="achieved")
        state(2.0, "P-1-3", "TODO", "TODO", event="ready")
        state(2.0, "P-1-4", "TODO", "TODO", event="ready")
        r(2.5, "plan-decision", task="P-1-3", agent="alice", decision="d1",
          chosen="Place(alice, red_cube, base)")
        state(2.5, "P-1-4", "UNPLANNED", "UNPLANNED", event="drop", reason="d1: another branch")
        state(2.5, "P-1-6", "UNPLANNED", "UNPLANNED", event="drop", reason="d1: another branch")
        r(3.0, "speech", agent="pr2", text="I picked the green cube.")
        state(3.0, "P-1-1", None, "EXECUTED", event="seen", reason="informed")
        state(4.0, "P-1-3", "EXECUTED", "EXECUTED", event="achieved")
        r(5.0, "shared-plan", task="n3", agent="pr2", state="achieved")
        r(5.0, "run-end", scenario="plan")
    return path


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("plan-run")
    write_plan_run(folder)
    return folder


# -- the fold ---------------------------------------------------------------------------

def test_the_plan_is_shown_whole_with_its_branches(run_dir: Path):
    view, changes = fold(run_dir / "log.sqlite", until=0.0)
    (plan,) = [c for c in changes if c[0] == "plan"]
    assert plan[1:6] == ["P-1", "n3", "shared-plan-task", "stack", ["pr2", "alice"]]
    rows = {row[0]: row for row in plan[6]}
    assert [row[0] for row in plan[6]] == ["P-1-1", "P-1-2", "P-1-3", "P-1-5", "P-1-7",
                                           "P-1-4", "P-1-6"]
    # an option heads its branch and is shown with the trunk; its tasks with the branch
    assert rows["P-1-3"][4:] == ["", "P-1-3", 1, "d1: alice decides"]
    assert rows["P-1-5"][4:7] == ["P-1-3", "", 1]
    assert rows["P-1-6"][4] == "P-1-4" and rows["P-1-7"][3] == "done"
    assert view.agents == {"pr2": "robot", "alice": "human"}


def test_each_view_side_by_side_not_seen_then_told(run_dir: Path):
    view, _ = fold(run_dir / "log.sqlite", until=2.0)
    states = view.plans.states
    assert states[("P-1-1", "pr2")] == "EXECUTED"
    assert states[("P-1-1", "alice")] == "NOT_SEEN"
    item = view.items["ns:P-1-1:alice"]
    assert item[1:5] == ["alice", 1.5, "NOT_SEEN Pick(pr2, green_cube)", "not-seen"]
    assert item[5] is None  # still open: she has not been told
    view, changes = fold(run_dir / "log.sqlite")
    assert view.plans.states[("P-1-1", "alice")] == "EXECUTED"
    assert view.items["ns:P-1-1:alice"][5] == 3.0
    lines = [c[4] for c in changes if c[0] == "line"]
    assert "alice did not see Pick(pr2, green_cube) (the robot's estimate)" in lines
    assert "alice now knows Pick(pr2, green_cube) is EXECUTED (informed)" in lines
    assert "d1: alice chose Place(alice, red_cube, base)" in lines
    assert ["plan-chose", "P-1", "d1", "P-1-3"] in changes
    assert changes[-3:-1] == [["plan-status", "P-1", "achieved", ""],
                              ["line", 5.0, "pr2", "plan", "shared plan: achieved"]]


def test_recognized_actions_head_and_speech(run_dir: Path):
    view, changes = fold(run_dir / "log.sqlite")
    (item,) = [i for i in view.items.values() if i[0].startswith("rc:c1")]
    assert item[1:] == ["alice", 1.0, "pick red_cube", "recognized-achieved", 2.0]
    assert [c[6] for c in changes if c[0] == "recognized"] == ["started", "achieved"]
    assert ["line", 2.0, "alice", "recognized", "recognized: alice pick red_cube"] in changes
    assert ["head", "pr2", "green_cube"] in changes
    assert ["says", "pr2", "I picked the green cube."] in changes


def test_a_snapshot_rebuilds_the_same_plan(run_dir: Path):
    view, _ = fold(run_dir / "log.sqlite")
    snapshot = view.snapshot()
    kinds = [c[0] for c in snapshot]
    assert kinds.index("plan") < kinds.index("plan-state") < kinds.index("plan-chose")
    assert ["plan-state", "P-1-1", "alice", "EXECUTED"] in snapshot
    again, _ = fold(run_dir / "log.sqlite")
    assert again.snapshot() == snapshot


def test_replay_shows_the_plan_as_it_stood(run_dir: Path):
    replay = Replay(run_dir / "log.sqlite", named_schemes())
    while_away = replay.changes_at(2.2)
    assert ["plan-state", "P-1-1", "alice", "NOT_SEEN"] in while_away
    assert ["plan-state", "P-1-1", "pr2", "EXECUTED"] in while_away
    assert ["plan-state", "P-1-1", "alice", "EXECUTED"] in replay.changes_at(replay.end)


def test_a_broken_plan_row_is_shown_as_far_as_it_goes():
    # cycles, unknown predecessors, junk entries and a very deep plan: every task once
    rows = plan_rows([{"id": "a", "after": ["b"]}, {"id": "b", "after": ["a"]},
                      {"id": "c", "after": ["zz"], "label": 3}])
    assert sorted(r[0] for r in rows) == ["a", "b", "c"]
    deep = [{"id": "t0", "after": []}]
    for i in range(1, 20_000):  # each task forks into two: 10,000 levels of decisions
        deep += [{"id": f"t{i}", "after": [f"t{i - 1 - (i - 1) % 2}"]}]
    assert len(plan_rows(deep)) == 20_000
    view = View(named_schemes())
    for data in ({"tasks": "x", "views": 3, "decisions": None}, {"tasks": [1, None, {}]},
                 {"prefix": ["x"], "tasks": [{"id": "x-1", "after": "x-0"}]}):
        view.apply(LogEvent(1, 0.0, "plan-loaded", "n1", "pr2", data))
    view.apply(LogEvent(2, 0.0, "plan-task", "x-1", None, {"state": "TODO"}))
    view.apply(LogEvent(3, 0.0, "recognition", None, None, {"params": "x"}))
    assert view.snapshot()


# -- operator messages about a plan ----------------------------------------------------------

def test_a_report_of_a_human_action_is_checked_against_the_plan(run_dir: Path):
    view, _ = fold(run_dir / "log.sqlite", until=1.5)

    def check(task: str, agent: str = "alice") -> str | None:
        return _check_report({"kind": "human-action", "by": "o", "agent": agent,
                              "plan_task": task}, view)

    assert check("P-1-2") is None  # hers, due now
    assert check("P-1-2", "bob") == "P-1-2 is alice's to do, not bob's"
    assert check("P-1-9") == "P-1-9 is not a task of a shared plan of this run"
    assert check("P-1-3") == "Place(alice, red_cube, base) is PLANNED, not due: nothing to report"
    assert view.plans.actions["P-1-3"] == ("Place", ["red_cube", "base"])


def test_a_breakpoint_on_a_task_state_pauses_the_run():
    live = LiveRun("t", lambda attachment: None, None, schemes=lambda name: None)
    live._control("breakpoint", {"kind": "breakpoint", "state": "NOT_SEEN", "agent": "alice"})
    assert live.status()["plan_breakpoints"] == [["NOT_SEEN", "alice"]]
    observe = live.attachment.observe
    observe(1.0, "plan-task", "P-1-1", "pr2", {"state": "NOT_SEEN", "name": "Pick(pr2, g)"})
    assert not live.paused  # another view
    observe(1.5, "plan-task", "P-1-1", "alice", {"state": "EXECUTED", "name": "Pick(pr2, g)"})
    assert not live.paused  # another state
    observe(2.0, "plan-task", "P-1-1", "alice", {"state": "NOT_SEEN", "name": "Pick(pr2, g)"})
    assert live.paused
    assert live.stopped_at == "breakpoint NOT_SEEN: Pick(pr2, g) in alice's view at 2.0 s"
    live._control("clear-breakpoint", {"kind": "clear-breakpoint", "state": "NOT_SEEN",
                                       "agent": "alice"})
    assert live.status()["plan_breakpoints"] == []


def test_the_recognizer_takes_a_reported_action_like_a_recognized_one():
    facts_rows: list[dict] = []
    from shary.facts.database import FactDatabase

    facts = FactDatabase()
    models = load_action_models([builtin_models("stack")], facts)
    recognizer = Recognizer(models, facts, clock=lambda: 7.0,
                            record=lambda kind, **row: facts_rows.append(row))
    heard = []
    recognizer.listeners.append(heard.append)
    got = recognizer.report("alice", "Place", ["cube-1", "base-1"], "operator")
    assert (got.state, got.action, got.agent, got.params, got.cause) == (
        "achieved", "place", "alice", {"Pickable": "cube-1", "Support": "base-1"},
        "reported by operator")
    assert heard == [got] and facts_rows[-1]["cause"] == "reported by operator"
    with pytest.raises(ValueError, match="no human action model is 'Juggle'"):
        recognizer.report("alice", "Juggle", [], "operator")


# -- the MCAP channels -----------------------------------------------------------------------

def test_the_plan_channels_in_the_mcap_file(run_dir: Path, tmp_path: Path):
    from mcap.reader import make_reader

    out = tmp_path / "plan.mcap"
    assert run_inprocess("export", run_dir / "log.sqlite", "--mcap", out).status == 0
    got: dict[str, list] = {}
    with out.open("rb") as stream:
        for schema, channel, message in make_reader(stream).iter_messages():
            data = json.loads(message.data)
            jsonschema.validate(data, json.loads(schema.data))
            got.setdefault(channel.topic, []).append(data)
    alice = [(d["task"], d["state"]) for d in got["/plan-tasks"] if d["view"] == "alice"]
    assert ("P-1-1", "NOT_SEEN") in alice
    assert alice.index(("P-1-1", "NOT_SEEN")) < alice.index(("P-1-1", "EXECUTED"))
    assert all(d["estimate"] == (d["view"] == "alice") for d in got["/plan-tasks"])
    assert [(d["state"], d["agent"], d["parameters"]) for d in got["/recognitions"]] == [
        ("started", "alice", {"Pickable": "red_cube"}),
        ("achieved", "alice", {"Pickable": "red_cube"})]


def test_a_replan_puts_the_new_plan_beside_the_old(run_dir: Path):
    view, _ = fold(run_dir / "log.sqlite", until=2.0)
    out = view.apply(LogEvent(999, 2.1, "shared-plan", "n3", "pr2",
                              {"state": "replan", "reason": "Place failed"}))
    out += view.apply(LogEvent(1000, 2.1, "plan-loaded", "n3", "pr2", {
        "prefix": "P-2", "problem": "stack", "views": ["pr2", "alice"],
        "tasks": [{"id": "P-2-1", "label": "Place(pr2, red_cube, base)", "agent": "pr2",
                   "after": []}]}))
    assert ["plan-status", "P-1", "replan", "Place failed"] in out
    assert ["plan-status", "P-1", "replaced", "by P-2"] in out
    assert [c[1] for c in view.snapshot() if c[0] == "plan"] == ["P-1", "P-2"]
    view.apply(LogEvent(1001, 3.0, "shared-plan", "n3", "pr2", {"state": "achieved"}))
    assert view.plans.status["P-2"][2] == "achieved"
    assert view.plans.status["P-1"][2] == "replaced"
