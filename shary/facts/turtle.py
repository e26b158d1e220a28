"""Reading Turtle files into rdflib triples, strictly, with positions, and within limits.

Oxigraph's parser (:mod:`pyoxigraph`) reads the file: it follows the Turtle
grammar strictly (rdflib's, an N3 parser in a Turtle mode, takes literal
subjects and bad escapes, and reports lines past the end of the file),
positions every error, parses a million triples in about two seconds where
rdflib needs minutes, and never fetches anything (a ``@prefix``, ``@base``
or ``owl:imports`` IRI is only a name).  Its terms are then converted once
each to rdflib's, the fact database's vocabulary.  See docs/architecture.md,
"The fact database", for the figures.
"""

from __future__ import annotations

import itertools
import logging
import os
import re
import warnings
from pathlib import Path

import pyoxigraph
from rdflib import XSD, BNode, Literal, URIRef
from rdflib.term import Node

from userfiles.errors import FileError, Problem
from userfiles.yamlsafe import read_text

__all__ = ["MAX_TURTLE_BYTES", "MAX_TURTLE_TRIPLES", "Triple", "read_turtle"]

MAX_TURTLE_BYTES = 8 * 1024 * 1024
"""Largest Turtle file accepted (8 MiB): a-priori knowledge of a home is far smaller."""

MAX_TURTLE_TRIPLES = 50_000
"""Most triples one Turtle file may hold: a home's a-priori knowledge is a few
thousand; fifty thousand load in about 0.6 s of CPU (rdflib's literals are
most of it), and a larger file is refused before any is converted."""

Triple = tuple[Node, Node, Node]


def read_turtle(path: str | os.PathLike[str]) -> set[Triple]:
    """The distinct triples of a Turtle file, or FileError with positions (see
    the module's documentation); the file is read as :func:`read_text` reads
    user files (size limit, UTF-8, no NUL)."""
    file = os.fspath(path)
    return _parse_turtle(read_text(file, max_bytes=MAX_TURTLE_BYTES), file)


def _parse_turtle(text: str, file: str) -> set[Triple]:
    """Parse Turtle text into rdflib triples, or raise FileError with positions.

    A file that holds more than :data:`MAX_TURTLE_TRIPLES` triples is refused
    as soon as the parser passes the limit, before any term is converted.
    Literals whose text does not fit their datatype (``"abc"^^xsd:integer``)
    are mistakes in the file like any other, refused with a position.
    """
    base = Path(file).resolve().as_uri()
    try:  # Oxigraph's own terms first, up to the limit: cheap, and a huge file stops early
        parsed = list(itertools.islice(
            pyoxigraph.parse(text, pyoxigraph.RdfFormat.TURTLE, base_iri=base,
                             rename_blank_nodes=True), MAX_TURTLE_TRIPLES + 1))
    except SyntaxError as err:
        line, col = _inside(text, err.lineno or 1, err.offset or 1)
        raise FileError([Problem(file, line, col, f"invalid Turtle: {_why(err)}")]) from None
    if len(parsed) > MAX_TURTLE_TRIPLES:
        raise FileError([Problem(file, 1, 1, f"more than {MAX_TURTLE_TRIPLES} triples; "
                                 f"the limit is {MAX_TURTLE_TRIPLES}")])
    terms = _TermConverter()
    # rdflib prints a traceback through its logger and warns of ill-typed literals:
    # here they are refused with a position (below), off the user's terminal
    rdflib_terms = logging.getLogger("rdflib.term")
    rdflib_terms.addFilter(_drop)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            triples = {(terms(t.subject), terms(t.predicate), terms(t.object)) for t in parsed}
    except _Unsupported as err:
        at = min((i for i in (text.find("<<"), text.find("{|")) if i >= 0), default=0)
        line, col = text.count("\n", 0, at) + 1, at - (text.rfind("\n", 0, at) + 1) + 1
        raise FileError([Problem(file, line, col, f"invalid Turtle: {err}")]) from None
    finally:
        rdflib_terms.removeFilter(_drop)
    if terms.ill_typed:
        raise FileError([Problem(file, *_find_literal(text, lexical),
                                 f'ill-typed literal: "{lexical}"^^<{datatype}>')
                         for lexical, datatype in terms.ill_typed])
    return triples


class _Unsupported(ValueError):
    """A term Turtle 1.2 allows and the fact database does not hold (a triple term)."""


class _TermConverter:
    """Oxigraph terms to rdflib terms, each distinct term converted (and kept) once."""

    def __init__(self) -> None:
        self._seen: dict[object, Node] = {}
        self.ill_typed: list[tuple[str, str]] = []
        """(text, datatype) of each literal whose text does not fit its datatype, in order."""

    def __call__(self, term: object) -> Node:
        found = self._seen.get(term)
        if found is None:
            found = self._seen[term] = self._convert(term)
        return found

    def _convert(self, term: object) -> Node:
        if isinstance(term, pyoxigraph.NamedNode):
            return URIRef(term.value)
        if isinstance(term, pyoxigraph.BlankNode):
            return BNode(term.value)
        if isinstance(term, pyoxigraph.Literal):
            if term.language:
                return Literal(term.value, lang=term.language)
            if term.datatype.value == _XSD_STRING:
                return Literal(term.value)  # a simple literal, as rdflib writes it
            literal = Literal(term.value, datatype=URIRef(term.datatype.value))
            if literal.ill_typed:
                self.ill_typed.append((term.value, term.datatype.value))
            return literal
        raise _Unsupported(f"triple terms (RDF 1.2 '<<( … )>>', '{{| … |}}') are not facts: "
                           f"{term} (facts are made of IRIs, blank nodes and literals)")


_XSD_STRING = str(XSD.string)

_LOCATION = re.compile(r"^Parser error (?:at line \d+ (?:between columns \d+ and \d+|column \d+)"
                       r"|between line \d+ column \d+ and line \d+ column \d+): ")


def _why(err: SyntaxError) -> str:
    """Oxigraph's message without the position it starts with (the problem line has it)."""
    return _LOCATION.sub("", err.msg or str(err))


def _inside(text: str, line: int, col: int) -> tuple[int, int]:
    """A position the file has: an error found at the end of the text (a missing
    final dot, an unclosed string) is put just after the last character."""
    lines = text.split("\n")
    if lines and lines[-1] == "":  # the text ends with a newline: no line after it
        lines.pop()
    if not lines:
        return 1, 1
    if line > len(lines):
        return len(lines), len(lines[-1].rstrip("\r")) + 1
    return max(line, 1), max(col, 1)


def _drop(record: logging.LogRecord) -> bool:
    """A logging filter that lets nothing through."""
    return False


def _find_literal(text: str, lexical: str) -> tuple[int, int]:
    """Where a literal's text first appears quoted (the file's start if written with
    escapes, which the parser has resolved)."""
    found = [at for mark in "\"'" if (at := text.find(f"{mark}{lexical}{mark}")) >= 0]
    if not found:
        return 1, 1
    at = min(found)
    return text.count("\n", 0, at) + 1, at - (text.rfind("\n", 0, at) + 1) + 1
