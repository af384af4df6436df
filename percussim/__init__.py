"""percussim: simulation of percussive impact devices (a striker, a variable-section tool, a
contact and a medium), after the discrete–continuous model of the percussion system.

    import percussim

    result = percussim.simulate(percussim.load_preset("fig3"))
    print(result.summary["peak_contact_force"])

The names below are the public API; each is imported when first used, so `import percussim`
imports neither NumPy's solver stack nor Numba (the kernel is loaded when a run needs it).
Below it: `percussim.solver` (the numerics), `percussim.worker` and `percussim.service`.
"""

from importlib import import_module
from importlib.metadata import version

__version__ = version("percussim")

# name → the module that defines it
_PUBLIC = {
    "simulate": "percussim.solver.simulate",
    "Case": "percussim.solver.case",
    "load_case": "percussim.solver.case",
    "load_preset": "percussim.solver.presets",
    "preset_names": "percussim.solver.presets",
    "Result": "percussim.solver.result",
    "read_result": "percussim.solver.io",
    "write_result": "percussim.solver.io",
    "run_sweep": "percussim.solver.simulate",
    "calibrate": "percussim.solver.calibrate",
    "optimize": "percussim.solver.optimize",
    "bearing_graph": "percussim.solver.pile_studies",
    "drivability": "percussim.solver.pile_studies",
    "read_record": "percussim.solver.record",
    "signal_match": "percussim.solver.signal_match",
    "read_pile_record": "percussim.solver.signal_match",
    "Limits": "percussim.solver.limits",
    "CaseError": "percussim.solver.case",
    "FieldError": "percussim.solver.case",
    "NumericalFailure": "percussim.solver.errors",
    "Cancelled": "percussim.solver.errors",
    "Client": "percussim.client",
    "ServiceError": "percussim.client",
}
__all__ = ["__version__", *_PUBLIC]


def __getattr__(name: str):
    if name not in _PUBLIC:
        raise AttributeError(f"module 'percussim' has no attribute {name!r}")
    value = getattr(import_module(_PUBLIC[name]), name)
    globals()[name] = value  # looked up once
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
