"""Understanding requests: the labels' grammar, a query per parameter, disambiguation."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shary.dialogue.reg import PerspectiveIndex
from shary.dialogue.requests import Grammar, Query, interpret_answer, resolve
from shary.facts.database import FactDatabase
from shary.recognition.ontology import load_action_ontology

WORLD = [
    ("g1", "type", "Cube"), ("g1", "color", "green"), ("g1", "isOn", "table"),
    ("g2", "type", "Cube"), ("g2", "color", "green"), ("g2", "isOn", "shelf"),
    ("r1", "type", "Cube"), ("r1", "color", "red"), ("r1", "isOn", "table"),
    ("yb", "type", "Bottle"), ("yb", "color", "yellow"), ("yb", "isOn", "table"),
    ("table", "type", "Table"), ("shelf", "type", "Shelf"), ("stick", "type", "Stick"),
    ("alice", "type", "Human"), ("bob", "type", "Human"), ("jido", "type", "Robot"),
]


@pytest.fixture(scope="module")
def grammar() -> Grammar:
    return Grammar.from_ontology(load_action_ontology(FactDatabase()))


@pytest.fixture(scope="module")
def index() -> PerspectiveIndex:
    return PerspectiveIndex.from_triples(WORLD)


def understand(grammar, index, sentence, it=None):
    found = grammar.parse(sentence, index, speaker="alice", addressee="jido", it=it)
    assert found.problem is None, found.problem
    return found.request


def test_take_the_green_cube_asks_which_one(grammar, index):
    request = understand(grammar, index, "Take the green cube.")
    assert (request.kind, request.action, request.agent) == ("request", "pick", "jido")
    resolution = resolve(request, index)
    assert resolution.status == "several" and resolution.candidates == ("g1", "g2")
    assert resolution.question == "Do you mean the green cube on the table or the one on the shelf?"
    assert interpret_answer("the one on the table", resolution, index) == "g1"
    assert interpret_answer("On the shelf.", resolution, index) == "g2"
    assert interpret_answer("the second one", resolution, index) == "g2"
    assert interpret_answer("the red one", resolution, index) is None
    assert interpret_answer("hmm", resolution, index) is None


def test_one_match_binds_every_parameter(grammar, index):
    request = understand(grammar, index, "put it on the stick", it="r1")
    assert request.action == "place"
    assert resolve(request, index).bindings == {"Agent": "jido", "Pickable": "r1",
                                                "Support": "stick"}
    give = understand(grammar, index, "Could you give me the yellow bottle, please?")
    assert give.action == "give-object" and give.roles == ("Agent", "Object", "Partner")
    assert resolve(give, index).bindings == {"Agent": "jido", "Object": "yb", "Partner": "alice"}
    to_bob = understand(grammar, index, "bring the red cube to Bob")
    assert resolve(to_bob, index).bindings["Partner"] == "bob"


def test_the_person_doing_it_is_a_plan_constraint(grammar, index):
    request = understand(grammar, index, "I'll take the bottle myself")
    assert (request.kind, request.action, request.agent) == ("constraint", "pick", "alice")
    assert resolve(request, index).bindings["Pickable"] == "yb"


def test_no_match_is_said(grammar, index):
    resolution = resolve(understand(grammar, index, "take the blue cube"), index)
    assert resolution.status == "none" and resolution.message == "I see no blue cube."


def test_the_reading_that_finds_things_wins(grammar, index):
    request = understand(grammar, index, "put the green cube on the table on the shelf")
    assert resolve(request, index).bindings["Pickable"] == "g1"
    assert resolve(request, index).bindings["Support"] == "shelf"


@pytest.mark.parametrize(("sentence", "problem"), [
    ("frobnicate the cube", "I did not understand 'frobnicate'."),
    ("take the unicorn", "I did not understand 'unicorn'."),
    ("the cube", "I did not understand what to do in 'the cube'."),
    ("", "I did not hear a request."),
    ("take take take", "I did not understand what to take in 'take take take'."),
    ("take the", "I did not understand what to take in 'take the'."),
    ("put it on the stick", "I do not know what 'it' is"),
])
def test_what_is_not_understood_is_said(grammar, index, sentence, problem):
    found = grammar.parse(sentence, index, speaker="alice", addressee="jido")
    assert found.request is None and found.problem.startswith(problem)


@settings(max_examples=60, deadline=None)
@given(st.text(max_size=60))
def test_any_text_is_understood_or_refused_never_raised(grammar, index, text):
    found = grammar.parse(text, index, speaker="alice", addressee="jido")
    assert (found.request is None) != (found.problem is None)


def test_queries_render_as_sparql_that_agrees_with_the_index(grammar, index):
    facts = FactDatabase()
    for triple in WORLD:
        facts.add(*triple)
    for sentence in ("take the green cube", "take the green cube on the shelf",
                     "take the cube on the table", "take the thing on the table"):
        query = understand(grammar, index, sentence).params["Pickable"]
        rows = facts.select(query.sparql())
        assert sorted(row["x"] for row in rows) == query.matches(index), sentence
    assert Query("Cube", (("color", "red"),)).sparql() == (
        "SELECT DISTINCT ?x WHERE {\n  ?x w:type w:Cube .\n  ?x w:color w:red .\n}")
