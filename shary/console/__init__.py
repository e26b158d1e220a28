"""The operator console: a live or replayed run in the browser, and MCAP exports.

The console never reaches into the engine's objects.  It reads the run as a
stream of context-log events (:mod:`shary.console.view` folds them into what
the page shows) and it acts on the run only through the ports a run offers
(:class:`shary.console.ports.RunPort`): an act sent for an agent, a task
cancelled, pause and step.  A live run (:mod:`shary.console.live`) and a
recorded one (:mod:`shary.console.replay`) are two implementations of that
port, and the page cannot tell them apart except by the controls offered.
"""
