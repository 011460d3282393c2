"""Gaps of a contact pair between the surfaces the meshes approximate: two quarter rings meshed apart
(non-matching at r = 1) touch on the circle. Measured between their facets they would cut into each
other by about h^2 / (8R); measured between the circles (the hierarchies' projectors) the gap is zero
at every nonmortar node, and a pressure from inside puts every node in contact with a nearly uniform
pressure (the Lame solution's)."""
from __future__ import annotations

import numpy as np

import contactmg as cm
from contactmg.mesh.mesh import Mesh

INNER_ARC, OUTER_ARC, SYM_X, SYM_Y = 1, 2, 3, 4


def quarter_ring(r0, r1, nr, nt) -> Mesh:
    r, t = np.meshgrid(np.linspace(r0, r1, nr + 1), np.linspace(0, np.pi / 2, nt + 1), indexing="ij")
    pts = np.c_[(r * np.cos(t)).ravel(), (r * np.sin(t)).ravel()]
    i, j = (a.ravel() for a in np.meshgrid(np.arange(nr), np.arange(nt), indexing="ij"))
    a = i * (nt + 1) + j
    quads = np.c_[a, a + nt + 1, a + nt + 2, a + 1]

    def tagger(mid):
        rr = np.linalg.norm(mid, axis=1)
        tags = np.where(rr < 0.5 * (r0 + r1), INNER_ARC, OUTER_ARC)
        tags[np.abs(mid[:, 0]) < 1e-12] = SYM_X
        tags[np.abs(mid[:, 1]) < 1e-12] = SYM_Y
        return tags

    return Mesh.from_cells(pts, quads, "quad", tagger)


def rings(projected: bool, levels: int = 3):
    inner, outer = quarter_ring(0.5, 1.0, 2, 5), quarter_ring(1.0, 1.5, 2, 7)
    proj = (lambda r0, r1: _rings_projector(r0, r1)) if projected else (lambda r0, r1: None)
    hi = cm.MeshHierarchy.build(inner, levels, projector=proj(0.5, 1.0))
    ho = cm.MeshHierarchy.build(outer, levels, projector=proj(1.0, 1.5))
    sym = [cm.Dirichlet([SYM_X], (0.0, None)), cm.Dirichlet([SYM_Y], (None, 0.0))]
    bodies = [cm.Body(hi, cm.Material(2000.0, 0.3), sym, pressure={INNER_ARC: 1.0}),
              cm.Body(ho, cm.Material(1000.0, 0.3), sym)]
    return cm.Problem(bodies, pairs=[cm.ContactPair(0, 1, [OUTER_ARC], [INNER_ARC], search=0.1)])


def _rings_projector(r0, r1):
    a, b = cm.CircleProjector((0.0, 0.0), r0, (INNER_ARC,)), cm.CircleProjector((0.0, 0.0), r1, (OUTER_ARC,))
    return lambda points, tags: b(a(points, tags), tags)


def test_faceted_rings_interfere_by_their_sag():
    p = rings(projected=False)
    h = np.pi / 2 / (7 * 4)  # the mortar arc's segment angle at level 3 (radius 1)
    assert p.contact.gaps.min() < -0.1 * h ** 2 / 8


def test_rings_measured_between_the_circles_touch_and_carry_one_pressure():
    p = rings(projected=True)
    assert np.all(p.contact.gaps == 0.0)
    r = p.solve()
    assert r.converged
    assert np.all(r.node_state[p.contact.nodes] > 0)  # every nonmortar node in contact
    pressure = -np.asarray(r.normal_stress)
    assert pressure.min() > 0
    # Lame, plane strain: the interface pressure q of two thick rings (a = 0.5, b = 1, c = 1.5), from
    # the radial displacement at r = b of each ring matched (no gap)
    q = _lame_interface_pressure(0.5, 1.0, 1.5, 1.0, (2000.0, 0.3), (1000.0, 0.3))
    assert abs(np.median(pressure) / q - 1) < 0.03
    assert (pressure.max() - pressure.min()) / q < 0.15


def _lame_interface_pressure(a, b, c, p, m_in, m_out):
    def ur(r, r0, r1, pin, pout, m):
        E, nu = m
        A = (pin * r0 ** 2 - pout * r1 ** 2) / (r1 ** 2 - r0 ** 2)
        B = (pin - pout) * r0 ** 2 * r1 ** 2 / (r1 ** 2 - r0 ** 2)
        # plane strain: u = (1 + nu) / E ((1 - 2 nu) A r + B / r)
        return (1 + nu) / E * ((1 - 2 * nu) * A * r + B / r)

    # u_inner(b; p, q) = u_outer(b; q, 0), linear in q
    f = lambda q: ur(b, a, b, p, q, m_in) - ur(b, b, c, q, 0.0, m_out)  # noqa: E731
    return -f(0.0) / (f(1.0) - f(0.0))
