"""Assemblies from the user's meshes: the bodies of a problem need not have hierarchies of equal
depth. A body coarsened from its own fine mesh, or given as its only level, joins bodies refined
from coarse meshes; the coarse levels change the cycle, never the answer, and the forces balance."""
from __future__ import annotations

import numpy as np
import pytest

import contactmg as cm
from contactmg.mesh.generators import RECT_BOTTOM, RECT_TOP, rectangle

UPPER, LOWER = cm.Material(1000.0, 0.3), cm.Material(300.0, 0.3)


def _blocks(upper_h: cm.MeshHierarchy, lower_h: cm.MeshHierarchy, friction=cm.Coulomb(0.3)):
    bodies = [cm.Body(upper_h, UPPER, [cm.Dirichlet([RECT_TOP], (0.002, -0.01))]),
              cm.Body(lower_h, LOWER, [cm.Dirichlet([RECT_BOTTOM], (0.0, 0.0))])]
    return cm.Problem(bodies, pairs=[cm.ContactPair(0, 1, [RECT_BOTTOM], [RECT_TOP], search=0.1)], friction=friction)


def _hierarchies(levels=4):
    up = cm.MeshHierarchy.build(rectangle(4, 2, 1.0, 0.5, origin=(0.25, 0.0)), levels)
    low = cm.MeshHierarchy.build(rectangle(5, 2, 1.5, 0.5, origin=(0.0, -0.5)), levels)
    return up, low


def _balance(res) -> float:
    """|reactions + load| over all bodies relative to the largest reaction (a pair's forces cancel)."""
    total = sum(res.reactions().values(), np.zeros(2)) + res.canonical_load().sum(axis=0)
    return float(np.abs(total).max() / max(np.abs(f).max() for f in res.reactions().values()))


@pytest.mark.parametrize("make_lower", ["coarsened", "alone"])
def test_a_body_with_its_own_coarse_levels_gives_the_same_answer(make_lower):
    up, low = _hierarchies()
    reference = _blocks(up, low).solve()
    fine = low.finest
    other = cm.MeshHierarchy.coarsened(fine) if make_lower == "coarsened" else cm.MeshHierarchy([fine])
    assert other.levels != low.levels
    p = _blocks(up, other)
    if make_lower == "alone":
        assert any("only level" in note for note in p.notes)
    r = p.solve()
    assert reference.converged and r.converged
    assert r.cycles <= 30
    scale = np.abs(reference.displacement).max()
    assert np.abs(r.displacement - reference.displacement).max() < 1e-6 * scale
    assert _balance(r) < 1e-8


def test_lone_meshes_of_both_bodies_get_coarse_levels():
    """Both bodies given as one mesh each, smaller than the coarsening's usual stop (200 nodes):
    coarse levels are made all the same, and the cycle count stays that of a hierarchy."""
    up, low = _hierarchies(levels=2)
    p = _blocks(cm.MeshHierarchy([up.finest]), cm.MeshHierarchy([low.finest]))
    assert up.finest.num_points < 200 and len(p.transfers) >= 1
    r = p.solve()
    assert r.converged and r.cycles <= 30
    assert _balance(r) < 1e-8
