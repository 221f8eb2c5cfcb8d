"""bisph, the boundary-integral SPH solver, from Python.

Build a case from a TOML file or a dict, change keys as ``bisph run --set`` does, build and
run the simulation, and read its state as NumPy arrays::

    import bisph

    case = bisph.Case.from_toml("cases/hydrostatic-2d.toml")
    case.set("resolution.dx", 0.025)
    sim = case.build()
    sim.run(until=0.5, out="out/hs")     # bisph run's loop and files
    print(sim.time, sim.energy["total"], sim.positions.shape)

``bisph.read_run(folder)`` reads the outputs of a finished run (from Python or from the
command line). The API is described in docs/python.md.
"""

from ._bisph import (
    Case,
    CaseError,
    Progress,
    RunError,
    Simulation,
    __version__,
    pack,
    shepard,
)
from ._runs import Run, read_run

__all__ = [
    "Case",
    "CaseError",
    "Progress",
    "Run",
    "RunError",
    "Simulation",
    "__version__",
    "pack",
    "read_run",
    "shepard",
]
