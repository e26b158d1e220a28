"""What reading a domain and reading a problem share: names, typed lists, terms,
conditions, effects, keyed lists and sections, each checked, every problem kept
with its position (:meth:`_Reader.finish` raises them all at once)."""

from __future__ import annotations

import difflib
import re
from collections.abc import Iterable

from planner.io.hddl.lexer import Node, SList, Symbol, Token, read_sexpr
from planner.io.hddl.model import Formula, Params, Subtask
from userfiles.errors import FileError, Problem

MAX_PROBLEMS = 200
"""At most this many problems are reported for one file (then a count of the rest)."""
KEPT_PROBLEMS = 10 * MAX_PROBLEMS
"""Problems found before reading stops (the first :data:`MAX_PROBLEMS` by position are
reported; a file is read in a few passes, so more are kept than reported): a file with
a million mistakes costs no more to refuse than one with a thousand."""
MAX_HINTS = 20
"""At most this many "did you mean" hints are looked for in one file: each compares a
word with every name it could have been (a thousand names at most), and a hostile file
with a hundred thousand misspellings must still be refused in a moment."""
HINT_POOL = 1000
"""The most names a hint compares a word with (beyond, no hint)."""

_NAME = re.compile(r"[a-z_][a-z0-9_\-]*\Z")
_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?\Z")

_UNSUPPORTED_SECTIONS = {
    ":functions": "numeric fluents",
    ":durative-action": "durative actions",
    ":derived": "derived predicates",
    ":constraints": "state-trajectory constraints",
    ":metric": "plan metrics",
    ":tihtn": "task insertion",
    ":htnti": "task insertion",
    ":process": "PDDL+ processes",
    ":event": "PDDL+ events",
}
_UNSUPPORTED_REQUIREMENTS = {
    ":durative-actions": "durative actions",
    ":duration-inequalities": "durative actions",
    ":continuous-effects": "continuous effects",
    ":fluents": "numeric and object fluents",
    ":numeric-fluents": "numeric fluents",
    ":object-fluents": "object fluents",
    ":action-costs": "action costs (numeric fluents)",
    ":timed-initial-literals": "timed initial literals",
    ":preferences": "preferences",
    ":constraints": "state-trajectory constraints",
    ":derived-predicates": "derived predicates",
    ":time": "PDDL+ time",
}
_NUMERIC_EFFECTS = frozenset({"increase", "decrease", "assign", "scale-up", "scale-down"})
_COMPARISONS = frozenset({"<", ">", "<=", ">="})
_TEMPORAL = frozenset({"at", "over"})
_SUBTASK_KEYS = {":subtasks": ":subtasks", ":tasks": ":subtasks",
                 ":ordered-subtasks": ":ordered-subtasks", ":ordered-tasks": ":ordered-subtasks",
                 ":ordering": ":ordering", ":order": ":ordering"}
_NETWORK_UNSUPPORTED = {
    ":causal-links": "causal links",
    ":causallinks": "causal links",
}


def _a(word: str) -> str:
    return f"{'an' if word[:1] in 'aeiou' else 'a'} {word}"


def _show(node: Node) -> str:
    return f"'{node.text}'" if isinstance(node, Symbol) else "a list"


def _definition(text: str, file: str, kind: str) -> tuple[SList, Symbol]:
    """The ``(define (KIND NAME) ...)`` form of a text and its name."""
    forms = read_sexpr(text, file)
    if not forms:
        raise FileError([Problem(file, 1, 1, f"empty file: expected '(define ({kind} NAME) ...)'")])
    problems: list[Problem] = []
    first = forms[0]
    for extra in forms[1:]:
        if isinstance(first, SList):
            where = f"the definition ends at {first.end_line}:{first.end_col}"
            problems.append(Problem(file, extra.line, extra.col,
                                    f"{_show(extra)} after the end of the definition ({where}; "
                                    "is there a ')' too many before it?)"))
        else:
            problems.append(Problem(file, extra.line, extra.col, f"unexpected {_show(extra)}"))
    expected = f"expected '(define ({kind} NAME) ...)'"
    if not isinstance(first, SList):
        raise FileError([*problems, Problem(file, first.line, first.col,
                                            f"{expected}, found {_show(first)}")])
    items = first.items
    if not items or not isinstance(items[0], Symbol) or items[0].value != "define":
        at = items[0] if items else first
        raise FileError([*problems, Problem(file, at.line, at.col,
                                            f"{expected}, found {_show(at)}")])
    header = items[1] if len(items) > 1 else None
    if (not isinstance(header, SList) or len(header.items) != 2
            or not all(isinstance(i, Symbol) for i in header.items)):
        at = header or items[0]
        raise FileError([*problems, Problem(file, at.line, at.col,
                                            f"{expected}: '({kind} NAME)' must follow 'define'")])
    word, name = header.items
    assert isinstance(word, Symbol) and isinstance(name, Symbol)
    if word.value != kind:
        other = "problem" if kind == "domain" else "domain"
        message = (f"this file defines a {other}, not a {kind}" if word.value == other else
                   f"{expected}, found '({word.text} ...)'")
        raise FileError([*problems, Problem(file, word.line, word.col, message)])
    if problems:
        raise FileError(problems)
    return first, name


class _Reader:
    """What domains and problems share: problems, names, parameters, formulas, networks."""

    def __init__(self, file: str):
        self.file = file
        self.problems: list[Problem] = []
        self.types: dict[str, str | None] = {"object": None}
        self.predicates: dict[str, Params] = {}
        self.tasks: dict[str, Params] = {}
        self.action_params: dict[str, Params] = {}
        self.objects: dict[str, str] = {}
        """Every name a term may be: constants (and, in a problem, objects)."""
        self.object_word = "constant"
        self.spelling: dict[str, str] = {}
        """Names declared otherwise than in lower case, as first written."""
        self.hints = 0
        """How many hints were looked for (see :data:`MAX_HINTS`)."""

    # -- problems

    def hint(self, word: str, choices: Iterable[str]) -> str:
        """`` (did you mean 'X'?)`` for a close name, or nothing (see :data:`MAX_HINTS`)."""
        if self.hints >= MAX_HINTS:
            return ""
        self.hints += 1
        pool = [c for c in choices if abs(len(c) - len(word)) <= 3]
        if not pool or len(pool) > HINT_POOL:
            return ""
        close = difflib.get_close_matches(word, pool, n=1, cutoff=0.6)
        return f" (did you mean '{close[0]}'?)" if close else ""

    def error(self, at: Node | Token | Subtask, message: str) -> None:
        """Record a problem; at the :data:`KEPT_PROBLEMS`-th, stop reading (raise them)."""
        self.problems.append(Problem(self.file, at.line, at.col, message))
        if len(self.problems) >= KEPT_PROBLEMS:
            self.finish(stopped_at=(at.line, at.col))

    def finish(self, stopped_at: tuple[int, int] | None = None) -> None:
        """Raise every problem found, first in the file first (at most :data:`MAX_PROBLEMS`,
        then a count of the others, and where reading stopped if it did)."""
        if not self.problems:
            return
        found = sorted(set(self.problems), key=lambda p: (p.line, p.col, p.message))
        more = len(found) - MAX_PROBLEMS
        if more > 0:
            rest = found[min(MAX_PROBLEMS, len(found) - 1)]
            found = [*found[:MAX_PROBLEMS],
                     Problem(self.file, rest.line, rest.col, f"... and {more} more problems")]
        if stopped_at is not None:
            found.append(Problem(self.file, *stopped_at, f"reading stopped here, after "
                                 f"{KEPT_PROBLEMS} problems: the rest of the file is not "
                                 "checked (correct these first)"))
        raise FileError(found)

    # -- names

    def name(self, node: Node, what: str) -> str | None:
        """A valid name (lower case), or None after reporting why it is not one."""
        if not isinstance(node, Symbol):
            self.error(node, f"expected the name of {what}, found a list")
            return None
        if not _NAME.match(node.value):
            if node.value.startswith("?"):
                self.error(node, f"expected the name of {what}, found the variable '{node.text}'")
            elif node.value.startswith(":"):
                self.error(node, f"expected the name of {what}, found the keyword '{node.text}'")
            else:
                self.error(node, f"'{node.text}' is not a valid name for {what} (a name starts "
                                 "with a letter and has letters, digits, '-' and '_')")
            return None
        self.spell(node)
        return node.value

    def spell(self, symbol: Symbol) -> None:
        """Keep how the file writes a declared name, when not in lower case."""
        if symbol.text != symbol.value:
            self.spelling.setdefault(symbol.value, symbol.text)

    def variable(self, node: Symbol) -> str | None:
        if not node.value.startswith("?") or not _NAME.match(node.value[1:]):
            if _NAME.match(node.value):
                self.error(node, f"expected a variable, found '{node.text}' (variables start "
                                 "with '?')")
            else:
                self.error(node, f"'{node.text}' is not a valid variable (a variable is '?' "
                                 "and a name)")
            return None
        return node.value

    def known_type(self, node: Node | None, kind: str) -> bool:
        if kind in self.types:
            return True
        self.error(node, f"unknown type '{node.text if isinstance(node, Symbol) else kind}'"
                         f"{self.hint(kind, self.types)}")
        return False

    # -- typed lists

    def typed_list(self, node: SList, variables: bool, what: str = "a variable"
                   ) -> list[tuple[Symbol, str, Node | None]]:
        """``a b - t c`` as (symbol, type, type node); untyped names are ``object``.

        ``what`` names the items (``a type``, ``an object``...) when they are not variables.
        """
        out: list[tuple[Symbol, str, Node | None]] = []
        pending: list[Symbol] = []
        items = node.items
        i = 0
        while i < len(items):
            item = items[i]
            if isinstance(item, Symbol) and item.value == "-":
                if i + 1 >= len(items):
                    self.error(item, "'-' must be followed by a type")
                    break
                kind_node = items[i + 1]
                kind = "object"
                if isinstance(kind_node, SList):
                    head = kind_node.items[0] if kind_node.items else None
                    if isinstance(head, Symbol) and head.value == "either":
                        self.error(kind_node, "'either' types are not supported")
                    else:
                        self.error(kind_node, "expected a type after '-', found a list")
                else:
                    checked = self.name(kind_node, "a type")
                    if checked is not None:
                        kind = checked
                if not pending:
                    self.error(item, "'-' must follow the names it gives a type to")
                out.extend((p, kind, kind_node) for p in pending)
                pending = []
                i += 2
                continue
            if isinstance(item, SList):
                self.error(item, f"expected {what}, found a list")
            elif self.variable(item) if variables else self.name(item, what):
                pending.append(item)
            i += 1
        out.extend((p, "object", None) for p in pending)
        return out

    def params(self, node: Node | None, what: str) -> Params:
        """A parameter list ``(?a ?b - t ...)``: no duplicates, known types."""
        if node is None:
            return ()
        if not isinstance(node, SList):
            self.error(node, f"the parameters of {what} must be a list like '(?x - type)', "
                             f"found {_show(node)}")
            return ()
        seen: dict[str, Symbol] = {}
        out: list[tuple[str, str]] = []
        for symbol, kind, kind_node in self.typed_list(node, variables=True):
            if symbol.value in seen:
                first = seen[symbol.value]
                self.error(symbol, f"duplicate parameter '{symbol.text}' of {what} (first at "
                                   f"{first.line}:{first.col})")
                continue
            seen[symbol.value] = symbol
            if kind_node is not None and not self.known_type(kind_node, kind):
                kind = "object"
            out.append((symbol.value, kind))
        return tuple(out)

    def fits(self, kind: str, wanted: str) -> bool:
        current: str | None = kind
        seen = set()
        while current is not None and current not in seen:
            if current == wanted:
                return True
            seen.add(current)
            current = self.types.get(current)
        return wanted == "object"

    # -- terms and atoms

    def terms(self, items: Iterable[Node], scope: dict[str, str],
              signature: Params | None, what: str) -> tuple[str, ...] | None:
        """Terms (variables of ``scope``, or constants) given to ``signature``'s parameters."""
        out: list[str] = []
        good = True
        for index, item in enumerate(items):
            if isinstance(item, SList):
                self.error(item, "expected a variable or a constant, found a list (function "
                                 "terms are not supported)")
                good = False
                continue
            value = item.value
            if value.startswith("?"):
                if value not in scope:
                    known = (f"declared: {', '.join(scope)}" if scope else
                             "no variables are in scope here")
                    self.error(item, f"variable '{item.text}' is not declared ({known})"
                                     f"{self.hint(value, scope)}")
                    good = False
            elif _NUMBER.match(value):
                self.error(item, f"number '{item.text}' where a constant is expected (numeric "
                                 "fluents are not supported)")
                good = False
            elif value not in self.objects:
                if _NAME.match(value):
                    self.error(item, f"unknown {self.object_word} '{item.text}'"
                                     f"{self.hint(value, self.objects)}")
                else:
                    self.error(item, f"expected a variable or a constant, found '{item.text}'")
                good = False
            elif signature is not None and index < len(signature):
                wanted = signature[index][1]
                kind = self.objects[value]
                if not self.fits(kind, wanted):
                    self.error(item, f"'{item.text}' is {_a(kind)}, but argument {index + 1} of "
                                     f"{what} is {_a(wanted)}")
                    good = False
            out.append(value)
        return tuple(out) if good else None

    def arity(self, at: Node, what: str, signature: Params, given: int) -> bool:
        if len(signature) == given:
            return True
        self.error(at, f"{what} takes {len(signature)} argument(s), given {given}")
        return False

    def atom(self, node: SList, scope: dict[str, str]) -> Formula | None:
        head = node.items[0]
        assert isinstance(head, Symbol)
        name = head.value
        if name not in self.predicates:
            if name in self.tasks or name in self.action_params:
                kind = "task" if name in self.tasks else "action"
                self.error(head, f"'{head.text}' is an {kind}, not a predicate")
            elif name.startswith("?"):
                self.error(head, f"expected a predicate, found the variable '{head.text}'")
            else:
                self.error(head, f"unknown predicate '{head.text}'"
                                 f"{self.hint(name, self.predicates)}")
            self.terms(node.items[1:], scope, None, "")
            return None
        signature = self.predicates[name]
        args = node.items[1:]
        ok = self.arity(head, f"predicate '{head.text}'", signature, len(args))
        terms = self.terms(args, scope, signature, f"'{head.text}'")
        if not ok or terms is None:
            return None
        return Formula("pred", (name, terms), node.line, node.col)

    # -- conditions and effects

    def condition(self, node: Node | None, scope: dict[str, str]) -> Formula | None:
        """A precondition or goal; ``()`` is None."""
        if node is None or (isinstance(node, SList) and not node.items):
            return None
        return self.gd(node, scope)

    def gd(self, node: Node, scope: dict[str, str]) -> Formula | None:
        if isinstance(node, Symbol):
            self.error(node, f"expected a condition in parentheses, found {_show(node)}")
            return None
        if not node.items:
            return Formula("and", (), node.line, node.col)
        head, args = node.items[0], node.items[1:]
        if isinstance(head, SList):
            self.error(head, "expected a predicate or 'and', 'or', 'not', 'imply', 'exists', "
                             "'forall', '=', found a list")
            return None
        word = head.value
        if word in ("and", "or"):
            parts = [self.gd(a, scope) for a in args]
            if any(p is None for p in parts):
                return None
            return Formula(word, tuple(parts), node.line, node.col)
        if word == "not":
            if not self.count(node, head, args, 1):
                return None
            inner = self.gd(args[0], scope)
            return None if inner is None else Formula("not", (inner,), node.line, node.col)
        if word == "imply":
            if not self.count(node, head, args, 2):
                return None
            a, b = self.gd(args[0], scope), self.gd(args[1], scope)
            return None if a is None or b is None else Formula("imply", (a, b), node.line,
                                                               node.col)
        if word in ("forall", "exists"):
            return self.quantified(node, head, args, scope, self.gd)
        if word == "=":
            if not self.count(node, head, args, 2):
                return None
            terms = self.terms(args, scope, None, "'='")
            return None if terms is None else Formula("=", terms, node.line, node.col)
        if self.unsupported(head, args):
            return None
        if word == "when":
            self.error(head, "'when' is a conditional effect; it cannot appear in a condition")
            return None
        return self.atom(node, scope)

    def effect(self, node: Node | None, scope: dict[str, str], top: bool = False
               ) -> Formula | None:
        if node is None:
            return None
        if isinstance(node, Symbol):
            self.error(node, f"expected an effect in parentheses, found {_show(node)}")
            return None
        if not node.items:
            return None if top else Formula("and", (), node.line, node.col)
        head, args = node.items[0], node.items[1:]
        if isinstance(head, SList):
            self.error(head, "expected a predicate or 'and', 'not', 'forall', 'when', found a "
                             "list")
            return None
        word = head.value
        if word == "and":
            parts = [self.effect(a, scope) for a in args]
            if any(p is None for p in parts):
                return None
            return Formula("and", tuple(parts), node.line, node.col)
        if word == "not":
            if not self.count(node, head, args, 1):
                return None
            inner = args[0]
            if (not isinstance(inner, SList) or not inner.items
                    or not isinstance(inner.items[0], Symbol)
                    or inner.items[0].value in ("and", "or", "not", "forall", "exists", "when",
                                                "imply", "=")):
                self.error(inner, "'not' in an effect must hold a single predicate, like "
                                  "'(not (p ?x))'")
                return None
            if self.unsupported(inner.items[0], inner.items[1:]):
                return None
            atom = self.atom(inner, scope)
            return None if atom is None else Formula("not", (atom,), node.line, node.col)
        if word == "forall":
            return self.quantified(node, head, args, scope, self.effect)
        if word == "when":
            if not self.count(node, head, args, 2):
                return None
            condition = self.condition(args[0], scope)
            if condition is None and isinstance(args[0], SList) and not args[0].items:
                condition = Formula("and", (), args[0].line, args[0].col)
            result = self.effect(args[1], scope)
            if condition is None or result is None:
                return None
            return Formula("when", (condition, result), node.line, node.col)
        if word in ("or", "exists", "imply", "="):
            self.error(head, f"'{head.text}' is not allowed in an effect")
            return None
        if self.unsupported(head, args):
            return None
        return self.atom(node, scope)

    def unsupported(self, head: Symbol, args: tuple[Node, ...]) -> bool:
        """Report a construct refused by name (numeric, temporal, preferences...)."""
        word = head.value
        if word in _NUMERIC_EFFECTS:
            self.error(head, f"numeric effect '{head.text}' is not supported (numeric fluents)")
        elif word in _COMPARISONS:
            self.error(head, f"numeric comparison '{head.text}' is not supported (numeric "
                             "fluents)")
        elif word == "preference":
            self.error(head, "preferences ('preference') are not supported")
        elif word in ("sortof", "typeof"):
            self.error(head, f"'{head.text}' constraints are not supported")
        elif (word in _TEMPORAL and word not in self.predicates and args
              and isinstance(args[0], Symbol) and args[0].value in ("start", "end", "all")):
            self.error(head, f"temporal '({head.text} {args[0].text} ...)' is not supported "
                             "(durative actions)")
        else:
            return False
        return True

    def count(self, node: SList, head: Symbol, args: tuple[Node, ...], wanted: int) -> bool:
        if len(args) == wanted:
            return True
        self.error(head if args else node,
                   f"'{head.text}' takes {wanted} argument(s), given {len(args)}")
        return False

    def quantified(self, node: SList, head: Symbol, args: tuple[Node, ...],
                   scope: dict[str, str], body_reader) -> Formula | None:
        if not self.count(node, head, args, 2):
            return None
        if not isinstance(args[0], SList):
            self.error(args[0], f"'{head.text}' needs its variables in a list, like "
                                "'(?x - type)'")
            return None
        params = self.params(args[0], f"'{head.text}'")
        inner_scope = {**scope, **dict(params)}
        body = body_reader(args[1], inner_scope)
        if body is None:
            return None
        return Formula(head.value, (params, body), node.line, node.col)

    # -- keyed lists: (:action NAME :key value ...)

    def keyed(self, items: tuple[Node, ...], allowed: dict[str, str],
              unsupported: dict[str, str], what: str) -> dict[str, tuple[Symbol, Node]]:
        out: dict[str, tuple[Symbol, Node]] = {}
        i = 0
        while i < len(items):
            key = items[i]
            if not isinstance(key, Symbol) or not key.value.startswith(":"):
                keys = ", ".join(sorted({k for k in allowed}))
                self.error(key, f"expected a keyword of {what} ({keys}), found {_show(key)}")
                i += 1
                continue
            value = items[i + 1] if i + 1 < len(items) else None
            if value is None or (isinstance(value, Symbol) and value.value.startswith(":")):
                self.error(key, f"'{key.text}' of {what} has no value")
                i += 1
                continue
            i += 2
            if key.value in unsupported:
                self.error(key, f"'{key.text}' is not supported in {what} "
                                f"({unsupported[key.value]})")
                continue
            if key.value not in allowed:
                self.error(key, f"unknown keyword '{key.text}' in {what}"
                                f"{self.hint(key.value, allowed)}")
                continue
            canonical = allowed[key.value]
            if canonical in out:
                first = out[canonical][0]
                self.error(key, f"'{key.text}' given twice in {what} (first at "
                                f"{first.line}:{first.col})")
                continue
            out[canonical] = (key, value)
        return out

    # -- sections

    def requirements(self, node: SList) -> list[str]:
        out = []
        for item in node.items[1:]:
            if not isinstance(item, Symbol) or not item.value.startswith(":"):
                self.error(item, f"expected a requirement like ':typing', found {_show(item)}")
                continue
            if item.value in _UNSUPPORTED_REQUIREMENTS:
                self.error(item, f"requirement '{item.text}' is not supported "
                                 f"({_UNSUPPORTED_REQUIREMENTS[item.value]})")
            out.append(item.value)
        return out

    def sections(self, define: SList, allowed: Iterable[str]
                 ) -> list[tuple[str, SList]]:
        """The sections after the header, as (keyword, list); others are reported."""
        known = set(allowed)
        out: list[tuple[str, SList]] = []
        for node in define.items[2:]:
            head = node.items[0] if isinstance(node, SList) and node.items else None
            if not isinstance(head, Symbol) or not head.value.startswith(":"):
                self.error(node, f"expected a section like '({sorted(known)[0]} ...)', found "
                                 f"{_show(node) if isinstance(node, Symbol) else 'a list'}")
                continue
            assert isinstance(node, SList)
            if head.value in _UNSUPPORTED_SECTIONS:
                self.error(head, f"'{head.text}' is not supported "
                                 f"({_UNSUPPORTED_SECTIONS[head.value]})")
                continue
            if head.value not in known:
                self.error(head, f"unknown section '{head.text}'{self.hint(head.value, known)}"
                                 f"; expected one of {', '.join(sorted(known))}")
                continue
            out.append((head.value, node))
        return out
