"""The numeric core: from an assembled model to a certified equilibrium.

``pipeline`` (the workspace and the single solve), ``conic`` (Clarabel's
statuses), ``forces`` (the documented split of hyperstatic forces),
``certificate`` (the one check every answer passes), ``batch`` (many loads and
plays at once) and ``exact`` (finite rotations). See docs/solver.md.
"""

from jointplay.solver.batch import BatchSolution
from jointplay.solver.pipeline import solve, solve_cases
from jointplay.solver.workspace import Workspace

__all__ = ["BatchSolution", "Workspace", "solve", "solve_cases"]
