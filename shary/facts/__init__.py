"""The fact database: what the robot believes, and what it estimates each person believes.

- :mod:`~shary.facts.database` -- :class:`FactDatabase`: perspectives, names and terms,
  SPARQL, fact changes as events;
- :mod:`~shary.facts.perspective` -- one perspective's facts, an index in front of its
  RDF graph;
- :mod:`~shary.facts.turtle` -- Turtle files read strictly, positioned and bounded.
"""
