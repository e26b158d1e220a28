"""The planning model: what a domain and a problem are, and what a plan is.

- :mod:`~planner.model.domain` -- entity types, actions, methods, social rules,
  problems (compiled): :class:`Domain`, :class:`Problem`, :class:`Action`,
  :class:`Method`;
- :mod:`~planner.model.expr` -- the expression language of preconditions, effects and
  costs, parsed and type-checked once; :mod:`~planner.model.closures` -- the closures it
  compiles to;
- :mod:`~planner.model.formulas` -- HDDL formulas compiled into closures, with PDDL's
  semantics; :mod:`~planner.model.statics` -- the values a method's variables may take
  in one problem (types and static facts);
- :mod:`~planner.model.state` -- search states (copy-on-write values, an index of the
  facts);
- :mod:`~planner.model.plan` -- plans: actions of several agents, per-agent streams,
  causal links, the decomposition tree (:class:`Plan`, :class:`PlanAction`,
  :class:`CausalLink`, :class:`TreeNode`).
"""
