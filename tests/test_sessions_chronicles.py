"""Chronicles as partially ordered conjunctions: a step of several fact events in any
order (``all:``), within a window, in sequence with other steps."""

from __future__ import annotations

import re
import textwrap

import pytest
from scripted import World

from shary.io.recipes import load_library
from shary.kernel.agenda import ChronicleRecognizer
from userfiles.errors import FileError

LIBRARY = """\
    chronicles:
      will-to-interact:
        doc: a person comes near the robot and looks at it, in either order
        events:
          - all:
              - added: [$person, isNear, jido]
              - added: [$person, looksAt, jido]
            within: 10s
        goal: {task: inform, with: {partner: $person, text: Hello.}}
      visit-then-leave:
        doc: near the table and looking at it (any order), then gone from the table
        events:
          - all:
              - added: [$person, isNear, table]
              - added: [$person, looksAt, table]
          - removed: [$person, isNear, table]
            within: 1min
        goal: {task: explore-place, with: {place: table}}
    """


@pytest.fixture
def world(tmp_path) -> World:
    path = tmp_path / "chronicles.yaml"
    path.write_text(textwrap.dedent(LIBRARY))
    w = World(extra_library=[path])
    w.facts.remove("alice", "looksAt", "jido")
    w.recognizer = ChronicleRecognizer(w.sup)
    return w


def goals(world: World) -> list[tuple[str, dict]]:
    return [(g.task, g.args) for g in world.sup.agenda.goals]


@pytest.mark.parametrize("first, second", [("isNear", "looksAt"), ("looksAt", "isNear")])
def test_the_events_of_a_step_come_in_any_order(world, first, second):
    world.facts.add("alice", first, "jido")
    world.run(4)
    assert goals(world) == []
    world.facts.add("alice", second, "jido")
    world.run(0.1)
    assert goals(world) == [("inform", {"partner": "alice", "text": "Hello."})]


def test_a_step_of_several_events_is_bounded_by_its_window(world):
    world.facts.add("alice", "isNear", "jido")
    world.run(11)
    world.facts.add("alice", "looksAt", "jido")
    world.run(0.1)
    assert goals(world) == []


def test_a_conjunction_then_a_sequence(world):
    world.facts.add("alice", "looksAt", "table")
    world.facts.add("alice", "isNear", "table")
    world.run(5)
    assert goals(world) == []
    world.facts.remove("alice", "isNear", "table")
    world.run(0.1)
    assert goals(world) == [("explore-place", {"place": "table"})]


@pytest.mark.parametrize("events, message", [
    ("- all: [{added: [$p, isNear, jido]}]", r"should be non-empty|too short|at least 2"),
    ("- {all: [{added: [$p, isNear, jido]}, {added: [$p, looksAt, jido]}], stays: 2s}",
     r"'stays' follows one event"),
])
def test_bad_conjunctions_are_refused_at_their_line(tmp_path, events, message):
    path = tmp_path / "bad.yaml"
    path.write_text("chronicles:\n  c:\n    events:\n      " + events
                    + "\n    goal: {task: explore-place, with: {place: $p}}\n")
    with pytest.raises(FileError) as err:
        load_library([path])
    text = str(err.value)
    assert "bad.yaml:4:" in text
    assert re.search(message, text), text
