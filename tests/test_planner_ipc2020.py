"""The IPC 2020 HTN suite (total order): feature tests, Blocksworld-GTOHP, Childsnack.

The suite is read where it lies (``ipc2020`` in the external suites' folder, see
``tests/suites.py``); without it these tests are skipped, saying how to get it.  To keep
the suite short, only the first instances of each domain are planned here;
``benchmarks/planner_vs_gtpyhop.py`` runs all thirty of each.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import problems
from suites import needs, suite

from planner import load_hddl, plan, validate
from planner.io.ipc import read_ipc, shape, write_ipc

SUITE = suite("ipc2020")
FEATURES = SUITE / "tests" / "ipc2020-feature-tests"
TOTAL = SUITE / "total-order"

pytestmark = needs("ipc2020")

EXPECTED = {
    "abort-iteration": ["noop(a)"],
    "arguments": ["noop(b, b)"],
    "constants": ["noop(a)"],
    "empty-methods-empty-plan": [],
    "forall": ["noop()"],
    "forall2": ["noop(f)"],
    "only-primitive": ["noop()"],
    "sortof": ["noop(a)"],
    "synonymes": ["noop1()", "noop2()"] * 4,
}
"""The plan each feature test expects (the only plan there is, or the one ``plans/``
gives)."""


def _feature(name: str) -> tuple[Path, Path]:
    return FEATURES / f"{name}-domain.hddl", FEATURES / f"{name}.hddl"


def test_every_feature_test_is_covered():
    names = {p.stem for p in FEATURES.glob("*.hddl") if not p.stem.endswith("-domain")}
    assert names == set(EXPECTED)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_feature_test_gives_the_expected_plan(name):
    problem = load_hddl(*_feature(name))
    result = plan(problem, 10_000, first=True)
    assert result.plan is not None, result.explain()
    assert [str(a) for a in result.plan.actions] == EXPECTED[name]
    assert validate(problem, result.plan) == []
    written = write_ipc(result.plan)
    for expected in (FEATURES / "plans").glob(f"{name}.*"):  # sortof's is sortof.hddl
        assert shape(read_ipc(written)) == shape(read_ipc(expected.read_text(), str(expected)))


def test_the_expected_plans_are_all_compared():
    assert {p.stem for p in (FEATURES / "plans").iterdir()} <= set(EXPECTED)


def test_a_domain_alone_reads_and_plans_with_a_problem_of_ours(write):
    domain = FEATURES / "empty-methods2-domain.hddl"
    mine = write("p.hddl", """\
        (define (problem p) (:domain test-domain)
          (:htn :ordered-subtasks (and (task1) (task1))))
        """)
    problem = load_hddl(domain, mine)
    result = plan(problem, 10_000, first=True)
    assert result.plan is not None and result.plan.actions == []
    assert [result.plan.tree[r].decomposition for r in result.plan.roots] == ["donothing"] * 2


@pytest.mark.parametrize("domain,number", [("Blocksworld-GTOHP", n) for n in range(1, 11)]
                         + [("Childsnack", n) for n in range(1, 11)])
def test_benchmark_instances_are_solved_and_validated(domain, number):
    problem = load_hddl(TOTAL / domain / "domain.hddl", TOTAL / domain / f"p{number:02d}.hddl")
    result = plan(problem, 60_000, first=True)
    assert result.plan is not None, result.explain()
    assert result.first
    assert validate(problem, result.plan) == []
    assert problem.goals and all(v is True for v in problem.goals.values())
    ipc = read_ipc(write_ipc(result.plan))
    assert [a for _, a in sorted(ipc.actions.items())] == [
        (a.name, a.args) for a in result.plan.actions]
    assert len(ipc.roots) == len(problem.tasks)


def test_cli_prints_the_plan_in_the_ipc_format(shary):
    status, out, err = shary("plan", "--hddl", TOTAL / "Childsnack" / "domain.hddl",
                             TOTAL / "Childsnack" / "p01.hddl", "--ipc")
    assert status == 0, err
    parsed = read_ipc(out)
    assert len(parsed.actions) == 50 and len(parsed.roots) == 10
    assert out.startswith("==>\n") and out.endswith("<==\n")


def test_cli_refuses_an_unsupported_construct_with_its_position(shary, write):
    domain = write("d.hddl", (FEATURES / "sortof-domain.hddl").read_text().replace(
        "(sortof ?b - A)", "(typeof ?b - A)"))
    status, out, err = shary("plan", "--hddl", domain, FEATURES / "sortof.hddl")
    assert status == 2
    (found,) = problems(err)
    assert found["file"] == str(domain)
    assert (found["line"], found["col"]) == ("14", "22")  # a tab is one column
    assert "'typeof' is not a supported task-network constraint" in found["message"]
