"""The model file of `contactmg run`: a TOML file read into a Problem, its solver options, its load
steps and the outputs to write (docs/guide/model-file.md describes the schema).

Every error is a ModelError (a ValueError) whose one-line message names the file, the key in the
dotted form of the file (`body[0].dirichlet[1].tags`) and what is wrong; an unknown key is an error,
with the closest known name where one is close. Paths in the file are relative to its folder."""
from __future__ import annotations

import contextlib
import difflib
import io
import math
import os
from dataclasses import dataclass, field
from typing import Dict, List, Optional

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11: the same parser as a package (a declared dependency there)
    import tomli as tomllib

import numpy as np

from ..mesh.hierarchy import MeshHierarchy
from ..mesh.io import read_mesh
from ..mesh.mesh import Mesh
from ..model.friction import Coulomb, Frictionless, Tresca
from ..model.loads import PointLoad, point_load_nodes
from ..model.material import Material
from ..model.obstacle import CylinderObstacle, MeshObstacle, PlaneObstacle, SphereObstacle
from ..model.problem import Body, ContactPair, Dirichlet, ObstacleContact, Problem
from ..solve.options import SolverOptions
from .common import MAX_LEVELS, PLOT_SUFFIXES

MAX_STEPS = 100000
TOP_KEYS = ("description", "body", "obstacle", "pair", "friction", "steps", "solver", "output")
BODY_KEYS = ("name", "mesh", "levels", "hierarchy", "material", "materials", "dirichlet", "traction", "pressure", "spring",
             "point_load", "body_force", "gravity", "surface", "geometry")
SURFACE_TYPES = ("sphere", "cylinder")
OBSTACLE_TYPES = ("plane", "sphere", "cylinder", "mesh")
FRICTION_LAWS = ("frictionless", "coulomb", "tresca")
PATH_METHODS = ("nmg", "fixed-point")
# how a body's levels are made: "refine" the mesh (the coarse level; levels below it by geometric
# coarsening where it is large or alone), or take it as the fine level with coarse levels made from it
# by "coarsening" (mesh/coarsening.py) or "aggregation" (mesh/aggregation.py)
HIERARCHIES = ("refine", "coarsening", "aggregation")


class ModelError(ValueError):
    """A model file that cannot be read: `file: key: what`."""

    def __init__(self, file: str, key: Optional[str], what: str):
        self.file, self.key, self.what = file, key, what
        super().__init__(f"{file}: {key}: {what}" if key else f"{file}: {what}")


@dataclass
class Outputs:
    """The files a run writes (absolute paths; None: not written) and whether it prints the
    result's summary table."""

    vtu: Optional[str] = None
    pvd: Optional[str] = None
    json: Optional[str] = None
    plot: Optional[str] = None
    summary: bool = False

    def files(self) -> Dict[str, str]:
        """The output files asked for, by kind."""
        return {k: v for k, v in (("vtu", self.vtu), ("pvd", self.pvd), ("json", self.json), ("plot", self.plot))
                if v is not None}


@dataclass
class BodyInfo:
    """What the report says of a body: its name, mesh file (as given), levels, finest mesh and how
    its hierarchy was made (refine, coarsening, aggregation)."""

    name: str
    mesh_file: str
    levels: int
    mesh: Mesh
    hierarchy: str = "refine"


@dataclass
class Model:
    """A model file read: the problem, the solver options, the number of proportional load steps,
    the outputs, the bodies' report facts and the friction law as given."""

    path: str
    problem: Problem
    options: SolverOptions
    steps: int
    outputs: Outputs
    bodies: List[BodyInfo]
    friction: dict = field(default_factory=dict)
    description: Optional[str] = None


# -- reading tables ---------------------------------------------------------------------------------
class _Table:
    """One TOML table of the file at `key` (dotted): its values taken one by one, checked, and the
    keys left over refused (done())."""

    def __init__(self, file: str, key: str, data, allowed):
        if not isinstance(data, dict):
            raise ModelError(file, key or None, f"must be a table, got {_kind(data)}")
        self.file, self.key, self.data, self.allowed, self.taken = file, key, data, tuple(allowed), set()
        self._refuse_unknown()  # at once: before any mesh is read or refined

    def _refuse_unknown(self) -> None:
        for k in self.data:
            if k not in self.taken and k not in self.allowed:
                raise self.error(k, "unknown key" + _close(k, self.allowed)
                                 + f" (known here: {', '.join(self.allowed)})")

    def at(self, name: str) -> str:
        return f"{self.key}.{name}" if self.key else name

    def error(self, name: Optional[str], what: str) -> ModelError:
        return ModelError(self.file, self.at(name) if name else (self.key or None), what)

    def has(self, name: str) -> bool:
        return name in self.data

    def raw(self, name: str, default=None):
        self.taken.add(name)
        return self.data.get(name, default)

    def required(self, name: str):
        if name not in self.data:
            raise self.error(None, f"{name} is missing")
        return self.raw(name)

    def string(self, name: str, default=None, required: bool = False, choices=None) -> Optional[str]:
        v = self.required(name) if required else self.raw(name, default)
        if v is None:
            return None
        if not isinstance(v, str) or not v.strip():
            raise self.error(name, f"must be a non-empty string, got {_kind(v)}")
        if choices is not None and v not in choices:
            raise self.error(name, f"must be one of {', '.join(choices)}, got {v!r}" + _close(v, choices))
        return v

    def integer(self, name: str, default=None, lo: int = 1, hi: Optional[int] = None) -> Optional[int]:
        v = self.raw(name, default)
        if v is None:
            return None
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.error(name, f"must be an integer, got {_kind(v)}")
        if v < lo or (hi is not None and v > hi):
            raise self.error(name, f"must lie in {lo}..{hi}, got {v}" if hi is not None else f"must be >= {lo}, got {v}")
        return v

    def number(self, name: str, default=None, required: bool = False, positive: bool = False,
               nonneg: bool = False) -> Optional[float]:
        v = self.required(name) if required else self.raw(name, default)
        if v is None:
            return None
        return _number(v, self.error, name, positive, nonneg)

    def boolean(self, name: str, default: bool = False) -> bool:
        v = self.raw(name, default)
        if not isinstance(v, bool):
            raise self.error(name, f"must be true or false, got {_kind(v)}")
        return v

    def vector(self, name: str, dim: int, required: bool = False, default=None, free: bool = False):
        """A list of `dim` numbers (with free: "free" for a component left free, given as None)."""
        v = self.required(name) if required else self.raw(name, default)
        if v is None:
            return None
        what = f"{dim} numbers" + (' (or "free")' if free else "")
        if not isinstance(v, list) or len(v) != dim:
            n = f"a list of {len(v)}" if isinstance(v, list) else _kind(v)
            raise self.error(name, f"must be a list of {what} (the mesh is {dim}D), got {n}")
        out = []
        for i, c in enumerate(v):
            if free and c == "free":
                out.append(None)
                continue
            out.append(_number(c, self.error, f"{name}[{i}]", False, False, what=what))
        return tuple(out)

    def tags(self, name: str, mesh: Mesh, mesh_file: str, facets: bool = True) -> tuple:
        """One integer facet tag or a non-empty list of them, each carried by a boundary facet of `mesh`."""
        v = self.required(name)
        items = v if isinstance(v, list) else [v]
        if not items:
            raise self.error(name, "must name at least one facet tag")
        for t in items:
            if isinstance(t, bool) or not isinstance(t, int):
                raise self.error(name, f"must be an integer facet tag or a list of them, got {_kind(t)}")
        present = sorted(set(np.unique(mesh.facet_tags).tolist()))
        for t in items:
            if t not in present:
                raise self.error(name, f"no boundary facet of {mesh_file} carries tag {t} (its facet tags: "
                                       f"{', '.join(map(str, present))})")
        if len(set(items)) != len(items):
            raise self.error(name, f"names a tag twice: {items}")
        return tuple(items)

    def tables(self, name: str) -> list:
        """An array of tables (absent: none)."""
        v = self.raw(name, [])
        if isinstance(v, dict):
            v = [v]
        if not isinstance(v, list) or not all(isinstance(t, dict) for t in v):
            raise self.error(name, f"must be an array of tables ([[{self.at(name)}]]), got {_kind(v)}")
        return v

    def table(self, name: str, allowed) -> Optional["_Table"]:
        if name not in self.data:
            self.taken.add(name)
            return None
        return _Table(self.file, self.at(name), self.raw(name), allowed)

    def done(self) -> None:
        self._refuse_unknown()
        for k in self.data:
            if k not in self.taken:  # a known key that this build does not read: refuse it rather than ignore it
                raise self.error(k, "not supported yet")


def _kind(v) -> str:
    if isinstance(v, bool):
        return f"a boolean ({str(v).lower()})"
    if isinstance(v, (int, float)):
        return f"a number ({v!r})"
    if isinstance(v, str):
        return f"a string ({v!r})"
    if isinstance(v, list):
        return "a list"
    if isinstance(v, dict):
        return "a table"
    return type(v).__name__


def _close(word: str, known) -> str:
    match = difflib.get_close_matches(str(word), list(known), n=1, cutoff=0.6)
    if not match:  # an abbreviation or a spelled-out name ("tolerance" for "tol")
        w = str(word).lower()
        match = sorted((k for k in known if len(k) >= 3 and (w.startswith(k.lower()) or k.lower().startswith(w))
                        and len(w) >= 3), key=len, reverse=True)
    return f" (did you mean {match[0]!r}?)" if match else ""


def _number(v, error, name, positive=False, nonneg=False, what="a number") -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise error(name, f"must be {what}, got {_kind(v)}")
    v = float(v)
    if not math.isfinite(v):
        raise error(name, f"must be finite, got {v}")
    if positive and v <= 0:
        raise error(name, f"must be positive, got {v!r}")
    if nonneg and v < 0:
        raise error(name, f"must not be negative, got {v!r}")
    return v


def _path(base: str, p: str) -> str:
    return p if os.path.isabs(p) else os.path.normpath(os.path.join(base, p))


# -- the model ------------------------------------------------------------------------------------
def read_model(path) -> Model:
    """Read the model file `path` (TOML) into a Model; a ModelError names what is wrong."""
    # the CAD models of bodies with a geometry, closed once the problem is built (their gmsh models
    # are loaded again should a projection be needed later)
    cads: list = []
    try:
        return _read_model(path, cads)
    finally:
        for cad in cads:
            cad.close()


def _read_model(path, cads: list) -> Model:
    path = os.fspath(path)
    file = path
    if not os.path.exists(path):
        raise ModelError(file, None, "no such file")
    if os.path.isdir(path):
        raise ModelError(file, None, "is a directory, not a model file")
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except tomllib.TOMLDecodeError as e:
        raise ModelError(file, None, f"not valid TOML: {e}") from None
    except (OSError, UnicodeDecodeError) as e:
        raise ModelError(file, None, f"cannot read: {e}") from None
    base = os.path.dirname(os.path.abspath(path))
    top = _Table(file, "", data, TOP_KEYS)
    description = top.string("description")
    body_tables = top.tables("body")
    if not body_tables:
        raise ModelError(file, "body", "the model needs at least one body ([[body]] with name and mesh)")
    bodies, infos = [], []
    names: Dict[str, int] = {}
    for k, t in enumerate(body_tables):
        body, info = _read_body(_Table(file, f"body[{k}]", t, BODY_KEYS), base, cads)
        if info.name in names:
            raise ModelError(file, f"body[{k}].name", f"the name {info.name!r} is taken by body[{names[info.name]}]")
        names[info.name] = k
        bodies.append(body)
        infos.append(info)
    dims = {i.mesh.dim for i in infos}
    if len(dims) != 1:
        raise ModelError(file, "body", f"the bodies' meshes need one dimension, got {sorted(dims)}")
    friction, friction_info = _read_friction(top.table("friction", ("law", "coefficient", "bound")))
    obstacles = [_read_obstacle(_Table(file, f"obstacle[{k}]", t, ("body", "tags", "type", "point", "normal", "center",
                                                                  "radius", "inside", "axis", "mesh", "body_side",
                                                                  "allow_penetration")), names, infos, base)
                 for k, t in enumerate(top.tables("obstacle"))]
    pairs = [_read_pair(_Table(file, f"pair[{k}]", t, ("nonmortar", "mortar", "nonmortar_tags", "mortar_tags",
                                                       "search")), names, infos)
             for k, t in enumerate(top.tables("pair"))]
    steps_table = top.table("steps", ("count",))
    steps = 1
    if steps_table is not None:
        steps = steps_table.integer("count", 1, 1, MAX_STEPS)
        steps_table.done()
    options = _read_solver(top.table("solver", [f.name for f in SolverOptions.__dataclass_fields__.values()]))
    if steps > 1 and options.method is not None and options.method not in PATH_METHODS:
        raise ModelError(file, "solver.method", f"load steps (steps.count = {steps}) are solved by one of "
                                                f"{', '.join(PATH_METHODS)}, got {options.method!r}")
    outputs = _read_outputs(top.table("output", ("vtu", "pvd", "json", "plot", "summary")), base, dims.pop())
    top.done()
    problem = _problem(file, bodies, obstacles, pairs, friction)
    if steps > 1 and problem.law == "linear":
        raise ModelError(file, "steps.count", "load steps need a contact boundary (an obstacle or a pair): without "
                                              "contact the problem is linear")
    if options.method == "fixed-point" and (friction_info["law"] != "coulomb" or problem.law == "linear"):
        raise ModelError(file, "solver.method", "the fixed-point method (Algorithm 1) needs Coulomb friction on a "
                                                "contact boundary")
    return Model(path, problem, options, steps, outputs, infos, friction_info, description)


def _read_body(t: _Table, base: str, cads: list):
    name = t.string("name", required=True)
    mesh_file = t.string("mesh", required=True)
    geometry = t.string("geometry")
    cad = None if geometry is None else _read_cad(t, _path(base, mesh_file), _path(base, geometry))
    if cad is not None:
        cads.append(cad)
    try:
        if cad is None:
            # meshio's Gmsh reader prints an empty line: a report on standard output (--json -) stays clean
            with contextlib.redirect_stdout(io.StringIO()):
                mesh = read_mesh(_path(base, mesh_file))
        else:
            mesh = cad.mesh
    except ValueError as e:
        raise t.error("mesh", str(e)) from None
    levels = t.integer("levels", 1, 1, MAX_LEVELS)
    kind = t.string("hierarchy", "refine", choices=HIERARCHIES)
    if kind != "refine" and levels != 1:
        raise t.error("hierarchy", f'"{kind}" takes the mesh as the fine level and makes the coarse levels from it: '
                                   f"levels must be 1 (refinement makes levels from a coarse mesh), got {levels}")
    d = mesh.dim
    material = _read_material(t, mesh)
    dirichlet = []
    for k, bt in enumerate(t.tables("dirichlet")):
        b = _Table(t.file, t.at(f"dirichlet[{k}]"), bt, ("tags", "value"))
        tags = b.tags("tags", mesh, mesh_file)
        value = b.vector("value", d, required=True, free=True)
        if all(v is None for v in value):
            raise b.error("value", 'fixes no component: every one is "free"')
        b.done()
        dirichlet.append(Dirichlet(tags, value))
    traction: Dict[int, tuple] = {}
    for k, bt in enumerate(t.tables("traction")):
        b = _Table(t.file, t.at(f"traction[{k}]"), bt, ("tags", "value"))
        tags = b.tags("tags", mesh, mesh_file)
        value = b.vector("value", d, required=True)
        b.done()
        for tag in tags:
            if tag in traction:
                raise b.error("tags", f"tag {tag} already carries a traction (give one traction per tag)")
            traction[tag] = value
    body_force = t.vector("body_force", d)
    pressure = _per_tag(t, "pressure", "value", mesh, mesh_file, lambda b, k: b.number(k, required=True))
    springs = _per_tag(t, "spring", "stiffness", mesh, mesh_file, lambda b, k: _stiffness(b, k, d))
    point_loads = []
    for k, bt in enumerate(t.tables("point_load")):
        b = _Table(t.file, t.at(f"point_load[{k}]"), bt, ("point", "force"))
        pl = PointLoad(b.vector("point", d, required=True), b.vector("force", d, required=True))
        b.done()
        try:
            point_load_nodes(mesh, [pl])
        except ValueError as e:
            raise b.error("point", str(e).split(": ", 1)[-1]) from None
        point_loads.append(pl)
    gravity = t.vector("gravity", d)
    if gravity is not None:
        regions = material.values() if isinstance(material, dict) else [material]
        if any(m.density is None for m in regions):
            raise t.error("gravity", "needs a density in the material" + ("" if isinstance(material, Material)
                                                                            else " of every region"))
    projector = _read_surfaces(t, mesh, mesh_file)
    if cad is not None:
        if projector is not None:
            raise t.error("surface", "give the curved surfaces by the geometry or by [[body.surface]], not both")
        projector = cad.projector()
    t.done()
    try:
        hierarchy = {"refine": lambda: MeshHierarchy.build(mesh, levels, projector=projector),
                     "coarsening": lambda: MeshHierarchy.coarsened(mesh),
                     "aggregation": lambda: MeshHierarchy.aggregated(mesh)}[kind]()
    except ValueError as e:
        raise t.error("mesh", str(e)) from None
    # the obstacle's contact tags are set when the obstacles are read (they name the body)
    body = Body(hierarchy, material, dirichlet, body_force=body_force, traction=traction or None,
                pressure=pressure or None, springs=springs or None, point_loads=point_loads, gravity=gravity)
    return body, BodyInfo(name, mesh_file, levels, hierarchy.finest, kind)


def _read_cad(t: _Table, mesh_path: str, geometry_path: str):
    """The CadModel of a body's gmsh mesh and the CAD (or .geo) file it was meshed from: its mesh, and
    a projector that puts the new boundary nodes of every refinement on the CAD surfaces. It stays
    open while the model lives (contact pairs measure their gaps on it)."""
    from ..mesh.cad import CadModel

    if not mesh_path.lower().endswith(".msh"):
        raise t.error("geometry", f"goes with a gmsh .msh mesh made from it (gmsh matches the two by entity tags), "
                                  f"got the mesh {os.path.basename(mesh_path)}")
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            return CadModel(mesh_path, geometry=geometry_path)
    except ValueError as e:
        raise t.error("geometry", str(e)) from None


def _read_surfaces(t: _Table, mesh: Mesh, mesh_file: str):
    """The projector of the body's [[body.surface]] tables (None without one): the analytic curved
    surfaces its facets of the given tags lie on. Refinement puts new boundary nodes on them, and
    contact pairs measure their gaps on them."""
    from ..mesh.generators import CircleProjector
    from ..mesh.generators_3d import CylinderProjector

    d, projectors, claimed = mesh.dim, [], {}
    for k, st in enumerate(t.tables("surface")):
        b = _Table(t.file, t.at(f"surface[{k}]"), st, ("tags", "type", "center", "point", "axis", "radius"))
        tags = b.tags("tags", mesh, mesh_file)
        for tag in tags:
            if tag in claimed:
                raise b.error("tags", f"tag {tag} already lies on surface[{claimed[tag]}]")
            claimed[tag] = k
        kind = b.string("type", required=True, choices=SURFACE_TYPES)
        if kind == "sphere":  # a circle in 2D
            b.allowed = ("tags", "type", "center", "radius")
            projectors.append(CircleProjector(b.vector("center", d, required=True),
                                              b.number("radius", required=True, positive=True), tags))
        else:
            if d == 2:
                raise b.error("type", 'a 2D section of a cylinder is a circle: give type = "sphere" with center and radius')
            b.allowed = ("tags", "type", "point", "axis", "radius")
            axis = b.vector("axis", d, required=True)
            if not any(axis):
                raise b.error("axis", "must not be the zero vector")
            projectors.append(CylinderProjector(b.number("radius", required=True, positive=True),
                                                b.vector("point", d, required=True), axis, tags))
        b.done()
    if not projectors:
        return None

    def project(points, tags):
        # each surface moves only the points of its own tags
        for p in projectors:
            points = p(points, tags)
        return points
    return project


def _per_tag(t: _Table, name: str, key: str, mesh: Mesh, mesh_file: str, read) -> dict:
    """{tag: value} of the array of tables `name` (each with tags and `key`, read by read(table, key))."""
    out: dict = {}
    for k, bt in enumerate(t.tables(name)):
        b = _Table(t.file, t.at(f"{name}[{k}]"), bt, ("tags", key))
        tags = b.tags("tags", mesh, mesh_file)
        value = read(b, key)
        b.done()
        for tag in tags:
            if tag in out:
                raise b.error("tags", f"tag {tag} already carries a {name.replace('_', ' ')} (give one per tag)")
            out[tag] = value
    return out


def _stiffness(b: _Table, key: str, d: int):
    """A spring stiffness per unit area: one number, or one per global axis."""
    v = b.raw(key)
    if isinstance(v, list):
        return b.vector(key, d, required=True)
    if v is None:
        raise b.error(None, f"{key} is missing")
    return b.number(key, required=True)


def _one_material(m: _Table) -> Material:
    E = m.number("E", required=True, positive=True)
    nu = m.number("nu", required=True)
    if not -1.0 < nu < 0.5:
        raise m.error("nu", f"Poisson's ratio must lie in (-1, 0.5), got {nu!r}")
    density = m.number("density", nonneg=True)
    m.done()
    return Material(E, nu, density)


def _read_material(t: _Table, mesh: Mesh):
    """One Material (material = {...}), or {region: Material} (materials = [{region = ..., ...}])."""
    if t.has("material") and t.has("materials"):
        raise t.error("materials", "give material (one for the body) or materials (one per region), not both")
    if t.has("materials"):
        regions = set(np.unique(mesh.cell_tags).tolist())
        out = {}
        tables = t.tables("materials")
        if not tables:
            raise t.error("materials", "names no region")
        for k, mt in enumerate(tables):
            m = _Table(t.file, t.at(f"materials[{k}]"), mt, ("region", "E", "nu", "density"))
            region = m.integer("region", None, lo=-2**62)
            if region is None:
                raise m.error(None, "region is missing (the cell tag of the region)")
            if region not in regions:
                raise m.error("region", f"no cell carries the region tag {region} (the mesh's regions: "
                                        f"{', '.join(map(str, sorted(regions)))})")
            if region in out:
                raise m.error("region", f"region {region} has a material already")
            out[region] = _one_material(m)
        missing = sorted(regions - set(out))
        if missing:
            raise t.error("materials", f"the cells of region(s) {', '.join(map(str, missing))} have no material")
        return out
    m = t.table("material", ("E", "nu", "density"))
    if m is None:
        raise t.error(None, "material is missing (material = { E = ..., nu = ... })")
    return _one_material(m)


def _read_friction(t: Optional[_Table]):
    if t is None:
        return Frictionless(), {"law": "frictionless"}
    law = t.string("law", required=True, choices=FRICTION_LAWS)
    if law == "coulomb":
        F = t.number("coefficient", required=True, nonneg=True)
        t.allowed = ("law", "coefficient")
        t.done()
        return Coulomb(F), {"law": law, "coefficient": F}
    if law == "tresca":
        g = t.number("bound", required=True, nonneg=True)
        t.allowed = ("law", "bound")
        t.done()
        return Tresca(g), {"law": law, "bound": g}
    t.allowed = ("law",)
    t.done()
    return Frictionless(), {"law": law}


def _body_ref(t: _Table, key: str, names: Dict[str, int]) -> int:
    name = t.string(key, required=True)
    if name not in names:
        raise t.error(key, f"no body is named {name!r} (bodies: {', '.join(names)})" + _close(name, names))
    return names[name]


def _read_obstacle(t: _Table, names, infos, base: str):
    k = _body_ref(t, "body", names)
    mesh, mesh_file = infos[k].mesh, infos[k].mesh_file
    tags = t.tags("tags", mesh, mesh_file)
    kind = t.string("type", required=True, choices=OBSTACLE_TYPES)
    d = mesh.dim
    common = ("body", "tags", "type", "allow_penetration")
    if kind == "plane":
        t.allowed = common + ("point", "normal")
        point = t.vector("point", d, required=True)
        normal = t.vector("normal", d, required=True)
        if not any(normal):
            raise t.error("normal", "must not be the zero vector")
        obstacle = PlaneObstacle(point, normal)
    elif kind == "sphere":
        t.allowed = common + ("center", "radius", "inside")
        center = t.vector("center", d, required=True)
        radius = t.number("radius", required=True, positive=True)
        obstacle = SphereObstacle(center, radius, t.boolean("inside", False))
    elif kind == "cylinder":
        # in 2D a cylinder's section is a circle about `point`: no axis
        t.allowed = common + (("point", "axis", "radius", "inside") if d == 3 else ("point", "radius", "inside"))
        if d == 2 and t.has("axis"):
            raise t.error("axis", "a 2D cylinder is a circle about point: give point and radius, no axis")
        point = t.vector("point", d, required=True)
        axis = t.vector("axis", d, required=True) if d == 3 else None
        if axis is not None and not any(axis):
            raise t.error("axis", "must not be the zero vector")
        radius = t.number("radius", required=True, positive=True)
        inside = t.boolean("inside", False)
        obstacle = CylinderObstacle(point, axis, radius, inside) if d == 3 else SphereObstacle(point, radius, inside)
    else:
        t.allowed = common + ("mesh", "body_side")
        surface = t.string("mesh", required=True)
        side = t.raw("body_side")
        if side is not None and (isinstance(side, bool) or side not in (1, -1)):
            raise t.error("body_side", f"must be 1 or -1 (the side of the surface's normals the body is on), got "
                                       f"{_kind(side)}")
        path = _path(base, surface)
        if not os.path.exists(path):
            raise t.error("mesh", f"cannot read {path}: no such file")
        try:
            with contextlib.redirect_stdout(io.StringIO()):
                obstacle = MeshObstacle.read(path, side)
        except (Exception, SystemExit) as e:  # meshio raises many kinds, and exits on some files
            raise t.error("mesh", f"cannot read the obstacle surface {path}: {e or type(e).__name__}") from None
        if obstacle.points.shape[1] != d:
            raise t.error("mesh", f"the obstacle surface {surface} is {obstacle.points.shape[1]}D, the body {d}D")
    allow = t.boolean("allow_penetration", False)
    t.done()
    return ObstacleContact(k, tags, obstacle, allow)


def _read_pair(t: _Table, names, infos):
    s = _body_ref(t, "nonmortar", names)
    m = _body_ref(t, "mortar", names)
    if s == m:
        raise t.error("mortar", "a pair couples two different bodies")
    stags = t.tags("nonmortar_tags", infos[s].mesh, infos[s].mesh_file)
    mtags = t.tags("mortar_tags", infos[m].mesh, infos[m].mesh_file)
    search = t.number("search", required=True, positive=True)
    t.done()
    return ContactPair(s, m, stags, mtags, search)


def _read_solver(t: Optional[_Table]) -> SolverOptions:
    if t is None:
        return SolverOptions()
    fields = {}
    for name in list(t.data):
        if name in t.allowed:
            fields[name] = t.raw(name)
    t.done()
    # each field on its own first: the error names the key that is wrong
    for name, v in fields.items():
        try:
            SolverOptions(**{name: v})
        except (ValueError, TypeError) as e:
            if name in ("linear", "lines") and fields.get("method") == "tnnmg":
                continue  # valid with the method given beside it
            if name in ("tol", "rtol") and v == 0:
                continue  # zero is fine where the other one is positive (checked together below)
            raise t.error(name, str(e)) from None
    try:
        return SolverOptions(**fields)
    except (ValueError, TypeError) as e:
        raise t.error(None, str(e)) from None


def _read_outputs(t: Optional[_Table], base: str, dim: int) -> Outputs:
    out = Outputs()
    if t is None:
        return out
    for name, suffixes in (("vtu", (".vtu",)), ("pvd", (".pvd",)), ("json", None), ("plot", PLOT_SUFFIXES)):
        p = t.string(name)
        if p is None:
            continue
        if suffixes and not p.lower().endswith(suffixes):
            raise t.error(name, f"must be a file name ending in {', '.join(suffixes)}, got {p!r}")
        setattr(out, name, _path(base, p))
    if out.plot is not None and dim != 2:
        raise t.error("plot", "the boundary stress plot is drawn for 2D models (this one is 3D)")
    out.summary = t.boolean("summary", False)
    t.done()
    return out


def _problem(file: str, bodies: List[Body], obstacles: List[ObstacleContact], pairs: List[ContactPair],
             friction) -> Problem:
    if len(bodies) == 1 and pairs:
        raise ModelError(file, "pair", "a pair couples two bodies: the model has one")
    if len(bodies) > 1 and not pairs:
        raise ModelError(file, "pair", "several bodies touch each other through pairs ([[pair]]): none given")
    try:
        # pairs first: result.contact_forces() names them "pair k" and the obstacles "obstacle j" in
        # the order of the file
        return Problem(bodies if len(bodies) > 1 else bodies[0], friction=friction,
                       contacts=[*pairs, *obstacles] or None)
    except (ValueError, TypeError) as e:
        raise ModelError(file, None, str(e)) from None
