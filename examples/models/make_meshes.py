"""Write the coarse meshes of the example models (Gmsh 2.2 .msh files with tagged facets) from
contactmg's generators, so that the examples run without gmsh. Run from the repository root:
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


if __name__ == "__main__":
    main()
