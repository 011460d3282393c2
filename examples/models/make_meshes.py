"""Write the coarse meshes of the example models (Gmsh 2.2 .msh files with tagged facets): the
blocks from contactmg's generators, the filleted cylinder with gmsh (pip install gmsh), so that the
examples run without gmsh. Run from the repository root:
    PYTHONPATH=python python3 examples/models/make_meshes.py
Facet tags of the rectangles: 1 bottom, 2 right, 3 top, 4 left; of the box: 1..6 for x = 0, x = lx,
y = 0, y = ly, z = 0, z = lz."""
import os

from contactmg.mesh.generators import rectangle
from contactmg.mesh.generators_3d import box
from contactmg.mesh.io import write_mesh

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    write_mesh(os.path.join(HERE, "block_2d", "block.msh"), rectangle(4, 2, lx=1.0, ly=0.5))
    write_mesh(os.path.join(HERE, "block_3d", "block.msh"), box(2, 2, 1, lx=1.0, ly=1.0, lz=0.5))
    # non-matching meshes at the interface y = 0.5: 3 cells along the upper block, 5 along the lower
    write_mesh(os.path.join(HERE, "two_blocks", "upper.msh"), rectangle(3, 2, lx=1.0, ly=0.5, origin=(0.0, 0.5)))
    write_mesh(os.path.join(HERE, "two_blocks", "lower.msh"), rectangle(5, 2, lx=1.4, ly=0.5, origin=(-0.2, 0.0)))
    fillet_cylinder(os.path.join(HERE, "fillet_cylinder", "cylinder.msh"))


def fillet_cylinder(path, size=0.2):
    """A cylinder of radius 0.5 and height 1 whose lower edge has a fillet of radius 0.1, meshed by
    gmsh (tetrahedra): facets tagged 1 (the bottom face and the fillet), 2 (the top face), 3 (the
    side)."""
    import gmsh

    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        c = gmsh.model.occ.addCylinder(0, 0, 0, 0, 0, 1, 0.5)
        gmsh.model.occ.synchronize()
        lower = [t for _, t in gmsh.model.getEntities(1) if abs(gmsh.model.occ.getCenterOfMass(1, t)[2]) < 1e-9]
        gmsh.model.occ.fillet([c], lower, [0.1])
        gmsh.model.occ.synchronize()
        faces = {1: [], 2: [], 3: []}
        for _, t in gmsh.model.getEntities(2):
            z = gmsh.model.occ.getCenterOfMass(2, t)[2]
            faces[2 if z > 0.999 else (1 if z < 0.1 else 3)].append(t)
        for tag, ts in faces.items():
            gmsh.model.addPhysicalGroup(2, ts, tag)
        gmsh.model.addPhysicalGroup(3, [t for _, t in gmsh.model.getEntities(3)], 1)
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
        gmsh.model.mesh.generate(3)
        gmsh.write(path)
    finally:
        gmsh.finalize()


if __name__ == "__main__":
    main()
