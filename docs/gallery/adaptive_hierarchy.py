"""An adaptive hierarchy for the Hertz problem: the finest mesh near the contact zone after
refinement by the hierarchical error estimator and bulk marking (theta = 0.8), and the estimated
error against the number of unknowns."""
import matplotlib.pyplot as plt
import numpy as np

import contactmg as cm

from _common import out_dir

LEVELS, THETA = 6, 0.8


def factory(hierarchy):
    """The same Hertz description on whatever hierarchy the refinement has reached."""
    body = cm.Body(hierarchy, cm.Material(E=2000.0, nu=0.28),
                   dirichlet=[cm.Dirichlet([cm.HERTZ_TOP], (0.0, -0.005))], contact_tags=[cm.HERTZ_ARC])
    return cm.Problem(body, obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=cm.Coulomb(0.4))


def main(argv=None):
    h = cm.adaptive_hierarchy(cm.hertz_half_disk("triangle"), LEVELS, factory, projector=cm.hertz_projector(),
                              theta=THETA)
    mesh = h.finest
    dofs = np.array([m.num_points * m.dim for m in h.meshes])
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    ax.triplot(mesh.points[:, 0], mesh.points[:, 1], mesh.cells, lw=0.3, color="k")
    ax.set_xlim(-0.2, 0.2)
    ax.set_ylim(0.0, 0.15)
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_title(f"finest mesh (level {h.levels}) near the contact zone")
    ax2.loglog(dofs[:len(h.estimated_error)], h.estimated_error, "o-")
    ax2.set_xlabel("unknowns")
    ax2.set_ylabel("estimated error (energy norm)")
    ax2.set_title(f"adaptive refinement, theta = {THETA}")
    fig.tight_layout()
    path = out_dir(argv) / "adaptive_hierarchy.png"
    fig.savefig(path, dpi=110)
    return {"figure": fig, "path": path, "hierarchy": h, "dofs": dofs}


if __name__ == "__main__":
    print(main()["path"])
