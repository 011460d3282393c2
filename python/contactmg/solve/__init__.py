"""Solving a Problem: SolverOptions and resolve_options (options.py), Solver (solver.py), load paths
(loadpath.py), adaptive hierarchies (adaptivity.py).

The convenience `problem.solve(...)` and the kept `problem.solver` of every Problem are defined
with the Problem (model/problem.py) and import this layer when they run."""
