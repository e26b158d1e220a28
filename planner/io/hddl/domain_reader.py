"""Reading an HDDL domain: types, constants, predicates, tasks, actions, methods."""

from __future__ import annotations

from planner.io.hddl.lexer import Node, SList, Symbol
from planner.io.hddl.model import Call, HAction, HDDLDomain, HMethod
from planner.io.hddl.networks import _Networks
from planner.io.hddl.reader import _NETWORK_UNSUPPORTED, _SUBTASK_KEYS, _show


class _DomainReader(_Networks):
    def read(self, definition: tuple[SList, Symbol]) -> HDDLDomain:
        define, name_node = definition
        domain_name = self.name(name_node, "the domain") or name_node.value
        sections = self.sections(define, (":requirements", ":types", ":constants", ":predicates",
                                          ":task", ":action", ":method"))
        where: dict[tuple[str, str], tuple[int, int]] = {}
        requirements: list[str] = []
        for word, node in sections:
            if word == ":requirements":
                requirements.extend(self.requirements(node))
        self.read_types([n for w, n in sections if w == ":types"], where)
        for word, node in sections:
            if word == ":constants":
                self.read_constants(node, where)
        for word, node in sections:
            if word == ":predicates":
                self.read_predicates(node, where)
        declared: list[tuple[str, SList, dict[str, tuple[Symbol, Node]], str]] = []
        for word, node in sections:
            if word in (":task", ":action"):
                found = self.declare(word, node, where)
                if found is not None:
                    declared.append(found)
        actions: dict[str, HAction] = {}
        for word, node, keys, name in declared:
            if word == ":action":
                scope = dict(self.action_params[name])
                pre = keys.get(":precondition")
                eff = keys.get(":effect")
                actions[name] = HAction(
                    name, self.action_params[name],
                    self.condition(pre[1], scope) if pre else None,
                    self.effect(eff[1], scope, top=True) if eff else None,
                    node.line, node.col)
        methods: list[HMethod] = []
        for word, node in sections:
            if word == ":method":
                method = self.read_method(node, where)
                if method is not None:
                    methods.append(method)
        return HDDLDomain(domain_name, tuple(requirements), dict(self.types), dict(self.objects),
                          dict(self.predicates), dict(self.tasks), methods, actions, self.file,
                          define.line, define.col, where, dict(self.spelling))

    def read_types(self, nodes: list[SList], where: dict) -> None:
        explicit: dict[str, tuple[str, Symbol, Node | None]] = {}
        implicit: dict[str, Node] = {}
        for node in nodes:
            body = node._replace(items=node.items[1:])
            for symbol, parent, parent_node in self.typed_list(body, False, "a type"):
                name = symbol.value
                if name == "object":
                    if parent != "object":
                        self.error(symbol, "'object' is the root type; it has no parent")
                    continue
                if name in explicit:
                    first = explicit[name][1]
                    self.error(symbol, f"duplicate type '{symbol.text}' (first at "
                                       f"{first.line}:{first.col})")
                    continue
                explicit[name] = (parent, symbol, parent_node)
                if parent_node is not None and parent != "object":
                    implicit.setdefault(parent, parent_node)
        for name, (parent, symbol, _) in explicit.items():
            self.types[name] = parent
            where[("type", name)] = (symbol.line, symbol.col)
        for name, node in implicit.items():
            if name not in self.types:
                self.types[name] = "object"
                where[("type", name)] = (node.line, node.col)
        for name, (_, symbol, _) in explicit.items():
            seen = [name]
            current = self.types.get(name)
            while current is not None:
                if current == name:
                    self.error(symbol, f"type '{symbol.text}' is its own ancestor ("
                                       f"{' - '.join([*seen, name])})")
                    self.types[name] = "object"
                    break
                if current in seen:
                    break
                seen.append(current)
                current = self.types.get(current)

    def read_constants(self, node: SList, where: dict) -> None:
        body = node._replace(items=node.items[1:])
        for symbol, kind, kind_node in self.typed_list(body, False, "a constant"):
            if kind_node is not None and not self.known_type(kind_node, kind):
                kind = "object"
            if symbol.value in self.objects:
                line, col = where[("constant", symbol.value)]
                self.error(symbol, f"duplicate constant '{symbol.text}' (first at {line}:{col})")
                continue
            self.objects[symbol.value] = kind
            self.spell(symbol)
            where[("constant", symbol.value)] = (symbol.line, symbol.col)

    def read_predicates(self, node: SList, where: dict) -> None:
        for item in node.items[1:]:
            if not isinstance(item, SList) or not item.items:
                self.error(item, f"expected a predicate like '(on ?x ?y - block)', found "
                                 f"{_show(item) if isinstance(item, Symbol) else '()'}")
                continue
            name = self.name(item.items[0], "a predicate")
            if name is None:
                continue
            params = self.params(item._replace(items=item.items[1:]), f"predicate '{name}'")
            if name in self.predicates:
                line, col = where[("predicate", name)]
                self.error(item.items[0], f"duplicate predicate '{item.items[0].text}' (first "
                                          f"at {line}:{col})")
                continue
            self.predicates[name] = params
            where[("predicate", name)] = (item.items[0].line, item.items[0].col)

    def declare(self, word: str, node: SList, where: dict
                ) -> tuple[str, SList, dict[str, tuple[Symbol, Node]], str] | None:
        """A task or an action: its name and parameters (bodies are read later)."""
        kind = word[1:]
        if len(node.items) < 2:
            self.error(node, f"'({word}' needs a name")
            return None
        label = node.items[1]
        name = self.name(label, "a task" if kind == "task" else "an action")
        if name is None or not isinstance(label, Symbol):
            return None
        what = f"{kind} '{label.text}'"
        if kind == "task":
            keys = self.keyed(node.items[2:], {":parameters": ":parameters",
                                               ":precondition": ":precondition",
                                               ":effect": ":effect"}, {}, what)
            for key in (":precondition", ":effect"):  # '()' is written, and means nothing
                if key in keys:
                    word, value = keys[key]
                    if not isinstance(value, SList) or value.items:
                        self.error(word, f"'{word.text}' is not supported in {what} (abstract "
                                         f"tasks with {key[1:]}s)")
        else:
            keys = self.keyed(node.items[2:], {":parameters": ":parameters",
                                               ":precondition": ":precondition",
                                               ":effect": ":effect"}, {
                ":duration": "durative actions",
                ":condition": "durative actions",
                ":cost": "action costs",
            }, what)
        params = self.params(keys[":parameters"][1] if ":parameters" in keys else None, what)
        for other in ("task", "action"):
            if (other, name) in where:
                line, col = where[(other, name)]
                article = "an" if other == "action" else "a"
                self.error(label, f"duplicate {kind} '{label.text}' (already defined as "
                                  f"{article} {other} at {line}:{col})")
                return None
        where[(kind, name)] = (node.line, node.col)
        if kind == "task":
            self.tasks[name] = params
        else:
            self.action_params[name] = params
        return word, node, keys, name

    def read_method(self, node: SList, where: dict) -> HMethod | None:
        if len(node.items) < 2:
            self.error(node, "'(:method' needs a name")
            return None
        label = node.items[1]
        name = self.name(label, "a method")
        if name is None or not isinstance(label, Symbol):
            return None
        text = label.text
        what = f"method '{text}'"
        keys = self.keyed(node.items[2:], {":parameters": ":parameters", ":task": ":task",
                                           ":precondition": ":precondition",
                                           ":constraints": ":constraints", **_SUBTASK_KEYS},
                          {":effect": "method effects", **_NETWORK_UNSUPPORTED}, what)
        duplicate = ("method", name) in where
        if duplicate:
            line, col = where[("method", name)]
            self.error(label, f"duplicate method '{text}' (first at {line}:{col})")
        else:
            where[("method", name)] = (node.line, node.col)
        params = self.params(keys[":parameters"][1] if ":parameters" in keys else None, what)
        scope = dict(params)
        constraints, narrowed = (self.constraints(keys[":constraints"][1], scope)
                                 if ":constraints" in keys else (None, {}))
        params = tuple((var, narrowed.get(var, kind)) for var, kind in params)
        scope = dict(params)
        task = self.method_task(keys.get(":task"), scope, what, node)
        pre = keys.get(":precondition")
        precondition = self.condition(pre[1], scope) if pre else None
        subtasks, ordered, ordering = self.network(keys, scope, what)
        if task is None or duplicate:
            return None
        return HMethod(name, params, task, precondition, subtasks, ordered, node.line, node.col,
                       ordering, constraints)

    def method_task(self, entry: tuple[Symbol, Node] | None, scope: dict[str, str], what: str,
                    node: SList) -> Call | None:
        if entry is None:
            self.error(node, f"{what} has no ':task' (the task it decomposes)")
            return None
        key, value = entry
        if not isinstance(value, SList) or not value.items or not isinstance(value.items[0],
                                                                             Symbol):
            self.error(value, f"':task' of {what} must be a task like '(task ?x)'")
            return None
        head = value.items[0]
        assert isinstance(head, Symbol)
        if head.value not in self.tasks:
            if head.value in self.action_params:
                self.error(head, f"{what} decomposes '{head.text}', which is an action, not a "
                                 "task")
            else:
                self.error(head, f"unknown task '{head.text}'{self.hint(head.value, self.tasks)}")
            self.terms(value.items[1:], scope, None, "")
            return None
        signature = self.tasks[head.value]
        ok = self.arity(head, f"task '{head.text}'", signature, len(value.items) - 1)
        args = self.terms(value.items[1:], scope, signature, f"task '{head.text}'")
        if not ok or args is None:
            return None
        return Call(head.value, args, value.line, value.col)
