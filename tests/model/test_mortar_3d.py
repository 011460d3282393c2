"""3D dual mortar (surface segment intersection) and two elastic bodies in contact in 3D."""
import json
import subprocess
import sys

import numpy as np
import pytest

from contactmg.model.friction import Coulomb, Frictionless
from contactmg.mesh.generators_3d import box
from contactmg.mesh.hierarchy import MeshHierarchy
from contactmg.model.material import Material
from contactmg.model.mortar_3d import (clip_polygons, element_dual_coefficients, mortar_coupling_3d, polygon_area,
                                 shape)
from contactmg.model.problem import Dirichlet
from contactmg.results.result import SLIP, STICK
from contactmg import Body, ContactPair, Problem

MAT = Material(1000.0, 0.3)
BOTTOM, TOP = 5, 6  # box tags of z = 0 and z = lz


# -- polygon clipping --------------------------------------------------------------------------------
def _clip_area(a, b):
    a, b = np.asarray(a, float)[None], np.asarray(b, float)[None]
    P, n = clip_polygons(a, np.array([a.shape[1]]), b, np.array([b.shape[1]]))
    return float(polygon_area(P, n)[0]) if n[0] >= 3 else 0.0


SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]


@pytest.mark.parametrize("subject,clip,area", [
    ([(0.5, 0.5), (1.5, 0.5), (1.5, 1.5), (0.5, 1.5)], SQUARE, 0.25),                     # shifted square
    ([(0.5 + np.sqrt(0.5) * np.cos(t), 0.5 + np.sqrt(0.5) * np.sin(t)) for t in np.arange(4) * np.pi / 2],
     SQUARE, 2 * (np.sqrt(2) - 1)),                                                          # rotated 45 degrees: an octagon
    ([(0.25, 0.25), (1.25, 0.25), (0.25, 1.25)], [(0, 0), (1, 0), (0, 1)], 0.125),            # shifted triangles
    ([(0.2, 0.2), (0.6, 0.2), (0.2, 0.6)], SQUARE, 0.08),                                      # inside
    ([(2, 2), (3, 2), (3, 3), (2, 3)], SQUARE, 0.0),                                          # disjoint
    (SQUARE, SQUARE, 1.0),                                                                    # identical (matching meshes)
    ([(1, 0), (2, 0), (2, 1), (1, 1)], SQUARE, 0.0),                                          # sharing an edge only
])
def test_clipping_gives_the_known_overlap_areas(subject, clip, area):
    assert _clip_area(subject, clip) == pytest.approx(area, abs=1e-14)
    assert _clip_area(clip, subject) == pytest.approx(area, abs=1e-14)


def test_clipping_random_convex_polygons_against_sampling():
    """Random convex quads and triangles (vectorized, one call): the clipped area is symmetric and
    agrees with the fraction of a fine grid inside both."""
    rng = np.random.default_rng(4)
    n = 40

    def convex(k):
        t = 2 * np.pi * (np.arange(k) + rng.uniform(-0.3, 0.3, (n, k))) / k + rng.uniform(0, 2 * np.pi, (n, 1))
        r = rng.uniform(0.3, 1.0, (n, 1))
        return np.stack([r * np.cos(t), r * np.sin(t)], axis=2) + rng.uniform(-0.3, 0.3, (n, 1, 2))

    a, b = convex(4), convex(3)
    P, c = clip_polygons(a, np.full(n, 4), b, np.full(n, 3))
    Q, d = clip_polygons(b, np.full(n, 3), a, np.full(n, 4))
    ab, ba = np.where(c >= 3, polygon_area(P, c), 0.0), np.where(d >= 3, polygon_area(Q, d), 0.0)
    assert np.allclose(ab, ba, atol=1e-13)
    g = np.linspace(-1.6, 1.6, 241)
    X, Y = np.meshgrid(g, g)
    pts = np.c_[X.ravel(), Y.ravel()]

    def inside(poly):
        e = np.roll(poly, -1, axis=0) - poly
        return np.all(e[:, 0] * (pts[:, None, 1] - poly[:, 1]) - e[:, 1] * (pts[:, None, 0] - poly[:, 0]) >= 0, axis=1)

    cell = (g[1] - g[0]) ** 2
    for i in range(0, n, 4):
        sampled = np.count_nonzero(inside(a[i]) & inside(b[i])) * cell
        assert abs(sampled - ab[i]) <= 0.02 + 0.02 * ab[i], (i, sampled, ab[i])
    assert np.count_nonzero(ab > 0.05) >= n // 2  # the sample does overlap


# -- the dual basis and the mortar matrices --------------------------------------------------------
def test_dual_basis_of_a_triangle_is_4phi_minus_1_and_biorthogonal_on_quads():
    """On a triangle psi_i = 4 phi_i - 1 = 3 phi_i - sum_{j != i} phi_j (int psi_i phi_j = 4 A/12 -
    A/3 = 0 for j != i; 3 phi_i - 1, the 1D rule's form, is not biorthogonal on triangles); on a
    non-parallelogram quad the element-wise D_e M_e^{-1} basis is biorthogonal under a fine rule."""
    X = np.array([[[0.0, 0.0, 0.0], [2.0, 0.1, 0.0], [0.3, 1.5, 0.2]]])
    A, De = element_dual_coefficients(X)
    assert np.allclose(A[0], 4 * np.eye(3) - 1, rtol=0, atol=1e-11)
    area = 0.5 * np.linalg.norm(np.cross(X[0, 1] - X[0, 0], X[0, 2] - X[0, 0]))
    assert np.allclose(De, area / 3)
    # a parallelogram: the tensor product of the 1D duals 2 phi_a - phi_b
    P = np.array([[[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [2.5, 1.0, 0.3], [0.5, 1.0, 0.3]]])
    B = np.array([[2.0, -1.0], [-1.0, 2.0]])
    ij = [(0, 0), (1, 0), (1, 1), (0, 1)]  # VTK order
    tensor = np.array([[B[i, k] * B[j, l] for (k, l) in ij] for (i, j) in ij])
    assert np.allclose(element_dual_coefficients(P)[0][0], tensor, rtol=0, atol=1e-11)
    # a planar non-parallelogram quad: int psi_i phi_j = delta_ij int phi_i by a fine tensor rule
    Q = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.3, 0.9, 0.0], [-0.1, 1.2, 0.0]]])
    A, De = element_dual_coefficients(Q)
    x, w = np.polynomial.legendre.leggauss(8)
    x, w = 0.5 * (x + 1), 0.5 * w
    S, T = np.meshgrid(x, x, indexing="ij")
    xi = np.c_[S.ravel(), T.ravel()]
    W = np.outer(w, w).ravel()
    phi = shape(4, xi)
    from contactmg.model.mortar_3d import surface_jacobian

    J = surface_jacobian(Q, 4, xi)[0]
    psi = phi @ A[0].T
    G = np.einsum("m,mi,mj->ij", W * J, psi, phi)
    assert np.allclose(G, np.diag(De[0]), atol=1e-13)
    assert De[0].sum() == pytest.approx(0.5 * abs(np.cross(Q[0, 2] - Q[0, 0], Q[0, 3] - Q[0, 1])[2]), rel=1e-13)


def _surface(cell, nx, ny, z, face, jitter=0.0, seed=0):
    """The facets (outward) of the face z = const of a box mesh on [0,1]^2, and its points with
    the interior surface nodes moved in the plane by up to jitter * h."""
    m = box(nx, ny, 1, 1.0, 1.0, 1.0, cell=cell, origin=(0.0, 0.0, z - (1.0 if face == TOP else 0.0)))
    f = m.facets[m.facet_tags == face]
    x = m.points.copy()
    if jitter:
        nodes = np.unique(f)
        inner = nodes[(np.min(np.abs(x[nodes, :2] - 0.5), axis=1) >= 0) & np.all(np.abs(x[nodes, :2] - 0.5) < 0.5 - 1e-9, axis=1)]
        rng = np.random.default_rng(seed)
        x[inner, :2] += rng.uniform(-jitter, jitter, (len(inner), 2)) / max(nx, ny)
    return x, f


def _lumped_measure(x, f, nodes):
    """int phi_p over the facets, independently: a triangle gives a third of its area to each node;
    a parallelogram a quarter."""
    k = f.shape[1]
    if k == 3:
        area = 0.5 * np.linalg.norm(np.cross(x[f[:, 1]] - x[f[:, 0]], x[f[:, 2]] - x[f[:, 0]]), axis=1)
    else:
        area = 0.5 * np.linalg.norm(np.cross(x[f[:, 2]] - x[f[:, 0]], x[f[:, 3]] - x[f[:, 1]]), axis=1)
    out = np.zeros(len(x))
    np.add.at(out, f.ravel(), np.repeat(area / k, k))
    return out[nodes]


@pytest.mark.parametrize("scell,mcell,sjit,mjit", [("tetra", "tetra", 0.3, 0.3), ("hexahedron", "hexahedron", 0.0, 0.3),
                                                  ("tetra", "hexahedron", 0.3, 0.0), ("hexahedron", "tetra", 0.0, 0.3)])
def test_flat_mortar_rows_sum_to_D_and_reproduce_linear_fields(scell, mcell, sjit, mjit):
    """Nonmortar: the bottom z = 0 of a body above (normal -z), mortar: the top z = -0.02 of a body
    below, meshed differently (5x4 against 3x7, interior surface nodes jittered): D = int phi_p,
    sum_q M_pq = D_p (partition of unity), D^{-1} M reproduces every linear field, normals -z and
    gaps 0.02."""
    xs, fs = _surface(scell, 5, 4, 0.0, BOTTOM, sjit, seed=1)
    xm, fm = _surface(mcell, 3, 7, -0.02, TOP, mjit, seed=2)
    c = mortar_coupling_3d(xs, fs, xm, fm, search=0.1)
    assert len(c.uncovered) == 0 and len(c.excluded) == 0
    assert np.allclose(c.D, _lumped_measure(xs, fs, c.nonmortar_nodes), rtol=1e-13, atol=0)
    assert np.allclose(np.asarray(c.M.sum(axis=1)).ravel(), c.D, rtol=1e-12, atol=0)
    assert np.allclose(c.normals, [0.0, 0.0, -1.0], atol=1e-14)
    assert np.allclose(c.gaps(xs, xm), 0.02, rtol=0, atol=1e-13)
    rng = np.random.default_rng(3)
    L, b = rng.standard_normal((3, 3)), rng.standard_normal(3)
    field = lambda x: x @ L + b  # noqa: E731
    expected = field(xs[c.nonmortar_nodes] + [0.0, 0.0, -0.02])
    assert np.allclose(c.Mhat @ field(xm), expected, rtol=0, atol=1e-12)


def test_matching_surfaces_give_node_to_node_coupling():
    """Coincident meshes on both sides: D^{-1} M is the identity pairing of coincident nodes."""
    for cell in ("tetra", "hexahedron"):
        xs, fs = _surface(cell, 3, 4, 0.0, BOTTOM)
        xm, fm = _surface(cell, 3, 4, 0.0, TOP)
        c = mortar_coupling_3d(xs, fs, xm, fm, search=0.1)
        Mh = c.Mhat.tocsr()
        Mh.data[np.abs(Mh.data) < 1e-12] = 0.0
        Mh.eliminate_zeros()
        assert np.all(np.diff(Mh.indptr) == 1) and np.allclose(Mh.data, 1.0, atol=1e-12)
        assert np.allclose(xm[Mh.indices], xs[c.nonmortar_nodes], atol=1e-14)


def test_partly_covered_nonmortar_nodes_keep_a_consistent_condition():
    """A mortar surface over part of the nonmortar one (its edge cuts through nonmortar elements):
    the nodes of the cut elements keep their condition with the dual basis of the covered part, D =
    the covered measure of their support, rows of M summing to D (a rigid translation of both bodies
    moves no weighted gap) and D^{-1} M reproducing linear fields; nodes not reached are reported."""
    xs, fs = _surface("hexahedron", 4, 4, 0.0, BOTTOM)
    xm, fm = _surface("tetra", 3, 3, -0.01, TOP)
    xm[:, 0] *= 0.4  # the mortar side spans x in [0, 0.4]: its edge cuts the nonmortar column 0.25..0.5
    c = mortar_coupling_3d(xs, fs, xm, fm, search=0.1)
    x = xs[c.nonmortar_nodes]
    assert np.all(x[:, 0] <= 0.5 + 1e-12) and np.any(x[:, 0] > 0.25 + 1e-12)
    assert len(c.uncovered) and np.all(xs[c.uncovered, 0] >= 0.5 - 1e-12)
    rows = np.asarray(c.M.sum(axis=1)).ravel()
    assert np.allclose(rows, c.D, rtol=1e-10)
    # D: the measure of the part of each support with x <= 0.4 (a grid of 0.25 x 0.25 quads)
    h = 0.25
    expected = np.zeros(len(x))
    for i, (px, py) in enumerate(x[:, :2]):
        for cx in (px - h, px):
            for cy in (py - h, py):
                if not (0 <= cx < 1 - 1e-12 and 0 <= cy < 1 - 1e-12):
                    continue
                # int over the quad [cx, cx+h] x [cy, cy+h] cut at x = 0.4 of the bilinear hat of (px, py)
                lo, hi = cx, min(cx + h, 0.4)
                if hi <= lo:
                    continue
                fx = lambda t: 1 - abs(t - px) / h  # noqa: E731
                gx = np.polynomial.legendre.leggauss(4)
                t = lo + (gx[0] + 1) / 2 * (hi - lo)
                expected[i] += np.sum(gx[1] * fx(t)) * (hi - lo) / 2 * h / 2
    assert np.allclose(c.D, expected, rtol=1e-9)
    field = lambda y: y @ np.array([[1.0, 0.5, 0.2], [0.3, -1.0, 0.4], [0.1, 0.2, 1.0]]) + [0.1, 0.2, 0.3]  # noqa: E731
    assert np.allclose(c.Mhat @ field(xm), field(x + [0.0, 0.0, -0.01]), atol=1e-10)


def test_bad_surfaces_are_clear_errors():
    xs, fs = _surface("tetra", 2, 2, 0.0, BOTTOM)
    with pytest.raises(ValueError, match="search distance"):
        mortar_coupling_3d(xs, fs, xs, fs, search=0.0)
    with pytest.raises(ValueError, match="triangles"):
        mortar_coupling_3d(xs, fs[:, :2], xs, fs, search=0.1)
    with pytest.raises(ValueError, match="nonmortar and mortar"):
        mortar_coupling_3d(xs, fs[:0], xs, fs, search=0.1)
    with pytest.raises(ValueError, match=r"\(n, 3\)"):
        mortar_coupling_3d(xs[:, :2], fs, xs, fs, search=0.1)


# -- two bodies in 3D ----------------------------------------------------------------------------------
def _stacked_boxes(cell, upper=(3, 3), lower=(4, 5), levels=2):
    up = MeshHierarchy.build(box(upper[0], upper[1], 2, cell=cell, origin=(0.0, 0.0, 0.0)), levels)
    lo = MeshHierarchy.build(box(lower[0], lower[1], 2, cell=cell, origin=(0.0, 0.0, -1.0)), levels)
    return up, lo


@pytest.mark.parametrize("cell", ["hexahedron", "tetra"])
def test_patch_test_uniform_pressure_across_a_non_matching_3d_interface(cell):
    """Uniaxial compression of two stacked boxes meshed differently (3x3 against 4x5 cells across):
    the linear field (uniform sigma_zz, no lateral stress) is discrete and the dual mortar transmits
    it exactly: the displacement is exact and every nonmortar node carries the pressure -sigma_zz."""
    eps_zz = -0.01
    eps_lat = -MAT.nu * eps_zz

    def exact(x):
        return np.c_[eps_lat * x[:, 0], eps_lat * x[:, 1], eps_zz * (x[:, 2] + 1.0)]

    up, lo = _stacked_boxes(cell)
    bodies = [Body(up, MAT, [Dirichlet([TOP], exact)]), Body(lo, MAT, [Dirichlet([BOTTOM], exact)])]
    p = Problem(bodies, pairs=ContactPair(0, 1, [BOTTOM], [TOP], search=0.1), friction=Frictionless())
    assert len(up.finest.boundary_nodes([BOTTOM])) != len(lo.finest.boundary_nodes([TOP]))  # non-matching
    r = p.solve()
    assert r.converged, r.status
    assert np.allclose(r.displacement, exact(p.mesh.points), rtol=0, atol=1e-10)
    assert np.all(r.contact_state > 0)
    assert np.allclose(np.abs(r.normal_stress), MAT.E * abs(eps_zz), rtol=1e-8)
    assert np.allclose(r.tangential_stress, 0.0, atol=1e-8 * MAT.E * abs(eps_zz))


def _mirror_box(mesh):
    from contactmg.mesh.mesh import Mesh

    pts = mesh.points * [1.0, 1.0, -1.0]
    cells = mesh.cells[:, [4, 5, 6, 7, 0, 1, 2, 3]] if mesh.cell_type == "hexahedron" else mesh.cells[:, [0, 2, 1, 3]]
    zmin, zmax = pts[:, 2].min(), pts[:, 2].max()

    def tagger(mid):
        t = np.zeros(len(mid), np.int64)
        t[np.abs(mid[:, 2] - zmin) < 1e-12] = BOTTOM
        t[np.abs(mid[:, 2] - zmax) < 1e-12] = TOP
        return t

    return Mesh.from_cells(pts, np.ascontiguousarray(cells), mesh.cell_type, tagger)


def test_matching_meshes_give_the_3d_node_to_node_solution():
    """Mirror-image boxes pressed by mirror-image non-uniform data: the interface stays on z = 0 and
    the upper body's solution is the one-body solution against the rigid plane z = 0 (an
    independent solve with an obstacle), with a partial contact zone. (Hexahedra: the red refinement
    of a mirrored tetrahedral mesh picks other interior diagonals, so its refinement is not the mirror
    image of the refined mesh and the problem is no longer symmetric.)"""
    from contactmg.model.obstacle import PlaneObstacle

    mesh = box(3, 3, 2, cell="hexahedron")
    up, lo = MeshHierarchy.build(mesh, 2), MeshHierarchy.build(_mirror_box(mesh), 2)

    def push(x):
        return np.c_[0.002 * x[:, 0], -0.001 * x[:, 1], -0.01 + 0.03 * x[:, 0] + 0.01 * x[:, 1]]

    def push_mirror(x):
        return push(x * [1.0, 1.0, -1.0]) * [1.0, 1.0, -1.0]

    bodies = [Body(up, MAT, [Dirichlet([TOP], push)]), Body(lo, MAT, [Dirichlet([BOTTOM], push_mirror)])]
    p = Problem(bodies, pairs=ContactPair(0, 1, [BOTTOM], [TOP], search=0.1), friction=Frictionless())
    r = p.solve(tol=1e-13)
    assert r.converged
    one = Problem(Body(up, MAT, [Dirichlet([TOP], push)], contact_tags=[BOTTOM]),
                  obstacle=PlaneObstacle((0.0, 0.0, 0.0), (0.0, 0.0, -1.0))).solve(tol=1e-13)
    n0 = p.parts[0].mesh.num_points
    scale = np.abs(one.displacement).max()
    assert 0 < one.counts()["contact_nodes"] < len(one.contact_nodes)
    assert np.abs(r.displacement[:n0] - one.displacement).max() <= 1e-8 * scale


def test_sliding_boxes_3d_every_node_at_the_coulomb_bound():
    """The upper box pushed down and sheared along (1, 1, 0)/sqrt(2) far enough to slide on the lower
    one (non-matching): every nonmortar node slides with |t_p| = F |n_p| and the friction force is
    opposite the relative slip."""
    F = 0.3
    up, lo = _stacked_boxes("hexahedron")
    bodies = [Body(up, MAT, [Dirichlet([TOP], (0.03, 0.03, -0.01))]), Body(lo, MAT, [Dirichlet([BOTTOM], (0.0, 0.0, 0.0))])]
    p = Problem(bodies, pairs=ContactPair(0, 1, [BOTTOM], [TOP], search=0.1), friction=Coulomb(F))
    r = p.solve()
    assert r.converged, r.status
    assert np.all(r.contact_state == SLIP)
    fn, ft = r.contact_force[:, 0], r.contact_force[:, 1:]
    assert np.allclose(np.linalg.norm(ft, axis=1), F * np.abs(fn), rtol=1e-8)
    from contactmg.examples.spheres import relative_displacement

    w = relative_displacement(p, r)[p.contact.nodes]
    wt = np.einsum("cij,ci->cj", r.contact_frames, w)[:, 1:]
    cosine = np.einsum("ij,ij->i", ft, wt) / (np.linalg.norm(ft, axis=1) * np.linalg.norm(wt, axis=1))
    assert np.allclose(cosine, -1.0, atol=1e-8)  # the friction force on the upper body opposes its slip
    # the nodal slip directions differ a little (lateral Poisson strains): the sum of the shear
    # magnitudes is F times the normal force, the resultant slightly less, along -(1, 1)
    R = r.reaction
    assert np.linalg.norm(ft, axis=1).sum() == pytest.approx(F * abs(R[2]), rel=1e-8)
    assert F * abs(R[2]) * (1 - 1e-2) <= np.hypot(R[0], R[1]) <= F * abs(R[2]) * (1 + 1e-12)
    assert R[0] < 0 and R[1] < 0 and R[0] == pytest.approx(R[1], rel=1e-2)


# -- the two hemispheres -------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def spheres_l2():
    from contactmg.examples.spheres import spheres_problem

    p = spheres_problem(levels=2, friction=0.4, E2=4000.0, nu2=0.2)
    return p, p.solve(threads=1)


def test_spheres_mortar_rows_sum_to_D_on_the_curved_non_matching_domes(spheres_l2):
    """Curved hexahedral domes meshed differently: the rows of M sum to D (the covered part of each
    nonmortar support) up to the quadrature of warped quads, D^{-1} M reproduces x (the nonmortar
    node's position plus the gap along the normal, at the centre of the contact zone), and the dual
    gap at the centre is the distance between the domes."""
    p, _ = spheres_l2
    c = p.coupling
    rows = np.asarray(c.M.sum(axis=1)).ravel()
    assert len(c.uncovered) == 0 and len(c.excluded) == 0 and len(c.D) >= 25  # the zone (r < 0.15) is inside where the normals reach the lower dome
    assert np.allclose(rows, c.D, rtol=1e-6, atol=0)  # measured 1e-11
    # the facets are quads on a sphere: D is close to a quarter of the areas around the node
    sm = p.parts[0].mesh
    x = sm.points[c.nonmortar_nodes]
    r = np.hypot(x[:, 0], x[:, 1])
    g = c.gaps(sm.points, p.parts[1].mesh.points)
    lower_z = -0.4 + np.sqrt(0.16 - r ** 2)
    centre = r < 0.05
    assert np.allclose(g[centre], (x[centre, 2] - lower_z[centre]) * np.abs(c.normals[centre, 2]), rtol=0.05, atol=2e-4)
    assert np.all(c.normals[:, 2] < -0.8)


def test_spheres_frictional_two_body_solve_is_verified(spheres_l2):
    """Unequal materials (E2 = 2 E1) and Coulomb F = 0.4: Algorithm 2 converges, the independent
    check of the discrete conditions on the relative displacement passes, stick and slip are both
    present, the two flat faces' support reactions balance, and the load is that of the contact."""
    from contactmg.results.checks import VIOLATION_TOL
    from contactmg.examples.spheres import check_conditions

    p, r = spheres_l2
    assert r.converged, r.status
    assert check_conditions(p, r)["max"] <= VIOLATION_TOL
    states = r.contact_state
    assert np.any(states == STICK) and np.any(states == SLIP)
    # the canonical residual A u - f: zero off the supports and the interface; the supports balance
    u = r.displacement
    res = (p.A_canonical @ u.ravel() - p.load_canonical.ravel()).reshape(-1, 3)
    fixed = p.fixed.any(axis=1)
    upper = p.body_id == 0
    top, bottom = res[fixed & upper].sum(axis=0), res[fixed & ~upper].sum(axis=0)
    assert np.allclose(top + bottom, 0.0, atol=1e-8 * abs(top[2]))
    assert top[2] == pytest.approx(-r.reaction[2], rel=1e-8)  # the support pushes down what the contact pushes up


def test_spheres_equal_materials_match_the_one_body_sphere():
    """Equal materials, frictionless: by symmetry each hemisphere is the one-body sphere on a
    frictionless rigid plane with the same D. At level 2 (non-matching coarse blocks 0.5 R and
    0.4 R wide) the load agrees within 5 % (measured 2.8 %: the lower dome is a second
    discretization where the one-body plane is exact) and the contact radius within one element."""
    from contactmg.examples.sphere import element_width, radius_of, sphere_problem
    from contactmg.examples.spheres import spheres_problem

    two = spheres_problem(levels=2, friction=0.0).solve()
    one = sphere_problem("hexahedron", 2, 0.0).solve()
    assert two.converged and one.converged
    assert two.reaction[2] == pytest.approx(one.reaction[2], rel=0.05)
    assert abs(radius_of(two, (1, 2)) - radius_of(one, (1, 2))) <= 1.01 * element_width(2)


def _cli(*args, timeout=600):
    return subprocess.run([sys.executable, "-m", "contactmg", *args], capture_output=True, text=True, timeout=timeout)


def test_cli_spheres_json_vtu(tmp_path):
    import meshio

    from contactmg.examples.spheres import two_body_p0, two_body_radius

    vtu = tmp_path / "s.vtu"
    run = _cli("spheres", "--levels", "1", "--friction", "0.4", "--E2", "3000", "--threads", "1", "--json", "-", "-q",
               "--vtu", str(vtu))
    assert run.returncode == 0, run.stderr
    rep = json.loads(run.stdout)
    for key in ("dim", "cell", "levels", "dofs", "converged", "cycles", "contact_nodes", "stick_nodes", "slip_nodes",
                "reaction", "contact_radius", "stick_radius", "hertz_radius", "hertz_p0", "central_pressure",
                "fitted_radius", "fitted_peak_pressure"):
        assert key in rep, key
    assert rep["problem"] == "spheres" and rep["converged"] and rep["dim"] == 3 and rep["contact_nodes"] > 0
    P = rep["reaction"][2]
    m1, m2 = Material(2000.0, 0.28), Material(3000.0, 0.28)
    assert rep["hertz_radius"] == pytest.approx(two_body_radius(P, 0.4, 0.4, m1, m2), rel=1e-12)
    assert rep["hertz_p0"] == pytest.approx(3 * P / (2 * np.pi * rep["hertz_radius"] ** 2), rel=1e-12)
    assert rep["check_violation"] <= 1e-6 and rep["threads"] == 1
    m = meshio.read(vtu)
    assert set(np.unique(m.point_data["body_id"])) == {0, 1}
    assert len(m.points) == rep["nodes"]


@pytest.mark.parametrize("args,word", [(["--nu2", "0.5"], "--nu2"), (["--E2=-1"], "--E2"), (["--levels", "0"], "--levels"),
                                       (["--displacement", "0.5"], "displacement")])
def test_cli_spheres_bad_input(args, word, capsys):
    from contactmg.cli.main import main

    try:
        code = main(["spheres", *args])
    except SystemExit as e:  # argparse's own errors
        code = e.code
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err
    assert word in err.strip().splitlines()[-1]


@pytest.mark.slow
def test_spheres_level3_against_the_two_body_hertz_formulas():
    """Level 3 (134,046 dofs), E2 = 2 E1, nu2 = 0.2, frictionless: the central pressure within 5 % of
    the two-body p0 (measured +3.0 %) and the contact radius within one element width of a
    (measured +3.8 %, 0.24 element widths); the solve is verified by the independent check."""
    from contactmg.results.checks import VIOLATION_TOL
    from contactmg.examples.sphere import central_pressure, element_width, radius_of
    from contactmg.examples.spheres import RADIUS, check_conditions, spheres_problem, two_body_p0, two_body_radius

    p = spheres_problem(levels=3, friction=0.0, E2=4000.0, nu2=0.2)
    r = p.solve(threads=1)
    assert r.converged and check_conditions(p, r)["max"] <= VIOLATION_TOL
    P = r.reaction[2]
    m1, m2 = p.bodies[0].material, p.bodies[1].material
    assert central_pressure(r) == pytest.approx(two_body_p0(P, RADIUS, RADIUS, m1, m2), rel=0.05)
    assert abs(radius_of(r, (STICK, SLIP)) - two_body_radius(P, RADIUS, RADIUS, m1, m2)) <= element_width(3)


def test_bodies_of_two_dimensions_are_a_clear_error():
    from contactmg.mesh.generators import rectangle

    up, _ = _stacked_boxes("hexahedron", levels=2)
    flat = MeshHierarchy.build(rectangle(3, 3, 1, 1), 2)
    with pytest.raises(ValueError, match="one dimension"):
        Problem([Body(up, MAT, [Dirichlet([TOP], (0.0, 0.0, -0.01))]), Body(flat, MAT, [Dirichlet([1], (0.0, 0.0))])],
                pairs=ContactPair(0, 1, [BOTTOM], [3], search=0.1))


def test_spheres_tnnmg_reaches_the_nmg_solution(spheres_l2):
    """TNNMG (the fine nonlinear sweeps, one linear truncated cycle, line search) on the transformed
    two-body problem converges to Algorithm 2's solution (and is what keeps the 3D two-body cycle
    counts flat with friction: 12-14 cycles on levels 2-4 against 13-69 for Algorithm 2)."""
    p, r = spheres_l2
    t = p.solve("tnnmg", threads=1)
    assert t.converged, t.status
    scale = np.abs(r.displacement).max()
    assert np.abs(t.displacement - r.displacement).max() <= 1e-8 * scale
    assert np.array_equal(t.contact_state, r.contact_state)
