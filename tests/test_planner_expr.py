"""The expression language of planning domains (planner/model/expr.py)."""

from __future__ import annotations

import ast
import operator
import re
from pathlib import Path
from typing import Any

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from planner.model import closures as closures_module
from planner.model import expr as expr_module
from planner.model.expr import EvalError, ExprError, compile_effect, compile_expr

ATTRIBUTES = {
    "Place": {},
    "Agent": {"kind": "string", "at": "Place", "carries": "Object", "x": "number",
              "note": "any"},
    "Furniture": {"place": "Place", "container": "bool"},
    "Object": {"on": "Furniture", "holder": "Agent", "owner": "Agent", "robot_reach": "bool"},
}
TYPED = {"ag": "Agent", "to": "Place", "obj": "Object", "f": "Furniture", "u": None}

STATE: dict[tuple[str, str], Any] = {
    ("jido", "kind"): "robot", ("jido", "at"): "base", ("jido", "carries"): None,
    ("jido", "x"): 2,
    ("alice", "kind"): "human", ("alice", "at"): "sofa-area", ("alice", "carries"): None,
    ("alice", "x"): 5.5,
    ("coffee-table", "place"): "coffee-area", ("coffee-table", "container"): False,
    ("bottle", "on"): None, ("bottle", "holder"): "alice", ("bottle", "owner"): "jido",
    ("cup", "on"): "coffee-table", ("cup", "holder"): None, ("cup", "owner"): None,
}
ENV = {"r": "jido", "h": "alice", "o": "bottle", "c": "cup", "p": "sofa-area", "n": None,
       "t": "coffee-table", "num": 3}


def get(entity: str, attribute: str) -> Any:
    return STATE.get((entity, attribute))


def run(text: str, env: dict[str, Any] = ENV) -> Any:
    return compile_expr(text, {name: None for name in env})(env, get)


def apply(text: str, env: dict[str, Any] = ENV) -> list[tuple[str, str, Any]]:
    writes: list[tuple[str, str, Any]] = []
    effect = compile_effect(text, {name: None for name in env})
    effect(env, get, lambda entity, attr, value: writes.append((entity, attr, value)))
    return writes


def error(text: str, variables: dict[str, str | None] | None = None,
          attributes: dict[str, dict[str, str]] | None = None, *,
          effect: bool = False) -> ExprError:
    compile_ = compile_effect if effect else compile_expr
    with pytest.raises(ExprError) as info:
        compile_(text, {"a": None, "b": None} if variables is None else variables, attributes)
    return info.value


# -- literals, precedence ---------------------------------------------------------------


@pytest.mark.parametrize("text, value", [
    ("42", 42), ("2.5", 2.5), ("1e3", 1000.0), ("'a b'", "a b"), ('"coffee-table"', "coffee-table"),
    ("true", True), ("false", False), ("null", None),
    ("1 + 2 * 3", 7), ("(1 + 2) * 3", 9), ("10 - 4 - 3", 3), ("8 / 4 / 2", 1.0),
    ("2 * -3", -6), ("- - 2", 2), ("-(1 + 2)", -3), ("7 / 2", 3.5),
    ("1 + 2 == 3", True), ("2 * 3 > 5", True),
])
def test_literals_and_arithmetic_precedence(text: str, value: Any) -> None:
    result = run(text)
    assert result == value and type(result) is type(value)


@pytest.mark.parametrize("text, value", [
    ("true or false and false", True),         # and binds tighter than or
    ("(true or false) and false", False),
    ("not false and false", False),             # not binds tighter than and
    ("not 1 == 2", True),                       # ... and looser than comparisons
    ("not not true", True),
    ("1 < 2 and 2 <= 2 and 3 > 2 and 3 >= 4", False),
    ("false or false or true", True),
    ("true and true and true and false", False),
    ("false or false or false or true", True),
])
def test_boolean_precedence(text: str, value: bool) -> None:
    assert run(text) is value


def test_logic_gives_booleans() -> None:
    assert run("o.holder and r.x") is True
    assert run("c.holder or 0") is False
    assert run("not o.on") is True


def test_functions() -> None:
    assert run("min(r.x, h.x, 1)") == 1
    assert run("max(r.x, h.x)") == 5.5
    assert run("abs(r.x - h.x)") == 3.5
    assert run("min(3)") == 3


def test_cost_expression() -> None:
    cost = compile_expr("3 + 2 * abs(a.x - b.x)", {"a": "Agent", "b": "Agent"}, ATTRIBUTES)
    assert cost({"a": "jido", "b": "alice"}, get) == 10.0
    assert cost.type == "number" and cost.reads == {"x"} and cost.variables == {"a", "b"}


def test_constants_are_folded() -> None:
    assert run("2 * 3 + 1") == 7
    assert compile_expr("-1", {}).fn({}, None) == -1  # no state needed at all


# -- attributes, entity names, null ---------------------------------------------------------


def test_attribute_of_a_variable() -> None:
    assert run("r.at") == "base"
    assert run("r.kind == 'robot'") is True


def test_attribute_chains() -> None:
    assert run("o.holder.at") == "sofa-area"
    assert run("o.holder.at == p") is True
    assert run("o.owner.kind") == "robot"
    assert run("c.on.place") == "coffee-area"


def test_chains_propagate_null() -> None:
    assert run("c.holder") is None
    assert run("c.holder.at") is None
    assert run("c.holder.at == p") is False
    assert run("c.holder.at != p") is True
    assert run("c.holder.at.place.x") is None
    assert run("n.at") is None
    assert run("(n).at.kind == null") is True


def test_quoted_entity_names() -> None:
    assert run('"coffee-table".place') == "coffee-area"
    assert run('t == "coffee-table"') is True
    assert run("'coffee-table' == t") is True
    assert run('c.on == "coffee-table" and "coffee-table".place == "coffee-area"') is True


def test_comparisons_with_null() -> None:
    assert run("r.carries == null") is True
    assert run("null == r.carries") is True
    assert run("r.carries != null") is False
    assert run("o.holder != null") is True
    assert run("null == null") is True
    assert run("n == null and n != 'x'") is True
    for op in ("<", "<=", ">", ">="):
        assert run(f"c.holder.x {op} 3") is False
        assert run(f"3 {op} c.holder.x") is False
        assert run(f"n {op} n") is False


def test_equality_against_variables_and_attributes() -> None:
    assert run("r.at != p and o.holder == h and r.carries == null") is True
    assert run("p == r.at") is False
    assert run("o.holder.at == h.at") is True
    assert run("r != h") is True


def test_typical_precondition() -> None:
    pre = compile_expr("ag.at != to and obj.on == f and ag.carries == null", TYPED, ATTRIBUTES)
    env = {"ag": "jido", "to": "coffee-area", "obj": "cup", "f": "coffee-table"}
    assert pre(env, get) is True
    assert pre({**env, "to": "base"}, get) is False
    assert pre({**env, "obj": "bottle"}, get) is False
    assert pre.fn(env, get) is True
    assert pre.variables == {"ag", "to", "obj", "f"}
    assert pre.reads == {"at", "on", "carries"}
    assert pre.type == "bool"
    assert pre.text == "ag.at != to and obj.on == f and ag.carries == null"


def test_reads_and_variables_of_chains() -> None:
    e = compile_expr("obj.owner.at == to or abs(u.x) > 1", TYPED, ATTRIBUTES)
    assert e.reads == {"owner", "at", "x"}
    assert e.variables == {"obj", "to", "u"}


# -- effects ------------------------------------------------------------------------------


def test_effects() -> None:
    assert apply("r.at = p") == [("jido", "at", "sofa-area")]
    assert apply("r.carries = o") == [("jido", "carries", "bottle")]
    assert apply("o.holder = null") == [("bottle", "holder", None)]
    assert apply("r.x = r.x + 2 * 3") == [("jido", "x", 8)]
    assert apply('r.at = "coffee-area"') == [("jido", "at", "coffee-area")]


def test_chained_effect_targets() -> None:
    assert apply("o.holder.at = p") == [("alice", "at", "sofa-area")]
    assert apply("o.owner.carries = o") == [("jido", "carries", "bottle")]
    effect = compile_effect("obj.holder.at = to", TYPED, ATTRIBUTES)
    assert effect.target_attribute == "at"
    assert effect.reads == {"holder"}
    assert effect.variables == {"obj", "to"}
    assert effect.text == "obj.holder.at = to"


def test_effect_attributes() -> None:
    effect = compile_effect("ag.carries = null", TYPED, ATTRIBUTES)
    assert effect.target_attribute == "carries" and effect.reads == set()
    assert effect.variables == {"ag"}


def test_assigning_through_null_is_an_eval_error() -> None:
    with pytest.raises(EvalError, match=r"cannot assign c\.holder\.at: c\.holder is null"):
        apply("c.holder.at = p")
    with pytest.raises(EvalError, match=r"n is null"):
        apply("n.at = p")
    with pytest.raises(EvalError, match="not an entity"):
        apply("num.at = p")


# -- run-time errors ------------------------------------------------------------------------


@pytest.mark.parametrize("text, message", [
    ("r.kind + 1", r"cannot compute r\.kind \+ 1: 'robot' is not a number"),
    ("1 + r.kind", r"'robot' is not a number"),
    ("c.holder.x + 1", r"null is not a number"),
    ("-r.kind", r"'robot' is not a number"),
    ("abs(n)", r"null is not a number"),
    ("max(r.x, c.holder)", r"null is not a number"),
    ("r.x / (h.x - 5.5)", r"division by zero in r\.x / \(h\.x - 5\.5\)"),
    ("r.kind < 3", r"cannot order 'robot' and 3"),
    ("num.at", r"num is 3, not an entity"),
    ("r.x.y", r"r\.x is 2, not an entity"),
    ("u + 1", r"True is not a number"),
])
def test_eval_errors(text: str, message: str) -> None:
    with pytest.raises(EvalError, match=message):
        run(text, {**ENV, "u": True})


def test_string_plus_number_in_an_effect() -> None:
    with pytest.raises(EvalError, match="not a number"):
        apply("r.x = r.kind + 1")


# -- syntax errors, each at its offset --------------------------------------------------------


@pytest.mark.parametrize("text, offset, message", [
    ("(a.x + 1", 0, "'(' is never closed"),
    ("abs(a.x", 3, "'(' is never closed"),
    ("(a.x + 1 b", 9, "expected ')'"),
    ("a.x)", 3, "unbalanced ')'"),
    ("a.x +", 4, "ends after '+'"),
    ("a.x == b.x and", 11, "ends after 'and'"),
    ("not", 0, "ends after 'not'"),
    ("a.x + * 2", 6, "expected a value, found '*'"),
    ("", 0, "empty expression"),
    ("   ", 0, "empty expression"),
    ("foo(a)", 0, "unknown function 'foo'"),
    ("1 + mni(a.x, 1)", 4, "did you mean 'min'"),
    ("abs(1, 2)", 0, "abs takes one argument"),
    ("max()", 0, "at least one argument"),
    ("sofa", 0, "unknown name 'sofa'; write entity names in quotes: \"sofa\""),
    ("a.on == sofa", 8, "unknown name 'sofa'"),
    ("aa.x", 0, "did you mean 'a'"),
    ("True", 0, "write true"),
    ("a == b == a", 7, "cannot be chained"),
    ("a.x = 1", 4, "use '==' to compare"),
    ("a.x @ 2", 4, "unexpected character '@'"),
    ("a && b", 2, "use 'and'"),
    ("a || b", 2, "use 'or'"),
    ("!a", 0, "use 'not'"),
    ("a.on == 'sofa", 8, "unterminated string"),
    ("a.", 2, "expected an attribute name"),
    ("a.1", 2, "expected an attribute name after '.', found '1'"),
    ("a b", 2, "unexpected 'b'"),
    ("null.x", 5, "null has no attributes"),
    ("1.5.x", 4, "not an entity"),
    ("1 / 0", 0, "division by zero"),
    ("'x' + 1", 0, "'+' needs numbers, not a quoted string"),
    ("true * 2", 0, "'*' needs numbers"),
    ("a < 'b'", 4, "'<' orders numbers"),
    ("a.x and", 4, "ends after 'and'"),
])
def test_syntax_error_offsets(text: str, offset: int, message: str) -> None:
    err = error(text)
    assert err.offset == offset, err
    assert message in err.message
    assert str(err) == f"{err.message} (at offset {offset})"


@pytest.mark.parametrize("text, offset, message", [
    ("a.x == b", 4, "an effect assigns with '=', not '=='"),
    ("a.x = b == ", 8, "ends after '=='"),
    ("a.x = ", 4, "ends after '='"),
    ("a = b", 0, "write a.attribute = value"),
    ("a.x", 3, "expected '=' after a.x, found the end"),
    ("a.x + 1 = b", 4, "expected '=' after a.x, found '+'"),
    ("a.x = b = 1", 8, "'=' assigns, once, in an effect"),
    ("abs(a).x = 1", 0, "an effect assigns an attribute of a variable"),
    ("'jido'.at = b", 0, "an effect assigns an attribute"),
    ("sofa.x = 1", 0, "unknown name 'sofa'"),
    ("a.x = (b", 6, "'(' is never closed"),
])
def test_effect_syntax_error_offsets(text: str, offset: int, message: str) -> None:
    err = error(text, effect=True)
    assert err.offset == offset, err
    assert message in err.message


def test_offset_can_be_shifted_by_a_caller() -> None:
    err = error("a +")
    err.offset += 10
    assert err.offset == 12 and "at offset 12" in str(err)


def test_errors_pickle() -> None:
    import pickle

    err = pickle.loads(pickle.dumps(error("a +")))
    assert (err.message, err.offset) == ("the expression ends after '+'", 2)


# -- types ------------------------------------------------------------------------------------


@pytest.mark.parametrize("text, offset, message", [
    ("ag.att == to", 3, "ag is an Agent, which has no attribute 'att'; did you mean 'at'?"),
    ("obj.owner.att == to", 10, "obj.owner is an Agent, which has no attribute 'att'; "
                                "did you mean 'at'?"),
    ("obj.holder.carries.onn == f", 19, "obj.holder.carries is an Object, which has no "
                                        "attribute 'onn'; did you mean 'on'?"),
    ("ag.zzz", 3, "(its attributes: at, carries, kind, note, x)"),
    ("f.place.x", 8, "f.place is a Place, which has no attribute 'x' (it has no attributes)"),
    ("ag.kind.x", 8, "ag.kind is a string, not an entity"),
    ("obj.robot_reach.x", 16, "is a bool, not an entity"),
    ("ag.kind + 1", 0, "'+' needs numbers, not ag.kind (a string)"),
    ("abs(ag)", 4, "'abs' needs numbers, not ag (an Agent)"),
    ("-obj.on", 1, "'-' needs numbers"),
    ("ag.at == obj", 6, "ag.at (a Place) and obj (an Object) are never equal"),
    ("obj.holder.at == 3", 14, "are never equal"),
    ("obj.robot_reach == 'yes'", 16, "are never equal"),
    ("ag.at < to", 0, "'<' orders numbers, not ag.at (a Place)"),
])
def test_type_errors(text: str, offset: int, message: str) -> None:
    err = error(text, TYPED, ATTRIBUTES)
    assert err.offset == offset, err
    assert message in err.message, err.message


@pytest.mark.parametrize("text", [
    "ag.at != to and obj.on == f and ag.carries == null",
    "obj.holder.at == to and obj.owner.carries.on.place == to",
    'ag.kind == "human" or obj.robot_reach',
    "ag.at == 'base' and obj.on != null",
    "u.anything.goes == 3",              # an untyped variable is not checked
    "ag.note.whatever == 1",             # nor is an attribute of type "any"
    "'coffee-table'.whatever == to",     # nor a quoted entity name
    "ag.x * 2 < max(1, abs(ag.x))",
    "not f.container and ag.kind != 'robot'",
])
def test_well_typed(text: str) -> None:
    compile_expr(text, TYPED, ATTRIBUTES)


def test_types_of_effects() -> None:
    compile_effect("obj.holder.at = to", TYPED, ATTRIBUTES)
    compile_effect("ag.at = 'base'", TYPED, ATTRIBUTES)
    compile_effect("ag.carries = null", TYPED, ATTRIBUTES)
    compile_effect("u.whatever = 1", TYPED, ATTRIBUTES)
    err = error("ag.at = obj", TYPED, ATTRIBUTES, effect=True)
    assert (err.offset, err.message) == (8, "cannot assign obj (an Object) to ag.at (a Place)")
    err = error("obj.robot_reach = 3", TYPED, ATTRIBUTES, effect=True)
    assert err.offset == 18 and "(a bool)" in err.message
    err = error("obj.owner.att = to", TYPED, ATTRIBUTES, effect=True)
    assert err.offset == 10 and "did you mean 'at'?" in err.message
    err = error("ag.zz.at = to", TYPED, ATTRIBUTES, effect=True)
    assert err.offset == 3 and "has no attribute 'zz'" in err.message


def test_no_attributes_means_no_type_checks() -> None:
    e = compile_expr("ag.att.zz == obj", TYPED)
    assert e({"ag": "jido", "obj": None}, get) is True
    assert compile_expr("ag.att.zz", TYPED).type is None
    assert compile_expr("ag.at", TYPED, ATTRIBUTES).type == "Place"


# -- safety and independence ---------------------------------------------------------------


SOURCE = "\n".join(Path(m.__file__).read_text("utf-8") for m in (expr_module, closures_module))


def test_no_eval_exec_or_compile() -> None:
    assert not re.search(r"\beval\(|\bexec\(|(?<![_\w])compile\(", SOURCE)
    names = {n.id for n in ast.walk(ast.parse(SOURCE)) if isinstance(n, ast.Name)}
    assert not names & {"eval", "exec", "compile", "__import__"}


def test_imports_nothing_from_the_engine() -> None:
    modules: set[str] = set()
    for node in ast.walk(ast.parse(SOURCE)):
        if isinstance(node, ast.Import):
            modules |= {alias.name.split(".")[0] for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            modules.add((node.module or "").split(".")[0])
    assert not modules & {"shary", "sim"}


def test_python_is_not_reachable_through_the_text() -> None:
    for text in ("__import__('os')", "().__class__", "[1]", "{}", "a[0]", "lambda: 1",
                 "a if b else c", "a.x; b"):
        with pytest.raises(ExprError):
            compile_expr(text, {"a": None, "b": None, "c": None})
    # an attribute is a key of the state, never a Python attribute
    seen = []
    e = compile_expr("a.__class__", {"a": None})
    assert e({"a": "jido"}, lambda *key: seen.append(key)) is None
    assert seen == [("jido", "__class__")]


# -- properties (hypothesis) ------------------------------------------------------------

_PIECES = st.sampled_from(
    ["a", "b", ".x", ".at", "1", "2.5", "1e999", "99999999999999999999", " ", "(", ")",
     "+", "-", "*", "/", "==", "!=", "<", ">=", "=", "and", "or", "not", "&&", "||", "abs",
     "max", "min", ",", "'s'", '"', "true", "null", "None", "é", "$", "\n"])


@settings(max_examples=200, deadline=None)
@given(st.one_of(st.text(max_size=60), st.lists(_PIECES, max_size=40).map(" ".join),
                 st.lists(_PIECES, max_size=60).map("".join)))
def test_any_text_compiles_or_is_refused_at_an_offset(text: str) -> None:
    """Any string: a compiled expression, or an ExprError at an offset inside the text
    (never another exception, however deep or long)."""
    try:
        compile_expr(text, {"a": None, "b": None})
    except ExprError as err:
        assert 0 <= err.offset <= len(text), (err, len(text))


_LEAF = st.one_of(st.integers(0, 50), st.sampled_from("cdefg"))
_VALUES = {"c": 3, "d": 0, "e": 7, "f": 12, "g": 1}


def _extend(kids: st.SearchStrategy) -> st.SearchStrategy:
    return st.one_of(st.tuples(st.sampled_from("+-*/"), kids, kids),
                     st.tuples(st.just("neg"), kids),
                     st.tuples(st.just("abs"), kids),
                     st.tuples(st.sampled_from(["min", "max"]), st.lists(kids, min_size=1,
                                                                           max_size=3)))


def _render(tree: Any) -> str:
    if not isinstance(tree, tuple):
        return str(tree)
    op, *rest = tree
    if op == "neg":
        return f"-({_render(rest[0])})"
    if op == "abs":
        return f"abs({_render(rest[0])})"
    if op in ("min", "max"):
        return f"{op}({', '.join(_render(t) for t in rest[0])})"
    return f"({_render(rest[0])} {op} {_render(rest[1])})"


def _python(tree: Any) -> Any:
    """The same tree computed by Python's own arithmetic."""
    if not isinstance(tree, tuple):
        return _VALUES[tree] if isinstance(tree, str) else tree
    op, *rest = tree
    if op == "neg":
        return -_python(rest[0])
    if op == "abs":
        return abs(_python(rest[0]))
    if op in ("min", "max"):
        return (min if op == "min" else max)(_python(t) for t in rest[0])
    left, right = _python(rest[0]), _python(rest[1])
    return {"+": operator.add, "-": operator.sub, "*": operator.mul,
            "/": operator.truediv}[op](left, right)


def _depth(tree: Any) -> int:
    if not isinstance(tree, tuple):
        return 0
    kids = tree[1] if tree[0] in ("min", "max") else tree[1:]
    return 1 + max(_depth(k) for k in kids)


@settings(max_examples=150, deadline=None)
@given(st.recursive(_LEAF, _extend, max_leaves=30))
def test_nested_arithmetic_is_pythons(tree: Any) -> None:
    """Generated nested expressions within the budget compile, and evaluate exactly as
    Python's arithmetic on the same tree (division by zero: an EvalError or, when the
    whole expression is constant, an ExprError at compile time)."""
    assume(_depth(tree) <= 10)  # at most two levels of nesting each: within MAX_NESTING
    text = _render(tree)
    try:
        expected = _python(tree)
    except ZeroDivisionError:
        with pytest.raises((EvalError, ExprError), match="division by zero"):
            compile_expr(text, dict.fromkeys(_VALUES))(_VALUES, get)
        return
    value = compile_expr(text, dict.fromkeys(_VALUES))(_VALUES, get)
    assert value == expected and type(value) is type(expected), (text, value, expected)
