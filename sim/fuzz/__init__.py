"""Behaviour campaigns (``shary fuzz``, docs/fuzz.md): :mod:`.behaviours` draws what the
people do, :mod:`.campaign` runs and judges, :mod:`.invariants` says what must hold,
:mod:`.report` prints it."""
