"""A HATP-like human-aware HTN planner (standalone: it imports nothing from shary).

HATP (Alami et al., in SHARY, section 2.3) plans with the robot *and* the
humans in the plan, reads its plans as one stream of actions per agent with
causal links between the streams, and scores them with action costs plus
"social rules" so that the plan is one people accept.

    from planner import load_domain, load_problem, plan, validate

    domain = load_domain("living-room")
    problem = load_problem("planner/problems/clean-up.yaml", domain)
    result = plan(problem, budget_ms=200)
    for agent, actions in result.plan.streams.items(): ...
    assert validate(problem, result.plan) == []

HDDL (the IPC's HTN language, total-order subset) is translated into the same
model: ``problem = load_hddl("domain.hddl", "p01.hddl")``, then
``plan(problem, first=True)``; :mod:`planner.io.ipc` writes the plan in the IPC
format.
"""

from planner.evaluation.validate import validate
from planner.io.domainfiles import (
    builtin_domains,
    builtin_problems,
    find_domain,
    load_domain,
    load_problem,
)
from planner.io.translate import load_hddl
from planner.model.domain import Domain, Problem
from planner.model.plan import CausalLink, Plan, PlanAction, TreeNode
from planner.search.branchbound import Result
from planner.search.portfolio import plan

__all__ = [
    "CausalLink",
    "Domain",
    "Plan",
    "PlanAction",
    "Problem",
    "Result",
    "TreeNode",
    "builtin_domains",
    "builtin_problems",
    "find_domain",
    "load_domain",
    "load_hddl",
    "load_problem",
    "plan",
    "validate",
]
