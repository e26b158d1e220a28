"""The steps the dialogue's recipes are made of: saying a sentence, turning the head."""

from __future__ import annotations

from shary.kernel.recipes import Step, Term


def say(name: str, text: str, emit: str | None = None, after: tuple[str, ...] = ()) -> Step:
    """A step that says ``text`` aloud (the ``speak`` atomic task)."""
    return Step(name, "speak", None, {"text": Term("const", text)}, None, after, emit)


def look(name: str, target: str, after: tuple[str, ...] = ()) -> Step:
    """A step that turns the robot's head to ``target``."""
    return Step(name, "look-at", None, {"target": Term("const", target)}, None, after)
