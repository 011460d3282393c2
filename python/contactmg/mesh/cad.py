"""CAD models through gmsh: the coarse mesh of a geometry and a boundary projector that moves the
new boundary nodes of every refinement onto the CAD surfaces (3D) or curves (2D) they belong to.

    cad = CadModel("cylinder.step", size=0.2)
    h = MeshHierarchy.build(cad.mesh, 4, projector=cad.projector())

gmsh is a dependency of the package, imported only when a CadModel is made (importing contactmg does not load it).
gmsh is one global state per process: a CadModel initializes it if it is not (and finalizes it
again on close() if it did), and keeps its geometry in a gmsh model of its own name, made current
whenever it projects; other gmsh models of the process are left as they are."""
from __future__ import annotations

import hashlib
import itertools
import os
import warnings
from typing import Dict, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from ..mesh.hierarchy import facet_parents
from ..mesh.io import read_mesh
from ..mesh.mesh import Mesh, unique_rows
from ..mesh.quality import boundary_caps

CAD_EXTENSIONS = (".brep", ".step", ".stp", ".iges", ".igs")
MODEL_EXTENSIONS = (".geo", ".msh") + CAD_EXTENSIONS
# gmsh element types of first-order cells and facets
_GMSH_CELLS = {4: "tetra", 5: "hexahedron", 2: "triangle", 3: "quad"}
_GMSH_FACETS = {"tetra": 2, "hexahedron": 3, "triangle": 1, "quad": 1}
_counter = itertools.count()
_opened_by_us = []  # CadModels that initialized gmsh and have not closed yet


def _gmsh():
    try:
        import gmsh
    except ImportError:  # pragma: no cover - gmsh is a test extra
        raise ImportError("CAD models need gmsh: pip install gmsh") from None
    return gmsh


def _key(facets: np.ndarray) -> str:
    """A fingerprint of a mesh's boundary facets: identifies the level a projector is refining."""
    f = np.ascontiguousarray(facets, dtype=np.int64)
    return hashlib.blake2b(f.tobytes() + str(f.shape).encode(), digest_size=16).hexdigest()


class CadModel:
    """A gmsh geometry and its coarse mesh: `mesh` (a contactmg Mesh: facet tags are the physical
    group tags of the boundary entities, cell tags those of the volumes, or surfaces in 2D) and
    `projector()` for MeshHierarchy.build.

    source: a .geo file, a CAD file (.brep, .step/.stp, .iges/.igs: read by gmsh's OpenCASCADE
    kernel) or a .msh file. A .geo or CAD file is meshed here (size: the largest element size,
    gmsh's Mesh.MeshSizeMax; a .geo's own sizes apply below it) unless the .geo already holds a
    mesh; a .msh is read as it is, and since a .msh holds no CAD geometry, its geometry must be
    given as `geometry` (the CAD or .geo file it was meshed from: gmsh matches the mesh to it by
    entity tags). dim: 3 (volumes) or 2 (a planar surface model in the z = 0 plane); by default the
    highest dimension of the model. groups: {facet tag: [boundary entity tags]} to use instead of
    the model's physical groups (a CAD file has none); a boundary entity in no group gets its own
    entity tag as facet tag. curvature: elements per 2 pi of radius of curvature (gmsh's
    Mesh.MeshSizeFromCurvature) when meshing here. optimize: gmsh's mesh optimizer run after
    meshing tetrahedra here ("Netgen" by default; None for none). Why Netgen: it removes "caps",
    tetrahedra with two faces on the boundary, which projection flattens on every level (their
    children at the shared edge keep all four nodes on the surface, their thickness a chord's sag
    h^2 / R shrinking faster than their size h): the smallest quality of a torus went 0.25, 0.13,
    0.06, 0.03 over three refinements with gmsh's default mesh and 0.48, 0.38, 0.34, 0.32 with the
    Netgen-optimized one (benchmarks/model/cad_refinement.py). A mesh read as it is (a .msh, a .geo
    holding one) is not optimized: `caps` counts its caps on curved entities and a UserWarning
    says when there are any. Raises ValueError for
    a file it cannot read, a model without first-order simplices or hexahedra/quadrilaterals, or a
    boundary entity in two groups.

    Cost: gmsh's closest-point search, one call per CAD entity and level with all the new boundary
    nodes on it (about 10-50 microseconds a node)."""

    def __init__(self, source: Union[str, os.PathLike], size: Optional[float] = None, dim: Optional[int] = None,
                 groups: Optional[Mapping[int, Sequence[int]]] = None,
                 geometry: Optional[Union[str, os.PathLike]] = None,
                 curvature: Optional[float] = None, optimize: Optional[str] = "Netgen"):
        self.source = os.fspath(source)
        self.geometry = None if geometry is None else os.fspath(geometry)
        ext = os.path.splitext(self.source)[1].lower()
        if ext not in MODEL_EXTENSIONS:
            raise ValueError(f"cannot read {self.source}: unknown extension {ext!r} "
                             f"(CadModel reads {', '.join(MODEL_EXTENSIONS)})")
        for path in (self.source, self.geometry):
            if path is not None and not os.path.isfile(path):
                raise ValueError(f"cannot read {path}: no such file")
        if self.geometry is not None and os.path.splitext(self.geometry)[1].lower() not in (".geo",) + CAD_EXTENSIONS:
            raise ValueError(f"geometry must be a .geo or CAD file ({', '.join(CAD_EXTENSIONS)}), got {self.geometry}")
        if size is not None and not (isinstance(size, (int, float)) and not isinstance(size, bool) and size > 0
                                     and np.isfinite(size)):
            raise ValueError(f"size must be a positive number, got {size!r}")
        if dim not in (None, 2, 3):
            raise ValueError(f"dim must be 2 or 3, got {dim!r}")
        if curvature is not None and not (isinstance(curvature, (int, float)) and not isinstance(curvature, bool)
                                          and curvature > 0 and np.isfinite(curvature)):
            raise ValueError(f"curvature must be a positive number of elements per 2 pi radius, got {curvature!r}")
        self.size = size
        self.curvature = curvature
        self.optimize = optimize
        self._name = f"contactmg-cad-{next(_counter)}"
        self._closed = False
        self._groups = None if groups is None else {int(t): [int(e) for e in es] for t, es in groups.items()}
        gmsh = _gmsh()
        try:
            self._open(mesh=True)
            self.dim = dim if dim is not None else max(d for d, _ in gmsh.model.getEntities())
            self.mesh, self.facet_entities = self._extract()
        except Exception:
            self.close()
            raise
        gmsh = self._current()
        flat = {e for e in np.unique(self.facet_entities).tolist()
                if gmsh.model.getType(self.dim - 1, e) in ("Plane", "Line")}
        self.caps = boundary_caps(self.mesh, ~np.isin(self.facet_entities, list(flat)))
        if self.caps:
            warnings.warn(f"{self.source}: {self.caps} cells have two or more facets on the boundary; refinement with "
                          "projection flattens their children (optimize='Netgen' on a mesh made here removes them)",
                          UserWarning, stacklevel=2)
        # boundary entity tags of every facet, per refinement level met so far (by facet fingerprint)
        self._entities: Dict[str, np.ndarray] = {_key(self.mesh.facets): self.facet_entities}
        self._curves: Dict[Tuple[int, int], list] = {}

    # -- gmsh lifetime -------------------------------------------------------------------------
    def _open(self, mesh: bool) -> None:
        """Load the geometry (and, with `mesh`, make or read the mesh) into this object's gmsh model."""
        gmsh = _gmsh()
        if not gmsh.isInitialized():
            gmsh.initialize(readConfigFiles=False)
            gmsh.option.setNumber("General.Terminal", 0)
            _opened_by_us.append(self)
        gmsh.model.add(self._name)
        ext = os.path.splitext(self.source)[1].lower()
        try:
            if ext == ".msh":
                if self.geometry is None:
                    raise ValueError(f"{self.source} holds a mesh but no CAD geometry to project onto: pass "
                                     "geometry= (the .brep/.step/.geo file it was meshed from)")
                self._load_geometry(self.geometry)
                if mesh:
                    gmsh.merge(self.source)
            else:
                self._load_geometry(self.source)
                if mesh and not len(gmsh.model.mesh.getNodes()[0]):
                    if self.size is not None:
                        gmsh.option.setNumber("Mesh.MeshSizeMax", float(self.size))
                    if self.curvature is not None:
                        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", float(self.curvature))
                    gmsh.model.mesh.generate(max(d for d, _ in gmsh.model.getEntities()))
                    if self.optimize and gmsh.model.getEntities(3):
                        gmsh.model.mesh.optimize(self.optimize)
        except ValueError:
            raise
        except Exception as e:
            raise ValueError(f"gmsh cannot read {self.source}: {e}") from None
        if not gmsh.model.getEntities():
            raise ValueError(f"{self.source} holds no geometry")

    def _load_geometry(self, path: str) -> None:
        gmsh = _gmsh()
        if os.path.splitext(path)[1].lower() == ".geo":
            gmsh.merge(path)
        else:
            gmsh.model.occ.importShapes(path)
            gmsh.model.occ.synchronize()

    def _current(self):
        """gmsh with this object's model current (loaded again, geometry only, after close())."""
        gmsh = _gmsh()
        if self._closed or not gmsh.isInitialized() or self._name not in gmsh.model.list():
            self._closed = False
            self._open(mesh=False)
        gmsh.model.setCurrent(self._name)
        return gmsh

    def close(self) -> None:
        """Remove this object's gmsh model, and finalize gmsh if this object initialized it and no
        other CadModel that did is open. A later projection loads the geometry again."""
        gmsh = _gmsh()
        if self._closed:
            return
        self._closed = True
        if gmsh.isInitialized() and self._name in gmsh.model.list():
            gmsh.model.setCurrent(self._name)
            gmsh.model.remove()
        if self in _opened_by_us:
            _opened_by_us.remove(self)
            if not _opened_by_us and gmsh.isInitialized():
                gmsh.finalize()

    def __enter__(self) -> "CadModel":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        return (f"CadModel({self.source!r}, {self.mesh.cell_type}, {self.mesh.num_points} nodes, "
                f"{len(np.unique(self.facet_entities))} boundary entities)")

    # -- the coarse mesh -----------------------------------------------------------------------
    def _physical(self, dim: int, tags) -> Dict[int, int]:
        """The group tag of each entity of dimension `dim` (its own tag where it is in none)."""
        gmsh = _gmsh()
        out = {}
        if dim == self.dim - 1 and self._groups is not None:
            source = [(ptag, ents) for ptag, ents in self._groups.items()]
        else:
            source = [(ptag, list(gmsh.model.getEntitiesForPhysicalGroup(dim, ptag)))
                      for _, ptag in gmsh.model.getPhysicalGroups(dim)]
        for ptag, ents in source:
            for e in ents:
                if e in out and out[e] != ptag:
                    raise ValueError(f"entity {e} of dimension {dim} is in groups {out[e]} and {ptag}: a facet "
                                     "or cell carries one tag")
                out[int(e)] = int(ptag)
        unknown = set(out) - set(tags)
        if dim == self.dim - 1 and self._groups is not None and unknown:
            raise ValueError(f"groups name entities {sorted(unknown)} that are not boundary entities of dimension {dim} "
                             f"(there are {sorted(tags)})")
        return {t: out.get(t, t) for t in tags}

    def _extract(self) -> Tuple[Mesh, np.ndarray]:
        gmsh = _gmsh()
        d = self.dim
        node_tags, coords, _ = gmsh.model.mesh.getNodes()
        if not len(node_tags):
            raise ValueError(f"{self.source}: gmsh made no mesh")
        order = np.argsort(node_tags)
        node_tags = np.asarray(node_tags)[order]
        xyz = np.asarray(coords, float).reshape(-1, 3)[order]

        def index(tags):
            i = np.searchsorted(node_tags, tags)
            return i

        cell_type, cells, cell_tags = None, [], []
        volumes = [t for _, t in gmsh.model.getEntities(d)]
        region = self._physical(d, volumes)
        for v in volumes:
            for etype, _, enodes in zip(*gmsh.model.mesh.getElements(d, v)):
                name = _GMSH_CELLS.get(int(etype))
                if name is None or (name in ("tetra", "hexahedron")) != (d == 3):
                    raise ValueError(f"{self.source}: cells of gmsh type "
                                     f"{gmsh.model.mesh.getElementProperties(etype)[0]!r} are not supported "
                                     "(first-order tetrahedra, hexahedra, triangles, quadrilaterals only)")
                if cell_type not in (None, name):
                    raise ValueError(f"{self.source}: mixed cell types {cell_type} and {name} are not supported")
                cell_type = name
                c = index(np.asarray(enodes, np.int64)).reshape(-1, {"tetra": 4, "hexahedron": 8,
                                                                      "triangle": 3, "quad": 4}[name])
                cells.append(c)
                cell_tags.append(np.full(len(c), region[v], np.int64))
        if cell_type is None:
            raise ValueError(f"{self.source}: no cells of dimension {d}")
        cells = np.vstack(cells)
        used = np.unique(cells)
        renum = np.full(len(node_tags), -1, np.int64)
        renum[used] = np.arange(len(used))
        points = xyz[used]
        cells = renum[cells]
        # facets of every boundary entity, with the entity that holds them
        bnd = sorted({abs(t) for _, t in gmsh.model.getBoundary([(d, v) for v in volumes], combined=False,
                                                                oriented=False)})
        ftag = self._physical(d - 1, bnd)
        fnodes, fent = [], []
        kf = 2 if d == 2 else None
        for e in bnd:
            for etype, _, enodes in zip(*gmsh.model.mesh.getElements(d - 1, e)):
                if int(etype) != _GMSH_FACETS[cell_type]:
                    continue
                kf = {1: 2, 2: 3, 3: 4}[int(etype)]
                f = renum[index(np.asarray(enodes, np.int64))].reshape(-1, kf)
                fnodes.append(f)
                fent.append(np.full(len(f), e, np.int64))
        if not fnodes:
            raise ValueError(f"{self.source}: the boundary entities carry no facets")
        fnodes, fent = np.vstack(fnodes), np.concatenate(fent)
        import meshio

        ftype = {"tetra": "triangle", "hexahedron": "quad", "triangle": "line", "quad": "line"}[cell_type]
        m = meshio.Mesh(points, [(cell_type, cells), (ftype, fnodes)],
                        cell_data={"gmsh:physical": [np.concatenate(cell_tags),
                                                     np.array([ftag[e] for e in fent], np.int64)]})
        mesh = read_mesh(m, dim=d)
        entities = self._match(mesh.facets, fnodes, fent)
        if np.any(entities < 0):
            i = int(np.argmax(entities < 0))
            raise ValueError(f"{self.source}: boundary facet {mesh.facets[i].tolist()} lies on no boundary entity "
                             "of the geometry")
        return mesh, entities

    @staticmethod
    def _match(facets: np.ndarray, fnodes: np.ndarray, fent: np.ndarray) -> np.ndarray:
        """The entity of each of `facets` (by node set) among gmsh's facets fnodes; -1 where none."""
        a = np.sort(np.asarray(facets, np.int64), axis=1)
        b = np.sort(fnodes, axis=1)
        _, inv = unique_rows(np.vstack([a, b]), return_inverse=True)
        ent = np.full(inv.max() + 1, -1, np.int64)
        ent[inv[len(a):]] = fent
        return ent[inv[:len(a)]]

    # -- projection ----------------------------------------------------------------------------
    def projector(self) -> "CadProjector":
        """The boundary projector of this geometry for MeshHierarchy.build(self.mesh, ...)."""
        return CadProjector(self)

    def entities_of(self, mesh: Mesh) -> np.ndarray:
        """The boundary entity of every facet of `mesh`: known for the coarse mesh and for every
        level this model's projector has refined; otherwise (another mesh of the same geometry) the
        closest entity to the facet's centre among those of its facet tag's group."""
        key = _key(mesh.facets)
        if key not in self._entities:
            self._entities[key] = self._nearest_entities(mesh.points[mesh.facets].mean(axis=1), mesh.facet_tags)
        return self._entities[key]

    def _group_entities(self, tag: int) -> list:
        return sorted({int(e) for e, t in zip(self.facet_entities, self.mesh.facet_tags) if t == tag})

    def _nearest_entities(self, x: np.ndarray, tags: np.ndarray) -> np.ndarray:
        out = np.full(len(x), -1, np.int64)
        for tag in np.unique(tags):
            sel = np.flatnonzero(tags == tag)
            ents = self._group_entities(int(tag))
            if not ents:
                raise ValueError(f"facet tag {int(tag)} is no boundary group of {self.source} "
                                 f"(its groups: {sorted(set(self.mesh.facet_tags.tolist()))})")
            best = np.full(len(sel), np.inf)
            for e in ents:
                dist = np.linalg.norm(self.closest(self.dim - 1, e, x[sel]) - x[sel], axis=1)
                better = dist < best
                best[better], out[sel[better]] = dist[better], e
        return out

    def closest(self, dim: int, entity: int, x: np.ndarray) -> np.ndarray:
        """gmsh's closest points on the geometric entity (dim, entity) to the points x (m, d)."""
        x = np.asarray(x, float)
        if x.ndim != 2 or x.shape[1] != self.dim:
            raise ValueError(f"points must have shape (m, {self.dim}), got {x.shape}")
        if not len(x):
            return x.copy()
        if not np.all(np.isfinite(x)):
            raise ValueError("cannot project a non-finite point")
        gmsh = self._current()
        xyz = np.c_[x, np.zeros(len(x))] if self.dim == 2 else x
        p, _ = gmsh.model.getClosestPoint(dim, int(entity), xyz.ravel())
        return np.asarray(p, float).reshape(-1, 3)[:, :self.dim]

    def distance(self, mesh: Mesh, start: int = 0) -> np.ndarray:
        """Per boundary node of `mesh` numbered `start` or above (ascending; start =
        coarse.num_points: the nodes refinement made), its distance from the CAD: the largest
        distance to gmsh's closest point on the entities of the facets around it. gmsh's own
        nodes at CAD vertices can be off a curve by the CAD's tolerance (an OpenCASCADE curve
        ends within 1e-7 of its vertex: 5e-9 on a rounded rectangle)."""
        ent = self.entities_of(mesh)
        nodes = mesh.boundary_nodes()
        nodes = nodes[nodes >= start]
        kf = mesh.facets.shape[1]
        pairs = unique_rows(np.c_[mesh.facets.ravel(), np.repeat(ent, kf)])
        pairs = pairs[pairs[:, 0] >= start]
        pos = np.searchsorted(nodes, pairs[:, 0])
        out = np.zeros(len(nodes))
        x = mesh.points
        for e in np.unique(pairs[:, 1]):
            sel = pairs[:, 1] == e
            dist = np.linalg.norm(self.closest(self.dim - 1, e, x[pairs[sel, 0]]) - x[pairs[sel, 0]], axis=1)
            np.maximum.at(out, pos[sel], dist)
        return out

    def _common_curves(self, e1: int, e2: int) -> list:
        """The CAD curves bounding both surfaces e1 and e2 (3D)."""
        key = (min(e1, e2), max(e1, e2))
        if key not in self._curves:
            gmsh = self._current()

            def curves(e):
                return {abs(t) for _, t in gmsh.model.getBoundary([(2, e)], combined=False, oriented=False)}
            common = sorted(curves(e1) & curves(e2)) or sorted(curves(e1) | curves(e2))
            self._curves[key] = common
        return self._curves[key]

    def project(self, mesh: Mesh, r: dict) -> np.ndarray:
        """The new boundary nodes of the refinement r of `mesh` (_core.refine's dict) moved onto
        the CAD: a node whose facets all lie on one entity to its closest point on that surface
        (3D) or curve (2D); a node on an edge between facets of two entities (3D) to the closest
        point on their common curve, so that it stays on the CAD edge."""
        parents = facet_parents(mesh, r)
        fine_ent = self.entities_of(mesh)[parents]
        facets = np.asarray(r["facets"], np.int64)
        self._entities[_key(facets)] = fine_ent
        nb = np.asarray(r["boundary_nodes"], np.int64)
        x = np.asarray(r["points"], float)[nb]
        kf = facets.shape[1]
        pairs = unique_rows(np.c_[facets.ravel(), np.repeat(fine_ent, kf)])
        pos = np.full(len(r["points"]), -1, np.int64)
        pos[nb] = np.arange(len(nb))
        pairs = pairs[pos[pairs[:, 0]] >= 0]
        # (node, entity) pairs grouped by node in the order of nb
        pairs = pairs[np.argsort(pos[pairs[:, 0]], kind="stable")]
        count = np.bincount(pos[pairs[:, 0]], minlength=len(nb))
        if np.any(count == 0):
            raise ValueError(f"new boundary node {int(nb[np.argmax(count == 0)])} lies on no boundary facet")
        if np.any(count > 2) or (self.dim == 2 and np.any(count > 1)):
            i = int(np.argmax((count > 2) | ((count > 1) & (self.dim == 2))))
            raise ValueError(f"new boundary node {int(nb[i])} lies on {int(count[i])} CAD entities: the coarse mesh "
                             "does not follow the geometry's entities")
        second = np.full(len(nb), -1, np.int64)
        start = np.r_[0, np.cumsum(count)[:-1]]
        first = pairs[start, 1]
        two = count == 2
        second[two] = pairs[start[two] + 1, 1]
        out = x.copy()
        for e in np.unique(first[~two]):
            sel = np.flatnonzero(~two & (first == e))
            out[sel] = self.closest(self.dim - 1, e, x[sel])
        if two.any():
            keys = np.c_[first[two], second[two]]
            idx = np.flatnonzero(two)
            for e1, e2 in unique_rows(keys):
                sel = idx[(keys[:, 0] == e1) & (keys[:, 1] == e2)]
                best = np.full(len(sel), np.inf)
                for c in self._common_curves(int(e1), int(e2)):
                    p = self.closest(1, c, x[sel])
                    dist = np.linalg.norm(p - x[sel], axis=1)
                    better = dist < best
                    best[better] = dist[better]
                    out[sel[better]] = p[better]
                if not np.all(np.isfinite(best)):
                    raise ValueError(f"surfaces {e1} and {e2} share no curve to project onto")
        return out


class CadProjector:
    """The boundary projector of a CadModel: MeshHierarchy.build calls project_refinement, which
    follows the CAD entity of every facet from level to level; called as projector(points, tags)
    (by code that only gives the facet tags) it moves each point to the closest entity of its tag's
    group, which is right inside a face but may leave a node on a CAD edge off the edge."""

    # MeshHierarchy.build relaxes the interior nodes next to the projected ones by default
    relax = True

    def __init__(self, cad: CadModel):
        self.cad = cad

    def project_refinement(self, coarse: Mesh, r: dict) -> np.ndarray:
        """The new boundary nodes of the refinement r of `coarse`, moved onto the CAD."""
        return self.cad.project(coarse, r)

    def __call__(self, points: np.ndarray, tags: np.ndarray) -> np.ndarray:
        points = np.asarray(points, float)
        tags = np.asarray(tags)
        if points.ndim != 2 or points.shape[1] != self.cad.dim or tags.shape != (len(points),):
            raise ValueError(f"expected points (m, {self.cad.dim}) and tags (m,), got {points.shape} and {tags.shape}")
        ent = self.cad._nearest_entities(points, tags)
        out = points.copy()
        for e in np.unique(ent):
            sel = ent == e
            out[sel] = self.cad.closest(self.cad.dim - 1, e, points[sel])
        return out
