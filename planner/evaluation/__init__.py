"""Judging plans: their score, the weights of the criteria, and an independent check.

- :mod:`~planner.evaluation.evaluate` -- streams, causal links, times, criteria, social
  rules, score (:class:`Evaluator`);
- :mod:`~planner.evaluation.ahp` -- the Analytic Hierarchy Process that weighs the
  criteria;
- :mod:`~planner.evaluation.validate` -- replaying a plan and checking everything again
  (:func:`validate`).
"""
