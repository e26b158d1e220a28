"""The team (HRI/OS) on the simulated clock: delegation, questions, respawn, breakpoints,
association, control authority, the context manager.  No physics: the robots' executors
are tests/scripted.py's fakes."""

from __future__ import annotations

from pathlib import Path

from scripted import ScriptedExecutor

from shary.log import ContextLog, read_events
from shary.team import Team, load_team

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
