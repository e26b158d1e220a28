"""Safe, located YAML: every value of a user's file keeps its line and column.

PyYAML's ``safe_load`` throws the positions away and expands aliases without
limit.  Here a file goes through three gates before anything else sees it:

1. bytes: at most :data:`MAX_BYTES`, valid UTF-8, not empty;
2. the event stream (PyYAML's parser is iterative, so hostile nesting cannot
   overflow the stack here): nesting depth at most :data:`MAX_DEPTH`, one
   document, no tag outside YAML's core schema (nothing is ever constructed
   from a tag), and the format's size limits (a scenario's ``people:`` at
   most 50): a mapping of ten thousand entries is refused at its key after
   reading its 51st, before any node is built;
3. the node graph, converted to plain ``dict``/``list``/scalars while counting
   expanded nodes, so an alias bomb stops at :data:`MAX_NODES` instead of
   eating the memory; duplicate keys, and numbers that are not finite or larger
   than :data:`MAX_MAGNITUDE`, are recorded as problems (the value is kept so
   that checking can go on and report everything at once).  Every number of
   every format is thus finite and bounded by construction: a JSON Schema's
   ``maximum`` cannot catch NaN, which compares false with everything.

The result, :class:`Located`, maps every path (a tuple of keys and indices) to
the position of its value and of its key, which is what turns a JSON Schema
error or a meaning check into ``FILE:LINE:COL: error: …``.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, NoReturn

import yaml
from yaml.constructor import SafeConstructor

from userfiles.errors import FileError, Problem

MAX_BYTES = 1024 * 1024
"""Largest file accepted (1 MiB): a scheme of a thousand states is about 100 KB."""
MAX_DEPTH = 64
"""Deepest nesting of mappings and sequences, aliases expanded."""
MAX_NODES = 200_000
"""Most values a document may expand to, aliases expanded (stops alias bombs)."""
MAX_MAGNITUDE = 1e15
"""Largest number (in absolute value) a file may hold: far beyond any duration, count,
cost or coordinate that means something, and exact as a float."""

Path = tuple[Any, ...]
Mark = tuple[int, int]
Sizes = Mapping[Path, int]
"""Most entries of the mapping or list at a path of keys (see :func:`load_text`)."""

_SafeLoader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
"""libyaml's parser when PyYAML was built with it: about ten times faster on big files
(a 600 KB scenario parses in a fraction of a second instead of seconds)."""


class _Loader(_SafeLoader):  # type: ignore[misc, valid-type]
    """PyYAML's safe loader with YAML 1.2 booleans: only true and false.

    Under YAML 1.1, ``on``, ``off``, ``yes`` and ``no`` are booleans, so a
    parameter named ``on`` (put the object *on* the table) or a person named
    ``No`` would silently become ``True``/``False``.
    """


_Loader.yaml_implicit_resolvers = {
    first: [(tag, regexp) for tag, regexp in resolvers if tag != "tag:yaml.org,2002:bool"]
    for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
}
_Loader.add_implicit_resolver("tag:yaml.org,2002:bool",
                              re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"),
                              list("tTfF"))

_SafeDumper = getattr(yaml, "CSafeDumper", yaml.SafeDumper)


class _Dumper(_SafeDumper):  # type: ignore[misc, valid-type]
    """PyYAML's safe dumper (libyaml's emitter when there) that quotes a string only
    where :class:`_Loader` would read something else: ``on:`` stays plain, as every
    scheme writes it, where YAML 1.1's rules would write ``'on':``."""


_Dumper.yaml_implicit_resolvers = _Loader.yaml_implicit_resolvers


def dump(data: Any) -> str:
    """``data`` as YAML text that :func:`load_text` reads back as ``data``: keys in their
    order, Unicode as is, lines up to 100 characters."""
    return yaml.dump(data, Dumper=_Dumper, sort_keys=False, allow_unicode=True, width=100)


_CORE_TAGS = {
    "tag:yaml.org,2002:" + name
    for name in ("str", "int", "float", "bool", "null", "map", "seq")
}
_PLAIN_SCALARS = {
    "tag:yaml.org,2002:" + name for name in ("null", "bool", "int", "float", "str")
}


@dataclass
class Located:
    """A loaded YAML document with the position of every value and key."""

    file: str
    data: Any
    marks: dict[Path, Mark] = field(default_factory=dict)
    key_marks: dict[Path, Mark] = field(default_factory=dict)
    inline: dict[Path, int] = field(default_factory=dict)
    """For each string written on one line: how many characters (a quote) come before
    its text, so that a position inside the text (an expression's error) is exact."""
    problems: list[Problem] = field(default_factory=list)
    """Problems that did not stop loading (a duplicate key keeps its first value):
    the file's checker reports them with its own, so that all come at once."""

    def at(self, path: Path) -> Mark:
        """Position of the value at ``path``, or of its nearest located ancestor."""
        path = tuple(path)
        while path not in self.marks and path:
            path = path[:-1]
        return self.marks.get(path, (1, 1))

    def key_at(self, path: Path) -> Mark:
        """Position of the key that introduces ``path`` (falls back on the value)."""
        return self.key_marks.get(tuple(path)) or self.at(path)

    def problem(self, path: Path, message: str, *, key: bool = False) -> Problem:
        line, col = self.key_at(path) if key else self.at(path)
        return Problem(self.file, line, col, message)

    def problem_inside(self, path: Path, offset: int, message: str) -> Problem:
        """A problem ``offset`` characters into the string at ``path`` (at the string's
        start when it spans lines or holds escapes, where columns would not add up)."""
        line, col = self.at(path)
        before = self.inline.get(tuple(path))
        return Problem(self.file, line, col + before + offset if before is not None else col,
                       message)


@dataclass(frozen=True)
class Outline:
    """What the event pass learns of a document without building it."""

    keys: tuple[str, ...] | None
    """Its top-level keys (None when the document is not a mapping)."""
    empty: bool = False
    """Whether it holds no value at all (only comments or blank lines)."""
    mark: Mark = (1, 1)
    """Where its value starts (after leading comments)."""


def read_text(path: str | os.PathLike[str], *, max_bytes: int = MAX_BYTES) -> str:
    """Read a user's file as UTF-8 text, refusing huge, binary or empty files."""
    name = os.fspath(path)
    try:
        size = os.stat(name).st_size
        if size > max_bytes:
            raise FileError([Problem(name, 1, 1, f"file is {size} bytes; the limit is "
                                     f"{max_bytes} bytes")])
        with open(name, "rb") as handle:
            raw = handle.read(max_bytes + 1)
    except OSError as err:
        raise FileError([Problem(name, 1, 1, f"cannot read file: {err.strerror}")]) from None
    if len(raw) > max_bytes:
        raise FileError([Problem(name, 1, 1, f"file is larger than {max_bytes} bytes")])
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        before = raw[: err.start].decode("utf-8-sig")
        raise FileError([Problem(name, *_mark(before, len(before)),
                                 f"not UTF-8 text (byte 0x{raw[err.start]:02x})")]) from None
    if "\x00" in text:
        raise FileError([Problem(name, *_mark(text, text.index("\x00")),
                                 "NUL character: this is not a text file")])
    return text


_EMPTY = "empty file: expected a YAML mapping"

_BREAKS = re.compile(r"\r\n|[\r\n\x85\u2028\u2029]")
"""The line breaks YAML counts lines by (so do its marks, so must ours)."""


def _mark(text: str, at: int) -> Mark:
    """Line and column (from 1) of ``text[at]``, lines counted as YAML counts them."""
    breaks = list(_BREAKS.finditer(text, 0, at))
    start = breaks[-1].end() if breaks else 0
    return len(breaks) + 1, at - start + 1


def load_file(path: str | os.PathLike[str], *, sizes: Sizes | None = None) -> Located:
    """Load one YAML file safely, with positions (see the module's docstring)."""
    return load_text(read_text(path), os.fspath(path), sizes=sizes)


def outline(path: str | os.PathLike[str]) -> Outline:
    """The top-level keys of a YAML file, through the first two gates only (no node is
    built): enough to tell what kind of file it is before reading it with its limits."""
    text = read_text(path)
    found = _check_events(text, os.fspath(path), {})
    if found.empty:
        raise FileError([Problem(os.fspath(path), 1, 1, _EMPTY)])
    return found


def load_text(text: str, file: str = "<string>", *, sizes: Sizes | None = None) -> Located:
    """Load YAML text safely, with positions; raise :class:`FileError` when refused.

    ``sizes`` maps paths of keys from the root (``("people",)``) to the most entries
    the mapping or list there may have; they are enforced during the event pass."""
    if len(text.encode("utf-8", "surrogatepass")) > MAX_BYTES:
        raise FileError([Problem(file, 1, 1, f"text is larger than {MAX_BYTES} bytes")])
    _check_events(text, file, sizes or {})
    try:
        node = yaml.compose(text, Loader=_Loader)
    except yaml.YAMLError as err:
        raise FileError([_yaml_problem(err, file, text)]) from None
    if node is None:
        raise FileError([Problem(file, 1, 1, _EMPTY)])
    located = Located(file, None)
    converter = _Converter(located)
    located.data = converter.convert(node, ())
    located.problems = converter.problems
    return located


def _yaml_problem(err: yaml.YAMLError, file: str, text: str) -> Problem:
    mark = getattr(err, "problem_mark", None) or getattr(err, "context_mark", None)
    line, col = (mark.line + 1, mark.column + 1) if mark is not None else (1, 1)
    line, col = _within(text, line, col)
    what = getattr(err, "problem", None) or str(err)
    if what.startswith("exceeded maximum nesting depth"):
        # libyaml 0.2.5's own limit (PyYAML 6.0.4 on), met while it scans ahead of the
        # events that would have met ours: the same refusal in our words
        return Problem(file, line, col, f"nesting deeper than {MAX_DEPTH} levels")
    context = getattr(err, "context", None)
    message = f"YAML syntax: {what}" + (f" ({context})" if context else "")
    return Problem(file, line, col, message)


def _within(text: str, line: int, col: int) -> Mark:
    """A position the file has: PyYAML puts "end of stream" on the line after the last
    one when the file ends with a newline; an editor shows the end of the last line."""
    lines = _BREAKS.split(text)
    if lines[-1] == "" and len(lines) > 1:
        lines.pop()  # a final line break does not open a line an editor shows
    if line > len(lines):
        return len(lines), len(lines[-1]) + 1
    return line, min(col, len(lines[line - 1]) + 1)


def _check_events(text: str, file: str, sizes: Sizes) -> Outline:
    """The event pass: depth, documents, tags and the size limits of ``sizes``, checked
    before any node is built, so a huge mapping is refused at its key after reading just
    past its limit.  Returns the document's outline (its top-level keys)."""
    frames: list[_Frame] = []
    keys: list[str] | None = None
    documents = 0
    empty = True
    root: Mark = (1, 1)
    try:
        for event in yaml.parse(text, Loader=_Loader):
            tag = getattr(event, "tag", None)
            if tag is not None and tag != "!" and tag not in _CORE_TAGS:
                _refuse(file, event, f"tag {tag!r} is not allowed: files are data, "
                                     "nothing is constructed from a tag")
            if isinstance(event, _NODE_EVENTS):
                if empty:
                    root = (event.start_mark.line + 1, event.start_mark.column + 1)
                empty = False
                path = _entered(frames, event, file)
                if not frames and isinstance(event, yaml.MappingStartEvent):
                    keys = []
                elif len(frames) == 1 and keys is not None and frames[0].keys_next is False \
                        and isinstance(event, yaml.ScalarEvent):
                    keys.append(event.value)
                if isinstance(event, yaml.MappingStartEvent | yaml.SequenceStartEvent):
                    if len(frames) >= MAX_DEPTH:
                        _refuse(file, event, f"nesting deeper than {MAX_DEPTH} levels")
                    mapping = isinstance(event, yaml.MappingStartEvent)
                    frames.append(_Frame(path, sizes.get(path) if path is not None else None,
                                         frames[-1].key_mark if frames else (1, 1),
                                         True if mapping else None))
            elif isinstance(event, yaml.MappingEndEvent | yaml.SequenceEndEvent):
                frames.pop()
            elif isinstance(event, yaml.DocumentStartEvent):
                documents += 1
                if documents > 1:
                    _refuse(file, event, "more than one YAML document in the file")
    except yaml.YAMLError as err:
        raise FileError([_yaml_problem(err, file, text)]) from None
    return Outline(None if keys is None else tuple(keys), empty, root)


_NODE_EVENTS = (yaml.ScalarEvent, yaml.AliasEvent, yaml.MappingStartEvent,
                yaml.SequenceStartEvent)


@dataclass
class _Frame:
    """An open mapping or sequence during the event pass."""

    path: Path | None
    """Its keys from the root, while every ancestor is a mapping (None below a list)."""
    limit: int | None
    """Most entries it may have (from the schema's ``maxProperties``/``maxItems``)."""
    mark: Mark
    """Where to blame it: the key that introduces it."""
    keys_next: bool | None
    """For a mapping, whether the next node is a key; None for a sequence."""
    count: int = 0
    key: str | None = None
    key_mark: Mark = (1, 1)


def _entered(frames: list[_Frame], event: yaml.Event, file: str) -> Path | None:
    """Account for one node in its parent; the path of the node when it is a value
    reached through mapping keys only."""
    if not frames:
        return ()
    frame = frames[-1]
    if frame.keys_next is None or frame.keys_next:
        frame.count += 1
        if frame.limit is not None and frame.count > frame.limit:
            raise FileError([Problem(file, *frame.mark, f"more than {frame.limit} entries: too "
                                     f"many (the limit is {frame.limit})")])
    if frame.keys_next is None:
        return None
    if frame.keys_next:
        frame.keys_next = False
        frame.key = event.value if isinstance(event, yaml.ScalarEvent) else None
        frame.key_mark = (event.start_mark.line + 1, event.start_mark.column + 1)
        return None
    frame.keys_next = True
    if frame.path is None or frame.key is None:
        return None
    return frame.path + (frame.key,)


def _refuse(file: str, event: yaml.Event, message: str) -> NoReturn:
    mark = event.start_mark
    raise FileError([Problem(file, mark.line + 1, mark.column + 1, message)])


class _Converter:
    """Turns a composed node graph into plain data, counting expanded nodes."""

    def __init__(self, located: Located):
        self.located = located
        self.count = 0
        self.scalars = SafeConstructor()
        self.problems: list[Problem] = []

    def convert(self, node: yaml.Node, path: Path, depth: int = 0) -> Any:
        self.count += 1
        if self.count > MAX_NODES or depth > MAX_DEPTH:
            limit = (f"more than {MAX_NODES} values" if self.count > MAX_NODES
                     else f"nesting deeper than {MAX_DEPTH} levels")
            raise FileError([Problem(self.located.file, node.start_mark.line + 1,
                                     node.start_mark.column + 1,
                                     f"document expands to {limit} once aliases are "
                                     "followed (an alias bomb?)")])
        self.located.marks[path] = (node.start_mark.line + 1, node.start_mark.column + 1)
        if isinstance(node, yaml.MappingNode):
            return self._mapping(node, path, depth)
        if isinstance(node, yaml.SequenceNode):
            return [self.convert(item, path + (i,), depth + 1)
                    for i, item in enumerate(node.value)]
        if node.tag in _PLAIN_SCALARS:
            quote = 1 if node.style in ("'", '"') else 0
            width = node.end_mark.column - node.start_mark.column
            if node.style in (None, "", "'", '"') and node.start_mark.line == node.end_mark.line \
                    and width == len(node.value) + 2 * quote:
                self.located.inline[path] = quote  # as written: no escape, no folding
            return self._scalar(node)
        return node.value  # e.g. a timestamp: kept as the text the user wrote

    def _scalar(self, node: yaml.ScalarNode) -> Any:
        """A plain scalar; a number must be finite and at most :data:`MAX_MAGNITUDE`."""
        mark = (node.start_mark.line + 1, node.start_mark.column + 1)
        try:
            value = self.scalars.construct_object(node)
        except ValueError:  # an integer of thousands of digits (Python refuses to convert)
            self.problems.append(Problem(self.located.file, *mark, f"{node.value[:20]}…: "
                                         f"number too large (the limit is {MAX_MAGNITUDE:g})"))
            return 0
        if isinstance(value, float) and not math.isfinite(value):
            self.problems.append(Problem(self.located.file, *mark, f"{node.value!r} is not a "
                                         "finite number"))
        elif isinstance(value, int | float) and not isinstance(value, bool) \
                and abs(value) > MAX_MAGNITUDE:
            self.problems.append(Problem(self.located.file, *mark, f"{node.value}: number too "
                                         f"large (the limit is {MAX_MAGNITUDE:g})"))
        return value

    def _mapping(self, node: yaml.MappingNode, path: Path, depth: int) -> dict[str, Any]:
        result: dict[str, Any] = {}
        first: dict[str, Mark] = {}
        problems: list[Problem] = []
        file = self.located.file
        for key_node, value_node in node.value:
            mark = (key_node.start_mark.line + 1, key_node.start_mark.column + 1)
            if key_node.tag == "tag:yaml.org,2002:merge":
                problems.append(Problem(file, *mark, "merge keys ('<<') are not supported; "
                                        "write the keys out"))
                continue
            if not isinstance(key_node, yaml.ScalarNode):
                problems.append(Problem(file, *mark, "a key must be a plain scalar"))
                continue
            key = key_node.value
            if key in first:
                line, col = first[key]
                problems.append(Problem(file, *mark, f"duplicate key {key!r} "
                                        f"(first given at line {line}, column {col})"))
                continue
            first[key] = mark
            self.located.key_marks[path + (key,)] = mark
            result[key] = self.convert(value_node, path + (key,), depth + 1)
        self.problems.extend(problems)
        return result
