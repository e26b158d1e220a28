"""The expression language of the data model: what it computes, what it refuses, its bounds.

Refusals at load time are in the hostile corpora (``tests/hostile/scheme/expr-*``);
here are the values, and the evaluations stopped by a bound, which a running
scheme turns into ``error.execution``.
"""

from __future__ import annotations

import pytest

from shary.statechart.expressions import (
    MAX_INT_BITS,
    MAX_LENGTH,
    EvaluationError,
    ExpressionError,
    compile_expression,
    compile_location,
)


class Instance:
    """What an expression reads of a running scheme: its data and its active states."""

    def __init__(self, **data):
        self.data = data

    def is_active(self, name: str) -> bool:
        return name == "here"


@pytest.mark.parametrize(("text", "value"), [
    ("1 + 2 * 3", 7), ("n // 2", 2), ("-n ** 2", -25), ("'a' + 'b'", "ab"),
    ("_event.data.answer == 'yes'", True), ("_event.data['answer']", "yes"),
    ("n if n > 3 else 0", 5), ("[1, 2][n - 4]", 2), ("{'k': n}", {"k": 5}),
    ("len(items) + max(1, 2)", 5), ("In('here') and not In('there')", True),
    ("null is None and true", True), ("1 < n <= 5", True), ("'x' in items", True),
    ("items[1:]", ["y", "z"]), ("str(n) + '!'", "5!"),
    ("bound('n') and not bound('nothing') and not bound('unset')", True),
])
def test_expressions_compute(text, value):
    instance = Instance(n=5, items=["x", "y", "z"], unset=None,
                        _event={"data": {"answer": "yes"}})
    assert compile_expression(text)(instance) == value


def test_names_and_states_are_known_before_running():
    expr = compile_expression("a + b.c if In('s') else d[0]")
    assert expr.names == {"a", "b", "d"} and expr.states == {"s"}


@pytest.mark.parametrize("text", [
    "9 ** 9 ** 9", f"2 ** {MAX_INT_BITS + 1}", f"'x' * {MAX_LENGTH + 1}",
    f"[0] * {MAX_LENGTH + 1}", f"1 << {MAX_INT_BITS + 1}", "s * 1000 * 1000",
    "n / 0", "items[7]", "n.key", "missing_key.x", "int('x')", "'%0999999999d' % 1",
    "int('9' * 5000)", "10.0 ** 400",
])
def test_evaluations_beyond_a_bound_or_failing_stop_with_an_evaluation_error(text):
    instance = Instance(n=5, items=[1], s="abcdefghij" * 10, missing_key={})
    with pytest.raises(EvaluationError):
        compile_expression(text)(instance)


def test_a_big_value_is_refused_where_it_would_be_made_not_after():
    expr = compile_expression("s + s")
    with pytest.raises(EvaluationError, match="more than"):
        expr(Instance(s="x" * (MAX_LENGTH // 2 + 1)))


def test_locations_assign_below_a_variable_and_refuse_system_variables():
    instance = Instance(box={"items": [0, 0]}, _event=None)
    compile_location("box['items'][1]").assign(instance, 7)
    compile_location("box.name").assign(instance, "b")
    assert instance.data["box"] == {"items": [0, 7], "name": "b"}
    with pytest.raises(EvaluationError, match="system variables"):
        compile_location("_event").assign(instance, 1)
    with pytest.raises(ExpressionError, match="not a place to assign"):
        compile_location("f(x)")


def test_a_collection_made_into_text_is_cut_however_it_nests():
    nested: list = []
    for _ in range(60):
        nested = [nested, nested]  # 2**60 leaves, in 60 lists
    text = compile_expression("str(x)")(Instance(x=nested))
    assert len(text) < 1_000
