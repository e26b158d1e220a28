"""The console on an HRI/OS team, without a browser: the team's fold, the operator's team
actions and their checks, robot breakpoints, a team file run alone, ``shary serve``'s
refusals.  No physics: the robots' executors are tests/scripted.py's fakes (the browser
test runs the PyBullet site)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from hostile import run_inprocess
from scripted import ScriptedExecutor

from shary.console.replay import named_schemes
from shary.console.teamlive import TeamSteering, roster, run_team
from shary.console.view import View
from shary.log.contextlog import ContextLog, LogEvent, read_events
from shary.team import Team, load_team

DATA = Path(__file__).parent / "data"
ATOMIC = ("drive", "weld", "scan", "aim-light")


class Watching:
    """What the run's driver talks to (a :class:`shary.console.live.Attachment`'s
    interface): every event folded into a :class:`View`, the team handed to the steering."""

    def __init__(self) -> None:
        self.view = View(named_schemes())
        self.steering = TeamSteering()
        self.seq = 0
        self.changes: list[list[Any]] = []

    def attach(self, team: Team) -> None:
        self.steering.attach(team)

    def observe(self, t: float, kind: str, task: str | None, agent: str | None,
                data: dict[str, Any]) -> None:
        self.seq += 1
        self.changes += self.view.apply(LogEvent(self.seq, t, kind, task, agent, dict(data)))

    def between(self, now: float) -> None:
        pass


class Logged:
    """The team's log, each row also shown to the console (as the weld run's log is)."""

    def __init__(self, log: ContextLog, console: Watching):
        self.log, self.console, self.path = log, console, log.path

    def record(self, t: float, kind: str, *, task=None, agent=None, **data: Any) -> int:
        self.console.observe(t, kind, task, agent, data)
        return self.log.record(t, kind, task=task, agent=agent, **data)

    def flush(self) -> None:
        self.log.flush()


def seam_team(tmp_path: Path, edit=None) -> tuple[Team, Watching]:
    spec = load_team(DATA / "team" / "seam-team.yaml")
    if edit is not None:
        spec = edit(spec)
    console = Watching()
    team = Team(spec, log=Logged(ContextLog(tmp_path / "run.sqlite"), console))
    executor = ScriptedExecutor(team.loop, {"drive": 2.0, "weld": 10.0, "scan": 3.0,
                                            "aim-light": 1.0})
    for robot in spec.of_kind("robot"):
        for name in ATOMIC:
            team.robot(robot.name).world.register(name, executor)
    team.record("team", **roster(team))
    console.attach(team)
    return team, console


def check(console: Watching, **message: Any) -> str | None:
    return console.steering.check({"by": "op", **message}, console.view)


# -- the fold ----------------------------------------------------------------------------


def test_the_fold_has_every_member_the_task_table_and_the_delegations(tmp_path: Path):
    team, console = seam_team(tmp_path)
    assert team.run(600) == "done"
    view = console.view
    assert {n: c[2] for n, c in view.team.members.items()} == {
        "K-10": "robot", "Robonaut-B": "robot", "EVA1": "human", "EVA2": "human",
        "IVA": "human", "CM": "software"}
    assert view.team.members["K-10"][3]["atomic"] == {
        "aim-light": ["target"], "drive": ["to"], "scan": ["seam"], "weld": ["seam"]}
    assert set(view.team.tasks) == set(team.tasks.tasks)
    assert all(t["state"] == "done" for t in view.team.tasks.values())
    assert {t["agent"] for t in view.team.tasks.values()} >= {"K-10", "Robonaut-B"}
    assert not any(view.team.holds.values())  # nobody holds a task at the end
    chosen = [d for d in view.team.delegations if d[3] == "task"]
    assert chosen and all(len(d[6]) <= 3 and d[5] == d[6][0]["agent"] for d in chosen)
    # each robot has its own agenda on the page: goal ids are per robot
    assert {g[0].split(" #")[0] for g in view.goals.values()} == {"K-10", "Robonaut-B"}
    # a page that joins late gets the same team
    again = View(named_schemes())
    snapshot = view.snapshot()
    kinds = {c[0] for c in snapshot}
    assert {"member", "team-task", "delegation", "item"} <= kinds
    members = [c for c in snapshot if c[0] == "member"]
    assert [c[1] for c in members] == list(team.agents)
    assert again.snapshot()[-1:] != snapshot[-1:]
    # the log's replay shows the members in the team file's order too
    team.log.flush()
    for event in read_events(tmp_path / "run.sqlite"):
        again.apply(event)
    assert list(again.team.members) == list(team.agents)
    assert again.team.tasks == view.team.tasks


def test_questions_answers_control_and_associations_fold_into_changes():
    view = View(named_schemes())
    rows = [
        (0.0, "team", None, None, {"team": "t", "members": [
            {"name": "K-10", "kind": "robot", "skills": ["inspect-seam"],
             "atomic": {"aim": ["target"]}},
            {"name": "IVA", "kind": "human", "skills": [], "remote": True},
            {"name": "EVA1", "kind": "human", "skills": ["mount-panel"]}],
            "tasks": [{"name": "inspect", "skill": "inspect-seam", "after": []}]}),
        (1.0, "question", "inspect", "K-10", {"question": "q3", "text": "Is this seam okay?",
                                              "question_type": "yes-no", "priority": 5,
                                              "expires": 20.0,
                                              "data": {"image": "/x/run/k-10-01-q.png"}}),
        (1.0, "delegation", "q3", "IVA", {"need": "question", "ranking": [
            {"agent": "IVA", "score": 0.9, "by": {}}, {"agent": "EVA1", "score": 0.6, "by": {}},
            {"agent": "EVA2", "score": 0.5, "by": {}}, {"agent": "X", "score": 0.1, "by": {}}]}),
        (2.0, "control", None, "K-10", {"mode": "user", "by": "IVA"}),
        (3.0, "associate", None, "K-10", {"requester": "EVA1"}),
    ]
    changes = []
    for i, (t, kind, task, agent, data) in enumerate(rows, 1):
        changes += view.apply(LogEvent(i, t, kind, task, agent, data))
    question = view.team.questions["q3"]
    assert question["holder"] == "IVA" and question["expires"] == 21.0
    assert question["image"] == "k-10-01-q.png"  # a name in the run's folder, not a path
    assert len(view.team.delegations[-1][6]) == 3  # the top three
    assert ["control", "K-10", "user", "IVA"] in changes
    assert ["assoc", "K-10", "EVA1"] in changes
    assert any(c[0] == "item" and c[5] == "usermode" for c in changes)
    steering = TeamSteering()
    message = {"kind": "answer", "by": "op", "question": "q3", "agent": "IVA", "text": "yes"}
    assert steering.check(message, view) is None
    for wrong, why in ((dict(text="maybe"), "yes-no question, not 'maybe'"),
                       (dict(agent="EVA1"), "put to IVA, not EVA1"),
                       (dict(agent="K-10"), "K-10 is not a person"),
                       (dict(question="q9"), "q9 is not open")):
        assert why in steering.check({**message, **wrong}, view)
    view.apply(LogEvent(9, 4.0, "answer", "inspect", "IVA", {"question": "q3", "value": "no"}))
    assert "not open" in steering.check(message, view)
    # a multiple choice and a free text question, put to EVA1
    for i, (qid, kind, choices) in enumerate((("q5", "multiple-choice", ["P3", "P4"]),
                                              ("q6", "free-text", []))):
        view.apply(LogEvent(10 + i, 5.0, "question", "inspect", "K-10", {
            "question": qid, "text": "which?", "question_type": kind, "choices": choices,
            "to": "EVA1"}))
    answer = {"kind": "answer", "by": "op", "agent": "EVA1"}
    assert steering.check({**answer, "question": "q5", "text": "P4"}, view) is None
    assert "takes one of P3, P4, not 'P9'" in steering.check(
        {**answer, "question": "q5", "text": "P9"}, view)
    assert steering.check({**answer, "question": "q6", "text": "the left one"}, view) is None
    assert view.team.questions["q5"]["expires"] is None  # none said: no countdown
    assert [c[0] for c in view.snapshot() if c[0].startswith("tq")] == ["tq", "tq-end", "tq", "tq"]


# -- the operator's team actions ------------------------------------------------------------


def test_operator_team_actions_are_checked_against_the_view(tmp_path: Path):
    team, console = seam_team(tmp_path)
    team.start()
    team.loop.advance(1.0)
    assert "EVA1 is not a robot" in check(console, kind="take-control", agent="EVA1",
                                          person="IVA")
    assert "K-10 is not a person" in check(console, kind="take-control", agent="Robonaut-B",
                                           person="K-10")
    assert "say which person" in check(console, kind="take-control", agent="K-10")
    assert "not driven by IVA" in check(console, kind="hand-back", agent="K-10", person="IVA")
    assert check(console, kind="take-control", agent="K-10", person="IVA") is None
    console.steering.perform({"kind": "take-control", "agent": "K-10", "person": "IVA"}, "op")
    team.loop.advance(0.1)
    assert "already driven by IVA" in check(console, kind="take-control", agent="K-10",
                                            person="EVA1")
    teleop = dict(kind="teleoperate", agent="K-10", person="IVA")
    assert "no atomic task 'fly'" in check(console, **teleop, atomic="fly", args={})
    assert "drive takes to, not place" in check(console, **teleop, atomic="drive",
                                                args={"place": "x"})
    assert "not driven by EVA1" in check(console, **{**teleop, "person": "EVA1"},
                                         atomic="drive", args={"to": "P1"})
    assert check(console, **teleop, atomic="drive", args={"to": "P1"}) is None
    assert "answer questions" in check(console, kind="act", agent="IVA", act="H-AGREE")
    assert "cannot seek" in check(console, kind="seek", time=1.0)
    assert "is not offered or running" in check(console, kind="cancel-team-task",
                                                team_task="nothing")


def test_take_control_teleoperate_and_hand_back_go_through_the_team(tmp_path: Path):
    team, console = seam_team(tmp_path)
    team.start()
    steer = console.steering.perform
    steer({"kind": "take-control", "agent": "K-10", "person": "IVA"}, "op")
    team.loop.advance(0.1)
    steer({"kind": "teleoperate", "agent": "K-10", "person": "IVA", "atomic": "drive",
           "args": {"to": "P1"}}, "op")
    team.loop.advance(3.0)
    steer({"kind": "hand-back", "agent": "K-10", "person": "IVA"}, "op")
    team.loop.advance(0.1)
    events = list(read_events(tmp_path / "run.sqlite"))
    assert [(e.data["mode"], e.data["by"]) for e in events if e.kind == "control"] == [
        ("user", "IVA"), ("system", "IVA")]
    teleop = [e for e in events if e.kind == "exec-request" and e.data.get("by") == "IVA"]
    assert [e.data["args"] for e in teleop] == [{"to": "P1"}]
    assert console.view.team.control["K-10"] == ["system", "IVA"]


def test_a_breakpoint_stops_a_robot_between_atomic_tasks_until_cleared(tmp_path: Path):
    team, console = seam_team(tmp_path)
    team.start()
    team.loop.advance(0.5)  # Robonaut-B waits for the panels (27 s), drives, welds
    steer = console.steering.perform
    steer({"kind": "robot-breakpoint", "agent": "Robonaut-B"}, "op")
    team.loop.advance(30.0)
    requests = lambda: [e.data["atomic"] for e in read_events(tmp_path / "run.sqlite")  # noqa: E731
                        if e.kind == "exec-request" and e.agent == "Robonaut-B"]
    results = lambda: [e.data["status"] for e in read_events(tmp_path / "run.sqlite")  # noqa: E731
                       if e.kind == "exec-result" and e.agent == "Robonaut-B"]
    team.log.flush()
    assert requests() == ["drive"] and results() == []  # the drive is held
    assert console.view.team.breaks["Robonaut-B"] == ["stopped", "drive"]
    assert "has a breakpoint already" in check(console, kind="robot-breakpoint",
                                               agent="Robonaut-B")
    steer({"kind": "clear-robot-breakpoint", "agent": "Robonaut-B"}, "op")
    team.loop.advance(15.0)
    team.log.flush()
    assert requests() == ["drive", "weld"]  # the held drive started when cleared
    assert results() == ["done", "done"]
    assert console.view.team.breaks["Robonaut-B"] == ["cleared", None]


def test_a_cancelled_team_task_fails_for_the_task_manager(tmp_path: Path):
    team, console = seam_team(tmp_path)
    team.start()

    def cancel_one(kind: str) -> str:
        tasks, members = console.view.team.tasks, console.view.team.members
        running = [n for n, t in tasks.items() if t["state"] == "running"
                   and members[t["agent"]][2] == kind]
        assert running and check(console, kind="cancel-team-task", team_task=running[0]) is None
        console.steering.perform({"kind": "cancel-team-task", "team_task": running[0]}, "op")
        team.loop.advance(0.5)
        return running[0]

    team.loop.advance(1.5)  # the people mount the panels
    person = cancel_one("human")
    for _ in range(300):  # … then a robot welds
        team.loop.advance(1.0)
        if any(t["state"] == "running" and t["agent"] == "Robonaut-B"
               for t in console.view.team.tasks.values()):
            break
    robot = cancel_one("robot")
    team.log.flush()
    failed = {e.task: e.data["reason"] for e in read_events(tmp_path / "run.sqlite")
              if e.kind == "task-failed"}
    assert failed[person] == failed[robot] == "cancelled by the operator op"
    # the holders were told (a message, as in a distributed run) and stopped: the robot's
    # goal is cancelled on its agenda (then it is free for the retry), the person dropped
    # the assignment
    robonaut = team.robot("Robonaut-B")
    goals = [g for g in robonaut.sup.agenda.goals
             if any(s.startswith(f"team:{robot}#") for s in g.sources)]
    assert goals[0].sources == {f"team:{robot}#1"} and goals[0].state == "cancelled"
    assert all(g.state != "cancelled" for g in goals[1:])  # the retry, offered to it again
    assert all(person not in team.human(p).assignments for p in ("EVA1", "EVA2"))
    assert console.view.team.tasks[robot]["state"] in ("failed", "ready", "pending",
                                                      "offered", "running")


# -- a team file alone, and what ``shary serve`` refuses --------------------------------------


def test_a_team_of_people_runs_alone_under_the_console(tmp_path: Path):
    console = Watching()
    result = run_team(load_team(DATA / "transport" / "panels.team.yaml"), console,
                      out=tmp_path)
    assert result.outcome == "done" and result.summary()["passed"]
    assert {"log.sqlite", "timeline.svg", "summary.json"} <= {p.name for p in tmp_path.iterdir()}
    assert [t["state"] for t in console.view.team.tasks.values()] == ["done"] * 3
    assert set(console.view.team.members) == {"EVA1", "EVA2", "IVA"}


def test_serve_refuses_a_team_file_whose_robots_need_a_world():
    outcome = run_inprocess("serve", "--team", str(DATA / "team" / "seam-team.yaml"))
    assert outcome.status == 2 and "Traceback" not in outcome.err
    assert "K-10 is a robot" in outcome.err and "seam-welding scenario" in outcome.err
    both = run_inprocess("serve", "weld-nominal", "--team", str(DATA / "team" / "seam-team.yaml"))
    assert both.status == 2 and "one of them" in both.err
