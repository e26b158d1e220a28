"""The action ontology: inheritance, labels, parameters, names, and refusals at their line."""

from __future__ import annotations

import pytest

import planner
from shary.facts.database import FactDatabase
from shary.io.recipes import load_library
from shary.recognition.ontology import LabelPart, label_parts, load_action_ontology
from userfiles.errors import FileError


@pytest.fixture(scope="module")
def ontology():
    return load_action_ontology(FactDatabase())


def test_a_human_place_inherits_the_label_and_parameters_of_place(ontology):
    assert ontology.action_class("place", agent="Human") == "HumanPlaceAction"
    assert ontology.superclasses("HumanPlaceAction") == ("PlaceAction", "PhysicalAction",
                                                         "Action")
    assert ontology.label("HumanPlaceAction") == "{Agent} @Place {Pickable} on {Support}"
    assert [(p.role, p.role_class) for p in ontology.parameters("HumanPlaceAction")] == [
        ("Pickable", "Pickable"), ("Support", "Support")]
    assert ontology.agent_class("HumanPlaceAction") == "Human"
    assert ontology.agent_class("PlaceAction") == "Agent"


def test_names_choose_the_agent_specific_class_but_not_another_action(ontology):
    assert ontology.action_class("place", agent="Robot") == "RobotPlaceAction"
    assert ontology.action_class("place") == "PlaceAction"
    assert ontology.action_class("PutDown", agent="Human") == "HumanPlaceAction"
    assert ontology.action_class("dump", agent="Human") == "DumpAction"
    assert ontology.action_class("dump") != ontology.action_class("place")
    assert ontology.is_a("DumpAction", "PlaceAction")
    assert ontology.action_class("juggle") is None


def test_every_action_and_task_the_recipes_and_domains_name_has_a_labelled_class(ontology):
    library = load_library()
    names = set(library.atomic) | set(library.tasks)
    for domain in planner.builtin_domains():
        names |= set(planner.load_domain(domain).actions)
    missing = sorted(n for n in names if ontology.action_class(n) is None)
    assert not missing, f"no action class for {missing}"
    for name in names:
        assert ontology.label(ontology.action_class(name)).startswith("{Agent} @")


def test_the_ontology_is_in_the_fact_base(ontology):
    facts = FactDatabase()
    load_action_ontology(facts)
    assert facts.holds("HumanPlaceAction", "rdfs:subClassOf", "PlaceAction")
    rows = facts.select("SELECT ?c WHERE { ?c rdfs:subClassOf+ w:PlaceAction }")
    assert {"HumanPlaceAction", "RobotPlaceAction", "DumpAction"} <= {r["c"] for r in rows}


def test_label_parts_split_roles_verbs_and_text():
    assert label_parts("{Agent} @Place {Pickable} on {Support}") == [
        LabelPart("role", "Agent"), LabelPart("text", " "), LabelPart("verb", "Place"),
        LabelPart("text", " "), LabelPart("role", "Pickable"), LabelPart("text", " on "),
        LabelPart("role", "Support")]
    assert label_parts("a @ b {") == [LabelPart("text", "a @ b {")]


def test_a_task_specific_file_adds_classes_that_inherit(tmp_path):
    extra = tmp_path / "stack.ttl"
    extra.write_text("@prefix w: <http://shary.dev/world#> .\n"
                     "@prefix rdfs: <http://www.w3.org/2000/01/rdf-schema#> .\n"
                     "w:HumanPlaceCube rdfs:subClassOf w:HumanPlaceAction .\n")
    ontology = load_action_ontology(FactDatabase(), [extra])
    assert ontology.label("HumanPlaceCube") == "{Agent} @Place {Pickable} on {Support}"
    assert ontology.agent_class("HumanPlaceCube") == "Human"


def test_a_cycle_in_the_hierarchy_is_refused_at_its_line(tmp_path):
    extra = tmp_path / "cycle.ttl"
    extra.write_text("@prefix w: <http://shary.dev/world#> .\n"
                     "@prefix rdfs: <http://www.w3.org/2000/01/rdf-schema#> .\n"
                     "w:A rdfs:subClassOf w:B .\n"
                     "w:B rdfs:subClassOf w:A .\n")
    with pytest.raises(FileError) as caught:
        load_action_ontology(FactDatabase(), [extra])
    lines = {(p.file, p.line) for p in caught.value.problems}
    assert lines == {(str(extra), 3), (str(extra), 4)}
    assert "cycle" in str(caught.value)


def test_bad_turtle_is_refused_at_its_line(tmp_path):
    extra = tmp_path / "bad.ttl"
    extra.write_text("@prefix w: <http://shary.dev/world#> .\nw:A w:b \"unterminated .\n")
    with pytest.raises(FileError) as caught:
        load_action_ontology(FactDatabase(), [extra])
    assert caught.value.problems[0].line == 2
