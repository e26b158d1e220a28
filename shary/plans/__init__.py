"""Shared plans (JAHRVIS, Section VI-C): tasks with nine states, plan managers, theory of mind.

* :mod:`shary.plans.tasks`: abstract and primitive tasks read from the planner's
  plans (one format for usual, AgentX and conditional plans);
* :mod:`shary.plans.states`: each task's state in each agent's view, run by the
  ``shared-plan-task`` scheme (``schemes/shared-plan-task.yaml``);
* :mod:`shary.plans.execution`: a plan under way, its robot plan manager and its
  human plan manager;
* :mod:`shary.plans.beliefs`: what the robot estimates a human knows of the plan.
"""
