"""The HDDL reader (planner/io/hddl/): tokens, S-expressions, the checked tree, the IPC 2020 suite.

The suite is read where it lies (``ipc2020`` in the external suites' folder, see
``tests/suites.py``; never copied here); the tests that need it are skipped, saying how
to get it, when it is absent.

Every feature test of the suite reads: ``sortof-domain.hddl``'s method ``donothing`` has
``:constraints (and (sortof ?b - A))``, which narrows ``?b`` to type ``A``.

No feature test is partially ordered: ``:subtasks`` there have one subtask or a total
``:ordering`` (``synonymes``).  ``empty-methods2-domain.hddl`` has no problem file; it is
read alone.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest
from suites import absent, needs, suite

from planner.io import hddl
from planner.io.hddl import (
    Formula,
    HDDLDomain,
    Subtask,
    is_total_order,
    read_domain,
    read_problem,
    read_sexpr,
    refuse_partial_order,
    supertypes,
    tokenize,
)
from userfiles.errors import FileError

IPC = suite("ipc2020")
FEATURES = IPC / "tests" / "ipc2020-feature-tests"
TOTAL = IPC / "total-order"
MISSING = absent("ipc2020")


def _suite(folder: Path, pattern: str) -> list:
    """Files of the suite as parameters, or one skipped parameter saying the suite is absent."""
    if not folder.is_dir():
        return [pytest.param(None, marks=pytest.mark.skip(reason=MISSING), id="suite-missing")]
    return [pytest.param(path, id=path.name) for path in sorted(folder.glob(pattern))]


needs_suite = needs("ipc2020")


def _at(text: str, needle: str, nth: int = 0) -> tuple[int, int]:
    """Line and column (from 1) of the nth occurrence of needle in text."""
    index = -1
    for _ in range(nth + 1):
        index = text.index(needle, index + 1)
    line = text.count("\n", 0, index) + 1
    return line, index - (text.rfind("\n", 0, index) + 1) + 1


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def _problems(call) -> list[tuple[int, int, str]]:
    with pytest.raises(FileError) as caught:
        call()
    assert "Traceback" not in str(caught.value)
    return [(p.line, p.col, p.message) for p in caught.value.problems]


def _has(found: list[tuple[int, int, str]], at: tuple[int, int], words: str) -> bool:
    return any((line, col) == at and words in message for line, col, message in found)


# --------------------------------------------------------------------------- tokens


def test_tokens_have_lines_columns_and_lower_case_values():
    text = "(DEFINE (domain Blocks) ; a comment (with parentheses)\r\n\t(:Types  block)\n)"
    tokens = tokenize(text)
    assert [(t.kind, t.value, t.text, t.line, t.col) for t in tokens] == [
        ("(", "(", "(", 1, 1),
        ("atom", "define", "DEFINE", 1, 2),
        ("(", "(", "(", 1, 9),
        ("atom", "domain", "domain", 1, 10),
        ("atom", "blocks", "Blocks", 1, 17),
        (")", ")", ")", 1, 23),
        ("(", "(", "(", 2, 2),  # a tab is one column
        ("atom", ":types", ":Types", 2, 3),
        ("atom", "block", "block", 2, 11),
        (")", ")", ")", 2, 16),
        (")", ")", ")", 3, 1),
    ]


def test_parentheses_split_atoms_and_comments_end_at_the_line():
    tokens = tokenize(":ordered-subtasks(and (t1 (nop)));(not a token)\n?x")
    assert [t.text for t in tokens] == [":ordered-subtasks", "(", "and", "(", "t1", "(", "nop",
                                        ")", ")", ")", "?x"]
    assert (tokens[-1].line, tokens[-1].col) == (2, 1)


def test_sexpressions_keep_the_positions_of_lists_and_atoms():
    text = "(a (b c)\n  (d))\n(e)"
    first, second = read_sexpr(text)
    assert (first.line, first.col, first.end_line, first.end_col) == (1, 1, 2, 6)
    b_list, d_list = first.items[1], first.items[2]
    assert (b_list.line, b_list.col, b_list.end_line, b_list.end_col) == (1, 4, 1, 8)
    assert (d_list.line, d_list.col) == (2, 3)
    assert (b_list.items[1].value, b_list.items[1].line, b_list.items[1].col) == ("c", 1, 7)
    assert (second.line, second.col, second.items[0].value) == (3, 1, "e")


# --------------------------------------------------------------------------- syntax errors


def test_stray_and_unclosed_parentheses_are_reported_together():
    text = ")\n(define (domain d)\n  (:predicates (p)\n"
    found = _problems(lambda: read_sexpr(text, "f.hddl"))
    assert (1, 1, "unexpected ')': no '(' is open here") in found
    assert _has(found, (2, 1), "'(' is never closed")
    assert _has(found, (3, 3), "'(' is never closed")
    assert len(found) == 3


def test_a_missing_parenthesis_points_at_the_section_swallowed(tmp_path):
    text = ("(define (domain d)\n"
            "  (:predicates (p))\n"
            "  (:action a :parameters () :precondition (and (p))\n"
            "  (:action b :parameters () :effect (p)))\n")
    found = _problems(lambda: read_domain(_write(tmp_path, "d.hddl", text)))
    assert _has(found, (1, 1), "'(' is never closed (the file ends at 4:42)")
    assert _has(found, (4, 3), "'(:action' is inside '(:action' opened at 3:3: a ')' is "
                               "probably missing before it")


def test_an_extra_parenthesis_points_where_the_definition_ends(tmp_path):
    text = ("(define (domain d)\n"
            "  (:predicates (p)))\n"
            "  (:action a :parameters () :precondition (p)))\n")
    found = _problems(lambda: read_domain(_write(tmp_path, "d.hddl", text)))
    assert _has(found, (2, 20), "is this ')' one too many?")
    assert _has(found, (3, 47), "unexpected ')'")


def test_file_level_mistakes(tmp_path):
    assert _problems(lambda: read_domain(_write(tmp_path, "e.hddl", "; nothing\n"))) == [
        (1, 1, "empty file: expected '(define (domain NAME) ...)'")]
    found = _problems(lambda: read_domain(_write(tmp_path, "p.hddl", "(define (problem p))")))
    assert found == [(1, 10, "this file defines a problem, not a domain")]
    found = _problems(lambda: read_domain(_write(tmp_path, "x.hddl", "(defne (domain d))")))
    assert found == [(1, 2, "expected '(define (domain NAME) ...)', found 'defne'")]
    deep = "(" * (hddl.MAX_DEPTH + 1)
    assert "nested deeper" in _problems(lambda: read_sexpr(deep))[0][2]
    binary = tmp_path / "b.hddl"
    binary.write_bytes(b"(define \xff)")
    assert "not UTF-8" in _problems(lambda: read_domain(binary))[0][2]
    assert "cannot read" in _problems(lambda: read_domain(tmp_path / "absent.hddl"))[0][2]


# --------------------------------------------------------------------------- a small domain

DOMAIN = """\
(define (domain Tidy)
  (:requirements :typing :hierarchy :negative-preconditions)
  (:types block - thing robot thing)
  (:constants table - block)
  (:predicates (on ?x ?y - block) (clear ?x - block) (holding ?r - robot ?x - block))
  (:task tidy :parameters (?x - block))
  (:method m-tidy
    :parameters (?x ?y - block ?r - robot)
    :task (tidy ?x)
    :precondition (and (on ?x ?y) (not (clear ?y)))
    :subtasks (and (t1 (pick ?r ?x)) (t2 (drop ?r ?x table)))
    :ordering (and (< t2 t1)))
  (:method m-done :parameters (?x - block) :task (tidy ?x) :ordered-subtasks (and))
  (:action pick
    :parameters (?r - robot ?x - block)
    :precondition (forall (?z - block) (imply (on ?z ?x) (= ?z ?x)))
    :effect (and (holding ?r ?x) (forall (?z - block) (when (on ?x ?z) (not (on ?x ?z))))))
  (:action drop
    :parameters (?r - robot ?x ?y - block)
    :precondition (or (holding ?r ?x) (exists (?b - block) (on ?b ?x)))
    :effect (and (not (holding ?r ?x)) (on ?x ?y)))
)
"""

PROBLEM = """\
(define (problem P1) (:domain TIDY)
  (:objects a b - block r2d2 - robot)
  (:htn :parameters () :ordered-subtasks (and (tidy a) (tidy b)))
  (:init (on a b) (clear a) (on b table))
  (:goal (and (clear b) (forall (?q - block) (not (holding r2d2 ?q)))))
)
"""


@pytest.fixture
def tidy(tmp_path) -> HDDLDomain:
    return read_domain(_write(tmp_path, "domain.hddl", DOMAIN))


def test_the_tree_of_a_domain(tidy):
    assert tidy.name == "tidy"
    assert tidy.requirements == (":typing", ":hierarchy", ":negative-preconditions")
    assert tidy.types == {"object": None, "block": "thing", "robot": "object", "thing": "object"}
    assert tidy.constants == {"table": "block"}
    assert tidy.predicates["holding"] == (("?r", "robot"), ("?x", "block"))
    assert tidy.tasks == {"tidy": (("?x", "block"),)}
    assert sorted(tidy.actions) == ["drop", "pick"]
    assert tidy.where[("predicate", "clear")] == _at(DOMAIN, "clear ?x - block")
    assert tidy.where[("method", "m-done")] == _at(DOMAIN, "(:method m-done")
    method = tidy.methods[0]
    assert (method.name, method.line, method.col) == ("m-tidy", *_at(DOMAIN, "(:method m-tidy"))
    assert method.params == (("?x", "block"), ("?y", "block"), ("?r", "robot"))
    assert (method.task.name, method.task.args) == ("tidy", ("?x",))
    assert str(method.precondition) == "(and (on ?x ?y) (not (clear ?y)))"
    # ':subtasks' with a total ':ordering' is total: the subtasks come in that order.
    assert method.ordered
    assert [(s.id, s.name, s.args) for s in method.subtasks] == [
        ("t2", "drop", ("?r", "?x", "table")), ("t1", "pick", ("?r", "?x"))]
    assert (method.subtasks[0].line, method.subtasks[0].col) == _at(DOMAIN, "(t2 (drop")
    assert method.ordering == (("t2", "t1"),)
    assert tidy.methods[1].subtasks == () and tidy.methods[1].ordered
    assert is_total_order(tidy)


def test_formulas_are_a_tagged_tree_with_positions(tidy):
    pick, drop = tidy.actions["pick"], tidy.actions["drop"]
    pre = pick.precondition
    assert pre.kind == "forall" and pre.children[0] == (("?z", "block"),)
    imply = pre.children[1]
    assert imply.kind == "imply"
    assert imply.children[0] == Formula("pred", ("on", ("?z", "?x")), *_at(DOMAIN, "(on ?z ?x)"))
    assert imply.children[1].kind == "=" and imply.children[1].children == ("?z", "?x")
    when = pick.effect.children[1].children[1]
    assert when.kind == "when" and (when.line, when.col) == _at(DOMAIN, "(when")
    assert str(when) == "(when (on ?x ?z) (not (on ?x ?z)))"
    assert [f.kind for f in drop.precondition.walk()] == ["or", "pred", "exists", "pred"]
    assert str(drop.effect) == "(and (not (holding ?r ?x)) (on ?x ?y))"


def test_the_tree_of_a_problem(tidy, tmp_path):
    problem = read_problem(_write(tmp_path, "p.hddl", PROBLEM), tidy)
    assert (problem.name, problem.domain_name) == ("p1", "tidy")
    assert problem.objects == {"a": "block", "b": "block", "r2d2": "robot"}
    assert hddl.all_objects(tidy, problem)["table"] == "block"
    assert [(f.pred, f.args) for f in problem.init] == [
        ("on", ("a", "b")), ("clear", ("a",)), ("on", ("b", "table"))]
    assert (problem.init[1].line, problem.init[1].col) == _at(PROBLEM, "(clear a)")
    assert problem.htn_subtasks == (Subtask(None, "tidy", ("a",), *_at(PROBLEM, "(tidy a)")),
                                    Subtask(None, "tidy", ("b",), *_at(PROBLEM, "(tidy b)")))
    assert problem.ordered and is_total_order(tidy, problem)
    assert str(problem.goal) == "(and (clear b) (forall (?q - block) (not (holding r2d2 ?q))))"
    assert (problem.goal.line, problem.goal.col) == _at(PROBLEM, "(and (clear b)")


def test_supertypes(tidy):
    assert supertypes(tidy, "block") == ["block", "thing", "object"]
    assert supertypes(tidy, "Robot") == ["robot", "object"]
    assert supertypes(tidy, "object") == ["object"]
    with pytest.raises(KeyError):
        supertypes(tidy, "furniture")


def test_untyped_files_without_htn_and_the_short_ordering_forms(tmp_path):
    text = """\
(define (domain plain)
  (:predicates (at ?x ?y) (free ?x))
  (:task go :parameters (?x ?y))
  (:method walk :parameters (?x ?y ?z) :task (go ?x ?y)
    :tasks (and (s2 (step ?z ?y)) (s1 (step ?x ?z))) :order (s1 < s2))
  (:action step :parameters (?a ?b) :precondition (at ?a ?b) :effect (and)))
"""
    domain = read_domain(_write(tmp_path, "d.hddl", text))
    assert domain.types == {"object": None} and domain.predicates["at"] == (
        ("?x", "object"), ("?y", "object"))
    walk = domain.methods[0]
    assert walk.ordered and [s.id for s in walk.subtasks] == ["s1", "s2"]
    assert domain.actions["step"].effect == Formula("and", (), *_at(text, "(and)"))
    problem = read_problem(_write(tmp_path, "p.hddl", "(define (problem p) (:domain plain)"
                                  " (:objects home work) (:init (at home work)))"), domain)
    assert problem.objects == {"home": "object", "work": "object"}
    assert problem.htn_subtasks == () and problem.ordered and problem.goal is None


def test_keywords_names_and_values(tmp_path):
    text = DOMAIN.replace("(:action drop\n", "(:action 9lives) (:action drop :effect\n", 1)
    text = text.replace(":effect (and (not (holding ?r ?x)) (on ?x ?y)))", ":effect)")
    found = _domain_problems(tmp_path, text)
    assert _has(found, _at(text, "9lives"), "'9lives' is not a valid name for an action")
    assert _has(found, _at(text, ":effect)"), "':effect' of action 'drop' has no value")
    assert _has(found, _at(text, ":effect\n"), "':effect' of action 'drop' has no value")


def test_case_does_not_matter_but_messages_keep_the_text(tmp_path):
    text = DOMAIN.replace("(:task tidy", "(:TASK Tidy").replace("(clear ?y)", "(CLEAR ?Y)")
    domain = read_domain(_write(tmp_path, "d.hddl", text))
    assert "tidy" in domain.tasks and str(domain.methods[0].precondition).endswith(
        "(not (clear ?y)))")
    broken = text.replace("(CLEAR ?Y)", "(CLEAR ?W)")
    found = _problems(lambda: read_domain(_write(tmp_path, "b.hddl", broken)))
    assert _has(found, _at(broken, "?W"), "variable '?W' is not declared")


# --------------------------------------------------------------------------- meaning errors


def _domain_problems(tmp_path, text: str) -> list[tuple[int, int, str]]:
    return _problems(lambda: read_domain(_write(tmp_path, "bad-domain.hddl", text)))


@pytest.mark.parametrize(("old", "new", "marker", "message"), [
    # undefined things
    ("(?x - block))\n  (:method m-tidy", "(?x - blok))\n  (:method m-tidy", "blok",
     "unknown type 'blok' (did you mean 'block'?)"),
    ("(:constants table - block)", "(:constants table - furniture)", "furniture",
     "unknown type 'furniture'"),
    ("(not (clear ?y))", "(not (clean ?y))", "clean", "unknown predicate 'clean'"),
    (":task (tidy ?x)\n    :precondition", ":task (tody ?x)\n    :precondition", "tody",
     "unknown task 'tody' (did you mean 'tidy'?)"),
    (":task (tidy ?x)\n    :precondition", ":task (pick ?r ?x)\n    :precondition", "pick ?r ?x)",
     "method 'm-tidy' decomposes 'pick', which is an action, not a task"),
    ("(t1 (pick ?r ?x))", "(t1 (pik ?r ?x))", "pik",
     "unknown task or action 'pik' (did you mean 'pick'?)"),
    ("(t1 (pick ?r ?x))", "(t1 (clear ?x))", "clear ?x))",
     "'clear' is a predicate, not a task or an action"),
    ("(drop ?r ?x table)", "(drop ?r ?x tabel)", "tabel",
     "unknown constant 'tabel' (did you mean 'table'?)"),
    # arity
    ("(on ?x ?y) (not", "(on ?x) (not", "on ?x) (not",
     "predicate 'on' takes 2 argument(s), given 1"),
    ("(t1 (pick ?r ?x))", "(t1 (pick ?r))", "pick ?r))", "action 'pick' takes 2 argument(s), "
     "given 1"),
    (":task (tidy ?x)\n    :precondition", ":task (tidy ?x ?y)\n    :precondition", "tidy ?x ?y",
     "task 'tidy' takes 1 argument(s), given 2"),
    # variables
    ("(not (clear ?y))", "(not (clear ?w))", "?w",
     "variable '?w' is not declared (declared: ?x, ?y, ?r)"),
    ("(t1 (pick ?r ?x))", "(t1 (pick ?robot ?x))", "?robot", "variable '?robot' is not declared"),
    (":task (tidy ?x)\n    :precondition", ":task (tidy ?b)\n    :precondition", "?b)",
     "variable '?b' is not declared"),
    ("(on ?x ?y)))\n)", "(on ?x ?z)))\n)", "?z)))\n)", "variable '?z' is not declared (declared: "
     "?r, ?x, ?y)"),
    ("(when (on ?x ?z)", "(when (on ?x ?q)", "?q", "variable '?q' is not declared"),
    # types of constants
    ("(drop ?r ?x table)", "(drop table ?x table)", "table ?x", "'table' is a block, but "
     "argument 1 of action 'drop' is a robot"),
    # duplicates
    ("robot thing)", "robot thing robot)", "robot)", "duplicate type 'robot' (first at 3:25)"),
    ("(:constants table - block)", "(:constants table - block table)", "table)",
     "duplicate constant 'table' (first at 4:15)"),
    ("(clear ?x - block)", "(clear ?x - block) (on ?a - block)", "on ?a",
     "duplicate predicate 'on' (first at 5:17)"),
    ("(:task tidy :parameters (?x - block))", "(:task tidy :parameters (?x - block)) "
     "(:task tidy)", "tidy)", "duplicate task 'tidy' (already defined as a task at 6:3)"),
    ("(:action drop", "(:action tidy :parameters ()) (:action drop", "tidy :parameters ()",
     "duplicate action 'tidy' (already defined as a task at 6:3)"),
    ("(:action drop", "(:action pick) (:action drop", "pick)",
     "duplicate action 'pick' (already defined as an action at 14:3)"),
    ("(:method m-done", "(:method m-tidy :task (tidy ?x)) (:method m-done", "m-tidy :task",
     "duplicate method 'm-tidy' (first at 7:3)"),
    ("(?x ?y - block ?r - robot)", "(?x ?y - block ?x - robot)", "?x - robot",
     "duplicate parameter '?x' of method 'm-tidy' (first at 8:18)"),
    ("(t2 (drop", "(t1 (drop", "(t1 (drop", "duplicate subtask id 't1' in method 'm-tidy'"),
    # names and structure
    ("(:method m-done :parameters (?x - block)", "(:method m-done :parameters (x - block)",
     "x - block) :task (tidy ?x) :ordered", "expected a variable, found 'x'"),
    (":subtasks (and", ":subtask (and", ":subtask ", "unknown keyword ':subtask' in method "
     "'m-tidy' (did you mean ':subtasks'?)"),
    ("(:method m-done :parameters (?x - block) :task (tidy ?x)", "(:method m-done "
     ":parameters (?x - block)", "(:method m-done", "method 'm-done' has no ':task'"),
    ("(:predicates", "(:predicate", ":predicate", "unknown section ':predicate' (did you mean "
     "':predicates'?)"),
    (":ordering (and (< t2 t1))", ":ordering (and (< t2 t3))", "t3", "unknown subtask id 't3' in"
     " the ordering of method 'm-tidy' (ids: t1, t2)"),
    ("(< t2 t1)", "(< t2 t1) (< t1 t2)", ":ordering", "the ordering of method 'm-tidy' has a "
     "cycle through 't1', 't2'"),
    (":ordered-subtasks (and)", ":ordered-subtasks (and) :ordering (< a b)", ":ordering (< a b)",
     "':ordering' cannot be used with ':ordered-subtasks'"),
])
def test_each_meaning_error_is_reported_at_its_position(tmp_path, old, new, marker, message):
    assert old in DOMAIN, old
    text = DOMAIN.replace(old, new, 1)
    found = _domain_problems(tmp_path, text)
    at = _at(text, marker)
    assert _has(found, at, message), (at, found)


def test_type_cycles_and_the_root_type(tmp_path):
    text = DOMAIN.replace("(:types block - thing robot thing)",
                          "(:types block - thing thing - block object - robot robot)")
    found = _domain_problems(tmp_path, text)
    assert _has(found, _at(text, "block - thing"), "type 'block' is its own ancestor "
                                                   "(block - thing - block)")
    assert len([m for _, _, m in found if "own ancestor" in m]) == 1  # once per cycle
    assert _has(found, _at(text, "object - robot"), "'object' is the root type")


def test_a_type_used_only_as_a_parent_is_declared_under_object(tmp_path):
    text = DOMAIN.replace("(:types block - thing robot thing)", "(:types block - thing robot)")
    domain = read_domain(_write(tmp_path, "d.hddl", text))
    assert domain.types["thing"] == "object"
    assert supertypes(domain, "block") == ["block", "thing", "object"]


def test_all_problems_of_a_file_come_at_once(tmp_path):
    text = (DOMAIN.replace("(not (clear ?y))", "(not (clean ?y))")
            .replace("(t1 (pick ?r ?x))", "(t1 (pick ?r))")
            .replace("(on ?x ?y)))\n)", "(on ?x ?z)))\n)"))
    found = _domain_problems(tmp_path, text)
    assert len(found) == 3
    assert [line for line, _, _ in found] == sorted(line for line, _, _ in found)


def test_too_many_problems_are_counted(tmp_path):
    facts = " ".join(f"(nope{i})" for i in range(hddl.MAX_PROBLEMS + 50))
    text = DOMAIN.replace("(:goal", "").replace(
        "(:action drop", f"(:action many :precondition (and {facts})) (:action drop")
    found = _domain_problems(tmp_path, text)
    assert len(found) == hddl.MAX_PROBLEMS + 1
    assert found[-1][2] == "... and 50 more problems"


@pytest.mark.parametrize(("old", "new", "marker", "message"), [
    ("(define (problem P1) (:domain TIDY)", "(define (problem P1) (:domain untidy)", "untidy",
     "the problem is for domain 'untidy', but the domain read is 'tidy'"),
    ("r2d2 - robot", "r2d2 - droid", "droid", "unknown type 'droid'"),
    ("a b - block", "a b a - block", "a - block", "duplicate object 'a' (first at 2:13)"),
    ("a b - block", "a b table - block", None, None),  # a constant again, same type: fine
    ("a b - block", "a b - block table - robot", "table - robot",
     "'table' is a robot here but a block as a constant of the domain"),
    ("(clear a)", "(clear c)", "c)", "unknown object 'c'"),
    ("(clear a)", "(clean a)", "clean", "unknown predicate 'clean' (did you mean 'clear'?)"),
    ("(clear a)", "(clear a b)", "clear a b", "predicate 'clear' takes 1 argument(s), given 2"),
    ("(clear a)", "(clear r2d2)", "r2d2)", "'r2d2' is a robot, but argument 1 of 'clear' is "
     "a block"),
    ("(clear a)", "(clear ?a)", "?a)", "variable '?a' in ':init': facts are about objects"),
    ("(clear a)", "(not (clear a))", "not", "'not' in ':init'"),
    ("(tidy b)", "(tidy ?b)", "?b", "variable '?b' is not declared (no variables are in scope "
     "here)"),
    ("(tidy b)", "(tidyy b)", "tidyy", "unknown task or action 'tidyy' (did you mean 'tidy'?)"),
    ("(tidy b)", "(tidy b a)", "tidy b a", "task 'tidy' takes 1 argument(s), given 2"),
    ("(clear b)", "(clear ?b)", "?b", "variable '?b' is not declared"),
    ("(:goal", "(:goal (on a b)) (:goal", "(:goal", "section ':goal' given twice"),
])
def test_problem_errors_are_reported_at_their_position(tidy, tmp_path, old, new, marker,
                                                       message):
    assert old in PROBLEM, old
    text = PROBLEM.replace(old, new, 1)
    path = _write(tmp_path, "p.hddl", text)
    if message is None:
        assert read_problem(path, tidy).objects["table"] == "block"
        return
    found = _problems(lambda: read_problem(path, tidy))
    at = _at(text, marker, nth=1 if marker == "(:goal" else 0)
    assert _has(found, at, message), (at, found)


# --------------------------------------------------------------------------- refused by name


@pytest.mark.parametrize(("old", "new", "marker", "message"), [
    (":negative-preconditions)", ":negative-preconditions :durative-actions)", ":durative-actions",
     "requirement ':durative-actions' is not supported (durative actions)"),
    ("(:task tidy", "(:functions (cost) - number) (:task tidy", ":functions",
     "':functions' is not supported (numeric fluents)"),
    ("(:task tidy", "(:durative-action go :parameters ()) (:task tidy", ":durative-action",
     "':durative-action' is not supported (durative actions)"),
    ("(:task tidy", "(:derived (d ?x) (clear ?x)) (:task tidy", ":derived",
     "':derived' is not supported (derived predicates)"),
    ("(:types block - thing robot thing)", "(:types block robot - (either thing obj) thing)",
     "(either", "'either' types are not supported"),
    ("(holding ?r ?x) (forall", "(increase (total-cost) 1) (forall", "increase",
     "numeric effect 'increase' is not supported (numeric fluents)"),
    ("(= ?z ?x)", "(> ?z ?x)", "> ?z", "numeric comparison '>' is not supported"),
    ("(= ?z ?x)", "(preference p (clear ?x))", "preference", "preferences ('preference') are "
     "not supported"),
    ("(:method m-done :parameters (?x - block) :task (tidy ?x)", "(:method m-done :parameters "
     "(?x - block) :task (tidy ?x) :effect (clear ?x)", ":effect (clear",
     "':effect' is not supported in method 'm-done' (method effects)"),
    ("(:method m-done :parameters (?x - block) :task (tidy ?x)", "(:method m-done :parameters "
     "(?x - block) :task (tidy ?x) :constraints (and (typeof ?x - block))", "typeof",
     "'typeof' is not a supported task-network constraint (supported: '=', '(not (= ...))' and "
     "'sortof')"),
    ("(:task tidy :parameters (?x - block))", "(:task tidy :parameters (?x - block) "
     ":precondition (clear ?x))", ":precondition (clear", "':precondition' is not supported in "
     "task 'tidy' (abstract tasks with preconditions)"),
    ("(:action drop\n", "(:action drop :duration (= ?duration 1)\n", ":duration",
     "':duration' is not supported in action 'drop' (durative actions)"),
])
def test_unsupported_constructs_are_refused_by_name(tmp_path, old, new, marker, message):
    assert old in DOMAIN, old
    text = DOMAIN.replace(old, new, 1)
    found = _domain_problems(tmp_path, text)
    assert _has(found, _at(text, marker), message), (_at(text, marker), found)


@pytest.mark.parametrize(("old", "new", "marker", "message"), [
    ("(:goal", "(:constraints (always (clear a))) (:goal", ":constraints",
     "':constraints' is not supported (state-trajectory constraints)"),
    ("(:goal", "(:metric minimize (total-cost)) (:goal", ":metric",
     "':metric' is not supported (plan metrics)"),
    ("(clear a)", "(= (cost a) 3)", "=", "numeric fluents ('=' in ':init') are not supported"),
    ("(clear a)", "(at 10 (clear a))", "at 10", "timed initial literals"),
    ("(:htn :parameters ()", "(:htn :parameters () :causal-links ()", ":causal-links",
     "':causal-links' is not supported in the initial task network"),
])
def test_unsupported_problem_constructs_are_refused_by_name(tidy, tmp_path, old, new, marker,
                                                            message):
    text = PROBLEM.replace(old, new, 1)
    found = _problems(lambda: read_problem(_write(tmp_path, "p.hddl", text), tidy))
    assert _has(found, _at(text, marker), message), (_at(text, marker), found)


# --------------------------------------------------------------------------- partial order

PARTIAL = DOMAIN.replace(
    "(:method m-done",
    "(:method m-fork :parameters (?x - block ?r - robot) :task (tidy ?x)\n"
    "    :subtasks (and (a (pick ?r ?x)) (b (pick ?r ?x)) (c (drop ?r ?x ?x)))\n"
    "    :ordering (and (< a c) (b < c)))\n"
    "  (:method m-bag :parameters (?x - block ?r - robot) :task (tidy ?x)\n"
    "    :tasks (and (pick ?r ?x) (drop ?r ?x ?x)))\n"
    "  (:method m-one :parameters (?x - block ?r - robot) :task (tidy ?x)\n"
    "    :subtasks (pick ?r ?x))\n"
    "  (:method m-done")


def test_partial_orders_are_recorded_then_refused_by_name(tmp_path):
    domain = read_domain(_write(tmp_path, "d.hddl", PARTIAL))
    ordered = {m.name: m.ordered for m in domain.methods}
    assert ordered == {"m-tidy": True, "m-fork": False, "m-bag": False, "m-one": True,
                       "m-done": True}
    fork = next(m for m in domain.methods if m.name == "m-fork")
    assert fork.ordering == (("a", "c"), ("b", "c"))  # '(< a c)' and infix '(b < c)'
    assert not is_total_order(domain)
    found = _problems(lambda: refuse_partial_order(domain))
    assert found == [
        (*_at(PARTIAL, "(:method m-fork"), "method 'm-fork' is not totally ordered: 'a' and 'b' "
         "are not ordered by ':ordering'; only the total-order subset of HDDL is supported"),
        (*_at(PARTIAL, "(:method m-bag"), "method 'm-bag' is not totally ordered: its 2 "
         "subtasks have no ':ordering'; only the total-order subset of HDDL is supported"),
    ]


def test_a_partially_ordered_initial_task_network(tidy, tmp_path):
    text = PROBLEM.replace(":ordered-subtasks (and (tidy a) (tidy b))",
                           ":subtasks (and (tidy a) (tidy b))")
    problem = read_problem(_write(tmp_path, "p.hddl", text), tidy)
    assert not problem.ordered and not is_total_order(tidy, problem) and is_total_order(tidy)
    found = _problems(lambda: refuse_partial_order(tidy, problem))
    assert found == [(*_at(text, "(:htn"), "the initial task network of problem 'p1' is not "
                      "totally ordered: its 2 subtasks have no ':ordering'; only the total-order "
                      "subset of HDDL is supported")]
    refuse_partial_order(tidy)  # the domain alone is fine


# --------------------------------------------------------------------------- the IPC 2020 suite


@pytest.mark.parametrize("path", _suite(FEATURES, "*-domain.hddl"))
def test_every_feature_test_reads(path):
    domain = read_domain(path)
    assert is_total_order(domain)
    problem_path = path.with_name(path.name.replace("-domain", ""))
    if problem_path.exists():  # empty-methods2 has no problem
        problem = read_problem(problem_path, domain)
        assert is_total_order(domain, problem)
        assert problem.htn_subtasks


@needs_suite
def test_what_the_feature_tests_say():
    synonymes = read_domain(FEATURES / "synonymes-domain.hddl")
    # ':subtasks' + ':ordering', ':tasks' + ':ordering', ':ordered-subtasks', ':ordered-tasks'
    assert [(m.name, m.ordered, [s.name for s in m.subtasks]) for m in synonymes.methods] == [
        (f"sequence{i}", True, ["noop1", "noop2"]) for i in range(1, 5)]
    problem = read_problem(FEATURES / "synonymes.hddl", synonymes)
    assert [s.name for s in problem.htn_subtasks] == ["task1", "task2", "task3", "task4"]
    constants = read_domain(FEATURES / "constants-domain.hddl")
    problem = read_problem(FEATURES / "constants.hddl", constants)
    assert problem.objects == {} and problem.init[0].args == ("a",)  # 'a' is a constant
    assert problem.htn_subtasks[0].id == "task0"
    sortof = read_domain(FEATURES / "sortof-domain.hddl")
    assert sortof.methods[0].params == (("?b", "a"),)  # (sortof ?b - A) narrows ?b - B
    assert sortof.methods[0].constraints is None
    forall = read_domain(FEATURES / "forall2-domain.hddl")
    assert str(forall.actions["noop"].precondition) == "(forall (?a - a) (foo ?a ?b))"
    abort = read_domain(FEATURES / "abort-iteration-domain.hddl")
    assert [m.subtasks[0].name for m in abort.methods] == ["task1", "noop"]  # recursion
    empty = read_domain(FEATURES / "only-primitive-domain.hddl")
    assert empty.actions["noop"].precondition is None and not empty.methods
    problem = read_problem(FEATURES / "only-primitive.hddl", empty)
    assert problem.htn_subtasks[0].name == "noop" and problem.goal is None


def _section(text: str, keyword: str) -> str:
    """The text of '(keyword ...)' found by counting parentheses (independent of the reader)."""
    start = text.lower().index("(" + keyword)
    depth = 0
    for index in range(start, len(text)):
        depth += {"(": 1, ")": -1}.get(text[index], 0)
        if depth == 0:
            return text[start:index + 1]
    raise AssertionError(keyword)


@pytest.fixture(scope="module")
def blocksworld() -> HDDLDomain:
    return read_domain(TOTAL / "Blocksworld-GTOHP" / "domain.hddl")


@pytest.fixture(scope="module")
def childsnack() -> HDDLDomain:
    return read_domain(TOTAL / "Childsnack" / "domain.hddl")


@needs_suite
def test_the_two_total_order_domains(blocksworld, childsnack):
    assert (blocksworld.name, len(blocksworld.actions), len(blocksworld.methods)) == (
        "blocks", 5, 8)
    assert blocksworld.types == {"object": None, "block": "object"}
    assert blocksworld.actions["nop"].precondition is None  # ':precondition ()'
    assert blocksworld.actions["nop"].effect is None
    assert is_total_order(blocksworld)
    assert (childsnack.name, len(childsnack.actions), len(childsnack.methods)) == (
        "child-snack", 7, 2)
    assert childsnack.constants == {"kitchen": "place"}
    assert childsnack.methods[0].subtasks[2].args == ("?t", "kitchen", "?p2")
    assert is_total_order(childsnack)


@pytest.mark.parametrize("path", _suite(TOTAL / "Blocksworld-GTOHP", "p*.hddl"))
def test_blocksworld_problems(blocksworld, path):
    problem = read_problem(path, blocksworld)
    text = path.read_text()
    blocks = int(problem.name.rsplit("-", 1)[1])  # BW-rand-N
    assert problem.objects == {f"b{i}": "block" for i in range(1, blocks + 1)}
    assert len(problem.init) == _section(text, ":init").count("(") - 1 > 0
    assert len(problem.htn_subtasks) == _section(text, ":htn").count("(") // 2 - 1 > 0
    assert {s.name for s in problem.htn_subtasks} <= set(blocksworld.tasks)
    assert problem.goal.kind == "and" and {g.children[0] for g in problem.goal.children} == {"on"}
    assert is_total_order(blocksworld, problem)


@pytest.mark.parametrize("path", _suite(TOTAL / "Childsnack", "p*.hddl"))
def test_childsnack_problems(childsnack, path):
    problem = read_problem(path, childsnack)
    text = path.read_text()
    children = int(re.search(r"with (\d+) children", text).group(1))
    kinds = [kind for kind in problem.objects.values()]
    assert kinds.count("child") == children
    assert len(problem.htn_subtasks) == children
    assert [s.args for s in problem.htn_subtasks] == [(f"child{i}",) for i in
                                                       range(1, children + 1)]
    assert len(problem.init) == _section(text, ":init").count("(") - 1
    assert sum(f.pred == "waiting" for f in problem.init) == children
    assert sum(f.pred == "notexist" for f in problem.init) == kinds.count("sandwich")
    # Not always one per child: p19's goal forgets child22.
    assert len(problem.goal.children) == _section(text, ":goal").count("(served") > 0
    assert is_total_order(childsnack, problem)


# --------------------------------------------------------------------------- standalone


def test_the_reader_imports_neither_shary_nor_sim():
    imported = set()
    for path in Path(hddl.__file__).parent.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                imported.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.module:
                imported.add(node.module)
    tops = {name.split(".")[0] for name in imported}
    assert not tops & {"shary", "sim"}
    assert tops <= {"__future__", "difflib", "heapq", "os", "re", "collections", "dataclasses",
                    "typing", "userfiles", "planner"}
    assert {name for name in imported if name.startswith("planner")} <= {
        f"planner.io.hddl.{m.stem}" for m in Path(hddl.__file__).parent.glob("*.py")}


def test_each_module_of_the_reader_stays_small():
    for path in Path(hddl.__file__).parent.glob("*.py"):
        assert len(path.read_text(encoding="utf-8").splitlines()) < 650, path.name
