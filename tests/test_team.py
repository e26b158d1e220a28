"""The team (HRI/OS) on the simulated clock: delegation, questions, respawn, breakpoints,
association, control authority, the context manager.  No physics: the robots' executors
are tests/scripted.py's fakes."""

from __future__ import annotations

from pathlib import Path

import pytest
from scripted import ScriptedExecutor

from shary.log.contextlog import ContextLog, read_events
from shary.team import Team, load_team
from shary.team.agents import SYSTEM, USER

DATA = Path(__file__).parent / "data" / "team"
ATOMIC = ("drive", "weld", "scan", "aim-light")


def build(tmp_path: Path, *, durations: dict[str, float] | None = None, seed: int = 0,
          edit=None):
    spec = load_team(DATA / "seam-team.yaml")
    if edit is not None:
        spec = edit(spec)
    log = ContextLog(tmp_path / "run.sqlite")
    team = Team(spec, log=log)
    team.loop.random.seed(seed)
    executors = {}
    for robot in spec.of_kind("robot"):
        executor = ScriptedExecutor(team.loop, dict(durations or {"drive": 2.0, "weld": 10.0,
                                                                  "scan": 3.0,
                                                                  "aim-light": 1.0}))
        for name in ATOMIC:
            team.robot(robot.name).world.register(name, executor)
        executors[robot.name] = executor
    return team, log, executors


def kinds(path: Path, kind: str) -> list:
    return [e for e in read_events(path) if e.kind == kind]


def test_the_goal_runs_in_the_constrained_order(tmp_path: Path) -> None:
    team, log, _ = build(tmp_path)
    assert team.run(600) == "done"
    log.close()
    done = {e.task: (e.time, e.agent) for e in kinds(tmp_path / "run.sqlite", "task-done")}
    assert set(done) == {"mount-P1", "mount-P2", "weld-P1-P2", "inspect-P1-P2"}
    assert done["weld-P1-P2"][0] > max(done["mount-P1"][0], done["mount-P2"][0])
    assert done["inspect-P1-P2"][0] > done["weld-P1-P2"][0]
    assert done["weld-P1-P2"][1] == "Robonaut-B" and done["inspect-P1-P2"][1] == "K-10"
    # the two panels were mounted in parallel, by the two astronauts
    assert {done["mount-P1"][1], done["mount-P2"][1]} == {"EVA1", "EVA2"}
    answers = kinds(tmp_path / "run.sqlite", "answer")
    assert [(a.agent, a.data["value"]) for a in answers] == [("IVA", "yes")]


def _answers_no(spec):
    from dataclasses import replace

    iva = spec.agents["IVA"]
    behaviour = replace(iva.behaviour, answers={"seam-okay": "no"})
    return replace(spec, agents={**spec.agents, "IVA": replace(iva, behaviour=behaviour)})


def test_a_failed_inspection_respawns_the_weld(tmp_path: Path) -> None:
    team, log, _ = build(tmp_path, edit=_answers_no)
    assert team.run(900) == "failed"
    log.close()
    path = tmp_path / "run.sqlite"
    welds = [e for e in kinds(path, "task-done") if e.task == "weld-P1-P2"]
    respawns = kinds(path, "respawn")
    assert len(respawns) == 2 and len(welds) == 3  # 3 inspection attempts, each after a weld
    assert respawns[0].task == "weld-P1-P2" and respawns[0].data["by"] == "inspect-P1-P2"
    assert "IVA answered 'no'" in respawns[0].data["reason"]
    assert kinds(path, "task-given-up")[0].task == "inspect-P1-P2"


def _times(path: Path, *names: str) -> dict[str, list]:
    wanted = set(names)
    out: dict[str, list] = {n: [] for n in names}
    for event in read_events(path):
        if event.kind in wanted:
            out[event.kind].append(event)
    return out


def test_a_robot_serves_a_person_at_a_breakpoint_then_resumes(tmp_path: Path) -> None:
    """Fig. 7: EVA1 asks for light while K-10 inspects; K-10 finishes its current atomic
    task, suspends the inspection, associates with EVA1, serves, is released, resumes."""
    team, log, executors = build(tmp_path)
    k10 = team.robot("K-10")
    asked: list[float] = []

    def ask_for_light() -> None:
        asked.append(team.loop.now())
        team.human("EVA1").request_help("point-light", {"target": "P3-bottom-right"},
                                        release_after=5.0)

    def when_scanning() -> None:
        if k10.current == "inspect-P1-P2" and executors["K-10"].names()[-1:] == ["scan"]:
            ask_for_light()
        else:
            team.loop.call_later(0.5, when_scanning)

    team.loop.call_later(1.0, when_scanning)
    assert team.run(900) == "done"
    log.close()
    path = tmp_path / "run.sqlite"
    rows = _times(path, "breakpoint", "associate", "release", "exec-request", "exec-result")
    (breakpoint,) = rows["breakpoint"]
    assert breakpoint.agent == "K-10" and breakpoint.data["before"] == "ask"
    scan_end = next(e.time for e in rows["exec-result"] if e.agent == "K-10"
                    and e.data["request"] == next(r.data["request"] for r in rows["exec-request"]
                                                  if r.data["atomic"] == "scan"))
    assert asked[0] < scan_end <= breakpoint.time  # the scan was not cut short
    (associate,) = rows["associate"]
    assert associate.data == {"requester": "EVA1", "suspended": "inspect-P1-P2"}
    light = next(r for r in rows["exec-request"] if r.data["atomic"] == "aim-light")
    assert light.agent == "K-10" and light.data["args"] == {"target": "P3-bottom-right"}
    (release,) = rows["release"]
    assert release.data["by"] == "EVA1" and release.time >= light.time + 5.0
    # the question of the inspection is asked only after the release
    question = kinds(path, "question")[0]
    assert question.agent == "K-10" and question.time >= release.time
    assert k10.associated is None and k10.mode == SYSTEM


def test_a_human_takes_control_of_a_robot_and_hands_back(tmp_path: Path) -> None:
    team, log, executors = build(tmp_path)
    k10 = team.robot("K-10")
    outcomes: list[str] = []

    def take() -> None:
        if k10.current != "inspect-P1-P2":
            team.loop.call_later(0.5, take)
            return
        team.take_control("IVA", "K-10")
        team.loop.call_later(0.1, drive)

    def drive() -> None:
        assert k10.mode == USER and k10.controller == "IVA"
        assert k10.teleoperate("EVA1", "drive", {"to": "P4"}) is None  # not in control
        k10.teleoperate("IVA", "drive", {"to": "P4"}, lambda o: outcomes.append(o.status))
        team.loop.call_later(5.0, team.hand_back, "IVA", "K-10")

    team.loop.call_later(1.0, take)
    assert team.run(900) == "done"
    log.close()
    path = tmp_path / "run.sqlite"
    control = kinds(path, "control")
    assert [(c.data["mode"], c.data["by"], c.task) for c in control] == [
        ("user", "IVA", "inspect-P1-P2"), ("system", "IVA", "inspect-P1-P2")]
    teleop = [e for e in kinds(path, "exec-request") if e.data.get("by") == "IVA"]
    assert [(e.agent, e.data["atomic"], e.data["args"]) for e in teleop] == [
        ("K-10", "drive", {"to": "P4"})]
    assert outcomes == ["done"]
    suspended = [e for e in kinds(path, "goal-suspended") if e.agent == "K-10"]
    assert suspended and suspended[0].data["reason"] == "held by control:IVA"
    assert kinds(path, "teleop-refused")[0].data["by"] == "EVA1"
    assert k10.mode == SYSTEM


def test_the_context_manager_says_what_an_agent_did(tmp_path: Path) -> None:
    from hostile import run_inprocess

    from shary.team.context import ContextManager

    team, log, _ = build(tmp_path)
    eva1 = team.human("EVA1")
    team.loop.call_later(40.0, lambda: eva1.request_help("point-light", {"target": "P3"},
                                                         release_after=2.0))
    assert team.run(900) == "done"
    # from Python, during the run's log (the team's Context Manager), and after it
    summary = team.context.summary(agent="K-10", last=600)
    assert [t["task"] for t in summary.tasks] == ["inspect-P1-P2"]
    assert summary.questions[0]["by"] == "IVA" and summary.questions[0]["answer"] == "yes"
    texts = [text for _, text in summary.moments]
    assert "K-10 served EVA1: point-light (target=P3)" in texts
    assert "EVA1 released K-10" in texts
    log.close()
    path = tmp_path / "run.sqlite"
    end = summary.until
    early = ContextManager(path).summary(agent="K-10", until=38.0)
    assert early.tasks == [] and early.actions == []
    assert {t["task"] for t in ContextManager(path).summary(agent="EVA1").tasks} <= {
        "mount-P1", "mount-P2"}
    outcome = run_inprocess("context", path, "--agent", "K-10", "--last", "10min")
    assert outcome.status == 0, outcome.err
    assert f"K-10, 0.0s – {end:.1f}s of the run" in outcome.out
    assert "question 'Is this seam okay?' from K-10 -> IVA: 'yes'" in outcome.out
    outcome = run_inprocess("context", path, "--task", "weld-P1-P2", "--json")
    import json

    document = json.loads(outcome.out)
    assert [t["agent"] for t in document["tasks"]] == ["Robonaut-B"]
    with pytest.raises(SystemExit) as exit_:
        run_inprocess("context", path, "--last", "ten minutes")
    assert exit_.value.code == 2


def _behave(spec, name: str, **changes):
    from dataclasses import replace

    agent = spec.agents[name]
    behaviour = replace(agent.behaviour, **changes)
    return replace(spec, agents={**spec.agents, name: replace(agent, behaviour=behaviour)})


def _question(spec, **changes):
    from dataclasses import replace

    question = replace(spec.questions["seam-okay"], **changes)
    return replace(spec, questions={**spec.questions, "seam-okay": question})


def test_an_unanswered_question_falls_back_and_a_late_answer_is_logged(tmp_path: Path) -> None:
    from shary.team.spec import Reply

    def slow_iva_with_fallback(spec):
        spec = _behave(spec, "IVA", questions=Reply("answer", (90.0, 90.0)))
        return _question(spec, fallback="yes", expires=30.0)

    team, log, _ = build(tmp_path, edit=slow_iva_with_fallback)
    assert team.run(900) == "done"
    log.close()
    path = tmp_path / "run.sqlite"
    (answer,) = kinds(path, "answer")
    assert answer.data["value"] == "yes" and answer.data["expired"] is True
    assert answer.agent is None and answer.data["after"] == 30.0
    late = kinds(path, "answer-late")
    assert late == []  # the question was withdrawn from IVA when it expired
    assert team.agents["IVA"].track_record("question") == (0, 1)


def test_an_expired_question_without_fallback_fails_the_step(tmp_path: Path) -> None:
    from shary.team.spec import Reply

    def silent_iva(spec):
        spec = _behave(spec, "IVA", questions=Reply("ignore"))
        return _question(spec, expires=20.0)

    team, log, _ = build(tmp_path, edit=silent_iva)
    assert team.run(900) == "failed"
    log.close()
    path = tmp_path / "run.sqlite"
    failed = kinds(path, "task-failed")
    assert failed and failed[0].task == "inspect-P1-P2"
    assert "nobody answered 'Is this seam okay?' within 20s" in failed[0].data["reason"]
    # every attempt respawned the weld first, then gave up
    assert len(kinds(path, "respawn")) == 2 and kinds(path, "task-given-up")


def test_a_person_who_declines_passes_the_question_on(tmp_path: Path) -> None:
    from shary.team.spec import Reply

    def iva_declines(spec):
        spec = _behave(spec, "IVA", questions=Reply("refuse", (1.0, 1.0)))
        spec = _behave(spec, "EVA1", questions=Reply("refuse", (1.0, 1.0)))
        return _behave(spec, "EVA2", questions=Reply("answer", (2.0, 2.0)),
                       answers={"seam-okay": "yes"})

    team, log, _ = build(tmp_path, edit=iva_declines)
    assert team.run(900) == "done"
    log.close()
    path = tmp_path / "run.sqlite"
    routed = [e.agent for e in kinds(path, "delegation") if e.data["need"] == "question"]
    assert routed == ["IVA", "EVA1", "EVA2"]
    (answer,) = kinds(path, "answer")
    assert answer.agent == "EVA2" and answer.data["after"] == 4.0


def test_refusing_and_silent_people_are_passed_over(tmp_path: Path) -> None:
    from shary.team.spec import Reply

    def eva1_refuses_eva2_ignores(spec):
        from dataclasses import replace

        spec = _behave(spec, "EVA1", assignments=Reply("refuse", (1.0, 1.0)))
        spec = _behave(spec, "EVA2", assignments=Reply("ignore"))
        eva3 = replace(spec.agents["EVA2"], name="EVA3",
                       behaviour=replace(spec.agents["EVA2"].behaviour,
                                         assignments=Reply("accept", (1.0, 1.0))))
        return replace(spec, agents={**spec.agents, "EVA3": eva3})

    team, log, _ = build(tmp_path, edit=eva1_refuses_eva2_ignores)
    assert team.run(2000) == "done"
    log.close()
    path = tmp_path / "run.sqlite"
    mounted = {e.task: e.agent for e in kinds(path, "task-done") if e.task.startswith("mount")}
    assert set(mounted.values()) == {"EVA3"}  # one task per agent: one after the other
    expired = kinds(path, "assignment-expired")
    assert expired and {e.agent for e in expired} == {"EVA2"}
    assert expired[0].data["after"] == 30.0
    refusals = [e for e in kinds(path, "message") if e.data.get("status") == "refused"]
    assert {e.agent for e in refusals} == {"EVA1"}
    # past answers: the refuser and the silent one now rank below EVA3
    assert team.agents["EVA1"].track_record("task")[0] == 0
    assert team.agents["EVA3"].track_record("task") == (2, 2)


def test_a_question_that_does_not_make_the_robot_wait(tmp_path: Path) -> None:
    team, log, _ = build(tmp_path, edit=lambda s: _question(s, wait=False, accept=()))
    assert team.run(900) == "done"
    team.loop.advance(30)  # the answer comes after the goal is over
    log.close()
    path = tmp_path / "run.sqlite"
    (question,) = kinds(path, "question")
    (answer,) = kinds(path, "answer")
    done = next(e for e in kinds(path, "task-done") if e.task == "inspect-P1-P2")
    assert done.time == question.time < answer.time  # it went on without the answer


def test_a_person_answers_the_most_urgent_question_first(tmp_path: Path) -> None:
    from shary.team.spec import QuestionSpec, Reply

    def only_iva_answers(spec):
        for name in ("EVA1", "EVA2"):
            spec = _behave(spec, name, questions=Reply("refuse", (1.0, 1.0)))
        return spec

    team, log, _ = build(tmp_path, edit=only_iva_answers)
    answers: list[str] = []
    low = QuestionSpec("chat", "Lunch?", "choice", ("now", "later"), priority=0, expires=600)
    high = QuestionSpec("alarm", "Abort the weld?", priority=50, expires=600)
    for spec in (low, low, high):
        team.interaction.ask("K-10", spec, on_answer=lambda a: answers.append(a.value))
    team.loop.advance(60)
    log.close()
    # the others decline, so IVA gets all three; the first one, already being answered,
    # stays first; then the urgent one jumps the queue
    assert answers == ["now", "yes", "now"]
    rows = kinds(tmp_path / "run.sqlite", "question")
    assert rows[0].data["choices"] == ["now", "later"] and rows[0].data["question_type"] == "choice"


def test_the_resource_manager_explains_and_takes_new_criteria(tmp_path: Path) -> None:
    from shary.team.resources import TASK, Need

    team, log, _ = build(tmp_path)

    class PreferEva2:
        name = "prefer-eva2"

        def score(self, agent, need, now):
            return 1.0 if agent.name == "EVA2" else 0.0

    need = Need(TASK, "mount-panel", at=(1.0, 1.0), subject="t")
    ranked = team.resources.rank(need, team.agents.values())
    assert [r.agent.name for r in ranked] == ["EVA1", "EVA2"]  # EVA1 stands at (1, 1)
    assert ranked[0].parts["distance"] == 1.0 and set(ranked[0].parts) == {
        "capability", "availability", "distance", "workload", "activity", "past-answers"}
    team.resources.add(PreferEva2(), weight=100.0)
    assert team.resources.choose(need, team.agents.values()).name == "EVA2"
    log.close()
    (row,) = kinds(tmp_path / "run.sqlite", "delegation")
    assert row.agent == "EVA2" and row.data["ranking"][0]["by"]["prefer-eva2"] == 1.0


def test_weights_from_ahp_comparisons(tmp_path: Path) -> None:
    text = (DATA / "seam-team.yaml").read_text("utf-8").replace(
        "goal:\n", "scoring:\n  compare:\n    availability: {distance: 3, workload: 3}\n"
        "    distance: {workload: 1}\ngoal:\n")
    (tmp_path / "seam-recipes.yaml").write_text((DATA / "seam-recipes.yaml").read_text())
    path = tmp_path / "team.yaml"
    path.write_text(text)
    weights = load_team(path).weights
    assert weights["availability"] == pytest.approx(0.6)
    assert weights["distance"] == pytest.approx(0.2) == pytest.approx(weights["workload"])


def test_a_software_agent_answers_queries_with_the_context(tmp_path: Path) -> None:
    from shary.transport.messages import Act

    team, log, _ = build(tmp_path)
    replies: list = []
    team.port.subscribe("console", replies.append)
    team.run(900)
    team.port.send(Act("console", "CM", id="x1", act="QUERY",
                       data={"service": "context", "agent": "Robonaut-B"}))
    team.port.send(Act("console", "CM", id="x2", act="QUERY", data={"service": "spatial"}))
    team.loop.run_until_idle()
    log.close()
    assert [r.act for r in replies] == ["INFORM", "INFORM"]
    assert [t["task"] for t in replies[0].data["tasks"]] == ["weld-P1-P2"]
    assert "offers no service 'spatial'" in replies[1].data["error"]


def test_messages_survive_a_round_trip_through_json() -> None:
    import json

    from shary.transport.messages import Answer, Assignment, Progress, Question, message_from_dict

    for message in (Question("K-10", "IVA", id="q1", text="ok?", choices=("a", "b"),
                             data={"image": "seam.png"}),
                    Answer("IVA", "K-10", question="q1", value="a"),
                    Assignment("tasks", "K-10", task="t", skill="s", args={"x": 1}),
                    Progress("K-10", "tasks", task="t", status="done")):
        assert message_from_dict(json.loads(json.dumps(message.as_dict()))) == message


def test_the_timeline_has_a_lane_per_agent_with_the_team(tmp_path: Path) -> None:
    import re

    from shary.log.timeline import render_timeline

    team, log, _ = build(tmp_path, edit=_answers_no)
    eva1 = team.human("EVA1")
    team.loop.call_later(42.0, lambda: eva1.request_help("point-light", {"target": "P3"},
                                                         release_after=3.0))
    team.run(900)
    log.close()
    svg = render_timeline(read_events(tmp_path / "run.sqlite"))
    lanes = re.findall(r'<g class="lane" data-agent="([^"]+)"', svg)
    assert lanes[0] == "Robonaut-B" and set(lanes) == {"Robonaut-B", "EVA1", "EVA2", "K-10",
                                                       "IVA"}  # no lane for the managers
    def items(cls: str) -> list[str]:
        return re.findall(rf'<g class="{cls}" data-agent="([^"]+)"', svg)

    assert items("team team-task").count("K-10") == 3  # three inspections, each failed
    assert items("act question").count("K-10") == 3 and items("act answer") == ["IVA"] * 3
    assert items("act question").count("EVA1") == 1  # the help request
    assert items("team associated") == ["K-10"]
    assert svg.count('<g class="respawn"') == 2 and "respawn weld-P1-P2" in svg
    assert "answers no" in svg and "team task failed" in svg


def test_questions_carry_what_the_team_attaches_and_people_ask_on_their_own(
        tmp_path: Path) -> None:
    from shary.team.spec import HelpRequest

    def eva1_asks_for_light(spec):
        return _behave(spec, "EVA1", requests=(
            HelpRequest(41.0, "point-light", {"target": "P3-corner"}, release=4.0),))

    team, log, _ = build(tmp_path, edit=eva1_asks_for_light)
    seen: list[tuple[str, str]] = []
    team.attach("seam-okay", lambda robot, request, then: then({
        "image": f"{robot.name}-{request.id.split('/')[-1]}.png"}))
    team.human("IVA").listeners.append(lambda m: seen.append((m.kind, getattr(m, "text", ""))))
    assert team.run(900) == "done"
    log.close()
    path = tmp_path / "run.sqlite"
    (question,) = kinds(path, "question")
    assert question.data["data"] == {"image": "K-10-r5.png"}
    assert ("question", "Is this seam okay?") in seen
    (request,) = kinds(path, "help-request")
    assert (request.agent, request.time, request.data["args"]) == (
        "EVA1", 41.0, {"target": "P3-corner"})
    (release,) = kinds(path, "release")
    serve = kinds(path, "serve")[0]
    assert release.data["by"] == "EVA1" and release.time == pytest.approx(serve.time + 1 + 4)


def test_a_world_performs_what_a_person_accepted(tmp_path: Path) -> None:
    team, log, _ = build(tmp_path)
    eva1 = team.human("EVA1")
    carried: list[str] = []

    def carry(assignment) -> None:  # the world moves the panel, then says it is done
        carried.append(assignment.args["panel"])
        team.loop.call_later(7.0, eva1.report, assignment.task, "done")

    eva1.performers["mount-panel"] = carry
    assert team.run(900) == "done"
    log.close()
    done = {e.task: e for e in kinds(tmp_path / "run.sqlite", "task-done")}
    assert carried == ["P1"] and done["mount-P1"].time == 1.0 + 7.0


def test_a_task_goes_to_an_agent_with_the_resources_it_needs(tmp_path: Path) -> None:
    from dataclasses import replace

    def k10_welds_without_a_tool(spec):
        k10 = replace(spec.agents["K-10"], skills=(*spec.agents["K-10"].skills, "weld-seam"))
        weld = replace(spec.tasks["weld-P1-P2"], needs=("welding-tool",))
        return replace(spec, agents={**spec.agents, "K-10": k10},
                       tasks={**spec.tasks, "weld-P1-P2": weld})

    team, log, _ = build(tmp_path, edit=k10_welds_without_a_tool)
    assert team.run(900) == "done"
    log.close()
    row = next(e for e in kinds(tmp_path / "run.sqlite", "delegation") if e.task == "weld-P1-P2")
    assert row.agent == "Robonaut-B" and row.data["candidates"] == 1


def test_the_same_help_asked_twice_is_served_once_and_both_hear(tmp_path: Path) -> None:
    team, log, _ = build(tmp_path)
    eva1 = team.human("EVA1")
    heard: list[tuple[str, str]] = []
    eva1.listeners.append(lambda m: heard.append((m.task, m.status))
                          if m.kind == "progress" else None)

    def twice() -> None:
        eva1.request_help("point-light", {"target": "P3"})
        eva1.request_help("point-light", {"target": "P3"})

    team.loop.call_later(10.0, twice)  # K-10 is idle: it associates at once
    team.loop.call_later(30.0, lambda: team.interaction.release("EVA1", "K-10"))
    assert team.run(900) == "done"
    log.close()
    served = [task for task, status in heard if status == "served"]
    assert len(served) == 2 and len(set(served)) == 2
    lights = [e for e in kinds(tmp_path / "run.sqlite", "exec-request")
              if e.data["atomic"] == "aim-light"]
    assert len(lights) == 1
    team.start()  # a started team does not start again


def test_a_task_that_never_ends_is_withdrawn_by_the_watchdog_and_the_goal_ends(
        tmp_path: Path) -> None:
    """Nothing progresses while the weld runs forever: the Task Manager's watchdog
    withdraws it (a row that says why), it is retried, and once its attempts are spent
    the goal fails instead of running until the caller's limit."""
    team, log, _ = build(tmp_path, durations={"drive": 2.0, "weld": 1e6, "scan": 3.0,
                                              "aim-light": 1.0})
    assert team.run(3000) == "failed"
    log.close()
    path = tmp_path / "run.sqlite"
    dogs = kinds(path, "watchdog")
    assert dogs and dogs[0].data["action"] == "withdraw"
    assert dogs[0].data["running"] == ["weld-P1-P2"]
    assert dogs[0].time >= team.tasks.watchdog
    (given_up,) = kinds(path, "task-given-up")
    assert given_up.task == "weld-P1-P2" and "said nothing" in given_up.data["reason"]


def test_the_team_file_sets_the_watchdog(tmp_path: Path) -> None:
    """``goal: watchdog: 2min``: the Task Manager looks after two minutes without
    progress, not after the default five (a key of the file, not a constructor's)."""
    file = DATA / "seam-team.yaml"
    text = file.read_text("utf-8").replace("goal:\n  tasks:", "goal:\n  watchdog: 2min\n  tasks:")
    assert "watchdog: 2min" in text
    spec = load_team(file, text=text)
    assert spec.watchdog == 120.0 and load_team(file).watchdog == 300.0
    team, log, _ = build(tmp_path, edit=lambda _: spec,
                         durations={"drive": 2.0, "weld": 1e6, "scan": 3.0, "aim-light": 1.0})
    assert team.run(3000) == "failed"
    log.close()
    dogs = kinds(tmp_path / "run.sqlite", "watchdog")
    assert [d.data["idle"] for d in dogs] == [120.0] * len(dogs) and dogs
    assert dogs[0].data["running"] == ["weld-P1-P2"]
    assert dogs[0].time < 300.0  # the default would not have looked yet
