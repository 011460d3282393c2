"""The distributed solves that test_distributed_solve.py compares across rank counts and with the
serial solver: small Hertz half disks and Hertz spheres, frictionless and Tresca, every cell type.
`solve_case(name, comm)` returns what is compared: the gathered displacement (on rank 0), the cycle
count, the correction norms and energies of every cycle."""
import numpy as np

from contactmg.examples.distributed import hertz, sphere
from contactmg.solve.options import SolverOptions

# name: (example, levels, cell, Tresca bound (0: frictionless), partition: None (METIS) or "scattered")
CASES = {
    "hertz-triangle-frictionless": (hertz, 4, "triangle", 0.0, None),
    "hertz-quad-tresca": (hertz, 3, "quad", 0.02, None),
    "hertz-triangle-tresca-scattered": (hertz, 3, "triangle", 0.02, "scattered"),
    "sphere-tetra-frictionless": (sphere, 2, "tetra", 0.0, None),
    "sphere-hexahedron-tresca": (sphere, 2, "hexahedron", 0.002, None),
}
OPTIONS = SolverOptions(cycle="F", tol=1e-11)


def solve_case(name, comm):
    example, levels, cell, bound, part = CASES[name]
    if part == "scattered":
        from contactmg.mesh.generators import hertz_half_disk
        part = np.arange(hertz_half_disk(cell).num_cells) % comm.size
    problem = example(levels, cell, bound, comm, part=part)
    result = problem.solve(OPTIONS)
    u = result.gathered_u()
    return {"u": u, "cycles": result.cycles, "converged": result.converged,
            "correction": np.array([h["correction_norm"] for h in result.history]),
            "energy": np.array([h["energy"] for h in result.history]),
            "contact_nodes": problem.num_contact}
