"""The closures that compiled expressions are made of: every decision taken once.

:mod:`planner.model.expr` parses and type-checks a text; each node of its syntax
tree becomes one of these closures, which the search then calls millions of
times.  The split follows that seam: the parser decides *what* a text means,
this module decides *how* it runs fast (a constant operand folded, a variable
read without a look-up chain, the common case first, the slow path only when
the types could not rule an error out at compile time).
"""

from __future__ import annotations

import operator
from collections.abc import Callable
from typing import Any

NUMBER_TYPES = frozenset((int, float))
NOT_CONSTANT = object()  # "not a constant"


class EvalError(Exception):
    """A problem only the state reveals: assigning through null, arithmetic on a
    null or a string, division by zero."""


Getter = Callable[[str, str], Any]
Setter = Callable[[str, str, Any], None]


class Node:
    """One parsed node: its closure, static type, span, and what specialisation needs."""

    __slots__ = ("fn", "type", "pos", "end", "const", "var", "path", "boolean")

    def __init__(self, fn: Callable, type_: str | None, pos: int, end: int, *,
                 const: Any = NOT_CONSTANT, var: str | None = None,
                 path: tuple[str, str] | None = None, boolean: bool = False):
        self.fn, self.type, self.pos, self.end = fn, type_, pos, end
        self.const, self.var, self.path, self.boolean = const, var, path, boolean


def const(value: Any, type_: str | None, pos: int, end: int) -> Node:
    return Node(lambda env, get: value, type_, pos, end, const=value,
                 boolean=isinstance(value, bool))


def read(base: Node, attr: str, src: str) -> Callable:
    """``base.attr``: null propagates, a non-entity is an error.  The common case,
    an attribute of a variable, reads the variable itself (one closure, not two)."""

    def bad(value: Any) -> EvalError:
        return EvalError(f"{src} is {value!r}, not an entity: it has no attribute {attr!r}")

    if base.var is not None:
        var = base.var

        def read_var(env: dict, get: Getter) -> Any:
            entity = env[var]
            if entity.__class__ is str:
                return get(entity, attr)
            if entity is None:
                return None
            raise bad(entity)

        return read_var
    inner = base.fn

    def read(env: dict, get: Getter) -> Any:
        entity = inner(env, get)
        if entity.__class__ is str:
            return get(entity, attr)
        if entity is None:
            return None
        raise bad(entity)

    return read


def logic(conjunction: bool, parts: list[Node]) -> Callable:
    """``a and b and ...`` / ``a or b or ...`` as one closure, always giving a bool."""
    fns = tuple(p.fn for p in parts)
    if conjunction:
        if len(fns) == 2:
            a, b = fns
            fn = lambda env, get: a(env, get) and b(env, get)  # noqa: E731
        elif len(fns) == 3:
            a, b, c = fns
            fn = lambda env, get: a(env, get) and b(env, get) and c(env, get)  # noqa: E731
        elif len(fns) == 4:
            a, b, c, d = fns
            fn = lambda env, get: (  # noqa: E731
                a(env, get) and b(env, get) and c(env, get) and d(env, get))
        else:

            def fn(env: dict, get: Getter) -> Any:  # a loop: no generator made per call
                value = True
                for f in fns:
                    value = f(env, get)
                    if not value:
                        return value
                return value

    elif len(fns) == 2:
        a, b = fns
        fn = lambda env, get: a(env, get) or b(env, get)  # noqa: E731
    elif len(fns) == 3:
        a, b, c = fns
        fn = lambda env, get: a(env, get) or b(env, get) or c(env, get)  # noqa: E731
    else:

        def fn(env: dict, get: Getter) -> Any:
            value = False
            for f in fns:
                value = f(env, get)
                if value:
                    return value
            return value

    if all(p.boolean for p in parts):
        return fn
    return lambda env, get: True if fn(env, get) else False


def compare(op: str, left: Node, right: Node, src: str) -> Callable:
    """A comparison.  Equality against a constant or a variable reads it directly,
    and ``var.attr == <constant or variable>``, the bulk of preconditions, is one
    closure (the general reader only serves when var is not an entity)."""
    if op in ("==", "!="):
        if left.const is not NOT_CONSTANT or (left.var is not None and right.const is NOT_CONSTANT):
            left, right = right, left  # equality is symmetric: put the simple side right
        f, c, v = left.fn, right.const, right.var
        if left.path is not None and (c is not NOT_CONSTANT or v is not None):
            var, attr = left.path
            test = ((operator.is_ if op == "==" else operator.is_not) if c is None else
                    (operator.eq if op == "==" else operator.ne))
            if v is None:
                return lambda env, get: test(
                    get(e, attr) if (e := env[var]).__class__ is str else f(env, get), c)
            return lambda env, get: test(
                get(e, attr) if (e := env[var]).__class__ is str else f(env, get), env[v])
        if c is None:
            return ((lambda env, get: f(env, get) is None) if op == "==" else
                    (lambda env, get: f(env, get) is not None))
        if c is not NOT_CONSTANT:
            return ((lambda env, get: f(env, get) == c) if op == "==" else
                    (lambda env, get: f(env, get) != c))
        if v is not None:
            return ((lambda env, get: f(env, get) == env[v]) if op == "==" else
                    (lambda env, get: f(env, get) != env[v]))
        g = right.fn
        if left.path is not None and right.path is not None:  # var.a == var2.b: one closure
            (var, attr), (var2, attr2) = left.path, right.path
            test = operator.eq if op == "==" else operator.ne
            return lambda env, get: test(
                get(e, attr) if (e := env[var]).__class__ is str else f(env, get),
                get(e2, attr2) if (e2 := env[var2]).__class__ is str else g(env, get))
        return ((lambda env, get: f(env, get) == g(env, get)) if op == "==" else
                (lambda env, get: f(env, get) != g(env, get)))
    order = {"<": operator.lt, "<=": operator.le, ">": operator.gt, ">=": operator.ge}[op]
    f, g = left.fn, right.fn

    def compare(env: dict, get: Getter) -> bool:
        a, b = f(env, get), g(env, get)
        try:
            return order(a, b)
        except TypeError:
            if a is None or b is None:
                return False
            raise EvalError(f"cannot compute {src}: cannot order {a!r} and {b!r}") from None

    return compare


def arith(op: str, f: Callable, g: Callable | None, src: str) -> Callable:
    """``+ - * /`` and negation over numbers; anything else is an EvalError."""
    nums = NUMBER_TYPES
    if g is None:

        def negate(env: dict, get: Getter) -> Any:
            a = f(env, get)
            if a.__class__ not in nums:
                numbers(src, a)
            return -a

        return negate
    apply = {"+": operator.add, "-": operator.sub, "*": operator.mul,
             "/": operator.truediv}[op]

    def arith(env: dict, get: Getter) -> Any:
        a, b = f(env, get), g(env, get)
        if a.__class__ not in nums or b.__class__ not in nums:
            numbers(src, a, b)
        try:
            return apply(a, b)
        except ZeroDivisionError:
            raise EvalError(f"division by zero in {src}") from None

    return arith


def function(name: str, fns: list[Callable], src: str) -> Callable:
    if name == "abs":
        (f,) = fns

        def absolute(env: dict, get: Getter) -> Any:
            a = f(env, get)
            if a.__class__ not in NUMBER_TYPES:
                numbers(src, a)
            return abs(a)

        return absolute
    pick = min if name == "min" else max

    def extreme(env: dict, get: Getter) -> Any:
        values = [f(env, get) for f in fns]
        numbers(src, *values)
        return pick(values)

    return extreme


def numbers(src: str, *values: Any) -> None:
    """Raise unless all ``values`` are numbers (the slow path of arithmetic)."""
    for value in values:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            what = "null" if value is None else repr(value)
            raise EvalError(f"cannot compute {src}: {what} is not a number")


def assign(owner: Node, attr: str, value: Node, owner_src: str, target: str) -> Callable:
    """The closure of an effect: find the entity, then ``set`` its attribute."""

    def bad(entity: Any) -> EvalError:
        what = "null" if entity is None else f"{entity!r}, not an entity"
        return EvalError(f"cannot assign {target}: {owner_src} is {what}")

    find = owner.fn
    if owner.var is not None:  # var.attr = ...: the variable itself, one closure not two
        var = owner.var
        if value.const is not NOT_CONSTANT:
            c = value.const

            def assign_var_const(env: dict, get: Getter, set: Setter) -> None:
                entity = env[var]
                if entity.__class__ is not str:
                    raise bad(entity)
                set(entity, attr, c)

            return assign_var_const
        compute = value.fn

        def assign_var(env: dict, get: Getter, set: Setter) -> None:
            entity = env[var]
            if entity.__class__ is not str:
                raise bad(entity)
            set(entity, attr, compute(env, get))

        return assign_var
    if value.const is not NOT_CONSTANT:
        c = value.const

        def assign_const(env: dict, get: Getter, set: Setter) -> None:
            entity = find(env, get)
            if entity.__class__ is not str:
                raise bad(entity)
            set(entity, attr, c)

        return assign_const
    compute = value.fn

    def assign(env: dict, get: Getter, set: Setter) -> None:
        entity = find(env, get)
        if entity.__class__ is not str:
            raise bad(entity)
        set(entity, attr, compute(env, get))

    return assign


