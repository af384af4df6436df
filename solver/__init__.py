"""percussim solver: the discrete–continuous percussion model, pure numerics."""

from .case import Case, CaseError, FieldError, load_case, parse_case
from .controller import Cancelled, NumericalFailure, Result, simulate_rod
from .grid import resolve_numerics, tool_mass

__version__ = "0.1.0"
__all__ = [
    "Case", "CaseError", "FieldError", "load_case", "parse_case",
    "Cancelled", "NumericalFailure", "Result", "simulate_rod",
    "resolve_numerics", "tool_mass", "__version__",
]
