"""The public functions of the numeric core, on top of its layers.

``solve`` and ``solve_cases`` build a workspace and solve on it;
``solve_loads`` is what ``Workspace.solve`` calls: the small-displacement
solve (``pipeline``) or, with ``exact``, exact rotations (``exact``). Nothing
below imports this module but ``Workspace``'s own delegating methods.
"""

from __future__ import annotations

from collections.abc import Sequence

from jointplay.assembly import assemble
from jointplay.model.mechanism import Load, Model
from jointplay.numerics import linalg
from jointplay.result import Result
from jointplay.settings import SolverSettings
from jointplay.solver import exact as exact_rotations
from jointplay.solver import pipeline
from jointplay.solver.workspace import Workspace


def solve(
    model: Model,
    settings: SolverSettings | None = None,
    *,
    case: str | None = None,
    exact: bool = False,
) -> Result:
    """Find the equilibrium of ``model`` (under load case ``case``, if given):
    positions, contacts, forces and certificate. ``exact``: with exact
    rotations, refined from the small-displacement answer (``exact.py``)."""
    ws = Workspace(assemble(model), settings)
    return ws.solve(loads=None if case is None else model.loads_of(case), exact=exact)


def solve_cases(
    model: Model, settings: SolverSettings | None = None, *, exact: bool = False
) -> dict[str, Result]:
    """Every load case of ``model`` on one assembly: ``{case: Result}``."""
    ws = Workspace(assemble(model), settings)
    return {case: ws.solve(loads=model.loads_of(case), exact=exact) for case in model.case_names}


def solve_loads(
    ws: Workspace, loads: Sequence[Load] | None = None, *, exact: bool = False
) -> Result:
    """The certified equilibrium of ``ws``'s model under its loads, or under
    ``loads`` instead (``exact``: with exact rotations, see ``exact.py``)."""
    with linalg.one_blas_thread():
        if exact:
            return exact_rotations.solve_exact(ws, loads)
        return pipeline.solve_loads(ws, loads)
