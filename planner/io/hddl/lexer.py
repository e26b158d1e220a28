"""HDDL's tokens and S-expressions, with the line and column of every piece.

HDDL is case-insensitive: every token has a lower-case ``value`` and keeps its
original ``text`` for messages.  ``;`` starts a comment up to the end of the
line.  Columns count characters (a tab is one column).  :func:`read_sexpr` is
iterative (hostile nesting cannot overflow the stack; it stops at
:data:`MAX_DEPTH`) and reports every stray ``)`` and every ``(`` that is never
closed at once.
"""

from __future__ import annotations

import re
from typing import NamedTuple

from userfiles.errors import FileError, Problem

MAX_DEPTH = 256
"""Deepest nesting of parentheses accepted."""

# --------------------------------------------------------------------------- tokens


class Token(NamedTuple):
    """``kind`` is ``"("``, ``")"`` or ``"atom"``; ``value`` is ``text`` in lower case."""

    kind: str
    value: str
    text: str
    line: int
    col: int


_TOKEN = re.compile(r"\n|[()]|;[^\n]*|[^\s();]+")
_ROW_TOKEN = re.compile(r"[()]|;.*|[^\s();]+")
"""A token within one line (the reader goes line by line: no newline tokens to skip)."""
MAX_STRAYS = 200
"""Stray ')' reported one by one (then a count)."""


def tokenize(text: str) -> list[Token]:
    """The tokens of an HDDL text, comments left out, each with its line and column."""
    tokens: list[Token] = []
    line, start = 1, 0
    for match in _TOKEN.finditer(text):
        word = match.group()
        if word == "\n":
            line, start = line + 1, match.end()
        elif word[0] != ";":
            kind = word if word in ("(", ")") else "atom"
            tokens.append(Token(kind, word.lower(), word, line, match.start() - start + 1))
    return tokens


# --------------------------------------------------------------------------- S-expressions


class Symbol(NamedTuple):
    """An atom: ``value`` in lower case, ``text`` as written."""

    value: str
    text: str
    line: int
    col: int


class SList(NamedTuple):
    """A parenthesised list; ``line``/``col`` are those of its ``(``, ``end_*`` of its ``)``."""

    items: tuple[Node, ...]
    line: int
    col: int
    end_line: int
    end_col: int


Node = Symbol | SList

_SECTION_WORDS = frozenset({
    ":requirements", ":types", ":constants", ":predicates", ":functions", ":task", ":action",
    ":method", ":durative-action", ":derived", ":objects", ":htn", ":init", ":goal",
    ":domain", ":constraints", ":metric",
})


def read_sexpr(text: str, file: str = "<string>") -> list[Node]:
    """Every top-level S-expression of ``text``; ``FileError`` on a syntax error."""
    problems: list[Problem] = []
    new = tuple.__new__  # builds the named tuples below without their slower __new__
    stack: list[list[Node]] = [[]]
    top = stack[0]
    opens: list[tuple[int, int]] = []
    end = (1, 1)
    strays = 0
    finditer = _ROW_TOKEN.finditer
    for line, row in enumerate(text.split("\n"), 1):
        match = None
        for match in finditer(row):
            word = match.group()
            col = match.start() + 1
            if word == "(":
                if len(opens) >= MAX_DEPTH:
                    raise FileError([Problem(file, line, col, f"parentheses nested deeper "
                                                              f"than {MAX_DEPTH} levels")])
                opens.append((line, col))
                top = []
                stack.append(top)
            elif word == ")":
                if not opens:
                    strays += 1
                    if strays <= MAX_STRAYS:
                        problems.append(Problem(file, line, col,
                                                "unexpected ')': no '(' is open here"))
                    continue
                opened_line, opened_col = opens.pop()
                items = stack.pop()
                top = stack[-1]
                top.append(new(SList, (tuple(items), opened_line, opened_col, line, col)))
            elif word[0] != ";":
                top.append(new(Symbol, (word.lower(), word, line, col)))
            else:
                break
        if match is not None and match.group()[0] != ";":
            end = (line, match.end() + 1)
    if strays > MAX_STRAYS:
        problems.append(Problem(file, end[0], end[1],
                                f"... and {strays - MAX_STRAYS} more unexpected ')'"))
    if problems and len(stack[0]) > 1 and isinstance(stack[0][0], SList):
        first, after = stack[0][0], stack[0][1]
        problems.append(Problem(file, first.end_line, first.end_col,
                                f"the first list of the file ends here, but the file goes on at "
                                f"{after.line}:{after.col}: is this ')' one too many?"))
    if opens:
        for opened_line, opened_col in opens:
            problems.append(Problem(file, opened_line, opened_col,
                                    f"'(' is never closed (the file ends at {end[0]}:{end[1]})"))
        # A ')' missing in the middle leaves the outermost '(' open and nests the next
        # section inside the previous one: point at the first section that is too deep.
        for items in stack[1:]:
            for node in items:
                found = _nested_section(node)
                if found is not None:
                    inner, outer = found
                    problems.append(Problem(
                        file, inner.line, inner.col,
                        f"'({_head_text(inner)}' is inside '({_head_text(outer)}' opened at "
                        f"{outer.line}:{outer.col}: a ')' is probably missing before it"))
                    break
            else:
                continue
            break
    if problems:
        raise FileError(problems)
    return stack[0]


def _head_text(node: SList) -> str:
    head = node.items[0] if node.items else None
    return head.text if isinstance(head, Symbol) else ""


def _is_section(node: Node) -> bool:
    return (isinstance(node, SList) and bool(node.items) and isinstance(node.items[0], Symbol)
            and node.items[0].value in _SECTION_WORDS)


def _nested_section(node: Node) -> tuple[SList, SList] | None:
    """The first section list nested inside another section list, with that section."""
    if not isinstance(node, SList):
        return None
    todo: list[tuple[SList, SList | None]] = [(node, node if _is_section(node) else None)]
    while todo:
        current, section = todo.pop(0)
        for child in current.items:
            if not isinstance(child, SList):
                continue
            if _is_section(child) and section is not None:
                return child, section
            todo.append((child, section if section is not None else
                         (child if _is_section(child) else None)))
    return None
