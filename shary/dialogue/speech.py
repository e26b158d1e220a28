"""What the robot says in an act: a ``say`` step of a recipe made into a sentence.

A recipe speaks in one of two ways (``recipes/core.yaml``):

* ``{do: say, with: {act: propose, about: "give-object({robot}, {object}, {partner})",
  to: $partner}}`` -- the sentence is generated: ``about`` names an action or
  task of the action ontology with its agent first and then its parameters
  in the ontology's order; its verbal label is conjugated for ``act`` (see
  :mod:`shary.dialogue.verbalize`) with the performing robot as speaker and
  ``to`` as addressee (``_`` for nobody in particular), and every object is
  named by a referring expression in the addressee's perspective of the fact
  base, or in the robot's where the addressee's holds nothing of it ("Shall I
  give the yellow bottle to you?");
* ``{do: speak, with: {text: "Thank you for the {object}."}}`` -- the
  recipe's own sentence, said as written: the override for what no action
  label says (thanks, reasons, greetings).

The supervisor turns a ``say`` request into a ``speak`` request with the
generated text (:meth:`Speech.say`), so executors only ever speak text and
the context log holds the words that were said.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Mapping
from typing import Any

from shary.dialogue.reg import Referrer
from shary.dialogue.verbalize import ACTS, verbalize
from userfiles.schema import did_you_mean

__all__ = ["SAY_PARAMS", "Speech", "check_say", "core_ontology", "parse_about"]

SAY_PARAMS = ("act", "about", "to")
"""The parameters of the ``say`` atomic task."""

_ABOUT = re.compile(r"\s*([\w.-]+)\s*\(([^()]*)\)\s*")
_PLACEHOLDER = re.compile(r"\{([^{}]*)\}")


def parse_about(text: str) -> tuple[str, list[str]]:
    """``"give-object(jido, yellow-bottle, alice)"`` -> ("give-object", [jido, …])."""
    match = _ABOUT.fullmatch(str(text))
    if match is None:
        raise ValueError(f"say: 'about' must read action(agent, param, ...), not {text!r}")
    args = [a.strip() for a in match.group(2).split(",")] if match.group(2).strip() else []
    unbound = [a for a in args if not a or "{" in a]
    if not args or unbound:
        raise ValueError(f"say: {text!r} has an unbound or empty argument; the agent comes "
                         "first, then the action's parameters")
    return match.group(1), args


def check_say(args: Mapping[str, Any], params: set[str]) -> list[tuple[str, str]]:
    """What is wrong with a ``say`` step's arguments as a recipe writes them (values
    before substitution; ``params`` are the names ``{name}`` may use): (argument,
    message) pairs, so that ``shary validate`` refuses the step at its line."""
    problems: list[tuple[str, str]] = []
    act = args.get("act")
    if isinstance(act, str) and not act.startswith("$") and act not in ACTS:
        problems.append(("act", f"say: unknown act {act!r}; one of: {', '.join(ACTS)}"))
    about = args.get("about")
    if not isinstance(about, str) or about.startswith("$"):
        return problems
    unknown = [n for n in _PLACEHOLDER.findall(about) if n not in params]
    if unknown:
        return problems + [("about", f"say: {{{unknown[0]}}} is not a parameter here"
                                     f"{did_you_mean(unknown[0], sorted(params))}; "
                                     f"parameters: {', '.join(sorted(params))}")]
    filled = _PLACEHOLDER.sub(lambda m: m.group(1), about)
    try:
        name, values = parse_about(filled)
        _action(core_ontology(), name, values)
    except ValueError as err:
        problems.append(("about", str(err).replace(repr(filled), repr(about))))
    return problems


def _action(ontology: Any, name: str, values: list[str]) -> tuple[str, list[str]]:
    """The class and parameter roles of the action ``name`` called with ``values``."""
    cls = ontology.action_class(name)
    if cls is None or not ontology.label(cls):
        raise ValueError(f"say: the action ontology has no label for {name!r}")
    roles = [p.role for p in ontology.parameters(cls)]
    if len(values) != len(roles) + 1:
        raise ValueError(f"say: {name} takes the agent and {', '.join(roles) or 'nothing'}"
                         f" ({len(roles) + 1} arguments), not {len(values)}")
    return cls, roles


@functools.cache
def core_ontology() -> Any:
    """The core action ontology, loaded once into a fact base of its own (it is a-priori
    knowledge shared by every run; a run's facts are not filled with it)."""
    from shary.facts.database import FactDatabase
    from shary.recognition.ontology import load_action_ontology

    return load_action_ontology(FactDatabase())


class Speech:
    """Generates the sentences of ``say`` steps over one fact base (see the module)."""

    def __init__(self, facts: Any, ontology: Any = None):
        self.facts = facts
        self.ontology = ontology

    def say(self, args: Mapping[str, Any], speaker: str, perspective: str | None = None) -> str:
        """The sentence of a ``say`` request's ``args`` spoken by ``speaker``; a
        ValueError says what is wrong with them.

        Objects are described in ``to``'s perspective (``perspective``, if given).
        """
        act = str(args.get("act"))
        if act not in ACTS:
            raise ValueError(f"say: unknown act {act!r}; one of: {', '.join(ACTS)}")
        name, values = parse_about(args.get("about", ""))
        ontology = self.ontology or core_ontology()
        cls, roles = _action(ontology, name, values)
        addressee = args.get("to")
        addressee = str(addressee) if addressee not in (None, "", "_") else None
        agents = {t for t in values if self._is_agent(t)}
        seen_by = perspective or addressee or "robot"
        listener = Referrer.for_perspective(self.facts, seen_by)
        scene = listener if seen_by == "robot" else Referrer.for_perspective(self.facts, "robot")

        people = {speaker: "me", **({addressee: "you"} if addressee else {})}
        # The things the sentence relates an object to: the action's other things, and
        # its agent once it is done ("I picked up the red cube": the one in my hand).
        implied = values[1:] + (values[:1] if act == "inform-done" else [])

        def refer(thing: str) -> str:
            # What the listener's perspective says nothing of (the robot has no estimate
            # of what they know of it) is described from the scene the robot perceives,
            # which they share, rather than by its identifier.  The sentence's other
            # things are named anyway: relations to them go unsaid (see Referrer.describe).
            known = listener.knows(thing) or not scene.knows(thing)
            return (listener if known else scene).describe(
                thing, by_name=True, implied=implied).text(people=people)

        bindings = {"Agent": values[0], **dict(zip(roles, values[1:], strict=True))}
        return verbalize(ontology.label(cls), bindings, act, speaker=speaker,
                         addressee=addressee, agents=agents, refer=refer)

    def _is_agent(self, thing: str) -> bool:
        types = set(map(str, self.facts.objects(thing, "type")))
        return bool(types & {"Agent", "Human", "Robot"})
