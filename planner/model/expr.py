"""The expression language of planning domains: preconditions, effects and costs.

HATP writes tasks with small expressions over entity attributes (Fig. 5:
``Ag.posTopo != P2; P2.freePlace == true``, effects ``Ag.posTopo = P2``, costs
that depend on the state).  The world they run against maps (entity, attribute)
to a value: None, a bool, a number or a string, and a string that names an
entity *is* that entity, so ``obj.holder.at`` reads ``at`` of whoever holds
``obj``.

Each text is parsed, type-checked and compiled once, when the domain is
loaded, into nested Python closures, one per node of the syntax tree.  Why
closures: the search evaluates the same few conditions millions of times, so
all the deciding (which operator, which variable, is an operand constant) is
done once; a call is then plain function calls, with no walk over a tree and
no lookup of operators.  Why a parser of our own: a domain file is data, and
nothing from its text ever reaches Python's eval, exec or compile builtins; a
typo is reported at its column instead of being run.

Semantics, chosen for planning:

* attribute access propagates null: an attribute of null is null, so
  ``obj.holder.at == p`` is simply false while nobody holds ``obj``;
* ``== null`` and ``!= null`` test for null; ``<`` ``<=`` ``>`` ``>=`` with a
  null operand are false (an unknown quantity satisfies no bound);
* ``and``, ``or`` and ``not`` give booleans; ``/`` divides exactly;
* arithmetic takes numbers only (not null, strings or booleans), and what the
  types cannot rule out at compile time is an :class:`EvalError` at run time.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Callable
from typing import Any, NoReturn

from planner.model import closures as build
from planner.model.closures import EvalError, Getter, Setter

__all__ = ["EvalError", "Effect", "Expr", "ExprError", "compile_effect", "compile_expr"]

FUNCTIONS = ("abs", "max", "min")
_KEYWORDS = ("and", "or", "not", "true", "false", "null")
_LITERALS = {"true": True, "false": False, "null": None}
_PYTHON_NAMES = {"True": "true", "False": "false", "None": "null"}
_COMPARISONS = ("==", "!=", "<", "<=", ">", ">=")

MAX_NESTING = 32
"""Deepest nesting of parentheses, ``not``, unary minus and function calls: the parser
descends once per level, so hostile nesting is refused before it can overflow the stack."""
MAX_OPERATIONS = 256
"""Most operations in one expression: each is one closure around the previous ones, so
this bounds how deep evaluation calls go (far below Python's recursion limit)."""
MAX_NUMBER = 1e15
"""Largest literal number (as in YAML files): larger ones overflow costs to infinity."""

# A token is a number, a name, a quoted string or an operator; anything else is an error.
_TOKEN = (r"(?P<num>[0-9]+(?:\.[0-9]+)?(?:[eE][-+]?[0-9]+)?)|(?P<name>[A-Za-z_][A-Za-z0-9_]*)"
          r"|(?P<str>\"[^\"]*\"|'[^']*')|(?P<op>==|!=|<=|>=|&&|\|\||[-+*/<>=().,])"
          r"|(?P<ws>\s+)|(?P<bad>.)")


class ExprError(Exception):
    """A syntax or type error found at compile time, at ``offset`` (0-based) in the text.

    ``offset`` is a plain attribute so that a caller that compiled a piece of a
    larger text (a subtask argument) can shift it to a position in the whole.
    """

    def __init__(self, message: str, offset: int):
        super().__init__(message, offset)  # both in args, so that it pickles
        self.message = message
        self.offset = offset

    def __str__(self) -> str:
        return f"{self.message} (at offset {self.offset})"




class Expr:
    """A compiled expression: ``expr(env, get)`` evaluates it.

    ``env`` binds every name of ``variables``; ``get(entity, attribute)`` reads
    the state.  ``reads`` are the attribute names it may read (for causal links
    and lower bounds), ``type`` its static type when known (an entity type,
    "bool", "number", "string" or None), ``fn`` the bare closure for hot loops.
    """

    __slots__ = ("text", "variables", "reads", "type", "fn")

    def __init__(self, text: str, fn: Callable[[dict[str, Any], Getter], Any],
                 variables: frozenset[str], reads: frozenset[str], type_: str | None):
        self.text, self.fn, self.variables, self.reads, self.type = (
            text, fn, variables, reads, type_)

    def __call__(self, env: dict[str, Any], get: Getter) -> Any:
        return self.fn(env, get)

    def __repr__(self) -> str:
        return f"Expr({self.text!r})"


class Effect:
    """A compiled assignment: ``effect(env, get, set)`` calls ``set(entity, attr, value)``.

    ``target_attribute`` is the attribute it writes; ``variables`` and ``reads``
    are as for :class:`Expr` (reads include the attributes that lead to the target).
    ``plain`` describes the commonest effect, ``var.attr = <constant or variable>``, as
    (var, attr, the variable assigned or None, the constant), so that the search's step
    can write it without calling anything (None: any other effect).
    """

    __slots__ = ("text", "target_attribute", "variables", "reads", "fn", "plain")

    def __init__(self, text: str, fn: Callable[[dict[str, Any], Getter, Setter], None],
                 target_attribute: str, variables: frozenset[str], reads: frozenset[str],
                 plain: tuple[str, str, str | None, Any] | None = None):
        self.text, self.fn, self.target_attribute, self.variables, self.reads = (
            text, fn, target_attribute, variables, reads)
        self.plain = plain

    def __call__(self, env: dict[str, Any], get: Getter, set: Setter) -> None:
        self.fn(env, get, set)

    def __repr__(self) -> str:
        return f"Effect({self.text!r})"


def compile_expr(text: str, variables: dict[str, str | None],
                 attributes: dict[str, dict[str, str]] | None = None) -> Expr:
    """Compile a condition or a cost; ``variables`` maps names to entity types (or None),
    ``attributes`` maps entity types to {attribute: type} (None: no type checks)."""
    p = _Parser(text, variables, attributes)
    node = p.or_()
    p.finish()
    return Expr(text, node.fn, frozenset(p.used), frozenset(p.reads), _public(node.type))


def compile_effect(text: str, variables: dict[str, str | None],
                   attributes: dict[str, dict[str, str]] | None = None) -> Effect:
    """Compile one assignment ``var.attr = expr`` (or ``var.a.b = expr``)."""
    p = _Parser(text, variables, attributes)
    kind, word, pos = p.peek()
    if kind != "name" or word in _KEYWORDS:
        p.fail("an effect assigns an attribute: write var.attr = value", pos)
    owner = p.primary()
    if owner.var is None:
        p.fail("an effect assigns an attribute of a variable: write var.attr = value", pos)
    steps = p.attribute_names()
    if not steps:
        p.fail(f"an effect assigns an attribute: write {word}.attribute = value", pos)
    for attr, at in steps[:-1]:
        owner = p.attribute(owner, attr, at)
    attr, at = steps[-1]
    target_type = p.attribute_type(owner, attr, at)
    target = text[pos:p.last_end]
    kind, word, eq = p.next()
    if word == "==":
        p.fail("an effect assigns with '=', not '=='", eq)
    if word != "=":
        p.fail(f"expected '=' after {target}, found {_show(word)}", eq)
    value = p.or_()
    p.finish()
    if not _comparable(target_type, value.type):
        p.fail(f"cannot assign {p.describe(value)} to {target} ({_a(target_type or '')})",
               value.pos)
    plain = None
    if owner.var is not None and value.var is not None:
        plain = (owner.var, attr, value.var, None)
    elif owner.var is not None and value.const is not build.NOT_CONSTANT:
        plain = (owner.var, attr, None, value.const)
    return Effect(text, build.assign(owner, attr, value, text[pos:owner.end], target),
                  attr, frozenset(p.used), frozenset(p.reads), plain)


class _Parser:
    """Recursive descent; each method parses one precedence level and returns a
    :class:`build.Node` whose closure is already built (parsing and compiling are one pass).

    Static types: None (unknown), "number", "bool", "string", "null", "name"
    (a quoted string: text or an entity of unknown type), or an entity type.
    """

    def __init__(self, text: str, variables: dict[str, str | None],
                 attributes: dict[str, dict[str, str]] | None):
        self.text, self.variables, self.attributes = text, variables, attributes
        self.tokens = _tokenize(text)
        self.i = 0
        self.last_end = 0
        self.used: set[str] = set()
        self.reads: set[str] = set()
        self.depth = 0
        self.operations = 0

    # -- tokens -------------------------------------------------------------------

    def peek(self) -> tuple[str, str, int]:
        return self.tokens[self.i]

    def next(self) -> tuple[str, str, int]:
        tok = self.tokens[self.i]
        if tok[0] != "end":
            self.i += 1
            self.last_end = tok[2] + len(tok[1])
        return tok

    def at(self, *words: str) -> bool:
        kind, word, _ = self.tokens[self.i]
        return word in words and kind in ("name", "op")

    def fail(self, message: str, offset: int) -> NoReturn:
        raise ExprError(message, offset)

    def finish(self) -> None:
        kind, word, pos = self.peek()
        if kind == "end":
            return
        if word == ")":
            self.fail("unbalanced ')': no '(' to close", pos)
        if word == "=":
            self.fail("'=' assigns, once, in an effect; use '==' to compare", pos)
        if word in _COMPARISONS:
            self.fail("comparisons cannot be chained; use 'and'", pos)
        self.fail(f"unexpected {_show(word)} after {self.text[:pos].strip()!r}", pos)

    def describe(self, node: build.Node) -> str:
        src = self.text[node.pos:node.end]
        return src if node.type in (None, "name", "null") else f"{src} ({_a(node.type)})"

    # -- precedence levels ----------------------------------------------------------

    def or_(self) -> build.Node:
        return self.logic("or", self.and_)

    def and_(self) -> build.Node:
        return self.logic("and", self.not_)

    def logic(self, word: str, operand: Callable[[], build.Node]) -> build.Node:
        parts = [operand()]
        while self.at(word):
            self.next()
            parts.append(operand())
        if len(parts) == 1:
            return parts[0]
        return self.fold(build.logic(word == "and", parts), "bool", parts, boolean=True)

    def deeper(self, pos: int) -> None:
        """One more level of nesting (see :data:`MAX_NESTING`)."""
        self.depth += 1
        if self.depth > MAX_NESTING:
            self.fail(f"expression nested deeper than {MAX_NESTING} levels", pos)

    def not_(self) -> build.Node:
        if not self.at("not"):
            return self.comparison()
        pos = self.next()[2]
        self.deeper(pos)
        operand = self.not_()
        self.depth -= 1
        f = operand.fn
        node = self.fold(lambda env, get: not f(env, get), "bool", [operand], boolean=True)
        node.pos = pos
        return node

    def comparison(self) -> build.Node:
        left = self.sum()
        if not self.at(*_COMPARISONS):
            return left
        op, pos = self.next()[1:]
        right = self.sum()
        if self.at(*_COMPARISONS):
            self.fail("comparisons cannot be chained; use 'and'", self.peek()[2])
        if op in ("==", "!=") and not _comparable(left.type, right.type):
            self.fail(f"{self.describe(left)} and {self.describe(right)} are never equal", pos)
        if op not in ("==", "!="):
            for side in (left, right):
                if side.type not in (None, "number", "null"):
                    self.fail(f"{op!r} orders numbers, not {self.describe(side)}", side.pos)
        fn = build.compare(op, left, right, self.text[left.pos:right.end])
        return self.fold(fn, "bool", [left, right], boolean=True)

    def sum(self) -> build.Node:
        node = self.product()
        while self.at("+", "-"):
            node = self.arithmetic(node, self.next()[1], self.product)
        return node

    def product(self) -> build.Node:
        node = self.unary()
        while self.at("*", "/"):
            node = self.arithmetic(node, self.next()[1], self.unary)
        return node

    def arithmetic(self, left: build.Node, op: str,
                   operand: Callable[[], build.Node]) -> build.Node:
        right = operand()
        self.need_numbers(op, left, right)
        fn = build.arith(op, left.fn, right.fn, self.text[left.pos:right.end])
        return self.fold(fn, "number", [left, right])

    def unary(self) -> build.Node:
        if not self.at("-"):
            return self.postfix()
        pos = self.next()[2]
        self.deeper(pos)
        inner = self.unary()
        self.depth -= 1
        self.need_numbers("-", inner)
        fn = build.arith("neg", inner.fn, None, self.text[pos:inner.end])
        node = self.fold(fn, "number", [inner])
        node.pos = pos
        return node

    def postfix(self) -> build.Node:
        node = self.primary()
        for attr, at in self.attribute_names():
            node = self.attribute(node, attr, at)
        return node

    def primary(self) -> build.Node:
        kind, word, pos = self.next()
        end = self.last_end
        if kind == "num":
            value = float(word) if ("." in word or "e" in word.lower()) else int(word)
            if not abs(value) <= MAX_NUMBER:
                self.fail(f"number {word} is too large (the limit is {MAX_NUMBER:g})", pos)
            return build.const(value, "number", pos, end)
        if kind == "str":
            return build.const(word[1:-1], "name", pos, end)
        if kind == "name" and word in _LITERALS:
            value = _LITERALS[word]
            return build.const(value, "null" if value is None else "bool", pos, end)
        if kind == "name" and word not in _KEYWORDS:
            if self.at("("):
                return self.call(word, pos)
            return self.variable(word, pos, end)
        if kind == "end":
            if self.i == 0:
                self.fail("empty expression", 0)
            before = self.tokens[self.i - 1]
            self.fail(f"the expression ends after {_show(before[1])}", before[2])
        if word == "(":
            self.deeper(pos)
            node = self.or_()
            self.depth -= 1
            self.close(pos, "(")
            node.pos, node.end = pos, self.last_end
            return node
        self.fail(f"expected a value, found {_show(word)}", pos)

    def close(self, opened: int, what: str) -> None:
        kind, word, pos = self.peek()
        if word == ")":
            self.next()
        elif kind == "end":
            self.fail(f"{what!r} is never closed", opened)
        else:
            self.fail(f"expected ')' or an operator, found {_show(word)}", pos)

    def variable(self, name: str, pos: int, end: int) -> build.Node:
        if name not in self.variables:
            hint = _PYTHON_NAMES.get(name)
            if hint:
                self.fail(f"unknown name {name!r}; write {hint}", pos)
            close = difflib.get_close_matches(name, list(self.variables), 1)
            maybe = f" (did you mean {close[0]!r}?)" if close else ""
            self.fail(f'unknown name {name!r}{maybe}; write entity names in quotes: "{name}"',
                      pos)
        self.used.add(name)
        type_ = _norm(self.variables[name]) if self.attributes is not None else None
        return build.Node(lambda env, get: env[name], type_, pos, end, var=name)

    def call(self, name: str, pos: int) -> build.Node:
        if name not in FUNCTIONS:
            close = difflib.get_close_matches(name, FUNCTIONS, 1)
            maybe = f"; did you mean {close[0]!r}?" if close else ""
            self.fail(f"unknown function {name!r} (the functions are "
                      f"{', '.join(FUNCTIONS)}){maybe}", pos)
        opened = self.next()[2]
        self.deeper(opened)
        args = []
        if not self.at(")"):
            args.append(self.or_())
            while self.at(","):
                self.next()
                args.append(self.or_())
        self.depth -= 1
        self.close(opened, "(")
        if name == "abs" and len(args) != 1:
            self.fail(f"abs takes one argument, not {len(args)}", pos)
        if not args:
            self.fail(f"{name} needs at least one argument", pos)
        self.need_numbers(name, *args)
        fn = build.function(name, [a.fn for a in args], self.text[pos:self.last_end])
        node = self.fold(fn, "number", args)
        node.pos = pos
        return node

    def attribute_names(self) -> list[tuple[str, int]]:
        out = []
        while self.at("."):
            self.next()
            kind, word, pos = self.next()
            if kind != "name":
                self.fail(f"expected an attribute name after '.', found {_show(word)}", pos)
            out.append((word, pos))
        return out

    def attribute(self, base: build.Node, attr: str, at: int) -> build.Node:
        self.operations += 1
        if self.operations > MAX_OPERATIONS:
            self.fail(f"expression has more than {MAX_OPERATIONS} operations; split it", at)
        type_ = self.attribute_type(base, attr, at)
        self.reads.add(attr)
        src = self.text[base.pos:base.end]
        path = None if base.var is None else (base.var, attr)
        return build.Node(build.read(base, attr, src), type_, base.pos, at + len(attr), path=path)

    def attribute_type(self, base: build.Node, attr: str, at: int) -> str | None:
        """The type of ``base.attr``, checked against the domain's types when known."""
        t, src = base.type, self.text[base.pos:base.end]
        if t == "null":
            self.fail(f"null has no attributes (reading {attr!r})", at)
        if t in ("number", "bool", "string"):
            self.fail(f"{src} is {_a(t)}, not an entity: it has no attribute {attr!r}", at)
        attrs = None if t is None or self.attributes is None else self.attributes.get(t)
        if attrs is None:  # unknown, a quoted name, or a type the domain does not describe
            return None
        if attr not in attrs:
            close = difflib.get_close_matches(attr, list(attrs), 1)
            hint = (f"; did you mean {close[0]!r}?" if close else
                    f" (its attributes: {', '.join(sorted(attrs))})" if attrs else
                    " (it has no attributes)")
            self.fail(f"{src} is {_a(t)}, which has no attribute {attr!r}{hint}", at)
        return _norm(attrs[attr])

    # -- checks and folding -----------------------------------------------------------

    def need_numbers(self, op: str, *nodes: build.Node) -> None:
        for node in nodes:
            if node.type not in (None, "number"):
                what = "a quoted string" if node.type == "name" else self.describe(node)
                self.fail(f"{op!r} needs numbers, not {what}", node.pos)

    def fold(self, fn: Callable, type_: str | None, parts: list[build.Node], *,
             boolean: bool = False) -> build.Node:
        """A node over ``parts``; computed now if they are all constants (so that
        ``-1`` or ``2 * 3`` cost nothing per call, and ``1 / 0`` is a compile error)."""
        pos, end = parts[0].pos, self.last_end
        self.operations += 1
        if self.operations > MAX_OPERATIONS:
            self.fail(f"expression has more than {MAX_OPERATIONS} operations; split it", pos)
        if all(p.const is not build.NOT_CONSTANT for p in parts):
            try:
                value = fn({}, None)
            except EvalError as err:
                raise ExprError(str(err), pos) from None
            node = build.const(value, type_, pos, end)
        else:
            node = build.Node(fn, type_, pos, end, boolean=boolean)
        return node


# -- tokens ---------------------------------------------------------------------------------


def _tokenize(text: str) -> list[tuple[str, str, int]]:
    out = []
    for m in re.finditer(_TOKEN, text, re.DOTALL):
        kind, word, pos = m.lastgroup or "bad", m.group(), m.start()
        if kind == "ws":
            continue
        if kind == "bad":
            if word in "\"'":
                raise ExprError(f"unterminated string: no closing {word}", pos)
            hint = {"!": "; use 'not' (or '!=')", "&": "; use 'and'", "|": "; use 'or'"}
            raise ExprError(f"unexpected character {word!r}{hint.get(word, '')}", pos)
        if word in ("&&", "||"):
            raise ExprError(f"unexpected {word!r}; use {'and' if word == '&&' else 'or'!r}", pos)
        out.append((kind, word, pos))
    out.append(("end", "", len(text)))
    return out


# -- types ---------------------------------------------------------------------------------


def _norm(type_: str | None) -> str | None:
    return None if type_ in (None, "any") else type_


def _public(type_: str | None) -> str | None:
    return {"name": "string", "null": None}.get(type_, type_) if type_ else None


def _comparable(a: str | None, b: str | None) -> bool:
    """Whether values of static types ``a`` and ``b`` can ever be equal (or ``b``
    assigned to an ``a``): numbers with numbers, booleans with booleans; quoted
    names and strings with any entity; distinct entity types never."""
    if a is None or b is None or "null" in (a, b) or a == b:
        return True
    scalar = ("number", "bool")
    if a in scalar or b in scalar:
        return False
    return a in ("name", "string") or b in ("name", "string")


def _a(type_: str) -> str:
    return f"{'an' if type_[:1].lower() in 'aeiou' else 'a'} {type_}"


def _show(word: str) -> str:
    return "the end" if word == "" else repr(word)
