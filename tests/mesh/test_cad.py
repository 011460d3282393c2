"""CAD models through gmsh: the coarse mesh with the model's groups as tags, refinement whose new
boundary nodes land on the CAD surfaces and curves, the quality of every level, clear refusals."""
import os
import warnings

import numpy as np
import pytest

gmsh = pytest.importorskip("gmsh")

from contactmg.mesh.cad import CadModel  # noqa: E402
from contactmg.mesh.generators_3d import box  # noqa: E402
from contactmg.mesh.generators import rectangle  # noqa: E402
from contactmg.mesh.hierarchy import MeshHierarchy  # noqa: E402
from contactmg.mesh.quality import boundary_caps, cell_quality, hierarchy_quality  # noqa: E402


def _write(path, build):
    """Write the OpenCASCADE geometry build() adds to `path` (a .brep) with a gmsh of its own."""
    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        build()
        gmsh.model.occ.synchronize()
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return str(path)


def _fillet():
    c = gmsh.model.occ.addCylinder(0, 0, 0, 0, 0, 1, 0.5)
    gmsh.model.occ.synchronize()
    lower = [t for _, t in gmsh.model.getEntities(1) if abs(gmsh.model.occ.getCenterOfMass(1, t)[2]) < 1e-9]
    gmsh.model.occ.fillet([c], lower, [0.1])


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("cad")
    return {"fillet": _write(d / "fillet.brep", _fillet),
            "torus": _write(d / "torus.brep", lambda: gmsh.model.occ.addTorus(0, 0, 0, 1.0, 0.3)),
            "rounded": _write(d / "rounded.brep",
                              lambda: gmsh.model.occ.addRectangle(0, 0, 0, 2, 1, roundedRadius=0.3)),
            "dir": d}


def _new_node_distance(cad, h):
    n0 = h.meshes[0].num_points
    return [float(cad.distance(m, start=n0).max()) for m in h.meshes[1:]]


def test_geo_round_trip_keeps_the_physical_groups(tmp_path):
    geo = tmp_path / "disk.geo"
    geo.write_text('SetFactory("OpenCASCADE");\nDisk(1) = {0, 0, 0, 1.0};\nRectangle(2) = {-0.3, -0.3, 0, 0.6, 0.6};\n'
                   "BooleanFragments{ Surface{1}; Delete; }{ Surface{2}; Delete; }\n"
                   "Physical Curve(7) = {Boundary{Surface{3};}};\n"
                   "Physical Surface(11) = {2};\nPhysical Surface(12) = {3};\n")
    with CadModel(geo, size=0.2) as cad:
        assert cad.mesh.dim == 2 and cad.mesh.cell_type == "triangle"
        assert set(cad.mesh.facet_tags.tolist()) == {7}
        assert set(cad.mesh.cell_tags.tolist()) == {11, 12}
        # the inner square region holds the cells whose centres lie inside it
        centre = cad.mesh.points[cad.mesh.cells].mean(axis=1)
        inner = np.all(np.abs(centre) < 0.3, axis=1)
        assert np.all(cad.mesh.cell_tags[inner] == 11) and np.all(cad.mesh.cell_tags[~inner] == 12)
        h = MeshHierarchy.build(cad.mesh, 4, projector=cad.projector())
        x = h.finest.points[h.finest.boundary_nodes()]
        assert np.abs(np.linalg.norm(x, axis=1) - 1.0).max() < 1e-10


def test_brep_groups_become_facet_tags(files):
    with CadModel(files["fillet"], size=0.25) as cad:
        ents = sorted(set(cad.facet_entities.tolist()))
        # without physical groups every boundary entity is its own group
        assert np.array_equal(cad.mesh.facet_tags, cad.facet_entities)
    groups = {1: ents[:2], 2: ents[2:]}
    with CadModel(files["fillet"], size=0.25, groups=groups) as cad:
        want = np.where(np.isin(cad.facet_entities, ents[:2]), 1, 2)
        assert np.array_equal(cad.mesh.facet_tags, want)


def test_msh_with_its_geometry(files, tmp_path):
    msh = tmp_path / "fillet.msh"
    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        gmsh.model.occ.importShapes(files["fillet"])
        gmsh.model.occ.synchronize()
        gmsh.model.addPhysicalGroup(2, [t for _, t in gmsh.model.getEntities(2)], 5)
        gmsh.model.addPhysicalGroup(3, [1], 9)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.25)
        gmsh.model.mesh.generate(3)
        gmsh.write(str(msh))
        n_nodes = len(gmsh.model.mesh.getNodes()[0])
    finally:
        gmsh.finalize()
    with pytest.raises(ValueError, match="geometry="):
        CadModel(msh)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # gmsh's own mesh: caps are expected
        with CadModel(msh, geometry=files["fillet"]) as cad:
            assert cad.mesh.num_points == n_nodes
            assert set(cad.mesh.facet_tags.tolist()) == {5} and set(cad.mesh.cell_tags.tolist()) == {9}
            h = MeshHierarchy.build(cad.mesh, 3, projector=cad.projector())
            assert max(_new_node_distance(cad, h)) < 1e-10


@pytest.mark.parametrize("name,size", [("fillet", 0.2), ("torus", 0.3), ("rounded", 0.3)])
def test_refined_boundary_nodes_lie_on_the_cad(files, name, size):
    with CadModel(files[name], size=size) as cad:
        h = MeshHierarchy.build(cad.mesh, 4, projector=cad.projector())
        assert h.finest.num_points > 20 * cad.mesh.num_points
        assert max(_new_node_distance(cad, h)) < 1e-10
        # without the projector the new nodes are off the curved surfaces by the chords' sag
        flat = MeshHierarchy.build(cad.mesh, 2)
        assert _new_node_distance(cad, flat)[0] > 1e-4


def test_nodes_on_cad_edges_stay_on_the_curves(files):
    with CadModel(files["fillet"], size=0.2) as cad:
        h = MeshHierarchy.build(cad.mesh, 4, projector=cad.projector())
        m = h.finest
        ent = cad.entities_of(m)
        node_ents = {}
        for f, e in zip(m.facets.tolist(), ent.tolist()):
            for n in f:
                node_ents.setdefault(n, set()).add(e)
        edge = np.array([n for n, es in node_ents.items() if len(es) == 2 and n >= cad.mesh.num_points])
        assert len(edge) > 100
        x = m.points[edge]
        r, z = np.hypot(x[:, 0], x[:, 1]), x[:, 2]
        # the fillet meets the bottom face on the circle r = 0.4, z = 0, the side on r = 0.5, z = 0.1,
        # and the top face meets the side on r = 0.5, z = 1
        on = (np.isclose(r, 0.4, atol=1e-10) & np.isclose(z, 0.0, atol=1e-10)) | \
             (np.isclose(r, 0.5, atol=1e-10) & (np.isclose(z, 0.1, atol=1e-10) | np.isclose(z, 1.0, atol=1e-10)))
        assert on.all(), x[~on][:3]


@pytest.mark.parametrize("name,size", [("fillet", 0.2), ("torus", 0.3), ("rounded", 0.3)])
def test_quality_stays_bounded_per_level(files, name, size):
    with CadModel(files[name], size=size) as cad:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # no degradation warning
            h = MeshHierarchy.build(cad.mesh, 4, projector=cad.projector())
        q = h.min_quality
        assert q == hierarchy_quality(h) and len(q) == 4
        assert min(q) >= 0.5 * q[0] > 0


def test_unoptimized_caps_degrade_and_warn(files):
    with pytest.warns(UserWarning, match="two or more facets on the boundary"):
        cad = CadModel(files["torus"], size=0.3, optimize=None)
    with cad:
        assert cad.caps > 0 and boundary_caps(cad.mesh) >= cad.caps
        with pytest.warns(UserWarning, match="boundary projection degrades the mesh"):
            h = MeshHierarchy.build(cad.mesh, 4, projector=cad.projector())
        assert h.min_quality[-1] < 0.25 * h.min_quality[0]


def test_relaxation_moves_only_new_interior_nodes_near_moved_ones(files):
    with CadModel(files["fillet"], size=0.2) as cad:
        plain = MeshHierarchy.build(cad.mesh, 3, projector=cad.projector(), relax=False)
        relaxed = MeshHierarchy.build(cad.mesh, 3, projector=cad.projector())
    # the transfers keep their midpoint weights (compared on level 1: further down the red
    # refinement picks each tetrahedron's inner diagonal by length, so the meshes may differ)
    ta, tb = plain.transfers[0], relaxed.transfers[0]
    assert np.array_equal(ta.ptr, tb.ptr) and np.array_equal(ta.parent, tb.parent)
    assert np.array_equal(ta.weight, tb.weight)
    assert np.array_equal(plain.meshes[1].cells, relaxed.meshes[1].cells)
    w = relaxed.transfers[1].weight
    assert set(np.unique(w).tolist()) <= {0.5, 1.0}
    # level 1 starts from the same coarse mesh: boundary and coarse nodes agree, some new interior
    # nodes moved, and none far from the boundary
    a, b = plain.meshes[1], relaxed.meshes[1]
    moved = np.flatnonzero(np.linalg.norm(a.points - b.points, axis=1) > 0)
    assert len(moved) > 0
    assert np.all(moved >= cad.mesh.num_points)
    assert not np.isin(moved, a.boundary_nodes()).any()
    assert np.linalg.norm(a.points - b.points, axis=1).max() < 0.05
    centre_far = np.linalg.norm(a.points[:, :2], axis=1) < 0.2
    assert not np.isin(moved, np.flatnonzero(centre_far & (np.abs(a.points[:, 2] - 0.5) < 0.2))).any()


def test_released_levels_are_made_again_identically(files):
    with CadModel(files["torus"], size=0.3) as cad:
        h = MeshHierarchy.build(cad.mesh, 3, projector=cad.projector())
        before = [m.points.copy() for m in h.meshes]
        assert h.release_coarse()
        cad.close()
        # the geometry is loaded again for the projection
        assert all(np.array_equal(p, m.points) for p, m in zip(before, h.meshes))


def test_gmsh_lifetime(files):
    assert not gmsh.isInitialized()
    cad = CadModel(files["torus"], size=0.4)
    assert gmsh.isInitialized()
    cad.close()
    assert not gmsh.isInitialized()
    # a gmsh the caller initialized stays initialized, with the caller's model current again
    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("mine")
        with CadModel(files["torus"], size=0.4):
            pass
        assert gmsh.isInitialized() and "mine" in gmsh.model.list()
    finally:
        gmsh.finalize()


def test_plain_projector_call_moves_points_onto_their_group(files):
    with CadModel(files["torus"], size=0.4) as cad:
        p = cad.projector()
        x = cad.mesh.points[cad.mesh.boundary_nodes()] * 1.01
        y = p(x, np.full(len(x), cad.mesh.facet_tags[0]))
        R = np.hypot(y[:, 0], y[:, 1])
        assert np.abs(np.hypot(R - 1.0, y[:, 2]) - 0.3).max() < 1e-10
        with pytest.raises(ValueError, match="no boundary group"):
            p(x, np.full(len(x), 99))
        with pytest.raises(ValueError, match="expected points"):
            p(x[:, :2], np.zeros(len(x)))
        with pytest.raises(ValueError, match="shape"):
            cad.closest(2, 1, np.zeros(3))
        with pytest.raises(ValueError, match="non-finite"):
            cad.closest(2, 1, np.full((1, 3), np.nan))


def test_bad_input_is_refused_clearly(files, tmp_path):
    with pytest.raises(ValueError, match="no such file"):
        CadModel(tmp_path / "missing.step")
    bad = tmp_path / "model.stl"
    bad.write_text("solid x\nendsolid x\n")
    with pytest.raises(ValueError, match="unknown extension"):
        CadModel(bad)
    garbage = tmp_path / "garbage.step"
    garbage.write_text("not a step file\n")
    with pytest.raises(ValueError, match="garbage.step"):
        CadModel(garbage)
    for size in (0, -1.0, float("nan"), "0.2", True):
        with pytest.raises(ValueError, match="size must be a positive number"):
            CadModel(files["torus"], size=size)
    with pytest.raises(ValueError, match="dim must be 2 or 3"):
        CadModel(files["torus"], dim=1)
    with pytest.raises(ValueError, match="not boundary entities"):
        CadModel(files["torus"], size=0.4, groups={1: [99]})
    with pytest.raises(ValueError, match="groups 1 and 2"):
        CadModel(files["fillet"], size=0.3, groups={1: [1], 2: [1]})
    assert not gmsh.isInitialized()  # the refused models did not leave gmsh behind


def test_cell_quality_of_every_cell_type():
    s3 = np.sqrt(3.0)
    assert cell_quality(rectangle(1, 1, cell="quad")).min() == pytest.approx(1.0)
    from contactmg.mesh.mesh import Mesh
    tri = Mesh(np.array([[0, 0], [1, 0], [0.5, s3 / 2]]), np.array([[0, 1, 2]]), "triangle", np.zeros((0, 2), int), [])
    assert cell_quality(tri) == pytest.approx([1.0])
    flat = Mesh(np.array([[0, 0], [1, 0], [0.5, 0.01]]), np.array([[0, 1, 2]]), "triangle", np.zeros((0, 2), int), [])
    assert cell_quality(flat)[0] < 0.05
    assert cell_quality(box(1, 1, 1, cell="hexahedron")).min() == pytest.approx(1.0)
    q = hierarchy_quality(MeshHierarchy.build(box(2, 2, 2), 2))
    assert len(q) == 2 and 0 < q[1] <= 1 and q[0] > 0
    # a box's corner cells have two faces on the boundary, but on planes: masked out
    m = box(1, 1, 1)
    assert boundary_caps(m) > 0 and boundary_caps(m, np.zeros(len(m.facets), bool)) == 0
