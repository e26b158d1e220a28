"""Reading the data model of a scheme file: variables, expressions and the actions over them.

Every expression of a scheme is compiled when the file is loaded
(:mod:`shary.statechart.expressions`): a syntax error, a construct the
language does not have, an unknown variable or function and an ``In()`` of an
unknown state are reported as ``FILE:LINE:COL: error: …`` with the column
inside the expression, before anything runs.  The variables are those under
``data:``, the system variables (``_event``, ``_sessionid``, ``_name``,
``_ioprocessors``, ``_x``) and the ``item``/``index`` of a ``foreach``.
"""

from __future__ import annotations

import copy
from typing import TYPE_CHECKING, Any

from shary.statechart.expressions import (
    SYSTEM_VARIABLES,
    Expression,
    ExpressionError,
    Location,
    compile_expression,
    compile_location,
)
from shary.statechart.model import (
    Action,
    Assign,
    Block,
    CancelComputed,
    DataModel,
    DoneData,
    Foreach,
    If,
    Log,
    SendParts,
    Variable,
)
from userfiles.schema import did_you_mean

if TYPE_CHECKING:
    from shary.io.schemes import SchemeBuilder

SEND_PARTS = ("eventexpr", "target", "targetexpr", "type", "typeexpr", "delayexpr",
              "idlocation", "params", "namelist", "content")
"""The keys of a ``send`` that need the data model."""


class DataReader:
    """The data-model part of one scheme file being read (see the module's docstring)."""

    def __init__(self, builder: SchemeBuilder):
        self.builder = builder
        self.used = False
        """Whether the file uses the data model at all (``data:`` or any expression)."""
        self.declared: dict[str, None] = dict.fromkeys(SYSTEM_VARIABLES)
        self.variables: list[Variable] = []
        """Every variable, in document order (the scheme's, then each state's)."""
        self.compiled: list[tuple[Expression | Location, tuple]] = []

    def declare(self, data: Any, path: tuple = (), state: str | None = None) -> None:
        """The variables under a ``data:`` (the scheme's, or a state's)."""
        if not isinstance(data, dict):
            return
        self.used = True
        for name, value in data.items():
            if not isinstance(name, str):
                continue
            at = path + ("data", name)
            self.declared[name] = None
            self.variables.append(Variable(name, self.expression(value, at),
                                           self.builder.located.key_at(at), state))

    def model(self, binding: Any) -> DataModel | None:
        """The scheme's data model (None when the file has none and uses none)."""
        if not self.used:
            return None
        return DataModel(tuple(self.variables), binding == "late")

    def expression(self, value: Any, path: tuple) -> Expression | None:
        """A string compiled as an expression; any other YAML value stands for itself."""
        self.used = True
        if not isinstance(value, str):
            if value is None:
                return None
            frozen = copy.deepcopy(value)
            return Expression(repr(frozen), frozenset(), frozenset(),
                              lambda instance: copy.deepcopy(frozen))
        try:
            compiled = compile_expression(value)
        except ExpressionError as err:
            self.builder.reader.problem_inside(path, err.col - 1, err.message)
            return None
        self.compiled.append((compiled, path))
        return compiled

    def location(self, value: Any, path: tuple, declare: bool = False) -> Location | None:
        """A place to assign to; ``declare`` adds its variable (a foreach's item and index)."""
        self.used = True
        if not isinstance(value, str):
            return None
        try:
            compiled = compile_location(value)
        except ExpressionError as err:
            self.builder.reader.problem_inside(path, err.col - 1, err.message)
            return None
        if declare and not compiled.path:
            self.declared[compiled.name] = None
        self.compiled.append((compiled, path))
        return compiled

    def named(self, value: Any, path: tuple) -> tuple[tuple[str, Expression | Location], ...]:
        """Named values (``params``): name to expression."""
        if not isinstance(value, dict):
            return ()
        return tuple((name, expr) for name, v in value.items()
                     if (expr := self.expression(v, path + (name,))) is not None)

    def namelist(self, value: Any, path: tuple) -> tuple[tuple[str, Expression | Location], ...]:
        """A namelist: each variable passed under its own name."""
        if not isinstance(value, list):
            return ()
        return tuple((name, loc) for i, name in enumerate(value)
                     if (loc := self.location(name, path + (i,))) is not None)

    def action(self, item: dict[str, Any], path: tuple) -> Action | None:
        """An action that needs the data model, or None when ``item`` is a fixed one."""
        actions = self.builder.actions
        if "assign" in item:
            location = self.location(item["assign"], path + ("assign",))
            expr = self.expression(item.get("expr"), path + ("expr",)) \
                or compile_expression("None")
            return Assign(location, expr) if location is not None else None
        if "if" in item:
            branches: list[tuple[Expression | None, tuple[Action, ...]]] = [
                (self.expression(item["if"], path + ("if",)),
                 actions(item.get("then"), path + ("then",)))]
            for index, other in enumerate(item.get("elif") or ()):
                if isinstance(other, dict):
                    at = path + ("elif", index)
                    branches.append((self.expression(other.get("if"), at + ("if",)),
                                     actions(other.get("then"), at + ("then",))))
            if "else" in item:
                branches.append((None, actions(item["else"], path + ("else",))))
            if any(test is None for test, _ in branches[:len(branches) - ("else" in item)]):
                return None
            return If(tuple(branches))
        if "block" in item:
            return Block(actions(item["block"], path + ("block",)))
        if "foreach" in item:
            array = self.expression(item["foreach"], path + ("foreach",))
            item_at = self.location(item.get("item"), path + ("item",), declare=True)
            index = self.location(item["index"], path + ("index",), declare=True) \
                if "index" in item else None
            body = actions(item.get("do"), path + ("do",))
            return Foreach(array, item_at, index, body) \
                if array is not None and item_at is not None else None
        if "log" in item and "expr" in item:
            expr = self.expression(item["expr"], path + ("expr",))
            return Log(item["log"], expr) if expr is not None else None
        if "cancel" in item and "sendidexpr" in item:
            expr = self.expression(item["sendidexpr"], path + ("sendidexpr",))
            return CancelComputed(expr) if expr is not None else None
        return None

    def send_parts(self, item: dict[str, Any], path: tuple) -> SendParts | None:
        """The computed parts of a send (None for a fixed send)."""
        if not any(key in item for key in SEND_PARTS):
            return None
        self.used = True

        def expr(key: str) -> Expression | None:
            return self.expression(item[key], path + (key,)) if key in item else None
        id_location = self.location(item["idlocation"], path + ("idlocation",)) \
            if "idlocation" in item else None
        namelist = self.namelist(item.get("namelist"), path + ("namelist",))
        return SendParts(event=expr("eventexpr"), target=item.get("target"),
                         target_expr=expr("targetexpr"), type=item.get("type"),
                         type_expr=expr("typeexpr"), delay_expr=expr("delayexpr"),
                         id_location=id_location,
                         params=self.named(item.get("params"), path + ("params",)),
                         namelist=tuple(loc for _, loc in namelist
                                        if isinstance(loc, Location)),
                         content=expr("content"))

    def donedata(self, value: Any, path: tuple) -> DoneData | None:
        if not isinstance(value, dict):
            return None
        self.used = True
        content = self.expression(value["content"], path + ("content",)) \
            if "content" in value else None
        return DoneData(self.named(value.get("params"), path + ("params",)), content)

    def check_names(self, states: dict[str, Any]) -> None:
        """Report the unknown variables and states the compiled expressions name."""
        for compiled, path in self.compiled:
            for name in sorted(compiled.names - self.declared.keys()):
                self.builder.reader.problem_inside(
                    path, max(0, compiled.source.find(name)),
                    f"unknown variable {name!r}{did_you_mean(name, self.declared)}; declare it "
                    "under 'data:'")
            for state in sorted(compiled.states - states.keys()):
                self.builder.reader.problem_inside(
                    path, max(0, compiled.source.find(state)),
                    f"In({state!r}) names an unknown state{did_you_mean(state, states)}")
