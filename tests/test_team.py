"""The team (HRI/OS) on the simulated clock: delegation, questions, respawn, breakpoints,
association, control authority, the context manager.  No physics: the robots' executors
are tests/scripted.py's fakes."""

from __future__ import annotations

from pathlib import Path

import pytest
from scripted import ScriptedExecutor

from shary.log import ContextLog, read_events
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
