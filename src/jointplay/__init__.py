"""jointplay: where the parts of a mechanism really sit when its joints have play.

>>> import jointplay
>>> model = jointplay.load("examples/paper/6.1.6.1.yaml")
>>> result = jointplay.solve(model)
>>> result.joints["l1"].translation  # mm, in the joint frame
"""

from typing import TYPE_CHECKING

from jointplay.errors import (
    JointplayError,
    ModelError,
    OptionError,
    SolverError,
    UnboundedMechanismError,
)
from jointplay.io.modelfile import load, model_from_dict
from jointplay.model.joints import JOINT_TYPES, Joint
from jointplay.model.mechanism import Body, Load, Model
from jointplay.result import (
    BodyResult,
    Certificate,
    ContactResult,
    JointResult,
    RequirementResult,
    Result,
)
from jointplay.settings import SolverSettings
from jointplay.solver.batch import BatchSolution
from jointplay.solver.pipeline import solve, solve_cases
from jointplay.solver.workspace import Workspace

if TYPE_CHECKING:
    from jointplay.present.report import Report
    from jointplay.studies.contributions import Contributions, ContributionsResult
    from jointplay.studies.envelope import Envelope, EnvelopeResult
    from jointplay.studies.montecarlo import MonteCarlo, MonteCarloResult
    from jointplay.studies.sweep import RotateLoad, Sweep, SweepResult, Vary
    from jointplay.studies.tolerances import Tolerances, TolerancesResult

from jointplay.version import __version__

#: The studies, imported on first use (they bring SciPy's statistics and pandas).
_STUDIES = {
    "MonteCarlo": "studies.montecarlo",
    "MonteCarloResult": "studies.montecarlo",
    "Envelope": "studies.envelope",
    "EnvelopeResult": "studies.envelope",
    "Sweep": "studies.sweep",
    "SweepResult": "studies.sweep",
    "Vary": "studies.sweep",
    "RotateLoad": "studies.sweep",
    "Contributions": "studies.contributions",
    "ContributionsResult": "studies.contributions",
    "Report": "present.report",
    "Tolerances": "studies.tolerances",
    "TolerancesResult": "studies.tolerances",
}


def __getattr__(name: str) -> object:
    if name in _STUDIES:
        import importlib

        return getattr(importlib.import_module(f".{_STUDIES[name]}", __name__), name)
    raise AttributeError(f"module 'jointplay' has no attribute {name!r}")


__all__ = [
    "JOINT_TYPES",
    "BatchSolution",
    "Body",
    "BodyResult",
    "Certificate",
    "ContactResult",
    "Contributions",
    "ContributionsResult",
    "Envelope",
    "EnvelopeResult",
    "Joint",
    "JointResult",
    "JointplayError",
    "Load",
    "Model",
    "ModelError",
    "MonteCarlo",
    "MonteCarloResult",
    "OptionError",
    "Report",
    "RequirementResult",
    "Result",
    "RotateLoad",
    "SolverError",
    "SolverSettings",
    "Sweep",
    "SweepResult",
    "Tolerances",
    "TolerancesResult",
    "UnboundedMechanismError",
    "Vary",
    "Workspace",
    "__version__",
    "load",
    "model_from_dict",
    "solve",
    "solve_cases",
]
