"""Communication acts and their types.

In SHARY an act is "defined by a name which characterizes the object of the
communication and by a type which defines the evolution of this object during
the interaction": ASK-TASK is performed as R-ACT (the robot asks), answered by
H-AGREE or H-DISAGREE (the human agrees or not).  Names are open (user files
add acts); types are the closed vocabulary below, generated from who performs
(robot or human) and how (performs the act, agrees, disagrees).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from functools import cache

from userfiles.reader import Reader, read

AGENT_KINDS = ("robot", "human")
_PREFIX = {"robot": "R", "human": "H"}
_KINDS = ("ACT", "AGREE", "DISAGREE")


@dataclass(frozen=True)
class ActType:
    """How an act evolves: who carries it out, and whether it is the act or an answer."""

    name: str
    performer: str
    kind: str


ACT_TYPES: dict[str, ActType] = {
    f"{_PREFIX[who]}-{kind}": ActType(f"{_PREFIX[who]}-{kind}", who, kind)
    for who in AGENT_KINDS for kind in _KINDS
}
"""R-ACT, R-AGREE, R-DISAGREE, H-ACT, H-AGREE, H-DISAGREE."""


def act_type(performer: str, kind: str = "ACT") -> ActType:
    """The type of an act carried out by an agent of kind ``performer``."""
    return ACT_TYPES[f"{_PREFIX[performer]}-{kind}"]


@dataclass(frozen=True)
class Act:
    """A communication act: a name, what it is for, and the answers it expects."""

    name: str
    doc: str = ""
    answers: tuple[str, ...] = ()
    source: str = "built-in"


@dataclass
class ActRegistry:
    """The acts a scheme may use: the built-in ones plus user-defined ones."""

    acts: dict[str, Act] = field(default_factory=dict)

    def extended(self, more: dict[str, Act]) -> ActRegistry:
        """A new registry with ``more`` added (the originals are left as they are)."""
        return ActRegistry({**self.acts, **more})

    def __contains__(self, name: object) -> bool:
        return name in self.acts

    def get(self, name: str) -> Act | None:
        return self.acts.get(name)

    def vocabulary(self) -> list[str]:
        """Every word an act event may be: act names and act types."""
        return [*self.acts, *ACT_TYPES]

    def is_act_word(self, word: str) -> bool:
        """True when ``word`` names an act or an act type (H-AGREE …)."""
        return word in self.acts or word in ACT_TYPES


def acts_from_data(data: dict, source: str) -> dict[str, Act]:
    """Acts from the already checked ``acts:`` mapping of a file."""
    return {name: Act(name, (spec or {}).get("doc", ""), tuple((spec or {}).get("answers", ())),
                      source)
            for name, spec in data.items()}


def load_acts(path: str | os.PathLike[str]) -> dict[str, Act]:
    """The acts defined in an acts file (``acts:`` at the top), read through the one
    pipeline (:func:`userfiles.reader.read`)."""
    from shary.io import schema

    def meaning(reader: Reader) -> dict[str, Act]:
        for name in reader.data["acts"]:
            if name in ACT_TYPES:
                reader.problem(("acts", name), f"{name!r} is an act type, not an act name",
                               key=True)
        return acts_from_data(reader.data["acts"], os.fspath(path))

    return read(path, schema.validator("acts"), meaning)


@cache
def builtin_acts() -> ActRegistry:
    """SHARY's task acts, from the built-in ``schemes/acts.yaml``."""
    from shary.builtin import find

    path = find("schemes", "acts")
    assert path is not None, "the built-in acts file is missing from the installation"
    return ActRegistry(load_acts(path))
