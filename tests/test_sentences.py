"""What the robots say is English about what a person can see.

``tests/data/sentences.txt`` holds every sentence robots said in a campaign of
runs (``tests/sentences.py``: the stack, living-room and weld families with
varied partner profiles), read sentence by sentence when it changes.  The
campaign is run again here and must say exactly those sentences; none of them
may read like an engine's log: a report of waiting, an internal name
("the placement 1", "red_cube_1"), a relation said twice ("on the stick on the
stick").  Each bad pattern is also produced on purpose, so that the checks can
fail, and the dialogue code that avoids it is tested directly.
"""

from __future__ import annotations

import re

import pytest
from rdflib import Literal
from sentences import FAMILIES, generate, read

from shary.dialogue.reg import PerspectiveIndex, Referrer
from shary.dialogue.speech import Speech
from shary.facts.database import FactDatabase

BAD = {
    "a report of waiting": re.compile(r"\b(?:I|you|we)\s+waited\b|\bI did (?!not\b)\w",
                                      re.IGNORECASE),
    "an internal name": re.compile(r"\b[a-z]+ \d+\b|\w_\w|\b[a-z]+-[a-z]+\b"),
    "a relation said twice": re.compile(
        r"\b((?:on|in|near|under|behind|across)\s+the\s+[\w ]+?)\s+\1\b"),
}
"""What a sentence about things a person can see must never contain."""

BAD_EXAMPLES = {
    "a report of waiting": "I waited.",
    "a task's name for want of words": "I did Place.",
    "an internal name": "I placed the red cube 1 on the placement 1.",
    "a relation said twice": "I placed the green cube on the blue cube on the stick on the "
                             "stick.",
}


GOOD_EXAMPLES = ["You did not answer, so I will not give you the yellow bottle.",
                 "I placed the green cube on the blue cube on the stick.",
                 "Is this seam okay?", "I picked up the red cube near you."]


def sentences() -> list[str]:
    return sorted({s for said in read().values() for s in said})


def problems(sentence: str) -> list[str]:
    return [name for name, pattern in BAD.items() if pattern.search(sentence)]


@pytest.mark.parametrize("name", sorted(BAD_EXAMPLES))
def test_each_bad_pattern_is_caught(name):
    assert problems(BAD_EXAMPLES[name])


@pytest.mark.parametrize("sentence", GOOD_EXAMPLES)
def test_good_english_passes(sentence):
    assert not problems(sentence)


def test_the_list_is_long_enough_and_reads_well():
    said = sentences()
    assert len(said) >= 40, f"only {len(said)} sentences: the campaign says too little"
    assert list(read()) == list(FAMILIES)
    for family, listed in read().items():
        assert listed == sorted(set(listed)), f"{family}: kept sorted, each sentence once"
    bad = {s: problems(s) for s in said if problems(s)}
    assert not bad, f"sentences that read badly: {bad}"
    for sentence in said:
        assert sentence[:1].isupper() and sentence[-1] in ".?!", sentence


@pytest.mark.parametrize("family", list(FAMILIES))
def test_the_campaign_says_what_the_list_holds(family):
    """Regenerated here; when it differs on purpose, ``python tests/sentences.py`` rewrites
    the list, and the new sentences are read before they are committed."""
    said = generate(family)
    old = read()[family]
    assert said == old, (f"new: {sorted(set(said) - set(old))}; "
                         f"gone: {sorted(set(old) - set(said))} "
                         "(python tests/sentences.py rewrites tests/data/sentences.txt)")


# -- the dialogue code behind each pattern ----------------------------------------------------

def stack_world() -> FactDatabase:
    """Two red cubes, two blue cubes, two placements and a stick, as the robot perceives
    them when Alice stands across the table (sim/stack/world.py's relations)."""
    facts = FactDatabase()
    for name, kind, colour in [("placement_1", "Placement", "white"),
                               ("placement_2", "Placement", "white"),
                               ("red_cube_1", "Cube", "red"), ("red_cube_2", "Cube", "red"),
                               ("blue_cube_1", "Cube", "blue"), ("blue_cube_2", "Cube", "blue"),
                               ("stick", "Stick", "brown")]:
        facts.add(name, "type", kind)
        facts.add(name, "color", colour)
    for agent, kind in (("pr2", "Robot"), ("alice", "Human")):
        facts.add(agent, "type", kind)
        facts.add(agent, "type", "Agent")
    facts.add("Human", "rdfs:label", Literal("person"))
    for thing, relation, landmark in [
            ("placement_1", "rightOf", "alice"), ("placement_2", "leftOf", "alice"),
            ("red_cube_1", "isNear", "pr2"), ("red_cube_2", "isNear", "alice"),
            ("blue_cube_1", "isNear", "pr2"), ("blue_cube_2", "isOn", "stick"),
            ("stick", "isNear", "alice")]:
        facts.add(thing, relation, landmark)
    return facts


def say(facts: FactDatabase, act: str, about: str) -> str:
    return Speech(facts).say({"act": act, "about": about, "to": "alice"}, "pr2")


def test_places_and_lookalikes_are_described_from_the_listeners_side():
    facts = stack_world()
    assert say(facts, "request", "place(alice, red_cube_2, placement_2)") == \
        "Please place the red cube near you on the placement on your left."
    assert say(facts, "inform-planned", "pick(pr2, red_cube_1)") == \
        "I will pick up the red cube near me."
    facts.add("pr2", "isHolding", "red_cube_1")
    facts.remove("red_cube_1", "isNear", "pr2")
    facts.add("red_cube_1", "isNear", "alice")  # the other one is near her too, now
    assert say(facts, "inform-ongoing", "place(pr2, red_cube_1, placement_1)") == \
        "I am placing the red cube in my hand on the placement on your right."


def test_a_thing_nothing_tells_apart_is_one_of_its_kind_never_its_identifier():
    facts = stack_world()
    for thing, relation, landmark in [("red_cube_1", "isNear", "pr2"),
                                      ("red_cube_2", "isNear", "alice")]:
        facts.remove(thing, relation, landmark)
    assert say(facts, "inform-done", "pick(pr2, red_cube_1)") == \
        "I picked up one of the red cubes."
    facts.add("pebble_3", "isOn", "stick")  # numbered, and of no known type
    assert say(facts, "inform-done", "pick(pr2, pebble_3)") == "I picked up the pebble."


def test_what_the_sentence_says_is_not_said_again_in_a_description():
    facts = stack_world()
    assert say(facts, "inform-done", "place(pr2, blue_cube_2, stick)") == \
        "I placed the blue cube on the stick."
    assert say(facts, "request", "pick(alice, blue_cube_2)") == \
        "Please pick up the blue cube on the stick."


def test_a_persons_hand_and_side_read_with_their_name_for_a_third_party():
    facts = stack_world()
    facts.add("alice", "isHolding", "red_cube_2")
    facts.remove("red_cube_2", "isNear", "alice")
    reg = Referrer(PerspectiveIndex.from_triples(facts.triples("robot")))
    assert reg.text("red_cube_2") == "the red cube in Alice's hand"
    assert reg.describe("placement_1").text(people={"alice": "you"}) == \
        "the placement on your right"
