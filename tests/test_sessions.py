"""Interaction sessions on a scripted world: the will to interact (a partially ordered
conjunction), greeting, busy and idle, farewell, and the agenda's session gate."""

from __future__ import annotations

import pytest
from scripted import World

from shary.dialogue.sessions import Sessions
from shary.io.schemes import load_scheme
from shary.statechart.compiler import compile_scheme


def said(world: World) -> list[str]:
    return [args["text"] for _, atomic, args in world.executor.started if atomic == "speak"]


@pytest.fixture
def world() -> World:
    w = World()
    w.facts.remove("alice", "looksAt", "jido")  # Alice is across the room, busy elsewhere
    for person in ("alice", "bob"):
        w.facts.add(person, "type", "Human")
        w.facts.add(person, "isAt", "sofa-area")
    w.sessions = Sessions(w.sup)
    w.sessions.start()
    return w


def test_the_session_scheme_greets_idles_and_says_goodbye():
    run = compile_scheme(load_scheme("session")).start()
    run.send("arrived")
    assert run.configuration == ("greet",)
    run.send("done")
    assert run.configuration == ("idle",)
    run.send("task-started")
    assert run.configuration == ("busy",)
    run.send("task-over")
    run.send("left")
    assert run.configuration == ("farewell",)


@pytest.mark.parametrize("first, second", [("isNear", "looksAt"), ("looksAt", "isNear")])
def test_coming_near_and_looking_in_either_order_opens_a_session(world, first, second):
    world.facts.add("alice", first, "jido")
    world.run(3)
    assert "alice" not in world.sessions.open
    world.facts.add("alice", second, "jido")
    world.run(3)
    assert "alice" in world.sessions.open
    assert said(world) == ["Hello, Alice."]


def test_the_two_events_must_come_close_together(world):
    world.facts.add("alice", "isNear", "jido")
    world.run(30)  # she stays near, looking elsewhere
    world.facts.add("alice", "looksAt", "jido")
    world.run(3)
    assert "alice" not in world.sessions.open and said(world) == []


def test_people_attending_at_the_start_are_in_session_without_a_greeting():
    w = World()
    w.facts.add("alice", "type", "Human")
    sessions = Sessions(w.sup)
    sessions.start()
    w.run(2)
    assert "alice" in sessions.open and said(w) == []


def test_a_task_with_a_person_waits_for_a_session_with_them(world):
    goal = world.sup.agenda.add("give-object", {"object": "bottle", "partner": "alice"})
    world.run(5)
    assert goal.state == "pending" and goal.run is None
    world.facts.add("alice", "isNear", "jido")
    world.facts.add("alice", "looksAt", "jido")
    world.run(3)
    assert goal.run is not None
    session = world.sessions.open["alice"]
    assert "busy" in session.configuration
    world.sup.receive_act("alice", "H-AGREE")
    world.run(30)
    assert goal.state == "done" and "idle" in session.configuration


def test_a_task_of_the_robot_alone_does_not_wait(world):
    goal = world.sup.agenda.add("explore-place", {"place": "table"})
    world.run(1)
    assert goal.run is not None


def test_looking_away_is_not_leaving_but_going_out_of_sight_is(world):
    world.facts.add("alice", "isNear", "jido")
    world.facts.add("alice", "looksAt", "jido")
    world.run(3)
    world.facts.remove("alice", "looksAt", "jido")  # a phone call
    world.facts.remove("alice", "isNear", "jido")
    world.run(10)
    assert "alice" in world.sessions.open
    world.facts.remove("alice", "isAt", "sofa-area")  # out of the room
    world.run(10)
    assert said(world)[-1] == "Goodbye, Alice."
    assert "alice" not in world.sessions.open
