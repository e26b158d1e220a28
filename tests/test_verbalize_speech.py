"""The ``say`` step: sentences generated from the action ontology in the listener's terms."""

from __future__ import annotations

import pytest
from hostile import assert_refused, run_inprocess

from shary.dialogue.speech import Speech, parse_about
from shary.facts.database import FactDatabase


@pytest.fixture
def facts() -> FactDatabase:
    facts = FactDatabase()
    for s, p, o in [("jido", "type", "Robot"), ("alice", "type", "Human"),
                    ("c1", "type", "Cube"), ("c1", "color", "green"), ("c1", "isOn", "table"),
                    ("c2", "type", "Cube"), ("c2", "color", "green"), ("c2", "isOn", "shelf"),
                    ("table", "type", "Table"), ("shelf", "type", "Shelf")]:
        facts.add(s, p, o, perspective="alice")
    facts.add("c1", "type", "Cube", perspective="robot")
    return facts


def test_sentences_come_from_labels_and_the_listeners_perspective(facts):
    speech = Speech(facts)
    assert speech.say({"act": "propose", "about": "give-object(jido, c1, alice)",
                       "to": "alice"}, "jido") == "Shall I give you the cube on the table?"
    assert speech.say({"act": "question", "about": "place(alice, c2, table)", "to": "alice"},
                      "jido") == "Can you place the cube on the shelf on the table?"
    assert speech.say({"act": "inform-done", "about": "explore-place(jido, coffee-area)",
                       "to": "_"}, "jido") == "I explored the coffee area."


@pytest.mark.parametrize(("args", "message"), [
    ({"act": "boast", "about": "pick(jido, c1)", "to": "alice"}, "unknown act 'boast'"),
    ({"act": "propose", "about": "pick jido", "to": "alice"}, "must read action"),
    ({"act": "propose", "about": "pick(jido, {object})", "to": "alice"}, "unbound"),
    ({"act": "propose", "about": "juggle(jido, c1)", "to": "alice"}, "no label for 'juggle'"),
    ({"act": "propose", "about": "pick(jido)", "to": "alice"}, "takes the agent and Pickable"),
])
def test_a_bad_say_step_says_why(facts, args, message):
    with pytest.raises(ValueError, match=message):
        Speech(facts).say(args, "jido")


def test_about_is_read_as_a_call():
    assert parse_about(" give(alice, cup, jido) ") == ("give", ["alice", "cup", "jido"])


def test_shary_validate_refuses_a_bad_say_step_at_its_line(write):
    path = write("say.yaml", """\
        tasks:
          greet: {params: [person], scheme: robot-task}
        recipes:
          - task: greet
            act: REALIZE-TASK
            steps:
              - {do: say, with: {act: boast, about: "explore-place({robot}, {person})", to: _}}
              - {do: say, with: {act: propose, about: "juggle({robot})", to: $person}}
              - {do: say, with: {act: propose, about: "pick({robot}, {objet})", to: _}}
              - {do: say, with: {act: propose, about: "give-object({robot})", to: _}}
        """)
    outcome = run_inprocess("validate", path)
    assert_refused(outcome, path, message="say: unknown act 'boast'")
    for line, message in ((7, "unknown act 'boast'"), (8, "no label for 'juggle'"),
                          (9, "{objet} is not a parameter here"),
                          (10, "give-object takes the agent and Object, Partner")):
        assert f"{path}:{line}:" in outcome.err and message in outcome.err, outcome.err
