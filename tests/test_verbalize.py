"""Verbalization: labels conjugated by act, person and the listener's referring expressions."""

from __future__ import annotations

import pytest

from shary.dialogue.reg import PerspectiveIndex, Referrer
from shary.dialogue.verbalize import Label, Verbalizer, conjugate, verbalize

PLACE = "{Agent} @Place {Pickable} on {Support}"


def say(act, agent="jido", label=PLACE, **bindings):
    values = {"Agent": agent, "Pickable": "blue-cube", "Support": "stick", **bindings}
    return verbalize(label, values, act, speaker="jido", addressee="alice", agents={"bob"})


@pytest.mark.parametrize(("act", "agent", "sentence"), [
    ("inform-done", "jido", "I placed the blue cube on the stick."),
    ("inform-done", "alice", "You placed the blue cube on the stick."),
    ("inform-done", "bob", "Bob placed the blue cube on the stick."),
    ("inform-ongoing", "jido", "I am placing the blue cube on the stick."),
    ("inform-ongoing", "alice", "You are placing the blue cube on the stick."),
    ("inform-ongoing", "bob", "Bob is placing the blue cube on the stick."),
    ("inform-planned", "alice", "You will place the blue cube on the stick."),
    ("inform-failed", "jido", "I could not place the blue cube on the stick."),
    ("request", "alice", "Please place the blue cube on the stick."),
    ("question", "alice", "Can you place the blue cube on the stick?"),
    ("ask-done", "alice", "Did you place the blue cube on the stick?"),
    ("propose", "jido", "Shall I place the blue cube on the stick?"),
    ("propose", "alice", "Would you like to place the blue cube on the stick?"),
])
def test_acts_choose_tense_person_and_mood(act, agent, sentence):
    assert say(act, agent) == sentence


def test_irregular_verbs_and_be():
    assert say("inform-done", label="{Agent} @Give {Recipient} {Object}", Recipient="alice",
               Object="yellow-bottle") == "I gave you the yellow bottle."
    assert say("inform-done", "alice", label="{Agent} @take {Object}", Object="cup") == \
        "You took the cup."
    assert say("inform-done", "bob", label="{Agent} @put {Object} down", Object="cup") == \
        "Bob put the cup down."
    assert say("inform-done", "jido", label="{Agent} @be near {Place}", Place="sofa") == \
        "I was near the sofa."
    assert say("inform-done", "alice", label="{Agent} @be near {Place}", Place="sofa") == \
        "You were near the sofa."
    assert say("inform-planned", "bob", label="{Agent} @be near {Place}", Place="sofa") == \
        "Bob will be near the sofa."
    assert conjugate("be", "VBP", 1) == "am" and conjugate("lie", "VBD") == "lay"


def test_phrasal_verbs_are_inflected_on_their_head():
    label = "{Agent} @pick_up {Object}"
    assert say("inform-done", label=label, Object="cup") == "I picked up the cup."
    assert say("inform-ongoing", label=label, Object="cup") == "I am picking up the cup."
    assert conjugate("set up", "VBD") == "set up"


def test_objects_are_named_in_the_listeners_terms():
    index = PerspectiveIndex.from_triples([
        ("g1", "type", "Cube"), ("g1", "color", "green"), ("g1", "isOn", "table"),
        ("g2", "type", "Cube"), ("g2", "color", "green"), ("g2", "isOn", "shelf"),
        ("table", "type", "Table"), ("shelf", "type", "Shelf"), ("stick", "type", "Stick")])
    speaker = Verbalizer("jido", "alice", refer=Referrer(index).text)
    assert speaker.say("{Agent} @pick {Object}", {"agent": "alice", "object": "g1"},
                       "question") == "Can you pick the cube on the table?"
    assert speaker.say(PLACE, {"Agent": "jido", "Pickable": "g2", "Support": "stick"},
                       "inform-done") == "I placed the cube on the shelf on the stick."


@pytest.mark.parametrize(("label", "message"), [
    ("@Place {Object}", "must start with its agent"),
    ("{Agent} {Object}", "exactly one verb"),
    ("{Agent} @Place @Put", "exactly one verb"),
    ("{Agent} @Place {Object", "cannot read"),
    ("{Agent} place @it", "the verb must follow the agent"),
])
def test_bad_labels_are_refused_with_a_reason(label, message):
    with pytest.raises(ValueError, match=message):
        Label.parse(label)


def test_unbound_parameters_and_unknown_acts_are_refused():
    with pytest.raises(ValueError, match="no value for Support"):
        verbalize(PLACE, {"Agent": "jido", "Pickable": "cube"}, "inform-done", speaker="jido")
    with pytest.raises(ValueError, match="unknown communicative act 'boast'"):
        verbalize(PLACE, {"Agent": "jido", "Pickable": "c", "Support": "s"}, "boast",
                  speaker="jido")


def test_a_pronoun_recipient_comes_first():
    label = "{Agent} @Give {Object} to {Partner}"
    assert say("propose", label=label, Object="yellow-bottle", Partner="alice") == \
        "Shall I give you the yellow bottle?"
    assert say("question", "alice", label=label, Object="cup", Partner="jido") == \
        "Can you give me the cup?"
    assert say("inform-done", label=label, Object="cup", Partner="bob") == \
        "I gave the cup to Bob."
