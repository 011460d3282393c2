"""Verification scenes of two and three elastic bodies in contact, built as a user builds them:
gmsh meshes through the gmsh Python API and the public contactmg API. Each builder is a pure
function of its size parameters returning a `contactmg.Problem`; the exact values the scenes are
measured against are functions here too, with their formulas in the docstrings.

Scenes:

- roller_problem: a steel roller on an aluminium block, plane strain (two-body Hertz), full model
  or half model cut by the symmetry plane x = 0.
- rings_problem: two concentric rings, meshed separately (non-matching), internal pressure
  p0 + p2 cos 2 theta on the inner ring, quarter model (Lame and Michell solutions).
- shells_problem: two concentric hollow spheres, octant model, internal pressure (Lame).
- hemispheres_problem: two equal hemispheres pressed together, quarter model; and
  hemisphere_on_plane_problem: the upper one alone on a rigid plane at half the approach.
- stack_problem: three blocks of unequal sizes stacked on a rigid floor, no supports.

The functions at the end measure what the contact boundary of a problem leaves out
(nonmortar_nodes_left_out) and the per-body force balance of a multi-body result (body_balance).
"""
from __future__ import annotations

import math

import numpy as np

import _common
import contactmg as cm

# facet tags shared by the scenes
CONTACT, TOP, BOTTOM, SYM_X, SYM_Y, SYM_Z, INNER, OUTER, SIDE = 1, 2, 3, 4, 5, 6, 7, 8, 9


def gmsh_mesh(build, classify, size, dim):
    """_common.gmsh_mesh with all volumes (surfaces in 2D) region 1."""
    return _common.gmsh_mesh(build, classify, size, dim, one_region=True)


def projectors(*projs):
    """One projector applying each of `projs` in turn (each moves only the nodes of its own tags)."""
    def project(points, tags):
        for p in projs:
            points = p(points, tags)
        return points
    return project


def _sym(dim, axis):
    """The Dirichlet value of a symmetry plane normal to `axis`: that component 0, the others free."""
    v = [None] * dim
    v[axis] = 0.0
    return tuple(v)


# ---------------------------------------------------------------------------------------------
# 1. roller on block
# ---------------------------------------------------------------------------------------------
ROLLER_R, STEEL, ALU = 50.0, cm.Material(210000.0, 0.3), cm.Material(70000.0, 0.3)
ROLLER_P = math.pi * 6.21 * 3585 / 2          # line load (force per unit thickness)
ROLLER_H0 = 2.0                              # coarse element size at the contact


def roller_hertz():
    """The two-body Hertz line contact of the roller (R1 = 50) on a flat block (R2 = infinity):
    b = sqrt(4 P R / (pi E*)), p0 = 2 P / (pi b), 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2,
    P = pi 6.21 3585 / 2 (chosen so that b = 6.21, p0 = 3585 to the digits given)."""
    Es = 1.0 / ((1 - STEEL.nu ** 2) / STEEL.E + (1 - ALU.nu ** 2) / ALU.E)
    b = math.sqrt(4 * ROLLER_P * ROLLER_R / (math.pi * Es))
    return b, 2 * ROLLER_P / (math.pi * b)


def roller_problem(half: bool, levels: int, friction: float = 0.0, h0: float = ROLLER_H0):
    """A steel roller (radius 50, its upper half cut off flat at y = R; E 210000, nu 0.3) on an
    aluminium block (200 x 100, or 100 x 100 in the half model; E 70000, nu 0.3), plane strain,
    touching at the origin. The line load P is a uniform pressure P / (2R) on the roller's flat top;
    the block's bottom is clamped. Full model: the flat top is guided (u_x = 0: without it only the
    tilt of the discrete arc's normals would hold the frictionless roller sideways). Half model: the
    symmetry plane x = 0 cuts both bodies (u_x = 0 there). The roller is the nonmortar side. The coarse mesh has size h0 at the contact (growing
    away from it); `levels` uniform levels, so the contact size is h0 / 2^(levels-1)."""
    import gmsh
    R = ROLLER_R

    def size(x, y, z):
        return min(h0 + 0.15 * max(math.hypot(x, y) - 10, 0), 12.0)

    def roller():
        d = gmsh.model.occ.addDisk(0, R, 0, R, R)
        cut = gmsh.model.occ.addRectangle(-R - 1, R, 0, 2 * R + 2, R + 1)
        out = gmsh.model.occ.cut([(2, d)], [(2, cut)])
        if half:
            gmsh.model.occ.cut(out[0], [(2, gmsh.model.occ.addRectangle(-R - 1, -1, 0, R + 1, R + 3))])

    def cls_roller(c):
        if abs(c[1] - R) < 1e-6:
            return TOP
        return SYM_X if half and abs(c[0]) < 1e-6 else CONTACT

    def block():
        x0 = 0 if half else -100
        gmsh.model.occ.addRectangle(x0, -100, 0, 100 - x0, 100)

    def cls_block(c):
        if abs(c[1]) < 1e-6:
            return CONTACT
        if abs(c[1] + 100) < 1e-6:
            return BOTTOM
        return SYM_X if half and abs(c[0]) < 1e-6 else SIDE

    mr, mb = gmsh_mesh(roller, cls_roller, size, 2), gmsh_mesh(block, cls_block, size, 2)
    hr = cm.MeshHierarchy.build(mr, levels, projector=cm.CircleProjector((0.0, R), R, (CONTACT,)))
    hb = cm.MeshHierarchy.build(mb, levels)
    sym = [cm.Dirichlet([SYM_X], (0.0, None))] if half else []
    # the press guides the roller: its flat top keeps x (the half model's symmetry plane does that)
    guide = sym if half else [cm.Dirichlet([TOP], (0.0, None))]
    bodies = [cm.Body(hr, STEEL, guide, pressure={TOP: ROLLER_P / (2 * R)}),
              cm.Body(hb, ALU, [cm.Dirichlet([BOTTOM], (0.0, 0.0))] + sym)]
    pair = cm.ContactPair(0, 1, [CONTACT], [CONTACT], search=5.0, region=lambda mid: np.abs(mid[:, 0]) < 20)
    law = cm.Coulomb(friction) if friction else cm.Frictionless()
    return cm.Problem(bodies, pairs=[pair], friction=law)


# ---------------------------------------------------------------------------------------------
# 2. concentric rings (plane strain)
# ---------------------------------------------------------------------------------------------
RING_A, RING_B, RING_C = 50.0, 75.0, 100.0
RING_INNER, RING_OUTER = cm.Material(210000.0, 0.3), cm.Material(70000.0, 0.3)
# The interface is a circle on both sides; between their nodes both meshes are polygons whose chords
# would cut into each other by about h^2 / (8 R) if the gaps were measured between the facets. They
# are measured between the circles (the hierarchies' projectors), so the load's size does not matter
# (the problem is linear in it).
RING_P0, RING_P2 = 1000.0, 500.0


def _lame_cylinder(a, b, pin, pout, m):
    """Lame's thick cylinder a < r < b (plane strain): sigma_r = A - B/r^2, sigma_t = A + B/r^2,
    A = (pin a^2 - pout b^2)/(b^2 - a^2), B = (pin - pout) a^2 b^2/(b^2 - a^2);
    u(r) = (1 + nu)/E ((1 - 2 nu) A r + B / r). Returns u as a function of r."""
    A = (pin * a ** 2 - pout * b ** 2) / (b ** 2 - a ** 2)
    B = (pin - pout) * a ** 2 * b ** 2 / (b ** 2 - a ** 2)
    return lambda r: (1 + m.nu) / m.E * ((1 - 2 * m.nu) * A * r + B / r)


def rings_lame(p0=RING_P0):
    """The uniform interface pressure q of two rings a < r < b (inner) and b < r < c (outer), no
    initial gap, internal pressure p0: u_inner(b; p0, q) = u_outer(b; q, 0) with Lame's u(r) (linear
    in q, solved exactly)."""
    def mismatch(q):
        return (_lame_cylinder(RING_A, RING_B, p0, q, RING_INNER)(RING_B)
                - _lame_cylinder(RING_B, RING_C, q, 0.0, RING_OUTER)(RING_B))
    m0, m1 = mismatch(0.0), mismatch(1.0)
    return -m0 / (m1 - m0)


def _michell2(A, B, C, D, r, m):
    """The cos 2 theta Michell terms phi = (A r^2 + B r^4 + C r^-2 + D) cos 2 theta (Barber, Table
    8.1, plane strain kappa = 3 - 4 nu): rows sigma_r / cos, tau_rt / sin, u_r / cos at r."""
    mu, k = m.E / (2 * (1 + m.nu)), 3 - 4 * m.nu
    sr = -(2 * A + 6 * C / r ** 4 + 4 * D / r ** 2)
    tr = 2 * A + 6 * B * r ** 2 - 6 * C / r ** 4 - 2 * D / r ** 2
    ur = (-2 * A * r + (k - 3) * B * r ** 3 + 2 * C / r ** 3 + (k + 1) * D / r) / (2 * mu)
    return sr, tr, ur


def rings_michell(p2=RING_P2):
    """The cos 2 theta amplitude q2 of the interface pressure for an internal pressure p2 cos 2 theta
    on the inner ring, the interface frictionless and closed (normal displacement continuous, no
    shear): per ring phi = (A r^2 + B r^4 + C r^-2 + D) cos 2 theta; eight conditions, sigma_r(a) =
    -p2, tau(a) = 0, tau_inner(b) = tau_outer(b) = 0, sigma_r,inner(b) = sigma_r,outer(b),
    u_r,inner(b) = u_r,outer(b), sigma_r(c) = tau(c) = 0, solved as a linear system; q2 =
    -sigma_r(b). The displacement formulas satisfy Hooke's law (plane strain) and the
    strain-displacement relations with these stresses: checked by central differences to 1e-9."""
    def rows(r, m):
        return np.array([_michell2(*np.eye(4)[i], r, m) for i in range(4)]).T  # 3 x 4
    a_in, b_in = rows(RING_A, RING_INNER), rows(RING_B, RING_INNER)
    b_out, c_out = rows(RING_B, RING_OUTER), rows(RING_C, RING_OUTER)
    Z = np.zeros(4)
    M = np.array([np.r_[a_in[0], Z], np.r_[a_in[1], Z], np.r_[b_in[1], Z], np.r_[Z, b_out[1]],
                  np.r_[b_in[0], -b_out[0]], np.r_[b_in[2], -b_out[2]], np.r_[Z, c_out[0]], np.r_[Z, c_out[1]]])
    rhs = np.array([-p2, 0, 0, 0, 0, 0, 0, 0])
    x = np.linalg.solve(M, rhs)
    return float(-(b_in[0] @ x[:4]))


def rings_problem(levels: int, size: float = 10.0, p2: float = RING_P2, mesh_levels: int = None):
    """A quarter of two concentric rings (inner 50 < r < 75, E 210000; outer 75 < r < 100, E 70000;
    nu 0.3; plane strain), meshed separately with sizes `size` and 1.37 `size` (non-matching at
    r = 75), touching without gap or friction. The inner ring carries the pressure p0 + p2 cos 2
    theta (p0 = 1000, p2 = 500) on r = 50; symmetry conditions on x = 0 and y = 0 hold both rings. The inner
    ring's outer arc is the nonmortar side."""
    import gmsh

    def ring(r0, r1):
        def build():
            o = gmsh.model.occ.addDisk(0, 0, 0, r1, r1)
            i = gmsh.model.occ.addDisk(0, 0, 0, r0, r0)
            ring = gmsh.model.occ.cut([(2, o)], [(2, i)])[0]
            box = gmsh.model.occ.addRectangle(0, 0, 0, r1 + 1, r1 + 1)
            gmsh.model.occ.intersect(ring, [(2, box)])
        return build

    def classify(r0, r1):
        def cls(c):
            if abs(c[0]) < 1e-6:
                return SYM_X
            if abs(c[1]) < 1e-6:
                return SYM_Y
            # a quarter arc of radius r has its centre of mass at 2 sqrt(2) r / pi ~ 0.9 r
            return INNER if abs(np.hypot(c[0], c[1]) - 2 * math.sqrt(2) * r0 / math.pi) < 1e-3 * r1 else OUTER
        return cls

    mi = gmsh_mesh(ring(RING_A, RING_B), classify(RING_A, RING_B), size, 2)
    mo = gmsh_mesh(ring(RING_B, RING_C), classify(RING_B, RING_C), 1.37 * size, 2)
    c = (0.0, 0.0)
    hi = cm.MeshHierarchy.build(mi, levels, projector=projectors(cm.CircleProjector(c, RING_A, (INNER,)),
                                                                 cm.CircleProjector(c, RING_B, (OUTER,))))
    ho = cm.MeshHierarchy.build(mo, levels, projector=projectors(cm.CircleProjector(c, RING_B, (INNER,)),
                                                                 cm.CircleProjector(c, RING_C, (OUTER,))))
    sym = [cm.Dirichlet([SYM_X], (0.0, None)), cm.Dirichlet([SYM_Y], (None, 0.0))]

    def load(x):
        # traction -p n with n = -x/|x| on r = a: p x/|x|, p = p0 + p2 cos 2 theta
        r = np.linalg.norm(x, axis=1)
        cos2 = (x[:, 0] ** 2 - x[:, 1] ** 2) / r ** 2
        return (RING_P0 + p2 * cos2)[:, None] * x / r[:, None]

    bodies = [cm.Body(hi, RING_INNER, sym, traction={INNER: load}),
              cm.Body(ho, RING_OUTER, sym)]
    pair = cm.ContactPair(0, 1, [OUTER], [INNER], search=0.2 * size)
    return cm.Problem(bodies, pairs=[pair])


# ---------------------------------------------------------------------------------------------
# 3. concentric hollow spheres (octant)
# ---------------------------------------------------------------------------------------------
# The gaps are measured between the spheres (see RING_P0): the size of the pressure does not matter.
SHELL_A, SHELL_B, SHELL_C, SHELL_P = 0.5, 1.0, 1.5, 1.0e5
SHELL_INNER, SHELL_OUTER = cm.Material(210000.0, 0.3), cm.Material(70000.0, 0.3)


def _lame_sphere(a, b, pin, pout, m):
    """Lame's thick sphere a < r < b: u = A r + B / r^2, sigma_r = E/(1 - 2 nu) A - 2 E/(1 + nu)
    B / r^3, with sigma_r(a) = -pin, sigma_r(b) = -pout. Returns u as a function of r."""
    M = np.array([[m.E / (1 - 2 * m.nu), -2 * m.E / (1 + m.nu) / a ** 3],
                  [m.E / (1 - 2 * m.nu), -2 * m.E / (1 + m.nu) / b ** 3]])
    A, B = np.linalg.solve(M, [-pin, -pout])
    return lambda r: A * r + B / r ** 2


def shells_lame(p=SHELL_P):
    """The uniform interface pressure q of the shells 0.5 < r < 1 (inner) and 1 < r < 1.5 (outer),
    no initial gap, internal pressure p: u_inner(1; p, q) = u_outer(1; q, 0) with Lame's u(r)."""
    def mismatch(q):
        return (_lame_sphere(SHELL_A, SHELL_B, p, q, SHELL_INNER)(SHELL_B)
                - _lame_sphere(SHELL_B, SHELL_C, q, 0.0, SHELL_OUTER)(SHELL_B))
    m0, m1 = mismatch(0.0), mismatch(1.0)
    return -m0 / (m1 - m0)


def _octant_classify(r0, r1):
    def cls(c):
        for axis, tag in enumerate((SYM_X, SYM_Y, SYM_Z)):
            if abs(c[axis]) < 1e-6:
                return tag
        # a sphere octant of radius r has its centre of mass at (r/2, r/2, r/2)
        return INNER if abs(np.linalg.norm(c) - math.sqrt(3) * r0 / 2) < 1e-3 * r1 else OUTER
    return cls


def shells_problem(levels: int, size: float = 0.25):
    """An octant of two concentric hollow spheres (inner 0.5 < r < 1, E 210000; outer 1 < r < 1.5,
    E 70000; nu 0.3), tetrahedra of gmsh with sizes `size` and 1.3 `size` (non-matching at r = 1),
    internal pressure 1e5 on r = 0.5, symmetry conditions on the three coordinate planes, no gap,
    frictionless. The inner shell's outer sphere is the nonmortar side."""
    import gmsh

    def shell(r0, r1):
        def build():
            o = gmsh.model.occ.addSphere(0, 0, 0, r1)
            i = gmsh.model.occ.addSphere(0, 0, 0, r0)
            s = gmsh.model.occ.cut([(3, o)], [(3, i)])[0]
            gmsh.model.occ.intersect(s, [(3, gmsh.model.occ.addBox(0, 0, 0, r1 + 1, r1 + 1, r1 + 1))])
        return build

    mi = gmsh_mesh(shell(SHELL_A, SHELL_B), _octant_classify(SHELL_A, SHELL_B), size, 3)
    mo = gmsh_mesh(shell(SHELL_B, SHELL_C), _octant_classify(SHELL_B, SHELL_C), 1.3 * size, 3)
    c = (0.0, 0.0, 0.0)
    hi = cm.MeshHierarchy.build(mi, levels, projector=projectors(cm.SphereProjector(c, SHELL_A, (INNER,)),
                                                                 cm.SphereProjector(c, SHELL_B, (OUTER,))))
    ho = cm.MeshHierarchy.build(mo, levels, projector=projectors(cm.SphereProjector(c, SHELL_B, (INNER,)),
                                                                 cm.SphereProjector(c, SHELL_C, (OUTER,))))
    sym = [cm.Dirichlet([SYM_X], _sym(3, 0)), cm.Dirichlet([SYM_Y], _sym(3, 1)), cm.Dirichlet([SYM_Z], _sym(3, 2))]
    bodies = [cm.Body(hi, SHELL_INNER, sym, pressure={INNER: SHELL_P}), cm.Body(ho, SHELL_OUTER, sym)]
    return cm.Problem(bodies, pairs=[cm.ContactPair(0, 1, [OUTER], [INNER], search=0.2 * size)])


# ---------------------------------------------------------------------------------------------
# 4. two equal hemispheres
# ---------------------------------------------------------------------------------------------
HEMI_R, HEMI_MAT = 1.0, cm.Material(1000.0, 0.3)
HEMI_APPROACH = 0.045   # total approach of the two flat faces: Hertz a = sqrt(approach R / 2) = 0.15


def _hemisphere_mesh(upper: bool, h0: float, quarter: bool = True):
    """A quarter (x, y >= 0; or the whole one) of the hemisphere of radius 1 touching z = 0 at the origin, above it
    (upper) or below it; element size h0 at the origin growing away from it."""
    import gmsh
    R, s = HEMI_R, 1.0 if upper else -1.0

    def build():
        ball = gmsh.model.occ.addSphere(0, 0, s * R, R)
        lo = 0.0 if quarter else -R - 1
        box = gmsh.model.occ.addBox(lo, lo, 0 if upper else -R, R + 1 - lo, R + 1 - lo, R)
        gmsh.model.occ.intersect([(3, ball)], [(3, box)])

    def cls(c):
        if quarter and abs(c[0]) < 1e-6:
            return SYM_X
        if quarter and abs(c[1]) < 1e-6:
            return SYM_Y
        return TOP if abs(abs(c[2]) - R) < 1e-6 else CONTACT

    def size(x, y, z):
        return min(h0 + 0.5 * max(math.sqrt(x * x + y * y + z * z) - 0.2, 0.0), 0.3)

    return gmsh_mesh(build, cls, size, 3)


def hemisphere_hertz(approach=HEMI_APPROACH):
    """Hertz for two equal spheres (R, E, nu) at the approach delta: R* = R/2, E* = E / (2 (1 -
    nu^2)), a = sqrt(R* delta), p0 = 2 a E* / (pi R*), force F = 4/3 E* sqrt(R*) delta^1.5 (the
    same as one sphere on a rigid plane at delta/2: R* = R, E* = E / (1 - nu^2)). Returns a, p0."""
    Rs, Es = HEMI_R / 2, HEMI_MAT.E / (2 * (1 - HEMI_MAT.nu ** 2))
    a = math.sqrt(Rs * approach)
    return a, 2 * a * Es / (math.pi * Rs)


def hemispheres_problem(levels: int, h0: float = 0.05, approach: float = HEMI_APPROACH, quarter: bool = True):
    """Two equal hemispheres (radius 1, E 1000, nu 0.3) touching at the origin, a quarter model
    (symmetry planes x = 0 and y = 0; their flat faces z = +-1 are moved towards each other by
    approach/2 each) or, not `quarter`, the whole hemispheres (the flat faces moved so and held in
    x and y, which holds their rigid motions); frictionless. The lower mesh has 1.25 times the
    element size (non-matching). The upper hemisphere is the nonmortar side. By symmetry the contact plane stays at z = 0."""
    mu, ml = _hemisphere_mesh(True, h0, quarter), _hemisphere_mesh(False, 1.25 * h0, quarter)
    hu = cm.MeshHierarchy.build(mu, levels, projector=cm.SphereProjector((0, 0, HEMI_R), HEMI_R, (CONTACT,)))
    hl = cm.MeshHierarchy.build(ml, levels, projector=cm.SphereProjector((0, 0, -HEMI_R), HEMI_R, (CONTACT,)))
    sym = [cm.Dirichlet([SYM_X], _sym(3, 0)), cm.Dirichlet([SYM_Y], _sym(3, 1))] if quarter else []
    held = None if quarter else 0.0
    bodies = [cm.Body(hu, HEMI_MAT, sym + [cm.Dirichlet([TOP], (held, held, -approach / 2))]),
              cm.Body(hl, HEMI_MAT, sym + [cm.Dirichlet([TOP], (held, held, approach / 2))])]
    pair = cm.ContactPair(0, 1, [CONTACT], [CONTACT], search=0.2, region=lambda mid: np.hypot(mid[:, 0], mid[:, 1]) < 0.4)
    return cm.Problem(bodies, pairs=[pair])


def hemisphere_on_plane_problem(levels: int, h0: float = 0.05, approach: float = HEMI_APPROACH):
    """The upper hemisphere of hemispheres_problem alone (the same mesh) pressed by approach/2
    onto the rigid plane z = 0: with equal bodies each deforms half, so this is the same contact
    (E* of the pair is half that of one body on a rigid plane)."""
    mu = _hemisphere_mesh(True, h0)
    hu = cm.MeshHierarchy.build(mu, levels, projector=cm.SphereProjector((0, 0, HEMI_R), HEMI_R, (CONTACT,)))
    sym = [cm.Dirichlet([SYM_X], _sym(3, 0)), cm.Dirichlet([SYM_Y], _sym(3, 1))]
    body = cm.Body(hu, HEMI_MAT, sym + [cm.Dirichlet([TOP], (None, None, -approach / 2))], contact_tags=[CONTACT])
    return cm.Problem(body, obstacle=cm.PlaneObstacle((0.0, 0.0, 0.0), (0.0, 0.0, -1.0)))


# ---------------------------------------------------------------------------------------------
# 5. three bodies stacked on a floor
# ---------------------------------------------------------------------------------------------
STACK_PRESSURE = 10.0
# (x0, y0, width, height) of the bottom, middle and top block
STACK_BLOCKS = ((0.0, 0.0, 4.0, 1.0), (1.0, 1.0, 2.0, 0.8), (1.5, 1.8, 1.0, 0.5))


def stack_meshes(size: float):
    """The fine gmsh meshes of the three blocks, sizes 1.4 size, size, 0.7 size (bottom to top)."""
    import gmsh
    out = []
    for (x0, y0, w, h), s in zip(STACK_BLOCKS, (1.4 * size, size, 0.7 * size)):
        out.append(gmsh_mesh(lambda x0=x0, y0=y0, w=w, h=h: gmsh.model.occ.addRectangle(x0, y0, 0, w, h),
                             lambda c, y0=y0, h=h: BOTTOM if abs(c[1] - y0) < 1e-9 else (
                                 TOP if abs(c[1] - y0 - h) < 1e-9 else SIDE), s, 2))
    return out


def stack_problem(size: float = 0.1, levels: int = None, friction: float = 0.3):
    """Three blocks (4 x 1, 2 x 0.8, 1 x 0.5; E 210000, 70000, 210000, nu 0.3) stacked centred on a
    rigid floor y = 0, no supports at all (held by contact and Coulomb friction `friction`), a
    pressure 10 on the top block's top. Each hierarchy is coarsened from its own fine mesh
    (MeshHierarchy.coarsened), or, with `levels`, the gmsh mesh refined uniformly. Pairs: the
    middle block's bottom on the bottom block's top, the top block's bottom on the middle block's
    top (upper body nonmortar); the bottom block on the floor (ObstacleContact)."""
    meshes = stack_meshes(size)
    hs = [cm.MeshHierarchy.coarsened(m) if levels is None else cm.MeshHierarchy.build(m, levels) for m in meshes]
    mats = (cm.Material(210000.0, 0.3), cm.Material(70000.0, 0.3), cm.Material(210000.0, 0.3))
    bodies = [cm.Body(h, m, []) for h, m in zip(hs, mats)]
    bodies[2] = cm.Body(hs[2], mats[2], [], pressure={TOP: STACK_PRESSURE})
    contacts = [cm.ContactPair(1, 0, [BOTTOM], [TOP], search=0.1 * size),
                cm.ContactPair(2, 1, [BOTTOM], [TOP], search=0.1 * size),
                cm.ObstacleContact(0, [BOTTOM], cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)))]
    return cm.Problem(bodies, contacts=contacts, friction=cm.Coulomb(friction))


# ---------------------------------------------------------------------------------------------
# measurements
# ---------------------------------------------------------------------------------------------
def nonmortar_nodes_left_out(problem):
    """What the contact boundary of `problem` leaves out: per pair, the nonmortar facet nodes (of
    the facets with its nonmortar tags, within its region) that carry no contact condition, as a dict
    {"total", "left_out", "held", "uncovered"}: "held" are held along their normal (or in every
    axis) by Dirichlet data, "uncovered" face the mortar side over less than 1 % of their support
    (mortar.MIN_NODE_COVER); both are taken out by the boundary modification of the dual basis.
    One body on an obstacle: the nodes of its contact-tag facets that are not contact nodes (a list
    of one dict, held and uncovered not told apart)."""
    keep = problem.contact.nodes
    if not problem.multibody:
        m = problem.mesh
        tags = [t for oc in problem.obstacle_contacts for t in oc.tags] or list(problem.bodies[0].contact_tags)
        nodes = np.unique(m.facets[np.isin(m.facet_tags, tags)])
        out = np.setdiff1d(nodes, keep)
        return [{"total": len(nodes), "left_out": len(out), "held": None, "uncovered": None}]
    res = []
    for q, c in zip(problem.pairs, problem.couplings):
        off = problem.offsets[q.nonmortar]
        kept = int(np.isin(c.nonmortar_nodes + off, keep).sum())
        total = len(c.nonmortar_nodes) + len(c.excluded) + len(c.uncovered)
        res.append({"total": total, "left_out": total - kept, "held": len(c.excluded), "uncovered": len(c.uncovered)})
    return res


def body_balance(result):
    """Per body |reactions + spring forces + contact forces on it + load| relative to the largest
    component of the total load: the obstacle forces on their body, a pair's force ("pair k") on
    its nonmortar body and its opposite on its mortar body."""
    p = result.problem
    load = result.canonical_load()
    cf = result.contact_forces()
    d = p.mesh.dim
    scale = max(float(np.abs(load.sum(axis=0)).max()), 1e-300)
    reactions, springs = result.reactions(), result.spring_forces()
    out = []
    for k in range(len(p.bodies)):
        f = load[p.offsets[k]:p.offsets[k + 1]].sum(axis=0)
        f = f + sum((v for key, v in reactions.items() if key[0] == k), np.zeros(d))
        f = f + sum((v for key, v in springs.items() if key[0] == k), np.zeros(d))
        for j, q in enumerate(p.pairs):
            if q.nonmortar == k:
                f = f + cf.get(f"pair {j}", 0.0)
            if q.mortar == k:
                f = f - cf.get(f"pair {j}", 0.0)
        for j, oc in enumerate(p.obstacle_contacts):
            if oc.body == k:
                f = f + cf.get(f"obstacle {j}", 0.0)
        out.append(float(np.abs(f).max()) / scale)
    return out
