import numpy as np
import pytest

from contactmg.mesh.generators import rectangle
from contactmg.mesh.hierarchy import MeshHierarchy
from contactmg.model.material import Material
from contactmg.model.problem import Body, Dirichlet, Problem


@pytest.fixture
def rng():
    return np.random.default_rng(1234)


def clamped_rectangle(cell, levels, n=2, material=Material(1.0, 0.3), body_force=(0.0, -1.0)):
    """Unit square clamped on its left side (tag 4) with a body force: a linear elasticity problem."""
    h = MeshHierarchy.build(rectangle(n, n, cell=cell), levels)
    return Problem(Body(h, material, [Dirichlet([4], (0.0, 0.0))], body_force=body_force))
