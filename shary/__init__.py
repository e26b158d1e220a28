"""shary: a SHARY-style supervision engine for robots that work with people.

The public entry points for communication schemes are re-exported here:
load a scheme (:func:`load_scheme`), compile it once (:func:`compile_scheme`)
and start as many instances of it as there are tasks (:meth:`CompiledScheme.start`).
"""

from shary.io.schemes import load_scheme
from shary.statechart.acts import ActRegistry, builtin_acts
from shary.statechart.clock import SimulatedClock
from shary.statechart.compiler import CompiledScheme, compile_scheme
from shary.statechart.conditions import ConditionRegistry
from shary.statechart.instance import SchemeInstance
from userfiles.errors import FileError, Problem

__all__ = [
    "ActRegistry",
    "CompiledScheme",
    "ConditionRegistry",
    "FileError",
    "Problem",
    "SchemeInstance",
    "SimulatedClock",
    "builtin_acts",
    "compile_scheme",
    "load_scheme",
]
__version__ = "0.1.0"
