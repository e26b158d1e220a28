"""The action ontology: classes of actions with inheritance, verbal labels, parameters.

JAHRVIS keeps its action classes in Ontologenius so that *human_place_cube*
and *robot_place_cube* both inherit what *PlaceAction* says, above all the
label used to talk about them (Section VI-A.1.a).  Here the classes are RDF in
the fact base's a-priori graph, written in Turtle (``actions.ttl`` beside this
module, read with :mod:`shary.facts.turtle`, so a mistake is refused at its line),
and :class:`ActionOntology` answers the few questions the engine asks of them,
from an index built once when the ontology is loaded (the ontology is a-priori
knowledge: it does not change during a run, and questions are asked per
recognized action or per sentence, so they must not cost a SPARQL query).

The API (used by recognition, and by verbalization to say what an agent did)::

    ontology = load_action_ontology(facts)            # actions.ttl + extra Turtle files
    ontology.action_class("place", agent="Human")     # "HumanPlaceAction"
    ontology.label("HumanPlaceAction")                 # "{Agent} @Place {Pickable} on {Support}"
    ontology.parameters("HumanPlaceAction")            # (Parameter(1, "Pickable", "Pickable"),
                                                       #  Parameter(2, "Support", "Support"))
    ontology.agent_class("HumanPlaceAction")           # "Human"
    ontology.superclasses("HumanPlaceAction")          # ("PlaceAction", "PhysicalAction", "Action")
    ontology.is_a("HumanPlaceAction", "PlaceAction")   # True

Names are the fact base's short names (``"PlaceAction"`` is ``w:PlaceAction``).
A class inherits its label, agent class and parameters from its nearest
superclass that states them (breadth-first, superclasses in name order, so
the answer never depends on hashing).  The label grammar is JAHRVIS's:
``{Role}`` is a parameter (or ``{Agent}``) filled when speaking, ``@Verb`` a
verb to conjugate; :func:`label_parts` splits a label into those pieces.
"""

from __future__ import annotations

import os
import re
from collections import deque
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

from rdflib import RDFS, Literal, URIRef

from shary.facts.database import FactDatabase
from userfiles.errors import FileError, Problem

__all__ = ["ACTIONS_TTL", "ActionOntology", "LabelPart", "Parameter", "label_parts",
           "load_action_ontology"]

ACTIONS_TTL = Path(__file__).with_name("actions.ttl")
"""The core action ontology, shipped with the package."""


class Parameter(NamedTuple):
    """One parameter of an action class: its place in the argument list (from 1),
    the role name labels and action models use, and the class of what fills it."""

    position: int
    role: str
    role_class: str


class LabelPart(NamedTuple):
    """A piece of a verbal label: ``kind`` is "text", "role" ({Role}) or "verb" (@Verb)."""

    kind: str
    text: str


_LABEL_PART = re.compile(r"\{(?P<role>[^{}]+)\}|@(?P<verb>\w+)|(?P<text>[^{@]+|[{@])")


def label_parts(label: str) -> list[LabelPart]:
    """Split a verbal label into text, roles and verbs, in order:
    ``"{Agent} @Place {Pickable}"`` -> role Agent, text " ", verb Place, text " ",
    role Pickable.  A stray ``{`` or ``@`` is text."""
    parts: list[LabelPart] = []
    for match in _LABEL_PART.finditer(label):
        if match["role"] is not None:
            parts.append(LabelPart("role", match["role"].strip()))
        elif match["verb"] is not None:
            parts.append(LabelPart("verb", match["verb"]))
        elif parts and parts[-1].kind == "text":
            parts[-1] = LabelPart("text", parts[-1].text + match["text"])
        else:
            parts.append(LabelPart("text", match["text"]))
    return parts


@dataclass
class _Class:
    """What one class states itself (inheritance is resolved on demand)."""

    supers: tuple[str, ...] = ()
    label: str | None = None
    agent_class: str | None = None
    parameters: tuple[Parameter, ...] | None = None
    names: tuple[str, ...] = ()


class ActionOntology:
    """Action classes, their inheritance, labels and parameters (see the module's
    documentation for the API and the inheritance rule)."""

    def __init__(self, classes: dict[str, _Class]):
        self._classes = classes
        self._ancestors: dict[str, tuple[str, ...]] = {}
        self._by_name: dict[str, list[str]] = {}
        for cls in sorted(classes):
            for name in classes[cls].names:
                self._by_name.setdefault(name, []).append(cls)

    @classmethod
    def from_facts(cls, facts: FactDatabase) -> ActionOntology:
        """The ontology held by the fact base's a-priori graph (loaded Turtle)."""
        graph = facts.dataset.default_graph
        classes: dict[str, _Class] = {}

        def named(term: object) -> str | None:
            name = facts.name(term) if isinstance(term, URIRef) else None
            return name if isinstance(name, str) else None

        def entry(term: object) -> _Class | None:
            name = named(term)
            return None if name is None else classes.setdefault(name, _Class())

        w = facts.term
        for s, _, o in graph.triples((None, RDFS.subClassOf, None)):
            child, parent = entry(s), named(o)
            if child is not None and parent is not None:
                entry(o)
                child.supers = tuple(sorted({*child.supers, parent}))
        for s, _, o in graph.triples((None, RDFS.label, None)):
            found = entry(s) if named(s) in classes else None
            if found is not None and isinstance(o, Literal) and o.language in (None, "en"):
                if found.label is None or o.language == "en":
                    found.label = str(o)
        for s, _, o in graph.triples((None, w("agentClass"), None)):
            found, agent = entry(s), named(o)
            if found is not None and agent is not None:
                found.agent_class = agent
        for s, _, o in graph.triples((None, w("actionName"), None)):
            found = entry(s)
            if found is not None and isinstance(o, Literal):
                found.names = tuple(sorted({*found.names, str(o)}))
        for s, _, node in graph.triples((None, w("parameter"), None)):
            found = entry(s)
            position = graph.value(node, w("position"))
            role = graph.value(node, w("role"))
            role_class = named(graph.value(node, w("roleClass")))
            if found is None or not isinstance(position, Literal) or role is None:
                continue
            parameter = Parameter(int(position.toPython()), str(role), role_class or "Entity")
            found.parameters = tuple(sorted({*(found.parameters or ()), parameter}))
        return cls(classes)

    # -- questions -------------------------------------------------------------------------------

    def classes(self) -> list[str]:
        """Every class the ontology knows, in name order."""
        return sorted(self._classes)

    def __contains__(self, cls: object) -> bool:
        return cls in self._classes

    def superclasses(self, cls: str) -> tuple[str, ...]:
        """Every superclass of ``cls``, nearest first (breadth-first); () for a root."""
        found = self._ancestors.get(cls)
        if found is None:
            seen: dict[str, None] = {}
            queue = deque(self._known(cls).supers)
            while queue:
                parent = queue.popleft()
                if parent not in seen:
                    seen[parent] = None
                    queue.extend(self._classes.get(parent, _Class()).supers)
            found = self._ancestors[cls] = tuple(seen)
        return found

    def is_a(self, cls: str, ancestor: str) -> bool:
        """Whether ``cls`` is ``ancestor`` or inherits from it."""
        return cls == ancestor or ancestor in self.superclasses(cls)

    def label(self, cls: str) -> str | None:
        """The verbal label of ``cls``, its own or inherited; None if no class states one."""
        return self._inherited(cls, "label")

    def agent_class(self, cls: str) -> str:
        """The class of agent performing ``cls`` (own or inherited; "Agent" by default)."""
        return self._inherited(cls, "agent_class") or "Agent"

    def parameters(self, cls: str) -> tuple[Parameter, ...]:
        """The parameters of ``cls`` in position order, its own or inherited."""
        return self._inherited(cls, "parameters") or ()

    def action_class(self, name: str, agent: str | None = None) -> str | None:
        """The class a recipe, executor, planner domain or action model means by
        ``name`` (``"place"``, ``"PutDown"``, or a class name itself).

        With ``agent`` (an agent class: "Human", "Robot"), the most specific
        subclass of that class whose agent class fits is chosen: ``place``
        for a Human is ``HumanPlaceAction`` when the ontology has one, else
        ``PlaceAction`` (a subclass with a name of its own, as ``DumpAction``,
        is another action).  None when nothing in the ontology has that name.
        """
        candidates = self._by_name.get(name) or ([name] if name in self._classes else [])
        if not candidates:
            return None
        base = candidates[0]
        if agent is None:
            return base
        # the same action done by a kind of agent: subclasses that are not named
        # otherwise (DumpAction is a PlaceAction but is not what "place" means)
        fitting = [cls for cls in self._classes
                   if self.is_a(cls, base) and self.is_a(agent, self.agent_class(cls))
                   and (cls == base or not self._classes[cls].names
                        or name in self._classes[cls].names)]
        if not fitting:
            return base
        deepest = max(len(self.superclasses(cls)) for cls in fitting)
        return min(cls for cls in fitting if len(self.superclasses(cls)) == deepest)

    # -- inside ----------------------------------------------------------------------------------

    def _known(self, cls: str) -> _Class:
        try:
            return self._classes[cls]
        except KeyError:
            raise KeyError(f"{cls!r} is not a class of the action ontology") from None

    def _inherited(self, cls: str, attribute: str):  # noqa: ANN202 - the attribute's own type
        value = getattr(self._known(cls), attribute)
        if value is not None:
            return value
        for parent in self.superclasses(cls):
            value = getattr(self._classes.get(parent, _Class()), attribute)
            if value is not None:
                return value
        return None


def load_action_ontology(facts: FactDatabase,
                         extra: list[str | os.PathLike[str]] = ()) -> ActionOntology:
    """Load the core ontology and any extra Turtle files (a task's own classes) into the
    fact base's a-priori graph, and index them.

    Raises FileError at the offending line for a file that is not Turtle, and
    for a class hierarchy with a cycle (``A subClassOf B``, ``B subClassOf A``):
    inheritance would have no nearest superclass.
    """
    files = [os.fspath(path) for path in (ACTIONS_TTL, *extra)]
    for file in files:
        facts.load_turtle(file)
    ontology = ActionOntology.from_facts(facts)
    cyclic = [cls for cls in ontology.classes() if cls in ontology.superclasses(cls)]
    if cyclic:
        raise FileError([_where_stated(files, cls, "rdfs:subClassOf",
                                       f"the class hierarchy has a cycle through {cls}: "
                                       "a class cannot inherit from itself")
                         for cls in cyclic])
    return ontology


def _where_stated(files: list[str], cls: str, word: str, message: str) -> Problem:
    """A problem at the first line of the loaded files that names ``cls`` with ``word``
    (the file's first line if none does: the statement may be spread over lines)."""
    pattern = re.compile(rf"\b{re.escape(cls)}\b.*{re.escape(word)}")
    for file in reversed(files):
        for number, line in enumerate(Path(file).read_text(encoding="utf-8").splitlines(), 1):
            found = pattern.search(line)
            if found:
                return Problem(file, number, found.start() + 1, message)
    return Problem(files[-1], 1, 1, message)
