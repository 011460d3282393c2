"""The load path options of the solve commands (`--steps N`, `--shear S --shear-steps M`,
`--series PATH.pvd`, `--zone-plot PATH`;): the path of a two-phase
loading on the command's loaded facets, the JSON `steps` list, the time series and the zone plot.
The top-level JSON keys describe the last step."""
from __future__ import annotations

from typing import Callable, Optional

from ..solve.loadpath import two_phase_path
from .stop import stop_fields


def wanted(args) -> bool:
    """Does the command line ask for a load path (--steps)?"""
    return getattr(args, "steps", None) is not None or getattr(args, "shear", None) is not None \
        or getattr(args, "pull_back", False)


def check(args) -> None:
    """Refuse option combinations that mean nothing, before any work (exit 2)."""
    if getattr(args, "shear_steps", None) is not None and getattr(args, "shear", None) is None \
            and not getattr(args, "pull_back", False):
        raise ValueError("--shear-steps needs --shear")
    if not wanted(args):
        for opt, name in (("series", "--series"), ("zone_plot", "--zone-plot")):
            if getattr(args, opt, None):
                raise ValueError(f"{name} writes a load path: give --steps N (or --shear S)")
        return
    if args.method not in ("nmg", "fixed-point"):
        raise ValueError(f"a load path is solved by --method nmg or fixed-point, not {args.method} "
                         "(the linear cost reference has no load path)")


def solve(args, problem, tags, first, second, position: Optional[Callable] = None, label: str = "x"):
    """The path on `problem`: `tags` moved to `first` in --steps increments, then by `second`
    in the second phase's increments (--shear-steps; none without a second phase)."""
    steps = args.steps or 1
    second_steps = 0
    if getattr(args, "shear", None) is not None or getattr(args, "pull_back", False):
        second_steps = args.shear_steps or 1
    path = two_phase_path(problem, tags, first, steps, second if second_steps else None, second_steps)
    result = path.solve(args.method, **stop_fields(args), max_cycles=args.max_cycles)
    if getattr(args, "series", None):
        result.write_pvd(args.series)
    if getattr(args, "zone_plot", None):
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from ..results.plots_loadpath import plot_zones_over_steps

        fig, ax = plt.subplots(figsize=(7, 4))
        plot_zones_over_steps(result, ax=ax, position=position, label=label)
        ax.set_title(f"{args.command}: stick and slip zones over the load path, F = {args.friction}", fontsize=9)
        fig.tight_layout()
        fig.savefig(args.zone_plot, dpi=150)
        plt.close(fig)
    return result


def report(args, path_result, out: dict, zone: Optional[Callable] = None, radii: bool = False) -> None:
    """Add `steps` (one object per step) and the path totals to the JSON object `out`."""
    rows = path_result.summary(zone)
    if radii:  # 3D: the zone sizes are radii about the axis; both names, as at the top level
        for row in rows:
            row["contact_radius"], row["stick_radius"] = row["contact_halfwidth"], row["stick_halfwidth"]
    out["steps"] = rows
    out["path"] = {"steps": len(path_result.path), "steps_solved": len(rows), "converged": path_result.converged,
                   "total_cycles": int(sum(r["cycles"] for r in rows)), "seconds": path_result.seconds,
                   "parameters": path_result.parameters}
    out["path_seconds"] = path_result.seconds
    if getattr(args, "series", None):
        out["series"] = args.series


def print_steps(out: dict, stream) -> None:
    """Print one line per load step."""
    p = out["path"]
    print(f"  load path: {p['steps_solved']}/{p['steps']} steps, {p['total_cycles']} cycles, {p['seconds']:.2f} s; "
          "cycles per step " + " ".join(str(r["cycles"]) for r in out["steps"]), file=stream)
    if all(r.get("stick_halfwidth") is not None for r in out["steps"]):
        print("  stick half-width per step " + " ".join(f"{r['stick_halfwidth']:.4g}" for r in out["steps"]), file=stream)
    elif all("stick_area" in r for r in out["steps"]):
        print("  stick area per step " + " ".join(f"{r['stick_area']:.4g}" for r in out["steps"]), file=stream)
