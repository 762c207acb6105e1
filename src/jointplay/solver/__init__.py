"""The numeric core: from an assembled model to a certified equilibrium.

Layers, bottom up, each importing only those below: ``workspace`` (one
model's matrices, free motions and balance maps, made once); ``certificate``
(the one check every answer passes) and ``held`` (motions the joints do not
hold); ``conic`` (Clarabel's statuses) and ``newton``; ``ties`` and ``forces``
(the documented split of hyperstatic forces); ``pipeline`` (the single
solve); ``batch`` (many loads and plays at once) and ``exact`` (finite
rotations); ``solve`` (the public functions). See docs/solver.md."""

from jointplay.solver.batch import BatchSolution
from jointplay.solver.solve import solve, solve_cases
from jointplay.solver.workspace import Workspace

__all__ = ["BatchSolution", "Workspace", "solve", "solve_cases"]
