"""Is the Coulomb problem still monotone where it slides?  Per adaptive level and coefficient: the
chain of sliding contact nodes at the contact edges of Algorithm 2's converged Hertz solution and
the smallest real part of the eigenvalues of the Coulomb Jacobian's block on their tangential dofs,
next to the same block of the stiffness matrix (issue 11: why the cycle counts at F >= 5 grow on
level 11 and nowhere below).

    python benchmarks/slip_chain_jacobian.py [--levels 7 9 10 11] [--frictions 2 5 8 40]
        [--json benchmarks/results/slip_chain_jacobian.json]

On a fixed contact state a sliding node's tangential row is r_T - sign(z) F r_n = 0, so the
Jacobian's rows there are K_T - sign(z) F K_n (coulomb_newton_diagnosis.hertz_system's frames).
Where that block has an eigenvalue with a negative real part the discrete problem is not monotone on
the slip zone: no nodal Gauss-Seidel sweep on it contracts, and the energy argument behind
Algorithm 2's global convergence no longer describes the coupled problem. The hierarchy is that of
`contactmg table1` (benchmarks/cycle_growth.py's cache); F(3,3), tol 1e-11 from u = 0, one thread.
"""
import argparse
import os
import sys

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, os.path.dirname(__file__))


def slip_chain(p, F, u):
    """(sliding tangential dofs, min Re eig of the Jacobian's block, min eig of K's block)."""
    from coulomb_newton_diagnosis import coulomb_state, hertz_system

    S = hertz_system(p)
    K, n, t = S["K"], S["n"], S["t"]
    x = S["D"] * np.asarray(u).ravel()
    _, z, _, _, slip = coulomb_state(S, F, x)
    N = K.shape[0]
    E = sp.csr_matrix((-np.sign(z[slip]) * F, (t[slip], n[slip])), shape=(N, N))
    J = (K + E @ K).tocsr()
    sl = t[slip]
    if len(sl) == 0:
        return sl, float("nan"), float("nan")
    ej = np.linalg.eigvals(J[sl][:, sl].toarray())
    ek = np.linalg.eigvalsh(K[sl][:, sl].toarray())
    return sl, float(ej.real.min()), float(ek.min())


def main():
    from bench_json import write_json
    from cycle_growth import adaptive_hierarchy
    from contactmg.hertz import hertz_problem_on

    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", type=int, nargs="+", default=[7, 9, 10, 11])
    ap.add_argument("--frictions", type=float, nargs="+", default=[2.0, 5.0, 8.0, 40.0])
    ap.add_argument("--json")
    a = ap.parse_args()
    H = adaptive_hierarchy(11)
    rows = []
    print("| level | dofs | F | cycles | sliding nodes | min Re eig, Jacobian's chain block | min eig, K's chain block |")
    print("|---|---|---|---|---|---|---|")
    for L in a.levels:
        for F in a.frictions:
            p = hertz_problem_on(H.truncated(L), F)
            r = p.solve("nmg", tol=1e-11, max_cycles=200, threads=1)
            row = {"level": L, "dofs": int(p.mesh.points.size), "F": F, "cycles": r.cycles, "converged": bool(r.converged)}
            if r.converged:
                sl, row["min_re_jacobian"], row["min_stiffness"] = slip_chain(p, F, r.displacement)
                row["sliding"] = int(len(sl))
                cells = f"{len(sl)} | {row['min_re_jacobian']:.3g} | {row['min_stiffness']:.3g}"
            else:
                cells = "- | - | -"
            rows.append(row)
            print(f"| {L} | {row['dofs']:,} | {F:g} | {r.cycles}{'' if r.converged else '!'} | {cells} |", flush=True)
    write_json(a.json, {"runs": rows})


if __name__ == "__main__":
    main()
