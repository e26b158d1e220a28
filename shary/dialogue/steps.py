"""The steps the dialogue's recipes are made of: saying a sentence, turning the head."""

from __future__ import annotations

from typing import Any

from shary.kernel.recipes import Step, Term


def say(name: str, text: str, emit: str | None = None, after: tuple[str, ...] = (),
        emit_data: dict[str, Any] | None = None) -> Step:
    """A step that says ``text`` aloud (the ``speak`` atomic task), then emits ``emit``
    carrying ``emit_data``."""
    return Step(name, "speak", None, {"text": Term("const", text)}, None, after, emit,
                emit_data)


def look(name: str, target: str, after: tuple[str, ...] = (), emit: str | None = None,
         emit_data: dict[str, Any] | None = None) -> Step:
    """A step that turns the robot's head to ``target``, then emits ``emit`` carrying
    ``emit_data`` (what a sentence would have emitted, when it is not said to someone
    who does not attend)."""
    return Step(name, "look-at", None, {"target": Term("const", target)}, None, after, emit,
                emit_data)
