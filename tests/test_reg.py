"""Referring expressions: minimal, in the listener's perspective, never ambiguous."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st
from rdflib import Literal

from shary.dialogue.reg import Description, PerspectiveIndex, Referrer
from shary.facts.database import FactDatabase

TABLETOP = [
    ("g1", "type", "Cube"), ("g1", "color", "green"), ("g1", "isOn", "table"),
    ("g2", "type", "Cube"), ("g2", "color", "green"), ("g2", "isOn", "shelf"),
    ("r1", "type", "Cube"), ("r1", "color", "red"), ("r1", "isOn", "table"),
    ("table", "type", "Table"), ("shelf", "type", "Shelf"),
    ("alice", "type", "Human"),
]


def referrer(triples, **options) -> Referrer:
    return Referrer(PerspectiveIndex.from_triples(triples), **options)


def test_the_papers_example_green_cube_on_the_table():
    reg = referrer(TABLETOP)
    assert reg.text("g1") == "the green cube on the table"
    assert reg.text("g2") == "the green cube on the shelf"
    assert reg.text("r1") == "the red cube"
    assert reg.text("table") == "the table"


def test_agents_are_named_not_described():
    reg = referrer(TABLETOP + [("b", "type", "Bottle"), ("c", "type", "Bottle"),
                               ("b", "isNear", "alice")])
    assert reg.text("alice") == "Alice"
    assert reg.text("b") == "the bottle near Alice"


def test_preferred_attributes_are_configurable():
    triples = [("a", "type", "Ball"), ("a", "color", "red"), ("a", "size", "small"),
               ("b", "type", "Ball"), ("b", "color", "blue"), ("b", "size", "big")]
    assert referrer(triples).text("a") == "the red ball"
    assert referrer(triples, attributes=("type", "size", "color")).text("a") == "the small ball"
    both = triples + [("c", "type", "Ball"), ("c", "color", "red"), ("c", "size", "big")]
    assert referrer(both).text("a") == "the small red ball"  # size before colour in English


def test_landmarks_are_described_in_turn():
    triples = [("c1", "type", "Cube"), ("c1", "isOn", "t1"), ("c2", "type", "Cube"),
               ("c2", "isOn", "t2"), ("t1", "type", "Table"), ("t1", "color", "white"),
               ("t2", "type", "Table"), ("t2", "color", "black")]
    assert referrer(triples).text("c1") == "the cube on the white table"


def test_no_description_points_instead():
    reg = referrer(TABLETOP + [("g3", "type", "Cube"), ("g3", "color", "green"),
                               ("g3", "isOn", "table")])
    described = reg.describe("g1")
    assert described.pointing and described.gesture == ("point-at", "g1")
    assert described.text() == "this cube"


def test_disambiguation_among_candidates_keeps_what_was_said():
    reg = referrer(TABLETOP)
    said = [("color", "green")]
    first = reg.describe("g1", context=["g1", "g2"], given=said)
    second = reg.describe("g2", context=["g1", "g2"], given=said)
    assert f"{first.text()} or {second.text('one')}" == \
        "the green cube on the table or the one on the shelf"


def test_the_listeners_perspective_decides():
    facts = FactDatabase()
    for s, p, o in TABLETOP:
        facts.add(s, p, o, perspective="robot")
        if s != "g2":  # Alice has not seen the cube on the shelf
            facts.add(s, p, o, perspective="alice")
    assert Referrer.for_perspective(facts, "robot").text("g1") == "the green cube on the table"
    assert Referrer.for_perspective(facts, "alice").text("g1") == "the green cube"


# -- property: for random worlds, every description denotes exactly its target --------------

TYPES, COLOURS, SIZES = ("Cube", "Ball", "Bottle"), ("red", "green", "blue"), ("small", "big")
SUPPORTS = [("table", "Table"), ("shelf", "Shelf"), ("desk", "Table")]

thing = st.tuples(st.sampled_from(TYPES), st.one_of(st.none(), st.sampled_from(COLOURS)),
                  st.one_of(st.none(), st.sampled_from(SIZES)),
                  st.one_of(st.none(), st.sampled_from([s for s, _ in SUPPORTS])),
                  st.one_of(st.none(), st.integers(0, 11)))


def world(things) -> list[tuple[str, str, str]]:
    triples = [(name, "type", kind) for name, kind in SUPPORTS]
    triples += [("desk", "color", "brown")]
    for i, (kind, colour, size, support, near) in enumerate(things):
        name = f"o{i}"
        triples.append((name, "type", kind))
        if colour:
            triples.append((name, "color", colour))
        if size:
            triples.append((name, "size", size))
        if support:
            triples.append((name, "isOn", support))
        if near is not None and near < len(things) and near != i:
            triples.append((name, "isNear", f"o{near}"))
    return triples


def meaning(description: Description, triples) -> set[str]:
    """What a description denotes, read straight from the triples (not the index)."""
    if description.name is not None or description.pointing:
        return {description.target}
    facts = set(triples)
    things = {s for s, p, _ in triples if p == "type"}
    found = {t for t in things if all((t, a, v) in facts for a, v in description.attributes)}
    for predicate, _, landmark in description.relations:
        landmarks = meaning(landmark, triples)
        found = {t for t in found if any((t, predicate, m) in facts for m in landmarks)}
    return found


@settings(max_examples=60, deadline=None)
@given(st.lists(thing, min_size=1, max_size=12))
def test_every_description_denotes_exactly_its_target(things):
    triples = world(things)
    reg = referrer(triples)
    for target in {s for s, p, _ in triples if p == "type"}:
        described = reg.describe(target)
        assert meaning(described, triples) == {target}, described.text()
        if not described.pointing:
            assert ("type", dict((p, o) for s, p, o in triples if s == target)["type"]) \
                in described.attributes


@settings(max_examples=40, deadline=None)
@given(st.lists(thing, min_size=2, max_size=10), st.data())
def test_descriptions_among_candidates_tell_them_apart(things, data):
    triples = world(things)
    reg = referrer(triples)
    names = [f"o{i}" for i in range(len(things))]
    candidates = data.draw(st.lists(st.sampled_from(names), min_size=2, unique=True))
    for target in candidates:
        described = reg.describe(target, context=candidates)
        assert meaning(described, triples) & set(candidates) == {target}


def test_a_perspectives_index_follows_the_facts_without_being_built_again():
    """The index a referrer reads is the database's, kept current change by change (a
    sentence must not cost the whole world), and it always equals an index built
    afresh from the facts."""
    facts = FactDatabase()
    for s, p, o in TABLETOP:
        facts.add(s, p, o)
    index = Referrer.for_perspective(facts, "robot").index
    assert Referrer.for_perspective(facts, "robot").text("g1") == "the green cube on the table"
    facts.set("g2", "isOn", "table")
    facts.remove("r1", "type", "Cube")
    facts.add("b1", "type", "Ball")
    facts.add("b1", "isNear", "g1")
    facts.remove("g1", "isOn", "table")
    facts.add("Shelf", "rdfs:label", Literal("bookshelf"))
    reg = Referrer.for_perspective(facts, "robot")
    assert reg.index is index
    fresh = PerspectiveIndex.from_triples(facts.triples("robot"))
    for part in ("entities", "values", "having", "related", "relations", "labels"):
        assert getattr(index, part) == getattr(fresh, part), part
    assert reg.text("g2") == "the cube on the table"  # g1 is green too, and nowhere now
    assert reg.text("b1") == "the ball"
    assert reg.text("shelf") == "the bookshelf"
