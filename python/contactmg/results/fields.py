"""Strain and stress of a displacement field: per cell at the cell centroid, recovered at the
nodes, and the von Mises stress. Linear isotropic elasticity as the core assembles it
(cpp/fem/assembly.hpp): 3D, or plane strain in 2D (eps_zz = 0, sigma_zz = nu (sigma_xx +
sigma_yy)). Tensors are returned as full 3 x 3 matrices in both dimensions, in the model's units
(strain dimensionless, stress in the units of E)."""
from __future__ import annotations

from typing import Tuple

import numpy as np

from ..mesh.mesh import Mesh
from ..model.material import cell_moduli

# Gradients of the first-order shape functions at the centroid of the reference cell (rows: nodes
# in the mesh's order, as in cpp/fem/element.hpp).
_H = 0.5
_REFERENCE_GRADIENTS = {
    "triangle": np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]]),
    "quad": np.array([[-_H, -_H], [_H, -_H], [_H, _H], [-_H, _H]]),
    "tetra": np.array([[-1.0, -1.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
    # VTK order: bottom face counterclockwise, then the top face; d N_i / d xi_j at (1/2, 1/2, 1/2)
    "hexahedron": 0.25 * np.array([[2 * c - 1 for c in corner] for corner in
                                   [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0),
                                    (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]], dtype=float),
}


def centroid_gradients(mesh: Mesh) -> np.ndarray:
    """Physical gradients (ncells, k, d) of the k shape functions of every cell at the centroid of
    its reference cell."""
    G = _REFERENCE_GRADIENTS[mesh.cell_type]
    X = mesh.points[mesh.cells]                      # (m, k, d)
    J = np.einsum("cki,kj->cij", X, G)               # J_ij = dx_i / dxi_j
    return np.einsum("kj,cji->cki", G, np.linalg.inv(J))


def cell_strain(mesh: Mesh, displacement: np.ndarray) -> np.ndarray:
    """The small strain (ncells, 3, 3) of the displacement (n, d) at every cell centroid (exact on
    simplices, whose strain is constant; 2D: plane strain, the zz, xz, yz components zero)."""
    u = np.asarray(displacement, dtype=float)
    if u.shape != (mesh.num_points, mesh.dim):
        raise ValueError(f"the displacement must have shape {(mesh.num_points, mesh.dim)}, got {u.shape}")
    d = mesh.dim
    H = np.einsum("cki,ckj->cij", u[mesh.cells], centroid_gradients(mesh))  # H_ij = d u_i / d x_j
    eps = np.zeros((mesh.num_cells, 3, 3))
    eps[:, :d, :d] = 0.5 * (H + H.transpose(0, 2, 1))
    return eps


def hooke(strain: np.ndarray, E: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """The stress (m, 3, 3) of the strains (m, 3, 3) with Young's modulus E (m,) and Poisson ratio
    nu (m,): sigma = lambda tr(eps) I + 2 mu eps; in 2D (plane strain, eps_zz = 0) that makes
    sigma_zz = lambda tr(eps) = nu (sigma_xx + sigma_yy)."""
    E, nu = np.asarray(E, dtype=float), np.asarray(nu, dtype=float)
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    mu = E / (2 * (1 + nu))
    tr = np.trace(strain, axis1=1, axis2=2)
    return lam[:, None, None] * tr[:, None, None] * np.eye(3) + 2 * mu[:, None, None] * strain


def von_mises(stress: np.ndarray) -> np.ndarray:
    """The von Mises equivalent stress sqrt(3/2 s:s) (m,) of stresses (m, 3, 3), s the deviator."""
    s = stress - np.trace(stress, axis1=1, axis2=2)[:, None, None] / 3 * np.eye(3)
    return np.sqrt(1.5 * np.einsum("cij,cij->c", s, s))


def nodal_average(mesh: Mesh, cell_values: np.ndarray) -> np.ndarray:
    """The recovered nodal field (n, ...) of per-cell values (ncells, ...): at every node the
    average of the values of its cells weighted by their measures (area or volume)."""
    v = np.asarray(cell_values, dtype=float)
    if v.shape[0] != mesh.num_cells:
        raise ValueError(f"cell values need one entry per cell ({mesh.num_cells}), got {v.shape[0]}")
    w = mesh.cell_measures()
    k = mesh.cells.shape[1]
    flat = v.reshape(len(v), -1)
    total = np.zeros((mesh.num_points, flat.shape[1]))
    np.add.at(total, mesh.cells.ravel(), np.repeat(w[:, None] * flat, k, axis=0))
    weight = np.bincount(mesh.cells.ravel(), weights=np.repeat(w, k), minlength=mesh.num_points)
    # a node of no cell (none in a valid mesh) gets 0, not NaN
    out = total / np.where(weight > 0, weight, 1.0)[:, None]
    return out.reshape((mesh.num_points,) + v.shape[1:])


def problem_cell_moduli(problem) -> Tuple[np.ndarray, np.ndarray]:
    """E and nu (ncells,) per cell of the problem's mesh: the union of the bodies' meshes, body by
    body, each with its own material."""
    if getattr(problem, "multibody", False):
        parts = [cell_moduli(b.hierarchy.finest, b.material) for b in problem.bodies]
        return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])
    return cell_moduli(problem.mesh, problem.material)


def cell_stress(mesh: Mesh, displacement: np.ndarray, E: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """The stress (ncells, 3, 3) of the displacement at every cell centroid (Hooke's law of the
    centroid strain, E and nu per cell)."""
    return hooke(cell_strain(mesh, displacement), E, nu)
