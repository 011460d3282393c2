"""The same Hertz problem under three friction laws: frictionless, Tresca (a fixed stress bound)
and Coulomb (a bound proportional to the normal stress). The tangential stress along the contact."""
import matplotlib.pyplot as plt

import contactmg as cm
from contactmg.results import plots

from _common import hertz_problem, out_dir

LAWS = {"frictionless": cm.Frictionless(), "Tresca, bound 20": cm.Tresca(20.0), "Coulomb, F = 0.4": cm.Coulomb(0.4)}


def main(argv=None):
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    results = {}
    for name, law in LAWS.items():
        result = hertz_problem(levels=6, friction=law).solve("nmg", tol=1e-10)
        data = plots.boundary_stress_data(result, margin=1.5)
        top.plot(data["x"], data["normal"], marker=".", ms=3, label=name)
        bottom.plot(data["x"], data["tangential"], marker=".", ms=3, label=name)
        results[name] = result
    top.set_ylabel("normal stress")
    bottom.set_ylabel("tangential stress")
    bottom.set_xlabel("x")
    top.legend(fontsize=8)
    top.set_title("Hertz problem, level 6: three friction laws")
    fig.tight_layout()
    path = out_dir(argv) / "friction_laws.png"
    fig.savefig(path, dpi=110)
    return {"figure": fig, "path": path, "results": results}


if __name__ == "__main__":
    print(main()["path"])
