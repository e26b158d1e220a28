"""The scheme engine: communication schemes as statecharts with SCXML's semantics.

- :mod:`~shary.statechart.model` -- the scheme model (:class:`Scheme`, :class:`State`,
  :class:`Transition`, executable content);
- :mod:`~shary.statechart.acts` -- communication acts and their types (R-ACT, H-AGREE …):
  :class:`ActRegistry`; :mod:`~shary.statechart.conditions` -- the registered conditions
  guards name (:class:`ConditionRegistry`);
- :mod:`~shary.statechart.semantics` -- SCXML's step algorithm, as pure functions of a
  snapshot;
- :mod:`~shary.statechart.compiler` -- a scheme compiled once onto a flat
  ``transitions`` machine shared by its instances (:func:`compile_scheme`);
- :mod:`~shary.statechart.instance` -- a running instance: queues, timers, listener
  (:class:`SchemeInstance`); :mod:`~shary.statechart.clock` -- time and timers without
  threads (:class:`SimulatedClock`);
- :mod:`~shary.statechart.conformance` and :mod:`~shary.statechart.w3c` -- the external
  statechart suites (SCION's traces, the W3C's IRP tests).
"""
