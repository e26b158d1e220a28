"""The fact database: a-priori Turtle, perspectives, SPARQL SELECT, change events."""

from __future__ import annotations

from pathlib import Path

import pytest
from rdflib import Literal, URIRef

from shary.facts.database import FactDatabase, FactEvent
from userfiles.errors import FileError

LIVING_ROOM = Path(__file__).parent / "data" / "living-room.ttl"
W = "http://shary.dev/world#"

BOTTLES_ON = """
    SELECT ?bottle WHERE { ?bottle a w:Bottle ; w:isOn ?place . } ORDER BY ?bottle
"""


@pytest.fixture
def db() -> FactDatabase:
    facts = FactDatabase()
    facts.load_turtle(LIVING_ROOM)
    return facts


def recorder(db: FactDatabase, **pattern) -> list[FactEvent]:
    events: list[FactEvent] = []
    db.subscribe(events.append, **pattern)
    return events


# -- terms ---------------------------------------------------------------------------------------

def test_terms_short_prefixed_full_and_literals():
    db = FactDatabase()
    assert db.term("bottle-yellow") == URIRef(W + "bottle-yellow")
    assert db.term("w:isOn") == URIRef(W + "isOn")
    assert db.term("rdf:type") == URIRef("http://www.w3.org/1999/02/22-rdf-syntax-ns#type")
    assert db.term("http://example.org/x") == URIRef("http://example.org/x")
    assert db.term(3) == Literal(3)
    assert db.term(True) == Literal(True)
    assert db.term(0.5) == Literal(0.5)
    for term in (URIRef(W + "isOn"), URIRef("http://example.org/x"), Literal(3), Literal(True),
                 Literal(0.5), Literal("coffee table"), db.term("rdfs:label")):
        assert db.term(db.name(term)) == term
    assert db.name(db.term("rdfs:label")) == "rdfs:label"
    assert db.name(Literal("coffee table")) == Literal("coffee table")


def test_other_namespace():
    db = FactDatabase("http://example.org/home/")
    assert db.term("sofa") == URIRef("http://example.org/home/sofa")
    assert db.name(URIRef("http://example.org/home/sofa")) == "sofa"
    assert db.name(URIRef(W + "sofa")) == W + "sofa"


@pytest.mark.parametrize("bad", ["coffee table", "x:isOn", "w:has space", ""])
def test_bad_names_are_refused(bad):
    with pytest.raises(ValueError):
        FactDatabase().term(bad)


# -- a-priori knowledge and SPARQL ---------------------------------------------------------------

def test_load_and_select_with_bindings(db):
    # "which bottles are on the coffee table", the place bound from Python
    assert db.select(BOTTLES_ON, place="coffee-table") == [
        {"bottle": "bottle-blue"}, {"bottle": "bottle-yellow"}]
    assert db.select(BOTTLES_ON, place="kitchen-table") == [{"bottle": "bottle-red"}]
    # the same prepared query, many bindings, no cross-talk
    assert db.select(BOTTLES_ON, place="sofa") == []
    rows = db.select("SELECT ?b ?ml WHERE { ?b w:hasColor ?c ; w:volumeMl ?ml }", c="yellow")
    assert rows == [{"b": "bottle-yellow", "ml": 500}]
    rows = db.select("SELECT ?label WHERE { w:coffee-table rdfs:label ?label }")
    assert rows == [{"label": Literal("coffee table")}]


def test_select_sees_changes_and_leaves_unbound_variables_none(db):
    db.set("bottle-red", "isOn", "coffee-table")
    assert [r["bottle"] for r in db.select(BOTTLES_ON, place="coffee-table")] == [
        "bottle-blue", "bottle-red", "bottle-yellow"]
    rows = db.select("SELECT ?x ?label WHERE { ?x a w:Seat OPTIONAL { ?x rdfs:label ?label } }")
    assert rows == [{"x": "sofa", "label": None}]


@pytest.mark.parametrize("query", [
    "INSERT DATA { w:a w:b w:c }",
    "DELETE WHERE { ?s ?p ?o }",
    "ASK { ?s ?p ?o }",
    "CONSTRUCT { ?s ?p ?o } WHERE { ?s ?p ?o }",
    "SELEC ?x WHERE { ?x ?p ?o }",
])
def test_select_refuses_anything_but_select(db, query):
    with pytest.raises(ValueError):
        db.select(query)


def test_load_returns_the_number_of_triples(tmp_path):
    path = tmp_path / "two.ttl"
    path.write_text("@prefix w: <http://shary.dev/world#> .\nw:a w:b w:c , w:d .\n")
    db = FactDatabase()
    assert db.load_turtle(path) == 2
    assert db.objects("a", "b") == ["c", "d"]


# -- malformed files -----------------------------------------------------------------------------

def test_malformed_turtle_gives_file_line_col(write):
    path = write("broken.ttl", """\
        @prefix w: <http://shary.dev/world#> .

        w:sofa a w:Seat .
        w:bottle-yellow w:isOn w:sofa .
        w:bottle-blue w:isOn  x:sofa .
        w:cup w:isOn w:sofa .
    """)
    db = FactDatabase()
    with pytest.raises(FileError) as caught:
        db.load_turtle(path)
    [problem] = caught.value.problems
    assert (problem.file, problem.line, problem.col) == (str(path), 5, 23)
    assert "x:" in problem.message and "not been declared" in problem.message
    assert str(problem).startswith(f"{path}:5:23: error: invalid Turtle")
    assert db.select("SELECT ?s WHERE { ?s ?p ?o }") == []  # nothing half-loaded


def test_bad_term_has_a_position(write):
    path = write("lang.ttl", '@prefix w: <http://shary.dev/world#> .\nw:a w:b "x"@1 .\n')
    with pytest.raises(FileError) as caught:
        FactDatabase().load_turtle(path)
    [problem] = caught.value.problems
    assert (problem.line, problem.col) == (2, 13)
    assert "language code" in problem.message


def test_unreadable_and_non_utf8_files(write, tmp_path):
    with pytest.raises(FileError) as caught:
        FactDatabase().load_turtle(tmp_path / "missing.ttl")
    assert "cannot read" in caught.value.problems[0].message
    path = write("latin1.ttl", b'@prefix w: <http://shary.dev/world#> .\nw:a w:b "caf\xe9" .\n')
    with pytest.raises(FileError) as caught:
        FactDatabase().load_turtle(path)
    assert caught.value.problems[0].line == 2


# -- changes and events --------------------------------------------------------------------------

def test_add_remove_and_their_events(db):
    events = recorder(db)
    assert db.add("bottle-yellow", "isHeldBy", "jido") is True
    assert db.add("bottle-yellow", "isHeldBy", "jido") is False  # unchanged: no event
    assert db.holds("bottle-yellow", "isHeldBy", "jido")
    assert db.remove("bottle-yellow", "isHeldBy", "jido") is True
    assert db.remove("bottle-yellow", "isHeldBy", "jido") is False
    assert events == [
        FactEvent("added", "bottle-yellow", "isHeldBy", "jido", "robot"),
        FactEvent("removed", "bottle-yellow", "isHeldBy", "jido", "robot"),
    ]


def test_literal_objects_in_events(db):
    events = recorder(db, predicate="distance")
    db.set("human-1", "distance", 1.5)
    db.set("human-1", "distance", 0.8)
    assert events == [
        FactEvent("added", "human-1", "distance", 1.5, "robot"),
        FactEvent("removed", "human-1", "distance", 1.5, "robot"),
        FactEvent("added", "human-1", "distance", 0.8, "robot"),
    ]
    assert db.objects("human-1", "distance") == [0.8]


def test_patterns(db):
    by_predicate = recorder(db, predicate="looksAt")
    by_subject = recorder(db, subject="human-1")
    by_object = recorder(db, object="jido")
    by_perspective = recorder(db, perspective="human-1")
    by_all = recorder(db, subject="human-1", predicate="looksAt", object="jido",
                      perspective="robot")
    wildcard = recorder(db)

    db.add("human-1", "looksAt", "jido")
    db.add("human-1", "looksAt", "bottle-yellow")
    db.add("bottle-yellow", "isHeldBy", "jido")
    db.add("jido", "looksAt", "human-1", perspective="human-1")

    looks = FactEvent("added", "human-1", "looksAt", "jido", "robot")
    at_bottle = FactEvent("added", "human-1", "looksAt", "bottle-yellow", "robot")
    held = FactEvent("added", "bottle-yellow", "isHeldBy", "jido", "robot")
    seen_by_human = FactEvent("added", "jido", "looksAt", "human-1", "human-1")
    assert by_predicate == [looks, at_bottle, seen_by_human]
    assert by_subject == [looks, at_bottle]
    assert by_object == [looks, held]
    assert by_perspective == [seen_by_human]
    assert by_all == [looks]
    assert wildcard == [looks, at_bottle, held, seen_by_human]


def test_delivery_in_subscription_order_across_buckets(db):
    calls = []
    for i, pattern in enumerate([{}, {"predicate": "isOn"}, {"subject": "bottle-blue"},
                                 {"subject": "bottle-blue", "predicate": "isOn"}, {}]):
        db.subscribe(lambda event, i=i: calls.append(i), **pattern)
    db.add("bottle-blue", "isOn", "sofa")
    assert calls == [0, 1, 2, 3, 4]


def test_unsubscribe(db):
    events = []
    subscription = db.subscribe(events.append, predicate="isOn")
    db.add("cup-white", "isOn", "sofa")
    db.unsubscribe(subscription)
    db.unsubscribe(subscription)  # harmless
    db.add("cup-white", "isOn", "kitchen-table")
    assert len(events) == 1 and not subscription.active


def test_set_removes_other_objects_then_adds(db):
    events = recorder(db, subject="bottle-yellow", predicate="isOn")
    db.add("bottle-yellow", "isOn", "sofa")  # now on two things
    events.clear()
    assert db.set("bottle-yellow", "isOn", "kitchen-table") is True
    assert events == [
        FactEvent("removed", "bottle-yellow", "isOn", "coffee-table", "robot"),
        FactEvent("removed", "bottle-yellow", "isOn", "sofa", "robot"),
        FactEvent("added", "bottle-yellow", "isOn", "kitchen-table", "robot"),
    ]
    assert db.objects("bottle-yellow", "isOn") == ["kitchen-table"]
    events.clear()
    assert db.set("bottle-yellow", "isOn", "kitchen-table") is False
    assert events == []


def test_set_callbacks_see_the_finished_change(db):
    seen = []
    db.subscribe(lambda e: seen.append((e.kind, db.objects("bottle-blue", "isOn"))),
                 predicate="isOn")
    db.set("bottle-blue", "isOn", "sofa")
    assert seen == [("removed", ["sofa"]), ("added", ["sofa"])]


def test_change_removes_and_adds_as_one_change(db):
    seen = []
    db.subscribe(lambda e: seen.append((e.kind, e.object, db.objects("alice", "looksAt"))),
                 subject="alice")
    db.add("alice", "looksAt", "jido")
    seen.clear()
    # what a perception message does: her gaze moves; no subscriber sees her look nowhere
    assert db.change([("alice", "looksAt", "jido"), ("alice", "isAt", "door")],
                     [("alice", "looksAt", "tv"), ("alice", "looksAt", "tv")]) == 2
    assert seen == [("removed", "jido", ["tv"]), ("added", "tv", ["tv"])]
    seen.clear()
    assert db.change([], [("alice", "looksAt", "tv")]) == 0 and seen == []


# -- perspectives --------------------------------------------------------------------------------

def test_perspectives_are_separate_and_share_a_priori(db):
    assert db.perspectives() == []
    db.add("bottle-yellow", "isHeldBy", "jido")                       # the robot believes X
    assert db.holds("bottle-yellow", "isHeldBy", "jido")
    assert not db.holds("bottle-yellow", "isHeldBy", "jido", perspective="human-1")
    for perspective in ("robot", "human-1"):                          # a-priori: seen by both
        assert db.holds("sofa", "isIn", "living-room", perspective=perspective)
        assert db.holds("bottle-red", "rdf:type", "Bottle", perspective=perspective)

    db.set("bottle-red", "isOn", "coffee-table", perspective="robot")  # the robot saw it moved
    assert db.objects("bottle-red", "isOn") == ["coffee-table"]
    assert db.objects("bottle-red", "isOn", perspective="human-1") == ["kitchen-table"]
    db.add("jido", "looksAt", "human-1", perspective="human-1")
    assert db.perspectives() == ["robot", "human-1"]
    assert [r["bottle"] for r in db.select(BOTTLES_ON, "human-1", place="coffee-table")] == [
        "bottle-blue", "bottle-yellow"]

    graphs = {str(g.identifier) for g in db.dataset.graphs()}
    assert {"urn:shary:perspective:robot", "urn:shary:perspective:human-1"} <= graphs


def test_a_priori_loaded_later_reaches_every_perspective(db, write):
    db.add("jido", "looksAt", "human-1")
    path = write("more.ttl", "@prefix w: <http://shary.dev/world#> .\nw:shelf a w:Furniture .\n")
    db.load_turtle(path)
    assert db.holds("shelf", "rdf:type", "Furniture")
    assert db.holds("shelf", "rdf:type", "Furniture", perspective="human-2")


def test_load_into_one_perspective(db, write):
    path = write("belief.ttl",
                 "@prefix w: <http://shary.dev/world#> .\nw:bottle-red w:isOn w:sofa .\n")
    assert db.load_turtle(path, perspective="human-1") == 1
    assert db.objects("bottle-red", "isOn", perspective="human-1") == ["kitchen-table", "sofa"]
    assert db.objects("bottle-red", "isOn") == ["kitchen-table"]


# -- reentrancy ----------------------------------------------------------------------------------

def test_reentrant_changes_are_queued_fifo(db):
    log = []

    def first(event):
        log.append(("first", event.kind, event.object))
        if event.object == "sofa":
            db.add("bottle-blue", "isNear", "human-1")   # queued behind the current event
            db.add("bottle-blue", "isNear", "jido")

    def second(event):
        log.append(("second", event.kind, event.object))

    db.subscribe(first, subject="bottle-blue")
    db.subscribe(second, subject="bottle-blue")
    db.set("bottle-blue", "isOn", "sofa")
    assert log == [
        ("first", "removed", "coffee-table"), ("second", "removed", "coffee-table"),
        ("first", "added", "sofa"), ("second", "added", "sofa"),
        ("first", "added", "human-1"), ("second", "added", "human-1"),
        ("first", "added", "jido"), ("second", "added", "jido"),
    ]


def test_unsubscribe_and_subscribe_during_delivery(db):
    log = []
    later = []

    def once(event):
        log.append(event.object)
        db.unsubscribe(second)
        db.subscribe(later.append, predicate="isOn")

    db.subscribe(once, predicate="isOn")
    second = db.subscribe(log.append, predicate="isOn")
    db.add("cup-white", "isOn", "sofa")
    assert log == ["sofa"]
    assert later == []  # subscribed during the event: receives only later ones
    db.add("cup-white", "isOn", "kitchen-table")
    assert [e.object for e in later] == ["kitchen-table"]


def test_failing_callback_does_not_starve_others(db):
    events = []

    def broken(event):
        raise RuntimeError("monitor bug")

    db.subscribe(broken, predicate="isOn")
    db.subscribe(events.append, predicate="isOn")
    with pytest.raises(RuntimeError, match="monitor bug"):
        db.set("cup-white", "isOn", "sofa")
    assert [e.kind for e in events] == ["removed", "added"]
    events.clear()
    with pytest.raises(RuntimeError):
        db.add("cup-white", "isOn", "kitchen-table")
    assert len(events) == 1  # the database is not stuck in "delivering"


def test_ill_typed_literals_are_refused_quietly(write, caplog):
    path = write("typed.ttl", """\
        @prefix w: <http://shary.dev/world#> .
        @prefix xsd: <http://www.w3.org/2001/XMLSchema#> .
        w:bottle-yellow w:volumeMl 500 .
        w:bottle-blue w:volumeMl "a lot"^^xsd:integer .
    """)
    with pytest.raises(FileError) as caught:
        FactDatabase().load_turtle(path)
    [problem] = caught.value.problems
    assert (problem.line, problem.col) == (4, 26)
    assert "ill-typed literal" in problem.message
    assert not [record for record in caplog.records if record.name.startswith("rdflib")]


def test_subscription_to_one_kind_of_change(db):
    removed = recorder(db, subject="human-1", predicate="looksAt", kind="removed")
    db.add("human-1", "looksAt", "jido")
    db.remove("human-1", "looksAt", "jido")
    assert removed == [FactEvent("removed", "human-1", "looksAt", "jido", "robot")]
    with pytest.raises(ValueError, match="'added' or 'removed'"):
        db.subscribe(removed.append, kind="changed")


def test_a_derived_structure_is_kept_current_by_changes(db, write):
    """A derived structure (an index) sees every change of its predicates as it is made,
    also inside a subscriber's callback; other predicates never reach it; loading
    Turtle drops it, and the next call builds it again from the facts."""
    built: list[int] = []

    def build(triples):
        built.append(len(triples))
        return set(triples)

    def changed(found, added, s, p, o):
        (found.add if added else found.discard)((s, p, o))

    def cups():
        return db.derived("cups", "robot", build, ["isOn"], changed)

    db.add("cup", "type", "Cup")  # the robot's perspective is its own from now on
    start = cups()
    assert ("bottle-yellow", "isOn", "coffee-table") in start
    seen_in_callback = []
    db.subscribe(lambda event: seen_in_callback.append(
        ("cup", "isOn", "sofa") in cups()), subject="cup", predicate="isOn")
    db.set("bottle-yellow", "isOn", "sofa")
    db.add("cup", "isOn", "sofa")
    db.add("cup", "color", "red")
    assert cups() is start and len(built) == 1
    assert ("bottle-yellow", "isOn", "sofa") in start
    assert ("bottle-yellow", "isOn", "coffee-table") not in start
    assert not any(p == "color" for _, p, _ in start)
    assert seen_in_callback == [True]
    assert start == {t for t in db.triples("robot") if t[1] == "isOn"}
    db.load_turtle(write("more.ttl", "@prefix w: <http://shary.dev/world#> .\n"
                                     "w:mug w:isOn w:sofa .\n"), perspective="robot")
    again = cups()
    assert again is not start and ("mug", "isOn", "sofa") in again and len(built) == 2


def test_a_perspective_written_first_gets_its_own_derived_structure(db):
    """Before anything is written to it a perspective reads (and derives from) the
    a-priori facts; its first change makes its own copy, and its own structure."""
    def build(triples):
        return set(triples)

    def changed(found, added, s, p, o):
        (found.add if added else found.discard)((s, p, o))

    shared = db.derived("on", "alice", build, ["isOn"], changed)
    assert db.derived("on", "bob", build, ["isOn"], changed) is shared
    db.remove("bottle-yellow", "isOn", "coffee-table", perspective="alice")
    own = db.derived("on", "alice", build, ["isOn"], changed)
    assert own is not shared
    assert ("bottle-yellow", "isOn", "coffee-table") in shared
    assert ("bottle-yellow", "isOn", "coffee-table") not in own
