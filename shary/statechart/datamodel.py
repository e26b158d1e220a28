"""The data model of a running scheme: variables, executable content over them, events with data.

A scheme with a data model (``data:`` in YAML, ``<datamodel>`` in SCXML) gives
each instance a dictionary ``instance.data`` of its variables and SCXML's
system variables.  This module runs what reads and writes it: the start of
the variables, ``assign``, ``if``, ``foreach``, ``log`` of a value, sends
whose parts are computed, done data and the parameters of an invoke.  An
expression that fails (:class:`~shary.statechart.expressions.EvaluationError`)
becomes SCXML's ``error.execution`` event on the internal queue, and the rest
of that block of actions is skipped, as SCXML says.

A scheme without a data model never comes here: its instances have
``data = None`` and run the fixed actions of :mod:`shary.statechart.model`
alone, at the same cost as before the data model existed.
"""

from __future__ import annotations

import itertools
import re
from typing import Any

from shary.statechart.expressions import EvaluationError, Expression, Location, show
from shary.statechart.model import (
    PARENT,
    Assign,
    Block,
    CancelComputed,
    DoneData,
    Foreach,
    If,
    Invoke,
    Log,
    Scheme,
    Send,
    SendParts,
)

SCXML_PROCESSOR = "http://www.w3.org/TR/scxml/#SCXMLEventProcessor"
"""The one event I/O processor: events between schemes of one engine."""
PROCESSOR_NAMES = ("", "scxml", SCXML_PROCESSOR, "http://www.w3.org/TR/scxml/")
INVOKE_TYPES = ("", "scxml", "http://www.w3.org/TR/scxml/", "http://www.w3.org/TR/scxml")
"""The types of an invoke that start a scheme (SCXML's names for a chart)."""
ERROR_EXECUTION = "error.execution"
_DELAY = re.compile(r"^\s*([0-9]*\.?[0-9]+)\s*(ms|s|min|h)?\s*$")
_UNITS = {"ms": 0.001, "s": 1.0, "min": 60.0, "h": 3600.0, None: 1.0}
MAX_ITERATIONS = 100_000
"""Most rounds the ``foreach`` actions of one block may run, nested ones included: a
foreach over 100,000 items inside another would otherwise run ten billion times."""
_sessions = itertools.count(1)
_rounds = [0, 0]
"""How deep in foreach actions the engine is, and how many rounds they ran so far."""
_send_ids = itertools.count(1)


class Stopped(EvaluationError):
    """Nested actions failed (their ``error.execution`` is queued): the enclosing block stops."""


class DataEvent:
    """An event with SCXML's fields, as ``_event`` shows them (``type``, ``sendid`` …)."""

    __slots__ = ("name", "data", "type", "sendid", "origin", "origintype", "invokeid")

    def __init__(self, name: str, data: Any = None, type: str = "external",
                 sendid: str | None = None, origin: str | None = None,
                 origintype: str | None = None, invokeid: str | None = None):
        self.name = name
        self.data = data
        self.type = type
        self.sendid = sendid
        self.origin = origin
        self.origintype = origintype
        self.invokeid = invokeid

    def __repr__(self) -> str:
        return f"DataEvent({self.name!r}, {self.data!r})"


def fields(event: Any) -> dict[str, Any]:
    """The ``_event`` variable for an event (a plain event is an outside one, with no origin)."""
    return {"name": event.name, "data": event.data,
            "type": getattr(event, "type", "external"),
            "sendid": getattr(event, "sendid", None), "origin": getattr(event, "origin", None),
            "origintype": getattr(event, "origintype", None),
            "invokeid": getattr(event, "invokeid", None)}


def start(instance: Any, scheme: Scheme, given: dict[str, Any] | None) -> list[str]:
    """Bind the system variables and the declared ones; return the errors met.

    ``given`` holds the values an invoking parent passed (params and namelist):
    they replace the declared start of variables of the same name.
    """
    session = f"{scheme.name}-{next(_sessions)}"
    data: dict[str, Any] = {
        "_sessionid": session, "_name": scheme.name, "_event": None, "_x": {},
        "_ioprocessors": {SCXML_PROCESSOR: {"location": f"#_scxml_{session}"},
                          "scxml": {"location": f"#_scxml_{session}"}},
    }
    instance.data = data
    errors = []
    assert scheme.datamodel is not None
    late = scheme.datamodel.late
    for variable in scheme.datamodel.variables:
        if given and variable.name in given:
            data[variable.name] = given[variable.name]
            continue
        data[variable.name] = None
        if variable.expr is not None and not (late and variable.state is not None):
            try:
                data[variable.name] = variable.expr(instance)
            except EvaluationError as err:
                errors.append(str(err))
    if late:
        data[LATE] = set()
    return errors


LATE = "#entered"
"""Where a late-binding instance keeps the states whose variables it has set (a key no
expression can name)."""


def bind_late(instance: Any, state: str, variables: tuple) -> None:
    """Set a state's own variables the first time it is entered (late binding)."""
    entered = instance.data[LATE]
    if state in entered:
        return
    entered.add(state)
    for variable in variables:
        if variable.expr is not None:
            try:
                instance.data[variable.name] = variable.expr(instance)
            except EvaluationError as err:
                instance._internal.append(error_event(str(err)))


def take(instance: Any, event: Any, kind: str) -> None:
    """Bind ``_event`` for an event the instance takes (``kind``: from which queue), and run
    the ``finalize`` of the invoke it comes from, if any."""
    found = fields(event)
    if not isinstance(event, DataEvent):
        found["type"] = kind
    instance.data["_event"] = found
    invokeid = found["invokeid"]
    if invokeid is not None:  # (the child may have ended since it sent the event)
        for state in instance.definition.scheme.states.values():
            for invoke in state.invokes:
                if invoke.id == invokeid and invoke.finalize:
                    instance._run(invoke.finalize)


def invoke_values(instance: Any, invoke: Invoke) -> dict[str, Any] | None | bool:
    """What an invoke passes its child (params, namelist), with its id stored if asked;
    False when one fails or its type, computed, is not a scheme's: SCXML then cancels
    the invoke (and raises ``error.execution``)."""
    try:
        if invoke.type_expr is not None:
            kind = invoke.type_expr(instance)
            if kind not in INVOKE_TYPES:
                raise EvaluationError(f"invoke type {kind!r}: only schemes are invoked")
        if invoke.id_location is not None:
            invoke.id_location.assign(instance, invoke.id)
        return values(instance, invoke.params)
    except EvaluationError as err:
        instance._internal.append(error_event(str(err)))
        return False


def error_event(why: str) -> DataEvent:
    return DataEvent(ERROR_EXECUTION, {"error": why}, type="platform")


def guard(expr: Expression) -> Any:
    """The condition of a guard over the data: false, with ``error.execution``, if it fails."""
    evaluate = expr.evaluate

    def condition(instance: Any, event: Any) -> bool:
        try:
            return bool(evaluate(instance))
        except Exception as err:  # noqa: BLE001 - any failure of an expression is SCXML's error
            instance._internal.append(error_event(f"{expr.source!r}: {err}"))
            return False
    return condition


def execute(instance: Any, action: Any) -> None:
    """Run one action of the data model; :class:`EvaluationError` stops its block."""
    if isinstance(action, Assign):
        action.location.assign(instance, action.expr(instance))
    elif isinstance(action, If):
        for test, actions in action.branches:
            if test is None or test(instance):
                if not instance._run(actions):
                    raise Stopped(ERROR_EXECUTION)
                return
    elif isinstance(action, Foreach):
        _foreach(instance, action)
    elif isinstance(action, Block):
        instance._run(action.actions)
    elif isinstance(action, Log):
        value = action.expr(instance) if action.expr is not None else None
        if instance.listener is not None:
            shown = show(value) if not isinstance(value, str) else repr(value)
            instance.listener.logged(instance, f"{action.text}: {shown}" if action.text
                                     else shown)
    elif isinstance(action, CancelComputed):
        instance._cancel_send(str(action.id(instance)))
    elif isinstance(action, Send):
        _send(instance, action, action.computed)


def _foreach(instance: Any, action: Foreach) -> None:
    array = action.array(instance)
    if not isinstance(array, (list, tuple, dict)):
        raise EvaluationError(f"{action.array.source!r} is a {type(array).__name__}, not "
                              "a list to iterate over")
    if _rounds[0] == 0:
        _rounds[1] = 0
    _rounds[0] += 1
    try:
        for index, item in enumerate(list(array)):
            _rounds[1] += 1
            if _rounds[1] > MAX_ITERATIONS:
                raise EvaluationError(f"foreach ran more than {MAX_ITERATIONS} rounds in one "
                                      "block of actions")
            action.item.assign(instance, item)
            if action.index is not None:
                action.index.assign(instance, index)
            if not instance._run(action.actions):
                raise Stopped(ERROR_EXECUTION)
    finally:
        _rounds[0] -= 1


def values(instance: Any, pairs: tuple[tuple[str, Expression | Location], ...]) -> dict[str, Any]:
    """The named values of params and namelists (a namelist's location is read as a variable)."""
    out = {}
    for name, source in pairs:
        if isinstance(source, Location):
            out[name] = source.read(instance)
        else:
            out[name] = source(instance)
    return out


def done_data(instance: Any, done: DoneData | None) -> Any:
    """The data of a done event (None when the final state has none or it fails)."""
    if done is None:
        return None
    try:
        if done.content is not None:
            return done.content(instance)
        return values(instance, done.params)
    except EvaluationError as err:
        instance._internal.append(error_event(str(err)))
        return None


def _send(instance: Any, send: Send, parts: SendParts | None) -> None:
    """A send with computed parts: event name, target, type, delay, id and data."""
    parts = parts or SendParts()
    name = str(parts.event(instance)) if parts.event is not None else send.event
    target = str(parts.target_expr(instance)) if parts.target_expr is not None \
        else parts.target
    kind = str(parts.type_expr(instance)) if parts.type_expr is not None else parts.type
    if kind is not None and kind not in PROCESSOR_NAMES:
        raise EvaluationError(f"send type {kind!r}: only SCXML's event processor is known")
    delay = send.delay
    if parts.delay_expr is not None:
        text = parts.delay_expr(instance)
        match = _DELAY.match(str(text))
        if match is None:
            raise EvaluationError(f"delay {text!r} is not a duration")
        delay = float(match.group(1)) * _UNITS[match.group(2)]
    ident = send.id
    if ident is None and parts.id_location is not None:
        ident = f"send.{next(_send_ids)}"
    if parts.id_location is not None:
        parts.id_location.assign(instance, ident)
    data = values(instance, parts.params + tuple((n.source, n) for n in parts.namelist)) \
        if parts.params or parts.namelist else None
    if parts.content is not None:
        data = parts.content(instance)
    to = send.to
    if target is not None:
        try:
            to = _route(instance, target)
        except EvaluationError as err:  # the error tells which send failed
            instance._internal.append(DataEvent(ERROR_EXECUTION, {"error": str(err)},
                                                type="platform", sendid=ident))
            raise Stopped(ERROR_EXECUTION) from None
        if to == UNREACHABLE:
            instance._internal.append(DataEvent("error.communication", {"target": target},
                                                type="platform", sendid=ident))
            return
    session = instance.data["_sessionid"]
    event = DataEvent(name, data, sendid=ident, origin=f"#_scxml_{session}",
                      origintype=SCXML_PROCESSOR,
                      invokeid=instance.invoke_id if to == PARENT else None)
    if to == "#_internal":
        event.type = "internal"
        instance._internal.append(event)
        return
    instance._dispatch(event, delay, ident, to)


UNREACHABLE = "#unreachable"
"""Where a send to a session that does not exist (any more) goes: ``error.communication``."""


def _route(instance: Any, target: str) -> str | None:
    """Where an SCXML target leads: None for the instance itself, ``#_internal``,
    ``parent``, an invoke id, :data:`UNREACHABLE`, or :class:`EvaluationError` for a
    target that is no target at all."""
    if target in ("", "#_internal"):
        return target or None
    if target == "#_parent":
        return PARENT
    if target.startswith("#_scxml_"):
        session = target[len("#_scxml_"):]
        if session == instance.data["_sessionid"]:
            return None
        parent = instance.parent
        if parent is not None and parent.data is not None and \
                session == parent.data.get("_sessionid"):
            return PARENT
        return UNREACHABLE
    if target.startswith("#_") and len(target) > 2:
        return target[2:]
    raise EvaluationError(f"send target {target!r}: a scheme sends to itself, '#_parent', "
                          "'#_internal', '#_scxml_SESSION' or '#_INVOKEID'")
