"""The expression language of a scheme's data model: small, checked, bounded.

Expressions are written in a subset of Python's syntax (so editors and users
know it) but are never given to Python's ``eval``: the text is parsed with
:func:`ast.parse` and each node is compiled into a closure by this module,
which knows only the nodes below.  Everything else (comprehensions, lambdas,
``import``, walrus, f-strings, method calls …) is refused when the file is
loaded, with the column of the offending part.

* values: numbers, strings, ``True``/``False``/``None`` (also ``true``,
  ``false``, ``null``), lists ``[…]``, tuples, dictionaries ``{…}``;
* names: the scheme's declared variables and the system variables
  (:data:`SYSTEM_VARIABLES`); any other name is an error at load time;
* ``a.b`` reads key ``b`` of a mapping (``_event.data.answer``), ``a[i]``
  an item; no name or attribute may start with ``__``;
* arithmetic ``+ - * / // % **``, comparisons (``in`` and ``not in`` too),
  ``and``, ``or``, ``not``, ``x if c else y``;
* calls to the functions of :data:`FUNCTIONS` only, besides ``In('STATE')`` and
  ``bound('NAME')`` (whether a variable of that name has a value: a name that
  is not declared is no error there).

Evaluation is bounded: there are no loops, an expression has at most
:data:`MAX_SOURCE` characters and :data:`MAX_DEPTH` levels of nesting, and
every value an operation makes is checked (integers of at most
:data:`MAX_INT_BITS` bits, strings and collections of at most
:data:`MAX_LENGTH` items), so ``9**9**9`` or ``'x' * 10**9`` stop with an
:class:`EvaluationError` before any memory is spent.  A scheme turns that
error into SCXML's ``error.execution`` event.
"""

from __future__ import annotations

import ast
import operator
import reprlib
from collections.abc import Callable
from typing import Any

MAX_SOURCE = 2_000
"""Most characters of one expression."""
MAX_DEPTH = 32
"""Deepest nesting of an expression's syntax tree."""
MAX_INT_BITS = 4_096
"""Largest integer an evaluation may make, in bits."""
MAX_LENGTH = 100_000
"""Longest string, list, tuple or dictionary an evaluation may make."""

SYSTEM_VARIABLES = ("_event", "_sessionid", "_name", "_ioprocessors", "_x")
"""SCXML's system variables, bound in every scheme with a data model (read-only)."""
CONSTANTS = {"true": True, "false": False, "null": None}

Evaluator = Callable[[Any], Any]
"""A compiled expression: a function of the running instance."""


class ExpressionError(Exception):
    """An expression that cannot be compiled; ``col`` counts from 1 within its text."""

    def __init__(self, message: str, col: int = 1):
        super().__init__(message)
        self.message = message
        self.col = col


class EvaluationError(Exception):
    """An expression that failed while it was evaluated (SCXML's ``error.execution``)."""


def _check(value: Any) -> Any:
    """``value`` if it stays within the bounds of an evaluation, else :class:`EvaluationError`."""
    if isinstance(value, int) and not isinstance(value, bool):
        if value.bit_length() > MAX_INT_BITS:
            raise EvaluationError(f"an integer of more than {MAX_INT_BITS} bits")
    elif isinstance(value, (str, list, tuple, dict)) and len(value) > MAX_LENGTH:
        raise EvaluationError(f"a value of more than {MAX_LENGTH} items or characters")
    return value


def _power(a: Any, b: Any) -> Any:
    if isinstance(a, int) and isinstance(b, int) and b > 0 and abs(a) > 1 \
            and a.bit_length() * b > MAX_INT_BITS:
        raise EvaluationError(f"a power of more than {MAX_INT_BITS} bits")
    return a ** b


def _times(a: Any, b: Any) -> Any:
    if isinstance(a, int) and isinstance(b, (str, list, tuple)):
        a, b = b, a
    if isinstance(a, (str, list, tuple)) and isinstance(b, int) and len(a) * b > MAX_LENGTH:
        raise EvaluationError(f"a value of more than {MAX_LENGTH} items or characters")
    return a * b


def _shift(a: Any, b: Any) -> Any:
    if isinstance(b, int) and b > MAX_INT_BITS:
        raise EvaluationError(f"an integer of more than {MAX_INT_BITS} bits")
    return a << b


SHOWN = reprlib.Repr()
"""How a collection is written as text: cut to a few levels and items, so that a list
holding itself a million times over cannot make a string of a terabyte."""
SHOWN.maxlevel, SHOWN.maxlist, SHOWN.maxtuple, SHOWN.maxdict = 4, 50, 50, 50
SHOWN.maxstring = SHOWN.maxother = 1_000


def show(value: Any) -> str:
    """A value as text, bounded (strings as they are, collections cut)."""
    return value if isinstance(value, str) else SHOWN.repr(value)


def _str(value: Any = "") -> str:
    return _check(show(value) if isinstance(value, (list, tuple, dict)) else
                  value if isinstance(value, str) else str(value))


def _modulo(a: Any, b: Any) -> Any:
    if isinstance(a, str):  # printf-style formatting could ask for any width
        raise EvaluationError("'%' does not format strings in an expression")
    return a % b


FUNCTIONS: dict[str, Callable[..., Any]] = {
    "len": len, "str": _str, "int": int, "float": float, "bool": bool, "abs": abs,
    "min": min, "max": max, "round": round,
    "list": lambda value=(): list(value),
}
"""The functions an expression may call (besides ``In`` and ``bound``), all bounded in time
and memory."""

_BINARY: dict[type, Callable[[Any, Any], Any]] = {
    ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: _times, ast.Div: operator.truediv,
    ast.FloorDiv: operator.floordiv, ast.Mod: _modulo, ast.Pow: _power,
    ast.LShift: _shift, ast.RShift: operator.rshift, ast.BitAnd: operator.and_,
    ast.BitOr: operator.or_, ast.BitXor: operator.xor,
}
_COMPARE: dict[type, Callable[[Any, Any], Any]] = {
    ast.Eq: operator.eq, ast.NotEq: operator.ne, ast.Lt: operator.lt, ast.LtE: operator.le,
    ast.Gt: operator.gt, ast.GtE: operator.ge, ast.In: lambda a, b: a in b,
    ast.NotIn: lambda a, b: a not in b, ast.Is: operator.is_, ast.IsNot: operator.is_not,
}
_UNARY: dict[type, Callable[[Any], Any]] = {
    ast.Not: operator.not_, ast.USub: operator.neg, ast.UAdd: operator.pos,
    ast.Invert: operator.invert,
}


class Expression:
    """One compiled expression: its text, the variables it reads, and its evaluator."""

    __slots__ = ("source", "names", "states", "evaluate")

    def __init__(self, source: str, names: frozenset[str], states: frozenset[str],
                 evaluate: Evaluator):
        self.source = source
        self.names = names
        """The variables it reads (system variables included)."""
        self.states = states
        """The states it names in ``In('STATE')``."""
        self.evaluate = evaluate

    def __repr__(self) -> str:
        return f"Expression({self.source!r})"

    def __call__(self, instance: Any) -> Any:
        """The value for a running instance; :class:`EvaluationError` if it fails."""
        try:
            return self.evaluate(instance)
        except EvaluationError:
            raise
        except (ArithmeticError, LookupError, TypeError, ValueError, AttributeError,
                RecursionError, MemoryError) as err:
            raise EvaluationError(f"{self.source!r}: {type(err).__name__}: {err}") from None


class Location:
    """Where an ``assign`` writes: a variable, or a key or item below one."""

    __slots__ = ("source", "name", "path", "names", "states")

    def __init__(self, source: str, name: str, path: tuple[Evaluator, ...],
                 names: frozenset[str], states: frozenset[str]):
        self.source = source
        self.name = name
        self.path = path
        self.names = names
        self.states = states

    def __repr__(self) -> str:
        return f"Location({self.source!r})"

    def read(self, instance: Any) -> Any:
        """The value there; :class:`EvaluationError` when there is none."""
        try:
            node = instance.data[self.name]
            for key in self.path:
                node = node[key(instance)]
            return node
        except (LookupError, TypeError) as err:
            raise EvaluationError(f"{self.source!r}: nothing there ({type(err).__name__})"
                                  ) from None

    def assign(self, instance: Any, value: Any) -> None:
        """Write ``value`` there; :class:`EvaluationError` when there is no such place."""
        data = instance.data
        if self.name in SYSTEM_VARIABLES:
            raise EvaluationError(f"{self.source!r}: system variables cannot be assigned")
        if not self.path:
            data[self.name] = value
            return
        try:
            node = data[self.name]
            for key in self.path[:-1]:
                node = node[key(instance)]
            last = self.path[-1](instance)
            if isinstance(node, list):
                node[last] = value
            elif isinstance(node, dict):
                node[last] = value
            else:
                raise TypeError(f"a {type(node).__name__} has no items to assign")
        except (LookupError, TypeError) as err:
            raise EvaluationError(f"{self.source!r}: {type(err).__name__}: {err}") from None


def compile_expression(source: str) -> Expression:
    """Compile an expression's text; :class:`ExpressionError` with a column if it is not one."""
    tree = _parse(source)
    compiler = _Compiler(source)
    evaluate = compiler.node(tree.body, 1)
    return Expression(source, frozenset(compiler.names), frozenset(compiler.states), evaluate)


def compile_location(source: str) -> Location:
    """Compile an assignable place: ``name``, ``name.key``, ``name[index]`` …"""
    tree = _parse(source)
    compiler = _Compiler(source)
    path: list[Evaluator] = []
    node = tree.body
    while isinstance(node, (ast.Attribute, ast.Subscript)):
        if isinstance(node, ast.Attribute):
            compiler.attribute_name(node)
            key = node.attr
            path.append(lambda instance, key=key: key)
        else:
            path.append(compiler.node(node.slice, 2))
        node = node.value
    if not isinstance(node, ast.Name):
        raise ExpressionError(f"{source.strip()!r} is not a place to assign to (a variable, "
                              "optionally followed by .key or [index])", _col(node))
    compiler.name(node)
    return Location(source, node.id, tuple(reversed(path)), frozenset(compiler.names),
                    frozenset(compiler.states))


def _parse(source: str) -> ast.Expression:
    if len(source) > MAX_SOURCE:
        raise ExpressionError(f"an expression of more than {MAX_SOURCE} characters")
    if not source.strip():
        raise ExpressionError("an empty expression")
    try:
        return ast.parse(source.strip(), mode="eval")
    except SyntaxError as err:
        raise ExpressionError(f"syntax error in expression {source.strip()!r}: {err.msg}",
                              max(1, err.offset or 1)) from None
    except (RecursionError, MemoryError, ValueError):
        raise ExpressionError(f"expression nested too deeply (at most {MAX_DEPTH} levels)"
                              ) from None


def _col(node: ast.AST) -> int:
    return getattr(node, "col_offset", 0) + 1


class _Compiler:
    """Turns a checked syntax tree into closures, collecting the names it reads."""

    def __init__(self, source: str):
        self.source = source
        self.names: set[str] = set()
        self.states: set[str] = set()

    def refuse(self, node: ast.AST, what: str) -> ExpressionError:
        return ExpressionError(f"{what} is not allowed in an expression ({self.source.strip()!r})",
                               _col(node))

    def name(self, node: ast.Name) -> None:
        if node.id.startswith("__"):
            raise self.refuse(node, f"the name {node.id!r}")
        self.names.add(node.id)

    def attribute_name(self, node: ast.Attribute) -> None:
        if node.attr.startswith("__"):
            raise self.refuse(node, f"the attribute {node.attr!r}")

    def node(self, node: ast.AST, depth: int) -> Evaluator:
        if depth > MAX_DEPTH:
            raise ExpressionError(f"expression nested too deeply (at most {MAX_DEPTH} levels)",
                                  _col(node))
        method = getattr(self, "_" + type(node).__name__, None)
        if method is None:
            raise self.refuse(node, type(node).__name__)
        return method(node, depth + 1)

    def _Constant(self, node: ast.Constant, depth: int) -> Evaluator:
        value = node.value
        if not isinstance(value, (int, float, str, bool, type(None))):
            raise self.refuse(node, f"the constant {value!r}")
        return lambda instance: value

    def _Name(self, node: ast.Name, depth: int) -> Evaluator:
        if node.id in CONSTANTS:
            value = CONSTANTS[node.id]
            return lambda instance: value
        self.name(node)
        name = node.id

        def read(instance: Any) -> Any:
            try:
                return instance.data[name]
            except KeyError:
                raise EvaluationError(f"{name!r} is not bound") from None
        return read

    def _Attribute(self, node: ast.Attribute, depth: int) -> Evaluator:
        self.attribute_name(node)
        value, key = self.node(node.value, depth), node.attr

        def read(instance: Any) -> Any:
            found = value(instance)
            if not isinstance(found, dict):
                raise EvaluationError(f"{self.source.strip()!r}: a {type(found).__name__} "
                                      f"has no key {key!r}")
            try:
                return found[key]
            except KeyError:
                raise EvaluationError(f"{self.source.strip()!r}: no key {key!r}") from None
        return read

    def _Subscript(self, node: ast.Subscript, depth: int) -> Evaluator:
        value, index = self.node(node.value, depth), self.node(node.slice, depth)
        return lambda instance: _check(value(instance)[index(instance)])

    def _Slice(self, node: ast.Slice, depth: int) -> Evaluator:
        parts = [self.node(p, depth) if p is not None else (lambda instance: None)
                 for p in (node.lower, node.upper, node.step)]
        return lambda instance: slice(*(p(instance) for p in parts))

    def _BinOp(self, node: ast.BinOp, depth: int) -> Evaluator:
        op = _BINARY.get(type(node.op))
        if op is None:
            raise self.refuse(node, type(node.op).__name__)
        left, right = self.node(node.left, depth), self.node(node.right, depth)
        return lambda instance: _check(op(left(instance), right(instance)))

    def _UnaryOp(self, node: ast.UnaryOp, depth: int) -> Evaluator:
        op, operand = _UNARY[type(node.op)], self.node(node.operand, depth)
        return lambda instance: op(operand(instance))

    def _BoolOp(self, node: ast.BoolOp, depth: int) -> Evaluator:
        values = [self.node(v, depth) for v in node.values]
        if isinstance(node.op, ast.And):
            def conjunction(instance: Any) -> Any:
                result = True
                for v in values:
                    result = v(instance)
                    if not result:
                        return result
                return result
            return conjunction

        def disjunction(instance: Any) -> Any:
            result = False
            for v in values:
                result = v(instance)
                if result:
                    return result
            return result
        return disjunction

    def _Compare(self, node: ast.Compare, depth: int) -> Evaluator:
        first = self.node(node.left, depth)
        rest = [(_COMPARE[type(op)], self.node(v, depth))
                for op, v in zip(node.ops, node.comparators, strict=True)]
        if len(rest) == 1:
            op, right = rest[0]
            return lambda instance: op(first(instance), right(instance))

        def chain(instance: Any) -> bool:
            left = first(instance)
            for op, right in rest:
                value = right(instance)
                if not op(left, value):
                    return False
                left = value
            return True
        return chain

    def _IfExp(self, node: ast.IfExp, depth: int) -> Evaluator:
        test, body, orelse = (self.node(n, depth) for n in (node.test, node.body, node.orelse))
        return lambda instance: body(instance) if test(instance) else orelse(instance)

    def _List(self, node: ast.List, depth: int) -> Evaluator:
        items = [self.node(e, depth) for e in node.elts]
        return lambda instance: [i(instance) for i in items]

    def _Tuple(self, node: ast.Tuple, depth: int) -> Evaluator:
        items = [self.node(e, depth) for e in node.elts]
        return lambda instance: tuple(i(instance) for i in items)

    def _Dict(self, node: ast.Dict, depth: int) -> Evaluator:
        if any(k is None for k in node.keys):
            raise self.refuse(node, "'**' in a dictionary")
        pairs = [(self.node(k, depth), self.node(v, depth))  # type: ignore[arg-type]
                 for k, v in zip(node.keys, node.values, strict=True)]
        return lambda instance: {k(instance): v(instance) for k, v in pairs}

    def _Call(self, node: ast.Call, depth: int) -> Evaluator:
        if not isinstance(node.func, ast.Name) or node.keywords:
            raise self.refuse(node, "a call other than NAME(ARGUMENTS)")
        name = node.func.id
        if any(isinstance(a, ast.Starred) for a in node.args):
            raise self.refuse(node, "'*' in a call")
        if name == "In":
            arg = node.args[0] if len(node.args) == 1 else None
            if not (isinstance(arg, ast.Constant) and isinstance(arg.value, str)):
                raise ExpressionError("In() takes one state name in quotes: In('STATE')",
                                      _col(node))
            state = arg.value
            self.states.add(state)
            return lambda instance: instance.is_active(state)
        if name == "bound":
            arg = node.args[0] if len(node.args) == 1 else None
            if not (isinstance(arg, ast.Constant) and isinstance(arg.value, str)):
                raise ExpressionError("bound() takes one variable name in quotes: "
                                      "bound('NAME')", _col(node))
            variable = arg.value
            return lambda instance: instance.data.get(variable) is not None
        func = FUNCTIONS.get(name)
        if func is None:
            raise ExpressionError(f"unknown function {name!r}; an expression may call "
                                  f"In, bound, {', '.join(FUNCTIONS)}", _col(node))
        args = [self.node(a, depth) for a in node.args]
        return lambda instance: _check(func(*(a(instance) for a in args)))
