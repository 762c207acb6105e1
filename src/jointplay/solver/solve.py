"""The public entry points of the numeric core, on top of its layers.

``Workspace`` is the plain ``WorkspaceData`` with the solves on it:
``solve`` (the small-displacement solve, ``pipeline``, or with ``exact``
exact rotations, ``exact``) and ``solve_batch`` (``batch``). ``solve`` and
``solve_cases`` build a workspace and solve on it. Nothing in the solver
imports this module.
"""

from __future__ import annotations

from collections.abc import Sequence

from jointplay.assembly import assemble
from jointplay.errors import SolverError, UnassembledError, UnboundedMechanismError
from jointplay.geometry import FloatArray
from jointplay.model.mechanism import Load, Model
from jointplay.numerics import linalg
from jointplay.result import Result
from jointplay.settings import SolverSettings
from jointplay.solver import batch, pipeline
from jointplay.solver import exact as exact_rotations
from jointplay.solver.batch import BatchSolution, Start
from jointplay.solver.workspace import WorkspaceData


class Workspace(WorkspaceData):
    """The solver's side of one model, with its solves.

    Built once from an ``Assembly``; the model is never modified. ``solve``
    may be called again with other loads (``loads=``), each solved on its own.
    """

    def solve(self, loads: Sequence[Load] | None = None, *, exact: bool = False) -> Result:
        """The equilibrium under the model's loads, or under ``loads`` instead
        (``exact``: with exact rotations, see ``solver/exact.py``)."""
        with linalg.one_blas_thread():
            if exact:
                return exact_rotations.solve_exact(self, loads)
            return pipeline.solve_loads(self, loads)

    def check_held(self, case: str | None = None) -> None:
        """Solve's verdict on the model's own loads (in load case ``case``),
        for a study whose probes or samples stand in for them: where the
        joints do not hold those loads (a free motion they drive, a part they
        lift off), the ``UnboundedMechanismError`` a solve raises, in its
        words and under that case; a study of such a mechanism has no numbers.
        Nominal parts that cannot be assembled, or a nominal answer declined,
        are left to the study, which meets them part by part in its own words."""
        try:
            self.solve(loads=self.asm.model.loads_of(case))
        except UnboundedMechanismError as exc:
            raise (exc if case is None else exc.in_case(case)) from None
        except (UnassembledError, SolverError):
            return

    def solve_batch(
        self,
        work: FloatArray,
        radii: FloatArray | None = None,
        centres: FloatArray | None = None,
        *,
        forces: bool = True,
        starts: Sequence[Start] = (),
        own_starts: Sequence[Start | None] | None = None,
    ) -> BatchSolution:
        """Equilibria under many loads at once: ``work`` is (B, m), one row of
        the loads' work per sample (build rows with ``Assembly.wrench_work``).
        ``radii`` (B, n): each sample's own plays, as scaled cone radii in the
        order of ``Assembly.balls`` (``variation.PlayMap.radii`` builds them).
        ``centres`` (B, rows): each sample's cone centres, stacked like the
        rows of ``stack.A`` (``deviations.DeviationMap`` builds them).
        ``forces``: split each sample's contact forces by the documented rule
        (``BatchSolution.forces``); a study that reads positions only says
        False and skips that split where Newton's own forces certify them.
        ``starts``: samples solved before (``batch.solved_start``) that start
        Newton like the batch's own solved samples (a study's chunks share one).
        ``own_starts``: one per row, the same sample solved in a nearby batch
        (``BatchSolution.own_starts`` of the previous pose of a motion), tried
        first; given, the solution carries its rows' own starts in turn."""
        return batch.solve_batch(
            self, work, radii, centres, forces=forces, starts=starts, own_starts=own_starts
        )


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
