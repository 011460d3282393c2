"""Random and malformed input never crashes or hangs: only ValueError/TypeError (issue 5)."""
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from contactmg import _core
from contactmg.hierarchy import MeshHierarchy
from contactmg.io import read_mesh
from contactmg.material import Material
from contactmg.mesh import Mesh

FAST = settings(max_examples=60, deadline=2000, suppress_health_check=[HealthCheck.too_slow])
floats = st.floats(allow_nan=True, allow_infinity=True, width=64)


@FAST
@given(points=arrays(np.float64, st.tuples(st.integers(0, 8), st.integers(1, 4)), elements=floats),
       cells=arrays(np.int64, st.tuples(st.integers(0, 6), st.integers(1, 9)), elements=st.integers(-3, 10)),
       cell_type=st.sampled_from(["triangle", "quad", "tetra", "hexahedron", "line", ""]))
def test_mesh_rejects_garbage_cleanly(points, cells, cell_type):
    try:
        m = Mesh.from_cells(points, cells, cell_type)
    except (ValueError, TypeError):
        return
    # accepted: then it is a valid mesh the core accepts too, and a hierarchy can be built
    assert np.all(m.cell_measures() > 0)
    _core.check_cells(m.points, m.cells, m.cell_type)
    if m.dim == 2:
        MeshHierarchy.build(m, 2)


@FAST
@given(points=arrays(np.float64, st.tuples(st.integers(3, 8), st.just(2)), elements=st.floats(-1, 1)),
       cells=arrays(np.int64, st.tuples(st.integers(1, 4), st.just(3)), elements=st.integers(0, 7)),
       E=floats, nu=floats)
def test_assembly_rejects_garbage_cleanly(points, cells, E, nu):
    try:
        A = _core.assemble_elasticity(points, cells, "triangle", E, nu)
    except (ValueError, TypeError):
        return
    K = A.data
    assert np.all(np.isfinite(K))
    Material(E, nu)  # the core accepted the material: so does Python


@FAST
@given(data=st.binary(min_size=0, max_size=400), ext=st.sampled_from([".vtu", ".msh", ".vtk", ".xdmf", ".obj"]))
def test_read_mesh_on_random_bytes(tmp_path_factory, data, ext):
    path = tmp_path_factory.mktemp("fuzz") / f"m{ext}"
    path.write_bytes(data)
    try:
        read_mesh(path)
    except (ValueError, TypeError):
        pass


@FAST
@given(shape=st.tuples(st.integers(0, 5), st.integers(0, 4)))
def test_core_shape_checks(shape):
    A = _core.assemble_elasticity(np.array([[0, 0], [1, 0], [0, 1.0]]), np.array([[0, 1, 2]]), "triangle", 1.0, 0.3)
    x = np.zeros(shape)
    if shape == (3, 2):
        assert A.matvec(x).shape == (3, 2)
    else:
        with pytest.raises(ValueError, match="shape"):
            A.matvec(x)
