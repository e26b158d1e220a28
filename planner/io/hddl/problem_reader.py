"""Reading an HDDL problem: objects, initial state, initial task network, goal."""

from __future__ import annotations

from planner.io.hddl.lexer import SList, Symbol
from planner.io.hddl.model import Fact, HDDLDomain, HDDLProblem, Params, Subtask
from planner.io.hddl.networks import _Networks
from planner.io.hddl.reader import _NETWORK_UNSUPPORTED, _NUMBER, _SUBTASK_KEYS, _a, _show


class _ProblemReader(_Networks):
    def __init__(self, file: str, domain: HDDLDomain):
        super().__init__(file)
        self.domain = domain
        self.types = dict(domain.types)
        self.predicates = dict(domain.predicates)
        self.tasks = dict(domain.tasks)
        self.action_params = {name: a.params for name, a in domain.actions.items()}
        self.objects = dict(domain.constants)
        self.object_word = "object"

    def read(self, definition: tuple[SList, Symbol]) -> HDDLProblem:
        define, name_node = definition
        problem_name = self.name(name_node, "the problem") or name_node.value
        sections = self.sections(define, (":domain", ":requirements", ":objects", ":htn",
                                          ":init", ":goal"))
        where: dict[tuple[str, str], tuple[int, int]] = {}
        first: dict[str, SList] = {}
        for word, node in sections:
            if word in (":domain", ":htn", ":goal", ":init") and word in first:
                earlier = first[word]
                self.error(node, f"section '{word}' given twice (first at "
                                 f"{earlier.line}:{earlier.col})")
            first.setdefault(word, node)
        domain_name = self.domain.name
        if ":domain" not in first:
            self.error(define, f"the problem does not say its domain: add '(:domain "
                               f"{self.domain.name})'")
        else:
            node = first[":domain"]
            if len(node.items) != 2 or not isinstance(node.items[1], Symbol):
                self.error(node, "expected '(:domain NAME)'")
            else:
                domain_name = node.items[1].value
                if domain_name != self.domain.name:
                    self.error(node.items[1], f"the problem is for domain "
                                              f"'{node.items[1].text}', but the domain read is "
                                              f"'{self.domain.name}' ({self.domain.file})")
        requirements: list[str] = []
        for word, node in sections:
            if word == ":requirements":
                requirements.extend(self.requirements(node))
        own: dict[str, str] = {}
        for word, node in sections:
            if word == ":objects":
                self.read_objects(node, own, where)
        init: list[Fact] = []
        if ":init" in first:
            init = self.read_init(first[":init"])
        params: Params = ()
        subtasks: tuple[Subtask, ...] = ()
        ordered, ordering = True, ()
        htn_line = htn_col = 0
        constraints = None
        if ":htn" in first:
            node = first[":htn"]
            htn_line, htn_col = node.line, node.col
            keys = self.keyed(node.items[1:], {":parameters": ":parameters",
                                               ":constraints": ":constraints", **_SUBTASK_KEYS},
                              _NETWORK_UNSUPPORTED,
                              "the initial task network (':htn')")
            params = self.params(keys[":parameters"][1] if ":parameters" in keys else None,
                                 "':htn'")
            if ":constraints" in keys:
                constraints, narrowed = self.constraints(keys[":constraints"][1], dict(params))
                params = tuple((var, narrowed.get(var, kind)) for var, kind in params)
            subtasks, ordered, ordering = self.network(keys, dict(params),
                                                       "the initial task network")
        goal = None
        if ":goal" in first:
            node = first[":goal"]
            if len(node.items) != 2:
                self.error(node, f"'(:goal' needs exactly one condition, given "
                                 f"{len(node.items) - 1}")
            else:
                goal = self.condition(node.items[1], {})
        return HDDLProblem(problem_name, domain_name, own, tuple(init), params, subtasks, ordered,
                           goal, self.file, define.line, define.col, tuple(requirements),
                           ordering, htn_line, htn_col, where, constraints, dict(self.spelling))

    def read_objects(self, node: SList, own: dict[str, str], where: dict) -> None:
        body = node._replace(items=node.items[1:])
        for symbol, kind, kind_node in self.typed_list(body, False, "an object"):
            if kind_node is not None and not self.known_type(kind_node, kind):
                kind = "object"
            name = symbol.value
            if name in own:
                line, col = where[("object", name)]
                self.error(symbol, f"duplicate object '{symbol.text}' (first at {line}:{col})")
                continue
            if name in self.domain.constants and self.domain.constants[name] != kind:
                line, col = self.domain.where.get(("constant", name), (1, 1))
                self.error(symbol, f"'{symbol.text}' is {_a(kind)} here but "
                                   f"{_a(self.domain.constants[name])} as a constant of the domain "
                                   f"({self.domain.file}:{line}:{col})")
                continue
            own[name] = kind
            self.objects[name] = kind
            self.spell(symbol)
            where[("object", name)] = (symbol.line, symbol.col)

    def read_init(self, node: SList) -> list[Fact]:
        facts: list[Fact] = []
        for item in node.items[1:]:
            if not isinstance(item, SList) or not item.items:
                self.error(item, f"expected a fact like '(on a b)', found "
                                 f"{_show(item) if isinstance(item, Symbol) else '()'}")
                continue
            head = item.items[0]
            if not isinstance(head, Symbol):
                self.error(head, "expected a predicate, found a list")
                continue
            if head.value == "=":
                self.error(head, "numeric fluents ('=' in ':init') are not supported")
                continue
            if head.value == "not":
                self.error(head, "'not' in ':init': the initial state lists only the facts that "
                                 "hold")
                continue
            if (head.value == "at" and len(item.items) > 1 and isinstance(item.items[1], Symbol)
                    and _NUMBER.match(item.items[1].value)):
                self.error(head, "timed initial literals ('(at TIME ...)') are not supported")
                continue
            if head.value in ("and", "or", "forall", "exists", "when", "imply"):
                self.error(head, f"'{head.text}' in ':init': the initial state lists facts only")
                continue
            variables = [i for i in item.items[1:]
                         if isinstance(i, Symbol) and i.value.startswith("?")]
            if variables:
                self.error(variables[0], f"variable '{variables[0].text}' in ':init': facts "
                                         "are about objects")
                continue
            fact = self.atom(item, {})
            if fact is not None:
                name, args = fact.children
                facts.append(Fact(name, args, item.line, item.col))
        return facts
