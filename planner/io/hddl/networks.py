"""Task networks (a method's, and a problem's ``:htn``): subtasks, their order, and
the ``:constraints`` HDDL allows on their variables."""

from __future__ import annotations

from planner.io.hddl.lexer import Node, SList, Symbol
from planner.io.hddl.model import Formula, Subtask, _label, _order
from planner.io.hddl.reader import _Reader, _show


class _Networks(_Reader):
    """A reader of task networks (shared by the domain's methods and the problem's ``:htn``)."""

    # -- task networks

    def network(self, keys: dict[str, tuple[Symbol, Node]], scope: dict[str, str], what: str
                ) -> tuple[tuple[Subtask, ...], bool, tuple[tuple[str, str], ...]]:
        """Subtasks, whether they are totally ordered, and the ordering as written."""
        plain, ordered_key = keys.get(":subtasks"), keys.get(":ordered-subtasks")
        ordering_key = keys.get(":ordering")
        if plain and ordered_key:
            self.error(ordered_key[0], f"{what} has both '{plain[0].text}' and "
                                       f"'{ordered_key[0].text}'")
        entry = ordered_key or plain
        subtasks = self.subtasks(entry[1], scope) if entry else []
        pairs = self.ordering(ordering_key[1]) if ordering_key else []
        if ordered_key and pairs:
            self.error(ordering_key[0], f"'{ordering_key[0].text}' cannot be used with "
                                        f"'{ordered_key[0].text}', which is already ordered")
            return tuple(subtasks), True, ()
        ids: dict[str, Subtask] = {}
        for subtask in subtasks:
            if subtask.id is None:
                continue
            if subtask.id in ids:
                first = ids[subtask.id]
                self.error(subtask, f"duplicate subtask id '{subtask.id}' in {what} (first at "
                                    f"{first.line}:{first.col})")
            ids[subtask.id] = subtask
        written: list[tuple[str, str]] = []
        for before, after in pairs:
            good = True
            for symbol in (before, after):
                if symbol.value not in ids:
                    known = ", ".join(ids) or "none"
                    self.error(symbol, f"unknown subtask id '{symbol.text}' in the ordering of "
                                       f"{what} (ids: {known}){self.hint(symbol.value, ids)}")
                    good = False
            if good and before.value == after.value:
                self.error(before, f"subtask '{before.text}' cannot come before itself")
                good = False
            if good:
                written.append((before.value, after.value))
        if ordered_key:
            return tuple(subtasks), True, ()
        result = _order(subtasks, written)
        if result.cycle:
            names = ", ".join(_label(subtasks[i], i) for i in result.cycle)
            assert ordering_key is not None
            self.error(ordering_key[0], f"the ordering of {what} has a cycle through {names}")
            return tuple(subtasks), False, tuple(written)
        if result.order is not None:
            return tuple(subtasks[i] for i in result.order), True, tuple(written)
        return tuple(subtasks), False, tuple(written)

    def entries(self, node: Node, example: str, what: str) -> tuple[Node, ...]:
        """The entries of a list HDDL writes either as ``(and E1 E2 ...)`` or as one
        entry ``E`` (subtasks, orderings); ``()`` has none."""
        if not isinstance(node, SList):
            self.error(node, f"expected {what} like '{example}', found {_show(node)}")
            return ()
        if not node.items:
            return ()
        head = node.items[0]
        return (tuple(node.items[1:]) if isinstance(head, Symbol) and head.value == "and"
                else (node,))

    def subtasks(self, node: Node, scope: dict[str, str]) -> list[Subtask]:
        out = []
        for entry in self.entries(node, "(and (t1 (task ?x)) ...)", "subtasks"):
            subtask = self.subtask(entry, scope)
            if subtask is not None:
                out.append(subtask)
        return out

    def subtask(self, entry: Node, scope: dict[str, str]) -> Subtask | None:
        if not isinstance(entry, SList) or not entry.items:
            self.error(entry, f"expected a subtask like '(task ?x)' or '(id (task ?x))', found "
                              f"{_show(entry) if isinstance(entry, Symbol) else '()'}")
            return None
        ident: str | None = None
        call = entry
        if len(entry.items) == 2 and isinstance(entry.items[1], SList):
            ident = self.name(entry.items[0], "a subtask id")
            call = entry.items[1]
            if ident is None:
                return None
            if not call.items:
                self.error(call, "expected a task like '(task ?x)', found '()'")
                return None
        head = call.items[0]
        if not isinstance(head, Symbol):
            self.error(head, "expected the name of a task or an action, found a list")
            return None
        name = head.value
        signature = self.tasks.get(name, self.action_params.get(name))
        if signature is None:
            known = [*self.tasks, *self.action_params]
            what = "predicate" if name in self.predicates else None
            if what:
                self.error(head, f"'{head.text}' is a predicate, not a task or an action")
            else:
                self.error(head, f"unknown task or action '{head.text}'{self.hint(name, known)}")
            self.terms(call.items[1:], scope, None, "")
            # Kept (the file is refused anyway) so that its id does not look unknown.
            return Subtask(ident, name, (), entry.line, entry.col)
        kind = "task" if name in self.tasks else "action"
        ok = self.arity(head, f"{kind} '{head.text}'", signature, len(call.items) - 1)
        args = self.terms(call.items[1:], scope, signature, f"{kind} '{head.text}'")
        return Subtask(ident, name, args if ok and args is not None else (), entry.line,
                       entry.col)

    def ordering(self, node: Node) -> list[tuple[Symbol, Symbol]]:
        out: list[tuple[Symbol, Symbol]] = []
        for entry in self.entries(node, "(and (< t1 t2))", "ordering constraints"):
            items = entry.items if isinstance(entry, SList) else ()
            if len(items) == 3 and all(isinstance(i, Symbol) for i in items):
                a, b, c = items
                assert isinstance(a, Symbol) and isinstance(b, Symbol) and isinstance(c, Symbol)
                if a.value == "<":
                    out.append((b, c))
                    continue
                if b.value == "<":
                    out.append((a, c))
                    continue
                if a.value == ">" or b.value == ">":
                    self.error(entry, "only '<' orders subtasks: write '(< t1 t2)'")
                    continue
            self.error(entry, "expected an ordering constraint like '(< t1 t2)', found "
                              f"{_show(entry) if isinstance(entry, Symbol) else 'a list'}")
        return out

    def constraints(self, node: Node, scope: dict[str, str]
                    ) -> tuple[Formula | None, dict[str, str]]:
        """A method's or the ``:htn``'s ``:constraints``: ``(= a b)``, ``(not (= a b))`` and
        ``(sortof ?v - type)`` (``?v`` must be of ``type``, a subtype of its own), in an
        ``and`` or alone.  The conditions, and the narrowed type of each variable."""
        if not isinstance(node, SList):
            self.error(node, f"expected constraints like '(and (sortof ?x - type))', found "
                             f"{_show(node)}")
            return None, {}
        items = node.items
        if items and isinstance(items[0], Symbol) and items[0].value == "and":
            items = items[1:]
        elif items:
            items = (node,)
        parts: list[Formula] = []
        narrowed: dict[str, str] = {}
        for item in items:
            head = item.items[0] if isinstance(item, SList) and item.items else None
            word = head.value if isinstance(head, Symbol) else ""
            inner = (item.items[1] if word == "not" and isinstance(item, SList)
                     and len(item.items) == 2 else None)
            if word == "=" or (isinstance(inner, SList) and inner.items
                               and isinstance(inner.items[0], Symbol)
                               and inner.items[0].value == "="):
                formula = self.gd(item, scope)
                if formula is not None:
                    parts.append(formula)
            elif word == "sortof":
                assert isinstance(item, SList) and isinstance(head, Symbol)
                self.sortof(item, head, scope, narrowed)
            else:
                at = head if head is not None else item
                self.error(at, f"'{_show(at)[1:-1] if isinstance(at, Symbol) else 'a list'}' "
                               "is not a supported task-network constraint (supported: '=', "
                               "'(not (= ...))' and 'sortof')")
        formula = Formula("and", tuple(parts), node.line, node.col) if parts else None
        return formula, narrowed

    def sortof(self, item: SList, head: Symbol, scope: dict[str, str],
               narrowed: dict[str, str]) -> None:
        """``(sortof ?v - type)``: record ``type`` for ``?v`` when it fits."""
        args = item.items[1:]
        if (len(args) != 3 or not all(isinstance(a, Symbol) for a in args)
                or args[1].value != "-"):
            self.error(head, "expected '(sortof ?variable - type)'")
            return
        var, _, kind = args
        assert isinstance(var, Symbol) and isinstance(kind, Symbol)
        if var.value not in scope:
            self.error(var, f"variable '{var.text}' is not a parameter of this task network"
                            f"{self.hint(var.value, scope)}")
        elif self.known_type(kind, kind.value):
            if not self.fits(kind.value, scope[var.value]):
                self.error(kind, f"'{kind.text}' is not a subtype of {var.text}'s type "
                                 f"'{scope[var.value]}'")
            else:
                narrowed[var.value] = kind.value
