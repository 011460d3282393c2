"""The stop of a command's solve from --tol and --rtol."""
from __future__ import annotations

from ..solve.options import PAPER_TOL


def stop_fields(args) -> dict:
    """The solve's stop from --tol and --rtol: the one given (both: the first met), neither: the
    paper's absolute 1e-11 (the commands run the paper's benchmarks)."""
    if args.tol is None and args.rtol is None:
        return {"tol": PAPER_TOL}
    return {k: v for k, v in (("tol", args.tol), ("rtol", args.rtol)) if v is not None}
