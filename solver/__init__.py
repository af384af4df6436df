"""percussim.solver: the discrete–continuous percussion model, pure numerics.

case → grid → kernel → controller → summary → io, with `adaptive` choosing grids to a tolerance
and `simulate` the one entry point. Importing this package imports nothing else: validating a
case (`case`) needs no Numba, and the kernel is compiled or loaded only when a run needs it.
The public API is the `percussim` package above this one.
"""

# The folder is installed as percussim.solver; loaded under its folder's name (the repository on
# sys.path) its modules would exist twice, with two sets of classes that compare unequal.
if __name__ != "percussim.solver":
    raise ImportError(f"import percussim.solver, not {__name__} (the folder solver/ is that package)")
