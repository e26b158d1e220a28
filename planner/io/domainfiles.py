"""Loading planning domains and problems: schema first, then meaning.

Domains and problems are YAML, read with :mod:`userfiles` (safe, located,
limited), checked against ``planner/schemas/*.schema.json``, then compiled:
every condition, effect, cost and subtask argument is parsed by
:mod:`planner.model.expr` once, with the types of its variables, so that an
unknown attribute or a typo in an expression is reported at its line and
column before any search.
"""

from __future__ import annotations

import os
import re
from functools import cache
from pathlib import Path
from typing import Any

from jsonschema import Draft202012Validator

from planner.conditional.agendas import open_vars, read_agendas, read_assigns
from planner.evaluation.ahp import AHPError, priority_vector
from planner.evaluation.evaluate import BASE_CRITERIA
from planner.model.domain import (
    AGENT_KINDS,
    Action,
    ConditionalEffect,
    Decomposition,
    Domain,
    EntityType,
    Method,
    Problem,
    Rule,
    SelectedRule,
    Subtask,
)
from planner.model.expr import ExprError, compile_effect, compile_expr
from userfiles import schema as checks
from userfiles.errors import FileError
from userfiles.errors import Problem as FileProblem
from userfiles.reader import Reader, open_checked
from userfiles.schema import did_you_mean

SCHEMAS = Path(__file__).resolve().parents[1] / "schemas"
DOMAINS = Path(__file__).resolve().parents[1] / "domains"
PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
SCALARS = ("bool", "number", "string", "any")
_CALL = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*\((.*)\)\s*$", re.S)


@cache
def _validator(name: str) -> Draft202012Validator:
    return checks.validator(SCHEMAS, name)


def builtin_domains() -> list[Path]:
    return sorted(DOMAINS.glob("*.yaml"))


def builtin_problems() -> list[Path]:
    return sorted(PROBLEMS.glob("*.yaml"))


def find_domain(name_or_path: str | os.PathLike[str]) -> Path:
    """A domain file by path, or by the name of a built-in domain."""
    text = os.fspath(name_or_path)
    if os.path.exists(text) or text.endswith((".yaml", ".yml")) or os.sep in text:
        return Path(text)
    found = DOMAINS / f"{text}.yaml"
    if found.is_file():
        return found
    names = [p.stem for p in builtin_domains()]
    raise FileError([FileProblem(text, 1, 1, f"no such file, and no built-in domain {text!r}"
                                 f"{did_you_mean(text, names)}; built-in: {', '.join(names)}")])


def load_domain(name_or_path: str | os.PathLike[str]) -> Domain:
    """Load and compile a domain; raise FileError with every problem of the file."""
    reader = open_checked(find_domain(name_or_path), _validator("domain"))
    domain = _DomainBuilder(reader).build()
    reader.done()
    return domain


def load_problem(path: str | os.PathLike[str], domain: Domain) -> Problem:
    """Load a problem for ``domain``; raise FileError with every problem of the file."""
    reader = open_checked(path, _validator("problem"))
    problem = _ProblemBuilder(reader, domain).build()
    reader.done()
    return problem


class _Builder:
    """The meaning checks of a file whose shape is right (the reader pipeline's third
    step); problems go to the reader, which raises them all at once."""

    def __init__(self, reader: Reader):
        self.reader = reader
        self.located = reader.located
        self.data: dict[str, Any] = reader.data
        self.problem = reader.problem

    def expr_problem(self, path: tuple, err: ExprError, prefix: str = "") -> None:
        self.reader.problem_inside(path, err.offset, f"{prefix}{err.message}")


class _DomainBuilder(_Builder):
    def __init__(self, reader: Reader):
        super().__init__(reader)
        self.types: dict[str, EntityType] = {}

    def build(self) -> Domain:
        data = self.data
        for name, spec in _items(data.get("types")):
            spec = spec if isinstance(spec, dict) else {}
            static = {k: v for k, v in _items(spec.get("static")) if isinstance(v, str)}
            dynamic = {k: v for k, v in _items(spec.get("dynamic")) if isinstance(v, str)}
            for attr in set(static) & set(dynamic):
                self.problem(("types", name, "dynamic", attr), f"attribute {attr!r} is both "
                             "static and dynamic", key=True)
            self.types[name] = EntityType(name, static, dynamic, spec.get("agent") is True,
                                          spec.get("doc", "") or "")
        for name, etype in self.types.items():
            for part in ("static", "dynamic"):
                for attr, kind in getattr(etype, part).items():
                    if kind not in SCALARS and kind not in self.types:
                        self.problem(("types", name, part, attr), f"unknown type {kind!r}"
                                     f"{did_you_mean(kind, [*SCALARS, *self.types])}")
            if etype.agent and "kind" not in etype.static:
                self.problem(("types", name), "an agent type needs a static attribute "
                             "'kind' (robot or human)", key=True)
        self.attributes = {n: t.attributes for n, t in self.types.items()}
        actions = {n: self._action(n, s) for n, s in _items(data.get("actions"))
                   if isinstance(s, dict)}
        clash = set(actions) & set(_items_dict(data.get("methods")))
        for name in sorted(clash):
            self.problem(("methods", name), f"{name!r} is both an action and a method", key=True)
        self.task_params = {n: a.params for n, a in actions.items()}
        for name, spec in _items(data.get("methods")):
            if isinstance(spec, dict):
                self.task_params[name] = self._params(("methods", name, "params"),
                                                      spec.get("params"))
        methods = {n: self._method(n, s) for n, s in _items(data.get("methods"))
                   if isinstance(s, dict)}
        actions = read_assigns(self, actions, methods)
        rules = {n: self._rule(n, s, actions, methods) for n, s in _items(data.get("rules"))
                 if isinstance(s, dict)}
        domain = Domain(str(data.get("domain", "domain")), self.types, actions, methods, rules,
                        data.get("doc", "") or "", self.located.file)
        if isinstance(data.get("uncontrolled"), list):
            domain.uncontrolled = tuple(str(k) for k in data["uncontrolled"])
        return domain

    def _params(self, path: tuple, raw: Any) -> tuple[tuple[str, str], ...]:
        out = []
        for name, kind in _items(raw):
            if not isinstance(kind, str):
                continue
            if kind not in self.types:
                self.problem(path + (name,), f"unknown type {kind!r}"
                             f"{did_you_mean(kind, self.types)}")
            out.append((name, kind))
        return tuple(out)

    def _expr(self, path: tuple, raw: Any, variables: dict[str, str]) -> Any:
        if raw is None:
            return None
        if isinstance(raw, bool):
            raw = "true" if raw else "false"
        if isinstance(raw, (int, float)):
            return float(raw)
        try:
            return compile_expr(str(raw), variables, self.attributes)
        except ExprError as err:
            self.expr_problem(path, err)
            return None

    def _effects(self, path: tuple, raw: Any, variables: dict[str, str]) -> tuple:
        out: list[Any] = []
        for index, item in enumerate(raw if isinstance(raw, list) else []):
            where = path + (index,)
            if isinstance(item, str):
                try:
                    out.append(compile_effect(item, variables, self.attributes))
                except ExprError as err:
                    self.expr_problem(where, err)
            elif isinstance(item, dict):
                condition = self._expr(where + ("if",), item.get("if"), variables)
                inner = []
                for j, text in enumerate(item.get("then") or []):
                    try:
                        inner.append(compile_effect(str(text), variables, self.attributes))
                    except ExprError as err:
                        self.expr_problem(where + ("then", j), err)
                if condition is not None:
                    out.append(ConditionalEffect(condition, tuple(inner)))
        return tuple(out)

    def _action(self, name: str, spec: dict[str, Any]) -> Action:
        path = ("actions", name)
        params = self._params(path + ("params",), spec.get("params"))
        variables = dict(params)
        agent = spec.get("agent")
        if isinstance(agent, str):
            if agent not in variables:
                self.problem(path + ("agent",), f"{agent!r} is not a parameter of {name}"
                             f"{did_you_mean(agent, variables)}")
            elif variables[agent] in self.types and not self.types[variables[agent]].agent:
                self.problem(path + ("agent",), f"parameter {agent!r} is a "
                             f"{variables[agent]}, which is not an agent type "
                             "(say 'agent: true' on the type)")
        pre = self._expr(path + ("pre",), spec.get("pre"), variables)
        cost = self._expr(path + ("cost",), spec.get("cost", 1), variables)
        duration = self._expr(path + ("duration",), spec.get("duration", 1), variables)
        effects = self._effects(path + ("effects",), spec.get("effects"), variables)
        for target in [e for e in effects if not isinstance(e, ConditionalEffect)]:
            self._check_dynamic(path, target)
        return Action(name, params, str(agent), pre, effects,
                      1.0 if cost is None else cost, 1.0 if duration is None else duration,
                      spec.get("doc", "") or "")

    def _check_dynamic(self, path: tuple, effect: Any) -> None:
        attr = effect.target_attribute
        static = [t for t, et in self.types.items() if attr in et.static
                  and attr not in et.dynamic]
        if static and not any(attr in et.dynamic for et in self.types.values()):
            self.problem(path + ("effects",), f"effect {effect.text!r} changes {attr!r}, a "
                         f"static attribute of {', '.join(static)}")

    def _method(self, name: str, spec: dict[str, Any]) -> Method:
        path = ("methods", name)
        params = self.task_params[name]
        decompositions = []
        seen: set[str] = set()
        for index, dec in enumerate(spec.get("decompositions") or []):
            if not isinstance(dec, dict):
                continue
            where = path + ("decompositions", index)
            dec_name = str(dec.get("name", f"d{index + 1}"))
            if dec_name in seen:
                self.problem(where + ("name",), f"two decompositions of {name} are named "
                             f"{dec_name!r}")
            seen.add(dec_name)
            vars_ = self._params(where + ("vars",), dec.get("vars"))
            variables = {**dict(params), **dict(vars_)}
            for var, _ in vars_:
                if var in dict(params):
                    self.problem(where + ("vars", var), f"{var!r} is already a parameter of "
                                 f"{name}", key=True)
            pre = self._expr(where + ("pre",), dec.get("pre"), variables)
            subtasks = []
            for j, text in enumerate(dec.get("subtasks") or []):
                sub = self._subtask(where + ("subtasks", j), str(text), variables)
                if sub is not None:
                    subtasks.append(sub)
            decompositions.append(Decomposition(
                dec_name, vars_, pre, tuple(subtasks), dec.get("doc", "") or "",
                weight=float(dec.get("weight", 1.0)), abandon=dec.get("abandon"),
                open=open_vars(self, where, dec.get("open"), dict(vars_))))
        return Method(name, params, tuple(decompositions), spec.get("doc", "") or "",
                      first=spec.get("choose") == "first")

    def _subtask(self, path: tuple, text: str, variables: dict[str, str]) -> Subtask | None:
        match = _CALL.match(text)
        if not match:
            self.problem(path, f"{text!r} is not a subtask: write Task(arg, ...)")
            return None
        task, inner = match.group(1), match.group(2)
        if task not in self.task_params:
            self.problem(path, f"unknown task {task!r}"
                         f"{did_you_mean(task, self.task_params)}")
            return None
        pieces = _split_args(inner)
        params = self.task_params[task]
        if len(pieces) != len(params):
            self.problem(path, f"{task} takes {len(params)} argument(s) "
                         f"({', '.join(p for p, _ in params)}), not {len(pieces)}")
            return None
        args = []
        base = text.index("(") + 1
        for (offset, piece) in pieces:
            try:
                args.append(compile_expr(piece, variables, self.attributes))
            except ExprError as err:
                err.offset += base + offset
                self.expr_problem(path, err)
                return None
        return Subtask(task, tuple(args), text)

    def _rule(self, name: str, spec: dict[str, Any], actions: dict[str, Action],
              methods: dict[str, Method]) -> Rule:
        path = ("rules", name)
        kind = str(spec.get("kind"))
        if name in BASE_CRITERIA:
            self.problem(path, f"{name!r} is the name of a criterion; give the rule another "
                         "name", key=True)
        vars_ = self._params(path + ("vars",), spec.get("vars"))
        when = self._expr(path + ("when",), spec.get("when"), dict(vars_))
        if kind == "state" and when is None and "when" not in spec:
            self.problem(path, "a state rule needs 'when' (the undesirable state)", key=True)

        def step(key: str) -> tuple[str, str | None] | None:
            raw = spec.get(key)
            if not isinstance(raw, dict):
                if kind == "sequence":
                    self.problem(path, f"a sequence rule needs {key!r}", key=True)
                return None
            action = str(raw.get("action"))
            if action not in actions:
                self.problem(path + (key, "action"), f"unknown action {action!r}"
                             f"{did_you_mean(action, actions)}")
            return action, raw.get("agent_kind")

        first, then = step("first"), step("then")
        link = tuple((str(a), str(b)) for a, b in _items(spec.get("link")))
        for a, b in link:
            if first and first[0] in actions and a not in dict(actions[first[0]].params):
                self.problem(path + ("link",), f"{a!r} is not a parameter of {first[0]}")
            if then and then[0] in actions and b not in dict(actions[then[0]].params):
                self.problem(path + ("link", a), f"{b!r} is not a parameter of {then[0]}")
        method = spec.get("method")
        if kind == "decomposition":
            if method not in methods:
                self.problem(path + ("method",), f"unknown method {method!r}"
                             f"{did_you_mean(str(method), methods)}")
            elif spec.get("decomposition") not in {d.name for d in
                                                   methods[method].decompositions}:
                self.problem(path + ("decomposition",), f"{method} has no decomposition "
                             f"{spec.get('decomposition')!r}")
        return Rule(name, kind, vars_, when, spec.get("during") is True, first, then, link,
                    str(spec.get("agents", "any")), spec.get("immediately", True) is not False,
                    method if isinstance(method, str) else None,
                    spec.get("decomposition"), float(spec.get("max_wait", 0.0)),
                    spec.get("doc", "") or "")


class _ProblemBuilder(_Builder):
    def __init__(self, reader: Reader, domain: Domain):
        super().__init__(reader)
        self.domain = domain

    def build(self) -> Problem:
        data = self.data
        domain = self.domain
        declared = data.get("domain")
        if isinstance(declared, str) and declared not in (domain.name, Path(domain.file).name,
                                                          domain.file):
            self.problem(("domain",), f"this problem is for domain {declared!r}, not "
                         f"{domain.name!r}")
        entities: dict[str, str] = {}
        initial: dict[tuple[str, str], Any] = {}
        for name, spec in _items(data.get("entities")):
            if not isinstance(spec, dict) or not isinstance(spec.get("type"), str):
                continue
            etype = domain.types.get(spec["type"])
            if etype is None:
                self.problem(("entities", name, "type"), f"unknown type {spec['type']!r}"
                             f"{did_you_mean(spec['type'], domain.types)}")
                continue
            entities[name] = etype.name
        for name, spec in _items(data.get("entities")):
            if name not in entities:
                continue
            etype = domain.types[entities[name]]
            for attr, value in spec.items():
                if attr == "type":
                    continue
                if attr not in etype.attributes:
                    self.problem(("entities", name, attr), f"{etype.name} has no attribute "
                                 f"{attr!r}{did_you_mean(attr, etype.attributes)}", key=True)
                    continue
                self._check_value(("entities", name, attr), etype.attributes[attr], value,
                                  entities)
                initial[(name, attr)] = value
            if etype.agent and spec.get("kind") not in AGENT_KINDS:
                self.problem(("entities", name), f"agent {name!r} needs kind: robot or human",
                             key=True)
        tasks = []
        for index, text in enumerate(data.get("tasks") or []):
            task = self._task(("tasks", index), str(text), entities)
            if task is not None:
                tasks.append(task)
        goals = {}
        for key, value in _items(data.get("goals")):
            entity, _, attr = key.rpartition(".")
            if entity not in entities:
                self.problem(("goals", key), f"unknown entity {entity!r}"
                             f"{did_you_mean(entity, entities)}", key=True)
                continue
            if attr not in domain.types[entities[entity]].attributes:
                self.problem(("goals", key), f"{entities[entity]} has no attribute {attr!r}",
                             key=True)
                continue
            goals[(entity, attr)] = value
        rules = {}
        for name, spec in _items(data.get("rules")):
            rule = domain.rules.get(name)
            if rule is None:
                self.problem(("rules", name), f"the domain has no rule {name!r}"
                             f"{did_you_mean(name, domain.rules)}", key=True)
                continue
            spec = spec if isinstance(spec, dict) else {}
            penalty = spec.get("penalty", 1.0)
            table = dict(penalty) if isinstance(penalty, dict) else {"default": float(penalty)}
            rules[name] = SelectedRule(rule, {k: float(v) for k, v in table.items()},
                                       float(spec.get("weight", 1.0)))
        weights, scale = self._criteria(rules)
        agendas = read_agendas(self, entities)
        return Problem(str(data.get("problem", "problem")), domain, entities, initial,
                       tuple(tasks), goals, rules, weights, scale,
                       int(data.get("budget_ms", 1000)), data.get("doc", "") or "",
                       self.located.file, agendas, dict(data.get("policy") or {}))

    def _check_value(self, path: tuple, kind: str, value: Any, entities: dict[str, str]) -> None:
        if value is None or kind == "any":
            return
        if kind == "bool" and not isinstance(value, bool):
            self.problem(path, f"expected true or false, got {value!r}")
        elif kind == "number" and (isinstance(value, bool) or not isinstance(value, (int, float))):
            self.problem(path, f"expected a number, got {value!r}")
        elif kind == "string" and not isinstance(value, str):
            self.problem(path, f"expected a string, got {value!r}")
        elif kind not in SCALARS:
            if value not in entities:
                self.problem(path, f"unknown entity {value!r}"
                             f"{did_you_mean(str(value), entities)}")
            elif entities[value] != kind:
                self.problem(path, f"{value!r} is a {entities[value]}, not a {kind}")

    def _task(self, path: tuple, text: str, entities: dict[str, str]
              ) -> tuple[str, tuple[Any, ...]] | None:
        match = _CALL.match(text)
        if not match:
            self.problem(path, f"{text!r} is not a task: write Task(entity, ...)")
            return None
        name = match.group(1)
        params = self._params_of(name)
        if params is None:
            self.problem(path, f"unknown task {name!r}"
                         f"{did_you_mean(name, [*self.domain.actions, *self.domain.methods])}")
            return None
        args = [piece.strip().strip("'\"") for _, piece in _split_args(match.group(2))]
        if len(args) != len(params):
            self.problem(path, f"{name} takes {len(params)} argument(s), not {len(args)}")
            return None
        for arg, (param, kind) in zip(args, params, strict=True):
            if arg not in entities:
                self.problem(path, f"unknown entity {arg!r} for {param}"
                             f"{did_you_mean(arg, entities)}")
                return None
            if entities[arg] != kind:
                self.problem(path, f"{arg!r} is a {entities[arg]}; {name} wants a {kind} "
                             f"for {param}")
                return None
        return name, tuple(args)

    def _params_of(self, name: str) -> tuple[tuple[str, str], ...] | None:
        task = self.domain.task(name)
        return task.params if task is not None else None

    def _criteria(self, rules: dict[str, SelectedRule]
                  ) -> tuple[dict[str, float], dict[str, float]]:
        spec = self.data.get("criteria")
        if not isinstance(spec, dict):
            return {}, {}
        names = [n for n in spec.get("names") or [] if isinstance(n, str)]
        known = [*BASE_CRITERIA, *rules]
        ok = True
        for index, name in enumerate(names):
            if name not in known:
                self.problem(("criteria", "names", index), f"unknown criterion {name!r}"
                             f"{did_you_mean(name, known)}; criteria: {', '.join(known)}")
                ok = False
        matrix = []
        for i, row in enumerate(spec.get("matrix") or []):
            values = []
            for j, cell in enumerate(row if isinstance(row, list) else []):
                number = _number(cell)
                if number is None:
                    self.problem(("criteria", "matrix", i, j), f"{cell!r} is not a number or "
                                 "a fraction such as 1/3")
                    ok = False
                values.append(number or 0.0)
            matrix.append(values)
        if not ok:
            return {}, {}
        if len(matrix) != len(names) or any(len(r) != len(names) for r in matrix):
            self.problem(("criteria", "matrix"), f"the matrix must be {len(names)} x "
                         f"{len(names)}, one row and one column per criterion")
            return {}, {}
        try:
            result = priority_vector(matrix)
        except AHPError as err:
            row, col = getattr(err, "row", None), getattr(err, "col", None)
            where = ("criteria", "matrix") + ((row, col) if row is not None and col is not None
                                              else ())
            self.problem(where, str(err))
            return {}, {}
        scale = {k: float(v) for k, v in _items(spec.get("scale"))}
        return dict(zip(names, result.weights, strict=True)), scale


def _number(cell: Any) -> float | None:
    if isinstance(cell, bool):
        return None
    if isinstance(cell, (int, float)):
        return float(cell)
    match = re.fullmatch(r"\s*([0-9.]+)\s*/\s*([0-9.]+)\s*", str(cell))
    if match:
        try:
            return float(match.group(1)) / float(match.group(2))
        except (ValueError, ZeroDivisionError):
            return None
    return None


def _split_args(text: str) -> list[tuple[int, str]]:
    """Split ``a, f(b, c), "x,y"`` at top-level commas; keep each piece's offset."""
    pieces: list[tuple[int, str]] = []
    depth = 0
    quote = ""
    start = 0
    for i, ch in enumerate(text):
        if quote:
            if ch == quote:
                quote = ""
        elif ch in "'\"":
            quote = ch
        elif ch == "(":
            depth += 1
        elif ch == ")":
            depth -= 1
        elif ch == "," and depth == 0:
            pieces.append((start, text[start:i]))
            start = i + 1
    if text.strip():
        pieces.append((start, text[start:]))
    return [(offset + len(piece) - len(piece.lstrip()), piece.strip()) for offset, piece in pieces]


def _items(value: Any) -> list[tuple[str, Any]]:
    return list(value.items()) if isinstance(value, dict) else []


def _items_dict(value: Any) -> dict[str, Any]:
    return value if isinstance(value, dict) else {}
