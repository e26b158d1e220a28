"""shary: a SHARY-style supervision engine for robots that work with people.

The public entry points for communication schemes are re-exported here:
load a scheme (:func:`load_scheme`), compile it once (:func:`compile_scheme`)
and start as many instances of it as there are tasks (:meth:`CompiledScheme.start`).
"""

from shary.acts import ActRegistry, builtin_acts
from shary.clock import SimulatedClock
from shary.compiler import CompiledScheme, compile_scheme
from shary.conditions import ConditionRegistry
from shary.instance import SchemeInstance
from shary.io.schemes import load_scheme
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
