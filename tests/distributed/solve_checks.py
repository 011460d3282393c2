"""The distributed solves that test_distributed_solve.py compares across rank counts and with the
serial solver: small Hertz half disks and Hertz spheres, frictionless, Tresca and Coulomb, every
cell type.
`solve_case(name, comm)` returns what is compared: the gathered displacement (on rank 0), the cycle
count, the correction norms and energies of every cycle, and the final check's figures."""
import numpy as np

from contactmg.examples.distributed import hertz, sphere
from contactmg.model.friction import Coulomb, Frictionless, Tresca
from contactmg.solve.options import SolverOptions

# name: (example, levels, cell, friction, partition: None (METIS) or "scattered", whole_below: the
# coarse levels of at most so many nodes held whole by every rank: all of them (10**9), a boundary
# between whole and distributed levels, none (0), or the default rule (None)); the Coulomb cases have
# sliding nodes, so their cycles are Anderson-mixed
CASES = {
    "hertz-triangle-coulomb": (hertz, 4, "triangle", Coulomb(0.4), None, 100),
    "hertz-quad-tresca": (hertz, 3, "quad", Tresca(0.02), None, 10**9),
    "hertz-triangle-frictionless-scattered": (hertz, 3, "triangle", Frictionless(), "scattered", 0),
    "sphere-tetra-coulomb": (sphere, 2, "tetra", Coulomb(0.4), None, 1000),
    "sphere-hexahedron-tresca": (sphere, 2, "hexahedron", Tresca(0.002), None, None),
}
# compared across rank counts only, over their first cycles: level 3 has ghost nodes at the edge of a
# fine layer whose Galerkin rows reach coarse nodes the rank does not hold (left out: no owned coarse
# row needs them), which the smaller cases do not have
RANKS_ONLY = {"sphere-tetra-level3-coulomb": (sphere, 3, "tetra", Coulomb(0.4), None, 0)}
RANKS_ONLY_CYCLES = 3
OPTIONS = SolverOptions(cycle="F", tol=1e-11)


def solve_case(name, comm):
    example, levels, cell, friction, part, whole_below = CASES[name] if name in CASES else RANKS_ONLY[name]
    if part == "scattered":
        from contactmg.mesh.generators import hertz_half_disk
        part = np.arange(hertz_half_disk(cell).num_cells) % comm.size
    problem = example(levels, cell, friction, comm, part=part)
    options = OPTIONS if name in CASES else OPTIONS.replace(max_cycles=RANKS_ONLY_CYCLES)
    result = problem.solve(options) if whole_below is None else problem.solve(options, whole_below=whole_below)
    u = result.gathered_u()
    return {"u": u, "cycles": result.cycles, "converged": result.converged,
            "correction": np.array([h["correction_norm"] for h in result.history]),
            "energy": np.array([h["energy"] for h in result.history]),
            "contact_nodes": problem.num_contact, "slip_nodes": result.slip_nodes, "rebuilds": result.rebuilds,
            "final_check": np.array([result.final_check[k] for k in sorted(result.final_check)])
            if result.final_check is not None else np.zeros(0)}
