"""Clarabel's answers in our words: one explicit map of its statuses.

A status is never read by its suffix: ``AlmostSolved`` is an inaccurate
answer (kept only if our own certificate holds), not an optimum, and a
status that a new Clarabel release adds stops the solve with its name.
"""

from __future__ import annotations

from typing import Any, Literal

Outcome = Literal["optimal", "inaccurate", "infeasible", "unbounded", "stopped"]

STATUS: dict[str, Outcome] = {
    "Solved": "optimal",
    "AlmostSolved": "inaccurate",
    "PrimalInfeasible": "infeasible",
    "AlmostPrimalInfeasible": "infeasible",
    "DualInfeasible": "unbounded",  # the loads' work grows without end along a ray
    "AlmostDualInfeasible": "unbounded",
    "MaxIterations": "stopped",
    "MaxTime": "stopped",
    "NumericalError": "stopped",
    "InsufficientProgress": "stopped",
    "CallbackTerminated": "stopped",
    "Unsolved": "stopped",
}


def status_name(solution: Any) -> str:
    """The status's name, as Clarabel spells it (``SolverStatus.Solved`` -> ``Solved``)."""
    return str(solution.status).rsplit(".", 1)[-1]


def outcome(solution: Any) -> Outcome:
    """What a Clarabel solution means for us; a status we do not know is ``stopped``."""
    return STATUS.get(status_name(solution), "stopped")


def has_answer(solution: Any) -> bool:
    """Whether the solution holds a point worth certifying."""
    return outcome(solution) in ("optimal", "inaccurate")
