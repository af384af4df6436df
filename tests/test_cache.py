"""A new process finds the kernel in Numba's cache and does not compile it again."""

import json
import subprocess
import sys
from pathlib import Path

PROBE = """
import json
from percussim.solver import kernel
from percussim.solver.presets import load_preset
from percussim.solver.controller import simulate_rod
simulate_rod(load_preset("fig3"))
s = kernel.advance.stats
print(json.dumps({"hits": sum(s.cache_hits.values()), "misses": sum(s.cache_misses.values())}))
"""


def test_a_new_process_loads_the_compiled_kernel():
    root = Path(__file__).resolve().parents[1]
    runs = [json.loads(subprocess.run([sys.executable, "-c", PROBE], cwd=root, capture_output=True,
                                      text=True, check=True, timeout=300).stdout) for _ in range(2)]
    # The first run may have filled the cache; the second must only read it.
    assert runs[1] == {"hits": 1, "misses": 0}
