"""Loading communication schemes from YAML: schema first, then meaning.

:func:`parse_scheme` turns a located document into a :class:`~shary.statechart.model.Scheme`
and collects every problem of the file before refusing it: schema violations,
unknown acts, roles and guards, dangling targets, missing initial states,
transitions that can never be taken because an earlier unguarded one of the
same state takes the same events, and states that nothing can reach.
"""

from __future__ import annotations

import os
import re
from typing import Any

import networkx as nx

from shary import builtin
from shary.io import invokes, schema
from shary.io.scheme_data import DataReader
from shary.statechart.acts import ACT_TYPES, ActRegistry, act_type, acts_from_data, builtin_acts
from shary.statechart.conditions import ConditionRegistry
from shary.statechart.model import (
    ATOMIC,
    COMPOUND,
    EXPR_GUARD,
    FINAL,
    HISTORY,
    PARALLEL,
    PARENT,
    Action,
    Cancel,
    Coverage,
    Invoke,
    Log,
    Raise,
    Scheme,
    Send,
    State,
    Transition,
)
from userfiles import yamlsafe
from userfiles.errors import FileError, Problem
from userfiles.limits import seconds
from userfiles.reader import Reader
from userfiles.schema import did_you_mean

DEFAULT_ROLES = {"robot": "robot", "partner": "human"}
"""Roles of a scheme that declares none: one robot and its human partner."""

EVENTLESS_KEY = "always"
_AFTER = re.compile(r"^after\s+(\S+)$")
_GUARD = re.compile(r"^(not )?([a-z][a-z0-9_-]*|in [A-Za-z0-9_][A-Za-z0-9_.:-]*)$")
_ACT_WORD = re.compile(r"^[A-Z][A-Z0-9]*(-[A-Z0-9]+)*$")
_DESCRIPTOR = re.compile(r"^(\*|[A-Za-z0-9_][A-Za-z0-9_:-]*(\.[A-Za-z0-9_:-]+)*(\.\*)?)$")


def load_scheme(name_or_path: str | os.PathLike[str], *, acts: ActRegistry | None = None,
                conditions: ConditionRegistry | None = None,
                chain: tuple[str, ...] = (), loaded: dict | None = None) -> Scheme:
    """Load a scheme by built-in name (``give-object``) or by path, fully checked.

    ``chain`` lists the files whose invokes led here (to find invoke cycles);
    ``loaded`` the child schemes loaded so far (each file is read once).
    """
    path = resolve(name_or_path)
    return parse_scheme(yamlsafe.load_file(path), acts=acts, conditions=conditions,
                        chain=chain, loaded=loaded)


def resolve(name_or_path: str | os.PathLike[str]) -> str:
    """The file a scheme name or path designates (a built-in name wins over nothing)."""
    text = os.fspath(name_or_path)
    if os.path.exists(text) or text.endswith((".yaml", ".yml")) or os.sep in text:
        return text
    found = builtin.find("schemes", text)
    if found is None:
        names = [p.stem for p in builtin.files("schemes") if p.stem != "acts"]
        raise FileError([Problem(text, 1, 1, f"no such file, and no built-in scheme {text!r}"
                                 f"{did_you_mean(text, names)}; built-in schemes: "
                                 f"{', '.join(names)}")])
    return str(found)


def parse_scheme(located: yamlsafe.Located, *, acts: ActRegistry | None = None,
                 conditions: ConditionRegistry | None = None,
                 check_reachable: bool = True, chain: tuple[str, ...] = (),
                 loaded: dict | None = None) -> Scheme:
    """Build and check a scheme from a located document; raise :class:`FileError`.

    ``check_reachable=False`` is for tools that prune unreachable states
    themselves (the SCXML importer); every other check still applies.
    Invoked child schemes are loaded and checked too (:mod:`shary.io.invokes`).
    """
    if not isinstance(located.data, dict):
        raise FileError([located.problem((), "expected a mapping with 'scheme' and 'states' "
                                         "at the top of a scheme file")])
    builder = SchemeBuilder(located, acts or builtin_acts(), conditions, check_reachable,
                       chain + (invokes.identity(located.file),),
                       {} if loaded is None else loaded)
    if not builder.reader.shape_ok:  # meaning is only checked on the schema's shape
        raise FileError(builder.problems)
    scheme = builder.build()
    if builder.problems:
        raise FileError(builder.problems)
    return scheme


class SchemeBuilder:
    """One scheme file being read into the model, with the problems found so far."""

    def __init__(self, located: yamlsafe.Located, acts: ActRegistry,
                 conditions: ConditionRegistry | None, check_reachable: bool,
                 chain: tuple[str, ...], loaded: dict):
        self.located = located
        self.loaded = loaded
        self.base_acts = acts
        self.chain = chain
        self.invoke_ids: dict[str, tuple] = {}
        self.send_targets: list[tuple[str, tuple]] = []
        """The invoke ids that sends name in ``to:``, with where: checked once all are known."""
        self.check_reachable = check_reachable
        self.data: dict[str, Any] = located.data
        self.reader = Reader(located, schema.check(located, "scheme"))
        self.problems: list[Problem] = self.reader.problems
        self.problem = self.reader.problem
        self.acts = acts
        self.conditions = conditions
        self.states: dict[str, State] = {}
        self.paths: dict[str, tuple] = {}
        self.order = 0
        self.transition_order = 0
        self.data_reader = DataReader(self)

    def parse_child(self, located: yamlsafe.Located) -> Scheme:
        """A child scheme written inline in this one, checked with this scheme's acts,
        conditions and chain of invokes."""
        return parse_scheme(located, acts=self.base_acts, conditions=self.conditions,
                            chain=self.chain, loaded=self.loaded)

    def load_child(self, file: str) -> Scheme:
        """A child scheme read from ``file``, checked as :meth:`parse_child` does."""
        return load_scheme(file, acts=self.base_acts, conditions=self.conditions,
                           chain=self.chain, loaded=self.loaded)

    # -- building --------------------------------------------------------

    def build(self) -> Scheme:
        data = self.data
        own_acts = data.get("acts")
        if isinstance(own_acts, dict) and all(isinstance(k, str) for k in own_acts):
            for name in own_acts:
                if name in ACT_TYPES:
                    self.problem(("acts", name), f"{name!r} is an act type, not an act name",
                                 key=True)
            self.acts = self.acts.extended(
                acts_from_data({k: v if isinstance(v, dict) else None
                                for k, v in own_acts.items()}, self.located.file))
        roles = data.get("roles")
        self.roles = dict(roles) if isinstance(roles, dict) and roles else dict(DEFAULT_ROLES)
        self.data_reader.declare(data.get("data"))
        root = State("", COMPOUND, mark=self.located.at(()))
        root.initial, root.initial_actions = self._initial(data.get("initial"), ("initial",))
        states = data.get("states")
        if isinstance(states, dict):
            self._children(root, states, ("states",))
        name = data.get("scheme") if isinstance(data.get("scheme"), str) else "scheme"
        doc = data.get("doc") if isinstance(data.get("doc"), str) else ""
        self.data_reader.check_names(self.states)
        datamodel = self.data_reader.model(data.get("binding"))
        scheme = Scheme(name, root, self.states, self.roles, self.acts, doc, self.located.file,
                        datamodel)
        self._check_initial(root, ())
        for state in self.states.values():
            self._check_initial(state, self.paths[state.name])
            self._check_state(state)
            taken = Coverage()
            for transition in state.transitions:
                self._check_transition(transition, taken)
        for to, path in self.send_targets:
            if to not in self.invoke_ids:
                self.problem(path, f"send to {to!r}: no invoke of this scheme has that id"
                             f"{did_you_mean(to, self.invoke_ids)}; 'to' is '{PARENT}' (the "
                             "scheme that invoked this one) or an invoke id of this scheme")
        if self.check_reachable:
            self._check_reachable(scheme)
        return scheme

    def _children(self, parent: State, states: dict[str, Any], path: tuple) -> None:
        for name, spec in states.items():
            spec_path = path + (name,)
            spec = spec if isinstance(spec, dict) else {}
            if name in self.states:
                first = self.located.key_at(self.paths[name])
                self.problem(spec_path, f"duplicate state name {name!r} (first defined at line "
                             f"{first[0]}, column {first[1]}); state names are unique in a "
                             "scheme", key=True)
                continue
            self.order += 1
            state = State(name, self._kind(spec), parent=parent, order=self.order,
                          depth=parent.depth + 1, mark=self.located.key_at(spec_path))
            parent.children.append(state)
            self.states[name] = state
            self.paths[name] = spec_path
            state.doc = spec.get("doc", "") if isinstance(spec.get("doc"), str) else ""
            state.initial, state.initial_actions = self._initial(spec.get("initial"),
                                                                 spec_path + ("initial",))
            state.default, default_actions = self._initial(spec.get("default"),
                                                           spec_path + ("default",))
            state.initial_actions = state.initial_actions or default_actions
            if "data" in spec:
                self.data_reader.declare(spec["data"], spec_path, name)
            if "donedata" in spec:
                state.donedata = self.data_reader.donedata(spec["donedata"],
                                                           spec_path + ("donedata",))
            if spec.get("outcome") in ("done", "failed"):
                state.outcome = spec["outcome"]
            if spec.get("history") in ("shallow", "deep"):
                state.history = spec["history"]
            self._act(state, spec, spec_path)
            state.on_entry = self.actions(spec.get("on_entry"), spec_path + ("on_entry",))
            state.on_exit = self.actions(spec.get("on_exit"), spec_path + ("on_exit",))
            if isinstance(spec.get("on"), dict):
                self._transitions(state, spec["on"], spec_path + ("on",))
            if "invoke" in spec:
                self._invokes(state, spec["invoke"], spec_path + ("invoke",))
            if isinstance(spec.get("states"), dict):
                self._children(state, spec["states"], spec_path + ("states",))

    @staticmethod
    def _kind(spec: dict[str, Any]) -> str:
        if "history" in spec:
            return HISTORY
        if spec.get("final") is True:
            return FINAL
        if spec.get("parallel") is True:
            return PARALLEL
        return COMPOUND if isinstance(spec.get("states"), dict) and spec["states"] else ATOMIC

    def _act(self, state: State, spec: dict[str, Any], path: tuple) -> None:
        act = spec.get("act")
        by = spec.get("by")
        if isinstance(by, str) and by not in self.roles:
            self.problem(path + ("by",), f"unknown role {by!r}{did_you_mean(by, self.roles)}; "
                         f"roles of this scheme: {', '.join(self.roles)}")
            by = None
        if not isinstance(act, str):
            if isinstance(by, str):
                self.problem(path + ("by",), "'by' names who carries out the act; this state "
                             "has no 'act'")
            return
        if act not in self.acts:
            self.problem(path + ("act",), f"unknown act {act!r}"
                         f"{did_you_mean(act, self.acts.acts)}; declare it under 'acts:'")
            return
        state.act = act
        state.by = by if isinstance(by, str) else next(iter(self.roles))
        state.act_type = act_type(self.roles[state.by])

    def _initial(self, value: Any, path: tuple) -> tuple[tuple[str, ...], tuple[Action, ...]]:
        """Targets and actions of an ``initial`` or ``default`` (a name, a list, a transition)."""
        if isinstance(value, dict):
            return self._targets(value.get("target")), self.actions(value.get("do"),
                                                                     path + ("do",))
        return self._targets(value), ()

    def _invokes(self, state: State, value: Any, path: tuple) -> None:
        items = value if isinstance(value, list) else [value]
        out: list[Invoke] = []
        for index, item in enumerate(items):
            item_path = path + (index,) if isinstance(value, list) else path
            if not isinstance(item, dict):
                continue
            ident = item.get("id")
            if not isinstance(ident, str):
                ident = state.name if len(items) == 1 else f"{state.name}.{index + 1}"
            if item.get("id") == PARENT:
                self.problem(item_path + ("id",), f"invoke id {PARENT!r} is reserved: a "
                             f"send's 'to: {PARENT}' names the scheme that invoked this one")
                continue
            if ident in self.invoke_ids:
                first = self.located.at(self.invoke_ids[ident])
                self.problem(item_path, f"duplicate invoke id {ident!r} (first at line "
                             f"{first[0]}, column {first[1]}); the parent tells its children "
                             "apart by id")
                continue
            self.invoke_ids[ident] = item_path
            child = invokes.child_scheme(self, item.get("scheme"), item_path + ("scheme",))
            if child is not None:
                reader = self.data_reader
                params = reader.named(item.get("params"), item_path + ("params",)) \
                    + reader.namelist(item.get("namelist"), item_path + ("namelist",))
                id_location = reader.location(item["idlocation"], item_path + ("idlocation",)) \
                    if "idlocation" in item else None
                out.append(Invoke(ident, child, item.get("autoforward") is True,
                                  self.located.at(item_path), params,
                                  self.actions(item.get("finalize"), item_path + ("finalize",)),
                                  id_location,
                                  reader.expression(item["typeexpr"], item_path + ("typeexpr",))
                                  if "typeexpr" in item else None))
        state.invokes = tuple(out)

    def _targets(self, value: Any) -> tuple[str, ...]:
        if isinstance(value, str):
            return (value,)
        if isinstance(value, list):
            return tuple(v for v in value if isinstance(v, str))
        return ()

    def _transitions(self, state: State, on: dict[str, Any], path: tuple) -> None:
        for key, value in on.items():
            key_path = path + (key,)
            items = value if isinstance(value, list) else [value]
            after = _AFTER.match(key)
            for index, item in enumerate(items):
                item_path = key_path + (index,) if isinstance(value, list) else key_path
                self.transition_order += 1
                t = Transition(state, None, order=self.transition_order,
                               mark=self.located.key_at(key_path))
                if after:
                    try:
                        if not after.group(1)[-1:].isalpha():  # in an event, the unit is due
                            raise ValueError(after.group(1))
                        t.after = seconds(after.group(1))
                    except ValueError:
                        self.problem(key_path, f"{after.group(1)!r} is not a duration "
                                     "(write e.g. 250ms, 10s, 1.5min, 2h)", key=True)
                        continue
                    t.events = (f"after {after.group(1)}@{state.name}",)
                elif key != EVENTLESS_KEY:
                    descriptors = tuple(key.split())
                    if not self._descriptors_ok(descriptors, key_path):
                        continue
                    t.events = descriptors
                if isinstance(item, str):
                    t.targets = (item,)
                    t.target_mark = self.located.at(item_path)
                elif isinstance(item, dict):
                    t.targets = self._targets(item.get("target"))
                    t.target_mark = self.located.at(item_path + ("target",))
                    guard = item.get("guard")
                    t.guard = guard if isinstance(guard, str) and _GUARD.match(guard) else None
                    if "cond" in item:
                        if guard is not None:
                            self.problem(item_path + ("cond",), "a transition takes 'guard' (a "
                                         "registered condition) or 'cond' (an expression), not "
                                         "both", key=True)
                        t.cond = self.data_reader.expression(item["cond"],
                                                             item_path + ("cond",))
                        if t.cond is not None:
                            t.guard = EXPR_GUARD + t.cond.source
                    t.internal = item.get("type") == "internal"
                    t.actions = self.actions(item.get("do"), item_path + ("do",))
                else:
                    continue
                state.transitions.append(t)

    def _descriptors_ok(self, descriptors: tuple[str, ...], path: tuple) -> bool:
        ok = True
        for d in descriptors:
            if d in (EVENTLESS_KEY, "after"):
                self.problem(path, f"{d!r} is reserved: write 'always' alone for an eventless "
                             "transition and 'after 10s' for a timeout", key=True)
                ok = False
            elif not _DESCRIPTOR.match(d):
                self.problem(path, f"{d!r} is not an event descriptor (names of letters, digits "
                             "and _ : - joined by dots, optionally ending in .*, or *)", key=True)
                ok = False
            else:
                word = d.split(".")[0]
                if _ACT_WORD.match(word) and not self.acts.is_act_word(word):
                    self.problem(path, f"unknown act {word!r}"
                                 f"{did_you_mean(word, self.acts.vocabulary())}; names in "
                                 "capitals are communication acts or act types", key=True)
                    ok = False
        return ok

    def actions(self, value: Any, path: tuple) -> tuple[Action, ...]:
        if not isinstance(value, list):
            return ()
        out: list[Action] = []
        for index, item in enumerate(value):
            if not isinstance(item, dict):
                continue
            if any(k in item for k in ("assign", "if", "foreach", "block")) or "expr" in item \
                    or "sendidexpr" in item:
                found = self.data_reader.action(item, path + (index,))
                if found is not None:
                    out.append(found)
            elif isinstance(item.get("raise"), str):
                out.append(Raise(item["raise"]))
            elif "send" in item:
                delay = item.get("delay")
                try:
                    wait = seconds(delay) if isinstance(delay, str) else 0.0
                except ValueError:
                    continue  # the schema reported it
                ident = item.get("id") if isinstance(item.get("id"), str) else None
                to = item.get("to") if isinstance(item.get("to"), str) else None
                if to is not None and to != PARENT:
                    self.send_targets.append((to, path + (index, "to")))
                parts = self.data_reader.send_parts(item, path + (index,))
                if not isinstance(item["send"], str) and (parts is None or parts.event is None):
                    self.problem(path + (index,), "a send needs an event: 'send: EVENT' or "
                                 "'eventexpr'")
                    continue
                out.append(Send(item["send"] or "", wait, ident, to, parts))
            elif isinstance(item.get("cancel"), str):
                out.append(Cancel(item["cancel"]))
            elif isinstance(item.get("log"), str):
                out.append(Log(item["log"]))
        return tuple(out)

    # -- meaning ---------------------------------------------------------

    def _path(self, state: State) -> tuple:
        return self.paths.get(state.name, ())

    def _check_initial(self, state: State, path: tuple) -> None:
        where = "the scheme" if state.parent is None else f"state {state.name!r}"
        proper = state.proper_children()
        if state.kind == PARALLEL:
            if state.initial:
                self.problem(path + ("initial",), "a parallel state enters all its regions; "
                             "it takes no 'initial'")
            return
        if state.kind != COMPOUND:
            if state.initial:
                self.problem(path + ("initial",), f"{where} has no child states; 'initial' "
                             "makes no sense here")
            return
        if not state.initial:
            if len(proper) > 1:
                self.problem(path if path else (), f"{where} has {len(proper)} child states but "
                             f"no 'initial': say which one is entered first (one of: "
                             f"{', '.join(c.name for c in proper)})", key=bool(path))
            elif proper:
                state.initial = (proper[0].name,)
            return
        for name in state.initial:
            target = self.states.get(name)
            if target is None:
                self.problem(path + ("initial",), f"initial state {name!r} does not exist"
                             f"{did_you_mean(name, self._descendant_names(state))}")
            elif not target.is_descendant_of(state) or (target.kind == HISTORY
                                                         and target.parent is not state):
                self.problem(path + ("initial",), f"initial state {name!r} is not a child "
                             f"state of {where}")

    def _descendant_names(self, state: State) -> list[str]:
        return [s.name for s in self.states.values() if s.is_descendant_of(state)]

    def _check_state(self, state: State) -> None:
        path = self._path(state)
        spec = _at(self.data, path)
        spec = spec if isinstance(spec, dict) else {}
        if state.kind == FINAL:
            for key in ("states", "on", "parallel", "history", "invoke"):
                if key in spec:
                    self.problem(path + (key,), f"a final state cannot have {key!r}", key=True)
        if state.kind == HISTORY:
            for key in ("states", "on", "act", "parallel", "final", "on_entry", "on_exit",
                        "invoke"):
                if key in spec:
                    self.problem(path + (key,), f"a history state is a pseudo-state and cannot "
                                 f"have {key!r}", key=True)
            if state.parent is None or state.parent.parent is None:
                self.problem(path, "a history state belongs inside a compound or parallel "
                             "state, not at the top of the scheme", key=True)
            for name in state.default:
                target = self.states.get(name)
                if target is None:
                    self.problem(path + ("default",), f"history default {name!r} does not "
                                 f"exist{did_you_mean(name, self.states)}")
                elif not target.is_descendant_of(state.parent):
                    self.problem(path + ("default",), f"history default {name!r} is not inside "
                                 f"{state.parent.name!r}")
        if "outcome" in spec and state.kind != FINAL:
            self.problem(path + ("outcome",), "'outcome' belongs to final states", key=True)
        if "default" in spec and state.kind != HISTORY:
            self.problem(path + ("default",), "'default' belongs to history states only",
                         key=True)
        if state.kind == PARALLEL and not state.proper_children():
            self.problem(path, "a parallel state needs at least one region (child state)",
                         key=True)

    def _check_transition(self, t: Transition, taken: Coverage) -> None:
        at = Problem(self.located.file, *t.mark, "")
        for name in t.targets:
            if name not in self.states:
                self.problems.append(Problem(self.located.file, *t.target_mark,
                                             f"unknown target state {name!r}"
                                             f"{did_you_mean(name, self.states)}"))
        if t.in_state is not None and t.in_state not in self.states:
            self._at(at, f"guard 'in {t.in_state}' names an unknown state"
                     f"{did_you_mean(t.in_state, self.states)}")
        elif t.condition is not None and t.in_state is None and t.cond is None \
                and self.conditions is not None \
                and t.condition not in self.conditions:
            self._at(at, f"guard names an unknown condition {t.condition!r}"
                     f"{did_you_mean(t.condition, self.conditions)}; known conditions: "
                     f"{', '.join(sorted(self.conditions)) or 'none registered'}")
        if t.internal and not t.targets:
            self._at(at, "'type: internal' needs a target (a targetless transition never "
                     "leaves its state anyway)")
        if len(t.targets) > 1:
            targets = [self.states[n] for n in t.targets if n in self.states]
            for i, a in enumerate(targets):
                for b in targets[i + 1:]:
                    if a is b or a.is_descendant_of(b) or b.is_descendant_of(a) \
                            or not _in_parallel_regions(a, b):
                        self._at(at, f"targets {a.name!r} and {b.name!r} cannot be active "
                                 "together (several targets must lie in distinct regions of a "
                                 "parallel state)")
        if t.after is not None:
            return
        earlier = taken.covering(t.events)
        if isinstance(earlier, Transition):
            self._at(at, f"transition on {_trigger(t)!r} is never taken: the unguarded "
                     f"transition on {_trigger(earlier)!r} at line {earlier.mark[0]}, column "
                     f"{earlier.mark[1]} of the same state (with any other earlier unguarded "
                     "ones) takes the same events first")
        elif t.guard is None:
            taken.add(t.events, t)

    def _at(self, where: Problem, message: str) -> None:
        self.problems.append(Problem(where.file, where.line, where.col, message))

    def _check_reachable(self, scheme: Scheme) -> None:
        for state in unreachable(scheme):
            self.problem(self._path(state), f"state {state.name!r} is unreachable: no "
                         "transition or initial state leads to it", key=True)


def unreachable(scheme: Scheme, histories: bool = False) -> list[State]:
    """States that no run of the scheme can ever enter (history pseudo-states only if asked).

    A history state no transition targets is harmless in a scheme, but a tool
    that removes the unreachable states must remove it too: its default may
    name one of them.
    """
    graph = nx.DiGraph()
    graph.add_node(scheme.root)
    states = scheme.states
    for state in [scheme.root, *states.values()]:
        if state.parent is not None:
            graph.add_edge(state, state.parent)
        # a missing initial state is reported as such, not as unreachable children
        if state.kind == PARALLEL or (state.kind == COMPOUND and not state.initial):
            for child in state.proper_children():
                graph.add_edge(state, child)
        targets = [n for t in state.transitions for n in t.targets]
        for name in (*state.initial, *state.default, *targets):
            if name in states:
                graph.add_edge(state, states[name])
    reached = nx.descendants(graph, scheme.root)
    return [s for s in scheme.all_states() if s not in reached
            and (histories or s.kind != HISTORY)]


def _at(data: Any, path: tuple) -> Any:
    for key in path:
        if not isinstance(data, dict) or key not in data:
            return None
        data = data[key]
    return data


def _in_parallel_regions(a: State, b: State) -> bool:
    """True when the nearest common ancestor of ``a`` and ``b`` is a parallel state."""
    ancestors_a = a.ancestors()
    for anc in b.ancestors():
        if anc in ancestors_a:
            return anc.kind == PARALLEL
    return False


def _trigger(t: Transition) -> str:
    if t.after is not None:
        return t.events[0].split("@")[0] if t.events else "after"
    return " ".join(t.events) if t.events is not None else EVENTLESS_KEY

