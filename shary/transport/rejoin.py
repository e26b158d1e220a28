"""A member that (re)joins a running team learns the current state.

A process that died and is started again (``shary agent EVA1 …``) begins
with a fresh team: no task table, no questions, no associations, its clock at
zero.  When its liveliness token appears while the goal runs, the managers
send it one :class:`~shary.transport.messages.State` (:func:`state_for`): the
team's task table as the Task Manager holds it, the open questions it holds
(none after a loss: the Interaction Manager gave them to the next person, or
keeps them waiting and asks this one again once it is back), the robots it is
associated with or controls (as the robots logged them, from the managers'
merged view of the logs, :mod:`shary.transport.logshare`); then the open
questions again, with the time they have left.  A robot that a person
controlled is theirs again.  The State's time is the team's time: it is the
member's first step of the shared clock (it does not start its own script
again; a robot subscribes to the world's facts again, and gets them all at
once, :mod:`shary.transport.facts`).

The member (:func:`learn`) logs what it learned (``state-learned``) and sets
its shadows of the managers and of the robots to it (what its own requests
read).  The Task Manager then offers it work as to any free agent.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

from shary.transport.messages import Message, State

if TYPE_CHECKING:
    from shary.team.team import Team
    from shary.transport.logshare import TeamRecords


def state_for(team: Team, name: str, records: TeamRecords | None) -> list[Message]:
    """What the managers send ``name`` when it joins the running ``team``: its State, then
    the open questions it holds (their expiry is the time they have left)."""
    now = team.loop.now()
    tasks = {t.name: {"state": t.state, "agent": t.agent, "done_by": list(t.done_by)}
             for t in team.tasks.tasks.values()}
    held = [entry for entry in team.interaction.open.values() if entry.holder == name]
    associated, controlled = records.links() if records is not None else ({}, {})
    state = State(team.tasks.address, name, id=team.port.new_id("s"), time=now, tasks=tasks,
                  questions=tuple(e.question.id for e in held),
                  associated=tuple(sorted(_linked(associated, name))),
                  controls=tuple(sorted(_linked(controlled, name))))
    again: list[Message] = [state]
    for entry in held:
        again.append(replace(entry.question, sender=team.interaction.address, to=name,
                             expires=entry.left(now)))
    return again


def _linked(links: dict[str, str], name: str) -> set[str]:
    """The agents linked with ``name`` (robot -> person): its robots, or its person."""
    return {robot for robot, person in links.items() if person == name} | (
        {links[name]} if name in links else set())


def learn(team: Team, name: str, state: State) -> None:
    """The member ``name`` takes in what the managers sent (see the module's docstring)."""
    from shary.team.agents import USER
    from shary.team.robot import RobotAgent

    team.record("state-learned", agent=name, at=state.time, tasks=state.tasks,
                questions=list(state.questions) or None,
                associated=list(state.associated) or None,
                controls=list(state.controls) or None)
    shadow = team.tasks
    for task_name, row in state.tasks.items():
        task = shadow.tasks.get(task_name)
        if task is None or not isinstance(row, dict):
            continue
        task.state = str(row.get("state", task.state))
        agent = row.get("agent")
        task.agent = agent if isinstance(agent, str) else None
        task.done_by = [a for a in row.get("done_by", ()) if isinstance(a, str)]
    me = team.agents[name]
    me.current = next((t for t, row in state.tasks.items() if isinstance(row, dict)
                       and row.get("agent") == name and row.get("state") in ("offered",
                                                                               "running")),
                      None)
    for other in state.associated:
        robot = team.agents.get(other)
        if isinstance(robot, RobotAgent) and other != name:
            robot.associated = name
    for other in state.controls:
        robot = team.agents.get(other)
        if isinstance(robot, RobotAgent) and other != name:
            robot.mode, robot.controller = USER, name
    if isinstance(me, RobotAgent) and state.controls:
        # a robot restarted while a person drove it: it is still theirs (its own goals
        # wait) until they hand it back.  An association is not taken up again: the
        # help it served went to another robot when this one was lost.
        me.take_control(state.controls[0])

