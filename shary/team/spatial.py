"""The spatial reasoning agent: spatial language resolved from a speaker's perspective.

HRI/OS's spatial reasoning agent (paper 002, Section 3.7) turns "point the
light at the bottom right corner of panel P3" into a point in the world.  A
request carries a speaker, an addressee, a command, a reference object, a
spatial relation and a frame of reference.  Three frames are used, as in the
paper:

* **ego** — an agent's (or an object's) own frame: forward is where it faces,
  right is its right.  "My left", "your left" (the addressee's ego frame) and
  "K-10's left" are ego frames.
* **referent** — a frame placed *on the reference object, facing the
  perspective holder*: the mirror of the holder's frame, for objects that
  have no front of their own ("left of box 1" said by an astronaut) and for
  the parts of a face seen by the holder ("the bottom right corner of P3").
  Its right is the holder's left, which is how "left of the box" ends up on
  the holder's left.
* **exo** — the world's own axes (north is +y, east is +x, up is +z).

A request names no frame unless it says so ("my", "your", "X's", a compass
word); it is then resolved **from the speaker's perspective**, as people
expect.  What the rover sees as "right" when it faces the panel from the other
side is the speaker's left: the corner is the same, the words differ.

The agent reasons on the poses in a :class:`~shary.facts.database.FactDatabase`
perspective (the facts perception writes: ``x``, ``y``, ``z``, ``yaw``;
``width``, ``height``, ``thickness`` and ``type``), never on the simulator, so
the same code runs on a real robot's perception.  When a reference cannot be
resolved with confidence it returns a :class:`Question` for the speaker
(which panel, which corner) instead of guessing: a light pointed at the wrong
corner costs more than a question.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field, replace
from typing import Any

Vec3 = tuple[float, float, float]

EDGE_ON = math.cos(math.radians(70))
"""Below this |cos| between the holder's right and an object's width axis, the holder
sees the object edge-on and cannot tell its left from its right: ask."""
INSET = 0.03
"""How far inside a face's edges its corners and edges are taken to be, in metres."""
BESIDE = 0.5
"""How far beyond an object's side a point "left of" it lies, in metres."""
COMPASS = {"north": (0.0, 1.0), "south": (0.0, -1.0), "east": (1.0, 0.0), "west": (-1.0, 0.0)}


class SpatialError(ValueError):
    """A request the agent cannot even read (its words, not the world, are at fault)."""


@dataclass(frozen=True)
class Thing:
    """An agent or an object as a perspective of the fact base knows it."""

    name: str
    x: float
    y: float
    z: float
    yaw: float
    """Where its front faces (radians from +x, counter-clockwise)."""
    kinds: frozenset[str] = frozenset()
    width: float = 0.0
    height: float = 0.0
    thickness: float = 0.0
    fronted: bool = False
    """Whether it has a front of its own (agents, panels): its ego frame means something."""

    @property
    def centre(self) -> Vec3:
        return (self.x, self.y, self.z)

    def forward(self) -> tuple[float, float]:
        return (math.cos(self.yaw), math.sin(self.yaw))

    def right(self) -> tuple[float, float]:
        return (math.sin(self.yaw), -math.cos(self.yaw))


@dataclass(frozen=True)
class Request:
    """A spatial request: the paper's parameter set (speaker, addressee, command,
    reference object, relation, perspective)."""

    speaker: str
    addressee: str
    command: str
    referent: str | None
    """The reference object's name, or None when only its kind was said ("the panel")."""
    kind: str | None
    """The reference object's kind when said ("panel"), lower case."""
    relation: str
    """``corner``, ``edge``, ``centre`` (a part of the object) or ``beside`` (a place near it)."""
    vertical: str | None = None
    """``top`` or ``bottom`` for parts."""
    side: str | None = None
    """``left``, ``right``, ``front``, ``back`` or a compass word."""
    perspective: str = "speaker"
    """Whose left and right: ``speaker`` (unless said otherwise), ``addressee`` ("your left",
    "as you see it"), ``own`` (the reference's own: "K-10's left") or ``world`` (compass)."""


@dataclass(frozen=True)
class Resolved:
    """A request resolved: the point in world (exo) coordinates and in the holder's frame."""

    request: Request
    referent: str
    point: Vec3
    local: Vec3
    """The point in the perspective holder's ego frame: (right, forward, up) in metres."""
    frame: str
    """The frame of reference used: ``ego``, ``referent`` or ``exo`` (Section 3.7)."""
    perspective: str
    """Whose point of view gave left and right (an agent's or object's name)."""
    says: str
    """One sentence for the log: what was understood."""


@dataclass(frozen=True)
class Question:
    """What the agent asks back when a reference is ambiguous."""

    request: Request | None
    to: str
    text: str
    choices: tuple[str, ...] = ()
    kind: str = "multiple-choice"
    answers: dict[str, Any] = field(default_factory=dict)
    """Each choice's meaning: the point it resolves to (or the referent it names)."""


# ---------------------------------------------------------------------- reading words

_PART = re.compile(
    r"(?:the\s+)?(?P<vertical>top|bottom|upper|lower)?\s*"
    r"(?P<side>left|right|north|south|east|west)?[- ]?\s*"
    r"(?P<part>corner|edge|centre|center|middle)\s+of\s+(?P<ref>.+)$")
_BESIDE = re.compile(
    r"(?:to\s+|on\s+)?(?:the\s+)?"
    r"(?P<side>left|right|north|south|east|west)(?:\s+side)?\s+of\s+(?P<ref>.+)$")
_FRONT = re.compile(r"(?P<side>in front of|behind)\s+(?P<ref>.+)$")
_OWN = re.compile(r"(?:to\s+|on\s+)?(?P<owner>my|your|[\w-]+'s)\s+"
                  r"(?P<side>left|right|front|back)(?:\s+side)?$")
_SEEN = re.compile(r"\s*,?\s+(?:as\s+(?P<who1>i|you)\s+see\s+it|from\s+(?P<who2>my|your)\s+"
                   r"(?:point\s+of\s+view|side|perspective))$")
_COMMAND = re.compile(
    r"^(?P<verb>point\s+(?:the\s+|your\s+)?(?:light|spotlight|lamp|camera)|shine\s+(?:the\s+)?"
    r"(?:light|spotlight)|light\s+up|look|move|go|drive|put|place|bring)\s*(?:at|to|on|up)?\s+")
_COMMANDS = {"point": "point-light", "shine": "point-light", "light": "point-light",
             "look": "look", "move": "move", "go": "move", "drive": "move",
             "put": "place", "place": "place", "bring": "place"}


def _command(verb: str) -> str:
    words = verb.split()
    if words[0] == "point" and words[-1] == "camera":
        return "look"
    return _COMMANDS[words[0]]


def _referent(text: str) -> tuple[str | None, str | None]:
    """(name, kind) of a reference: "panel P3" -> (P3, panel), "the panel" -> (None, panel),
    "P3" -> (P3, None), "me" -> ("me", None)."""
    words = text.strip().rstrip(".!?").split()
    if words and words[0] in ("the", "a"):
        words = words[1:]
    if not words:
        raise SpatialError("the request names no object")
    if len(words) == 1:  # a name, or a kind ("the panel"): the fact base tells which
        return words[0], None
    if len(words) == 2:
        return words[1], words[0].lower()
    raise SpatialError(f"cannot tell which object {' '.join(words)!r} is")


def parse(text: str, speaker: str, addressee: str) -> Request:
    """A request from words such as "point the light at the bottom right corner of panel
    P3", "move to the left of box-1", "move to my left", "go to K-10's right", "look at the
    east edge of P2", "… of box-1 as you see it".

    Names keep their case ("P3", "K-10"); everything else is read in lower case.
    Raises :class:`SpatialError` for words it cannot read.
    """
    said = " ".join(text.strip().rstrip(".!?").split())
    found = _COMMAND.match(said.lower())
    if found is None:
        raise SpatialError(f"no command I know in {text!r} (point the light, look, move, "
                           "place)")
    command = _command(found.group("verb"))
    rest = said[found.end():]
    perspective = "speaker"
    if seen := _SEEN.search(rest.lower()):
        perspective = "speaker" if (seen["who1"] or seen["who2"]) in ("i", "my") else "addressee"
        rest = rest[:seen.start()]
    low = rest.lower()
    if m := _PART.match(low):
        name, kind = _referent(rest[m.start("ref"):])
        part = {"center": "centre", "middle": "centre"}.get(m["part"], m["part"])
        vertical = {"upper": "top", "lower": "bottom"}.get(m["vertical"], m["vertical"])
        if part == "corner" and not (vertical and m["side"]):
            raise SpatialError("a corner needs two words: top or bottom, and left or right")
        if part == "edge" and bool(vertical) == bool(m["side"]):
            raise SpatialError("an edge is one of top, bottom, left or right")
        return Request(speaker, addressee, command, name, kind, part, vertical, m["side"],
                       "world" if m["side"] in COMPASS else perspective)
    if m := _OWN.match(low):
        owner = m["owner"]
        if owner in ("my", "your"):
            who = speaker if owner == "my" else addressee
            return Request(speaker, addressee, command, who, None, "beside", side=m["side"],
                           perspective="speaker" if owner == "my" else "addressee")
        name = rest[m.start("owner"):m.end("owner") - 2]
        return Request(speaker, addressee, command, name, None, "beside", side=m["side"],
                       perspective="own")
    if m := _FRONT.match(low):
        name, kind = _referent(rest[m.start("ref"):])
        side = "front" if m["side"] == "in front of" else "back"
        return Request(speaker, addressee, command, name, kind, "beside", side=side,
                       perspective=perspective)
    if m := _BESIDE.match(low):
        name, kind = _referent(rest[m.start("ref"):])
        side = m["side"]
        return Request(speaker, addressee, command, name, kind, "beside", side=side,
                       perspective="world" if side in COMPASS else perspective)
    raise SpatialError(f"cannot tell where {rest!r} is (say e.g. 'the bottom right corner of "
                       "panel P3' or 'the left of box-1')")


# ---------------------------------------------------------------------- the agent

def _number(facts: Any, name: str, predicate: str, perspective: str) -> float | None:
    values = facts.objects(name, predicate, perspective)
    return float(values[0]) if values and isinstance(values[0], (int, float)) else None


class SpatialReasoner:
    """Resolves spatial requests on the poses one perspective of the fact base holds."""

    def __init__(self, facts: Any, perspective: str = "robot"):
        self.facts = facts
        self.perspective = perspective

    # -- what the fact base says ------------------------------------------------------

    def thing(self, name: str) -> Thing | None:
        """``name`` as the perspective knows it, or None when its position is unknown."""
        p = self.perspective
        coords = [_number(self.facts, name, axis, p) for axis in ("x", "y", "z")]
        if any(c is None for c in coords):
            return None
        x, y, z = coords
        kinds = frozenset(str(k).lower() for k in self.facts.objects(name, "type", p))
        facing = _number(self.facts, name, "yaw", p)
        return Thing(name, x, y, z, facing or 0.0, kinds,
                     _number(self.facts, name, "width", p) or 0.0,
                     _number(self.facts, name, "height", p) or 0.0,
                     _number(self.facts, name, "thickness", p) or 0.0,
                     fronted=facing is not None)

    def of_kind(self, kind: str) -> list[str]:
        """Every thing of ``kind`` whose position is known, by name."""
        return sorted(str(s) for s, p, o in self.facts.triples(self.perspective)
                      if str(p) == "type" and str(o).lower() == kind
                      and self.thing(str(s)) is not None)

    # -- resolving ------------------------------------------------------------------

    def understand(self, text: str, speaker: str, addressee: str) -> Resolved | Question:
        """Read ``text`` and resolve it; words it cannot read get a free-text question back."""
        try:
            request = parse(text, speaker, addressee)
        except SpatialError as err:
            return Question(None, speaker, f"Sorry, I did not understand: {err}. Where do you "
                            "mean?", kind="free-text")
        return self.resolve(request)

    def resolve(self, request: Request) -> Resolved | Question:
        """The point a request means, or the question that would settle it."""
        speaker = self.thing(request.speaker)
        if speaker is None:
            return Question(request, request.speaker,
                            f"I do not know where {request.speaker} is: where are you?",
                            kind="free-text")
        chosen = self._which(request, speaker)
        if isinstance(chosen, Question):
            return chosen
        if request.relation == "beside":
            return self._beside(request, speaker, chosen)
        return self._part(request, speaker, chosen)

    def _which(self, request: Request, speaker: Thing) -> Thing | Question:
        """The reference object: named, or the one of its kind the speaker looks at."""
        name = request.referent
        if name == "me":
            name = request.speaker
        elif name == "you":
            name = request.addressee
        kind = request.kind
        if name is not None:
            found = self.thing(name)
            if found is not None and (kind is None or kind in found.kinds):
                return found
            if found is None and kind is None and self.of_kind(name.lower()):
                name, kind = None, name.lower()  # "the panel": a kind, not a name
        candidates = self.of_kind(kind) if kind else []
        if name is None:
            looked = [str(o) for o in self.facts.objects(request.speaker, "looksAt",
                                                         self.perspective)]
            seen = [c for c in candidates if c in looked]
            if len(seen) == 1:
                return self.thing(seen[0])  # type: ignore[return-value]
            if len(candidates) == 1:
                return self.thing(candidates[0])  # type: ignore[return-value]
        what = kind or "thing"
        if not candidates:
            return Question(request, request.speaker,
                            f"I know no {what}" + (f" called {name}" if name else "")
                            + ": which one do you mean?", kind="free-text")
        nearest = sorted(candidates, key=lambda c: _ground(self.thing(c), speaker))
        opening = (f"I know no {what} called {name}" if name is not None
                   else f"There are {len(candidates)} {what}s")
        return Question(request, request.speaker,
                        f"{opening}: which {what} do you mean: {_either(nearest)}?",
                        tuple(nearest), answers={c: c for c in nearest})

    def _holder(self, request: Request, speaker: Thing, ref: Thing) -> Thing | Question:
        """Whose point of view gives left and right."""
        if request.perspective == "addressee":
            addressee = self.thing(request.addressee)
            if addressee is None:
                return Question(request, request.speaker, f"I do not know where "
                                f"{request.addressee} is: left and right as seen by whom?",
                                kind="free-text")
            return addressee
        if request.perspective == "own":
            if not ref.fronted:
                return Question(request, request.speaker, f"{ref.name} has no front of its own"
                                ": left as seen from where?", kind="free-text")
            return ref
        return speaker

    def _beside(self, request: Request, speaker: Thing, ref: Thing) -> Resolved | Question:
        """A place next to an object (or to an agent, in its own frame)."""
        holder = self._holder(request, speaker, ref)
        if isinstance(holder, Question):
            return holder
        side = request.side or "front"
        if side in COMPASS:
            direction, frame = COMPASS[side], "exo"
        elif holder.name == ref.name:
            # "to my left", "K-10's right": the holder's own (ego) frame, from its heading
            direction, frame = _side_vector(holder.forward(), side), "ego"
        else:
            # the referent frame: on the object, facing the holder (a mirror of its frame)
            sight = _unit((ref.x - holder.x, ref.y - holder.y))
            if sight is None:
                return Question(request, request.speaker, f"You are at {ref.name}: which way "
                                "do you mean?", kind="free-text")
            facing_holder = (-sight[0], -sight[1])
            # the holder's left is the referent frame's right; its front faces the holder
            direction, frame = _side_vector(facing_holder, _mirror(side)), "referent"
        reach = max(ref.width, ref.thickness) / 2 + BESIDE
        point = (ref.x + reach * direction[0], ref.y + reach * direction[1], ref.z)
        return self._done(request, ref, point, holder, frame, f"{side} of {ref.name}")

    def _part(self, request: Request, speaker: Thing, ref: Thing) -> Resolved | Question:
        """A corner, an edge or the centre of an object's face, as the holder sees it."""
        holder = self._holder(request, speaker, ref)
        if isinstance(holder, Question):
            return holder
        frame = "exo" if request.side in COMPASS else "referent"
        width_axis = ref.right()
        normal = (width_axis[1], -width_axis[0])
        sight = _unit((ref.x - holder.x, ref.y - holder.y))
        if sight is None:
            sight = holder.forward()
        # the face seen by the holder: the one whose normal points back at it
        if normal[0] * sight[0] + normal[1] * sight[1] > 0:
            normal = (-normal[0], -normal[1])
        seen_right = (sight[1], -sight[0])  # the holder's right, looking at the object
        if frame == "exo":
            seen_right = COMPASS[request.side]  # type: ignore[index]
        cosine = seen_right[0] * width_axis[0] + seen_right[1] * width_axis[1]
        wants_side = request.side in ("left", "right") or request.side in COMPASS
        vertical = {"top": 1, "bottom": -1, None: 0}[request.vertical]
        depth = ref.thickness / 2 + 0.005  # on the surface, not inside it

        def corner(sign: int) -> Vec3:
            # on the face, just inside its edges: a light aimed at the very edge would
            # pass into the gap beside it
            half = max(0.0, ref.width / 2 - INSET) * sign
            rise = vertical * max(0.0, ref.height / 2 - INSET)
            return (ref.x + half * width_axis[0] + depth * normal[0],
                    ref.y + half * width_axis[1] + depth * normal[1], ref.z + rise)

        if not wants_side:
            return self._done(request, ref, corner(0), holder, frame,
                              f"the {request.vertical or ''} {request.relation} of {ref.name}")
        if frame != "exo" and abs(cosine) < EDGE_ON:
            # edge-on: left and right are not the holder's to tell; ask in world terms
            words = f"{request.vertical} " if request.vertical else ""
            choices = {f"the {words}{_compass(width_axis, s)} {request.relation}": corner(s)
                       for s in (1, -1)}
            return Question(request, request.speaker,
                            f"From where you are, {ref.name} is edge-on: which {words}"
                            f"{request.relation} of {ref.name} do you mean: "
                            f"{_either(list(choices))}?",
                            tuple(choices), answers=choices)
        # +1: the end of the width axis on the holder's right (or toward the compass word)
        toward = 1 if cosine > 0 else -1
        sign = -toward if request.side == "left" else toward
        named = " ".join(w for w in (request.vertical, request.side, request.relation) if w)
        return self._done(request, ref, corner(sign), holder, frame, f"the {named} of {ref.name}")

    def _done(self, request: Request, ref: Thing, point: Vec3, holder: Thing, frame: str,
              what: str) -> Resolved:
        """The answer, with the point also in the holder's ego frame."""
        dx, dy = point[0] - holder.x, point[1] - holder.y
        fx, fy = holder.forward()
        rx, ry = holder.right()
        local = (round(dx * rx + dy * ry, 6), round(dx * fx + dy * fy, 6),
                 round(point[2] - holder.z, 6))
        view = "the world's axes" if frame == "exo" else f"{holder.name}'s point of view"
        says = (f"{request.command} at {what}, seen from {view} ({frame} frame): "
                f"({point[0]:.2f}, {point[1]:.2f}, {point[2]:.2f})")
        return Resolved(request, ref.name, point, local, frame, holder.name, says)

    # -- as a team's software agent ------------------------------------------------

    def service(self, data: dict[str, Any]) -> dict[str, Any]:
        """The ``spatial`` service a team's software agent offers (HRI/OS's SRA).

        A query with ``words``, ``speaker`` and ``addressee`` gets back ``point`` (x, y,
        z in the world), the ``frame``, whose ``perspective`` and what was understood
        (``says``); or a ``question`` for the speaker (``to``, ``choices``, and
        ``answers``: each choice's point, or the object it names).  The speaker's
        choice of object comes back as ``referent``, which then stands for the object
        the words named."""
        words = str(data.get("words", ""))
        speaker, addressee = str(data.get("speaker", "")), str(data.get("addressee", ""))
        chosen = data.get("referent")
        if chosen:
            try:
                request = parse(words, speaker, addressee)
            except SpatialError as err:
                return {"question": str(err), "to": speaker, "choices": [], "answers": {},
                        "question_type": "free-text"}
            answer: Resolved | Question = self.resolve(replace(request, referent=str(chosen),
                                                               kind=None))
        else:
            answer = self.understand(words, speaker, addressee)
        if isinstance(answer, Resolved):
            return {"point": [round(v, 4) for v in answer.point], "frame": answer.frame,
                    "perspective": answer.perspective, "referent": answer.referent,
                    "says": answer.says}
        return {"question": answer.text, "to": answer.to, "choices": list(answer.choices),
                "answers": {k: [round(v, 4) for v in a] if isinstance(a, tuple) else a
                            for k, a in answer.answers.items()},
                "question_type": answer.kind}


# ---------------------------------------------------------------------- geometry

def _unit(v: tuple[float, float]) -> tuple[float, float] | None:
    n = math.hypot(*v)
    return None if n < 1e-6 else (v[0] / n, v[1] / n)


def _ground(thing: Thing | None, other: Thing) -> float:
    return math.inf if thing is None else math.hypot(thing.x - other.x, thing.y - other.y)


def _side_vector(forward: tuple[float, float], side: str) -> tuple[float, float]:
    fx, fy = forward
    return {"front": (fx, fy), "back": (-fx, -fy), "right": (fy, -fx),
            "left": (-fy, fx)}[side]


def _mirror(side: str) -> str:
    return {"left": "right", "right": "left", "front": "front", "back": "back"}[side]


def _compass(axis: tuple[float, float], sign: int) -> str:
    x, y = axis[0] * sign, axis[1] * sign
    return ("east" if x > 0 else "west") if abs(x) >= abs(y) else ("north" if y > 0 else "south")


def _either(words: list[str]) -> str:
    return words[0] if len(words) == 1 else f"{', '.join(words[:-1])} or {words[-1]}"
